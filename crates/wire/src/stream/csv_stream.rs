//! A CSV bench's stream (docs/PROTOCOL.md §6) as the facts a binary device would have sent: every
//! data row placed at a sample index ([`RowPlacer`]), `# HELLO` lines believed by one rule
//! ([`BootTracker`]), `#EVENT` lines placed by their time. The daemon's CSV link (live runs and
//! `replay`) and recording ingest (`identify`) both read CSV through this one adapter, so a
//! recording replayed and the same recording identified place every row at the same index.
//!
//! | decoded line ([`CsvItem`])             | becomes ([`CsvFact`])                                 |
//! |----------------------------------------|-------------------------------------------------------|
//! | data row with a time ≥ 0               | [`CsvFact::Row`]: index from the time ([`RowPlacer`]; an `idx` column is kept), possibly a few rows later (warm-up) |
//! | data row without a time                | dropped, counted (`untimed`)                          |
//! | `# HELLO … boot_id H rate_hz R`        | [`CsvFact::Hello`]; the rate sets the period; a changed boot id only once two lines agree, then [`CsvFact::NewBoot`] after the old boot's rows and before the HELLO |
//! | `#EVENT NAME arg t_us index`           | [`CsvFact::Event`], its `sample_index` from its time in the current numbering (the bench's own index is not ours) |
//! | `#ACK …`                               | [`CsvFact::Ack`]; the first `#ACK PING OK` of a bench that never said HELLO is preceded by a made-up HELLO (boot 0, the measured rate), so a handshake completes |
//!
//! Headers and other comments carry no fact. Allocation-free after [`CsvStream::new`].

use super::boot::{BootTracker, HelloVerdict};
use super::place::{Placed, Placement, RowPlacer};
use crate::protocol::csv::{parse_comment, CommentFact, CsvAck, CsvCommandKind, CsvItem, CsvRow};
use crate::protocol::message::{EscProtocol, Event, Hello};

/// What a CSV line stands for (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CsvFact {
    /// A data row with its place (`index` in the current numbering, unwrapped `t_us`).
    Row(Placed<CsvRow>),
    /// A confirmed new boot: the old boot's rows have all been handed on; its HELLO follows.
    NewBoot,
    /// A HELLO (boot id as confirmed, or made up).
    Hello(Hello),
    /// A device event, `sample_index` in the current numbering.
    Event(Event),
    /// An acknowledgement.
    Ack(CsvAck),
}

/// Counters of the adapter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CsvStreamStats {
    /// Data rows placed (or held to be placed).
    pub rows: u64,
    /// Rows dropped because their time went back a little (out of order).
    pub out_of_order: u64,
    /// Rows dropped because they had no time.
    pub untimed: u64,
    /// ACK lines.
    pub acks: u64,
    /// HELLO lines naming another boot, held back until a second one confirmed it.
    pub unconfirmed_hellos: u64,
}

/// CSV lines in, device facts out (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct CsvStream {
    placer: RowPlacer<CsvRow>,
    boot: BootTracker,
    stats: CsvStreamStats,
}

impl CsvStream {
    /// An adapter; the placer's warm-up buffer is allocated here, once.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counters so far.
    pub fn stats(&self) -> &CsvStreamStats {
        &self.stats
    }

    /// The sample period in use, µs (`None` while the placer still measures it).
    pub fn period_us(&self) -> Option<f64> {
        self.placer.period_us()
    }

    /// One decoded line; its facts go to `on`, in order.
    pub fn item(&mut self, item: CsvItem<'_>, on: &mut impl FnMut(CsvFact)) {
        let mut row = |p: Placed<CsvRow>| on(CsvFact::Row(p));
        match item {
            CsvItem::Header(_) => {}
            CsvItem::Row(r) => {
                let Some(t_s) = r.t_s.filter(|t| t.is_finite() && *t >= 0.0) else {
                    self.stats.untimed += 1;
                    return;
                };
                let t_us = (t_s * 1e6).round() as u64;
                let own_index = r.index.filter(|i| *i >= 0.0).map(|i| i as u64);
                match self.placer.push(t_us, own_index, r, &mut row) {
                    // a restart shows downstream as the index going back: a new segment
                    Placement::Accepted | Placement::Restarted => self.stats.rows += 1,
                    Placement::OutOfOrder => self.stats.out_of_order += 1,
                }
            }
            CsvItem::Ack(ack) => {
                self.stats.acks += 1;
                if ack.command == CsvCommandKind::Ping && ack.result.is_ok() && !self.boot.known() {
                    // A bench that never says HELLO: one is made up so the handshake completes.
                    self.boot.make_up();
                    let rate = self
                        .placer
                        .period_us()
                        .map_or(0, |p| (1e6 / p).round().clamp(0.0, 65_535.0) as u16);
                    on(CsvFact::Hello(made_up_hello(rate)));
                }
                on(CsvFact::Ack(ack));
            }
            CsvItem::Comment(text) => match parse_comment(text) {
                Some(CommentFact::Hello(mut h)) => {
                    h.boot_id = match self.boot.hello(h.boot_id) {
                        HelloVerdict::Same(b) => b,
                        HelloVerdict::New(b) => {
                            // a new boot: what the old one sent goes first, then numbering
                            // restarts
                            self.placer.restart(&mut row);
                            on(CsvFact::NewBoot);
                            b
                        }
                        HelloVerdict::Unconfirmed => {
                            self.stats.unconfirmed_hellos += 1;
                            return;
                        }
                    };
                    let mut row = |p: Placed<CsvRow>| on(CsvFact::Row(p));
                    self.placer.announce_rate(h.sample_rate_hz, &mut row);
                    on(CsvFact::Hello(h));
                }
                Some(CommentFact::Event(mut e)) => {
                    // the bench's own index is not ours: place the event by its time
                    e.sample_index = self.placer.index_at(u64::from(e.t_us)).unwrap_or(0) as u32;
                    on(CsvFact::Event(e));
                }
                None => {}
            },
        }
    }

    /// End of input: rows held for the period estimate are placed.
    pub fn finish(&mut self, on: &mut impl FnMut(CsvFact)) {
        self.placer.flush(&mut |p| on(CsvFact::Row(p)));
    }
}

/// The HELLO of a bench that never said one.
pub fn made_up_hello(rate_hz: u16) -> Hello {
    Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::None,
        fw_version: 0,
        boot_id: 0,
        t_us: 0,
        sample_rate_hz: rate_hz,
        channels: 0,
        motor_poles: 0,
        caps: 0,
        name: Hello::name_field("csv-bench"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::csv::{device_line, CsvDecoder};
    use crate::protocol::message::{EventCode, Message, Sample};

    fn facts(text: &str) -> (Vec<CsvFact>, CsvStreamStats) {
        let mut dec = CsvDecoder::default();
        let mut s = CsvStream::new();
        let mut out = Vec::new();
        dec.push(text.as_bytes(), |it| s.item(it, &mut |f| out.push(f)));
        dec.finish(|it| s.item(it, &mut |f| out.push(f)));
        s.finish(&mut |f| out.push(f));
        (out, *s.stats())
    }

    fn hello(boot_id: u32, rate: u16) -> String {
        let mut h = made_up_hello(rate);
        h.boot_id = boot_id;
        device_line(&Message::Hello(h)).unwrap_or_default()
    }

    fn row(t_us: u32) -> String {
        let s = Sample {
            t_us,
            throttle: 3000,
            thrust_n: 1.0,
            ..Sample::default()
        };
        device_line(&Message::Sample(s)).unwrap_or_default()
    }

    fn indices(f: &[CsvFact]) -> Vec<u64> {
        f.iter()
            .filter_map(|f| match f {
                CsvFact::Row(p) => Some(p.index),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_confirmed_new_boot_restarts_the_numbering_after_the_old_rows() {
        let mut text = hello(1, 1000);
        (0..5).for_each(|k| text += &row(1_000_000 + k * 1000));
        text += &hello(2, 1000); // one line: not believed yet
        (5..8).for_each(|k| text += &row(1_000_000 + k * 1000));
        text += &hello(2, 1000); // confirmed
        (0..3).for_each(|k| text += &row(2000 + k * 1000));
        let (f, st) = facts(&text);
        assert_eq!(indices(&f), [0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2]);
        let new_boot = f.iter().position(|f| *f == CsvFact::NewBoot).unwrap();
        assert!(matches!(f[new_boot - 1], CsvFact::Row(p) if p.index == 7));
        assert!(matches!(f[new_boot + 1], CsvFact::Hello(h) if h.boot_id == 2));
        assert_eq!((st.rows, st.unconfirmed_hellos), (11, 1));
    }

    #[test]
    fn events_are_placed_by_time_and_a_silent_bench_gets_a_made_up_hello() {
        let mut text = String::new();
        (0..20).for_each(|k| text += &row(k * 2000));
        text += "#ACK PING OK 40000\n";
        text += "#EVENT IMPULSE_START 0 30000 999\n";
        text += "1,2\n"; // a time of 1 µs, long before the last row: out of order
        text += "x,1,2\n";
        let (f, st) = facts(&text);
        let made_up = f.iter().find_map(|f| match f {
            CsvFact::Hello(h) => Some(*h),
            _ => None,
        });
        assert_eq!(
            made_up.map(|h| (h.boot_id, h.sample_rate_hz)),
            Some((0, 500))
        );
        let ev = f.iter().find_map(|f| match f {
            CsvFact::Event(e) => Some(*e),
            _ => None,
        });
        assert_eq!(
            ev.map(|e| (e.code, e.sample_index)),
            Some((EventCode::ImpulseStart, 15))
        );
        assert_eq!((st.rows, st.acks, st.out_of_order), (20, 1, 1));
    }
}
