//! A load cell's lag hidden in a measured stand log (issue 29 item 6): the log is read as
//! `propid diagnose` reads it (every stand channel), its thrust column alone is delayed and
//! filtered ([`lag_column`], drawn from a seed by [`Injection::draw`]), and the diagnosis must
//! name `sensor_lag` on the thrust with the injected delay (within a row) and τ (within 25 %),
//! on top of the thrust's own lag in the clean log. Prints a Markdown table;
//! `scripts/stand_lag_table.sh` puts it into `docs/injection.md`.
//!
//! Run: `cargo run --release -p propid-diagnose --example stand_lag_table -- FILE [DRAWS]`
//! (default 10 draws, seeds 1000.. as the injection table's).

use propid_diagnose::file::{signals, DEFAULT_OUTPUT, OPTIONAL};
use propid_diagnose::{Diagnosis, Options};
use propid_ingest::load::{load_bytes, Request};
use propid_numerics::EffectName;
use propid_testkit::inject::{lag_column, tolerance, Injection, Samples};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// The thrust's sensor lag a diagnosis names: (delay, τ), s.
fn thrust_lag(d: &Diagnosis) -> Option<(f64, f64)> {
    let f = d
        .findings
        .iter()
        .find(|f| f.effect == EffectName::SensorLag && f.params["channel"] == "thrust")?;
    Some((f.params["delay_s"].as_f64()?, f.params["tau_s"].as_f64()?))
}

/// The thrust's lag of the final stand model, named or not: (delay, τ), s.
fn model_lag(d: &Diagnosis) -> (f64, f64) {
    d.stand
        .as_ref()
        .and_then(|s| s.model.sensors.get("thrust"))
        .map_or((0.0, 0.0), |s| {
            (s.delay_s.value.unwrap_or(0.0), s.tau_s.value.unwrap_or(0.0))
        })
}

fn names(d: &Diagnosis) -> String {
    d.findings
        .iter()
        .map(|f| f.effect.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: stand_lag_table FILE [DRAWS]");
        std::process::exit(2);
    };
    let draws: u64 = args.get(1).and_then(|d| d.parse().ok()).unwrap_or(10);
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let outputs = [DEFAULT_OUTPUT.to_string()];
    let req = Request {
        outputs: &outputs,
        optional: &OPTIONAL,
        ..Request::default()
    };
    let file = load_bytes(path.into(), &bytes, &req).unwrap_or_else(|e| panic!("{e}"));
    let s = signals(&file, None).unwrap_or_else(|e| panic!("{e}"));
    let opts = Options::default();
    let clean = s.diagnose(&opts).unwrap_or_else(|e| panic!("{e}"));
    // The clean log's own thrust lag: the stand model's, also where the data chose the
    // generic baseline.
    let own = s
        .diagnose(&Options {
            prefer_stand: true,
            ..opts
        })
        .unwrap_or_else(|e| panic!("{e}"));
    let (d0, t0) = model_lag(&own);
    let params: Vec<String> = own
        .findings
        .iter()
        .map(|f| {
            format!(
                "{} {}",
                f.effect,
                serde_json::Value::Object(f.params.clone())
            )
        })
        .collect();
    eprintln!(
        "the stand model on the clean log (held out on thrust {:.2} %): {}",
        own.validation.mean_fit_percent,
        params.join("; ")
    );
    eprintln!(
        "clean: {:?} {} | {} | thrust lag {d0:.4} s, τ {t0:.4} s",
        clean.baseline.choice.kind,
        clean.baseline.choice.why,
        names(&clean)
    );
    let name = std::path::Path::new(path)
        .file_name()
        .map_or(path.clone(), |n| n.to_string_lossy().into_owned());
    println!(
        "{draws} seeded draws (seeds 1000..) of a load cell's lag hidden in the thrust of \
         `{name}` ({} rows at {:.4} s; every other channel kept): a first-order lag τ of 2–8 \
         rows, then a delay of 1–4 rows. Found = `sensor_lag` named on the thrust; the found \
         figures are less the clean log's own thrust lag ({d0:.3} s, τ {t0:.3} s; a delay \
         adds, lags in series add their time constants); within = delay within one row and τ \
         within 25 %.\n",
        s.u.len(),
        s.dt_s
    );
    println!(
        "| seed | injected delay, τ (s) | found delay, τ less the clean log's (s) | delay error \
         (rows) | τ error | baseline | named |"
    );
    println!("|---|---|---|---|---|---|---|");
    let samples = Samples {
        dt_s: s.dt_s,
        t0_s: 0.0,
        u: s.u.clone(),
        y: s.y.clone(),
        voltage: None,
    };
    let (mut found, mut within) = (0, 0);
    for k in 0..draws {
        let seed = 1000 + k;
        let inj = Injection::draw(
            EffectName::SensorLag,
            &samples,
            &mut StdRng::seed_from_u64(seed),
        )
        .expect("a sensor lag");
        let Injection::SensorLag { delay_s, tau_s, .. } = inj else {
            unreachable!()
        };
        let lagged = s.map_channel("thrust", |y| lag_column(y, s.dt_s, delay_s, tau_s));
        let d = lagged.diagnose(&opts).unwrap_or_else(|e| panic!("{e}"));
        let kind = format!("{:?}", d.baseline.choice.kind).to_lowercase();
        let (got, e_d, e_t, ok) = match thrust_lag(&d) {
            Some((gd, gt)) => {
                found += 1;
                let (fd, ft) = (gd - d0, gt - t0);
                let (ed, et) = ((fd - delay_s) / s.dt_s, ft / tau_s - 1.0);
                let ok = ed.abs() <= 1.0 && et.abs() <= tolerance(&inj);
                within += usize::from(ok);
                (
                    format!("{fd:.3}, {ft:.3}"),
                    format!("{ed:+.2}"),
                    format!("{:+.0} %", 100.0 * et),
                    ok,
                )
            }
            None => ("not named".into(), "–".into(), "–".into(), false),
        };
        if !ok {
            eprintln!("seed {seed}: {inj:?} → {}", d.baseline.choice.why);
        }
        println!(
            "| {seed} | {delay_s:.3}, {tau_s:.3} | {got} | {e_d} | {e_t} | {kind} | {} |",
            names(&d)
        );
    }
    println!("\nFound {found} of {draws}; within both tolerances {within} of {draws}.");
}
