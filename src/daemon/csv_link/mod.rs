//! The CSV fallback of TSP/1 (PROTOCOL.md §6) as the daemon speaks it, sans-IO: text in,
//! TSP/1 [`Frame`]s out, commands out as CSV lines.
//!
//! The daemon is built on binary frames (the sampler's tracker, the experiment plan, the
//! worker's windows). A CSV bench is made to look like a binary one here, so everything after
//! this adapter is the same code for both wire formats:
//!
//! | CSV (§6)                              | becomes                                             |
//! |---------------------------------------|-----------------------------------------------------|
//! | data row (any header, units, `*HH`)   | SAMPLE: index from the time ([`placer`]), pulse     |
//! |                                       | flags from the throttle ([`pulse_flags`]), VALID    |
//! |                                       | flags from the columns present                      |
//! | `#ACK <CMD> OK <t_us>` / `ERR <code>` | ACK of the last command of that kind sent ([`CsvLink::command_sent`]) — CSV lines carry no seq |
//! | `# HELLO … boot_id H rate_hz R`       | HELLO ([`comments`]); a changed boot id only once two lines agree ([`boot`]) |
//! | `#EVENT NAME arg t_us index`          | EVENT                                               |
//! | first `#ACK PING OK` without a HELLO  | a HELLO with boot id 0 and the measured rate, so the plan's handshake completes with a bench that never says HELLO |
//!
//! Commands are written with [`encode_csv_command`] (`PING`, `ARM`, `THR`, `IMP`, `STOP`, …).
//! CSV commands carry no sequence number: a re-sent command is executed again by the bench
//! (THR and STOP are idempotent; a re-sent IMP fires a second pulse, which the identification
//! sees as one more pulse).
//!
//! Every line is accounted for: decoded lines are `frames_ok`, dropped ones are counted by
//! kind ([`CsvLinkStats::dropped`]).

pub mod boot;
pub mod comments;
pub mod placer;
pub mod pulse_flags;

use boot::{BootTracker, HelloVerdict};
use comments::{parse_comment, CommentFact};
use placer::{IndexPlacer, Placement};
use propid_numerics::segment::SegmentRules;
use propid_wire::protocol::csv::{CsvAck, CsvDecoder, CsvItem, CsvOptions, CsvRow};
use propid_wire::protocol::csv_command::{encode_csv_command, CsvCommandError, CsvCommandKind};
use propid_wire::protocol::message::{
    msg_type, Ack, AckResult, EscProtocol, Frame, Hello, Message, Sample, SampleFlags,
};
use pulse_flags::PulseFlagger;

/// How the adapter reads a CSV bench.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CsvLinkOptions {
    /// Line decoder options (ESC µs range, motor poles, longest line).
    pub csv: CsvOptions,
    /// Level tolerance of the pulse rule, fraction ([`SegmentRules::level_tolerance`]).
    pub level_tolerance: f64,
    /// Longest pulse, samples ([`SegmentRules::max_pulse_samples`]).
    pub max_pulse_samples: usize,
}

impl Default for CsvLinkOptions {
    fn default() -> Self {
        Self {
            csv: CsvOptions::default(),
            level_tolerance: SegmentRules::CSV_BENCH.level_tolerance,
            max_pulse_samples: SegmentRules::CSV_BENCH.max_pulse_samples,
        }
    }
}

/// Counters of the adapter (the line decoder's and its own).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CsvLinkStats {
    /// Data rows handed on as SAMPLEs.
    pub rows: u64,
    /// Rows dropped because their time went back a little (out of order).
    pub out_of_order: u64,
    /// Rows dropped because they had no time.
    pub untimed: u64,
    /// ACK lines.
    pub acks: u64,
    /// Pulses found from the throttle column.
    pub pulses: u64,
    /// HELLO lines naming another boot, held back until a second one confirmed it.
    pub unconfirmed_hellos: u64,
}

/// The daemon's CSV link (see the module documentation).
pub struct CsvLink {
    decoder: CsvDecoder,
    state: LinkState,
}

/// Everything that turns decoded lines into frames.
struct LinkState {
    placer: IndexPlacer,
    flagger: PulseFlagger,
    /// Per command kind: the seq and wire type of the last one sent.
    sent: [Option<(u16, u8)>; 6],
    /// The bench's boot as its HELLO lines (or a made-up one) tell it.
    boot_id: BootTracker,
    stats: CsvLinkStats,
    seq: u16,
}

impl CsvLink {
    /// An adapter; its buffers are allocated here, once.
    pub fn new(opts: CsvLinkOptions) -> Self {
        Self {
            decoder: CsvDecoder::new(opts.csv),
            state: LinkState {
                placer: IndexPlacer::new(),
                flagger: PulseFlagger::new(SegmentRules {
                    level_tolerance: opts.level_tolerance,
                    max_pulse_samples: opts.max_pulse_samples,
                    ..SegmentRules::CSV_BENCH
                }),
                sent: [None; 6],
                boot_id: BootTracker::default(),
                stats: CsvLinkStats::default(),
                seq: 0,
            },
        }
    }

    /// The adapter's counters.
    pub fn stats(&self) -> CsvLinkStats {
        CsvLinkStats {
            pulses: self.state.flagger.pulses(),
            ..self.state.stats
        }
    }

    /// Lines that decoded (rows, headers, ACKs, comments).
    pub fn lines_ok(&self) -> u64 {
        let d = self.decoder.stats();
        d.rows + d.headers + d.comments
    }

    /// Dropped lines and rows, one count per kind (the `frames_dropped` names of a CSV link).
    pub fn dropped(&self) -> [(&'static str, u64); 6] {
        let d = self.decoder.stats();
        [
            ("line_too_long", d.too_long),
            ("bad_checksum", d.bad_checksum),
            ("bad_row", d.bad_row),
            ("row_out_of_order", self.state.stats.out_of_order),
            ("row_without_time", self.state.stats.untimed),
            ("hello_unconfirmed", self.state.stats.unconfirmed_hellos),
        ]
    }

    /// Writes `msg` as a command line into `out` and remembers its seq, so that the bench's
    /// `#ACK` can be given back to the plan as the ACK of this command.
    pub fn encode_command(
        &mut self,
        seq: u16,
        msg: &Message,
        out: &mut [u8],
    ) -> Result<usize, CsvCommandError> {
        let n = encode_csv_command(msg, out)?;
        if let Some(k) = kind_of(msg) {
            self.state.sent[k as usize] = Some((seq, msg.msg_type()));
        }
        Ok(n)
    }

    /// Bytes in; frames out, in order (samples possibly a few rows later, see the module
    /// documentation).
    pub fn push(&mut self, bytes: &[u8], on_frame: &mut impl FnMut(Frame)) {
        let state = &mut self.state;
        self.decoder
            .push(bytes, |item| state.on_item(item, &mut *on_frame));
    }

    /// End of input: the last line, rows held for the period estimate or an open excursion.
    pub fn finish(&mut self, on_frame: &mut impl FnMut(Frame)) {
        let state = &mut self.state;
        self.decoder
            .finish(|item| state.on_item(item, &mut *on_frame));
        let LinkState {
            placer,
            flagger,
            seq,
            ..
        } = state;
        let mut out = Out { seq, on_frame };
        let mut to_flagger = |s: Sample| flagger.push(s, &mut |s| out.sample(s));
        placer.flush(&mut to_flagger);
        flagger.flush(&mut |s| out.sample(s));
    }
}

/// Numbers the frames it hands on (device-side seq, as a binary device would).
struct Out<'a, F: FnMut(Frame)> {
    seq: &'a mut u16,
    on_frame: &'a mut F,
}

impl<F: FnMut(Frame)> Out<'_, F> {
    fn frame(&mut self, msg: Message) {
        let seq = *self.seq;
        *self.seq = seq.wrapping_add(1);
        (self.on_frame)(Frame { seq, msg });
    }

    fn sample(&mut self, s: Sample) {
        self.frame(Message::Sample(s));
    }
}

impl LinkState {
    /// One decoded line: the frames it stands for go to `on_frame`.
    fn on_item(&mut self, item: CsvItem<'_>, on_frame: &mut impl FnMut(Frame)) {
        let LinkState {
            placer,
            flagger,
            sent,
            boot_id,
            stats,
            seq,
        } = self;
        on_item(
            item,
            placer,
            flagger,
            sent,
            boot_id,
            stats,
            &mut Out { seq, on_frame },
        );
    }
}

#[allow(clippy::too_many_arguments)]
fn on_item<F: FnMut(Frame)>(
    item: CsvItem<'_>,
    placer: &mut IndexPlacer,
    flagger: &mut PulseFlagger,
    sent: &[Option<(u16, u8)>; 6],
    boot_id: &mut BootTracker,
    stats: &mut CsvLinkStats,
    out: &mut Out<'_, F>,
) {
    match item {
        CsvItem::Header(_) => {}
        CsvItem::Row(row) => {
            let Some(t_s) = row.t_s.filter(|t| t.is_finite() && *t >= 0.0) else {
                stats.untimed += 1;
                return;
            };
            let t_us = (t_s * 1e6).round() as u64;
            let own_index = row.index.filter(|i| *i >= 0.0).map(|i| i as u64);
            let sample = to_sample(&row);
            let mut to_flagger = |s: Sample| flagger.push(s, &mut |s| out.sample(s));
            match placer.push(t_us, own_index, sample, &mut to_flagger) {
                // a restart shows downstream as the index going back: a new segment
                Placement::Accepted | Placement::Restarted => stats.rows += 1,
                Placement::OutOfOrder => stats.out_of_order += 1,
            }
        }
        CsvItem::Ack(ack) => {
            stats.acks += 1;
            if ack.command == CsvCommandKind::Ping && ack.result.is_ok() && !boot_id.known() {
                // A bench that never says HELLO: one is made up so the handshake completes.
                boot_id.make_up();
                let rate = placer
                    .period_us()
                    .map_or(0, |p| (1e6 / p).round().clamp(0.0, 65_535.0) as u16);
                out.frame(Message::Hello(made_up_hello(rate)));
            }
            if let Some(a) = to_ack(&ack, sent) {
                out.frame(Message::Ack(a));
            }
        }
        CsvItem::Comment(text) => match parse_comment(text) {
            Some(CommentFact::Hello(mut h)) => {
                let mut to_flagger = |s: Sample| flagger.push(s, &mut |s| out.sample(s));
                h.boot_id = match boot_id.hello(h.boot_id) {
                    HelloVerdict::Same(b) => b,
                    HelloVerdict::New(b) => {
                        // a new boot: what the old one sent goes first, then numbering restarts
                        placer.restart(&mut to_flagger);
                        flagger.restart(&mut |s| out.sample(s));
                        b
                    }
                    HelloVerdict::Unconfirmed => {
                        stats.unconfirmed_hellos += 1;
                        return;
                    }
                };
                let mut to_flagger = |s: Sample| flagger.push(s, &mut |s| out.sample(s));
                placer.announce_rate(h.sample_rate_hz, &mut to_flagger);
                out.frame(Message::Hello(h));
            }
            Some(CommentFact::Event(mut e)) => {
                // the bench's own index is not ours: place the event by its time
                e.sample_index = placer.index_at(u64::from(e.t_us)).unwrap_or(0) as u32;
                out.frame(Message::Event(e));
            }
            None => {}
        },
    }
}

/// A CSV row as a SAMPLE (index, time and pulse flags are set later).
fn to_sample(row: &CsvRow) -> Sample {
    let mut flags = 0u16;
    let mut value = |v: Option<f64>, bit: SampleFlags| match v {
        Some(x) if x.is_finite() => {
            flags |= bit.0;
            x as f32
        }
        _ => f32::NAN,
    };
    let thrust_n = value(row.thrust_n, SampleFlags::THRUST_VALID);
    let torque_nm = value(row.torque_nm, SampleFlags::TORQUE_VALID);
    let rpm = value(row.rpm, SampleFlags::RPM_VALID);
    let voltage_v = value(row.voltage_v, SampleFlags::VOLTAGE_VALID);
    let current_a = value(row.current_a, SampleFlags::CURRENT_VALID);
    let throttle = row
        .throttle
        .filter(|t| t.is_finite())
        .map_or(0, |t| (t * 10_000.0).round().clamp(0.0, 10_000.0) as u16);
    Sample {
        sample_index: 0,
        t_us: 0,
        throttle,
        flags: SampleFlags(flags),
        thrust_n,
        torque_nm,
        rpm,
        voltage_v,
        current_a,
    }
}

/// The command kind a message is written as (HELLO_REQ and HEARTBEAT are both `PING`).
fn kind_of(msg: &Message) -> Option<CsvCommandKind> {
    Some(match msg {
        Message::HelloReq | Message::Heartbeat => CsvCommandKind::Ping,
        Message::Arm(_) => CsvCommandKind::Arm,
        Message::Disarm => CsvCommandKind::Disarm,
        Message::SetThrottle(_) => CsvCommandKind::Thr,
        Message::Impulse(_) => CsvCommandKind::Imp,
        Message::Stop => CsvCommandKind::Stop,
        _ => return None,
    })
}

/// The ACK a `#ACK` line stands for: that of the last command of its kind sent.
fn to_ack(ack: &CsvAck, sent: &[Option<(u16, u8)>; 6]) -> Option<Ack> {
    if ack.command == CsvCommandKind::Other {
        return None;
    }
    let (cmd_seq, cmd_type) = sent[ack.command as usize].unwrap_or((
        0,
        match ack.command {
            CsvCommandKind::Ping => msg_type::HELLO_REQ,
            CsvCommandKind::Arm => msg_type::ARM,
            CsvCommandKind::Disarm => msg_type::DISARM,
            CsvCommandKind::Thr => msg_type::SET_THROTTLE,
            CsvCommandKind::Imp => msg_type::IMPULSE,
            _ => msg_type::STOP,
        },
    ));
    let (result, t_us) = match ack.result {
        Ok(t) => (AckResult::Ok, t.unwrap_or(0) as u32),
        Err(code) => (AckResult::from_u8(code.clamp(0, 255) as u8), 0),
    };
    Some(Ack {
        cmd_seq,
        cmd_type,
        result,
        ack_flags: 0,
        t_us,
    })
}

fn made_up_hello(rate_hz: u16) -> Hello {
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
mod tests;
