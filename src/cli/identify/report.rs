//! `propid identify --report DIR`: the stabilization diagram (`stabilization.svg`) and a short
//! `identify.md` beside it.

use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::summary::Output;
use crate::plot::stabilization;

/// Writes `stabilization.svg` (when the diagram exists) and `identify.md` into `dir` (created
/// if needed).
pub fn write(dir: &Path, out: &Output<'_>) -> io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let (m, s) = (out.model, &out.source);
    let mut md = String::new();
    let _ = writeln!(md, "# propid identify: {}\n", s.file);
    let _ = writeln!(
        md,
        "Format {}, input {}, {} samples at {:.4} Hz, {} path. Model of order {}: \
         fn = {:.4} Hz, ζ = {:.4}.\n",
        s.format, s.input, s.samples, s.rate_hz, s.path, m.order, m.fn_hz, m.zeta
    );
    match out.stabilization {
        Some(st) => {
            let title = format!("stabilization diagram: {}", s.file);
            std::fs::write(
                dir.join("stabilization.svg"),
                stabilization::svg(&title, st)?,
            )?;
            md.push_str(&stabilization::markdown(
                st,
                m.fn_hz,
                m.zeta,
                "stabilization.svg",
            ));
        }
        None => md.push_str(
            "No stabilization diagram: the model's SVD could not be realised at other orders.\n",
        ),
    }
    std::fs::write(dir.join("identify.md"), md)
}
