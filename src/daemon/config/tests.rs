//! The configuration's defaults, ranges and refusals.

use super::*;
use crate::daemon::DaemonError;

fn err(text: &str) -> String {
    Config::parse(text, "test").unwrap_err().to_string()
}

#[test]
fn empty_text_gives_defaults() {
    let c = Config::parse("", "test").unwrap();
    assert_eq!(c, Config::default());
    assert_eq!(c.identify.pulses_per_model, 4);
    assert_eq!(c.device.baud, 921_600);
    assert!(c.publish.stdout);
}

#[test]
fn shipped_config_file_is_valid() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/propid.toml");
    let c = Config::load(&path).unwrap();
    assert_eq!(c.identify.output, "thrust_N");
    // the [experiment] table is the plan's, and the plan accepts it
    assert_eq!(c.experiment["levels"].as_array().unwrap().len(), 3);
    crate::daemon::plan::from_config(&c).unwrap();
}

#[test]
fn unknown_key_is_named() {
    let e = err("[identify]\npulses_per_modle = 3\n");
    assert!(e.contains("pulses_per_modle"), "{e}");
    let e = err("[nonsense]\nx = 1\n");
    assert!(e.contains("nonsense"), "{e}");
}

#[test]
fn wrong_type_is_refused() {
    let e = err("[device]\nbaud = \"fast\"\n");
    assert!(e.contains("baud") || e.contains("fast"), "{e}");
}

#[test]
fn nan_and_out_of_range_name_key_and_value() {
    let e = err("[identify]\nlevel_tolerance = nan\n");
    assert!(
        e.contains("identify.level_tolerance") && e.contains("NaN"),
        "{e}"
    );
    let e = err("[identify]\npulses_per_model = 0\n");
    assert!(
        e.contains("identify.pulses_per_model") && e.contains("= 0"),
        "{e}"
    );
    let e = err("[device]\nread_timeout_ms = 500\n");
    assert!(
        e.contains("device.read_timeout_ms") && e.contains("500"),
        "{e}"
    );
    let e = err("[device]\nstall_timeout_ms = 10\n");
    assert!(
        e.contains("device.stall_timeout_ms") && e.contains("10"),
        "{e}"
    );
    let c = Config::parse("[device]\nstall_timeout_ms = 0\n", "test").unwrap();
    assert_eq!(c.device.stall_timeout, None);
    assert_eq!(
        Config::default().device.stall_timeout,
        Some(Duration::from_secs(1))
    );
    let e = err("[daemon]\nmax_run_s = inf\n");
    assert!(e.contains("daemon.max_run_s") && e.contains("inf"), "{e}");
    let e = err("[identify]\noutput = \"voltage\"\n");
    assert!(
        e.contains("identify.output") && e.contains("voltage"),
        "{e}"
    );
}

#[test]
fn bad_experiment_keys_are_refused_by_the_plan() {
    for text in [
        "[experiment]\nlevles = [0.3]\n",
        "[experiment]\nlevels = [1.5]\n",
        "[experiment]\npulse_spacing_ms = \"x\"\n",
    ] {
        let c = Config::parse(text, "t").unwrap();
        let e = crate::daemon::plan::from_config(&c)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("lev") || e.contains("pulse_spacing_ms"), "{e}");
    }
}

#[test]
fn reconnect_max_below_initial_is_refused() {
    let e = err("[device]\nprotocol = \"nmea\"\n");
    assert!(e.contains("device.protocol") && e.contains("nmea"), "{e}");
    let e = err("[device]\nreconnect_initial_ms = 500\nreconnect_max_ms = 100\n");
    assert!(e.contains("device.reconnect_max_ms"), "{e}");
}

#[test]
fn csv_keys_are_checked() {
    let c = Config::parse("[csv]\nesc_min_us = 1100\nmotor_poles = 14\n", "t").unwrap();
    assert_eq!(c.csv.esc_min_us, 1100.0);
    assert_eq!(c.csv.motor_poles, Some(14));
    assert_eq!(c.csv.max_pulse_samples, 64);
    let e = err("[csv]\nesc_min_us = 1500\nesc_max_us = 1200\n");
    assert!(e.contains("csv.esc_max_us") && e.contains("1200"), "{e}");
    let e = err("[csv]\nmotor_poles = 7\n");
    assert!(e.contains("csv.motor_poles") && e.contains('7'), "{e}");
    let e = err("[csv]\nmax_pulse_samples = 0\n");
    assert!(e.contains("csv.max_pulse_samples"), "{e}");
    let e = err("[csv]\nesc_min_us = nan\n");
    assert!(e.contains("csv.esc_min_us") && e.contains("NaN"), "{e}");
    let e = err("[csv]\nbaud = 3\n");
    assert!(e.contains("baud"), "{e}");
}

#[test]
fn empty_strings_mean_unset() {
    let c = Config::parse("[publish]\nfile = \"\"\nsocket = \"\"\n", "t").unwrap();
    assert_eq!(c.publish.file, None);
    assert_eq!(c.publish.socket, None);
}

/// `[publish] http`: off by default; a bare port or `:PORT` is the loopback; another interface
/// only when written out; anything else is refused with the key named.
#[test]
fn http_address_is_loopback_unless_written_out() {
    assert_eq!(Config::default().publish.http, None);
    let addr = |t: &str| {
        Config::parse(&format!("[publish]\nhttp = \"{t}\"\n"), "t")
            .unwrap()
            .publish
            .http
            .map(|a| a.to_string())
    };
    assert_eq!(addr("8080").as_deref(), Some("127.0.0.1:8080"));
    assert_eq!(addr(":0").as_deref(), Some("127.0.0.1:0"));
    assert_eq!(addr("localhost:81").as_deref(), Some("127.0.0.1:81"));
    assert_eq!(addr("0.0.0.0:8080").as_deref(), Some("0.0.0.0:8080"));
    assert_eq!(addr("[::1]:9").as_deref(), Some("[::1]:9"));
    assert_eq!(addr(""), None);
    let e = Config::parse("[publish]\nhttp = \"example.org:80\"\n", "t")
        .unwrap_err()
        .to_string();
    assert!(e.contains("publish.http"), "{e}");
}

#[test]
fn limits_are_read_refused_by_key_and_hold_the_plan() {
    let c = Config::parse("[limits]\nmax_current_a = 12.5\nmax_throttle = 0.8\n", "t").unwrap();
    assert_eq!(c.limits.max_current_a, Some(12.5));
    assert_eq!(c.limits.max_rpm, None);
    crate::daemon::plan::from_config(&c).unwrap();
    let e = err("[limits]\nmax_curent_a = 3\n");
    assert!(e.contains("max_curent_a"), "{e}");
    let e = err("[limits]\nmin_voltage_v = -3.0\n");
    assert!(e.contains("[limits]") && e.contains("min_voltage_v"), "{e}");
    // the default plan (levels up to 0.6, pulses of 0.1) leaves a max_throttle of 0.65
    let c = Config::parse("[limits]\nmax_throttle = 0.65\n", "t").unwrap();
    let e = crate::daemon::plan::from_config(&c).err().unwrap();
    let text = e.to_string();
    assert!(
        text.contains("levels[2] + pulse_amplitudes[1]") && text.contains("max_throttle"),
        "{text}"
    );
    assert!(matches!(
        e,
        DaemonError::Config(ConfigError::Limits(LimitsError::PlanExceeds { .. }))
    ));
}
