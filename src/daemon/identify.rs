//! The daemon's [`Identifier`]: the identification core's [`Workspace`], sized once at start-up
//! from the configuration, so that identifying a window makes no heap allocation.
//!
//! The window's throttle is the input, the configured channel the output, the device's pulse
//! starts (rising edges of IMPULSE_ACTIVE) are given to the core as its pulse starts, and the
//! sample period comes from the device clock.
//!
//! **Jackknife beside the model.** The jackknife uncertainty (one leave-one-pulse-out
//! re-identification per pulse) is about a third of an identification. For the configuration
//! the daemon runs by default (order 2, truncated SVD path) it does not depend on the model's
//! own SVD ([`Workspace::jackknife_only`]), so a helper thread with a second workspace computes
//! it from a copy of the window while this thread identifies the model; the result is the one
//! [`Workspace::identify`] gives, to the bit. The window copy goes into buffers allocated at
//! start-up, and the hand-over is a mutex and a condition variable: still no heap allocation.
//! Other configurations (automatic order, the dense path) run the jackknife after the model.
//!
//! **Outliers.** Before identification, the isolated outlier samples of the window's output
//! are left out (marked missing, never replaced) by the rule `propid identify` applies
//! ([`propid_numerics::outliers`], the throttle's changes guarded), in buffers allocated at
//! start-up: one answer for one window. They count in the model's `missing_samples` and are
//! published as the model line's `outliers` ([`Identifier::outliers`]).

use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

use super::config::Config;
use super::live::{self, ResponseLine};
use super::window::{window_capacity, WindowView};
use super::DaemonError;
use propid_numerics::outliers::{find_outliers, OutlierScratch};
use propid_numerics::pulses::PulseInput;
use propid_numerics::stabilization::StabOptions;
use propid_numerics::stabilization::Stabilization;
use propid_numerics::svd::SvdChoice;
use propid_numerics::workspace::{IdentOptions, Limits, Workspace, AUTO_MAX_BLOCKS};
use propid_numerics::{IdentError, ModelReport};

pub use propid_session::identify::{Identifier, IdentifyError};

/// The core's workspace behind the daemon's [`Identifier`] trait.
pub struct CoreIdentifier {
    ws: Workspace,
    opts: IdentOptions,
    ok: bool,
    helper: Option<Helper>,
    /// The window's output and mask with its outliers left out (allocated once).
    clean: Cleaned,
}

/// A window's output and missing-sample mask with its isolated outliers left out, in buffers
/// allocated once.
#[derive(Default)]
struct Cleaned {
    y: Vec<f64>,
    missing: Vec<bool>,
    scratch: OutlierScratch,
    outliers: usize,
}

impl Cleaned {
    fn with_capacity(cap: usize) -> Cleaned {
        Cleaned {
            y: Vec::with_capacity(cap),
            missing: Vec::with_capacity(cap),
            scratch: OutlierScratch::with_capacity(cap),
            outliers: 0,
        }
    }

    /// Copies the window's output and mask and leaves out its isolated outliers (NaN, marked
    /// missing), judged as `propid identify` judges them, the throttle as the command.
    fn leave_out(&mut self, v: &WindowView<'_>) {
        copy_into(&mut self.y, v.output);
        copy_into(&mut self.missing, v.missing);
        self.missing.resize(v.output.len(), false);
        let found = find_outliers(v.output, v.missing, v.input, &mut self.scratch);
        for &k in found {
            self.y[k] = f64::NAN;
            self.missing[k] = true;
        }
        self.outliers = found.len();
    }

    /// `v` with this output and mask.
    fn view<'a>(&'a self, v: &WindowView<'a>) -> WindowView<'a> {
        WindowView {
            output: &self.y,
            missing: &self.missing,
            ..*v
        }
    }
}

/// A window copy for the helper, in buffers allocated once.
#[derive(Default)]
struct Job {
    dt_s: f64,
    u: Vec<f64>,
    y: Vec<f64>,
    missing: Vec<bool>,
    starts: Vec<usize>,
}

/// What the helper computed: the uncertainty `(std fn, std ζ, std DC gain)`, `None` when the
/// jackknife-only path does not apply.
type JkResult = Result<Option<(f64, f64, f64)>, IdentError>;

/// State shared with the helper thread.
struct State {
    job: Job,
    opts: IdentOptions,
    pending: bool,
    done: bool,
    exit: bool,
    result: JkResult,
}

struct Shared {
    state: Mutex<State>,
    cv: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic in the helper cannot leave the state half-written in a way that matters:
        // the flags are set last. Recover the guard instead of propagating the poison.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The helper thread computing the jackknife beside the model.
struct Helper {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl CoreIdentifier {
    /// Sizes the workspace for the window ([`window_capacity`]: the plan's windows at the
    /// fastest rate), Hankel matrices over whole pulse responses, and the pulses per model (and
    /// the helper's twin workspace when the jackknife is on).
    pub fn new(cfg: &Config) -> Result<CoreIdentifier, DaemonError> {
        let cap = window_capacity(cfg);
        // The Hankel may span the whole pulse response (half the window each way): at 20 kHz
        // a 12 Hz plant's response takes ~2 000 lags, far past the default 128 blocks.
        let blocks = (cap / 2).clamp(Limits::default().max_block_rows, AUTO_MAX_BLOCKS);
        let limits = Limits {
            max_samples: cap,
            max_block_rows: blocks,
            max_block_cols: blocks,
            max_outputs: 1,
            max_inputs: 1,
            max_order: cfg.identify.order.unwrap_or(8).max(8),
            // the window holds K pulses when identified; room for a few more is free
            max_pulses: cfg.identify.pulses_per_model as usize + 2,
        };
        let ws = Workspace::new(&limits).map_err(DaemonError::Identify)?;
        let opts = IdentOptions {
            order: cfg.identify.order,
            jackknife: cfg.identify.jackknife,
            ..IdentOptions::default()
        };
        let helper = if opts.jackknife && opts.order == Some(2) {
            let twin = Workspace::new(&limits).map_err(DaemonError::Identify)?;
            Helper::spawn(twin, cap.max(4), limits.max_pulses + 1, opts)
        } else {
            None
        };
        Ok(CoreIdentifier {
            ws,
            opts,
            ok: false,
            helper,
            clean: Cleaned::with_capacity(cap),
        })
    }

    /// Forces one SVD path (the default is [`SvdChoice::Auto`]); both are allocation-free.
    pub fn with_svd(mut self, svd: SvdChoice) -> CoreIdentifier {
        self.opts.svd = svd;
        self
    }

    /// Model and jackknife, the jackknife on the helper thread when it applies.
    fn identify_beside(&mut self, input: &PulseInput<'_>, v: &WindowView<'_>) -> JkResult {
        let Some(helper) = &self.helper else {
            return Ok(None);
        };
        helper.post(v, self.opts);
        let main = self.ws.identify_model(input, &self.opts).map(|_| ());
        let jk = helper.wait();
        main?;
        jk
    }
}

impl Helper {
    /// Starts the helper thread with its twin workspace and window buffers of `cap` samples
    /// and `max_starts` pulse starts. `None` if the thread cannot be started (the jackknife
    /// then runs after the model, as without a helper).
    fn spawn(
        mut twin: Workspace,
        cap: usize,
        max_starts: usize,
        opts: IdentOptions,
    ) -> Option<Helper> {
        let job = Job {
            dt_s: f64::NAN,
            u: Vec::with_capacity(cap),
            y: Vec::with_capacity(cap),
            missing: Vec::with_capacity(cap),
            starts: Vec::with_capacity(max_starts),
        };
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                job,
                opts,
                pending: false,
                done: false,
                exit: false,
                result: Ok(None),
            }),
            cv: Condvar::new(),
        });
        let sh = shared.clone();
        let thread = std::thread::Builder::new()
            .name("propid-jackknife".into())
            .spawn(move || helper_loop(&sh, &mut twin))
            .ok()?;
        Some(Helper {
            shared,
            thread: Some(thread),
        })
    }

    /// Copies the window into the job buffers (within their capacity: no allocation) and
    /// wakes the helper.
    fn post(&self, v: &WindowView<'_>, opts: IdentOptions) {
        let mut st = self.shared.lock();
        let job = &mut st.job;
        job.dt_s = v.dt_s;
        copy_into(&mut job.u, v.input);
        copy_into(&mut job.y, v.output);
        copy_into(&mut job.missing, v.missing);
        copy_into(&mut job.starts, v.pulse_starts);
        st.opts = opts;
        st.pending = true;
        st.done = false;
        drop(st);
        self.shared.cv.notify_all();
    }

    /// Waits for the helper's result.
    fn wait(&self) -> JkResult {
        let mut st = self.shared.lock();
        while !st.done {
            st = self.shared.cv.wait(st).unwrap_or_else(|p| p.into_inner());
        }
        st.result.clone()
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        self.shared.lock().exit = true;
        self.shared.cv.notify_all();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// `dst = src` within `dst`'s capacity (the window never outgrows the buffers sized from the
/// same configuration; a longer one would only reallocate, not fail).
fn copy_into<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
    dst.clear();
    dst.extend_from_slice(src);
}

/// The helper thread: waits for a job, computes the jackknife alone, hands the result back.
fn helper_loop(shared: &Shared, ws: &mut Workspace) {
    loop {
        let mut st = shared.lock();
        while !st.pending && !st.exit {
            st = shared.cv.wait(st).unwrap_or_else(|p| p.into_inner());
        }
        if st.exit {
            return;
        }
        st.pending = false;
        let job = std::mem::take(&mut st.job);
        let opts = st.opts;
        drop(st);
        let y = [&job.y[..]];
        let input = PulseInput {
            dt_s: job.dt_s,
            u: &job.u,
            y: &y,
            missing: &job.missing,
            pulse_starts: Some(&job.starts),
        };
        // A panic here (a bug) must not leave the worker waiting forever: it becomes this
        // window's error, and the helper lives on for the next one.
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            match ws.jackknife_only(&input, &opts) {
                Ok(true) => {
                    let (f, z, d) = ws.model().uncertainty(0);
                    Ok(Some((f, z, d)))
                }
                Ok(false) => Ok(None),
                Err(e) => Err(e),
            }
        }))
        .unwrap_or(Err(IdentError::InvalidInput(
            "internal error: the jackknife helper panicked on this window",
        )));
        let mut st = shared.lock();
        st.job = job;
        st.result = result;
        st.done = true;
        drop(st);
        shared.cv.notify_all();
    }
}

impl CoreIdentifier {
    /// Identifies `v` as it is (its outliers already left out).
    fn identify_view(&mut self, v: &WindowView<'_>) -> Result<(), IdentifyError> {
        let y = [v.output];
        let input = PulseInput {
            dt_s: v.dt_s,
            u: v.input,
            y: &y,
            missing: v.missing,
            pulse_starts: Some(v.pulse_starts),
        };
        match self.identify_beside(&input, v)? {
            Some((f, z, d)) => self.ws.set_uncertainty(f, z, &[d]),
            None if self.helper.is_some() => {
                // The helper did not apply (the dense path): the jackknife after the model.
                if self.opts.jackknife {
                    self.ws.jackknife_model(&input)?;
                }
            }
            None => {
                self.ws.identify(&input, &self.opts)?;
            }
        }
        Ok(())
    }
}

impl Identifier for CoreIdentifier {
    fn identify(&mut self, v: &WindowView<'_>) -> Result<(), IdentifyError> {
        self.ok = false;
        // moved out and back (no allocation), so that the view borrows it beside `self`
        let mut clean = std::mem::take(&mut self.clean);
        clean.leave_out(v);
        let result = self.identify_view(&clean.view(v));
        self.clean = clean;
        result?;
        self.ok = true;
        Ok(())
    }

    fn outliers(&self) -> usize {
        self.clean.outliers
    }

    fn report(&self) -> Result<ModelReport, IdentifyError> {
        if !self.ok {
            return Err(IdentifyError::NoModel);
        }
        Ok(self.ws.to_report())
    }

    fn response(&mut self, v: &WindowView<'_>) -> Option<ResponseLine> {
        if !self.ok {
            return None;
        }
        let model = self.ws.model().state_space();
        let lags = self.ws.markov().len();
        let v = self.clean.view(v);
        Some(live::response(
            self.ws.ensemble(),
            v.output,
            v.missing,
            lags,
            Some(&model),
            v.dt_s,
        ))
    }

    fn stabilization(&mut self) -> Option<Stabilization> {
        if !self.ok {
            return None;
        }
        self.ws.stabilization(&StabOptions::default()).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::window::Reason;

    /// A 1 kHz window of four ±pulses on a noisy 2nd-order response (fn 12 Hz, ζ 0.6),
    /// 300 samples apart: (throttle, thrust, pulse starts).
    fn window() -> (Vec<f64>, Vec<f64>, Vec<usize>) {
        let n = 1300;
        let dt = 1e-3;
        let (w, z) = (2.0 * std::f64::consts::PI * 12.0, 0.6);
        let (a1, a2) = (
            2.0 * (-z * w * dt).exp() * ((w * dt) * (1.0 - z * z).sqrt()).cos(),
            -(-2.0 * z * w * dt).exp(),
        );
        let starts = vec![100, 400, 700, 1000];
        let mut u = vec![0.3; n];
        for (k, &s) in starts.iter().enumerate() {
            u[s] += if k % 2 == 0 { 0.1 } else { -0.1 };
        }
        let (mut y, mut rng) = (vec![0.0; n], 0x2545_F491_4F6C_DD1Du64);
        let (mut y1, mut y2) = (0.0, 0.0);
        for k in 0..n {
            let x = if k > 0 { u[k - 1] - 0.3 } else { 0.0 };
            let v = a1 * y1 + a2 * y2 + 0.5 * x;
            (y2, y1) = (y1, v);
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            y[k] = 3.0 + v + 1e-3 * ((rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
        }
        (u, y, starts)
    }

    fn view<'a>(u: &'a [f64], y: &'a [f64], m: &'a [bool], s: &'a [usize]) -> WindowView<'a> {
        WindowView {
            input: u,
            output: y,
            missing: m,
            pulse_starts: s,
            dt_s: 1e-3,
            level: 0.3,
            level_number: 0,
            first_index: 0,
            last_t_us: 0,
            last_received: None,
            reason: Reason::Pulses,
        }
    }

    /// The jackknife on the helper thread gives the sequential `Workspace::identify` model,
    /// to the bit, on both SVD paths (the dense one falls back to the jackknife after the
    /// model), and over several windows in a row.
    #[test]
    fn helper_jackknife_equals_the_sequential_identification() {
        let (u, y, starts) = window();
        let missing = vec![false; u.len()];
        let cfg = Config::default();
        for svd in [SvdChoice::Truncated, SvdChoice::Dense] {
            let mut id = CoreIdentifier::new(&cfg).unwrap().with_svd(svd);
            assert!(
                id.helper.is_some(),
                "order 2 with jackknife starts the helper"
            );
            let mut ws = Workspace::new(&id.ws.limits().clone()).unwrap();
            let opts = IdentOptions { svd, ..id.opts };
            for round in 0..3 {
                let len = u.len() - 100 * round;
                let v = view(&u[..len], &y[..len], &missing[..len], &starts[..4 - round]);
                id.identify(&v).unwrap();
                let yy = [&y[..len]];
                let input = PulseInput {
                    dt_s: 1e-3,
                    u: &u[..len],
                    y: &yy,
                    missing: &missing[..len],
                    pulse_starts: Some(&starts[..4 - round]),
                };
                ws.identify(&input, &opts).unwrap();
                let (a, b) = (id.report().unwrap(), ws.to_report());
                // compared as published (NaN fields as null)
                let json = |r: &ModelReport| serde_json::to_value(r).unwrap();
                assert_eq!(json(&a), json(&b), "{svd:?} round {round}");
                assert!(b.uncertainty.fn_hz > 0.0);
            }
        }
    }

    /// Issue 12, one answer for one window: a daemon window with lost samples (in three of
    /// the four pulse responses, one of them at lag 2, and in a baseline) gives the model
    /// `propid identify` gives for the same samples through `identify_any` with the same
    /// options: the same rule (average per lag over the pulses measured there, path "pulse"),
    /// the same numbers, the jackknife included, and both say how many samples were missing.
    /// With an isolated outlier too (0.3 N on a 0.1 N response, in the second pulse's
    /// response): both leave it out by the same rule, count it, and still agree.
    #[test]
    fn window_with_holes_gives_the_model_identify_gives() {
        use propid_numerics::identify::{identify_any, AnyInput, PathTaken};
        use propid_numerics::okid::OkidOptions;
        use propid_numerics::outliers::isolated_outliers;
        let (u, y, starts) = window();
        let mut missing = vec![false; u.len()];
        let (mut u, mut y) = (u, y);
        for k in [60, 102, 433, 434, 790, 1111] {
            missing[k] = true;
            u[k] = f64::NAN;
            y[k] = f64::NAN;
        }
        let cfg = Config::default();
        let mut id = CoreIdentifier::new(&cfg).unwrap();
        for outlier in [None, Some(415)] {
            let mut y = y.clone();
            if let Some(k) = outlier {
                y[k] += 0.3;
            }
            let v = view(&u, &y, &missing, &starts);
            id.identify(&v).unwrap();
            let daemon = id.report().unwrap();
            assert_eq!((daemon.pulses, daemon.pulses_skipped), (4, 0));
            let n_out = usize::from(outlier.is_some());
            assert_eq!(id.outliers(), n_out, "{outlier:?}");
            assert_eq!(daemon.missing_samples, 6 + n_out, "{outlier:?}");
            // `propid identify`: the outliers its rule finds (the one put there) left out
            let found = isolated_outliers(&y, &missing, &u);
            assert_eq!(found, outlier.into_iter().collect::<Vec<_>>());
            let (mut y_id, mut missing_id) = (y.clone(), missing.clone());
            for &k in &found {
                y_id[k] = f64::NAN;
                missing_id[k] = true;
            }
            let offline = |y: &[f64], missing: &[bool]| {
                let ins = [&u[..]];
                let outs = [y];
                identify_any(
                    &AnyInput {
                        dt_s: 1e-3,
                        u: &ins,
                        y: &outs,
                        missing,
                        pulse_starts: Some(&starts),
                    },
                    &id.opts,
                    &OkidOptions::default(),
                )
                .unwrap()
            };
            let want = offline(&y_id, &missing_id);
            assert_eq!(want.path, PathTaken::Pulse);
            // The daemon's workspace is sized for its configuration (max order 8), identify's
            // for the record (max order 12): the truncated SVD's Lanczos basis differs in
            // size, so the numbers agree to rounding (1e-9 relative) and the singular values
            // beyond the converged ones differ in count; everything else is equal.
            let json = |r: &ModelReport| {
                let mut v = serde_json::to_value(r).unwrap();
                v["singular_values"].as_array_mut().unwrap().truncate(3);
                v
            };
            assert_close(&json(&daemon), &json(&want.report), &format!("{outlier:?}"));
            // and the clean tolerance holds: fn 12 Hz, ζ 0.6
            assert!((daemon.fn_hz / 12.0 - 1.0).abs() < 0.01, "{}", daemon.fn_hz);
            assert!((daemon.zeta / 0.6 - 1.0).abs() < 0.02, "{}", daemon.zeta);
            if outlier.is_some() {
                // left in, the outlier gives another model: the test sees the difference
                let kept = offline(&y, &missing).report;
                assert!((kept.zeta - daemon.zeta).abs() > 1e-6, "{}", kept.zeta);
            }
        }
    }

    /// `a == b` with numbers within 1e-9 relative (1e-12 absolute).
    fn assert_close(a: &serde_json::Value, b: &serde_json::Value, at: &str) {
        use serde_json::Value;
        match (a, b) {
            (Value::Number(x), Value::Number(y)) => {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!(
                    (x - y).abs() <= 1e-9 * x.abs().max(y.abs()) + 1e-12,
                    "{at}: {x} vs {y}"
                );
            }
            (Value::Array(x), Value::Array(y)) => {
                assert_eq!(x.len(), y.len(), "{at}");
                for (i, (x, y)) in x.iter().zip(y).enumerate() {
                    assert_close(x, y, &format!("{at}[{i}]"));
                }
            }
            (Value::Object(x), Value::Object(y)) => {
                assert_eq!(
                    x.keys().collect::<Vec<_>>(),
                    y.keys().collect::<Vec<_>>(),
                    "{at}"
                );
                for (k, x) in x {
                    assert_close(x, &y[k], &format!("{at}.{k}"));
                }
            }
            _ => assert_eq!(a, b, "{at}"),
        }
    }

    /// An identification error is reported as the sequential path reports it.
    #[test]
    fn helper_path_reports_the_same_errors() {
        let cfg = Config::default();
        let mut id = CoreIdentifier::new(&cfg).unwrap();
        let u = vec![0.3; 400];
        let y = vec![1.0; 400];
        let missing = vec![false; 400];
        let err = id.identify(&view(&u, &y, &missing, &[100])).unwrap_err();
        let mut ws = Workspace::new(id.ws.limits()).unwrap();
        let yy = [&y[..]];
        let input = PulseInput {
            dt_s: 1e-3,
            u: &u,
            y: &yy,
            missing: &missing,
            pulse_starts: Some(&[100]),
        };
        let want = ws.identify(&input, &id.opts).unwrap_err();
        assert_eq!(err, IdentifyError::Core(want));
        assert_eq!(id.report(), Err(IdentifyError::NoModel));
    }

    /// The web page's response of a window: the four pulses' measured responses per unit
    /// throttle (the alternating ±0.1 pulses give the same curve), their mean within the noise
    /// of the model's response to the same one-sample pulse; and its stabilization diagram
    /// holds the model's order.
    #[test]
    fn the_pages_response_is_the_pulses_mean_beside_the_models() {
        let (u, y, starts) = window();
        let missing = vec![false; u.len()];
        let cfg = Config::default();
        let mut id = CoreIdentifier::new(&cfg).unwrap();
        let v = view(&u, &y, &missing, &starts);
        assert!(id.response(&v).is_none(), "nothing before a model");
        id.identify(&v).unwrap();
        let r = id.response(&v).unwrap();
        assert_eq!((r.pulses, r.width, r.dt_s), (4, 1, 1e-3));
        assert_eq!(r.mean.len(), r.model.len());
        let peak = r.model.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        assert!(peak > 0.01, "{peak}");
        for k in 0..r.mean.len() {
            // noise 1e-3 / amplitude 0.1 = 1e-2 per pulse, and the baselines' share
            assert!((r.mean[k] - r.model[k]).abs() < 0.02, "lag {k}: {r:?}");
            assert!(r.spread[k] < 0.03, "lag {k}: {}", r.spread[k]);
        }
        let st = id.stabilization().unwrap();
        assert!(st.orders.iter().any(|o| o.order == 2));
        assert!(st.singular_values.len() >= 2);
    }
}
