//! The simulated-stand table of `propid diagnose` (issue 29 items 4 and 6): every effect of the
//! catalogue hidden in `CASES` seeded stands (even cases underdamped, odd overdamped) under
//! each kind of record (pulses, steps, a staircase; `propid_sim::stand_cases`), how often it
//! is named, how often with its parameter within the tolerance of `docs/detection.md`, how
//! often another effect is named; and the false alarms on as many clean stands per kind.
//!
//! With `motor`, the motor stands of `propid_sim::stand_cases::stand_case` instead (rpm,
//! thrust, current and voltage, the stand baseline; every effect of the stand catalogue
//! hidden, its truths in `stand_truth`; even cases underdamped: a resonance of the stand that
//! is part of it and not counted as another effect).
//!
//! Run: `cargo run --release -p propid-diagnose --example stand_table [CASES] [THREADS] [GATE]
//! [clean|motor] [BUDGET_S]` (per effect and record kind; default 7, 21 cases per effect and 21 clean
//! stands in all; 2 threads; GATE `rising` (default) or `paired`, [`Gate`]; `clean`: the clean
//! stands only; BUDGET_S, motor only: no case starts after that many seconds). Prints Markdown;
//! `scripts/stand_table.sh` puts it into `docs/detection.md`.

use propid_diagnose::folds::Gate;
use propid_diagnose::{self as diagnose, Diagnosis};
use propid_numerics::EffectName;
use propid_sim::stand_cases::{case, truth, RecordKind};
use propid_sim::synth;

mod motor;

/// One case's outcome.
struct Outcome {
    named: bool,
    /// The main parameter's error when named (`None`: not named or no such parameter).
    error: Option<f64>,
    within: bool,
    others: Vec<EffectName>,
}

fn diagnose_case(
    kind: RecordKind,
    name: Option<EffectName>,
    i: u64,
    gate: Gate,
) -> Option<Outcome> {
    let (cfg, m) = case(kind, name, i).ok()?;
    let opts = diagnose::Options {
        gate,
        ..Default::default()
    };
    let d: Diagnosis =
        diagnose::diagnose(synth::DT_S, &m.u, &m.y, &[], Some(&m.voltage), &opts).ok()?;
    let others: Vec<EffectName> = d
        .findings
        .iter()
        .map(|f| f.effect)
        .filter(|&e| Some(e) != name)
        .collect();
    let Some(name) = name else {
        return Some(Outcome {
            named: false,
            error: None,
            within: false,
            others,
        });
    };
    let v_mean = m.voltage.iter().sum::<f64>() / m.voltage.len().max(1) as f64;
    let t = truth(name, &cfg, v_mean)?;
    let found = d.findings.iter().find(|f| f.effect == name);
    let est = found.and_then(|f| f.params.get(t.key)?.as_f64());
    if found.is_none() {
        let found: Vec<String> = d
            .findings
            .iter()
            .map(|f| format!("{} {:+.2} pp", f.effect, f.cv_gain_pp))
            .collect();
        eprintln!(
            "{} {name} #{i}: missed (fn {:.1} Hz, ζ {:.2}; named {found:?})",
            kind.as_str(),
            cfg.fn_hz,
            cfg.zeta
        );
    }
    Some(Outcome {
        named: found.is_some(),
        error: est.map(|e| t.error(e)),
        within: est.is_some_and(|e| t.holds(e)),
        others,
    })
}

/// `f` over `jobs` on `threads` threads, results in order.
pub(crate) fn on_threads<J: Sync, T: Send>(
    jobs: &[J],
    threads: usize,
    f: impl Fn(&J) -> T + Sync,
) -> Vec<T> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, T)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(j) = jobs.get(i) else {
                            return out;
                        };
                        out.push((i, f(j)));
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a worker"))
            .collect()
    });
    done.sort_by_key(|d| d.0);
    done.into_iter().map(|d| d.1).collect()
}

pub(crate) fn pct(k: usize, n: usize) -> String {
    format!("{k} ({:.0} %)", 100.0 * k as f64 / n.max(1) as f64)
}

fn main() {
    let cases: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(7);
    let gate = match std::env::args().nth(3).as_deref() {
        Some("paired") => Gate::Paired,
        _ => Gate::Rising,
    };
    let threads: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2);
    if std::env::args().nth(4).as_deref() == Some("motor") {
        // the fifth argument: no case starts after that many seconds
        let budget_s = std::env::args()
            .nth(5)
            .and_then(|a| a.parse().ok())
            .unwrap_or(f64::INFINITY);
        motor::table(cases, threads, gate, budget_s);
        return;
    }
    // `clean` as the fourth argument: the clean stands alone (the false-alarm rate).
    let clean_only = std::env::args().nth(4).as_deref() == Some("clean");
    let mut jobs: Vec<(RecordKind, Option<EffectName>, u64)> = Vec::new();
    // Case-major: a run cut short has every effect and kind in it.
    for i in 0..cases {
        for kind in RecordKind::ALL {
            let effects = diagnose::effects::names().filter(|_| !clean_only);
            for name in std::iter::once(None).chain(effects.map(Some)) {
                jobs.push((kind, name, i));
            }
        }
    }
    let outcomes = on_threads(&jobs, threads, |&(k, n, i)| {
        let o = diagnose_case(k, n, i, gate);
        let name = n.map_or("clean", EffectName::as_str);
        match &o {
            Some(o) => eprintln!(
                "case: {} {name} {i} named={} within={} others={}",
                k.as_str(),
                o.named,
                o.within,
                o.others.len()
            ),
            None => eprintln!("case: {} {name} {i} failed", k.as_str()),
        }
        o
    });
    let of = |kind: RecordKind, name: Option<EffectName>| -> Vec<&Outcome> {
        jobs.iter()
            .zip(&outcomes)
            .filter(|((k, n, _), _)| *k == kind && *n == name)
            .filter_map(|(_, o)| o.as_ref())
            .collect()
    };
    println!(
        "### Simulated stands ({cases} cases per effect and record kind, {} per effect, seeded; \
         acceptance test: {})\n",
        cases as usize * RecordKind::ALL.len(),
        match gate {
            Gate::Rising => "a rising held-out figure",
            Gate::Paired => "the paired test against the folds' scatter",
        }
    );
    println!("| record | effect | cases | named | named, parameter within tolerance | other effect named | parameter error, median (max) |");
    println!("|---|---|---|---|---|---|---|");
    let (mut all_n, mut all_within) = (0, 0);
    for kind in RecordKind::ALL {
        for name in diagnose::effects::names().filter(|_| !clean_only) {
            let o = of(kind, Some(name));
            let n = o.len();
            let named = o.iter().filter(|o| o.named).count();
            let within = o.iter().filter(|o| o.within).count();
            let other = o.iter().filter(|o| !o.others.is_empty()).count();
            let mut errs: Vec<f64> = o.iter().filter_map(|o| o.error).collect();
            errs.sort_by(f64::total_cmp);
            let err = errs.get(errs.len() / 2).map_or("–".to_string(), |m| {
                format!("{m:.3} ({:.3})", errs.last().copied().unwrap_or(*m))
            });
            all_n += n;
            all_within += within;
            println!(
                "| {} | `{name}` | {n} | {} | {} | {other} | {err} |",
                kind.as_str(),
                pct(named, n),
                pct(within, n)
            );
        }
    }
    println!(
        "\nAll effects and kinds: {} of {all_n} found with the parameter within tolerance.\n",
        pct(all_within, all_n)
    );
    println!("### Clean simulated stands\n");
    println!("| record | cases | false alarms | effects named |");
    println!("|---|---|---|---|");
    let (mut clean_n, mut clean_alarms) = (0, 0);
    for kind in RecordKind::ALL {
        let o = of(kind, None);
        let alarms: Vec<&&Outcome> = o.iter().filter(|o| !o.others.is_empty()).collect();
        let mut named: Vec<&str> = alarms
            .iter()
            .flat_map(|o| o.others.iter().map(|e| e.as_str()))
            .collect();
        named.sort_unstable();
        named.dedup();
        clean_n += o.len();
        clean_alarms += alarms.len();
        println!(
            "| {} | {} | {} | {} |",
            kind.as_str(),
            o.len(),
            pct(alarms.len(), o.len()),
            if named.is_empty() {
                "–".to_string()
            } else {
                named.join(", ")
            }
        );
    }
    println!(
        "\nClean stands in all: {clean_n}, false alarms {}.",
        pct(clean_alarms, clean_n)
    );
}
