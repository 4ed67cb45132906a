//! The physical model's midpoint step (`Integrator::Midpoint`,
//! docs/model.md "Time integration"): backward Euler's solve over half the
//! step, then the state extrapolated to the step's end as the implicit
//! midpoint rule does (`x_end = 2 x_mid - x`, `v_end = 2 v_mid - v`), which
//! neither damps nor pumps a linear mode. Hair is stiff: the plain rule
//! blew up within a second (energy pumped into the stretch, shear, twist
//! and short-wavelength bending modes, which two Newton iterations leave
//! unconverged), so the extrapolation is kept to the slow modes:
//! - the edges keep the half step's lengths and stretch rates (stretch);
//! - each frame is carried by its edge (the shortest turn from the half
//!   step's tangent to the end's), its twist and twist rate the half
//!   step's (shear, twist);
//! - the extrapolated displacements and velocity changes are smoothed along
//!   the strand (`SMOOTHING_PASSES`), so a rough bending mode takes
//!   backward Euler's half step and a smooth one the midpoint rule.
//!
//! Where the extrapolation is not known to be safe the strand takes
//! backward Euler's whole step instead ([`takes_midpoint`]): a contact, a
//! hold, a blower or hair-hair act through the solve or through per-step
//! velocity changes that assume the step's end, and a root or target that
//! moves kinematically would be extrapolated as a velocity it never had.

use crate::sim::contact::colliders::boxes_overlap;
use crate::sim::math::{self, V3};
use crate::sim::work::{Context, StrandMut, Work};

/// Passes of the `[1/4, 1/2, 1/4]` filter over the extrapolation along the
/// strand. Each pass keeps `cos^2(k/2)` of a mode of `k` radians per edge:
/// the Nyquist mode (`k = pi`) not at all, the 5 cm hair's first mode on 16
/// edges 0.997 (it still keeps 0.999 of its amplitude a cycle at dt 1/120
/// after eight passes). A linear field (a turn of the whole strand about
/// its root, a translation) passes unchanged. Measured: a 20 cm helix (1
/// cm curl) hung under gravity blew up with two passes at 128 edges and dt
/// 1/360 and held with four (also at 64 edges and 1/120, 256 edges and
/// 1/1000); with four, one sag-free 21 cm strand of a generated scalp (1
/// cm edges) drifted 1.6 mm in 2 s where backward Euler held it, with
/// eight 0.07 mm (`sag_free_start_keeps_the_bangs_and_a_scalp_where_they_were_groomed`).
const SMOOTHING_PASSES: usize = 8;

/// A strand takes the midpoint step only if each of its edges is at least
/// this speed times `dt` long, m/s. Finer edges make light frames whose
/// rough modes the half step's two Newton iterations leave unconverged: the
/// hung helix above blew up at 0.19 m/s (128 edges, dt 1/120) and 0.28 m/s
/// (256 edges, 1/360) and held from 0.375 m/s up (64 edges at 1/120, the
/// 5 cm hair's 16 edges at 1/120). Such strands take backward Euler's step.
const MIN_EDGE_SPEED: f32 = 0.35;

/// A strand takes the midpoint step only if no edge turns faster than this
/// in a step (rad), at its velocities at the step's start: a strand in a
/// violent transient (its root jumped, it whips) takes backward Euler's
/// step, which damps it, until it is calm again. The released 5 cm hair's
/// tip edge turns about 0.07 rad a step at dt 1/120.
const MAX_TURN_PER_STEP: f32 = 0.25;

/// Whether strand `s` takes the midpoint step this step: the step allows it
/// (`Context::half`: physical model, `Integrator::Midpoint`, no hold,
/// blower or hair-hair), no vertex of it is driven, its root has not moved,
/// no edge is shorter than `MIN_EDGE_SPEED * dt`, and no collider's box comes within reach of it (where it is this step
/// and twice its velocity ahead, grown by a fall under gravity and two
/// radii).
pub(in crate::sim) fn takes_midpoint(ctx: &Context<'_>, s: &StrandMut<'_>) -> bool {
    if ctx.half.is_none() || s.controls.iter().any(|c| c.targeted) {
        return false;
    }
    let Some(&first) = s.positions.first() else {
        return false;
    };
    if ctx.root_transform.apply(s.root.position) != first {
        return false;
    }
    let shortest = MIN_EDGE_SPEED * ctx.dt;
    let m = s.positions.len() - 1;
    if s.edges[..m]
        .iter()
        .any(|e| e.rest_length.is_nan() || e.rest_length < shortest)
    {
        return false;
    }
    for (e, edge) in s.edges[..m].iter().enumerate() {
        let relative = math::sub(s.velocities[e + 1], s.velocities[e]);
        let turn = math::length(relative) * ctx.dt;
        if turn.is_nan() || turn > MAX_TURN_PER_STEP * edge.rest_length {
            return false;
        }
    }
    if ctx.colliders.is_empty() {
        return true;
    }
    let dt = ctx.dt;
    let (mut lo, mut hi) = (first, first);
    for (x, v) in s.positions.iter().zip(s.velocities.iter()) {
        let ahead = math::add(*x, math::scale(*v, 2.0 * dt));
        for c in 0..3 {
            lo[c] = lo[c].min(x[c]).min(ahead[c]);
            hi[c] = hi[c].max(x[c]).max(ahead[c]);
        }
    }
    let grow = math::length(ctx.gravity) * dt * dt + 2.0 * ctx.radius;
    let lo = lo.map(|c| c - grow);
    let hi = hi.map(|c| c + grow);
    !boxes_overlap(ctx.colliders, lo, hi, dt)
}

/// The end of a midpoint step: `work` holds the half step's solve
/// (`p`, `q`) from the state (`x`, `q_old`, `s`'s velocities); writes the
/// end's positions and frames into `p`, `q` and its velocities into `v`,
/// `omega`. `ctx` is the whole step's.
pub(in crate::sim) fn extrapolate(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    let n = s.positions.len();
    let m = n - 1;
    let inv_h = 2.0 * ctx.inv_dt;
    work.resize_midpoint(n);
    // The half step's velocities, and the raw extrapolation: displacement
    // `x_mid - x` and velocity change `v_mid - v`.
    for i in 0..n {
        let dx = math::sub(work.p[i], work.x[i]);
        let v_mid = math::scale(dx, inv_h);
        work.v_mid[i] = v_mid;
        work.ext_dx[i] = dx;
        work.ext_dv[i] = math::sub(v_mid, s.velocities[i]);
    }
    smooth(
        &mut work.ext_dx[..n],
        &work.w[..n],
        &mut work.smooth_scratch,
    );
    smooth(
        &mut work.ext_dv[..n],
        &work.w[..n],
        &mut work.smooth_scratch,
    );
    let fixed = |work: &Work, i: usize| work.w[i] <= 0.0;
    // Positions: the half step plus the smoothed displacement, each edge
    // then given its half-step length again (root to tip).
    for i in 0..n {
        work.mid[i] = work.p[i];
        if !fixed(work, i) {
            work.p[i] = math::add(work.p[i], work.ext_dx[i]);
        }
    }
    for e in 0..m {
        let mid_edge = math::sub(work.mid[e + 1], work.mid[e]);
        let length = math::length(mid_edge);
        let edge = math::sub(work.p[e + 1], work.p[e]);
        let now = math::length(edge);
        if !fixed(work, e + 1) && now > 0.0 {
            work.p[e + 1] = math::add(work.p[e], math::scale(edge, length / now));
        }
    }
    // Velocities: the half step's plus the smoothed change, each edge's
    // stretch rate then the half step's (root to tip).
    for i in 0..n {
        work.v[i] = if fixed(work, i) {
            // A fixed vertex moves as its half step (the root, still).
            work.v_mid[i]
        } else {
            math::add(work.v_mid[i], work.ext_dv[i])
        };
    }
    for e in 0..m {
        if fixed(work, e + 1) {
            continue;
        }
        let mid_edge = math::sub(work.mid[e + 1], work.mid[e]);
        let mid_length = math::length(mid_edge);
        let edge = math::sub(work.p[e + 1], work.p[e]);
        let length = math::length(edge);
        if mid_length <= 0.0 || length <= 0.0 {
            continue;
        }
        let t_mid = math::scale(mid_edge, 1.0 / mid_length);
        let t = math::scale(edge, 1.0 / length);
        let rate_mid = math::dot(math::sub(work.v_mid[e + 1], work.v_mid[e]), t_mid);
        let rate = math::dot(math::sub(work.v[e + 1], work.v[e]), t);
        work.v[e + 1] = math::add(work.v[e + 1], math::scale(t, rate_mid - rate));
    }
    // Frames: carried by their edges from the half step, their twist rate
    // the half step's.
    for e in 0..m {
        let q_mid = work.q[e];
        let q_old = work.q_old[e];
        let omega_mid = math::turn_rate(q_mid, q_old, inv_h);
        let mid_edge = math::sub(work.mid[e + 1], work.mid[e]);
        let edge = math::sub(work.p[e + 1], work.p[e]);
        let (mid_length, length) = (math::length(mid_edge), math::length(edge));
        if mid_length <= 0.0 || length <= 0.0 {
            work.omega[e] = omega_mid;
            continue;
        }
        let t_mid = math::scale(mid_edge, 1.0 / mid_length);
        let t = math::scale(edge, 1.0 / length);
        work.q[e] = math::qnormalize(math::qmul(math::rotation_between(t_mid, t), q_mid));
        let relative = math::sub(work.v[e + 1], work.v[e]);
        let swing = math::scale(math::cross(t, relative), 1.0 / length);
        let twist = math::dot(omega_mid, t_mid);
        work.omega[e] = math::add(swing, math::scale(t, twist));
    }
}

/// `SMOOTHING_PASSES` of `[1/4, 1/2, 1/4]` along the strand; fixed
/// vertices (`w` 0) keep their value (and bound the filter), the free tip sees a
/// neighbour continuing the last edge's change linearly (so a linear field
/// passes unchanged).
fn smooth(values: &mut [V3], w: &[f32], scratch: &mut Vec<V3>) {
    let n = values.len();
    if n < 3 {
        return;
    }
    scratch.clear();
    scratch.extend_from_slice(values);
    for _ in 0..SMOOTHING_PASSES {
        scratch.copy_from_slice(values);
        for i in 1..n {
            if w[i] <= 0.0 {
                continue;
            }
            let before = scratch[i - 1];
            let after = if i + 1 < n {
                scratch[i + 1]
            } else {
                // 2 x_i - x_{i-1}.
                math::sub(math::scale(scratch[i], 2.0), before)
            };
            values[i] = math::add(
                math::scale(scratch[i], 0.5),
                math::scale(math::add(before, after), 0.25),
            );
        }
    }
}
