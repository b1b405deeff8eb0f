//! Reading an input file (`identify`, `diagnose`, `replay`) within a bound, so that
//! `propid identify /dev/zero` ends with a clear error instead of reading until memory runs out.
//!
//! Every input is read through [`read_bounded`]: at most [`MAX_INPUT_BYTES`] (1 GiB, README),
//! regular files checked by their size first (nothing is read), anything else (a device, a
//! FIFO, a pipe) read through the same bound and refused one byte past it.

use std::io::{self, Read};
use std::path::Path;

/// The largest input read, bytes (1 GiB: a TSP/1 recording of ~3 h at 1 kHz, a CSV of ~30 M
/// rows). A CSV file's loading holds about 32 bytes a row per column read (the file's text is
/// dropped once its columns are parsed; docs/identify.md, "Memory"): 1 GiB of a three-column
/// log of 20-byte rows (54 M rows) takes about 5 GB, and identify's own buffers come on top.
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Why an input could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read (missing, unreadable): exit 7.
    #[error(transparent)]
    Io(#[from] io::Error),
    /// The input is larger than the bound: exit 3.
    #[error(
        "larger than {limit} bytes (1 GiB), the most propid reads of one input (a CSV file \
         takes about 32 bytes of memory a row per column read, and identify its own buffers \
         besides: docs/identify.md, Memory)"
    )]
    TooLarge {
        /// The bound, bytes.
        limit: u64,
    },
}

/// Reads all of `path`, at most `limit` bytes.
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_file() && meta.len() > limit {
        return Err(ReadError::TooLarge { limit });
    }
    let mut bytes = Vec::with_capacity(if meta.is_file() {
        meta.len() as usize
    } else {
        0
    });
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge { limit });
    }
    Ok(bytes)
}

/// Bytes read at a time by [`read_chunks`], and the most it gives its `take` for a decision.
pub const CHUNK_BYTES: usize = 1 << 16;

/// Reads a regular file of at most `limit` bytes in chunks of [`CHUNK_BYTES`]: `take` is
/// shown the first chunk (all of a smaller file; `true` when that is the whole file) and says
/// whether to go on (`false`: `Ok(false)`, nothing more read); every chunk, the first too,
/// then goes to `push`. `Ok(false)` too for anything but a regular file within the bound (the
/// caller reads it whole, with [`read_bounded`]'s checks).
pub fn read_chunks(
    path: &Path,
    limit: u64,
    take: impl FnOnce(&[u8], bool) -> bool,
    mut push: impl FnMut(&[u8]),
) -> Result<bool, ReadError> {
    let mut file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() || meta.len() > limit || meta.len() == 0 {
        return Ok(false);
    }
    let mut buf = vec![0u8; CHUNK_BYTES];
    let mut first = 0;
    while first < buf.len() {
        match file.read(&mut buf[first..]) {
            Ok(0) => break,
            Ok(n) => first += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
    if !take(&buf[..first], first < buf.len()) {
        return Ok(false);
    }
    push(&buf[..first]);
    loop {
        match file.read(&mut buf) {
            Ok(0) => return Ok(true),
            Ok(n) => push(&buf[..n]),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_and_devices_are_read_within_the_bound() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("f");
        std::fs::write(&f, [7u8; 100]).unwrap();
        assert_eq!(read_bounded(&f, 100).unwrap().len(), 100);
        assert!(matches!(
            read_bounded(&f, 99),
            Err(ReadError::TooLarge { limit: 99 })
        ));
        // a device without an end: refused one byte past the bound
        assert!(matches!(
            read_bounded(Path::new("/dev/zero"), 4096),
            Err(ReadError::TooLarge { limit: 4096 })
        ));
        assert!(matches!(
            read_bounded(&dir.path().join("missing"), 10),
            Err(ReadError::Io(e)) if e.kind() == io::ErrorKind::NotFound
        ));
    }

    #[test]
    fn a_file_is_read_in_chunks_once_its_first_is_taken() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("f");
        let bytes: Vec<u8> = (0..=255u8).cycle().take(3 * CHUNK_BYTES / 2).collect();
        std::fs::write(&f, &bytes).unwrap();
        let mut got = Vec::new();
        let taken = read_chunks(
            &f,
            1 << 20,
            |first, whole| first.len() == CHUNK_BYTES && !whole,
            |c| got.extend_from_slice(c),
        );
        assert!(taken.unwrap());
        assert_eq!(got, bytes);
        // refused by `take`, beyond the bound, or not a regular file: nothing pushed
        let mut pushed = false;
        assert!(!read_chunks(&f, 1 << 20, |_, _| false, |_| pushed = true).unwrap());
        assert!(!read_chunks(&f, 100, |_, _| true, |_| pushed = true).unwrap());
        assert!(!read_chunks(
            Path::new("/dev/zero"),
            1 << 20,
            |_, _| true,
            |_| pushed = true
        )
        .unwrap());
        assert!(!pushed);
    }
}
