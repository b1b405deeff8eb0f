//! The device's receiving side of TSP/1: host bytes in, commands (or refusals) out.
//!
//! The host's [`Decoder`](propid_wire::protocol::Decoder) drops a malformed frame without telling the
//! caller its `seq`, but the device must ACK a command it cannot execute with the reason
//! (§4: UNKNOWN_TYPE, BAD_LENGTH, VERSION). So this reader splits the stream with the
//! protocol's [`BlockSplitter`] and checks each block with the protocol's
//! [`check_block`] (COBS, length, CRC — the same check the host's decoder makes): a block whose
//! CRC holds has a trustworthy `seq` and `type` and is answered; a block that fails it (or is
//! oversize) cannot be attributed and is only counted.

use propid_wire::protocol::block::{Block, BlockSplitter};
use propid_wire::protocol::message::is_command_type;
use propid_wire::protocol::{check_block, AckResult, DecodeError, Message};

/// One block from the host, classified.
// A `Message` can hold a 200-byte LOG; an `Incoming` is short-lived (one per received command),
// so boxing it would only add an allocation per command.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Incoming {
    /// A well-formed command.
    Command {
        /// Command id.
        seq: u16,
        /// The command.
        msg: Message,
    },
    /// An intact frame the device refuses with `result` (it is ACKed, not executed).
    Refused {
        /// Command id.
        seq: u16,
        /// Type byte as received.
        msg_type: u8,
        /// UNKNOWN_TYPE, BAD_LENGTH or VERSION.
        result: AckResult,
    },
    /// Unattributable garbage (COBS, CRC, short or oversize): counted, not answered.
    Garbage,
}

/// Receive counters of the device.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct RxStats {
    /// Well-formed commands received.
    pub commands: u64,
    /// Intact frames refused (unknown type, short payload, other version).
    pub refused: u64,
    /// Blocks that could not be attributed.
    pub garbage: u64,
}

impl RxStats {
    /// Count one classified block or line.
    pub fn count(&mut self, inc: &Incoming) {
        match inc {
            Incoming::Command { .. } => self.commands += 1,
            Incoming::Refused { .. } => self.refused += 1,
            Incoming::Garbage => self.garbage += 1,
        }
    }
}

/// Fixed-buffer splitter and classifier for host → device bytes.
#[derive(Debug, Clone, Default)]
pub struct CommandReader {
    blocks: BlockSplitter,
    stats: RxStats,
}

impl CommandReader {
    /// An empty reader.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counters so far.
    pub fn stats(&self) -> RxStats {
        self.stats
    }

    /// Feeds host bytes; `on` gets every complete block, classified, in order. Empty blocks
    /// (two delimiters in a row) are ignored.
    pub fn push(&mut self, bytes: &[u8], mut on: impl FnMut(Incoming)) {
        let stats = &mut self.stats;
        self.blocks.push(bytes, |b| {
            let inc = match b {
                Block::Empty => return,
                Block::Oversize => Incoming::Garbage,
                Block::Data(d) => classify(d),
            };
            stats.count(&inc);
            on(inc);
        });
    }
}

/// Classifies one COBS block (without its delimiter), decoding it in place: the protocol's
/// [`check_block`] decides whether it can be attributed, then the device's rules (§4) whether
/// it is executed or refused, and why.
pub fn classify(block: &mut [u8]) -> Incoming {
    let Ok(raw) = check_block(block) else {
        return Incoming::Garbage;
    };
    let refuse = |result| Incoming::Refused {
        seq: raw.seq,
        msg_type: raw.msg_type,
        result,
    };
    match raw.decode() {
        Err(DecodeError::BadVersion(_)) => refuse(AckResult::Version),
        _ if !is_command_type(raw.msg_type) => refuse(AckResult::UnknownType),
        Ok(f) => Incoming::Command {
            seq: f.seq,
            msg: f.msg,
        },
        Err(DecodeError::ShortPayload { .. }) => refuse(AckResult::BadLength),
        Err(_) => refuse(AckResult::UnknownType),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_wire::protocol::{encode_frame, encode_raw, SetThrottle, MAX_FRAME_LEN};

    fn read(bytes: &[u8]) -> Vec<Incoming> {
        let mut r = CommandReader::new();
        let mut v = Vec::new();
        r.push(bytes, |i| v.push(i));
        v
    }

    fn raw(ver: u8, t: u8, seq: u16, p: &[u8]) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode_raw(ver, t, seq, p, &mut out).unwrap();
        out[..n].to_vec()
    }

    #[test]
    fn commands_refusals_and_garbage_are_told_apart() {
        let mut wire = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(
            8,
            &Message::SetThrottle(SetThrottle {
                level: 3500,
                ramp_ms: 0,
            }),
            &mut wire,
        );
        let mut bytes = b"noise\0".to_vec();
        bytes.extend_from_slice(&wire[..n]);
        bytes.extend(raw(1, 0x04, 9, &[1])); // short SET_THROTTLE
        bytes.extend(raw(1, 0x30, 10, &[])); // unknown command type
        bytes.extend(raw(1, 0x42, 11, &[0; 32])); // a device type sent to the device
        bytes.extend(raw(2, 0x06, 12, &[])); // another version
        let got = read(&bytes);
        assert_eq!(got[0], Incoming::Garbage);
        assert!(matches!(got[1], Incoming::Command { seq: 8, .. }));
        let refused: Vec<(u16, u8, AckResult)> = got[2..]
            .iter()
            .map(|i| match *i {
                Incoming::Refused {
                    seq,
                    msg_type,
                    result,
                } => (seq, msg_type, result),
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(
            refused,
            vec![
                (9, 0x04, AckResult::BadLength),
                (10, 0x30, AckResult::UnknownType),
                (11, 0x42, AckResult::UnknownType),
                (12, 0x06, AckResult::Version),
            ]
        );
    }

    #[test]
    fn protocol_test_vector_stop_is_a_command() {
        let got = read(&[0x04, 0x01, 0x06, 0x0a, 0x03, 0x33, 0x34, 0x00]);
        assert_eq!(
            got,
            vec![Incoming::Command {
                seq: 10,
                msg: Message::Stop
            }]
        );
    }

    #[test]
    fn byte_at_a_time_gives_the_same_commands() {
        let mut bytes = b"junk\0".to_vec();
        bytes.extend_from_slice(&[0x04, 0x01, 0x06, 0x0a, 0x03, 0x33, 0x34, 0x00]);
        bytes.extend(raw(1, 0x04, 9, &[1]));
        let whole = read(&bytes);
        let mut r = CommandReader::new();
        let mut single = Vec::new();
        for b in &bytes {
            r.push(std::slice::from_ref(b), |i| single.push(i));
        }
        assert_eq!(whole, single);
        assert_eq!(
            r.stats().commands + r.stats().refused + r.stats().garbage,
            3
        );
    }

    #[test]
    fn oversize_block_is_garbage_and_the_next_frame_survives() {
        let mut bytes = vec![0x55u8; 400];
        bytes.push(0);
        bytes.extend_from_slice(&[0x04, 0x01, 0x06, 0x0a, 0x03, 0x33, 0x34, 0x00]);
        let got = read(&bytes);
        assert_eq!(got.len(), 2);
        assert_eq!(got[0], Incoming::Garbage);
        assert!(matches!(got[1], Incoming::Command { seq: 10, .. }));
    }
}
