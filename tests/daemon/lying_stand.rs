//! A stand that lies (issue 27 items 3, 4, 6, 7, 8, 9), through the real binary against the
//! simulated stand with its misbehaviours switched on (`[faults]` of `propid_sim`): a runaway
//! throttle, BUSY to every pulse, commands acknowledged and never executed, a HELLO that lies
//! about the rate (65 535 Hz, or 0: a lie on TSP/1), clock jumps both ways, absurd finite values; and pulse levels outside 0..1
//! refused before anything is sent. Every run's commands, as the stand received them, are held
//! against the plan: nothing outside it, and STOP last when the plan ends on a fault.

use crate::daemon_proc;

use daemon_proc::{daemon_config, kind, of_type, sim_stand, stats, Daemon};
use propid_sim::SimConfig;
use propid_wire::experiment::ExperimentConfig;
use propid_wire::protocol::message::throttle_level;
use propid_wire::protocol::Message;
use serde_json::Value;
use std::path::Path;

/// The plan of [`daemon_config`] at `levels` (its keys as the test config writes them).
pub fn plan(levels: &[f64], pulses: u32) -> ExperimentConfig {
    ExperimentConfig {
        levels: levels.to_vec(),
        ramp_ms: 100,
        settle_ms: 300,
        pulse_amplitudes: vec![0.1, 0.15],
        pulse_spacing_ms: 150,
        pulses_per_level: pulses,
        ..ExperimentConfig::default()
    }
}

/// Every command the stand received is one the plan sends: the handshake, ARM, heartbeats,
/// SET_THROTTLE to one of its levels or 0, IMPULSE to one of its pulse levels, STOP, DISARM;
/// with `stop_last`, the last one is a STOP.
pub fn check_commands(cmds: &[(u16, Message)], plan: &ExperimentConfig, stop_last: bool) {
    assert!(!cmds.is_empty(), "no command reached the stand");
    let levels: Vec<u16> = plan.levels.iter().map(|&l| throttle_level(l)).collect();
    let pulse_levels: Vec<u16> = plan
        .levels
        .iter()
        .flat_map(|&l| (0..4).map(move |j| (l, j)))
        .map(|(l, j)| throttle_level(l + plan.pulse_delta(j)))
        .collect();
    for (seq, m) in cmds {
        let ok = match m {
            Message::HelloReq | Message::Arm(_) | Message::Heartbeat => true,
            Message::Stop | Message::Disarm => true,
            Message::SetThrottle(s) => s.level == 0 || levels.contains(&s.level),
            Message::Impulse(i) => pulse_levels.contains(&i.level),
            _ => false,
        };
        assert!(ok, "command {seq} {m:?} is outside the plan: {cmds:?}");
    }
    if stop_last {
        let last = cmds.last().map(|c| c.1);
        assert!(
            matches!(last, Some(Message::Stop)),
            "last {last:?}: {cmds:?}"
        );
    }
}

/// What a run gives: the exit code, the lines, stderr, the commands the stand received.
type Run = (Option<i32>, Vec<Value>, String, Vec<(u16, Message)>);

/// `propid run` against the simulated stand (1 kHz, the 2nd-order plant) lying as `lie` says;
/// returns the exit code, the lines, stderr and the commands the stand received.
fn run_against(levels: &[f64], pulses: u32, lie: impl FnOnce(&mut SimConfig)) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let list = format!("{levels:?}");
    let cfg = daemon_config(dir.path(), &list, pulses, 4, "");
    // the 2nd-order plant: fn 12 Hz, ζ 0.7
    let sim = sim_stand(1000, lie);
    let port = sim.path().display().to_string();
    let d = Daemon::run(&cfg, &port, None);
    let (status, lines, err) = d.finish(30.0);
    // the stand keeps what the daemon wrote until its last byte
    std::thread::sleep(std::time::Duration::from_millis(100));
    let cmds = sim.commands();
    drop(sim);
    (status.code(), lines, err, cmds)
}

/// The warning of kind `k`: exactly one.
fn one<'a>(lines: &'a [Value], k: &str) -> &'a Value {
    let w = kind(lines, k);
    assert_eq!(w.len(), 1, "{k}: {lines:#?}");
    assert_eq!(w[0]["type"], "warning");
    w[0]
}

#[test]
fn a_runaway_throttle_is_stopped_with_a_throttle_mismatch_and_exit_8() {
    let (code, lines, err, cmds) = run_against(&[0.3, 0.6], 8, |c| {
        c.faults.runaway_throttle = true;
    });
    assert_eq!(code, Some(8), "{err} {lines:#?}");
    let w = one(&lines, "throttle_mismatch");
    assert_eq!(w["applied"], 1.0, "{w}");
    assert!(w["commanded_max"].as_f64().unwrap() <= 0.3 + 1e-9, "{w}");
    assert!(w["for_ms"].as_u64().unwrap() >= 200, "{w}");
    assert!(of_type(&lines, "model").is_empty());
    check_commands(&cmds, &plan(&[0.3, 0.6], 8), true);
    // stopped during the ramp to the first level: no pulse was ever sent
    assert!(!cmds.iter().any(|c| matches!(c.1, Message::Impulse(_))));
    stats(&lines);
}

#[test]
fn a_stand_busy_to_every_pulse_is_a_refusal_after_max_retries() {
    let (code, lines, err, cmds) = run_against(&[0.4], 8, |c| {
        c.faults.busy_impulses = true;
    });
    assert_eq!(code, Some(8), "{err} {lines:#?}");
    let w = one(&lines, "command_refused");
    assert_eq!(w["command"], "IMPULSE");
    let impulses = cmds
        .iter()
        .filter(|c| matches!(c.1, Message::Impulse(_)))
        .count() as u32;
    // the first try and `max_retries` (3) more, not 1 092
    assert_eq!(
        impulses,
        ExperimentConfig::default().max_retries + 1,
        "{cmds:?}"
    );
    check_commands(&cmds, &plan(&[0.4], 8), true);
}

#[test]
fn commands_acknowledged_and_never_executed_are_said_and_exit_8() {
    let (code, lines, err, cmds) = run_against(&[0.4], 8, |c| {
        c.faults.ignore_commands = true;
    });
    assert_eq!(code, Some(8), "{err} {lines:#?}");
    let w = one(&lines, "commands_not_executed");
    assert_eq!(w["command"], "SET_THROTTLE", "{w}");
    assert_eq!(w["level"], 0.4, "{w}");
    assert!(kind(&lines, "plan_finished").is_empty());
    check_commands(&cmds, &plan(&[0.4], 8), true);
}

#[test]
fn a_hello_that_lies_about_the_rate_stops_the_plan() {
    let (code, lines, err, cmds) = run_against(&[0.4], 8, |c| {
        c.faults.hello_rate_hz = Some(65_535);
    });
    assert_eq!(code, Some(8), "{err} {lines:#?}");
    let w = one(&lines, "hello_rate_mismatch");
    assert_eq!(w["hello_hz"], 65_535);
    let measured = w["measured_hz"].as_f64().unwrap();
    assert!((measured - 1000.0).abs() < 5.0, "{w}");
    // stopped before the first pulse (sized from the HELLO's rate) could go out
    assert!(!cmds.iter().any(|c| matches!(c.1, Message::Impulse(_))));
    check_commands(&cmds, &plan(&[0.4], 8), true);
}

#[test]
fn a_hello_claiming_0_hz_is_a_lie_that_stops_the_plan() {
    let (code, lines, err, cmds) = run_against(&[0.4], 8, |c| {
        c.faults.hello_rate_hz = Some(0);
    });
    assert_eq!(code, Some(8), "{err} {lines:#?}");
    let w = one(&lines, "hello_rate_mismatch");
    assert_eq!(w["hello_hz"], 0);
    let measured = w["measured_hz"].as_f64().unwrap();
    assert!((measured - 1000.0).abs() < 5.0, "{w}");
    assert!(kind(&lines, "plan_finished").is_empty());
    check_commands(&cmds, &plan(&[0.4], 8), true);
}

/// The models of a run: each one's sample period is the stand's (1 ms), none spans a jump.
fn models_at_1_khz(lines: &[Value]) -> usize {
    let models = of_type(lines, "model");
    for m in &models {
        let dt = m["dt_s"].as_f64().unwrap();
        assert!((dt - 1e-3).abs() < 1e-6, "dt {dt}: {m}");
        let f = m["fn_hz"].as_f64().unwrap_or(f64::NAN);
        assert!(f > 8.0 && f < 16.0, "fn {f} for 12 Hz: {m}");
    }
    models.len()
}

#[test]
fn clock_jumps_both_ways_are_warned_and_no_model_spans_one() {
    for jump in [25_000i64, -40_000] {
        let (code, lines, err, cmds) = run_against(&[0.4], 16, |c| {
            c.faults.clock_jump_every_samples = 1500;
            c.faults.clock_jump_us = jump;
        });
        assert_eq!(code, Some(0), "{jump}: {err} {lines:#?}");
        let jumps = kind(&lines, "clock_jump");
        assert!(jumps.len() >= 2, "{jump}: {lines:#?}");
        for j in &jumps {
            assert_eq!(j["step_us"].as_i64().unwrap(), jump + 1000, "{j}");
            assert_eq!(j["sample_index"].as_u64().unwrap() % 1500, 0, "{j}");
        }
        assert!(models_at_1_khz(&lines) >= 1, "{jump}: {lines:#?}");
        assert_eq!(stats(&lines)["clock_jumps"], jumps.len() as u64);
        check_commands(&cmds, &plan(&[0.4], 16), false);
    }
}

#[test]
fn absurd_finite_values_never_reach_a_published_model_or_the_schedule() {
    let (code, lines, err, cmds) = run_against(&[0.4], 16, |c| {
        c.faults.absurd_thrust_every_samples = 97;
        // four in a row: not isolated outliers
    });
    assert_eq!(code, Some(0), "{err} {lines:#?}");
    let bound = propid_numerics::quality::MAX_ABS_DC_GAIN;
    // the stand's absurd values reach the windows' fits: refused by the bound, named
    let refused = kind(&lines, "model_unreliable");
    assert!(
        refused.iter().any(|w| w["reasons"]
            .as_array()
            .unwrap()
            .contains(&"implausible_dc_gain".into())),
        "{lines:#?}"
    );
    for m in of_type(&lines, "model") {
        let g = m["dc_gain"].as_f64().unwrap();
        assert!(g.abs() < bound, "{m}");
    }
    let schedule = of_type(&lines, "schedule");
    for row in schedule[0]["models"].as_array().unwrap() {
        let g = row["dc_gain"].as_f64().unwrap();
        assert!(g.abs() < bound, "{row}");
    }
    check_commands(&cmds, &plan(&[0.4], 16), false);
}

#[test]
fn pulse_levels_outside_0_to_1_are_refused_before_anything_is_sent() {
    for (levels, amps, key) in [
        ("[0.95]", "[0.1, 0.5]", "levels[0] + pulse_amplitudes[0]"),
        (
            "[0.3, 0.02]",
            "[0.05, 0.1]",
            "levels[1] - pulse_amplitudes[0]",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("propid.toml");
        std::fs::write(
            &p,
            format!("[experiment]\nlevels = {levels}\npulse_amplitudes = {amps}\n"),
        )
        .unwrap();
        let sim = sim_stand(1000, |_| {});
        let port = sim.path().display().to_string();
        let d = Daemon::run(&p, &port, None);
        let (status, lines, err) = d.finish(10.0);
        std::thread::sleep(std::time::Duration::from_millis(100));
        let cmds = sim.commands();
        drop(sim);
        assert_eq!(status.code(), Some(5), "{err}");
        assert!(err.contains(key), "{key}: {err}");
        assert!(cmds.is_empty(), "{cmds:?}");
        assert!(lines.is_empty() || of_type(&lines, "model").is_empty());
        let _ = Path::new(&port);
    }
}
