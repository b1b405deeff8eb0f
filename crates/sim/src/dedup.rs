//! The device's memory of recent commands (docs/PROTOCOL.md §4, reliability): the last 8
//! `(seq, type, result)`, so that a command the host re-sends because an ACK was lost is answered
//! again with the stored result and the DUPLICATE flag, without being executed twice.

/// How many commands are remembered.
pub const DEDUP_DEPTH: usize = 8;

/// How long a remembered command counts as a repeat, µs (one second).
pub const DEDUP_WINDOW_US: u64 = 1_000_000;

#[derive(Debug, Clone, Copy)]
struct Entry {
    seq: u16,
    msg_type: u8,
    result: u8,
    at_us: u64,
}

/// A ring of the last [`DEDUP_DEPTH`] executed commands. Fixed size, no allocation.
#[derive(Debug, Clone, Default)]
pub struct Dedup {
    ring: [Option<Entry>; DEDUP_DEPTH],
    next: usize,
}

impl Dedup {
    /// An empty memory (a fresh boot).
    pub fn new() -> Self {
        Self::default()
    }

    /// The stored result code when `(seq, msg_type)` was executed less than one second before
    /// `now_us` (device time since boot).
    pub fn lookup(&self, seq: u16, msg_type: u8, now_us: u64) -> Option<u8> {
        self.ring
            .iter()
            .flatten()
            .filter(|e| e.seq == seq && e.msg_type == msg_type)
            .filter(|e| now_us.saturating_sub(e.at_us) < DEDUP_WINDOW_US)
            .max_by_key(|e| e.at_us)
            .map(|e| e.result)
    }

    /// Remembers an executed command, forgetting the oldest of the eight.
    pub fn remember(&mut self, seq: u16, msg_type: u8, result: u8, now_us: u64) {
        self.ring[self.next] = Some(Entry {
            seq,
            msg_type,
            result,
            at_us: now_us,
        });
        self.next = (self.next + 1) % DEDUP_DEPTH;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeat_within_a_second_is_found_with_its_result() {
        let mut d = Dedup::new();
        d.remember(9, 0x05, 6, 1000);
        assert_eq!(d.lookup(9, 0x05, 1000 + 999_999), Some(6));
        assert_eq!(d.lookup(9, 0x05, 1000 + 1_000_000), None);
        assert_eq!(d.lookup(9, 0x04, 2000), None, "same seq, other type");
    }

    #[test]
    fn only_the_last_eight_are_remembered() {
        let mut d = Dedup::new();
        for s in 0..9u16 {
            d.remember(s, 0x07, 0, 10);
        }
        assert_eq!(d.lookup(0, 0x07, 10), None);
        assert_eq!(d.lookup(1, 0x07, 10), Some(0));
        assert_eq!(d.lookup(8, 0x07, 10), Some(0));
    }
}
