//! A CSV bench for the daemon tests: the rows a simple Arduino stand would print
//! (docs/PROTOCOL.md §6 header `t_us,throttle,thrust_N`) for a known plant.

use propid_wire::protocol::csv::line::append_checksum;

/// The bench's plant: a discrete 2nd-order thrust response to throttle at 1 kHz.
#[derive(Debug, Clone, Copy)]
pub struct Plant {
    /// Natural frequency, Hz.
    pub fn_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Thrust per unit throttle, N.
    pub gain: f64,
}

/// The plant every CSV-bench test uses: 12 Hz, ζ 0.4, 10 N per unit throttle.
pub const PLANT: Plant = Plant {
    fn_hz: 12.0,
    zeta: 0.4,
    gain: 10.0,
};

/// `n` data lines (no header) at 1 kHz from t = 2 s: throttle 0.3 with one-sample pulses of
/// alternately +0.05 and −0.05 every 200 samples (at sample 100, 300, …), thrust from the
/// plant's poles `exp(s·dt)` with a one-sample delay, noise-free. Each line ends in `\n`.
pub fn rows(p: Plant, n: usize) -> Vec<String> {
    let dt = 1e-3f64;
    let wn = 2.0 * std::f64::consts::PI * p.fn_hz;
    let (re, im) = (-p.zeta * wn * dt, wn * dt * (1.0 - p.zeta * p.zeta).sqrt());
    let (a1, a2) = (2.0 * re.exp() * im.cos(), -(2.0 * re).exp());
    let b = p.gain * (1.0 - a1 - a2);
    let (mut x1, mut x2, mut du_prev) = (0.0f64, 0.0f64, 0.0f64);
    (0..n)
        .map(|k| {
            let du = match k % 200 {
                100 if (k / 200) % 2 == 0 => 0.05,
                100 => -0.05,
                _ => 0.0,
            };
            let x = a1 * x1 + a2 * x2 + b * du_prev;
            (x2, x1, du_prev) = (x1, x, du);
            let throttle = ((0.3 + du) * 10_000.0).round();
            format!(
                "{},{throttle},{:.6}\n",
                2_000_000 + k * 1000,
                3.0 + p.gain * 0.3 + x
            )
        })
        .collect()
}

/// The header line.
pub const HEADER: &str = "t_us,throttle,thrust_N\n";

/// `line` (without its newline) with the NMEA-style `*HH` checksum appended (the dialect's
/// [`append_checksum`]).
pub fn with_checksum(line: &str) -> String {
    let mut body = line.trim_end().to_string();
    append_checksum(&mut body);
    body.push('\n');
    body
}
