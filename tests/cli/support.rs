//! What the subcommand tests share: running the real binary.

use std::process::Command;

/// Runs `propid ARGS`: exit code (-1 when killed by a signal), stdout, stderr.
pub fn propid(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(args)
        .output()
        .expect("run propid");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A simulator configuration in `dir` that names the 2nd-order plant (`config/sim.toml`, read by
/// `propid sim` without `--config`, is the motor): its path, for `propid sim --config`.
pub fn second_order_sim(dir: &std::path::Path) -> String {
    let path = dir.join("sim-second-order.toml");
    std::fs::write(&path, "[plant]\nkind = \"second_order\"\n").expect("write sim config");
    path.to_str().expect("utf-8 path").to_owned()
}

/// The `median` rows of `identify`'s summary (under its step table, up first).
pub fn median_rows(human: &str) -> Vec<&str> {
    human
        .lines()
        .filter(|l| l.trim_start().starts_with("median"))
        .collect()
}
