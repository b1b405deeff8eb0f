//! FILE → bytes → the one loader ([`propid_ingest::load`], re-exported here): the file read
//! within [`MAX_INPUT_BYTES`] (unreadable: exit 7, too large: exit 3), then its bytes loaded
//! as a [`Request`] asks.

use std::path::Path;

use super::CliError;
use crate::input::{read_bounded, ReadError, MAX_INPUT_BYTES};
pub use propid_ingest::load::*;

/// Reads all of `file` within [`MAX_INPUT_BYTES`]: unreadable is an I/O error (exit 7), too
/// large is bad input (exit 3).
pub fn read_input(file: &Path) -> Result<Vec<u8>, CliError> {
    let name = file.display().to_string();
    read_bounded(file, MAX_INPUT_BYTES).map_err(|e| match e {
        ReadError::Io(e) => CliError::io(format!("reading {name}"), e),
        ReadError::TooLarge { limit } => LoadError::TooLarge { file: name, limit }.into(),
    })
}

/// Reads `file` as `req` asks: TSP/1 binary recordings by channel name, everything else as CSV.
pub fn load(file: &Path, req: &Request) -> Result<LoadedFile, CliError> {
    let bytes = read_input(file)?;
    Ok(load_owned(file.display().to_string(), bytes, req)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn errors_keep_their_class() {
        let dir = tempfile::tempdir().unwrap();
        let e = load(&write(dir.path(), "e.csv", ""), &Request::default()).unwrap_err();
        assert!(matches!(&e, CliError::Load(LoadError::Empty { .. })), "{e}");
        assert_eq!(e.exit_code(), 3);
        let good = write(
            dir.path(),
            "g.csv",
            "t_s,throttle,thrust_N\n0,0.2,1\n0.01,0.2,1\n",
        );
        let bad_esc = [1000.0];
        let req = Request {
            esc_us: Some(&bad_esc),
            ..Request::default()
        };
        let e = load(&good, &req).unwrap_err();
        assert_eq!(e.to_string(), "--esc-us takes MIN,MAX");
        assert_eq!(e.exit_code(), 2);
        let e = load(&dir.path().join("absent.csv"), &Request::default()).unwrap_err();
        assert_eq!(e.exit_code(), 7, "{e}");
    }
}
