//! Effects hidden in real logs (issue 11, item 6), many draws: for every log of
//! [`REPO_LOGS`] (and of [`SHARED_LOGS`] when the shared data folder is given and present),
//! every effect of [`EFFECTS`] and `DRAWS` seeded random parameter draws
//! ([`Injection::draw`]), the injected log is written as a CSV file and run through
//! `propid diagnose --json`; the effect must be named with its parameter within
//! [`tolerance`] of the injected value (plus what the clean log already had). Prints a Markdown
//! table (found rate, within-tolerance rate, median parameter error) that
//! `scripts/injection_table.sh` writes to `docs/injection.md` for README.
//!
//! Usage: `cargo run --release --example injection_table -- BIN DRAWS [SHARED_DIR [EFFECT]]`
//! (every miss is told on stderr with its draw and the findings; `EFFECT` runs that effect's
//! rows only; with `PROPID_INJECTION_KEEP=DIR` every injected file is kept there; with
//! `PROPID_INJECTION_LOGS=NAME,...` only the logs whose names contain one of them).

use std::path::{Path, PathBuf};
use std::process::Command;

use propid::cli::load::{load, Request};
use propid_testkit::inject::{
    inject, judge, Injection, Log, Samples, EFFECTS, REPO_LOGS, SHARED_LOGS,
};
use propid_wire::record::names;
use rand::rngs::StdRng;
use rand::SeedableRng;
use serde_json::Value;

/// The log's samples as the app's loader reads them (`None`, with a message, when it cannot).
fn samples(path: &Path, log: &Log) -> Option<Samples> {
    let outputs: Vec<String> = log.output.iter().map(|s| s.to_string()).collect();
    let req = Request {
        input: log.input,
        outputs: &outputs,
        optional: &[names::VOLTAGE],
        fs_hz: log.fs_hz,
        ..Request::default()
    };
    let file = load(path, &req)
        .map_err(|e| eprintln!("injection_table: {}: {e}", path.display()))
        .ok()?;
    Samples::from_record(
        &file.record,
        file.input.as_deref()?,
        file.outputs.first()?,
        file.optional.first().map(String::as_str),
    )
}

/// `diagnose --json` findings of `s` written to `file`, and the kinds of its warnings; `None`
/// when diagnose fails.
fn findings(bin: &Path, file: &Path, s: &Samples) -> Option<(Vec<Value>, Vec<String>)> {
    std::fs::write(file, s.to_csv()).ok()?;
    let out = Command::new(bin)
        .args(["diagnose", "--json", "--input", "u", "--output", "y"])
        .arg(file)
        .output()
        .ok()?;
    let v: Value = serde_json::from_slice(&out.stdout).ok()?;
    let kinds = v["warnings"].as_array().map_or(Vec::new(), |w| {
        w.iter()
            .filter_map(|w| w["kind"].as_str().map(String::from))
            .collect()
    });
    Some((v["findings"].as_array().cloned()?, kinds))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(bin), Some(Ok(draws))) = (args.first(), args.get(1).map(|d| d.parse::<u64>())) else {
        eprintln!("usage: injection_table BIN DRAWS [SHARED_DIR [EFFECT]]");
        std::process::exit(2);
    };
    let bin = PathBuf::from(bin);
    let mut logs: Vec<(PathBuf, Log)> = REPO_LOGS
        .iter()
        .map(|l| (PathBuf::from(l.path), *l))
        .collect();
    match args.get(2).map(PathBuf::from) {
        Some(dir) if dir.is_dir() => {
            logs.extend(SHARED_LOGS.iter().map(|l| (dir.join(l.path), *l)))
        }
        Some(dir) => eprintln!(
            "injection_table: {} is absent: shared logs skipped",
            dir.display()
        ),
        None => {}
    }
    if let Ok(names) = std::env::var("PROPID_INJECTION_LOGS") {
        logs.retain(|(_, l)| names.split(',').any(|n| l.name.contains(n)));
    }
    let dir = tempfile::tempdir().expect("a temporary folder");
    println!(
        "{draws} seeded draws per effect and log; \"within\" = named with its parameter within \
         the tolerance (dead time ±1 sample, sinusoid 1 % on the frequency and 25 % on the \
         amplitude, drift 25 %, supply sag 30 %); error = median |parameter error| of the found \
         draws (samples for the dead time, relative otherwise); also = other effects named in \
         the injected log but not in the clean one (count over the draws); unidentifiable = \
         draws where diagnose warns that the effect cannot be identified in this log (the \
         `EFFECT_unidentifiable` warning). The supply sag scales the output, so it is injected \
         only where the output is zero at rest (not the tanks' water level).\n"
    );
    println!("| effect | log | found | within | median error | unidentifiable | also named |");
    println!("|---|---|---|---|---|---|---|");
    let only = args.get(3);
    let keep = std::env::var_os("PROPID_INJECTION_KEEP").map(PathBuf::from);
    for effect in EFFECTS
        .into_iter()
        .filter(|e| only.map_or(true, |o| o == e.as_str()))
    {
        for (path, log) in logs.iter().filter(|(_, l)| l.takes(effect)) {
            let Some(s) = samples(path, log) else {
                continue;
            };
            let file = dir.path().join("injected.csv");
            let Some((clean, _)) = findings(&bin, &file, &s) else {
                eprintln!(
                    "injection_table: {}: diagnose failed on the clean log",
                    log.name
                );
                continue;
            };
            let named = |fs: &[Value]| -> Vec<String> {
                fs.iter()
                    .filter_map(|f| f["effect"].as_str().map(String::from))
                    .collect()
            };
            let clean_names = named(&clean);
            let (mut found, mut within, mut errors, mut unident) = (0, 0, Vec::new(), 0);
            let unidentifiable = format!("{effect}_unidentifiable");
            let mut also: std::collections::BTreeMap<String, usize> = Default::default();
            for k in 0..draws {
                let mut rng = StdRng::seed_from_u64(1000 + k);
                let Some(inj) = Injection::draw(effect, &s, &mut rng) else {
                    continue;
                };
                let injected = inject(&s, &inj);
                if let Some(keep) = &keep {
                    let name = format!("{}-{effect}-{k}.csv", log.name.replace(' ', "_"));
                    let _ = std::fs::write(keep.join(name), injected.to_csv());
                }
                let (got, kinds) = findings(&bin, &file, &injected).unwrap_or_default();
                unident += usize::from(kinds.contains(&unidentifiable));
                let o = judge(&inj, &clean, &got);
                if !o.within(&inj) {
                    eprintln!(
                        "miss: {}: {inj:?} → {o:?}; findings {}",
                        log.name,
                        named(&got).join(", ")
                    );
                }
                found += usize::from(o.found);
                within += usize::from(o.within(&inj));
                errors.extend(o.error.filter(|e| e.is_finite()).map(f64::abs));
                for n in named(&got) {
                    if n != effect.as_str() && !clean_names.contains(&n) {
                        *also.entry(n).or_default() += 1;
                    }
                }
            }
            errors.sort_by(f64::total_cmp);
            let median = errors
                .get(errors.len() / 2)
                .map_or("—".to_string(), |e| format!("{e:.3}"));
            let also = also
                .iter()
                .map(|(n, c)| format!("{n} ×{c}"))
                .collect::<Vec<_>>()
                .join(", ");
            println!(
                "| {effect} | {} | {found}/{draws} | {within}/{draws} | {median} | {unident}/{draws} | {} |",
                log.name,
                if also.is_empty() { "—" } else { &also }
            );
        }
    }
}
