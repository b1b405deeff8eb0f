//! The daemon's [`Identifier`]: the identification core's [`Workspace`], sized once at start-up
//! from the configuration, so that identifying a window makes no heap allocation.
//!
//! The window's throttle is the input, the configured channel the output, the device's pulse
//! starts (rising edges of IMPULSE_ACTIVE) are given to the core as its pulse starts, and the
//! sample period comes from the device clock.

use serde_json::{Map, Value};

use super::config::Config;
use super::window::WindowView;
use super::worker::Identifier;
use super::DaemonError;
use crate::core::pulses::PulseInput;
use crate::core::svd::SvdChoice;
use crate::core::workspace::{IdentOptions, Limits, Workspace};

/// The core's workspace behind the daemon's [`Identifier`] trait.
pub struct CoreIdentifier {
    ws: Workspace,
    opts: IdentOptions,
    ok: bool,
}

impl CoreIdentifier {
    /// Sizes the workspace for the configured window length and pulses per model.
    pub fn new(cfg: &Config) -> Result<CoreIdentifier, DaemonError> {
        let limits = Limits {
            max_samples: cfg.identify.max_window_samples,
            max_outputs: 1,
            max_inputs: 1,
            max_order: cfg.identify.order.unwrap_or(8).max(8),
            // the window holds K pulses when identified; room for a few more is free
            max_pulses: cfg.identify.pulses_per_model as usize + 2,
            ..Limits::default()
        };
        let ws = Workspace::new(&limits).map_err(|e| DaemonError::Identify(e.to_string()))?;
        let opts = IdentOptions {
            order: cfg.identify.order,
            jackknife: cfg.identify.jackknife,
            ..IdentOptions::default()
        };
        Ok(CoreIdentifier {
            ws,
            opts,
            ok: false,
        })
    }

    /// Forces one SVD path (the default is [`SvdChoice::Auto`]); both are allocation-free.
    pub fn with_svd(mut self, svd: SvdChoice) -> CoreIdentifier {
        self.opts.svd = svd;
        self
    }
}

impl Identifier for CoreIdentifier {
    fn identify(&mut self, v: &WindowView<'_>) -> Result<(), String> {
        self.ok = false;
        let y = [v.output];
        let input = PulseInput {
            dt_s: v.dt_s,
            u: v.input,
            y: &y,
            missing: v.missing,
            pulse_starts: Some(v.pulse_starts),
        };
        self.ws
            .identify(&input, &self.opts)
            .map_err(|e| e.to_string())?;
        self.ok = true;
        Ok(())
    }

    fn report(&self) -> Result<Map<String, Value>, String> {
        if !self.ok {
            return Err("no model identified".into());
        }
        match serde_json::to_value(self.ws.to_report()) {
            Ok(Value::Object(m)) => Ok(m),
            Ok(_) => Err("the model report is not a JSON object".into()),
            Err(e) => Err(format!("cannot serialise the model: {e}")),
        }
    }
}
