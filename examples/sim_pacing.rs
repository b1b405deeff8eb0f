//! Measures how well the simulated stand keeps its sample rate over a real pty, read through
//! `serialport` as the daemon does: `cargo run --release --example sim_pacing -- [RATE_HZ] [SECONDS]`.
//! Prints samples received per wall-clock second, sample-index gaps, decoder drops and the
//! largest delay between consecutive reads that delivered samples.

use std::io::Read;
use std::time::{Duration, Instant};

use propid_sim::config::SimConfig;
use propid_sim::pty::{RunOptions, SimHandle};
use propid_wire::protocol::{Decoder, Message};

fn main() {
    let mut args = std::env::args().skip(1);
    let rate: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let seconds: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(3.0);
    let mut cfg = SimConfig::default();
    cfg.stand.sample_rate_hz = rate;
    if let Err(e) = cfg.validate() {
        eprintln!("sim_pacing: {e}");
        std::process::exit(2);
    }
    let sim = match SimHandle::spawn(cfg, RunOptions::default()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("sim_pacing: {e}");
            std::process::exit(6);
        }
    };
    let mut port = match serialport::new(sim.path().to_string_lossy(), 921_600)
        .timeout(Duration::from_millis(20))
        .open()
    {
        Ok(p) => p,
        Err(e) => {
            eprintln!("sim_pacing: {e}");
            std::process::exit(6);
        }
    };
    let mut dec = Decoder::new();
    let mut buf = vec![0u8; 1 << 16];
    let (mut first, mut last, mut count, mut gaps) = (None::<u32>, 0u32, 0u64, 0u64);
    let mut worst_gap = Duration::ZERO;
    let mut last_read = Instant::now();
    let start = Instant::now();
    while start.elapsed().as_secs_f64() < seconds {
        let Ok(n) = port.read(&mut buf) else { continue };
        let mut got = 0;
        dec.push(&buf[..n], |f| {
            if let Message::Sample(s) = f.msg {
                if first.is_some() && s.sample_index != last.wrapping_add(1) {
                    gaps += s.sample_index.wrapping_sub(last).wrapping_sub(1) as u64;
                }
                first.get_or_insert(s.sample_index);
                last = s.sample_index;
                count += 1;
                got += 1;
            }
        });
        if got > 0 {
            worst_gap = worst_gap.max(last_read.elapsed());
            last_read = Instant::now();
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let report = sim.stop().map(|r| r.firmware.samples).unwrap_or(0);
    println!(
        "rate {rate} Hz: {count} samples in {wall:.3} s = {:.0} /s ({:.2} % of nominal), \
         index gaps {gaps}, decoder drops {}, longest wait between reads with samples {:.2} ms, \
         stand took {report}",
        count as f64 / wall,
        100.0 * count as f64 / wall / rate as f64,
        dec.stats().dropped.total(),
        worst_gap.as_secs_f64() * 1e3
    );
}
