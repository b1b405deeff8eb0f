//! Files as they come (issue 27): a classic Mac text (lines ended by CR alone, Excel for Mac's
//! "CSV (Macintosh)") reads as its LF original; two columns of one name are refused naming
//! `--columns`; `--order 0` is automatic, as `order = 0` in the config.

use propid_testkit::dialects::dialects;
use serde_json::Value;

use crate::support::propid;

/// The Tyto 1585 dialect's export (UTF-8, LF line ends).
fn export() -> String {
    dialects()
        .into_iter()
        .find(|d| d.name == "tyto_1585_kgf")
        .expect("the Tyto 1585 dialect")
        .text
}

fn identify(path: &std::path::Path, extra: &[&str]) -> Value {
    let mut args = vec!["identify", path.to_str().unwrap(), "--json"];
    args.extend(extra);
    let (code, out, err) = propid(&args);
    assert_eq!(code, 0, "{}: {err}", path.display());
    let mut v: Value = serde_json::from_str(&out).unwrap();
    // the file's own name is the one difference allowed
    v["source"]["file"] = Value::Null;
    v
}

#[test]
fn cr_only_and_crlf_line_ends_read_as_lf() {
    let text = export();
    assert!(text.contains('\n') && !text.contains('\r'));
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, text: String| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let lf = identify(&file("lf.csv", text.clone()), &[]);
    assert!(lf["model"].is_object(), "{lf}");
    let cr = identify(&file("cr.csv", text.replace('\n', "\r")), &[]);
    assert_eq!(cr, lf);
    let crlf = identify(&file("crlf.csv", text.replace('\n', "\r\n")), &[]);
    assert_eq!(crlf, lf);
}

#[test]
fn order_0_is_automatic() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("export.csv");
    std::fs::write(&p, export()).unwrap();
    let auto = identify(&p, &[]);
    assert_eq!(identify(&p, &["--order", "0"]), auto);
}

#[test]
fn two_columns_of_one_name_are_refused_naming_columns() {
    let mut text = String::from("Time (s),ESC signal (µs),Thrust (N),Thrust (N)\n");
    for k in 0..400 {
        let u = if (k / 100) % 2 == 0 { 1300 } else { 1500 };
        let y = if u == 1300 { 1.0 } else { 3.0 };
        text += &format!("{:.3},{u},{y},{}\n", k as f64 * 0.01, y * 2.0);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("twice.csv");
    std::fs::write(&p, &text).unwrap();
    let (code, _, err) = propid(&["identify", p.to_str().unwrap(), "--json"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("\"Thrust (N)\"") && err.contains("columns 3, 4") && err.contains("--columns"),
        "{err}"
    );
    // Named apart, the file reads (the model's verdict on these made-up steps aside).
    let (code, out, err) = propid(&[
        "identify",
        p.to_str().unwrap(),
        "--json",
        "--columns",
        "t_s,throttle_us,thrust_N,extra",
    ]);
    assert!(code == 0 || code == 4, "{code}: {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["source"]["outputs"][0], "thrust_N", "{v}");
}
