//! The step's "forces" phase (ii): gravity, drag, the blower and the hold
//! act on the strand, giving its predicted positions and frames in the
//! working copy.

use super::blower::blower_dv;
#[cfg(target_arch = "x86_64")]
use super::blower::blower_dv_eight;
use super::hold::{fold, fold_frame};
#[cfg(target_arch = "x86_64")]
use crate::sim::avx::{eight_to_lanes, lanes_to_eight};
use crate::sim::instructions::in_widest;
use crate::sim::math::{self, V3};
use crate::sim::rod::constraints::{bend_coefficients, StretchCoefficients};
use crate::sim::work::{Context, StrandMut, Work};
use crate::sim::Blower;

/// (ii) of the step, the "forces" phase: external forces and the
/// predicted positions and frames in the working copy.
pub(in crate::sim) fn predict(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    in_widest!(ctx.instructions, fn(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
        predict_strand(ctx, s, work)
    })
}

#[inline(always)]
fn predict_strand(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    let n = s.positions.len();
    let m = n - 1;
    work.resize(n);
    work.strand = s.index;
    work.stuck.clear();
    let dt = ctx.dt;

    // (ii) External forces, then the predicted positions.
    if let Some(blower) = &ctx.blower {
        blow(ctx, blower, s, work);
    }
    for i in 0..n {
        let x = s.positions[i];
        work.x[i] = x;
        let mut blower_dv_here = [0.0f32; 3];
        if ctx.blower.is_some() {
            blower_dv_here = work.blower[i];
        } else {
            work.db[i][0] = 0.0;
        }
        if let Some(reform) = ctx.hydrogen_reform {
            work.db[i][0] += reform[s.first_vertex + i];
        }
        let control = s.controls[i];
        if control.targeted {
            work.p[i] = control.target;
            work.w[i] = 0.0;
            continue;
        }
        if i == 0 {
            work.p[0] = ctx.root_transform.apply(s.root.position);
            work.w[0] = 0.0;
            continue;
        }
        work.w[i] = 1.0;
        let mut a = ctx.gravity;
        if let Some(extra) = ctx.extra_acceleration {
            a = math::add(a, extra[s.first_vertex + i]);
        }
        // Damping slows the motion, not gravity: damping the acceleration
        // too would scale the weight by exp(-c dt) and move the static
        // equilibrium with c and dt.
        // Follow-The-Leader's correction (paper model) acts on the
        // prediction only; the state keeps the real velocity.
        let moving = math::sub(s.velocities[i], s.velocity_corrections[i]);
        let mut v = math::add(math::scale(moving, ctx.linear_keep), math::scale(a, dt));
        v = math::add(v, blower_dv_here);
        if let Some((alpha, grid)) = ctx.hair_hair {
            v = math::add(v, grid.penalty_dv(s.first_vertex + i, alpha, dt));
        }
        if let Some(volume) = ctx.volume {
            v = math::add(v, volume.dv(s.index, i));
        }
        work.p[i] = math::add(x, math::scale(v, dt));
        if let Some(hold) = &ctx.hold {
            let k = hold.at(s.groomed_fraction[i]);
            if k > 0.0 {
                let target = ctx.root_transform.apply(s.groomed[i]);
                (work.p[i], work.w[i]) = fold(work.p[i], target, k, dt);
            }
        }
    }
    work.root_frame = math::qmul(ctx.root_transform.rotation, s.root.frame);
    // The clamp's rest turn (zero unless the sag-free start set one).
    work.rest[0] = s.root.rest;
    for e in 0..m {
        let edge = s.edges[e];
        work.q_old[e] = edge.rotation;
        work.l[e] = edge.rest_length;
        if e == 0 && ctx.physical.is_none() {
            // The root frame is fixed to the scalp.
            work.q[0] = work.root_frame;
            work.w_q[0] = 0.0;
        } else {
            let w = math::scale(edge.angular_velocity, ctx.angular_keep);
            let q = edge.rotation;
            work.q[e] = if w == [0.0; 3] {
                // Renormalising a unit quaternion would only add round-off.
                q
            } else {
                let spin = math::qmul(math::pure(w), q);
                let h = 0.5 * dt;
                math::qnormalize([
                    q[0] + h * spin[0],
                    q[1] + h * spin[1],
                    q[2] + h * spin[2],
                    q[3] + h * spin[3],
                ])
            };
            if ctx.physical.is_none() {
                // (The physical model's inertias come from its constants.)
                work.w_q[e] = ctx.quaternion_mass_scale / (edge.rest_length * edge.rest_length);
            }
            work.frame_keep[e] = 1.0;
            if let Some(hold) = &ctx.hold {
                let f = s.groomed_fraction;
                let k = hold.at(0.5 * (f[e] + f[e + 1]));
                if k > 0.0 {
                    let target = math::qmul(ctx.root_transform.rotation, s.groomed_frames[e]);
                    let keep;
                    (work.q[e], keep) = fold_frame(work.q[e], target, k, dt);
                    work.frame_keep[e] = keep;
                    work.w_q[e] *= keep;
                }
            }
        }
        if ctx.physical.is_none() {
            work.stretch[e] =
                StretchCoefficients::new(work.w[e], work.w[e + 1], work.w_q[e], edge.rest_length);
        }
    }
    if ctx.physical.is_none() {
        // The paper model's sweep coefficients.
        for j in 1..m {
            work.bend[j] =
                bend_coefficients(work.w_q[j - 1], work.w_q[j], s.joints[j].stiffness_prime);
        }
    }
}

/// The blower's velocity change (19) at each vertex of the strand, into
/// `work.blower`, and its drying (21), which re-forms hydrogen bonds (held
/// vertices dry too), into `work.db`: eight vertices at a time in lanes
/// where the CPU has AVX2 (`blow_eights`: the same bits), the rest one by
/// one.
#[inline(always)]
fn blow(ctx: &Context<'_>, blower: &Blower, s: &StrandMut<'_>, work: &mut Work) {
    let n = s.positions.len();
    let m = n - 1;
    #[allow(unused_mut)]
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if ctx.instructions.avx2() {
        // SAFETY: the CPU has AVX2 (`Instructions::of_this_cpu`).
        done = unsafe { blow_eights(blower, s.positions, ctx.dt, work) };
    }
    for i in done..n {
        let x = s.positions[i];
        let edge = if i < m {
            math::sub(s.positions[i + 1], x)
        } else {
            math::sub(x, s.positions[i - 1])
        };
        let dv = blower_dv(blower, x, edge, ctx.dt);
        work.blower[i] = dv;
        work.db[i][0] = blower.hydrogen_rate * math::length(dv);
    }
}

/// `blow` of the strand's vertices in runs of eight, one per lane; returns
/// the vertices done (the rest are fewer than eight).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn blow_eights(blower: &Blower, positions: &[V3], dt: f32, work: &mut Work) -> usize {
    use std::arch::x86_64::*;
    let n = positions.len();
    let m = n - 1;
    // A vertex as four floats; the fourth (the next vertex's x, or 0 at
    // the strand's end) is not used.
    let load = |i: usize| {
        if i + 1 < n {
            // SAFETY: reads vertex i and the first float of vertex i + 1
            // (`[V3]` is contiguous).
            unsafe { _mm_loadu_ps(positions[i].as_ptr()) }
        } else {
            let p = positions[i];
            _mm_setr_ps(p[0], p[1], p[2], 0.0)
        }
    };
    let rate = _mm256_set1_ps(blower.hydrogen_rate);
    let mut start = 0;
    while start + 8 <= n {
        let [x, y, z, _] = eight_to_lanes(std::array::from_fn(|l| load(start + l)));
        let [nx, ny, nz, _] = eight_to_lanes(std::array::from_fn(|l| load((start + l + 1).min(m))));
        let mut edge = [
            _mm256_sub_ps(nx, x),
            _mm256_sub_ps(ny, y),
            _mm256_sub_ps(nz, z),
        ];
        if start + 8 == n {
            // The tip's edge is the last one, `p[m] - p[m - 1]`: lane 6's.
            let last = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 6);
            edge = edge.map(|e| _mm256_permutevar8x32_ps(e, last));
        }
        let dv = blower_dv_eight(blower, [x, y, z], edge, dt);
        // `hydrogen_rate * length(dv)`.
        let [dx, dy, dz] = dv;
        let squared = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
            _mm256_mul_ps(dz, dz),
        );
        let drying = _mm256_mul_ps(rate, _mm256_sqrt_ps(squared));
        for (l, v) in lanes_to_eight([dx, dy, dz, drying]).into_iter().enumerate() {
            let mut four = [0.0f32; 4];
            // SAFETY: stores the four floats of `four`.
            unsafe { _mm_storeu_ps(four.as_mut_ptr(), v) };
            work.blower[start + l] = [four[0], four[1], four[2]];
            work.db[start + l][0] = four[3];
        }
        start += 8;
    }
    start
}
