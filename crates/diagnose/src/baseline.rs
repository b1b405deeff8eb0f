//! The 2nd-order baseline fit every search starts from ([`baseline`]).

use crate::ctx::Ctx;
use crate::fit::Fit;
use crate::model::Model;
use crate::signals::Core;

/// The 2nd-order baseline with the terms of `template`: a grid over `fn` and `ζ` (gain,
/// offset and linear terms by least squares), then Levenberg–Marquardt from the best two grid
/// points and from every extra start (the core's ERA model); the best result wins.
pub fn baseline(ctx: &Ctx, template: &Model, extra_starts: &[Core]) -> Fit {
    let dt = ctx.sig.dt_s;
    let n = ctx.est.len().max(2) as f64;
    let f_lo = (5.0 / (n * dt)).min(0.1 / dt);
    let f_hi = 0.3 / dt;
    let mut starts = Vec::new();
    for i in 0..14 {
        let fn_hz = f_lo * (f_hi / f_lo).powf(i as f64 / 13.0);
        for zeta in [0.3, 0.7, 1.2, 2.5] {
            starts.push(template.with_core(Core {
                fn_hz,
                zeta,
                lead: template.core.lead,
                ..Core::default()
            }));
        }
    }
    let grid = ctx.best_of(starts, 2);
    let extra = ctx.best_of(
        extra_starts.iter().map(|c| {
            template.with_core(Core {
                lead: template.core.lead,
                ..*c
            })
        }),
        1,
    );
    if extra.sse < grid.sse {
        extra
    } else {
        grid
    }
}
