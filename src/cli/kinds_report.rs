//! `--report DIR` of `propid run` and `propid replay`: the files `propid_report::kinds`
//! renders, written into DIR.

use std::path::Path;

use propid_kinds::Material;

/// Writes the report of a run (its `material`) into `dir` (created when missing), as the
/// command's error.
pub fn write_for(dir: &Path, material: &Material) -> Result<(), super::CliError> {
    propid_report::kinds::render(material)
        .and_then(|files| {
            std::fs::create_dir_all(dir)?;
            files
                .iter()
                .try_for_each(|(name, text)| std::fs::write(dir.join(name), text))
        })
        .map_err(|e| super::CliError::io(format!("writing the report into {}", dir.display()), e))
}
