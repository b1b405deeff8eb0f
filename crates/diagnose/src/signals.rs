//! The data a model is fitted to ([`Signals`]) and the 2nd-order core every model starts from
//! ([`Core`]).

/// The 2nd-order core `T'' + 2ζωn T' + ωn² T = ωn² K v` and the output offset `c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Core {
    /// Natural frequency `fn = ωn / 2π`, Hz.
    pub fn_hz: f64,
    /// Damping ratio `ζ`.
    pub zeta: f64,
    /// Static gain `K`, output units per unit throttle.
    pub gain: f64,
    /// Output offset `c`, output units.
    pub offset: f64,
    /// The input's lead `α` (0..1), a share of a sample: each input sample takes effect `α·dt`
    /// before its own row's time (0: at its row, the zero-order hold of a command sent at the
    /// sample instant). Not fitted with the rest: chosen once for the record
    /// ([`crate::lead`]) and kept by every model.
    pub lead: f64,
}

impl Default for Core {
    fn default() -> Self {
        Core {
            fn_hz: 1.0,
            zeta: 0.7,
            gain: 1.0,
            offset: 0.0,
            lead: 0.0,
        }
    }
}

/// The data a model is fitted to.
#[derive(Debug, Clone, Copy)]
pub struct Signals<'a> {
    /// Sample period, seconds.
    pub dt_s: f64,
    /// Input (throttle 0..1), gaps filled with the previous value.
    pub u: &'a [f64],
    /// Measured output; `NaN` where missing.
    pub y: &'a [f64],
    /// Supply voltage, if measured (gaps filled).
    pub voltage: Option<&'a [f64]>,
    /// Reference throttle of the static map (mean of the input).
    pub u_ref: f64,
    /// Reference voltage of the supply term (the record's mean voltage).
    pub v_ref: f64,
}
