//! The recording against regular files, a full device and FIFOs whose reader never reads or is
//! missing.

use super::*;
use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;

/// Every note the recording gives.
fn notes(r: &mut Recorder) -> Vec<RecordNote> {
    let mut v = Vec::new();
    r.tick(&mut |n| v.push(n));
    v
}

/// Ends the recording; its last notes.
fn finish(r: &mut Recorder, timeout: Duration) -> Vec<RecordNote> {
    let mut v = Vec::new();
    r.finish(timeout, &mut |n| v.push(n));
    v
}

fn mkfifo(path: &Path) {
    let c = CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

/// The read end of a FIFO, opened without waiting for a writer, never read.
fn reader_that_never_reads(path: &Path) -> File {
    OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .unwrap()
}

#[test]
fn numbers_go_before_the_extension() {
    let p = Path::new("/x/rec.tsp");
    assert_eq!(numbered(p, 0), Path::new("/x/rec.tsp"));
    assert_eq!(numbered(p, 1), Path::new("/x/rec.1.tsp"));
    assert_eq!(numbered(Path::new("/x/rec"), 2), Path::new("/x/rec.2"));
    assert_eq!(number_of(p, Path::new("/x/rec.7.tsp")), Some(7));
}

#[test]
fn an_existing_record_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("rec.tsp");
    std::fs::write(&base, b"old").unwrap();
    let mut r = Recorder::create(&base, None).unwrap();
    assert_eq!(r.path(), dir.path().join("rec.1.tsp"));
    r.write(b"new");
    let mut all = notes(&mut r);
    all.extend(finish(&mut r, CLOSE_TIMEOUT));
    assert_eq!(std::fs::read(&base).unwrap(), b"old");
    assert_eq!(std::fs::read(dir.path().join("rec.1.tsp")).unwrap(), b"new");
    assert_eq!((r.bytes_written(), r.bytes_dropped()), (3, 0));
    assert!(matches!(&all[..], [RecordNote::File { path }] if path.ends_with("rec.1.tsp")));
    assert!(r.error().is_none());
}

#[test]
fn rotation_numbers_every_file_skips_a_fifo_and_a_link_and_loses_no_byte() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("r.tsp");
    std::fs::write(dir.path().join("r.2.tsp"), b"keep").unwrap();
    // a FIFO without a reader (opening it would block) and a link to a file of someone else's
    mkfifo(&dir.path().join("r.3.tsp"));
    std::fs::write(dir.path().join("other"), b"other").unwrap();
    std::os::unix::fs::symlink(dir.path().join("other"), dir.path().join("r.4.tsp")).unwrap();
    let mut r = Recorder::create(&base, Some(10)).unwrap();
    for k in 0..7u8 {
        r.write(&[k; 4]);
    }
    let mut all = notes(&mut r);
    all.extend(finish(&mut r, CLOSE_TIMEOUT));
    // 4 bytes per read, at most 10 per file: two reads per file
    let sizes: Vec<_> = ["r.tsp", "r.1.tsp", "r.5.tsp", "r.6.tsp"]
        .iter()
        .map(|n| std::fs::read(dir.path().join(n)).unwrap().len())
        .collect();
    assert_eq!(sizes, [8, 8, 8, 4]);
    assert_eq!(std::fs::read(dir.path().join("r.2.tsp")).unwrap(), b"keep");
    assert_eq!(std::fs::read(dir.path().join("other")).unwrap(), b"other");
    assert_eq!((r.bytes_written(), r.bytes_dropped()), (28, 0));
    assert_eq!(all.len(), 4, "{all:?}");
    assert!(all.iter().all(|n| matches!(n, RecordNote::File { .. })));
}

#[test]
fn a_full_disk_is_reported_once_and_counted() {
    let mut r = Recorder::create(Path::new("/dev/full"), None).unwrap();
    r.write(&[1; 100]);
    let mut all = finish(&mut r, CLOSE_TIMEOUT);
    r.write(&[1; 100]);
    all.extend(notes(&mut r));
    assert_eq!((r.bytes_written(), r.bytes_dropped()), (0, 0));
    let (path, e) = r.failure().unwrap();
    assert_eq!(path, Path::new("/dev/full"));
    assert_eq!(e.raw_os_error(), Some(28));
    assert_eq!(all.len(), 2, "{all:?}");
    assert!(matches!(all[1], RecordNote::Failed { .. }));
    assert!(r.error().unwrap().to_string().contains("/dev/full"));
}

#[test]
fn bytes_are_handed_over_within_the_flush_period() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("r.tsp");
    let mut r = Recorder::create(&base, None).unwrap();
    r.write(b"abc");
    notes(&mut r);
    // held by the sampler until HAND_OFF has passed: the recorder thread has nothing yet
    assert_eq!(std::fs::read(&base).unwrap().len(), 0);
    std::thread::sleep(HAND_OFF);
    notes(&mut r);
    // now written by the recorder thread, without `finish`
    let t = Instant::now();
    while std::fs::read(&base).unwrap().len() < 3 {
        assert!(t.elapsed() < Duration::from_secs(10), "never written");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(std::fs::read(&base).unwrap(), b"abc");
    finish(&mut r, CLOSE_TIMEOUT);
}

#[test]
fn a_fifo_whose_reader_never_reads_drops_counts_and_reports_once_and_never_waits() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    mkfifo(&fifo);
    let _reader = reader_that_never_reads(&fifo);
    let mut r = Recorder::create(&fifo, Some(65_536)).unwrap();
    assert_eq!(r.path(), fifo);
    // far more than the pipe (64 KiB) and every chunk (2 MiB) hold
    let read = [7u8; 4096];
    let reads = 2 * CHUNKS * CHUNK / read.len();
    let mut all = Vec::new();
    for _ in 0..reads {
        r.write(&read);
        r.tick(&mut |n| all.push(n));
    }
    let total = (reads * read.len()) as u64;
    assert!(r.bytes_dropped() > 0);
    all.extend(finish(&mut r, Duration::from_millis(50)));
    assert_eq!(r.bytes_written() + r.bytes_dropped(), total);
    assert!(r.bytes_written() <= 1 << 20, "{}", r.bytes_written());
    let dropped: Vec<_> = all
        .iter()
        .filter(|n| matches!(n, RecordNote::Dropped { .. }))
        .collect();
    assert_eq!(dropped.len(), 1, "{all:?}");
    // not rotated: the FIFO's numbered names are not ours
    assert!(all
        .iter()
        .all(|n| !matches!(n, RecordNote::File { path } if **path != *fifo)));
    let e = r.error().unwrap().to_string();
    assert!(
        e.contains("fell behind") && e.contains("bytes dropped"),
        "{e}"
    );
}

#[test]
fn a_fifo_without_a_reader_is_refused_at_once_and_a_block_device_always() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    mkfifo(&fifo);
    let e = Recorder::create(&fifo, None).unwrap_err();
    assert!(e.to_string().contains("FIFO with no reader"), "{e}");
    assert!(
        !dir.path().join("pipe.1").exists(),
        "no numbered file instead"
    );
    if let Some(dev) = ["/dev/loop0", "/dev/sda", "/dev/vda", "/dev/nvme0n1"]
        .iter()
        .find(|p| std::fs::metadata(p).is_ok_and(|m| m.file_type().is_block_device()))
    {
        let e = Recorder::create(Path::new(dev), None).unwrap_err();
        assert!(e.to_string().contains("block device"), "{e}");
    }
}
