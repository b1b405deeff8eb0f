//! `--report DIR` of `propid run` and `propid replay` for an experiment kind other than
//! pulses: the files `propid_report::kinds` renders, written into DIR.

use std::path::Path;

use propid_kinds::Published;

/// Writes the report of a run with `cfg` that published `published` into `dir` (created when
/// missing), as the command's error.
pub fn write_for(
    dir: &Path,
    cfg: &crate::daemon::Config,
    published: &[Published],
) -> Result<(), super::CliError> {
    let kind = cfg
        .experiment
        .get("kind")
        .and_then(|k| k.as_str())
        .unwrap_or("pulses");
    propid_report::kinds::render(kind, published)
        .and_then(|files| {
            std::fs::create_dir_all(dir)?;
            files
                .iter()
                .try_for_each(|(name, text)| std::fs::write(dir.join(name), text))
        })
        .map_err(|e| super::CliError::io(format!("writing the report into {}", dir.display()), e))
}
