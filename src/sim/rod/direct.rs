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
//! consistent flexibility of `bend_flexibility`, rod/shape_memory.rs), which keeps the
//! blocks' coupling to neighbours. Each block shares unknowns only with its
//! neighbours, so `J W J^T + alpha/dt^2` is block-tridiagonal and one
//! Newton-XPBD iteration costs O(edges). Hand-written rather than a sparse
//! crate: the 6x6 blocks are fixed-size and sparse in a known pattern
//! (written out in direct/algebra.rs), and the solve must not allocate per step; it runs
//! in f64 because hair is very stiff for its mass (the system's entries
//! span ~1e-3 to ~1e12).
//!
//! The solve is generic over [`Real`]: `f64` steps one strand, `f64x4`
//! four strands in SIMD lanes with the same operations in the same order,
//! so a strand's result does not depend on its group.

// Dense 3x3 and 6x6 algebra reads as the formulas with explicit indices.
#![allow(clippy::needless_range_loop)]

mod algebra;
mod constants;

use super::real::Real;
use crate::sim::instructions::{in_widest, Instructions};
use crate::sim::math::{Quat, V3};
use crate::sim::state::JointState;
use algebra::{
    backward_substitute, build, conj, cross, forward_substitute, gather, ldlt, mul_at_v, mul_av,
    qmul, rotation_matrix, tangent,
};
use constants::EdgeLane;
pub(in crate::sim) use constants::{
    edge_flexibility, segment_mass, FRAME_INERTIA_SPEED, MIDPOINT_FRAME_INERTIA_SPEED,
};

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
/// (`FRAME_INERTIA_SPEED`, direct/constants.rs); with the floor the perm keeps 0.67
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
    /// `bend_flexibility`, rod/shape_memory.rs), 1/(N m).
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
    /// `1 / (1 + k dt^2)` for one the hold pulls (forces/hold.rs).
    pub free: &'a [f32],
    /// Per edge, the factor of its frame's inverse inertia: 1, or `1 / (1 +
    /// k dt^2)` for a frame the hold pulls (forces/hold.rs).
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
    /// The frames' tilt inertia is at least that of a segment this speed
    /// times `dt` long, m/s (`FRAME_INERTIA_SPEED` for backward Euler,
    /// `MIDPOINT_FRAME_INERTIA_SPEED` for the midpoint step's half step).
    pub frame_inertia_speed: f64,
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
