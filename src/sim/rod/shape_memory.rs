//! The step's "bonds" phases: before the solve, the bond-rate changes and
//! the rest shape from the bonds (15), strand by strand or eight strands in
//! lanes; after it, the bond update (17) with the solved shape. Also the
//! joints' bend/twist flexibility the solves use.

use super::bonds::{driven_rates, reform, rest_darboux, still_rates};
#[cfg(target_arch = "x86_64")]
use super::bonds::{rest_eight, RatesIn};
use super::direct::{edge_flexibility, EdgeCompliance};
use super::real::WIDE;
use crate::sim::instructions::in_widest;
use crate::sim::math;
use crate::sim::state::JointState;
use crate::sim::work::{Context, StrandMut, Work};

/// (iii) of the step, the "bonds" phase: bond-rate changes and the rest
/// shape from the bonds (15), after `predict` (which fills the old frames
/// and, with a blower, the drying rates).
pub(in crate::sim) fn rest_shape(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    in_widest!(ctx.instructions, fn(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
        rest_shape_strand(ctx, s, work)
    })
}

#[inline(always)]
fn rest_shape_strand(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    let m = s.positions.len() - 1;
    let mut unchanged = true;
    for j in 1..m {
        let joint = &s.joints[j];
        let omega = math::darboux(work.q_old[j - 1], work.q_old[j]);
        let omega_w = math::darboux_real(work.q_old[j - 1], work.q_old[j]);
        let rates = if ctx.bonds_still {
            // `driven_rates` with zero drive and extra: the same values
            // (`b + 0` differs from `b` only for -0, which the clamp and `1
            // - b` of the rest shape treat as 0).
            still_rates(&joint.rates)
        } else {
            driven_rates(&joint.rates, work.db[j][0], &ctx.drive)
        };
        unchanged &= rates.unchanged;
        work.db[j] = rates.db;
        work.rest[j] = rest_darboux(
            omega,
            omega_w,
            &rates.effective,
            &joint.memories,
            &ctx.influences,
        );
    }
    work.bonds_unchanged = unchanged;
}

/// `rest_shape` of eight strands of one vertex count, joint by joint with
/// a strand per lane (`rest_eight`: the same bits). Returns false, doing
/// nothing, where it does not apply: the caller then takes `rest_shape`
/// strand by strand.
pub(in crate::sim) fn rest_shapes_in_lanes(
    ctx: &Context<'_>,
    strands: &[StrandMut<'_>],
    works: &mut [Work],
) -> bool {
    #[cfg(target_arch = "x86_64")]
    if ctx.instructions.avx512() && strands.len() == WIDE && works.len() >= WIDE {
        // SAFETY: the CPU has AVX-512F (`Instructions::of_this_cpu`), and
        // with it AVX2.
        unsafe { rest_shapes_avx512(ctx, strands, works) };
        return true;
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (ctx, strands, works);
    false
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn rest_shapes_avx512(ctx: &Context<'_>, strands: &[StrandMut<'_>], works: &mut [Work]) {
    let m = strands[0].positions.len() - 1;
    let mut unchanged = u32::MAX;
    for j in 1..m {
        let rule = if ctx.bonds_still {
            RatesIn::Still
        } else {
            RatesIn::Driven {
                drive: &ctx.drive,
                // The blower's drying, from `predict`.
                extra: std::array::from_fn(|l| works[l].db[j][0]),
            }
        };
        let (rest, db, same) = rest_eight(
            std::array::from_fn(|l| (&works[l].q_old[j - 1], &works[l].q_old[j])),
            std::array::from_fn(|l| &strands[l].joints[j].rates),
            std::array::from_fn(|l| &strands[l].joints[j].memories),
            &ctx.influences,
            rule,
        );
        unchanged &= same;
        for (l, work) in works.iter_mut().take(WIDE).enumerate() {
            work.rest[j] = rest[l];
            work.db[j] = db[l];
        }
    }
    for (l, work) in works.iter_mut().take(WIDE).enumerate() {
        work.bonds_unchanged = unchanged >> l & 1 == 1;
    }
}

/// The bend/twist compliances of the joints: the consistent flexibility of
/// a moment that varies linearly along each edge (the mixed, Hellinger-
/// Reissner beam element; the XPBD multipliers are the joints' moments).
///
/// The Darboux vector of joint `j` is half the turn between edges `j - 1`
/// and `j`, and that turn is the curvature integrated against the hat
/// function of vertex `j`: with the moment linear on each edge, edge `e`
/// (length `l`, stiffness `EI`) adds `l / (3 EI)` to each end joint's
/// flexibility and `l / (6 EI)` between them (times 1/4 for half-angles).
/// Lumping it all on the diagonal (`l_j / EI` with the Voronoi length)
/// charged the clamp's joint with the moment at the root over its half
/// edge, although the moment falls along that edge: first-order wrong at
/// the clamp, the heavy cantilever drooped `+(h/L)^2` too far (+2.8 % for
/// 8 edges on 24 cm). The tip has no joint (free end, no moment).
pub(in crate::sim) fn bend_flexibility(
    youngs_modulus: f64,
    shear_modulus: f64,
    lengths: &[f32],
    radii: &[f32],
    joints: &[JointState],
    out: &mut [EdgeCompliance],
) {
    let m = lengths.len();
    // The cuticle factor at vertex `i` (the root is healthy; the tip has
    // no joint of its own and takes the last one's).
    let cuticle = |i: usize| -> f64 {
        if i == 0 || m < 2 {
            1.0
        } else {
            joints[i.min(m - 1)].cuticle as f64
        }
    };
    for c in out.iter_mut() {
        (c.bend, c.twist, c.bend_next, c.twist_next) = (0.0, 0.0, 0.0, 0.0);
    }
    for e in 0..m {
        let factor = 0.5 * (cuticle(e) + cuticle(e + 1));
        let (bend, twist) = edge_flexibility(
            (youngs_modulus, shear_modulus),
            lengths[e] as f64,
            radii[e] as f64,
            radii[e + 1] as f64,
            factor,
        );
        let c = &mut out[e];
        c.bend += bend / 3.0;
        c.twist += twist / 3.0;
        if e + 1 < m {
            c.bend_next = bend / 6.0;
            c.twist_next = twist / 6.0;
            let next = &mut out[e + 1];
            next.bend += bend / 3.0;
            next.twist += twist / 3.0;
        }
    }
}

/// (v) of the step, the end of the "bonds" phase: the bond update (17)
/// with the shape after the projection.
pub(in crate::sim) fn update_bonds(ctx: &Context<'_>, s: &mut StrandMut<'_>, work: &Work) {
    in_widest!(ctx.instructions, fn(s: &mut StrandMut<'_>, work: &Work) {
        update_bonds_strand(s, work)
    })
}

#[inline(always)]
fn update_bonds_strand(s: &mut StrandMut<'_>, work: &Work) {
    if work.bonds_unchanged {
        return;
    }
    let m = s.positions.len() - 1;
    for j in 1..m {
        let db = work.db[j];
        let joint = &mut s.joints[j];
        if db.iter().any(|d| *d > 0.0) {
            let omega = math::darboux(work.q[j - 1], work.q[j]);
            let omega_w = math::darboux_real(work.q[j - 1], work.q[j]);
            for ((memory, rate), d) in joint.memories.iter_mut().zip(&joint.rates).zip(&db) {
                if *d > 0.0 {
                    *memory = reform(*memory, *rate, *d, omega, omega_w);
                }
            }
        }
        let rates: [f32; 4] = std::array::from_fn(|k| (joint.rates[k] + db[k]).clamp(0.0, 1.0));
        // Written only when a bit changes: in most steps no bond does, and
        // the joint's memory then is not written back (a quarter of the
        // step's memory traffic).
        if rates.map(f32::to_bits) != joint.rates.map(f32::to_bits) {
            joint.rates = rates;
        }
    }
}
