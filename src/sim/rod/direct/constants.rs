//! The physical model's constants of the direct solve (METHOD H): masses
//! from the density and the fibre's cross-section, the frames' inertias and
//! the bend/twist and stretch/shear compliances from the moduli, in lanes.

use super::algebra::gather;
use super::{Constants, Direct, DirectInput};
use crate::sim::rod::real::Real;

/// The frames' tilt inertia is at least that of a segment this speed
/// times `dt` long (m/s), a numerical rotary inertia that vanishes as `dt`
/// falls. A frame of a fine edge is so light (`m l^2 / 12`) that the
/// Newton step, which has no geometric stiffness, turned it far past its
/// edge when both ends of a near-straight strand were held (a perm rod
/// holding the tip, the scalp the root): 5 mm edges of a 15 cm strand
/// on a 1 cm rod blew up at the second step at dt 1/360 (edges 25,000 %
/// long; at dt 1/1000, or with 1 cm edges, they held), and a strand pinned
/// 0.1 um off its length did too. The blow-up needs the frame inertia ~5x
/// (5 mm edges), ~10x (4 mm), ~30x (3 mm) at 1/360, growing as `dt^2`; a
/// floor of 3 m/s failed at 3 mm edges, 4 m/s held 3-5 mm edges at 1/360
/// and 1/120; 6 m/s keeps a margin. It changes no static shape (frames
/// carry no load) and at dt 1/1000 (the frequency test) only edges under
/// 6 mm get heavier frames: the 5 cm cantilever's first mode moves by
/// `(k L)^2 / 24`, about 0.1 %.
pub(in crate::sim) const FRAME_INERTIA_SPEED: f64 = 6.0;

/// The floor of the midpoint step's half step (rod/midpoint.rs), m/s of
/// the half step's `dt`: 1.5 m/s of the whole step's. The floor's
/// numerical rotary inertia lowers the frequencies at a long `dt`: the
/// released 5 cm hair (16 edges) swung at 7.01 Hz at dt 1/120 with 6 m/s
/// of the half step's `dt`, 7.25 Hz with 3 (7.35 Hz asked, 2 % allowed).
/// The blow-ups the larger floor prevents came from strands held at both
/// ends and from fine edges, which take backward Euler's step
/// (`takes_midpoint`).
pub(in crate::sim) const MIDPOINT_FRAME_INERTIA_SPEED: f64 = 3.0;

/// The mass of an edge, kg: a cylinder of the mean radius of its ends.
#[inline(always)]
pub(in crate::sim) fn segment_mass<T: Real>(density: T, r0: T, r1: T, length: T) -> T {
    let r = T::splat(0.5) * (r0 + r1);
    density * T::splat(std::f64::consts::PI) * r * r * length
}

/// Edge `e`'s bend and twist flexibility `l / (4 EI)`, `l / (4 GJ)` per
/// unit of the Darboux vector (half-angles: a quarter) with the cuticle
/// factor `factor` of its ends; see `bend_flexibility` (rod/shape_memory.rs) for how
/// they make the joints' consistent flexibility.
#[inline(always)]
pub(in crate::sim) fn edge_flexibility<T: Real>(
    material: (T, T),
    length: T,
    r0: T,
    r1: T,
    factor: T,
) -> (T, T) {
    let (youngs, shear) = material;
    let r = T::splat(0.5) * (r0 + r1);
    let r2 = r * r;
    // A quarter by a multiplication: the same bits as dividing by 4 (a
    // power of two), without a division.
    let inertia = T::splat(std::f64::consts::PI) * (r2 * r2) * T::splat(0.25);
    let four = T::splat(4.0);
    let bend = length / (four * youngs * factor * inertia);
    let twist = length / (four * shear * factor * T::splat(2.0) * inertia);
    (bend, twist)
}

/// What `begin` finds of one edge before the blocks' constants.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct EdgeLane<T> {
    pub(super) l: T,
    /// The factor of the frame's inverse inertia (`DirectInput::frame_free`).
    pub(super) keep: T,
    /// Half the edge's mass (each end vertex gets it).
    pub(super) half_mass: T,
    /// The frame's inverse inertia across and about the tangent.
    pub(super) wq: T,
    pub(super) w_twist: T,
    /// Stretch/shear compliances `l / (G A)`, `l / (E A)`.
    pub(super) shear: T,
    pub(super) stretch: T,
    /// A third of the edge's own bend/twist flexibility
    /// (`edge_flexibility`): what it adds to each end joint.
    pub(super) bend_third: T,
    pub(super) twist_third: T,
}

impl<T: Real> Direct<T> {
    /// The physical model's masses, inertias and compliances (METHOD H)
    /// from the density, moduli, fibre radii and rest lengths, in the
    /// lanes: vertices lump half of each adjacent edge's mass `rho A l`;
    /// frames get the inertia of their segment about its centre, `m (l^2 /
    /// 12 + r^2 / 4)` across the tangent (a rigid segment's, a choice the
    /// papers leave open; with a floor, `FRAME_INERTIA_SPEED`) and the
    /// fibre's own `m r^2 / 2` about it (twist). Stiffness falls with the
    /// cuticle from root to tip (13)-(14): an edge takes the factor of its
    /// first joint. The inverse masses and inertias are rounded to `f32`,
    /// the precision the strand state keeps.
    #[inline(always)]
    pub(super) fn physical_constants(&mut self, strands: &[DirectInput<'_>]) {
        let n = strands[0].p.len();
        let m = n - 1;
        let (zero, one, half) = (T::splat(0.0), T::splat(1.0), T::splat(0.5));
        let pi = T::splat(std::f64::consts::PI);
        let youngs: T = gather(strands, |s| s.material.youngs_modulus);
        let shear: T = gather(strands, |s| s.material.shear_modulus);
        let density: T = gather(strands, |s| s.material.density);
        let arm_floor: T = gather(strands, |s| s.frame_inertia_speed * s.dt as f64);
        // Per vertex, its radius, its joint's cuticle factor and whether
        // it is free, and per edge its length, each read once, strand by
        // strand (as `begin`).
        self.vertices.clear();
        self.vertices.resize(n, [zero; 3]);
        self.edges.clear();
        self.edges.resize(m, EdgeLane::default());
        for (lane, s) in strands.iter().enumerate() {
            let per_vertex = s.radii.iter().zip(s.joints).zip(s.free);
            for (o, ((&radius, joint), &free)) in self.vertices.iter_mut().zip(per_vertex) {
                o[0].set_lane(lane, radius as f64);
                o[1].set_lane(lane, joint.cuticle as f64);
                o[2].set_lane(lane, free as f64);
            }
            for ((o, &l), &keep) in self.edges.iter_mut().zip(s.l).zip(s.frame_free) {
                o.l.set_lane(lane, l as f64);
                o.keep.set_lane(lane, keep as f64);
            }
        }
        let vertices = &self.vertices;
        // The cuticle factor of joint slot `i` for an edge (the root edge
        // takes joint 1's) and for the flexibility (the root is healthy;
        // the tip has no joint of its own and takes the last one's).
        let edge_cuticle = |k: usize| -> T {
            if m >= 2 {
                vertices[k.clamp(1, m - 1)][1]
            } else {
                one
            }
        };
        let cuticle_at = |i: usize| -> T {
            if i == 0 || m < 2 {
                one
            } else {
                vertices[i.min(m - 1)][1]
            }
        };
        for k in 0..m {
            let l = self.edges[k].l;
            let keep = self.edges[k].keep;
            let (r0, r1) = (vertices[k][0], vertices[k + 1][0]);
            let r = half * (r0 + r1);
            let area = pi * r * r;
            let segment = segment_mass(density, r0, r1, l);
            let arm = T::gt_select(l, arm_floor, l, arm_floor);
            let cuticle = edge_cuticle(k);
            let factor = half * (cuticle_at(k) + cuticle_at(k + 1));
            let (bend, twist) = edge_flexibility((youngs, shear), l, r0, r1, factor);
            let third = T::splat(3.0);
            self.edges[k] = EdgeLane {
                l,
                keep,
                half_mass: half * segment,
                // (`* 0.25`, `* 0.5`: the bits of `/ 4`, `/ 2`.)
                // (`* keep`: the same bits without a hold, `keep` = 1.)
                wq: (one / (segment * (arm * arm / T::splat(12.0) + r * r * T::splat(0.25))))
                    .to_f32_precision()
                    * keep,
                w_twist: (one / (segment * r * r * half)).to_f32_precision() * keep,
                shear: l / (shear * cuticle * area),
                stretch: l / (youngs * cuticle * area),
                bend_third: bend / third,
                twist_third: twist / third,
            };
        }
        // A free vertex's inverse mass: half of each adjacent edge's mass.
        self.w.clear();
        let edges = &self.edges;
        for i in 0..n {
            let free = vertices[i][2];
            let mass = match (i.checked_sub(1), edges.get(i)) {
                (Some(before), Some(after)) => edges[before].half_mass + after.half_mass,
                (None, Some(after)) => zero + after.half_mass,
                (Some(before), None) => edges[before].half_mass,
                (None, None) => one,
            };
            // (`* free`: the same bits for a free vertex, `free` = 1.)
            self.w.push(T::gt_select(
                free,
                zero,
                (one / mass).to_f32_precision() * free,
                free,
            ));
        }
        let inv_dt2: T = gather(strands, |s| 1.0 / (s.dt as f64 * s.dt as f64));
        let w = &self.w;
        self.constants.clear();
        for k in 0..m {
            let e = &edges[k];
            // The consistent flexibility: edge k - 1 and edge k each add a
            // third of theirs to joint k, a sixth between k and k + 1.
            let (bend_before, twist_before) = match k.checked_sub(1) {
                Some(before) => (
                    zero + edges[before].bend_third,
                    zero + edges[before].twist_third,
                ),
                None => (zero, zero),
            };
            // A sixth between joints k and k + 1: half of the third, exactly
            // (halving is exact, so `(x / 3) / 2` is `x / 6` to the bit).
            let (bend_next, twist_next) = if k + 1 < m {
                (e.bend_third * half, e.twist_third * half)
            } else {
                (zero, zero)
            };
            // Frame k - 1's inertia where it is free.
            let (wq_before, w_twist_before) = match k.checked_sub(1) {
                Some(before) => {
                    let b = &edges[before];
                    (
                        T::gt_select(b.wq, zero, b.wq, zero),
                        T::gt_select(b.wq, zero, b.w_twist, zero),
                    )
                }
                None => (zero, zero),
            };
            self.constants.push(Constants {
                l: e.l,
                w_pair: w[k] + w[k + 1],
                w_next: w[k + 1],
                wq: e.wq,
                dw: e.w_twist - e.wq,
                wq_before,
                dw_before: w_twist_before - wq_before,
                a_sh: e.shear * inv_dt2,
                a_st: e.stretch * inv_dt2,
                a_b: (bend_before + e.bend_third) * inv_dt2,
                a_t: (twist_before + e.twist_third) * inv_dt2,
                a_b_next: bend_next * inv_dt2,
                a_t_next: twist_next * inv_dt2,
                rest: [zero; 3],
                rest_w: zero,
            });
        }
        for (lane, s) in strands.iter().enumerate() {
            for (c, r) in self.constants.iter_mut().zip(s.rest) {
                for i in 0..3 {
                    c.rest[i].set_lane(lane, r[i] as f64);
                }
            }
        }
        // The rest's real part `sqrt(max(1 - |rest|^2, 0))`, in the lanes.
        for c in &mut self.constants {
            let r = c.rest;
            let real = one - (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
            c.rest_w = T::gt_select(real, zero, real, zero).sqrt();
        }
    }
}
