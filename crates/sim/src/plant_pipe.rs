//! The plant as a line-protocol server for an emulated firmware (`propid sim --plant-pipe`,
//! driven by `firmware/harness`): the emulator owns time, the plant answers one step per line.
//!
//! Each input line is the throttle (0..1, from the ESC pulse width the emulator measured) held
//! for the next [`STEP_S`]; the answer is one line `thrust_N torque_Nm rpm voltage_V current_A`,
//! the sensors' reading at the start of that step (as [`Plant::step`] returns it). A line that
//! is not a number is answered with the throttle taken as 0 and counted; the loop ends at end
//! of input.

use std::io::{self, BufRead, Write};

use crate::plant::Plant;

/// The plant's step in this mode, seconds (the emulator asks once per step).
pub const STEP_S: f64 = 0.001;

/// What [`serve`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PipeStats {
    /// Steps answered.
    pub steps: u64,
    /// Input lines that were not a throttle in 0..=1 (answered as throttle 0).
    pub bad_lines: u64,
}

/// The throttle of one input line: `None` unless a finite number in 0..=1.
pub fn parse_throttle(line: &str) -> Option<f64> {
    let u: f64 = line.trim().parse().ok()?;
    (u.is_finite() && (0.0..=1.0).contains(&u)).then_some(u)
}

/// Answers lines from `input` with `plant` (built with `dt_s = STEP_S`) until end of input.
pub fn serve<R: BufRead, W: Write>(
    plant: &mut Plant,
    input: R,
    mut out: W,
) -> io::Result<PipeStats> {
    let mut stats = PipeStats::default();
    for line in input.lines() {
        let line = line?;
        let u = parse_throttle(&line).unwrap_or_else(|| {
            stats.bad_lines += 1;
            0.0
        });
        let m = plant.step(u);
        let torque = if m.torque_nm.is_finite() {
            m.torque_nm
        } else {
            0.0
        };
        writeln!(
            out,
            "{:.6} {:.6} {:.3} {:.4} {:.4}",
            m.thrust_n, torque, m.rpm, m.voltage_v, m.current_a
        )?;
        out.flush()?;
        stats.steps += 1;
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::PlantConfig;

    #[test]
    fn one_answer_per_line_and_the_motor_spins_up_under_throttle() {
        let mut plant = Plant::new(&PlantConfig::default(), STEP_S, 1).unwrap();
        let input = "0\n".repeat(5) + &"0.5\n".repeat(300) + "junk\n";
        let mut out = Vec::new();
        let s = serve(&mut plant, input.as_bytes(), &mut out).unwrap();
        assert_eq!((s.steps, s.bad_lines), (306, 1));
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 306);
        assert!(rows.iter().all(|r| r.len() == 5));
        // 300 ms at half throttle: thrust near the reference thrust, well above rest
        let (first, spun) = (&rows[0], &rows[304]);
        assert!(first[0].abs() < 0.2, "{first:?}");
        assert!(spun[0] > 2.0 && spun[2] > 10_000.0, "{spun:?}");
    }

    #[test]
    fn throttle_outside_0_to_1_is_refused() {
        assert_eq!(parse_throttle(" 0.25\n"), Some(0.25));
        for bad in ["-0.1", "1.5", "nan", "", "x"] {
            assert_eq!(parse_throttle(bad), None, "{bad}");
        }
    }
}
