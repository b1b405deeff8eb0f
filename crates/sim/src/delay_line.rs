//! A pure delay of whole samples: the ESC's dead time of the motor plant and the `dead_time`
//! effect of the 2nd-order plant share it.

use std::collections::VecDeque;

/// `y_k = u_{k−d}`: the input of `d` samples ago (0 before the line has filled, the settled
/// input after [`DelayLine::settle`]).
#[derive(Debug, Clone)]
pub struct DelayLine {
    buf: VecDeque<f64>,
    samples: usize,
}

impl DelayLine {
    /// A line of `samples` samples (0: no delay).
    pub fn new(samples: usize) -> DelayLine {
        DelayLine {
            buf: VecDeque::with_capacity(samples + 1),
            samples,
        }
    }

    /// The delay, samples.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Pushes `u`, returns the input of `samples` ago.
    pub fn push(&mut self, u: f64) -> f64 {
        if self.samples == 0 {
            return u;
        }
        self.buf.push_back(u);
        if self.buf.len() > self.samples {
            self.buf.pop_front().unwrap_or(0.0)
        } else {
            0.0
        }
    }

    /// Fills the line with `u`, as if it had been held for ever.
    pub fn settle(&mut self, u: f64) {
        self.buf.clear();
        self.buf.extend(std::iter::repeat(u).take(self.samples));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_by_whole_samples_from_rest_and_from_a_settled_input() {
        let mut d = DelayLine::new(2);
        assert_eq!([1.0, 2.0, 3.0].map(|u| d.push(u)), [0.0, 0.0, 1.0]);
        d.settle(5.0);
        assert_eq!([6.0, 7.0, 8.0].map(|u| d.push(u)), [5.0, 5.0, 6.0]);
        let mut none = DelayLine::new(0);
        assert_eq!(none.push(4.0), 4.0);
    }
}
