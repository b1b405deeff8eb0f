//! The jackknife of a pulse identification: leave-one-pulse-out re-identifications at the
//! model's order, Hankel size and SVD path ([`crate::era::Era::decompose_loo`]), then the
//! jackknife standard deviations ([`crate::uncertainty`]).

use super::engine::Engine;
use super::{Workspace, C64};
use crate::eig::eigenvalues;
use crate::grouped::{input_matrix, InputScratch};
use crate::modal::{dc_gain, fn_zeta};
use crate::pulses::PulseInput;
use crate::statespace::{Abcd, AbcdMut};
use crate::uncertainty::{closest_pair, jackknife_std, strided_jackknife};
use crate::{IdentError, MarkovSeq};

impl Workspace {
    /// Leave-one-pulse-out re-identifications of the last model (its order, Hankel size and
    /// SVD path; `base` the pole pair to match), then the jackknife std. Needs at least two
    /// kept pulses (else the uncertainty stays NaN).
    pub(super) fn jackknife(
        &mut self,
        input: &PulseInput<'_>,
        base: Option<(C64, C64)>,
    ) -> Result<(), IdentError> {
        if self.ensemble.kept() < 2 {
            return Ok(());
        }
        let e = &mut self.engine;
        let mut count = 0;
        for i in 0..self.ensemble.pulses().len() {
            if !self.ensemble.pulses()[i].kept {
                continue;
            }
            self.groups.leave_one_out(
                &self.ensemble,
                input,
                i,
                &mut self.jk_markov,
                &mut self.jk_weights,
            )?;
            let w = &self.jk_weights[..self.groups.groups()];
            let groups = (self.groups.widths(), w);
            e.jackknife_one(&self.jk_markov, count, groups, self.groups.d(), base)?;
            count += 1;
        }
        e.finish_jackknife(count);
        Ok(())
    }
}

impl Engine {
    /// Re-identifies the leave-one-out sequence at the model's order, Hankel size and SVD
    /// path and stores fn, ζ and the DC gains as estimate number `slot` (`base`: the model's
    /// pole pair to match; `None`: it has none, fn and ζ stay NaN).
    fn jackknife_one(
        &mut self,
        markov: &MarkovSeq,
        slot: usize,
        (widths, weights): (&[usize], &[f64]),
        d: &[f64],
        base: Option<(C64, C64)>,
    ) -> Result<(), IdentError> {
        let m = &self.model;
        let (n, q, dims, path) = (m.n, m.q, m.dims, m.path);
        self.era.decompose_loo(markov, dims, n, path)?;
        let lt = &mut self.lite;
        let out = AbcdMut {
            a: &mut lt.a,
            b: &mut lt.b,
            c: &mut lt.c,
            d: &mut lt.d,
        };
        self.era.realize_loo(markov, dims, (n, path), out)?;
        let m = &self.model;
        lt.m[..n * n].copy_from_slice(&lt.a[..n * n]);
        eigenvalues(&mut lt.m, n, &mut lt.poles)?;
        let (f, z) = match base {
            Some(base) => {
                let (s1, s2) = closest_pair(&lt.poles[..n], base, m.dt_s);
                fn_zeta(s1, s2)
            }
            None => (f64::NAN, f64::NAN),
        };
        self.theta_fn[slot] = f;
        self.theta_zeta[slot] = z;
        let scratch = InputScratch {
            s: &mut lt.m,
            t: &mut lt.s,
            nrm: &mut lt.nrm,
        };
        let ok = input_matrix(&lt.a, n, &lt.b, (widths, weights), scratch, &mut lt.b1);
        if ok {
            let sys = Abcd {
                a: &lt.a,
                b: &lt.b1,
                c: &lt.c,
                d,
                n,
                q,
                p: 1,
            };
            dc_gain(sys, &mut lt.m, &mut lt.x, &mut lt.dc);
        } else {
            lt.dc[..q].fill(f64::NAN);
        }
        for i in 0..q {
            self.theta_dc[slot * self.limits.max_outputs + i] = lt.dc[i];
        }
        Ok(())
    }

    /// The jackknife std of fn, ζ and the DC gains over the first `count` estimates.
    fn finish_jackknife(&mut self, count: usize) {
        let m = &mut self.model;
        m.std_fn = jackknife_std(&self.theta_fn[..count]);
        m.std_zeta = jackknife_std(&self.theta_zeta[..count]);
        let mq = self.limits.max_outputs;
        for i in 0..m.q {
            let vals = (0..count).map(|s| self.theta_dc[s * mq + i]);
            m.std_dc[i] = strided_jackknife(vals, count);
        }
    }
}
