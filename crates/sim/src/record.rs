//! `propid sim --record`: the firmware and the host's experiment plan in one loop on a simulated
//! clock, no pty and no waiting, so that a recording of a whole experiment (pulses at every
//! operating point) exists without hardware and in a fraction of real time.
//!
//! The recording is the raw byte stream the device sent (faults included, as a host would have
//! received it), exactly what `cat /dev/ttyACM0 > run.tsp` would give. The host side decodes those
//! same bytes with the protocol [`Decoder`] and answers instantly (zero link latency).

use std::io::Write;

use super::config::{SimConfig, WireProtocol};
use super::dynamics::{Dynamics, PlantDynamics};
use super::faults::{FaultInjector, FaultStats};
use super::firmware::{Firmware, FirmwareStats};
use super::SimError;
use propid_wire::experiment::{Experiment, ExperimentConfigError, Notice, Output};
use propid_wire::protocol::{encode_frame, DecodeStats, Decoder, MAX_FRAME_LEN};

/// Why the host-side experiment of a recording cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExperimentError {
    /// Record mode runs the TSP/1 plan; the stand speaks another protocol.
    #[error("record mode runs the TSP/1 experiment plan: set stand.protocol = \"tsp\"")]
    NotTsp,
    /// The recording's length is not in (0, 86400] seconds.
    #[error("--seconds {0}: must be in (0, 86400]")]
    Seconds(f64),
    /// The plan refused its configuration.
    #[error(transparent)]
    Plan(#[from] ExperimentConfigError),
}

/// What a recording run did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RecordSummary {
    /// Simulated time covered, s.
    pub seconds: f64,
    /// Bytes written.
    pub bytes: u64,
    /// The firmware's counters.
    pub firmware: FirmwareStats,
    /// Injected faults.
    pub faults: FaultStats,
    /// The host decoder's counters over the recording.
    pub decode: DecodeStats,
    /// Pulses acknowledged to the plan.
    pub pulses: u32,
    /// Operating points completed.
    pub levels_done: usize,
    /// True when the plan finished (ramped down and disarmed).
    pub finished: bool,
    /// Every notice of the plan, in order (as text).
    pub notices: Vec<String>,
}

/// Simulated-clock step of the loop, µs: one sample period, at most 1 ms (the plan's timers
/// are in milliseconds).
fn step_us(rate_hz: u32) -> u64 {
    (1_000_000 / rate_hz.max(1) as u64).clamp(1, 1000)
}

/// Records `seconds` of the configured stand running the configured experiment into `sink`,
/// stopping early 0.5 s after the plan is over.
pub fn record(
    cfg: &SimConfig,
    seconds: f64,
    sink: &mut dyn Write,
) -> Result<RecordSummary, SimError> {
    if cfg.stand.protocol != WireProtocol::Tsp {
        return Err(ExperimentError::NotTsp.into());
    }
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 86_400.0) {
        return Err(ExperimentError::Seconds(seconds).into());
    }
    let dt_s = 1.0 / cfg.stand.sample_rate_hz as f64;
    let plant = PlantDynamics::new(&cfg.plant, dt_s, cfg.stand.seed)?;
    let faults = FaultInjector::new(&cfg.faults, cfg.stand.seed);
    let boot_id = super::boot_id(cfg.stand.seed, 0);
    let mut fw = Firmware::new(&cfg.stand, plant, boot_id, faults);
    let mut plan = Experiment::new(cfg.experiment.clone(), 0).map_err(ExperimentError::from)?;
    run_loop(&mut fw, &mut plan, seconds, sink)
}

/// The loop itself, for any stand (tests use exact stand-ins).
pub fn run_loop<D: Dynamics>(
    fw: &mut Firmware<D>,
    plan: &mut Experiment,
    seconds: f64,
    sink: &mut dyn Write,
) -> Result<RecordSummary, SimError> {
    let end_us = (seconds * 1e6) as u64;
    let step = step_us(fw.sample_rate_hz());
    let mut dec = Decoder::new();
    let mut wire = Vec::new();
    let mut frames = Vec::new();
    let mut sum = RecordSummary {
        seconds: 0.0,
        bytes: 0,
        firmware: FirmwareStats::default(),
        faults: FaultStats::default(),
        decode: DecodeStats::default(),
        pulses: 0,
        levels_done: 0,
        finished: false,
        notices: Vec::new(),
    };
    let mut over_at: Option<u64> = None;
    let mut t = 0;
    plan.start(t);
    loop {
        let mut cmd_bytes = Vec::new();
        while let Some(out) = plan.next_output() {
            match out {
                Output::Send { seq, msg } => {
                    let mut buf = [0u8; MAX_FRAME_LEN];
                    let n = encode_frame(seq, &msg, &mut buf);
                    cmd_bytes.extend_from_slice(&buf[..n]);
                }
                Output::Notice(n) => note(&mut sum, n),
            }
        }
        if !cmd_bytes.is_empty() {
            fw.feed(t, &cmd_bytes);
        }
        fw.advance(t);
        wire.clear();
        fw.drain_output(t, &mut wire);
        if !wire.is_empty() {
            sink.write_all(&wire)
                .map_err(|e| SimError::io("writing the recording", e))?;
            sum.bytes += wire.len() as u64;
            frames.clear();
            dec.push(&wire, |f| frames.push(f));
            for f in &frames {
                plan.on_frame(f, t);
            }
        }
        plan.poll(t);
        if plan.is_over() && over_at.is_none() {
            over_at = Some(t);
        }
        let stop_early = over_at.is_some_and(|o| t >= o + 500_000);
        if t >= end_us || stop_early {
            break;
        }
        t = (t + step).min(end_us);
    }
    while let Some(out) = plan.next_output() {
        if let Output::Notice(n) = out {
            note(&mut sum, n);
        }
    }
    sink.flush()
        .map_err(|e| SimError::io("writing the recording", e))?;
    sum.seconds = t as f64 / 1e6;
    sum.firmware = fw.stats();
    sum.faults = fw.fault_stats();
    sum.decode = *dec.stats();
    Ok(sum)
}

fn note(sum: &mut RecordSummary, n: Notice) {
    match n {
        Notice::PulseFired { .. } => sum.pulses += 1,
        Notice::LevelDone { .. } => sum.levels_done += 1,
        Notice::Finished => sum.finished = true,
        _ => {}
    }
    if !matches!(n, Notice::PulseFired { .. }) {
        sum.notices.push(format!("{n:?}"));
    }
}
