//! The operating-system side of the pty runner: opening a master/slave pair (close-on-exec,
//! non-blocking), pointing `--link` at the slave, and waiting, reading and writing on the
//! master without blocking.

use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serialport::{SerialPort, TTYPort};

use super::{schedule, PtyError};
use crate::SimError;

/// One pty pair: the master we keep, the slave path the host opens.
pub(super) struct Link {
    pub(super) master: TTYPort,
    pub(super) path: PathBuf,
}

pub(super) fn open_link(link: Option<&Path>) -> Result<Link, SimError> {
    let (master, slave) = TTYPort::pair().map_err(PtyError::Open)?;
    let path = slave
        .name()
        .map(PathBuf::from)
        .ok_or(PtyError::NoSlaveName)?;
    drop(slave);
    set_cloexec(master.as_raw_fd())?;
    set_nonblocking(master.as_raw_fd())?;
    if let Some(l) = link {
        point_link(l, &path)?;
    }
    Ok(Link { master, path })
}

/// Marks the master close-on-exec: `TTYPort::pair` opens it without, so every child process
/// (a daemon started by the same process, a test's `propid run`) would inherit it, hold the
/// pty open and never see the hang-up when the simulator closes its end.
fn set_cloexec(fd: i32) -> Result<(), SimError> {
    add_fcntl_flag(
        fd,
        (libc::F_GETFD, libc::F_SETFD),
        libc::FD_CLOEXEC,
        "making the pty master close-on-exec",
    )
}

fn set_nonblocking(fd: i32) -> Result<(), SimError> {
    add_fcntl_flag(
        fd,
        (libc::F_GETFL, libc::F_SETFL),
        libc::O_NONBLOCK,
        "making the pty master non-blocking",
    )
}

/// Adds `flag` to the flags of `fd` that the fcntl commands `(get, set)` read and write
/// (descriptor flags `F_GETFD`/`F_SETFD`, status flags `F_GETFL`/`F_SETFL`); `what` names the
/// step in the error.
fn add_fcntl_flag(
    fd: i32,
    (get, set): (libc::c_int, libc::c_int),
    flag: libc::c_int,
    what: &str,
) -> Result<(), SimError> {
    // SAFETY: fcntl on a descriptor we own; no memory is passed.
    let flags = unsafe { libc::fcntl(fd, get) };
    // SAFETY: as above.
    if flags < 0 || unsafe { libc::fcntl(fd, set, flags | flag) } < 0 {
        return Err(SimError::io(what, std::io::Error::last_os_error()));
    }
    Ok(())
}

/// Creates (or atomically replaces) the symlink `link -> target`. An existing file at `link`
/// that is not a symlink is left alone and refused.
pub fn point_link(link: &Path, target: &Path) -> Result<(), SimError> {
    if let Ok(meta) = std::fs::symlink_metadata(link) {
        if !meta.file_type().is_symlink() {
            return Err(PtyError::LinkNotSymlink(link.to_path_buf()).into());
        }
    }
    let tmp = link.with_extension(format!("tmp{}", std::process::id()));
    let _ = std::fs::remove_file(&tmp);
    std::os::unix::fs::symlink(target, &tmp)
        .map_err(|e| SimError::io(format!("creating symlink {}", tmp.display()), e))?;
    std::fs::rename(&tmp, link)
        .map_err(|e| SimError::io(format!("creating symlink {}", link.display()), e))
}

/// What `ppoll` said about the master.
pub(super) enum Ready {
    /// Nothing to read (or the wait timed out).
    Nothing,
    /// Host bytes are waiting.
    Input,
    /// Nobody has the slave open.
    NoReader,
}

/// Waits up to `timeout` for the master to be readable (or hung up).
pub(super) fn wait_master(fd: i32, timeout: Duration) -> Ready {
    let mut pfd = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    let ts = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: one valid pollfd, a valid timespec, no signal mask.
    let n = unsafe { libc::ppoll(&mut pfd, 1, &ts, std::ptr::null()) };
    if n <= 0 {
        Ready::Nothing
    } else if pfd.revents & libc::POLLIN != 0 {
        Ready::Input
    } else if pfd.revents & (libc::POLLHUP | libc::POLLERR) != 0 {
        Ready::NoReader
    } else {
        Ready::Nothing
    }
}

/// Bytes in the slave's input queue (written by us, not read by the host yet), through a second
/// descriptor of the slave opened for the query; `None` when it cannot be opened (a host that
/// holds the port exclusively, without the privilege to override it) or queried.
fn slave_unread(path: &Path) -> Option<usize> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    let flags = libc::O_RDONLY | libc::O_NOCTTY | libc::O_NONBLOCK | libc::O_CLOEXEC;
    // SAFETY: a valid NUL-terminated path; the descriptor is closed below.
    let fd = unsafe { libc::open(c.as_ptr(), flags) };
    if fd < 0 {
        return None;
    }
    let mut n: libc::c_int = 0;
    // SAFETY: FIONREAD writes one c_int to the pointer given.
    let r = unsafe { libc::ioctl(fd, libc::FIONREAD, &mut n) };
    // SAFETY: a descriptor we opened above.
    unsafe { libc::close(fd) };
    (r == 0).then_some(n.max(0) as usize)
}

/// Non-blocking read; `Ok(0)` when nothing is there.
pub(super) fn read_master(fd: i32, buf: &mut [u8]) -> std::io::Result<usize> {
    // SAFETY: `buf` is valid for `buf.len()` bytes.
    let n = unsafe { libc::read(fd, buf.as_mut_ptr().cast(), buf.len()) };
    if n >= 0 {
        return Ok(n as usize);
    }
    let e = std::io::Error::last_os_error();
    match e.kind() {
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted => Ok(0),
        _ => Err(e),
    }
}

/// Non-blocking write; `Ok(0)` when the pty buffer is full.
pub(super) fn write_master(fd: i32, buf: &[u8]) -> std::io::Result<usize> {
    // SAFETY: `buf` is valid for `buf.len()` bytes.
    let n = unsafe { libc::write(fd, buf.as_ptr().cast(), buf.len()) };
    if n >= 0 {
        return Ok(n as usize);
    }
    let e = std::io::Error::last_os_error();
    match e.kind() {
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted => Ok(0),
        _ => Err(e),
    }
}

/// A hang-up: the link is cut (nothing new goes out), then what is on its way — the backlog,
/// and the bytes in the slave's input queue — is given up to [`DRAIN_MAX`](super::DRAIN_MAX) to reach the host
/// before the port closes (closing the master discards the slave's unread bytes). Returns the
/// bytes the host had not read by then (0 when it keeps up). Where the slave's queue cannot
/// be measured (the slave cannot be opened a second time) it waits `DRAIN_BLIND`.
pub(super) fn drain_to_host(
    fd: i32,
    slave: &Path,
    backlog: &mut Vec<u8>,
    bytes_out: &mut u64,
) -> u64 {
    let start = Instant::now();
    let mut last_write = start;
    loop {
        if !backlog.is_empty() {
            match write_master(fd, backlog) {
                Ok(n) => {
                    *bytes_out += n as u64;
                    backlog.drain(..n);
                    if n > 0 {
                        last_write = Instant::now();
                    }
                }
                Err(_) => {
                    let left = backlog.len() as u64;
                    backlog.clear();
                    return left;
                }
            }
        }
        let unread = if backlog.is_empty() {
            slave_unread(slave)
        } else {
            None
        };
        let waited = start.elapsed();
        match unread {
            // the slave's count leaves out what the kernel has not moved to it yet: settled
            Some(0) if backlog.is_empty() && last_write.elapsed() >= schedule::DRAIN_SETTLE => {
                return 0
            }
            None if backlog.is_empty() && waited >= schedule::DRAIN_BLIND => return 0,
            _ if waited >= schedule::DRAIN_MAX => {
                let left = backlog.len() as u64 + unread.unwrap_or(0) as u64;
                backlog.clear();
                return left;
            }
            _ => std::thread::sleep(Duration::from_millis(1)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pty_master_is_close_on_exec() {
        let link = open_link(None).unwrap();
        // SAFETY: F_GETFD on a descriptor we own; no memory is passed.
        let flags = unsafe { libc::fcntl(link.master.as_raw_fd(), libc::F_GETFD) };
        assert!(flags >= 0);
        assert_ne!(
            flags & libc::FD_CLOEXEC,
            0,
            "children must not inherit the master"
        );
    }
}
