//! `propid walkthrough --out DIR` writes the page, the plots and the identified m, d, k; the
//! identified values (ERA, order 2, seeded noise of 1 % of the response peak) are within 3 %
//! of the true ones (they come out within ~0.5 %).

use std::process::Command;

fn run(out: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["walkthrough", "--out"])
        .arg(out)
        .output()
        .expect("running propid")
}

#[test]
fn writes_page_plots_and_identifies_m_d_k() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("wt");
    let res = run(&out);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    let md = std::fs::read_to_string(out.join("walkthrough.md")).unwrap();
    for svg in [
        "measurement.svg",
        "pareto.svg",
        "exact_impulse.svg",
        "exact_step.svg",
        "cleaned_impulse.svg",
        "cleaned_step.svg",
        "reduced_impulse.svg",
        "reduced_step.svg",
    ] {
        let text = std::fs::read_to_string(out.join(svg)).unwrap();
        assert!(text.starts_with("<svg") && text.contains("</svg>"), "{svg}");
        assert!(
            md.contains(&format!("]({svg})")),
            "page does not show {svg}"
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("walkthrough.json")).unwrap())
            .unwrap();
    for key in ["m", "d", "k"] {
        let truth = json["true"][key].as_f64().unwrap();
        let got = json["identified"][key].as_f64().unwrap();
        assert!(
            ((got - truth) / truth).abs() < 0.03,
            "{key}: identified {got}, true {truth}"
        );
    }
    assert_eq!(json["identified"]["order"], 2);
    // The exact full-order model fitted the noise: unstable, as the page says.
    assert!(json["exact_model_spectral_radius"].as_f64().unwrap() > 1.0);
    assert!(md.contains("unstable"));
}

#[test]
fn unwritable_output_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    let res = run(&file.join("sub"));
    assert_eq!(
        res.status.code(),
        Some(7),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
}
