//! Safety limits (issue 32 item 2) through the real binary against the simulated stand on a pty:
//! a current limit below what the top level draws ends the run with `limit_tripped`, exit 8,
//! STOP last and the stand disarmed, every command within the plan and the limits; a plan above
//! `max_throttle` is refused before anything is sent.

use crate::daemon_proc::{daemon_config, kind, of_type, sim_stand, stats, Daemon};
use crate::lying_stand::{check_commands, plan};
use propid_wire::protocol::message::throttle_level;
use propid_wire::protocol::Message;

#[test]
fn a_current_limit_below_the_top_level_trips_stops_and_exits_8() {
    let dir = tempfile::tempdir().unwrap();
    // the simulated stand draws 0.4 + 8 (T/T_ref)^1.5 A: about 4 A at 0.3, 11 A at 0.6
    let limits = "[limits]\nmax_current_a = 8.0\nmax_throttle = 0.8\nmax_temperature_c = 80.0\n";
    let cfg = daemon_config(dir.path(), "[0.3, 0.6]", 8, 4, limits);
    let sim = sim_stand(1000, |_| {});
    let port = sim.path().display().to_string();
    let d = Daemon::run(&cfg, &port, None);
    let (status, lines, err) = d.finish(30.0);
    std::thread::sleep(std::time::Duration::from_millis(100));
    let cmds = sim.commands();
    drop(sim);
    assert_eq!(status.code(), Some(8), "{err} {lines:#?}");
    let trips = kind(&lines, "limit_tripped");
    assert_eq!(trips.len(), 1, "{lines:#?}");
    let t = trips[0];
    assert_eq!(
        (&t["type"], &t["which"]),
        (&"event".into(), &"max_current_a".into())
    );
    assert_eq!(t["limit"], 8.0);
    let value = t["value"].as_f64().unwrap();
    eprintln!("tripped: {t}");
    assert!(value > 8.0 && value < 12.0, "{t}");
    // the first level was done under the limit; the ramp to the second tripped it
    let pos = |k: &str| lines.iter().position(|l| l["kind"] == k);
    let done = pos("level_done").expect("the first level finished");
    let tripped = pos("limit_tripped").unwrap();
    assert!(done < tripped, "{lines:#?}");
    assert_eq!(kind(&lines, "level_done").len(), 1, "{lines:#?}");
    assert!(kind(&lines, "plan_finished").is_empty());
    // the stand says it disarmed, after the trip
    let disarmed = lines.iter().rposition(|l| l["kind"] == "disarmed");
    assert!(disarmed.is_some_and(|i| i > tripped), "{lines:#?}");
    // nothing reports a temperature: named once
    let unchecked = kind(&lines, "limit_unchecked");
    assert_eq!(unchecked.len(), 1, "{lines:#?}");
    assert_eq!(unchecked[0]["which"], "max_temperature_c");
    // every command within the plan and max_throttle, STOP last
    check_commands(&cmds, &plan(&[0.3, 0.6], 8), true);
    let top = throttle_level(0.8);
    for (seq, m) in &cmds {
        let level = match m {
            Message::SetThrottle(s) => s.level,
            Message::Impulse(i) => i.level,
            _ => 0,
        };
        assert!(level <= top, "command {seq} {m:?} above max_throttle");
    }
    stats(&lines);
}

#[test]
fn a_plan_above_max_throttle_is_refused_before_anything_is_sent() {
    let dir = tempfile::tempdir().unwrap();
    // 0.6 + 0.15 = 0.75 > 0.7
    let cfg = daemon_config(
        dir.path(),
        "[0.3, 0.6]",
        8,
        4,
        "[limits]\nmax_throttle = 0.7\n",
    );
    let sim = sim_stand(1000, |_| {});
    let port = sim.path().display().to_string();
    let d = Daemon::run(&cfg, &port, None);
    let (status, lines, err) = d.finish(10.0);
    std::thread::sleep(std::time::Duration::from_millis(100));
    let cmds = sim.commands();
    drop(sim);
    assert_eq!(status.code(), Some(5), "{err}");
    assert!(
        err.contains("levels[1] + pulse_amplitudes[1]") && err.contains("max_throttle"),
        "{err}"
    );
    assert!(cmds.is_empty(), "{cmds:?}");
    assert!(of_type(&lines, "model").is_empty());
}
