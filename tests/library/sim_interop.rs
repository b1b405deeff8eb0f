//! The simulated stand's output read by the project's own ingest (binary and CSV dialect).

use propid_ingest::tsp::read_record;
use propid_sim::config::{FaultConfig, SimConfig, StandConfig, WireProtocol};
use propid_sim::dynamics::EchoStand;
use propid_sim::faults::FaultInjector;
use propid_sim::firmware::Firmware;
use propid_sim::record::record;
use propid_wire::record::names;

#[test]
fn recording_ingests_into_a_record_with_every_pulse_at_its_sample() {
    let cfg = SimConfig::default();
    let mut rec = Vec::new();
    let sum = record(&cfg, 60.0, &mut rec).unwrap();
    let (r, stats) = read_record(&rec).unwrap();
    assert!((r.dt_s - 1e-3).abs() < 1e-12, "{}", r.dt_s);
    assert_eq!(r.missing_count(), 0);
    assert_eq!(r.len() as u64, sum.firmware.samples);
    assert_eq!(r.impulse_starts().count(), sum.pulses as usize);
    let thr = &r.channel(names::THROTTLE).unwrap().data;
    for k in r.impulse_starts() {
        assert!((thr[k] - thr[k - 1]).abs() > 0.04, "pulse edge at {k}");
    }
    assert!(stats.frames.unwrap().dropped.total() == 0);
}

#[test]
fn csv_dialect_ingests_with_the_same_throttle_and_thrust() {
    let cfg = StandConfig {
        protocol: WireProtocol::Csv,
        ..StandConfig::default()
    };
    let faults = FaultInjector::new(&FaultConfig::default(), 1);
    let mut fw = Firmware::new(&cfg, EchoStand::new(10.0), 7, faults);
    fw.feed(100, b"ARM 500\nTHR 3000\n");
    fw.advance(200_000);
    fw.feed(200_100, b"IMP 4000 1000\n");
    fw.advance(400_000);
    let mut out = Vec::new();
    fw.drain_output(u64::MAX, &mut out);
    let (r, _) = read_record(&out).unwrap();
    assert_eq!(r.len() as u64, fw.stats().samples);
    let thr = &r.channel(names::THROTTLE).unwrap().data;
    let thrust = &r.channel(names::THRUST).unwrap().data;
    assert!(
        thr.iter().any(|&u| (u - 0.4).abs() < 1e-9),
        "the pulse is in the data"
    );
    for (u, y) in thr.iter().zip(thrust) {
        assert!((10.0 * u - y).abs() < 1e-3, "{u} {y}");
    }
}
