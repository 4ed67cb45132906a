//! The physical model's constraint solve: compliant (XPBD) stretch/shear
//! and bend/twist of one strand solved exactly per iteration by a direct,
//! linear-time block-tridiagonal solve (after Deul, Kugelstadt, Weiler,
//! Bender 2018, "Direct Position-Based Solver for Stiff Rods", here on the
//! vertex-and-frame discretisation of 000 §4).
//!
//! Unknowns: the free vertices' positions and the free frames' rotations
//! (`dtheta`, world axis-angle). Constraints along the strand, grouped per
//! edge `k` into one block of six rows: the bend/twist of joint `k`
//! (between frames `k - 1` and `k`; for `k = 0` between the fixed root
//! frame and the first edge's frame, the clamp) and the stretch/shear of
//! edge `k`. The bend/twist flexibility is tridiagonal over the joints (the
//! consistent flexibility of step.rs `bend_flexibility`), which keeps the
//! blocks' coupling to neighbours. Each block shares unknowns only with its
//! neighbours, so `J W J^T + alpha/dt^2` is block-tridiagonal and one
//! Newton-XPBD iteration costs O(edges). Hand-written rather than a sparse
//! crate: the 6x6 blocks are fixed-size and sparse in a known pattern
//! (written out below), and the solve must not allocate per step; it runs
//! in f64 because hair is very stiff for its mass (the system's entries
//! span ~1e-3 to ~1e12).
//!
//! The solve is generic over [`Real`]: `f64` steps one strand, `f64x4`
//! four strands in SIMD lanes with the same operations in the same order,
//! so a strand's result does not depend on its group.

// Dense 3x3 and 6x6 algebra reads as the formulas with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::real::Real;
use crate::sim::instructions::{in_widest, Instructions};
use crate::sim::math::{Quat, V3};
use crate::sim::state::JointState;

/// The largest frame rotation one iteration applies, radians: a trust
/// region for the linearisation, so a frame whose target jumps (a perm
/// rod's moving targets) gets there over several iterations instead of
/// overshooting. The clamp applies to the frames only (the positions take
/// the full Newton step), so a frame it holds back lags its edge, and the
/// stiff stretch/shear then pulls the edge after the frame. Hair whipping
/// onto the head turns its tip edges by about a radian in a step: at 0.1
/// the frames needed five steps to catch up while the edges, their
/// touching ends held along the contact normal, stretched (24 cm hair 15 %
/// against the ball head, 11 % against the mesh head at the default two
/// iterations; 0.04 % and 0.05 % at 0.5, the same as unclamped). 0.1 was
/// chosen for the perm before the frames' inertia floor
/// (`FRAME_INERTIA_SPEED` in step.rs); with the floor the perm keeps 0.67
/// of its rod and 1.20 of its 1.88 turns at 0.1, 0.5 and 1.0 alike.
const MAX_TURN: f64 = 0.5;

/// How much of a touching vertex's inverse mass along the contact normal
/// the solve removes: it is 100 times heavier across the surface than
/// along it. A full lock (1) makes the stretch block of an edge lying on a
/// surface singular up to its tiny compliance, and the pivots lost to
/// round-off blew short pressed strands up; at 0.99 the edges of the
/// bed-hair press stay within 0.001 % of rest and the vertex moves across
/// the surface by 1 % of a free vertex's correction (the projection after
/// the solve takes that back).
const CONTACT_LOCK: f64 = 0.99;

type M3<T> = [[T; 3]; 3];
type D3<T> = [T; 3];
type D6<T> = [T; 6];

/// The bend/twist compliance of one joint (the sag-free start's; the
/// solve finds its own in `physical_constants`, the same values).
#[derive(Debug, Clone, Copy, Default)]
pub struct EdgeCompliance {
    /// Bend/twist compliance of the joint at the edge's first vertex on the
    /// Darboux vector (the diagonal of the consistent flexibility, see
    /// `step.rs` `bend_flexibility`), 1/(N m).
    pub bend: f64,
    pub twist: f64,
    /// The flexibility coupling this joint's Darboux vector with the next
    /// joint's (the off-diagonal of the consistent flexibility), 1/(N m).
    pub bend_next: f64,
    pub twist_next: f64,
}

/// The physical model's material (METHOD H), the same for every strand.
#[derive(Debug, Clone, Copy)]
pub struct RodMaterial {
    /// Young's and shear moduli of healthy hair, Pa.
    pub youngs_modulus: f64,
    pub shear_modulus: f64,
    /// kg/m^3.
    pub density: f64,
}

/// What one strand's solve reads.
pub struct DirectInput<'a> {
    /// Predicted positions (`n`) and frames (`n - 1`).
    pub p: &'a [V3],
    pub q: &'a [Quat],
    /// Per vertex, 0 where it is pinned or driven, else the factor of its
    /// inverse mass: 1 for a free vertex (the solve weighs it by its mass),
    /// `1 / (1 + k dt^2)` for one the hold pulls (hold.rs).
    pub free: &'a [f32],
    /// Per edge, the factor of its frame's inverse inertia: 1, or `1 / (1 +
    /// k dt^2)` for a frame the hold pulls (hold.rs).
    pub frame_free: &'a [f32],
    /// Per vertex, the unit normal of a contact the solve must hardly move
    /// the vertex along (zero: no contact), or empty when nothing touches.
    /// The contact is folded into the vertex's inverse mass, `w (I -
    /// CONTACT_LOCK n n^T)`: the strand keeps its length by sliding along
    /// the surface instead of being pushed into it or having its edges
    /// squeezed by a projection after the solve.
    pub contact_normals: &'a [V3],
    /// Rest lengths per edge slot, fibre radii per vertex, metres.
    pub l: &'a [f32],
    pub radii: &'a [f32],
    /// Per joint slot, the share of the healthy moduli the cuticle
    /// gradient (13)-(14) leaves.
    pub joints: &'a [JointState],
    pub material: RodMaterial,
    /// Rest Darboux vectors per joint slot (canonical, real part >= 0).
    pub rest: &'a [V3],
    /// The fixed frame the first edge is clamped to (the scalp's).
    pub root_frame: Quat,
    pub dt: f32,
}

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
const FRAME_INERTIA_SPEED: f64 = 6.0;

/// The mass of an edge, kg: a cylinder of the mean radius of its ends.
#[inline(always)]
pub(in crate::sim) fn segment_mass<T: Real>(density: T, r0: T, r1: T, length: T) -> T {
    let r = T::splat(0.5) * (r0 + r1);
    density * T::splat(std::f64::consts::PI) * r * r * length
}

/// Edge `e`'s bend and twist flexibility `l / (4 EI)`, `l / (4 GJ)` per
/// unit of the Darboux vector (half-angles: a quarter) with the cuticle
/// factor `factor` of its ends; see `step.rs` `bend_flexibility` for how
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
struct EdgeLane<T> {
    l: T,
    /// The factor of the frame's inverse inertia (`DirectInput::frame_free`).
    keep: T,
    /// Half the edge's mass (each end vertex gets it).
    half_mass: T,
    /// The frame's inverse inertia across and about the tangent.
    wq: T,
    w_twist: T,
    /// Stretch/shear compliances `l / (G A)`, `l / (E A)`.
    shear: T,
    stretch: T,
    /// A third of the edge's own bend/twist flexibility
    /// (`edge_flexibility`): what it adds to each end joint.
    bend_third: T,
    twist_third: T,
}

/// The constants of block `k` for a step.
#[derive(Debug, Clone, Copy, Default)]
struct Constants<T> {
    l: T,
    /// `w_k + w_{k+1}` (the edge's vertices) and `w_{k+1}` (the vertex it
    /// shares with the next edge).
    w_pair: T,
    w_next: T,
    /// Frame `k`'s inverse inertia across the tangent and `w_twist - w_q`.
    wq: T,
    dw: T,
    /// The same of frame `k - 1` (0 for the root joint or a fixed frame).
    wq_before: T,
    dw_before: T,
    /// Compliances over `dt^2`: shear, stretch, bend, twist.
    a_sh: T,
    a_st: T,
    a_b: T,
    a_t: T,
    /// The bend and twist flexibility coupling joint `k` with joint
    /// `k + 1` (the consistent flexibility's off-diagonal), over `dt^2`.
    a_b_next: T,
    a_t_next: T,
    rest: D3<T>,
    rest_w: T,
}

/// The part below the diagonal of a unit lower triangular 6x6 matrix,
/// packed by rows (half the memory of the full block in the sweep).
#[derive(Debug, Clone, Copy, Default)]
struct Unit<T>([T; 15]);

impl<T> std::ops::Index<(usize, usize)> for Unit<T> {
    type Output = T;
    #[inline(always)]
    fn index(&self, (i, j): (usize, usize)) -> &T {
        debug_assert!(j < i);
        &self.0[i * (i - 1) / 2 + j]
    }
}

impl<T> std::ops::IndexMut<(usize, usize)> for Unit<T> {
    #[inline(always)]
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut T {
        debug_assert!(j < i);
        &mut self.0[i * (i - 1) / 2 + j]
    }
}

/// Block `k`'s linearisation and factor, rebuilt every iteration.
#[derive(Debug, Clone, Copy, Default)]
struct Factor<T> {
    d3: D3<T>,
    /// The bend Jacobian on frame `k` and `G d3`.
    g: M3<T>,
    g_d3: D3<T>,
    /// `L D L^T` factor of the eliminated diagonal block: `L` (unit lower,
    /// below the diagonal) and `D^-1`.
    unit: Unit<T>,
    inv: D6<T>,
    /// `D^-1 Z` with `Z = L^-1 U` the coupling to block `k + 1`, by its
    /// non-zero 3x3 parts: top left, bottom left, bottom right (lower
    /// triangular); the top right is zero.
    z_tl: M3<T>,
    z_bl: M3<T>,
    z_br: M3<T>,
    /// `D^-1 L^-1 b'` in the forward sweep, the solution `dlambda` after it.
    t: D6<T>,
}

/// Scratch of the direct solve of `T::WIDTH` strands of one vertex count
/// (reused across steps).
#[derive(Debug, Default)]
pub struct Direct<T> {
    w: Vec<T>,
    /// Per vertex, its contact normal (zero: none).
    contact: Vec<D3<T>>,
    /// Whether any lane has a contact: without one the solve takes the
    /// contact-free path, which skips the contact terms (exact zeros there)
    /// and the coupling that only a contact fills, with the same bits.
    touching: bool,
    /// Per lane, 1 where an iteration may move the strand, 0 where it must
    /// leave it as it is ([`Direct::set_active`]).
    active: T,
    p: Vec<D3<T>>,
    q: Vec<[T; 4]>,
    lambda: Vec<D6<T>>,
    constants: Vec<Constants<T>>,
    factors: Vec<Factor<T>>,
    root: [T; 4],
    /// `begin`'s per-edge scratch, and per vertex its radius, cuticle
    /// factor and whether it is free.
    edges: Vec<EdgeLane<T>>,
    vertices: Vec<[T; 3]>,
}

impl<T: Real> Direct<T> {
    /// Room for strands of `n` vertices, so that `begin` allocates nothing
    /// for them. A working copy that has only served the eight-wide solve
    /// has never begun its own; without this, the first step that sends it
    /// a strand on its own (a group with a frozen strand) allocated then.
    pub fn reserve(&mut self, n: usize) {
        fn room<U>(v: &mut Vec<U>, n: usize) {
            v.reserve(n.saturating_sub(v.len()));
        }
        room(&mut self.w, n);
        room(&mut self.contact, n);
        room(&mut self.p, n);
        room(&mut self.q, n);
        room(&mut self.lambda, n);
        room(&mut self.constants, n);
        room(&mut self.factors, n);
        room(&mut self.edges, n);
        room(&mut self.vertices, n);
    }

    /// Loads the predicted positions and frames and the constants of
    /// `T::WIDTH` strands of one vertex count, and resets the multipliers.
    #[inline(always)]
    pub fn begin(&mut self, strands: &[DirectInput<'_>]) {
        debug_assert_eq!(strands.len(), T::WIDTH);
        let n = strands[0].p.len();
        let m = n - 1;
        // The factors are fully written by every iteration before being
        // read: resized only when the strand length changes.
        if self.factors.len() != m {
            self.factors.clear();
            self.factors.resize(m, Factor::default());
        }
        // Strand by strand into the lanes (a store per number), not lane
        // by lane: eight scalar stores read back at once as one vector
        // stall the load, and `begin` was a sixth of a step.
        let zero = T::splat(0.0);
        self.contact.clear();
        self.contact.resize(n, [zero; 3]);
        self.p.clear();
        self.p.resize(n, [zero; 3]);
        self.q.clear();
        self.q.resize(m, [zero; 4]);
        for (lane, s) in strands.iter().enumerate() {
            set_lane(&mut self.contact, lane, s.contact_normals);
            set_lane(&mut self.p, lane, s.p);
            for (o, v) in self.q.iter_mut().zip(s.q) {
                for c in 0..4 {
                    o[c].set_lane(lane, v[c] as f64);
                }
            }
        }
        self.touching = touches(&self.contact);
        self.active = T::splat(1.0);
        self.root = build(|c| gather(strands, |s| s.root_frame[c] as f64));
        self.lambda.clear();
        self.lambda.resize(m, [T::splat(0.0); 6]);
        self.physical_constants(strands);
    }

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
    fn physical_constants(&mut self, strands: &[DirectInput<'_>]) {
        let n = strands[0].p.len();
        let m = n - 1;
        let (zero, one, half) = (T::splat(0.0), T::splat(1.0), T::splat(0.5));
        let pi = T::splat(std::f64::consts::PI);
        let youngs: T = gather(strands, |s| s.material.youngs_modulus);
        let shear: T = gather(strands, |s| s.material.shear_modulus);
        let density: T = gather(strands, |s| s.material.density);
        let arm_floor: T = gather(strands, |s| FRAME_INERTIA_SPEED * s.dt as f64);
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

    /// Writes each lane's positions and frames back (f32) into
    /// `out[lane]`, reading each vector once.
    pub fn end(&self, out: &mut [(&mut [V3], &mut [Quat])]) {
        for (i, v) in self.p.iter().enumerate() {
            for (lane, (p, _)) in out.iter_mut().enumerate() {
                p[i] = build(|c| v[c].lane(lane) as f32);
            }
        }
        for (k, v) in self.q.iter().enumerate() {
            for (lane, (_, q)) in out.iter_mut().enumerate() {
                q[k] = build(|c| v[c].lane(lane) as f32);
            }
        }
    }

    /// Lane `lane`'s positions, moved by something else (collisions)
    /// between iterations.
    pub fn set_positions(&mut self, lane: usize, p: &[V3]) {
        set_lane(&mut self.p, lane, p);
    }

    /// Lane `lane`'s contact normals, found by a projection between
    /// iterations (zero: none).
    pub fn set_contact_normals(&mut self, lane: usize, normals: &[V3]) {
        set_lane(&mut self.contact, lane, normals);
        self.touching = touches(&self.contact);
    }

    /// Whether the next iterations move lane `lane`'s strand (a strand
    /// that needs no more iterations keeps its state, bit for bit, while
    /// the other lanes iterate).
    pub fn set_active(&mut self, lane: usize, active: bool) {
        let old = self.active;
        self.active = T::gather(|i| {
            if i == lane {
                f64::from(u8::from(active))
            } else {
                old.lane(i)
            }
        });
    }

    /// Per lane, 1 where the strand has not converged (an edge's
    /// stretch/shear residual `|p_{k+1} - p_k - l d3_k|` is above
    /// `tolerance` times its rest length), 0 where every edge is within it
    /// (or a value is not finite: the quarantine judges that strand). The
    /// residual the user sees as stretched edges and kinks, and what the
    /// first iteration leaves after an impact; the bend/twist residual of
    /// free hair is settled by the first iteration (the cantilever tests).
    #[inline(always)]
    pub fn unconverged(&self, tolerance: f64) -> T {
        let one = T::splat(1.0);
        let tolerance2 = T::splat(tolerance * tolerance);
        let mut out = T::splat(0.0);
        for (k, c) in self.constants.iter().enumerate() {
            let d3 = tangent(self.q[k]);
            let (p0, p1) = (self.p[k], self.p[k + 1]);
            let r: D3<T> = build(|i| p1[i] - p0[i] - c.l * d3[i]);
            let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            out = T::gt_select(r2, tolerance2 * (c.l * c.l), one, out);
        }
        out
    }

    pub fn positions_f32(&self, lane: usize, p: &mut [V3]) {
        for (o, v) in p.iter_mut().zip(&self.p) {
            *o = build(|c| v[c].lane(lane) as f32);
        }
    }

    /// One Newton-XPBD iteration: linearise every constraint at the current
    /// state, solve `(J W J^T + alpha~) dlambda = -(C + alpha~ lambda)`
    /// exactly, apply `dx = W J^T dlambda`.
    #[inline(always)]
    pub fn iterate(&mut self) {
        if self.touching {
            self.iterate_with::<true>();
        } else {
            self.iterate_with::<false>();
        }
    }

    /// `iterate`, with the contact terms (`CONTACT`) or without (no lane
    /// touches: the terms are exact zeros and skipping them keeps the bits).
    #[inline(always)]
    fn iterate_with<const CONTACT: bool>(&mut self) {
        self.forward::<CONTACT>();
        if let Some(solved) = self.backward::<CONTACT>() {
            let solved = T::gt_select(self.active, T::splat(0.0), solved, T::splat(0.0));
            if (0..T::WIDTH).all(|i| solved.lane(i) > 0.0) {
                // The usual case: every lane moves (the same values as
                // selecting them).
                self.apply(|new, _| new);
            } else {
                let zero = T::splat(0.0);
                self.apply(|new, old| T::gt_select(solved, zero, new, old));
            }
        }
    }

    /// Builds each block of the system and eliminates it at once (block
    /// Thomas algorithm with `L D L^T` factors, no square roots on the
    /// sequential path): `D'_k = D_k - Z_{k-1}^T D_{k-1}^-1 Z_{k-1}`, `b'_k
    /// = b_k - Z_{k-1}^T D_{k-1}^-1 L_{k-1}^-1 b'_{k-1}`, `Z_k = L_k^-1
    /// U_k`.
    #[inline(always)]
    fn forward<const CONTACT: bool>(&mut self) {
        let m = self.q.len();
        // Every entry of the lower triangle and of `b` is written for each
        // block (the blocks are built in place: as returned values the
        // eight-wide ones were copied through memcpy).
        let zero = T::splat(0.0);
        let mut d = [[zero; 6]; 6];
        let mut b = [zero; 6];
        for k in 0..m {
            let c = &self.constants[k];
            let q = self.q[k];
            let d3 = tangent(q);
            let before = if k >= 1 { self.q[k - 1] } else { self.root };
            let bend = bend_linearisation(before, q, c.rest, c.rest_w);
            let g = bend.g;
            let g_d3 = mul_av(&g, d3);
            self.diagonal_block::<CONTACT>(k, c, d3, &bend, g_d3, &mut d, &mut b);
            if k >= 1 {
                self.eliminate_previous::<CONTACT>(k, &g, bend.g_before, &mut d, &mut b);
            }
            let f = &mut self.factors[k];
            f.d3 = d3;
            f.g = g;
            f.g_d3 = g_d3;
            ldlt(&d, &mut f.unit, &mut f.inv);
            f.t = forward_substitute(&f.unit, &f.inv, b);
        }
    }

    /// Block `k`'s diagonal block (lower triangle) and right-hand side.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn diagonal_block<const CONTACT: bool>(
        &self,
        k: usize,
        c: &Constants<T>,
        d3: D3<T>,
        bend: &Bend<T>,
        g_d3: D3<T>,
        d: &mut [D6<T>; 6],
        b: &mut D6<T>,
    ) {
        let zero = T::splat(0.0);
        // Bend/bend: G (W_k + W_{k-1}) G^T with W = w_q I + (w_twist -
        // w_q) d3 d3^T, G G^T = A A^T (R1 is a rotation).
        let wq_sum = c.wq + c.wq_before;
        let gb = bend.g_before;
        for r in 0..3 {
            for col in 0..=r {
                d[r][col] = wq_sum * bend.gg[r][col]
                    + c.dw * g_d3[r] * g_d3[col]
                    + c.dw_before * gb[r] * gb[col];
            }
        }
        d[0][0] = d[0][0] + c.a_b;
        d[1][1] = d[1][1] + c.a_b;
        d[2][2] = d[2][2] + c.a_t;
        // Stretch/bend through frame k: G W_k (l [d3]x)^T = -w_q l G [d3]x,
        // whose row r is -w_q l (g_r x d3).
        let wql = c.wq * c.l;
        for r in 0..3 {
            let x = cross(bend.g[r], d3);
            for s in 0..3 {
                d[3 + s][r] = -(wql * x[s]);
            }
        }
        // Stretch/stretch: (w_k + w_{k+1}) I + w_q l^2 (I - d3 d3^T) +
        // alpha_shear (I - d3 d3^T) + alpha_stretch d3 d3^T.
        let wql2 = wql * c.l;
        let c1 = c.w_pair + wql2 + c.a_sh;
        let c2 = c.a_st - c.a_sh - wql2;
        for r in 0..3 {
            for col in 0..=r {
                d[3 + r][3 + col] = c2 * d3[r] * d3[col];
            }
            d[3 + r][3 + r] = d[3 + r][3 + r] + c1;
        }
        // Contacts: the vertices' inverse masses lose CONTACT_LOCK of
        // their part along the normals.
        if CONTACT {
            let lock = T::splat(CONTACT_LOCK);
            let (lw0, lw1) = (lock * self.w[k], lock * self.w[k + 1]);
            let (n0, n1) = (self.contact[k], self.contact[k + 1]);
            for r in 0..3 {
                for col in 0..=r {
                    d[3 + r][3 + col] =
                        d[3 + r][3 + col] - (lw0 * n0[r] * n0[col] + lw1 * n1[r] * n1[col]);
                }
            }
        }
        // Right-hand side -(C + alpha~ lambda).
        let lam = self.lambda[k];
        let alpha_b = [c.a_b, c.a_b, c.a_t];
        // The flexibility is tridiagonal over the joints: alpha~ lambda
        // takes the neighbours' multipliers too.
        let coupled_before = match k.checked_sub(1) {
            Some(before) => {
                let (cb, lb) = (&self.constants[before], &self.lambda[before]);
                [
                    cb.a_b_next * lb[0],
                    cb.a_b_next * lb[1],
                    cb.a_t_next * lb[2],
                ]
            }
            None => [zero; 3],
        };
        let coupled_next = match self.lambda.get(k + 1) {
            Some(ln) => [c.a_b_next * ln[0], c.a_b_next * ln[1], c.a_t_next * ln[2]],
            None => [zero; 3],
        };
        for r in 0..3 {
            let alpha_lambda = alpha_b[r] * lam[r] + (coupled_before[r] + coupled_next[r]);
            b[r] = -(bend.omega[r] - c.rest[r] + alpha_lambda);
        }
        let along = d3[0] * lam[3] + d3[1] * lam[4] + d3[2] * lam[5];
        let a_diff = c.a_st - c.a_sh;
        let (p0, p1) = (self.p[k], self.p[k + 1]);
        for r in 0..3 {
            let cs = p1[r] - p0[r] - c.l * d3[r];
            let al = c.a_sh * lam[3 + r] + a_diff * d3[r] * along;
            b[3 + r] = -(cs + al);
        }
    }

    /// The coupling `U` of block `k - 1` to block `k`, `Z = L^-1 U` with
    /// block `k - 1`'s factor, and its elimination from block `k`.
    #[inline(always)]
    fn eliminate_previous<const CONTACT: bool>(
        &mut self,
        k: usize,
        g: &M3<T>,
        g_before: D3<T>,
        d: &mut [D6<T>; 6],
        b: &mut D6<T>,
    ) {
        let zero = T::splat(0.0);
        let cp = &self.constants[k - 1];
        let fp = &mut self.factors[k - 1];
        // Bend k-1 / bend k through frame k-1: -G_{k-1} W_{k-1} G_k^T.
        let mut au = [[zero; 3]; 3];
        for r in 0..3 {
            for col in 0..3 {
                let gg = fp.g[r][0] * g[col][0] + fp.g[r][1] * g[col][1] + fp.g[r][2] * g[col][2];
                au[r][col] = -(cp.wq * gg + cp.dw * fp.g_d3[r] * g_before[col]);
            }
        }
        // ... plus the flexibility coupling joints k-1 and k.
        au[0][0] = au[0][0] + cp.a_b_next;
        au[1][1] = au[1][1] + cp.a_b_next;
        au[2][2] = au[2][2] + cp.a_t_next;
        // Stretch k-1 / bend k: -w_q l [d3]x G_k^T, column c = d3 x g_c.
        let mut bm = [[zero; 3]; 3];
        let wql = cp.wq * cp.l;
        for col in 0..3 {
            let x = cross(fp.d3, g[col]);
            for r in 0..3 {
                bm[r][col] = -(wql * x[r]);
            }
        }
        // Stretch k-1 / stretch k share vertex k: -w_k I (bottom right).
        let l = &fp.unit;
        let inv = fp.inv;
        let mut z_tl = [[zero; 3]; 3];
        let mut z_bl = [[zero; 3]; 3];
        let mut z_br = [[zero; 3]; 3];
        let nk = self.contact[k];
        let lock_w = T::splat(CONTACT_LOCK) * self.w[k];
        for col in 0..3 {
            for i in 0..3 {
                let mut s = au[i][col];
                for j in 0..i {
                    s = s - l[(i, j)] * z_tl[j][col];
                }
                z_tl[i][col] = s;
            }
            for i in 0..3 {
                let mut s = bm[i][col];
                for j in 0..3 {
                    s = s - l[(3 + i, j)] * z_tl[j][col];
                }
                for j in 0..i {
                    s = s - l[(3 + i, 3 + j)] * z_bl[j][col];
                }
                z_bl[i][col] = s;
            }
            // -M_k = -w_k (I - CONTACT_LOCK n n^T): diagonal without a
            // contact (then Z's bottom right stays lower triangular), full
            // with one.
            // Without a contact the part above the diagonal is exactly
            // zero (left so), and so are the terms of the part below that
            // read it: skipped.
            let first = if CONTACT { 0 } else { col };
            for i in first..3 {
                let mut s = if CONTACT {
                    lock_w * nk[i] * nk[col]
                } else {
                    zero
                };
                if i == col {
                    s = s - cp.w_next;
                }
                for j in first..i {
                    s = s - l[(3 + i, 3 + j)] * z_br[j][col];
                }
                z_br[i][col] = s;
            }
        }
        // D^-1 Z, kept in the factor (written in place: a copy of the
        // eight-wide matrices went through memcpy).
        for r in 0..3 {
            for c in 0..3 {
                fp.z_tl[r][c] = z_tl[r][c] * inv[r];
                fp.z_bl[r][c] = z_bl[r][c] * inv[3 + r];
                fp.z_br[r][c] = z_br[r][c] * inv[3 + r];
            }
        }
        let (s_tl, s_bl, s_br) = (&fp.z_tl, &fp.z_bl, &fp.z_br);
        // D -= Z^T D^-1 Z (lower triangle), b -= Z^T (D^-1 L^-1 b').
        for i in 0..3 {
            for j in 0..=i {
                let mut s = zero;
                for r in 0..3 {
                    s = s + z_tl[r][i] * s_tl[r][j];
                }
                for r in 0..3 {
                    s = s + z_bl[r][i] * s_bl[r][j];
                }
                d[i][j] = d[i][j] - s;
            }
            // Z's bottom right is lower triangular without a contact: the
            // terms of its zeros (exact zeros, the sum starts at +0) are
            // skipped.
            let below = if CONTACT { 0 } else { i };
            for j in 0..3 {
                let mut s = zero;
                for r in below..3 {
                    s = s + z_br[r][i] * s_bl[r][j];
                }
                d[3 + i][j] = d[3 + i][j] - s;
            }
            for j in 0..=i {
                let mut s = zero;
                for r in below..3 {
                    s = s + z_br[r][i] * s_br[r][j];
                }
                d[3 + i][3 + j] = d[3 + i][3 + j] - s;
            }
        }
        let t = fp.t;
        for i in 0..3 {
            let mut s = zero;
            for r in 0..3 {
                s = s + z_tl[r][i] * t[r];
            }
            for r in 0..3 {
                s = s + z_bl[r][i] * t[3 + r];
            }
            b[i] = b[i] - s;
            let mut s = zero;
            for r in (if CONTACT { 0 } else { i })..3 {
                s = s + z_br[r][i] * t[3 + r];
            }
            b[3 + i] = b[3 + i] - s;
        }
    }

    /// Back substitution `x_k = L^-T (D^-1 L^-1 b'_k - D^-1 Z_k x_{k+1})`
    /// into `t`. Returns
    /// per lane 1 where the whole solution is finite, 0 where not (only from
    /// non-finite input; such a lane is left as it is for the quarantine to
    /// judge), or `None` when no lane is finite.
    #[inline(always)]
    fn backward<const CONTACT: bool>(&mut self) -> Option<T> {
        let m = self.q.len();
        let zero = T::splat(0.0);
        let mut probe = zero;
        let mut next = [zero; 6];
        for k in (0..m).rev() {
            let f = &mut self.factors[k];
            let mut y = f.t;
            if k + 1 < m {
                for r in 0..3 {
                    let mut s = zero;
                    for j in 0..3 {
                        s = s + f.z_tl[r][j] * next[j];
                    }
                    y[r] = y[r] - s;
                    let mut s = zero;
                    for j in 0..3 {
                        s = s + f.z_bl[r][j] * next[j];
                    }
                    // Without a contact Z's bottom right is lower
                    // triangular (trailing exact zeros skipped).
                    let last = if CONTACT { 2 } else { r };
                    for j in 0..=last {
                        s = s + f.z_br[r][j] * next[3 + j];
                    }
                    y[3 + r] = y[3 + r] - s;
                }
            }
            let x = backward_substitute(&f.unit, y);
            // x * 0 is 0 for finite x, NaN otherwise.
            for v in x {
                probe = probe + v * zero;
            }
            f.t = x;
            next = x;
        }
        let one = T::splat(1.0);
        let solved = T::eq_select(probe, zero, one, zero);
        (0..T::WIDTH)
            .any(|i| solved.lane(i) > 0.0)
            .then_some(solved)
    }

    /// `lambda += dlambda`, `dx = W J^T dlambda`; `keep(new, old)` picks
    /// per lane (the old value where the solve was not finite).
    #[inline(always)]
    fn apply(&mut self, keep: impl Fn(T, T) -> T) {
        let m = self.q.len();
        let zero = T::splat(0.0);
        for k in 0..m {
            let dl = self.factors[k].t;
            let lam = &mut self.lambda[k];
            for i in 0..6 {
                lam[i] = keep(lam[i] + dl[i], lam[i]);
            }
        }
        for i in 0..=m {
            let w = self.w[i];
            // Stretch i-1 has +I on p_i, stretch i has -I.
            let mut d = [zero; 3];
            if i >= 1 {
                let t = &self.factors[i - 1].t;
                d = [t[3], t[4], t[5]];
            }
            if i < m {
                let t = &self.factors[i].t;
                d = [d[0] - t[3], d[1] - t[4], d[2] - t[5]];
            }
            // M_i d = w d - CONTACT_LOCK w n (n . d).
            let n = self.contact[i];
            let lock_nd = T::splat(CONTACT_LOCK) * w * (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
            let p = &mut self.p[i];
            for c in 0..3 {
                let moved = T::gt_select(w, zero, p[c] + (w * d[c] - lock_nd * n[c]), p[c]);
                p[c] = keep(moved, p[c]);
            }
        }
        let half = T::splat(0.5);
        let max_turn = T::splat(MAX_TURN);
        for e in 0..m {
            let c = &self.constants[e];
            let f = &self.factors[e];
            let (d3, dl) = (f.d3, f.t);
            // (l [d3]x)^T ds = l ds x d3; G_e^T db_e - G_{e+1}^T db_{e+1}.
            let ds_d3 = cross([dl[3], dl[4], dl[5]], d3);
            let mut t: D3<T> = build(|r| ds_d3[r] * c.l);
            let gt = mul_at_v(&f.g, [dl[0], dl[1], dl[2]]);
            t = [t[0] + gt[0], t[1] + gt[1], t[2] + gt[2]];
            if e + 1 < m {
                let f1 = &self.factors[e + 1];
                let gt = mul_at_v(&f1.g, [f1.t[0], f1.t[1], f1.t[2]]);
                t = [t[0] - gt[0], t[1] - gt[1], t[2] - gt[2]];
            }
            // W t = w_q t + (w_twist - w_q) d3 (d3 . t).
            let along = c.dw * (d3[0] * t[0] + d3[1] * t[1] + d3[2] * t[2]);
            let mut dtheta: D3<T> = build(|r| c.wq * t[r] + along * d3[r]);
            // The linearisation holds for small turns: a frame that must
            // turn far in one step (a kinematic target jumping) gets there
            // over several iterations and steps instead of overshooting.
            let turn =
                (dtheta[0] * dtheta[0] + dtheta[1] * dtheta[1] + dtheta[2] * dtheta[2]).sqrt();
            // (The division only where a lane turns too far: the select
            // would keep `dtheta` in every other lane.)
            if (0..T::WIDTH).any(|i| turn.lane(i) > MAX_TURN) {
                let scale = max_turn / turn;
                dtheta = build(|r| T::gt_select(turn, max_turn, dtheta[r] * scale, dtheta[r]));
            }
            let q = self.q[e];
            // q += 1/2 (dtheta, 0) q, renormalised.
            let s = qmul([dtheta[0], dtheta[1], dtheta[2], zero], q);
            let n: [T; 4] = build(|i| q[i] + half * s[i]);
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] + n[3] * n[3]).sqrt();
            let turned: [T; 4] = build(|i| T::gt_select(len, zero, n[i] / len, q[i]));
            self.q[e] = build(|i| keep(T::gt_select(c.wq, zero, turned[i], q[i]), q[i]));
        }
    }
}

impl<T: Real> Direct<T> {
    /// `iterate` in the widest of `instructions` that fits the lanes
    /// (AVX-512 for eight, AVX2 for four; the same operations in wider
    /// registers, no FMA, so the same bits).
    pub fn iterate_lanes(&mut self, instructions: Instructions) {
        let lanes = self;
        in_widest!(Self::widest(instructions, 1), fn<T: Real>(lanes: &mut Direct<T>) {
            lanes.iterate()
        })
    }

    /// [`Direct::begin`] in the widest of `instructions` (the
    /// same bits).
    pub fn begin_lanes(&mut self, instructions: Instructions, strands: &[DirectInput<'_>]) {
        let lanes = self;
        in_widest!(
            Self::widest(instructions, 4),
            fn<T: Real>(lanes: &mut Direct<T>, strands: &[DirectInput<'_>]) {
                lanes.begin(strands)
            }
        )
    }

    /// [`Direct::unconverged`] in the widest of `instructions`
    /// (the same bits).
    pub fn unconverged_lanes(&self, instructions: Instructions, tolerance: f64) -> T {
        let lanes = self;
        in_widest!(
            Self::widest(instructions, 1),
            fn<T: Real>(lanes: &Direct<T>, tolerance: f64) -> T {
                lanes.unconverged(tolerance)
            }
        )
    }

    /// The widest of `instructions` for these lanes: AVX-512 only for
    /// eight, AVX2 only from `avx2_from` lanes.
    fn widest(instructions: Instructions, avx2_from: usize) -> Instructions {
        if T::WIDTH >= 8 {
            instructions
        } else if T::WIDTH >= avx2_from {
            instructions.min(Instructions::Avx2)
        } else {
            Instructions::Baseline
        }
    }
}

/// Whether any lane of any vertex has a contact normal.
fn touches<T: Real>(normals: &[D3<T>]) -> bool {
    normals
        .iter()
        .any(|n| n.iter().any(|c| (0..T::WIDTH).any(|i| c.lane(i) != 0.0)))
}

/// Replaces lane `lane` of every vector in `to` with `from`'s (f32 in),
/// leaving the other lanes as they are.
fn set_lane<T: Real>(to: &mut [D3<T>], lane: usize, from: &[V3]) {
    for (o, v) in to.iter_mut().zip(from) {
        for c in 0..3 {
            o[c].set_lane(lane, v[c] as f64);
        }
    }
}

/// The bend/twist linearisation of one joint.
struct Bend<T> {
    /// The Darboux vector, as the representative nearest the rest.
    omega: D3<T>,
    /// Its derivative with respect to a world rotation of the second frame
    /// (the negative for the first): `G = A R1^T`, `A = 1/2 (w I -
    /// [Omega]x)`.
    g: M3<T>,
    /// `G G^T = A A^T = 1/4 ((w^2 + |Omega|^2) I - Omega Omega^T)`.
    gg: M3<T>,
    /// `G d3_1 = A e_z` (the first frame's tangent is `R1 e_z`).
    g_before: D3<T>,
}

/// The Darboux vector of frames `q1`, `q2` as the representative nearest
/// the rest (the double cover, METHOD A: the 4D test on the full Darboux
/// quaternion) and its derivative.
#[inline(always)]
fn bend_linearisation<T: Real>(q1: [T; 4], q2: [T; 4], rest: D3<T>, rest_w: T) -> Bend<T> {
    let d = qmul(conj(q1), q2);
    let zero = T::splat(0.0);
    let one = T::splat(1.0);
    let test = d[0] * rest[0] + d[1] * rest[1] + d[2] * rest[2] + d[3] * rest_w;
    let sign = T::lt_select(test, zero, -one, one);
    let o = [sign * d[0], sign * d[1], sign * d[2]];
    let w = sign * d[3];
    let h = T::splat(0.5);
    let (hw, hx, hy, hz) = (h * w, h * o[0], h * o[1], h * o[2]);
    let a = [[hw, hz, -hy], [-hz, hw, hx], [hy, -hx, hw]];
    let r1 = rotation_matrix(q1);
    // G = A R1^T.
    let mut g = [[zero; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            g[r][c] = a[r][0] * r1[c][0] + a[r][1] * r1[c][1] + a[r][2] * r1[c][2];
        }
    }
    let n2 = w * w + (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
    let quarter = T::splat(0.25);
    let mut gg = [[zero; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            let outer = o[r] * o[c];
            gg[r][c] = quarter * if r == c { n2 - outer } else { -outer };
        }
    }
    Bend {
        omega: o,
        g,
        gg,
        g_before: [-hy, hx, hw],
    }
}

// The triangular loops below are written out row by row (by macros with
// literal bounds) so the compiler unrolls them fully: as nested loops with
// bounds depending on the outer index they stayed loops with index
// arithmetic and bounds checks on the solve's critical path. The operations
// and their order are those of the loops.

/// Row `i` of the `L D L^T` factor: `L D` and `L` below the diagonal (over
/// columns `j`), then the pivot.
macro_rules! ldlt_row {
    ($a:ident, $l:ident, $inv:ident, $ld:ident, $i:literal; $($j:literal)*) => {
        $(
            let mut s = $a[$i][$j];
            for k in 0..$j {
                s = s - $ld[k] * $l[($j, k)];
            }
            $ld[$j] = s;
            $l[($i, $j)] = s * $inv[$j];
        )*
        let mut s = $a[$i][$i];
        for k in 0..$i {
            s = s - $ld[k] * $l[($i, k)];
        }
        let (zero, one) = (T::splat(0.0), T::splat(1.0));
        $inv[$i] = one / T::gt_select(s, zero, s, one);
    };
}

/// `L D L^T` factor of a symmetric positive definite 6x6 block given by
/// its lower triangle: `L` unit lower (below the diagonal) and `D^-1`. A
/// non-positive pivot (only from non-finite input) becomes 1 so the
/// quarantine sees the NaN rather than a panic.
#[inline(always)]
// Row 0 (and column 0) have no terms: empty ranges from the macro.
#[allow(clippy::reversed_empty_ranges)]
fn ldlt<T: Real>(a: &[D6<T>; 6], l: &mut Unit<T>, inv: &mut D6<T>) {
    // Row i of L D, below the diagonal.
    let mut ld = [T::splat(0.0); 6];
    ldlt_row!(a, l, inv, ld, 0;);
    ldlt_row!(a, l, inv, ld, 1; 0);
    ldlt_row!(a, l, inv, ld, 2; 0 1);
    ldlt_row!(a, l, inv, ld, 3; 0 1 2);
    ldlt_row!(a, l, inv, ld, 4; 0 1 2 3);
    ldlt_row!(a, l, inv, ld, 5; 0 1 2 3 4);
}

/// `y_i = b_i - sum_{k < i} L_ik y_k`.
macro_rules! forward_row {
    ($l:ident, $y:ident, $i:literal) => {
        for k in 0..$i {
            $y[$i] = $y[$i] - $l[($i, k)] * $y[k];
        }
    };
}

/// `D^-1 L^-1 b`.
#[inline(always)]
fn forward_substitute<T: Real>(l: &Unit<T>, inv: &D6<T>, b: D6<T>) -> D6<T> {
    let mut y = b;
    forward_row!(l, y, 1);
    forward_row!(l, y, 2);
    forward_row!(l, y, 3);
    forward_row!(l, y, 4);
    forward_row!(l, y, 5);
    build(|i| y[i] * inv[i])
}

/// `x_i = y_i - sum_{j > i} L_ji x_j`.
macro_rules! backward_row {
    ($l:expr, $y:ident, $x:ident, $i:literal) => {
        let mut s = $y[$i];
        for j in $i + 1..6 {
            s = s - $l[(j, $i)] * $x[j];
        }
        $x[$i] = s;
    };
}

/// `L^-T y`.
#[inline(always)]
fn backward_substitute<T: Real>(l: &Unit<T>, y: D6<T>) -> D6<T> {
    let mut x = y;
    backward_row!(l, y, x, 4);
    backward_row!(l, y, x, 3);
    backward_row!(l, y, x, 2);
    backward_row!(l, y, x, 1);
    backward_row!(l, y, x, 0);
    x
}

#[inline(always)]
fn tangent<T: Real>(q: [T; 4]) -> D3<T> {
    let [x, y, z, w] = q;
    let two = T::splat(2.0);
    [
        two * (x * z + w * y),
        two * (y * z - w * x),
        T::splat(1.0) - two * (x * x + y * y),
    ]
}

#[inline(always)]
fn rotation_matrix<T: Real>(q: [T; 4]) -> M3<T> {
    let [x, y, z, w] = q;
    let one = T::splat(1.0);
    let two = T::splat(2.0);
    [
        [
            one - two * (y * y + z * z),
            two * (x * y - w * z),
            two * (x * z + w * y),
        ],
        [
            two * (x * y + w * z),
            one - two * (x * x + z * z),
            two * (y * z - w * x),
        ],
        [
            two * (x * z - w * y),
            two * (y * z + w * x),
            one - two * (x * x + y * y),
        ],
    ]
}

#[inline(always)]
fn qmul<T: Real>(a: [T; 4], b: [T; 4]) -> [T; 4] {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

#[inline(always)]
fn conj<T: Real>(q: [T; 4]) -> [T; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

/// `a v`.
#[inline(always)]
fn mul_av<T: Real>(a: &M3<T>, v: D3<T>) -> D3<T> {
    build(|r| a[r][0] * v[0] + a[r][1] * v[1] + a[r][2] * v[2])
}

/// `a^T v`.
#[inline(always)]
fn mul_at_v<T: Real>(a: &M3<T>, v: D3<T>) -> D3<T> {
    build(|c| a[0][c] * v[0] + a[1][c] * v[1] + a[2][c] * v[2])
}

/// Lane `i` of a number from strand `i`.
#[inline(always)]
fn gather<T: Real>(strands: &[DirectInput<'_>], get: impl Fn(&DirectInput<'_>) -> f64) -> T {
    T::gather(|i| get(&strands[i]))
}

/// `[f(0), .., f(N - 1)]`, always inlined (`array::map` and `from_fn`
/// were not, in the hot loop).
#[inline(always)]
fn build<U: Copy + Default, const N: usize>(mut f: impl FnMut(usize) -> U) -> [U; N] {
    let mut out = [U::default(); N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
    out
}

#[inline(always)]
fn cross<T: Real>(a: D3<T>, b: D3<T>) -> D3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
