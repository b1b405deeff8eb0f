//! The simulated stand on a pseudo-terminal: `propid sim`, and [`SimHandle`] for running it on
//! a thread inside another process (the daemon's `demo`, integration tests).
//!
//! `serialport::TTYPort::pair()` gives a master (ours) and a slave whose path the host opens
//! like any serial port. The runner closes its own slave handle, so the host is the only one
//! with the slave open: while nobody has it open, the master polls POLLHUP and the device's
//! output is discarded (a real USB device's bytes go nowhere without a host too), so a host that
//! opens late gets fresh data, not a backlog.
//!
//! A pty does not pace, so the runner does: the firmware schedules its samples on device time
//! and the runner hands it a monotonic clock ([`super::pace::MonoClock`]), waiting
//! for host bytes with `ppoll` until the next sample deadline. A late wake-up emits every sample
//! that became due (catch-up without drift). Writes are non-blocking; output the host does not
//! read yet is kept up to [`MAX_BACKLOG`] bytes, beyond which whole batches are dropped and
//! counted.
//!
//! Faults are injected only while a host has the slave open (the injector is switched off
//! otherwise), so [`SimReport::faults`] counts what a connected host could see.
//!
//! A hang-up fault drops the master (the host sees EOF/EIO, i.e. an unplug); with
//! `reopen_after_ms >= 0` a new pty is opened after that delay as a new boot (new boot id,
//! disarmed, counters restarted) and `--link` is re-pointed to it.
//!
//! A freeze fault (`freeze_after_s`, once per run, while a host has the port open) hangs the
//! firmware with the port open: from then on nothing is sent and what the host sends is read
//! and dropped, until the host closes the port (every slave descriptor closed: the master polls
//! POLLHUP), which resets the board — as the DTR line resets an Arduino-style USB board when
//! its port is closed and opened. The next boot (new boot id, disarmed) runs on the same pty.

use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::config::SimConfig;
use super::dynamics::PlantDynamics;
use super::faults::{FaultInjector, FaultStats};
use super::firmware::{Firmware, FirmwareStats};
use super::pace::MonoClock;
use super::SimError;
use propid_wire::protocol::Message;

mod link;
mod schedule;

pub use link::point_link;
use link::{drain_to_host, open_link, read_master, wait_master, write_master, Link, Ready};
use schedule::Schedule;
pub use schedule::DRAIN_MAX;

/// Output kept for a host that does not read, bytes; beyond it output is dropped and counted.
pub const MAX_BACKLOG: usize = 1 << 20;

/// Longest wait for host bytes between checks of the stop flag and the hang-up timer.
const MAX_WAIT: Duration = Duration::from_millis(5);

/// Shortest time between two batches of output, µs: above 2 kHz the samples go out in batches
/// (as a USB device sends per bus frame) instead of one wake-up per sample. Host bytes still
/// wake the runner at once.
const MIN_BATCH_US: u64 = 500;

/// Why the pseudo-terminal could not be created or used.
#[derive(Debug, thiserror::Error)]
pub enum PtyError {
    /// The master/slave pair could not be opened.
    #[error(transparent)]
    Open(#[from] serialport::Error),
    /// The slave of a new pair has no path.
    #[error("the pty slave has no name")]
    NoSlaveName,
    /// `--link` names a file that is not a symlink (left alone).
    #[error("--link {}: exists and is not a symlink", .0.display())]
    LinkNotSymlink(PathBuf),
    /// The runner thread ended before it opened a pty.
    #[error("the simulator did not open a pty")]
    NotOpened,
    /// The runner thread panicked.
    #[error("the simulator thread panicked")]
    ThreadPanicked,
}

/// How the runner is started.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Make a symlink at this path to the slave device (re-pointed after every re-open).
    pub link: Option<PathBuf>,
    /// Stop after this many seconds (None: until stopped or hung up for good).
    pub seconds: Option<f64>,
    /// Inject faults only during the first this many seconds of the run (None: all along); the
    /// rest is a clean tail, so that a host can read everything the faults touched before the
    /// stand stops and its counts can be compared exactly (`scripts/soak.sh`).
    pub faults_for: Option<f64>,
}

/// What the runner did; also available live from [`SimHandle::report`].
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct SimReport {
    /// Boots (1 + re-opens).
    pub boots: u64,
    /// Boot id of the current (or last) boot.
    pub boot_id: u32,
    /// Slave device path of the current (or last) boot.
    pub slave_path: String,
    /// Firmware counters of the current boot.
    pub firmware: FirmwareStats,
    /// SAMPLEs taken over all boots.
    pub samples_total: u64,
    /// Injected faults over all boots.
    pub faults: FaultStats,
    /// Bytes written to the master (this and the byte counters below: over all boots).
    pub bytes_out: u64,
    /// Bytes read from the master.
    pub bytes_in: u64,
    /// Bytes discarded because no host had the slave open.
    pub bytes_no_reader: u64,
    /// Bytes dropped because the host did not read fast enough.
    pub bytes_overrun: u64,
    /// Bytes on the wire the host had not read when a hang-up (or the stop) closed the port
    /// (the runner waits up to [`DRAIN_MAX`] for the host to read them: 0 unless the host was
    /// starved).
    pub bytes_unread_at_hangups: u64,
    /// Pulses started over all boots.
    pub pulses_total: u64,
    /// Why the runner ended (empty while running).
    pub ended: String,
}

/// Shared between the runner and its handle.
#[derive(Debug, Default)]
struct Shared {
    stop: AtomicBool,
    report: Mutex<SimReport>,
    /// Every command the host wrote, over all boots (at most [`MAX_COMMANDS`]).
    commands: Mutex<Vec<(u16, Message)>>,
}

/// Commands kept in [`SimHandle::commands`]'s log.
pub const MAX_COMMANDS: usize = 1 << 20;

/// Runs the simulated stand on a pty until `stop` is set, `opts.seconds` pass, or a hang-up
/// without re-open. `on_path(host_path, slave_path)` is called every time a pty is opened:
/// the path the host should open (the `--link` if given, else the slave) and the slave device.
pub fn run(
    cfg: &SimConfig,
    opts: &RunOptions,
    stop: &AtomicBool,
    mut on_path: impl FnMut(&Path, &Path),
) -> Result<SimReport, SimError> {
    let shared = Shared::default();
    let r = run_shared(cfg, opts, &shared, Some(stop), &mut on_path);
    let report = shared.report.lock().map(|r| r.clone()).unwrap_or_default();
    r.map(|_| report)
}

fn run_shared(
    cfg: &SimConfig,
    opts: &RunOptions,
    shared: &Shared,
    extra_stop: Option<&AtomicBool>,
    on_path: &mut dyn FnMut(&Path, &Path),
) -> Result<(), SimError> {
    let started = Instant::now();
    let deadline = opts
        .seconds
        .map(|s| started + Duration::from_secs_f64(s.max(0.0)));
    let faults_end = opts
        .faults_for
        .map(|s| started + Duration::from_secs_f64(s.max(0.0)));
    let faults_on = || faults_end.map_or(true, |e| Instant::now() < e);
    let stopped = || {
        shared.stop.load(Ordering::Relaxed)
            || extra_stop.is_some_and(|s| s.load(Ordering::Relaxed))
            || deadline.is_some_and(|d| Instant::now() >= d)
    };
    let dt_s = 1.0 / cfg.stand.sample_rate_hz as f64;
    let mut faults = FaultInjector::new(&cfg.faults, cfg.stand.seed);
    let mut schedule = Schedule::new(cfg, started);
    let mut boot = 0u64;
    let mut before = Before::default();
    loop {
        let link = open_link(opts.link.as_deref())?;
        on_path(opts.link.as_deref().unwrap_or(&link.path), &link.path);
        // kept across the boots on this pty: what is on its way out, whether a host is there
        let mut wire = Wire {
            backlog: Vec::new(),
            reader_present: false,
        };
        // the boots on this pty: the first, and one after every freeze the host reset
        loop {
            if boot > 0 {
                faults.new_boot();
            }
            let plant = PlantDynamics::new(&cfg.plant, dt_s, cfg.stand.seed.wrapping_add(boot))?;
            let id = super::boot_id(cfg.stand.seed, boot);
            let mut fw = Firmware::new(&cfg.stand, plant, id, faults);
            {
                let mut r = shared.report.lock().unwrap_or_else(|p| p.into_inner());
                r.boots = boot + 1;
                r.boot_id = id;
                r.slave_path = link.path.display().to_string();
            }
            let freeze = boot == 0;
            let end = serve(
                &mut fw,
                (&link, &mut wire),
                cfg,
                (shared, &mut schedule),
                [&stopped, &faults_on],
                before,
                freeze,
            )?;
            before.samples += fw.stats().samples;
            {
                let r = shared.report.lock().unwrap_or_else(|p| p.into_inner());
                before.io = [r.bytes_out, r.bytes_in, r.bytes_no_reader, r.bytes_overrun];
            }
            before.pulses += fw.stats().pulses;
            faults = fw.into_faults();
            match end {
                End::Stopped => {
                    set_ended(shared, "stopped");
                    return Ok(());
                }
                End::Reset => {
                    faults.discard_pending();
                    boot += 1;
                }
                End::HungUp => break,
            }
        }
        faults.note_hangup();
        faults.discard_pending();
        drop(link);
        if cfg.faults.reopen_after_ms < 0 {
            update(shared, None, &faults, before);
            set_ended(shared, "hung up");
            return Ok(());
        }
        let until = Instant::now() + Duration::from_millis(cfg.faults.reopen_after_ms as u64);
        while Instant::now() < until {
            if stopped() {
                update(shared, None, &faults, before);
                set_ended(shared, "stopped");
                return Ok(());
            }
            std::thread::sleep(MAX_WAIT);
        }
        faults.note_reopen();
        boot += 1;
    }
}

fn set_ended(shared: &Shared, why: &str) {
    let mut r = shared.report.lock().unwrap_or_else(|p| p.into_inner());
    r.ended = why.to_string();
}

fn update(shared: &Shared, fw: Option<FirmwareStats>, faults: &FaultInjector, before: Before) {
    let mut r = shared.report.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(s) = fw {
        r.firmware = s;
        r.samples_total = before.samples + s.samples;
        r.pulses_total = before.pulses + s.pulses;
    }
    r.faults = faults.stats();
}

/// Counters of the boots before the current one.
#[derive(Debug, Clone, Copy, Default)]
struct Before {
    samples: u64,
    pulses: u64,
    /// The byte counters (out, in, no reader, overrun).
    io: [u64; 4],
}

/// One pty's output side, kept across the boots on it.
struct Wire {
    /// Output taken from the firmware, not yet written to the master.
    backlog: Vec<u8>,
    /// Whether a host has the slave open (as last seen).
    reader_present: bool,
}

/// How one boot ended.
enum End {
    /// Stopped (stop flag, `--seconds`).
    Stopped,
    /// A hang-up fault closed the pty.
    HungUp,
    /// Frozen, then reset by the host closing the port, or reset with the port open
    /// (`reset_every_s`): a new boot on the same pty.
    Reset,
}

/// Serves one boot on one pty (`freeze`: the freeze fault may strike in this boot).
fn serve(
    fw: &mut Firmware<PlantDynamics>,
    (link, wire): (&Link, &mut Wire),
    cfg: &SimConfig,
    (shared, schedule): (&Shared, &mut Schedule),
    [stopped, faults_on]: [&dyn Fn() -> bool; 2],
    before: Before,
    freeze: bool,
) -> Result<End, SimError> {
    let fd = link.master.as_raw_fd();
    let clock = MonoClock::start();
    let hangup_us =
        (cfg.faults.hangup_after_s > 0.0).then_some((cfg.faults.hangup_after_s * 1e6) as u64);
    let freeze_us = (freeze && cfg.faults.freeze_after_s > 0.0)
        .then_some((cfg.faults.freeze_after_s * 1e6) as u64);
    let backlog = &mut wire.backlog;
    let mut rx = [0u8; 4096];
    let (mut bytes_out, mut bytes_in, mut no_reader, mut overrun) = (0u64, 0u64, 0u64, 0u64);
    loop {
        if stopped() {
            break;
        }
        let now = clock.now_us();
        let live = wire.reader_present && faults_on();
        let wall = Instant::now();
        if hangup_us.is_some_and(|h| now >= h) || schedule.due(Schedule::HANGUP, wall, live) {
            // the link is cut here; what is already on the wire still reaches the host
            cut_link(fw, (fd, &link.path), backlog, &mut bytes_out, shared);
            publish(
                shared,
                fw,
                before,
                [bytes_out, bytes_in, no_reader, overrun],
            );
            return Ok(End::HungUp);
        }
        if schedule.due(Schedule::RESET, wall, live) {
            fw.faults_mut().note_reset();
            publish(
                shared,
                fw,
                before,
                [bytes_out, bytes_in, no_reader, overrun],
            );
            return Ok(End::Reset);
        }
        if wire.reader_present && freeze_us.is_some_and(|f| now >= f) {
            fw.faults_mut().note_freeze();
            publish(
                shared,
                fw,
                before,
                [bytes_out, bytes_in, no_reader, overrun],
            );
            return Ok(frozen(fd, stopped, &mut rx, shared));
        }
        fw.faults_mut().set_enabled(live);
        fw.faults_mut().set_link_up(wire.reader_present);
        fw.advance(now);
        let start = backlog.len();
        fw.drain_output(now, backlog);
        if backlog.len() > MAX_BACKLOG {
            overrun += (backlog.len() - start) as u64;
            backlog.truncate(start);
        }
        if !wire.reader_present {
            no_reader += backlog.len() as u64;
            backlog.clear();
        } else if !backlog.is_empty() {
            match write_master(fd, backlog) {
                Ok(n) => {
                    bytes_out += n as u64;
                    backlog.drain(..n);
                }
                Err(_) => {
                    // EIO: the host closed the slave between the poll and the write.
                    no_reader += backlog.len() as u64;
                    backlog.clear();
                }
            }
        }
        let wake_us = fw.next_deadline_us().max(now + MIN_BATCH_US);
        let wait = clock.until(wake_us).min(MAX_WAIT);
        match wait_master(fd, wait) {
            Ready::Input => {
                wire.reader_present = true;
                // the host is there: the answers to what it sent go out
                fw.faults_mut().set_link_up(true);
                match read_master(fd, &mut rx) {
                    Ok(n) if n > 0 => {
                        bytes_in += n as u64;
                        fw.feed(clock.now_us(), &rx[..n]);
                        let taken = fw.take_commands();
                        let mut log = shared.commands.lock().unwrap_or_else(|p| p.into_inner());
                        let room = MAX_COMMANDS.saturating_sub(log.len());
                        log.extend(taken.into_iter().take(room));
                    }
                    Ok(_) => {}
                    Err(_) => wire.reader_present = false,
                }
            }
            Ready::NoReader => {
                wire.reader_present = false;
                std::thread::sleep(wait);
            }
            Ready::Nothing => wire.reader_present = true,
        }
        publish(
            shared,
            fw,
            before,
            [bytes_out, bytes_in, no_reader, overrun],
        );
    }
    if wire.reader_present {
        // stopped: the link is cut as at a hang-up, what is on the wire reaches the host
        cut_link(fw, (fd, &link.path), backlog, &mut bytes_out, shared);
    }
    publish(
        shared,
        fw,
        before,
        [bytes_out, bytes_in, no_reader, overrun],
    );
    Ok(End::Stopped)
}

/// The firmware hung: nothing goes out, the host's bytes are read and dropped, until the host
/// closes the port (a reset: [`End::Reset`]) or the runner is stopped.
/// Cuts the link (the fault injector counts what the host never receives from here on) and
/// lets what is already on the wire reach the host ([`drain_to_host`]); what it could not
/// deliver is counted in `bytes_unread_at_hangups`.
fn cut_link(
    fw: &mut Firmware<PlantDynamics>,
    (fd, slave): (i32, &std::path::Path),
    backlog: &mut Vec<u8>,
    bytes_out: &mut u64,
    shared: &Shared,
) {
    fw.faults_mut().set_link_up(false);
    let unread = drain_to_host(fd, slave, backlog, bytes_out);
    shared
        .report
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .bytes_unread_at_hangups += unread;
}

fn frozen(fd: i32, stopped: &dyn Fn() -> bool, rx: &mut [u8], shared: &Shared) -> End {
    loop {
        if stopped() {
            return End::Stopped;
        }
        let dropped = match wait_master(fd, MAX_WAIT) {
            Ready::Input => match read_master(fd, rx) {
                Ok(n) => n as u64,
                Err(_) => return End::Reset, // EIO: no slave open any more
            },
            Ready::NoReader => return End::Reset,
            Ready::Nothing => 0,
        };
        let mut r = shared.report.lock().unwrap_or_else(|p| p.into_inner());
        r.bytes_in += dropped;
    }
}

fn publish(shared: &Shared, fw: &Firmware<PlantDynamics>, before: Before, io: [u64; 4]) {
    let mut r = shared.report.lock().unwrap_or_else(|p| p.into_inner());
    let s = fw.stats();
    r.firmware = s;
    r.samples_total = before.samples + s.samples;
    r.pulses_total = before.pulses + s.pulses;
    r.faults = fw.fault_stats();
    r.bytes_out = before.io[0] + io[0];
    r.bytes_in = before.io[1] + io[1];
    r.bytes_no_reader = before.io[2] + io[2];
    r.bytes_overrun = before.io[3] + io[3];
}

/// The simulated stand running on its own thread.
#[derive(Debug)]
pub struct SimHandle {
    path: PathBuf,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Result<(), SimError>>>,
}

impl SimHandle {
    /// Starts the stand on a new pty on a thread; returns once the device path exists. The path
    /// is `opts.link` when given (needed to reconnect after a hang-up with re-open), else the
    /// slave device.
    pub fn spawn(cfg: SimConfig, opts: RunOptions) -> Result<SimHandle, SimError> {
        cfg.validate()?;
        let shared = Arc::new(Shared::default());
        let (tx, rx) = std::sync::mpsc::channel::<PathBuf>();
        let thread_shared = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("propid-sim".into())
            .spawn(move || {
                let mut on_path = |p: &Path, _slave: &Path| {
                    let _ = tx.send(p.to_path_buf());
                };
                let r = run_shared(&cfg, &opts, &thread_shared, None, &mut on_path);
                if let Err(e) = &r {
                    set_ended(&thread_shared, &format!("error: {e}"));
                }
                r
            })
            .map_err(|e| SimError::io("starting the simulator thread", e))?;
        let mut handle = SimHandle {
            path: PathBuf::new(),
            shared,
            thread: Some(thread),
        };
        match rx.recv_timeout(Duration::from_secs(5)) {
            Ok(p) => {
                handle.path = p;
                Ok(handle)
            }
            Err(_) => Err(handle
                .join()
                .err()
                .unwrap_or_else(|| PtyError::NotOpened.into())),
        }
    }

    /// The device path for the host to open.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A snapshot of the runner's counters (boots, firmware, faults, bytes).
    pub fn report(&self) -> SimReport {
        self.shared
            .report
            .lock()
            .map(|r| r.clone())
            .unwrap_or_default()
    }

    /// Every well-formed command the host wrote so far, in order, over all boots (`seq`,
    /// message; the first [`MAX_COMMANDS`]): what tests hold against the plan.
    pub fn commands(&self) -> Vec<(u16, Message)> {
        self.shared
            .commands
            .lock()
            .map(|c| c.clone())
            .unwrap_or_default()
    }

    /// True once the runner has ended (stopped, timed out, hung up for good, or failed).
    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().map_or(true, |t| t.is_finished())
    }

    /// Stops the stand (closing the pty) and returns its final report.
    pub fn stop(mut self) -> Result<SimReport, SimError> {
        self.shared.stop.store(true, Ordering::Relaxed);
        self.join()?;
        Ok(self.report())
    }

    fn join(&mut self) -> Result<(), SimError> {
        match self.thread.take() {
            Some(t) => t.join().map_err(|_| PtyError::ThreadPanicked)?,
            None => Ok(()),
        }
    }
}

impl Drop for SimHandle {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        let _ = self.join();
    }
}
