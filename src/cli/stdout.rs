//! Stdout as coreutils write it: every subcommand prints through [`write`] / [`line`], never
//! `println!` (which panics on a write error).
//!
//! - A closed pipe (`propid identify --json f | head -c 10`: EPIPE) is not a failure: the
//!   reader has what it wanted. [`CliError::Stdout`] with [`is_closed_pipe`] makes `main` end
//!   quietly with exit 0 (no message).
//! - Any other write error (`> /dev/full`: ENOSPC, EIO) is a failure: `main` prints
//!   `propid: write error: <cause>` and exits 7 (README), never 0 with the output lost.
//!
//! Rust ignores SIGPIPE, so a closed pipe arrives here as the error `BrokenPipe`. The daemon's
//! stdout sink ([`crate::daemon::publish`]) follows the same rule.

use std::io::{self, Write};

use super::CliError;

/// Writes `text` as it is to stdout and flushes it.
pub fn write(text: &str) -> Result<(), CliError> {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .map_err(CliError::Stdout)
}

/// Writes `text` and a newline to stdout and flushes it.
pub fn line(text: &str) -> Result<(), CliError> {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.write_all(b"\n"))
        .and_then(|_| out.flush())
        .map_err(CliError::Stdout)
}

/// Whether a write error means the reader went away (EPIPE): the quiet end, exit 0.
pub fn is_closed_pipe(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::BrokenPipe
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_pipe_is_quiet_and_a_full_disk_is_exit_7() {
        let pipe = CliError::Stdout(io::Error::from(io::ErrorKind::BrokenPipe));
        assert!(pipe.is_closed_pipe());
        let full = CliError::Stdout(io::Error::from_raw_os_error(28));
        assert!(!full.is_closed_pipe());
        assert_eq!(full.exit_code(), 7);
        assert!(full.to_string().starts_with("write error: "), "{full}");
    }
}
