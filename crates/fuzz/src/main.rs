//! propid's fuzz harness (issue 12 item 7), for the stable toolchain: no libFuzzer, a seeded
//! mutation loop in one process. Seed files (recordings, CSV logs) are sliced and mutated
//! ([`mutate`]) and every input goes through one target, each call under
//! `std::panic::catch_unwind`:
//!
//! - `tsp`: the TSP/1 `Decoder` (pushed in random chunks) — nearly every input;
//! - `csv`: the CSV dialect's `CsvDecoder` and the command / comment / ACK parsers on each line;
//! - `ingest`: the one loader, `propid_ingest::load::load_bytes` (format detection, TSP/1 and
//!   CSV-stream recordings through the wire crate's placement, exported CSV logs), with the
//!   default request and with `--input none` / `--fs`;
//! - `identify` and `diagnose`: the engines on what the loader read (the identification core's
//!   `identify_any_with`, as `propid identify` calls it; `propid_diagnose::diagnose_record`),
//!   every `--identify-every` / `--diagnose-every` inputs (they cost milliseconds to seconds
//!   each).
//!
//! A panic hook counts every panic, on any thread (the jackknife's helper thread too), and the
//! input is saved in `--out` (`panic-<target>-<n>.bin`, with the message in a `.txt`). The input
//! about to go into an expensive target is written to `--out/current.bin` first, so that a
//! hang or an abort (out of memory) leaves it behind. The same `--seed` gives the same inputs.
//!
//! Usage: `propid-fuzz --inputs N [--seed S] [--out DIR] SEED_PATH...` (`scripts/fuzz.sh`).

mod mutate;

use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use clap::Parser;
use propid_ingest::load::{load_bytes, Request, NO_INPUT};
use propid_numerics::identify::{identify_any_with, AnyInput};
use propid_numerics::okid::OkidOptions;
use propid_numerics::order::HankelSize;
use propid_numerics::stabilization::StabOptions;
use propid_numerics::workspace::IdentOptions;
use propid_wire::protocol::csv::{parse_ack, parse_comment, parse_csv_command};
use propid_wire::protocol::csv::{CsvDecoder, CsvOptions};
use propid_wire::protocol::Decoder;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// Panics seen by the hook, on every thread.
static PANICS: AtomicU64 = AtomicU64::new(0);
/// The last panic's message and place.
static LAST: Mutex<String> = Mutex::new(String::new());

#[derive(Debug, Parser)]
#[command(about = "Fuzz propid's decoder, CSV dialect, ingest, identify and diagnose")]
struct Args {
    /// Inputs to run.
    #[arg(long, default_value_t = 1_000_000)]
    inputs: u64,
    /// Seed of the mutation generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Directory for panicking inputs and `current.bin`.
    #[arg(long, default_value = "target/fuzz-out")]
    out: PathBuf,
    /// Every N-th input also goes through the identification core (0 = never).
    #[arg(long, default_value_t = 1000)]
    identify_every: u64,
    /// Every N-th input also goes through the diagnose engine (0 = never).
    #[arg(long, default_value_t = 20_000)]
    diagnose_every: u64,
    /// Seed files or directories (read recursively; files above 4 MiB are skipped).
    #[arg(required = true)]
    seeds: Vec<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Tsp,
    Csv,
    Ingest,
    Identify,
    Diagnose,
}

impl Target {
    const ALL: [Target; 5] = [
        Target::Tsp,
        Target::Csv,
        Target::Ingest,
        Target::Identify,
        Target::Diagnose,
    ];
    fn name(self) -> &'static str {
        match self {
            Target::Tsp => "tsp",
            Target::Csv => "csv",
            Target::Ingest => "ingest",
            Target::Identify => "identify",
            Target::Diagnose => "diagnose",
        }
    }
}

fn main() {
    let args = Args::parse();
    let seeds = read_seeds(&args.seeds);
    if seeds.is_empty() {
        eprintln!("propid-fuzz: no seed files");
        std::process::exit(2);
    }
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("propid-fuzz: {}: {e}", args.out.display());
        std::process::exit(7);
    }
    panic::set_hook(Box::new(|info| {
        PANICS.fetch_add(1, Ordering::SeqCst);
        if let Ok(mut l) = LAST.lock() {
            *l = info.to_string();
        }
    }));
    let mut rng = StdRng::seed_from_u64(args.seed);
    let mut runs = [0u64; 5];
    let mut found = [0u64; 5];
    let mut oks = [0u64; 5];
    let t0 = Instant::now();
    for i in 0..args.inputs {
        let s = rng.gen_range(0..seeds.len());
        let o = rng.gen_range(0..seeds.len());
        let expensive = (args.diagnose_every > 0 && i % args.diagnose_every == 0)
            .then_some(Target::Diagnose)
            .or((args.identify_every > 0 && i % args.identify_every == 0)
                .then_some(Target::Identify));
        let target = expensive.unwrap_or_else(|| match rng.gen_range(0..100) {
            0..=44 => Target::Tsp,
            45..=89 => Target::Csv,
            _ => Target::Ingest,
        });
        let max = match target {
            Target::Tsp | Target::Csv => 4096,
            Target::Ingest => 16_384,
            Target::Identify | Target::Diagnose => 65_536,
        };
        let mut input = mutate::slice(&mut rng, &seeds[s].1, max);
        mutate::mutate(&mut rng, &mut input, &seeds[o].1);
        let chunk = rng.gen_range(1..=512);
        if expensive.is_some() {
            let _ = std::fs::write(args.out.join("current.bin"), &input);
        }
        let before = PANICS.load(Ordering::SeqCst);
        let r = panic::catch_unwind(AssertUnwindSafe(|| run(target, &input, chunk)));
        let t = Target::ALL.iter().position(|&x| x == target).unwrap_or(0);
        runs[t] += 1;
        if r.as_ref().is_ok_and(|&ok| ok) {
            oks[t] += 1;
        }
        if r.is_err() || PANICS.load(Ordering::SeqCst) > before {
            found[t] += 1;
            save(&args.out, target, found[t], &input, &seeds[s].0);
        }
        if (i + 1) % 1_000_000 == 0 {
            report(i + 1, [&runs, &oks, &found], t0);
        }
    }
    report(args.inputs, [&runs, &oks, &found], t0);
    let _ = std::fs::remove_file(args.out.join("current.bin"));
    if found.iter().sum::<u64>() > 0 {
        std::process::exit(1);
    }
}

/// One input through one target.
fn run(target: Target, input: &[u8], chunk: usize) -> bool {
    match target {
        Target::Tsp => {
            let mut dec = Decoder::new();
            let mut n = 0usize;
            for c in input.chunks(chunk) {
                dec.push(c, |_| n += 1);
            }
            std::hint::black_box(dec.stats().dropped.total());
            n > 0
        }
        Target::Csv => {
            let mut dec = CsvDecoder::new(CsvOptions::default());
            let mut n = 0usize;
            for c in input.chunks(chunk) {
                dec.push(c, |_| n += 1);
            }
            dec.finish(|_| n += 1);
            for line in String::from_utf8_lossy(input).lines().take(64) {
                std::hint::black_box((
                    parse_csv_command(line).is_ok(),
                    parse_ack(line).is_some(),
                    parse_comment(line).is_some(),
                ));
            }
            n > 0
        }
        Target::Ingest => {
            let mut ok = false;
            for req in [
                Request::default(),
                Request {
                    input: Some(NO_INPUT),
                    fs_hz: Some(200.0),
                    ..Request::default()
                },
            ] {
                ok |= load_bytes("fuzz".into(), input, &req).is_ok();
            }
            ok
        }
        Target::Identify | Target::Diagnose => {
            let Ok(f) = load_bytes("fuzz".into(), input, &Request::default()) else {
                return false;
            };
            let rec = &f.record;
            let output = f.outputs.first().map_or("", String::as_str);
            if target == Target::Diagnose {
                let opts = propid_diagnose::Options::default();
                return propid_diagnose::diagnose_record(rec, output, &opts).is_ok();
            }
            let u = f.input.as_deref().map(|n| f.data(n)).unwrap_or_default();
            let y = f.data(output);
            let (u, y) = ([u.as_slice()], [y.as_slice()]);
            let starts: Vec<usize> = rec.impulse_starts().collect();
            let any = AnyInput {
                dt_s: rec.dt_s,
                u: &u,
                y: &y,
                missing: &rec.missing,
                pulse_starts: (!starts.is_empty()).then_some(&starts[..]),
            };
            let stab = StabOptions::default();
            identify_any_with(
                &any,
                &IdentOptions::default(),
                &OkidOptions::default(),
                HankelSize::Auto,
                Some(&stab),
            )
            .is_ok()
        }
    }
}

fn save(out: &Path, target: Target, n: u64, input: &[u8], seed: &Path) {
    let base = out.join(format!("panic-{}-{n}", target.name()));
    let msg = LAST.lock().map(|l| l.clone()).unwrap_or_default();
    eprintln!(
        "propid-fuzz: PANIC in {} (seed {}): {msg}",
        target.name(),
        seed.display()
    );
    let _ = std::fs::write(base.with_extension("bin"), input);
    let _ = std::fs::write(
        base.with_extension("txt"),
        format!("{msg}\nseed file: {}\n", seed.display()),
    );
}

/// One line: inputs per target, how many went through without an error (a frame or row
/// decoded, a file loaded, a model or a diagnosis), how many panicked.
fn report(done: u64, [runs, oks, found]: [&[u64; 5]; 3], t0: Instant) {
    let per: Vec<String> = (0..5)
        .map(|t| {
            format!(
                "{} {} ({} ok, {} panicking)",
                Target::ALL[t].name(),
                runs[t],
                oks[t],
                found[t]
            )
        })
        .collect();
    eprintln!(
        "propid-fuzz: {done} inputs in {:.0} s, panics {}: {}",
        t0.elapsed().as_secs_f64(),
        PANICS.load(Ordering::SeqCst),
        per.join(", ")
    );
}

/// Every file under `paths`, with its bytes (at most 4 MiB each).
fn read_seeds(paths: &[PathBuf]) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack: Vec<PathBuf> = paths.to_vec();
    while let Some(p) = stack.pop() {
        if p.is_dir() {
            if let Ok(rd) = std::fs::read_dir(&p) {
                let mut v: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
                v.sort();
                stack.extend(v);
            }
        } else if let Ok(b) = std::fs::read(&p) {
            if !b.is_empty() && b.len() <= 4 << 20 {
                out.push((p, b));
            }
        }
    }
    out.sort();
    out
}
