//! The CSV fallback of TSP/1 (docs/PROTOCOL.md §6) as the daemon speaks it, sans-IO: text in,
//! TSP/1 [`Frame`]s out, commands out as CSV lines.
//!
//! The daemon is built on binary frames (the sampler's tracker, the experiment plan, the
//! worker's windows). A CSV bench is made to look like a binary one here, so everything after
//! this adapter is the same code for both wire formats:
//!
//! | CSV (§6)                              | becomes                                             |
//! |---------------------------------------|-----------------------------------------------------|
//! | data row (any header, units, `*HH`)   | SAMPLE: index from the time (the one placer of      |
//! |                                       | [`CsvStream`], as recording ingest), pulse flags    |
//! |                                       | from the throttle ([`pulse_flags`]), VALID flags    |
//! |                                       | from the columns present                            |
//! | `#ACK <CMD> OK <t_us>` / `ERR <code>` | ACK of the last command of that kind sent ([`CsvLink::encode_command`]) — CSV lines carry no seq |
//! | `# HELLO … boot_id H rate_hz R`       | HELLO; a changed boot id only once two lines agree ([`CsvStream`]) |
//! | `#EVENT NAME arg t_us index`          | EVENT, placed by its time ([`CsvStream`])           |
//! | first `#ACK PING OK` without a HELLO  | a HELLO with boot id 0 and the measured rate, so the plan's handshake completes with a bench that never says HELLO |
//!
//! Rows, HELLO and EVENT lines become device facts in `propid_wire`'s [`CsvStream`], the same
//! adapter recording ingest reads CSV with, so a recording replayed here and the same
//! recording identified place every sample at the same index. What is the daemon's own is
//! the rest: SAMPLE frames, pulse flags, ACKs matched to the commands sent.
//!
//! Commands are written with [`encode_csv_command`] (`PING`, `ARM`, `THR`, `IMP`, `STOP`, …).
//! CSV commands carry no sequence number: a re-sent command is executed again by the bench
//! (THR and STOP are idempotent; a re-sent IMP fires a second pulse, which the identification
//! sees as one more pulse).
//!
//! Every line is accounted for: decoded lines are `frames_ok`, dropped ones are counted by
//! kind ([`CsvLinkStats::dropped`]).

pub mod pulse_flags;

use propid_numerics::segment::SegmentRules;
use propid_wire::protocol::csv::{
    encode_csv_command, CsvAck, CsvCommandError, CsvCommandKind, CsvDecoder, CsvOptions, CsvRow,
};
use propid_wire::protocol::message::{Ack, AckResult, Frame, Message, Sample, SampleFlags};
use propid_wire::stream::{CsvFact, CsvStream, Placed};
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
    stream: CsvStream,
    state: LinkState,
}

/// Everything that turns device facts into frames.
struct LinkState {
    flagger: PulseFlagger,
    /// Per command kind: the seq and wire type of the last one sent.
    sent: [Option<(u16, u8)>; 6],
    seq: u16,
}

impl CsvLink {
    /// An adapter; its buffers are allocated here, once.
    pub fn new(opts: CsvLinkOptions) -> Self {
        Self {
            decoder: CsvDecoder::new(opts.csv),
            stream: CsvStream::new(),
            state: LinkState {
                flagger: PulseFlagger::new(SegmentRules {
                    level_tolerance: opts.level_tolerance,
                    max_pulse_samples: opts.max_pulse_samples,
                    ..SegmentRules::CSV_BENCH
                }),
                sent: [None; 6],
                seq: 0,
            },
        }
    }

    /// The adapter's counters.
    pub fn stats(&self) -> CsvLinkStats {
        let s = self.stream.stats();
        CsvLinkStats {
            rows: s.rows,
            out_of_order: s.out_of_order,
            untimed: s.untimed,
            acks: s.acks,
            pulses: self.state.flagger.pulses(),
            unconfirmed_hellos: s.unconfirmed_hellos,
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
        let s = self.stream.stats();
        [
            ("line_too_long", d.too_long),
            ("bad_checksum", d.bad_checksum),
            ("bad_row", d.bad_row),
            ("row_out_of_order", s.out_of_order),
            ("row_without_time", s.untimed),
            ("hello_unconfirmed", s.unconfirmed_hellos),
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
        let k = CsvCommandKind::of(msg);
        if k != CsvCommandKind::Other {
            self.state.sent[k as usize] = Some((seq, msg.msg_type()));
        }
        Ok(n)
    }

    /// Bytes in; frames out, in order (samples possibly a few rows later, see the module
    /// documentation).
    pub fn push(&mut self, bytes: &[u8], on_frame: &mut impl FnMut(Frame)) {
        let Self {
            decoder,
            stream,
            state,
        } = self;
        decoder.push(bytes, |item| {
            stream.item(item, &mut |fact| state.fact(fact, &mut *on_frame))
        });
    }

    /// End of input: the last line, rows held for the period estimate or an open excursion.
    pub fn finish(&mut self, on_frame: &mut impl FnMut(Frame)) {
        let Self {
            decoder,
            stream,
            state,
        } = self;
        let mut on_fact = |fact| state.fact(fact, &mut *on_frame);
        decoder.finish(|item| stream.item(item, &mut on_fact));
        stream.finish(&mut on_fact);
        let LinkState { flagger, seq, .. } = state;
        flagger.flush(&mut |s| Out { seq, on_frame }.sample(s));
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
    /// One device fact: the frames it stands for go to `on_frame`.
    fn fact(&mut self, fact: CsvFact, on_frame: &mut impl FnMut(Frame)) {
        let LinkState { flagger, sent, seq } = self;
        let mut out = Out { seq, on_frame };
        match fact {
            CsvFact::Row(p) => flagger.push(to_sample(&p), &mut |s| out.sample(s)),
            CsvFact::NewBoot => flagger.restart(&mut |s| out.sample(s)),
            CsvFact::Hello(h) => out.frame(Message::Hello(h)),
            CsvFact::Event(e) => out.frame(Message::Event(e)),
            CsvFact::Ack(ack) => {
                if let Some(a) = to_ack(&ack, sent) {
                    out.frame(Message::Ack(a));
                }
            }
        }
    }
}

/// A placed CSV row as a SAMPLE (pulse flags are set later).
fn to_sample(p: &Placed<CsvRow>) -> Sample {
    let row = &p.value;
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
        // the wire's 32-bit counters: the low bits of the unwrapped ones
        sample_index: p.index as u32,
        t_us: p.t_us as u32,
        throttle,
        flags: SampleFlags(flags),
        thrust_n,
        torque_nm,
        rpm,
        voltage_v,
        current_a,
    }
}

/// The ACK a `#ACK` line stands for: that of the last command of its kind sent.
fn to_ack(ack: &CsvAck, sent: &[Option<(u16, u8)>; 6]) -> Option<Ack> {
    let wire_type = ack.command.msg_type()?;
    let (cmd_seq, cmd_type) = sent[ack.command as usize].unwrap_or((0, wire_type));
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

#[cfg(test)]
mod tests;
