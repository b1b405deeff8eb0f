//! Which boot of the bench a CSV `# HELLO` line speaks for.
//!
//! Binary HELLO frames carry a CRC; CSV comment lines usually carry no checksum, so one bit
//! flipped in `boot_id` would read as a device reset — and a reset ends the experiment plan
//! (it never re-arms by itself). A changed boot id is therefore believed only when two
//! consecutive HELLO lines agree on it (benches say HELLO every second; a real reset also shows
//! as the time column going back, which restarts the numbering on its own). A HELLO line with a
//! valid `*HH` is checked by the line decoder, but the rule is the same for every line.
//!
//! A bench that never says HELLO gets a made-up boot 0 when it acknowledges PING (so the
//! plan's handshake completes); if HELLO lines appear later, the first boot id they name *is*
//! that boot 0, not a new one.

/// What to do with a HELLO line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HelloVerdict {
    /// The current boot (or the first one): pass it on with this boot id.
    Same(u32),
    /// A confirmed new boot: restart the numbering, then pass it on with this boot id.
    New(u32),
    /// A changed boot id seen once: held back until a second line confirms it.
    Unconfirmed,
}

/// The bench's boot as far as the CSV link knows it.
#[derive(Debug, Clone, Copy, Default)]
pub struct BootTracker {
    current: Option<u32>,
    pending: Option<u32>,
    made_up: bool,
    alias: Option<u32>,
}

impl BootTracker {
    /// Whether any boot is known (real or made up).
    pub fn known(&self) -> bool {
        self.current.is_some()
    }

    /// The bench acknowledged PING without ever saying HELLO: boot 0 is made up.
    pub fn make_up(&mut self) {
        self.current = Some(0);
        self.made_up = true;
    }

    /// A HELLO line naming `boot_id`.
    pub fn hello(&mut self, boot_id: u32) -> HelloVerdict {
        let shown = if self.made_up && *self.alias.get_or_insert(boot_id) == boot_id {
            0
        } else {
            boot_id
        };
        match self.current {
            None => {
                self.current = Some(shown);
                HelloVerdict::Same(shown)
            }
            Some(b) if b == shown => {
                self.pending = None;
                HelloVerdict::Same(shown)
            }
            Some(_) if self.pending == Some(shown) => {
                self.pending = None;
                self.current = Some(shown);
                HelloVerdict::New(shown)
            }
            Some(_) => {
                self.pending = Some(shown);
                HelloVerdict::Unconfirmed
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use HelloVerdict::*;

    #[test]
    fn one_corrupted_hello_is_not_a_reset_two_agreeing_ones_are() {
        let mut b = BootTracker::default();
        assert_eq!(b.hello(7), Same(7));
        assert_eq!(b.hello(7 ^ 0x400), Unconfirmed); // one bit flipped
        assert_eq!(b.hello(7), Same(7));
        assert_eq!(b.hello(9), Unconfirmed); // a real reset ...
        assert_eq!(b.hello(9), New(9)); // ... confirmed by the next HELLO
        assert_eq!(b.hello(9), Same(9));
    }

    #[test]
    fn a_made_up_boot_is_the_boot_later_hellos_name_first() {
        let mut b = BootTracker::default();
        assert!(!b.known());
        b.make_up();
        assert!(b.known());
        assert_eq!(b.hello(0xABCD), Same(0));
        assert_eq!(b.hello(0xABCD), Same(0));
        assert_eq!(b.hello(5), Unconfirmed);
        assert_eq!(b.hello(5), New(5));
    }
}
