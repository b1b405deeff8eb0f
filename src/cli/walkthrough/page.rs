//! The walkthrough's files: the SVG plots and the Markdown page with the numbers.

use std::fmt::Write as _;
use std::path::Path;

use plotters::style::RGBColor;

use super::plot::{self, Series};
use super::WalkthroughError;
use crate::cli::CliError;
use propid_sim::walkthrough::{Derivation, Responses};

const TRUTH: RGBColor = RGBColor(0, 0, 0);
const MEASURED: RGBColor = RGBColor(150, 150, 150);
const MODEL: RGBColor = RGBColor(220, 40, 40);

/// Writes every plot into `out`; returns the file names in page order.
pub fn plots(d: &Derivation, out: &Path) -> Result<Vec<&'static str>, WalkthroughError> {
    let dt = d.setup.dt_s;
    let truth = &d.truth;
    let mut files = vec!["measurement.svg"];
    plot::lines(
        &out.join("measurement.svg"),
        "Measured impulse response (unit force for one sample) and the truth",
        "x (m)",
        dt,
        &[&truth.impulse],
        &[measured_series(d), truth_series(&truth.impulse)],
    )?;
    files.push("pareto.svg");
    plot::pareto(
        &out.join("pareto.svg"),
        "Singular values of H_1 (first 30) and their cumulative share",
        &d.singular_values,
        30,
    )?;
    for (stem, label, model) in [
        ("exact", "exact full-order model Â = H₂ H₁⁻¹", &d.exact),
        ("cleaned", "SVD-cleaned full-order model", &d.cleaned),
        ("reduced", "reduced 2nd-order model (ERA)", &d.reduced),
    ] {
        let (imp, step) = model_plots(stem);
        response_pair(out, d, label, model, imp, step)?;
        files.push(imp);
        files.push(step);
    }
    Ok(files)
}

fn model_plots(stem: &str) -> (&'static str, &'static str) {
    match stem {
        "exact" => ("exact_impulse.svg", "exact_step.svg"),
        "cleaned" => ("cleaned_impulse.svg", "cleaned_step.svg"),
        _ => ("reduced_impulse.svg", "reduced_step.svg"),
    }
}

fn response_pair(
    out: &Path,
    d: &Derivation,
    label: &str,
    model: &Responses,
    imp: &str,
    step: &str,
) -> Result<(), WalkthroughError> {
    let dt = d.setup.dt_s;
    plot::lines(
        &out.join(imp),
        &format!("Impulse response: {label}"),
        "x (m)",
        dt,
        &[&d.truth.impulse],
        &[
            measured_series(d),
            truth_series(&d.truth.impulse),
            model_series(label, &model.impulse),
        ],
    )?;
    plot::lines(
        &out.join(step),
        &format!("Step response: {label}"),
        "x (m)",
        dt,
        &[&d.truth.step],
        &[
            truth_series(&d.truth.step),
            model_series(label, &model.step),
        ],
    )
}

/// The measured impulse response, as grey dots.
fn measured_series(d: &Derivation) -> Series<'_> {
    Series {
        name: "measured",
        y: &d.measured,
        color: MEASURED,
        dots: true,
    }
}

/// A response of the true system, as a black line.
fn truth_series(y: &[f64]) -> Series<'_> {
    Series {
        name: "truth",
        y,
        color: TRUTH,
        dots: false,
    }
}

/// A model's response, as a red line named `label`.
fn model_series<'a>(label: &'a str, y: &'a [f64]) -> Series<'a> {
    Series {
        name: label,
        y,
        color: MODEL,
        dots: false,
    }
}

/// Root-mean-square difference of two responses over their common length.
fn rms_diff(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1);
    let s: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    (s / n as f64).sqrt()
}

/// Writes `walkthrough.md` and `walkthrough.json`.
pub fn write(d: &Derivation, out: &Path, files: &[&str]) -> Result<(), CliError> {
    let md = markdown(d, files);
    let path = out.join("walkthrough.md");
    std::fs::write(&path, md)
        .map_err(|e| CliError::io(format!("writing {}", path.display()), e))?;
    let s = &d.setup;
    let r = &d.report;
    let (fn_true, zeta_true) = d.true_fn_zeta;
    let json = serde_json::json!({
        "true": {"m": s.m, "d": s.d, "k": s.k, "fn_hz": fn_true, "zeta": zeta_true,
                 "dc_gain": 1.0 / s.k},
        "identified": {"m": r.mass_spring_damper.m, "d": r.mass_spring_damper.d,
                       "k": r.mass_spring_damper.k, "fn_hz": r.fn_hz, "zeta": r.zeta,
                       "dc_gain": r.dc_gain.get(0), "order": r.order},
        "setup": {"dt_s": s.dt_s, "hankel": s.hankel, "noise_std_m": s.noise, "seed": s.seed,
                  "samples": d.measured.len()},
        "exact_model_spectral_radius": d.exact_spectral_radius,
        "files": files,
    });
    let path = out.join("walkthrough.json");
    let text = serde_json::to_string_pretty(&json).map_err(CliError::Json)?;
    std::fs::write(&path, text).map_err(|e| CliError::io(format!("writing {}", path.display()), e))
}

fn markdown(d: &Derivation, _files: &[&str]) -> String {
    let s = &d.setup;
    let r = &d.report;
    let n = s.hankel;
    let (fn_true, zeta_true) = d.true_fn_zeta;
    let total: f64 = d.singular_values.iter().sum();
    let share2 = 100.0 * d.singular_values[..s.order].iter().sum::<f64>() / total;
    let horizon = 2 * n + 1;
    // Leading samples the exact model reproduces to 1 % of the noise level.
    let matched = d.exact.impulse[1..horizon]
        .iter()
        .zip(&d.measured[1..])
        .take_while(|(a, b)| (*a - *b).abs() <= 0.01 * s.noise.max(f64::MIN_POSITIVE))
        .count();
    let mut t = String::new();
    let _ = writeln!(t, "# ERA, step by step, on a noisy mass–spring–damper\n");
    let _ = writeln!(
        t,
        "Generated by `propid walkthrough`. It follows the derivation in *A deeper look into \
         the Eigensystem Realisation Algorithm* (after Juang & Pappa 1985, J. Guidance 8(5)).\n"
    );
    let _ = writeln!(t, "## 1. The plant and the measurement\n");
    let _ = writeln!(
        t,
        "`m ẍ + d ẋ + k x = F` with **m = {} kg, d = {} N·s/m, k = {} N/m** \
         (f_n = {:.4} Hz, ζ = {:.4}, DC gain 1/k = {} m/N), input the force F, output the \
         position x, discretised exactly (zero-order hold) at dt = {} s. The input is a unit \
         force held for one sample (the Kronecker delta), so the response is the sequence of \
         Markov parameters `y_k = C A^(k−1) B` (no 1/dt scaling). We measure {} samples with \
         white Gaussian noise of σ = {:e} m (seed {}).\n",
        s.m,
        s.d,
        s.k,
        fn_true,
        zeta_true,
        1.0 / s.k,
        s.dt_s,
        horizon,
        s.noise,
        s.seed
    );
    let _ = writeln!(t, "![measurement](measurement.svg)\n");
    let _ = writeln!(t, "## 2. The exact full-order model\n");
    let _ = writeln!(
        t,
        "With the {n} × {n} Hankel matrices `H_1 = [y_(i+j+1)]` and `H_2 = [y_(i+j+2)]`, \
         `H_2 = O A O⁻¹ H_1`, so `Â = H_2 H_1⁻¹`, `b̂ = H_1 e`, `ĉ = e` reproduces the \
         measurement, noise included: in exact arithmetic all of it; computed here, the first \
         {matched} samples to within 1 % of the noise level. Its order is {n} and its \
         spectral radius {:.4}: having fitted the noise it is {}, rounding errors grow by \
         that factor per step, and its step response is wrong (curves leaving the chart are \
         clipped at its frame).\n",
        d.exact_spectral_radius,
        if d.exact_spectral_radius > 1.0 {
            "unstable"
        } else {
            "stable"
        }
    );
    let _ = writeln!(
        t,
        "![exact impulse](exact_impulse.svg)\n\n![exact step](exact_step.svg)\n"
    );
    let _ = writeln!(t, "## 3. Singular values\n");
    let _ = writeln!(
        t,
        "`H_1 = P D Qᵀ`. The first {} singular values carry {share2:.1} % of the sum of all \
         {n}; the rest is noise spread thinly over many directions.\n",
        s.order
    );
    let _ = writeln!(
        t,
        "| i | σ_i | share (%) | cumulative (%) |\n|---|---|---|---|"
    );
    let mut acc = 0.0;
    for (i, sv) in d.singular_values.iter().take(8).enumerate() {
        acc += sv;
        let _ = writeln!(
            t,
            "| {} | {:.4e} | {:.2} | {:.2} |",
            i + 1,
            sv,
            100.0 * sv / total,
            100.0 * acc / total
        );
    }
    let _ = writeln!(t, "\n![pareto](pareto.svg)\n");
    let _ = writeln!(t, "## 4. The SVD-cleaned full-order model\n");
    let _ = writeln!(
        t,
        "Keeping the leading {} triplets, `H̃_1 = P̃ D̃ Q̃ᵀ` and its pseudo-inverse \
         `H̃_1* = Q̃ D̃⁻¹ P̃ᵀ` give `Ã = H_2 H̃_1*`, `b̃ = H̃_1 e`, `c̃ = e`: still of order {n}, \
         but the noise is gone (RMS error against the truth over the plot horizon: \
         {:.2e} m impulse, {:.2e} m step; the exact model: {:.2e} m and {:.2e} m).\n",
        s.order,
        rms_diff(&d.cleaned.impulse, &d.truth.impulse),
        rms_diff(&d.cleaned.step, &d.truth.step),
        rms_diff(&d.exact.impulse, &d.truth.impulse),
        rms_diff(&d.exact.step, &d.truth.step),
    );
    let _ = writeln!(
        t,
        "![cleaned impulse](cleaned_impulse.svg)\n\n![cleaned step](cleaned_step.svg)\n"
    );
    let _ = writeln!(t, "## 5. The reduced model (ERA)\n");
    let _ = writeln!(
        t,
        "Pushing `P̃ᵀ` and `D̃^(−½)` through the powers gives the order-{} realisation \
         `A = D̃^(−½) P̃ᵀ H_2 Q̃ D̃^(−½)`, `b = D̃^(½) Q̃ᵀ e`, `cᵀ = eᵀ P̃ D̃^(½)` — computed \
         here by propid's ERA (`core::era`) on the same Markov parameters and Hankel size. \
         Same responses as the cleaned model (RMS difference {:.2e} m), order {}.\n",
        r.order,
        rms_diff(&d.reduced.impulse, &d.cleaned.impulse),
        r.order
    );
    let _ = writeln!(
        t,
        "![reduced impulse](reduced_impulse.svg)\n\n![reduced step](reduced_step.svg)\n"
    );
    let _ = writeln!(t, "## 6. Identified against true\n");
    let _ = writeln!(
        t,
        "`k = 1 / DC gain`, `m = k / ω_n²`, `d = 2 ζ ω_n m` from the reduced model.\n"
    );
    let _ = writeln!(t, "| | true | identified | error (%) |\n|---|---|---|---|");
    let rows = [
        ("m (kg)", s.m, r.mass_spring_damper.m),
        ("d (N·s/m)", s.d, r.mass_spring_damper.d),
        ("k (N/m)", s.k, r.mass_spring_damper.k),
        ("f_n (Hz)", fn_true, r.fn_hz),
        ("ζ", zeta_true, r.zeta),
        ("DC gain (m/N)", 1.0 / s.k, r.dc_gain.get(0)),
    ];
    for (name, truth, got) in rows {
        let _ = writeln!(
            t,
            "| {name} | {truth:.6} | {got:.6} | {:+.2} |",
            100.0 * (got - truth) / truth
        );
    }
    t
}
