//! TSP/1 messages, both directions (docs/PROTOCOL.md §3, §4), and their registry.
//!
//! Each message type lives in one file and implements [`WireMessage`] there (type code, name,
//! payload layout, CSV form, test vector): HELLO in [`hello`], SAMPLE in [`sample`], ACK /
//! EVENT / LOG in [`reply`], the commands in [`command`]. The `messages!` list below registers
//! them, one line each, and makes [`Message`], [`msg_type`] and every dispatch over the types
//! (parse, write, names, CSV) from it. Everything is `Copy` and fixed-size (a LOG text lives in
//! a 200-byte array), so decoding a frame never allocates.

mod command;
mod hello;
mod reply;
mod sample;
mod wire_message;

use super::error::DecodeError;
use super::payload::{Writer, MAX_PAYLOAD};

pub use command::{
    Arm, Disarm, Heartbeat, HelloReq, Impulse, SetRate, SetThrottle, Stop, Tare, ARM_KEY,
};
pub use hello::{caps, EscProtocol, Hello};
#[cfg(test)]
pub(crate) use reply::EVENT_NAMES;
pub use reply::{
    event_code, event_name, Ack, AckResult, Event, EventCode, Log, ACK_DUPLICATE, LOG_TEXT_MAX,
};
pub use sample::{throttle_fraction, throttle_level, Sample, SampleFlags, THROTTLE_FULL_SCALE};
pub use wire_message::{CsvArgError, CsvArgs, CsvCommandForm, Vector, WireMessage};

/// Makes [`Message`], [`msg_type`] and the dispatch over the registered types. `payload`:
/// `CONST => Type` for a message whose variant carries `Type`; `unit`: the same for a
/// payload-less command (a unit struct, the variant carries nothing).
macro_rules! messages {
    (
        payload { $( $(#[$pd:meta])* $pc:ident => $p:ident, )* }
        unit { $( $(#[$ud:meta])* $uc:ident => $u:ident, )* }
    ) => {
        /// Message type codes (`type` byte of the frame body), from each message's
        /// [`WireMessage::TYPE`].
        pub mod msg_type {
            use super::WireMessage;
            $( $(#[$pd])* pub const $pc: u8 = <super::$p as WireMessage>::TYPE; )*
            $( $(#[$ud])* pub const $uc: u8 = <super::$u as WireMessage>::TYPE; )*
        }

        /// Any TSP/1 message, device → host or host → device.
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum Message {
            $( $(#[$pd])* $p($p), )*
            $( $(#[$ud])* $u, )*
        }

        impl Message {
            /// The wire type code.
            pub fn msg_type(&self) -> u8 {
                match self {
                    $( Self::$p(_) => msg_type::$pc, )*
                    $( Self::$u => msg_type::$uc, )*
                }
            }

            /// Protocol name of the message type (`"SAMPLE"`, `"SET_THROTTLE"`, …).
            pub fn name(&self) -> &'static str {
                match self {
                    $( Self::$p(_) => <$p as WireMessage>::NAME, )*
                    $( Self::$u => <$u as WireMessage>::NAME, )*
                }
            }

            /// Parses the payload of a message of type `msg_type`: its type's minimum length
            /// checked, trailing bytes ignored.
            pub fn parse(t: u8, p: &[u8]) -> Result<Message, DecodeError> {
                let min = min_payload_len(t).ok_or(DecodeError::UnknownType(t))?;
                if p.len() < min {
                    return Err(DecodeError::ShortPayload {
                        msg_type: t,
                        len: p.len(),
                        min,
                    });
                }
                // Every message reads within its minimum length, checked above.
                Ok(match t {
                    $( msg_type::$pc => Self::$p(<$p as WireMessage>::parse(p)), )*
                    $( msg_type::$uc => Self::$u, )*
                    other => return Err(DecodeError::UnknownType(other)),
                })
            }

            /// Writes the payload into `out`; returns its length.
            pub fn write_payload(&self, out: &mut [u8; MAX_PAYLOAD]) -> usize {
                let mut w = Writer::new(out);
                match self {
                    $( Self::$p(m) => m.write(&mut w), )*
                    $( Self::$u => $u.write(&mut w), )*
                }
                w.len()
            }

            /// The keyword of its CSV command line (`None`: it has none).
            pub fn csv_keyword(&self) -> Option<&'static str> {
                csv_keyword(self.msg_type())
            }

            /// Writes the arguments of its CSV command line.
            pub fn write_csv_args(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
                match self {
                    $( Self::$p(m) => m.write_csv_args(w), )*
                    $( Self::$u => $u.write_csv_args(w), )*
                }
            }

            /// Appends the line a CSV bench writes for it (no newline); false when it has none.
            pub fn write_csv_line(&self, s: &mut String) -> bool {
                match self {
                    $( Self::$p(m) => m.write_csv_line(s), )*
                    $( Self::$u => $u.write_csv_line(s), )*
                }
            }

            /// Reads a CSV command line's arguments as the message that reads `keyword`
            /// (`None` when no message does).
            pub fn parse_csv_args(
                keyword: &str,
                args: &mut CsvArgs<'_>,
            ) -> Option<Result<Message, CsvArgError>> {
                $( if <$p as WireMessage>::CSV_COMMAND.reads(keyword) {
                    return Some(<$p as WireMessage>::parse_csv_args(args).map(Self::$p));
                } )*
                $( if <$u as WireMessage>::CSV_COMMAND.reads(keyword) {
                    return Some(<$u as WireMessage>::parse_csv_args(args).map(|_| Self::$u));
                } )*
                None
            }
        }

        /// Protocol name of a known type code.
        pub fn type_name(t: u8) -> Option<&'static str> {
            Some(match t {
                $( msg_type::$pc => <$p as WireMessage>::NAME, )*
                $( msg_type::$uc => <$u as WireMessage>::NAME, )*
                _ => return None,
            })
        }

        /// Minimum payload length of a known type, `None` for an unknown type.
        pub fn min_payload_len(t: u8) -> Option<usize> {
            Some(match t {
                $( msg_type::$pc => <$p as WireMessage>::MIN_LEN, )*
                $( msg_type::$uc => <$u as WireMessage>::MIN_LEN, )*
                _ => return None,
            })
        }

        /// The CSV command form of a type code (`None` for an unknown type too).
        pub fn csv_command_form(t: u8) -> CsvCommandForm {
            match t {
                $( msg_type::$pc => <$p as WireMessage>::CSV_COMMAND, )*
                $( msg_type::$uc => <$u as WireMessage>::CSV_COMMAND, )*
                _ => CsvCommandForm::None,
            }
        }

        /// The type code of the message that reads `keyword` on a CSV command line.
        pub fn csv_reader(keyword: &str) -> Option<u8> {
            $( if <$p as WireMessage>::CSV_COMMAND.reads(keyword) {
                return Some(msg_type::$pc);
            } )*
            $( if <$u as WireMessage>::CSV_COMMAND.reads(keyword) {
                return Some(msg_type::$uc);
            } )*
            None
        }

        /// Every registered message's test vector, as a [`Message`].
        pub fn vectors() -> Vec<Vector<Message>> {
            vec![
                $( {
                    let v = <$p as WireMessage>::vector();
                    Vector { seq: v.seq, msg: Message::$p(v.msg), wire: v.wire, csv: v.csv }
                }, )*
                $( {
                    let v = <$u as WireMessage>::vector();
                    Vector { seq: v.seq, msg: Message::$u, wire: v.wire, csv: v.csv }
                }, )*
            ]
        }
    };
}

messages! {
    payload {
        /// Device → host: identity and state.
        HELLO => Hello,
        /// Device → host: one measurement.
        SAMPLE => Sample,
        /// Device → host: answer to a command.
        ACK => Ack,
        /// Device → host: something happened.
        EVENT => Event,
        /// Device → host: debug text.
        LOG => Log,
        /// Host → device: arm with a watchdog.
        ARM => Arm,
        /// Host → device: set the throttle (step or ramp).
        SET_THROTTLE => SetThrottle,
        /// Host → device: device-timed pulse.
        IMPULSE => Impulse,
        /// Host → device: change the sample rate.
        SET_RATE => SetRate,
    }
    unit {
        /// Host → device: ask for a HELLO.
        HELLO_REQ => HelloReq,
        /// Host → device: disarm.
        DISARM => Disarm,
        /// Host → device: stop everything.
        STOP => Stop,
        /// Host → device: reset the watchdog.
        HEARTBEAT => Heartbeat,
        /// Host → device: tare the load cell.
        TARE => Tare,
    }
}

impl Message {
    /// True for host → device messages (type 0x01..=0x3F).
    pub fn is_command(&self) -> bool {
        is_command_type(self.msg_type())
    }
}

/// True for the host → device type range 0x01..=0x3F.
pub fn is_command_type(t: u8) -> bool {
    (0x01..=0x3F).contains(&t)
}

/// The keyword a type code is written as on a CSV command line (HELLO_REQ and HEARTBEAT both
/// `PING`); `None` for a type without one.
pub fn csv_keyword(t: u8) -> Option<&'static str> {
    csv_command_form(t).keyword()
}

/// A decoded frame: the sender's link sequence number and the message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Per-sender counter (for commands also the command id).
    pub seq: u16,
    /// The message.
    pub msg: Message,
}

/// The longest prefix of `b` that is valid UTF-8.
fn utf8_prefix(b: &[u8]) -> &str {
    match std::str::from_utf8(b) {
        Ok(s) => s,
        // `valid_up_to` is a char boundary, so this inner conversion cannot fail.
        Err(e) => std::str::from_utf8(&b[..e.valid_up_to()]).unwrap_or(""),
    }
}

/// Largest index `<= max` that is a char boundary of `s`.
fn floor_char_boundary(s: &str, max: usize) -> usize {
    if s.len() <= max {
        return s.len();
    }
    (0..=max)
        .rev()
        .find(|&i| s.is_char_boundary(i))
        .unwrap_or(0)
}
