//! The motor-stand section of the table: every effect of the stand catalogue hidden in seeded
//! motor stands (`propid_sim::stand_cases::stand_case`: rpm, thrust, current and voltage),
//! diagnosed on the thrust with the stand channels passed as `propid diagnose` passes a log's
//! (`crate::file`); named, within every truth's tolerance, other effects named, the baseline
//! chosen; and the false alarms on clean stands.

use std::time::Instant;

use propid_diagnose::folds::Gate;
use propid_diagnose::stand::{BaselineKind, StandInput};
use propid_diagnose::{self as diagnose, Diagnosis};
use propid_numerics::stand_model::fit::Channel;
use propid_numerics::stand_model::Quantity;
use propid_numerics::EffectName;
use propid_sim::stand_cases::{
    stand_background, stand_case, stand_truth, RecordKind, StandRecord, STAND_DT_S,
};

use crate::{on_threads, pct};

/// The effects of the stand catalogue, in table order.
pub fn effects() -> impl Iterator<Item = EffectName> {
    EffectName::ALL
        .into_iter()
        .filter(|&e| e != EffectName::StiffnessNonlinearity)
}

/// One case's outcome.
pub struct Outcome {
    pub named: bool,
    /// The first truth's error when named (`None`: not named or no such parameter).
    pub error: Option<f64>,
    /// Named with every truth within its tolerance.
    pub within: bool,
    /// Effects named that are neither hidden nor part of the stand.
    pub others: Vec<EffectName>,
    /// The stand baseline was chosen.
    pub on_stand: bool,
    pub seconds: f64,
}

/// `diagnose` on a stand record's thrust, its rpm and current beside it (as the CLI passes
/// a log's stand channels).
pub fn diagnose_record(r: &StandRecord, gate: Gate) -> Option<Diagnosis> {
    let ch = |key, quantity, y| Channel {
        key,
        quantity,
        y,
        interpolated: &[],
    };
    let stand = StandInput {
        channels: vec![
            ch("rpm", Quantity::Speed, &r.rpm),
            ch("thrust", Quantity::Thrust, &r.thrust),
            ch("current", Quantity::Current, &r.current),
        ],
        output: Some("thrust"),
    };
    let opts = diagnose::Options {
        gate,
        ..Default::default()
    };
    diagnose::diagnose_with(
        STAND_DT_S,
        &r.u,
        &r.thrust,
        &[],
        Some(&r.voltage),
        Some(&stand),
        &opts,
    )
    .ok()
}

fn diagnose_case(
    kind: RecordKind,
    name: Option<EffectName>,
    i: u64,
    gate: Gate,
) -> Option<Outcome> {
    let t0 = Instant::now();
    let (cfg, r) = stand_case(kind, name, i).ok()?;
    let d = diagnose_record(&r, gate)?;
    let background = stand_background(&cfg);
    let others: Vec<EffectName> = d
        .findings
        .iter()
        .map(|f| f.effect)
        .filter(|&e| Some(e) != name && !background.contains(&e))
        .collect();
    let on_stand = d.baseline.choice.kind == BaselineKind::Stand;
    let seconds = t0.elapsed().as_secs_f64();
    let named_all: Vec<String> = d
        .findings
        .iter()
        .map(|f| format!("{} {:+.2} pp {:?}", f.effect, f.cv_gain_pp, f.params))
        .collect();
    let Some(name) = name else {
        if !others.is_empty() {
            eprintln!(
                "{} clean #{i}: false alarm (stand baseline {on_stand}; named {named_all:?})",
                kind.as_str()
            );
        }
        return Some(Outcome {
            named: false,
            error: None,
            within: false,
            others,
            on_stand,
            seconds,
        });
    };
    let v_mean = r.voltage.iter().sum::<f64>() / r.voltage.len().max(1) as f64;
    let truths = stand_truth(name, &cfg, v_mean);
    let found = d.findings.iter().find(|f| f.effect == name);
    let est = |key: &str| found.and_then(|f| f.params.get(key)?.as_f64());
    let error = truths.first().and_then(|t| est(t.key).map(|e| t.error(e)));
    let within = found.is_some()
        && !truths.is_empty()
        && truths
            .iter()
            .all(|t| est(t.key).is_some_and(|e| t.holds(e)));
    if !within || !others.is_empty() {
        let want: Vec<String> = truths
            .iter()
            .map(|t| format!("{} {:.4}", t.key, t.value))
            .collect();
        eprintln!(
            "{} {name} #{i}: named={} within={within} (truth {want:?}; stand baseline \
             {on_stand}; named {named_all:?}; why {})",
            kind.as_str(),
            found.is_some(),
            d.baseline.choice.why
        );
    }
    Some(Outcome {
        named: found.is_some(),
        error,
        within,
        others,
        on_stand,
        seconds,
    })
}

/// Runs `cases` per effect and record kind on `threads` threads and prints the Markdown; no
/// case starts after `budget_s` seconds (the counts say how many ran).
pub fn table(cases: u64, threads: usize, gate: Gate, budget_s: f64) {
    let start = Instant::now();
    let mut jobs: Vec<(RecordKind, Option<EffectName>, u64)> = Vec::new();
    // Case-major: a run cut short has every effect and kind in it.
    for i in 0..cases {
        for kind in RecordKind::ALL {
            for name in std::iter::once(None).chain(effects().map(Some)) {
                jobs.push((kind, name, i));
            }
        }
    }
    // `STAND_TABLE_ONLY="step static_nonlinearity 0,staircase clean 1"`: those cases alone
    if let Ok(only) = std::env::var("STAND_TABLE_ONLY") {
        let keep: Vec<&str> = only.split(',').map(str::trim).collect();
        jobs.retain(|(k, n, i)| {
            let name = n.map_or("clean", EffectName::as_str);
            keep.contains(&format!("{} {name} {i}", k.as_str()).as_str())
        });
    }
    let outcomes = on_threads(&jobs, threads, |&(k, n, i)| {
        if start.elapsed().as_secs_f64() > budget_s {
            return None;
        }
        let o = diagnose_case(k, n, i, gate);
        let name = n.map_or("clean", EffectName::as_str);
        match &o {
            Some(o) => eprintln!(
                "case: {} {name} {i} named={} within={} others={} stand={} {:.1} s",
                k.as_str(),
                o.named,
                o.within,
                o.others.len(),
                o.on_stand,
                o.seconds
            ),
            None => eprintln!("case: {} {name} {i} failed", k.as_str()),
        }
        o
    });
    let of = |kind: Option<RecordKind>, name: Option<EffectName>| -> Vec<&Outcome> {
        jobs.iter()
            .zip(&outcomes)
            .filter(|((k, n, _), _)| kind.map_or(true, |kind| *k == kind) && *n == name)
            .filter_map(|(_, o)| o.as_ref())
            .collect()
    };
    let secs: Vec<f64> = outcomes.iter().flatten().map(|o| o.seconds).collect();
    let per_effect: Vec<usize> = effects().map(|e| of(None, Some(e)).len()).collect();
    let (lo, hi) = (
        per_effect.iter().min().copied().unwrap_or(0),
        per_effect.iter().max().copied().unwrap_or(0),
    );
    let ran = if lo == hi {
        format!("{lo}")
    } else {
        format!("{lo}–{hi}")
    };
    let planned = cases as usize * RecordKind::ALL.len();
    let cut = if hi < planned {
        format!(" of {planned} planned: the run was cut at its time budget")
    } else {
        String::new()
    };
    println!(
        "### Motor stands ({ran} cases per effect{cut}, seeded, rows of {} ms; acceptance \
         test: {}; {:.0} s per case on average, one thread each)\n",
        STAND_DT_S * 1e3,
        match gate {
            Gate::Rising => "a rising held-out figure",
            Gate::Paired => "the paired test against the folds' scatter",
        },
        secs.iter().sum::<f64>() / secs.len().max(1) as f64
    );
    println!(
        "| record | effect | cases | stand baseline | named | named, parameters within \
         tolerance | other effect named | first parameter's error, median (max) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let row = |label: &str, name: EffectName, o: &[&Outcome]| {
        let n = o.len();
        let named = o.iter().filter(|o| o.named).count();
        let within = o.iter().filter(|o| o.within).count();
        let other = o.iter().filter(|o| !o.others.is_empty()).count();
        let stand = o.iter().filter(|o| o.on_stand).count();
        let mut errs: Vec<f64> = o.iter().filter_map(|o| o.error).collect();
        errs.sort_by(f64::total_cmp);
        let err = errs.get(errs.len() / 2).map_or("–".to_string(), |m| {
            format!("{m:.3} ({:.3})", errs.last().copied().unwrap_or(*m))
        });
        println!(
            "| {label} | `{name}` | {n} | {stand} | {} | {} | {other} | {err} |",
            pct(named, n),
            pct(within, n)
        );
        (n, within)
    };
    for kind in RecordKind::ALL {
        for name in effects() {
            row(kind.as_str(), name, &of(Some(kind), Some(name)));
        }
    }
    println!("\nPer effect over the three kinds:\n");
    println!(
        "| record | effect | cases | stand baseline | named | named, parameters within \
         tolerance | other effect named | first parameter's error, median (max) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let (mut all_n, mut all_within) = (0, 0);
    for name in effects() {
        let (n, w) = row("all", name, &of(None, Some(name)));
        all_n += n;
        all_within += w;
    }
    println!(
        "\nAll effects and kinds: {} of {all_n} found with the parameters within tolerance.\n",
        pct(all_within, all_n)
    );
    println!("### Clean motor stands\n");
    println!("| record | cases | stand baseline | false alarms | effects named |");
    println!("|---|---|---|---|---|");
    let (mut clean_n, mut clean_alarms) = (0, 0);
    for kind in RecordKind::ALL {
        let o = of(Some(kind), None);
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
            "| {} | {} | {} | {} | {} |",
            kind.as_str(),
            o.len(),
            o.iter().filter(|o| o.on_stand).count(),
            pct(alarms.len(), o.len()),
            if named.is_empty() {
                "–".to_string()
            } else {
                named.join(", ")
            }
        );
    }
    println!(
        "\nClean motor stands in all: {clean_n}, false alarms {}.",
        pct(clean_alarms, clean_n)
    );
}
