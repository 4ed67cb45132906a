//! The constraint sweep on four strands at once (one per SIMD lane). Every
//! lane performs exactly the float operations of the scalar code in
//! `constraints.rs` in the same order (branches become selects), so a
//! strand's result is bit-identical whether it runs alone or in a group.

use super::constraints::{
    StretchCoefficients, BEND_DEADBAND2, LENGTH_DEADBAND, NEWTON_RANGE, STRETCH_DEADBAND2,
};
use super::direct::Direct;
use super::real::F64x4;
use crate::sim::math::{Quat, V3};
use std::ops::{Add, Mul, Neg, Sub};

pub const LANES: usize = 4;

#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(align(16))]
pub struct F4(pub [f32; LANES]);

impl F4 {
    #[inline(always)]
    pub fn splat(v: f32) -> F4 {
        F4([v; LANES])
    }
    #[inline(always)]
    fn map2(self, other: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
        let mut out = [0.0; LANES];
        for (i, o) in out.iter_mut().enumerate() {
            *o = f(self.0[i], other.0[i]);
        }
        F4(out)
    }
    #[inline(always)]
    fn lt(self, other: F4) -> [bool; LANES] {
        std::array::from_fn(|i| self.0[i] < other.0[i])
    }
    #[inline(always)]
    fn gt(self, other: F4) -> [bool; LANES] {
        std::array::from_fn(|i| self.0[i] > other.0[i])
    }
    #[inline(always)]
    fn abs(self) -> F4 {
        F4(self.0.map(f32::abs))
    }
    #[inline(always)]
    fn sqrt(self) -> F4 {
        F4(self.0.map(f32::sqrt))
    }
    /// `mask ? a : b` per lane.
    #[inline(always)]
    fn select(mask: [bool; LANES], a: F4, b: F4) -> F4 {
        F4(std::array::from_fn(
            |i| if mask[i] { a.0[i] } else { b.0[i] },
        ))
    }
}

impl Add for F4 {
    type Output = F4;
    #[inline(always)]
    fn add(self, o: F4) -> F4 {
        self.map2(o, |a, b| a + b)
    }
}
impl Sub for F4 {
    type Output = F4;
    #[inline(always)]
    fn sub(self, o: F4) -> F4 {
        self.map2(o, |a, b| a - b)
    }
}
impl Mul for F4 {
    type Output = F4;
    #[inline(always)]
    fn mul(self, o: F4) -> F4 {
        self.map2(o, |a, b| a * b)
    }
}
impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        F4(self.0.map(|a| -a))
    }
}

type P4 = [F4; 3];
type Q4 = [F4; 4];

#[inline(always)]
fn select3(mask: [bool; LANES], a: P4, b: P4) -> P4 {
    [
        F4::select(mask, a[0], b[0]),
        F4::select(mask, a[1], b[1]),
        F4::select(mask, a[2], b[2]),
    ]
}

#[inline(always)]
fn select4(mask: [bool; LANES], a: Q4, b: Q4) -> Q4 {
    [
        F4::select(mask, a[0], b[0]),
        F4::select(mask, a[1], b[1]),
        F4::select(mask, a[2], b[2]),
        F4::select(mask, a[3], b[3]),
    ]
}

#[inline(always)]
fn and(a: [bool; LANES], b: [bool; LANES]) -> [bool; LANES] {
    std::array::from_fn(|i| a[i] && b[i])
}

#[inline(always)]
fn not(a: [bool; LANES]) -> [bool; LANES] {
    a.map(|x| !x)
}

/// `renormalize` of constraints.rs, per lane.
#[inline(always)]
fn renormalize(q: Q4) -> Q4 {
    let n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    let e = n2 - F4::splat(1.0);
    let s = F4::splat(1.0) - F4::splat(0.5) * e + F4::splat(0.375) * e * e;
    let newton = [q[0] * s, q[1] * s, q[2] * s, q[3] * s];
    // qnormalize: 1 / sqrt(n2) when n2 > 0, else unchanged.
    let inv = F4::splat(1.0).map2(n2.sqrt(), |a, b| a / b);
    let positive = n2.gt(F4::splat(0.0));
    let exact = select4(
        positive,
        [q[0] * inv, q[1] * inv, q[2] * inv, q[3] * inv],
        q,
    );
    select4(e.abs().lt(F4::splat(NEWTON_RANGE)), newton, exact)
}

/// Stretch/shear coefficients of four lanes.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stretch4 {
    inv_l: F4,
    a: F4,
    b: F4,
    k: F4,
}

impl Stretch4 {
    pub fn gather(c: [&StretchCoefficients; LANES]) -> Stretch4 {
        Stretch4 {
            inv_l: F4(c.map(|c| c.inv_l)),
            a: F4(c.map(|c| c.a)),
            b: F4(c.map(|c| c.b)),
            k: F4(c.map(|c| c.k)),
        }
    }
}

/// `stretch_shear` of constraints.rs, per lane.
#[inline(always)]
fn stretch_shear(p1: &mut P4, p2: &mut P4, q: &mut Q4, c: &Stretch4) {
    let [x, y, z, w] = *q;
    let two = F4::splat(2.0);
    let d3 = [
        two * (x * z + w * y),
        two * (y * z - w * x),
        F4::splat(1.0) - two * (x * x + y * y),
    ];
    let g = [
        (p2[0] - p1[0]) * c.inv_l - d3[0],
        (p2[1] - p1[1]) * c.inv_l - d3[1],
        (p2[2] - p1[2]) * c.inv_l - d3[2],
    ];
    let g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    let apply = not(g2.lt(F4::splat(STRETCH_DEADBAND2)));
    let new_p1 = [p1[0] + c.a * g[0], p1[1] + c.a * g[1], p1[2] + c.a * g[2]];
    let new_p2 = [p2[0] - c.b * g[0], p2[1] - c.b * g[1], p2[2] - c.b * g[2]];
    let [g0, g1, g2v] = g;
    let t0 = g0 * w + g1 * z - g2v * y;
    let t1 = -g0 * z + g1 * w + g2v * x;
    let t2 = g0 * y - g1 * x + g2v * w;
    let t3 = -g0 * x - g1 * y - g2v * z;
    let k = c.k;
    let new_q = renormalize([x - k * t1, y + k * t0, z - k * t3, w + k * t2]);
    *p1 = select3(apply, new_p1, *p1);
    *p2 = select3(apply, new_p2, *p2);
    *q = select4(and(apply, k.gt(F4::splat(0.0))), new_q, *q);
}

/// `qmul_pure` of constraints.rs, per lane.
#[inline(always)]
fn qmul_pure(q: Q4, v: P4) -> Q4 {
    [
        q[3] * v[0] + q[1] * v[2] - q[2] * v[1],
        q[3] * v[1] - q[0] * v[2] + q[2] * v[0],
        q[3] * v[2] + q[0] * v[1] - q[1] * v[0],
        -q[0] * v[0] - q[1] * v[1] - q[2] * v[2],
    ]
}

/// `bend_twist` of constraints.rs, per lane.
#[inline(always)]
fn bend_twist(q1: &mut Q4, q2: &mut Q4, rest: P4, a: F4, b: F4) {
    let (p, r) = (*q1, *q2);
    let omega = [
        p[3] * r[0] - p[0] * r[3] - p[1] * r[2] + p[2] * r[1],
        p[3] * r[1] + p[0] * r[2] - p[1] * r[3] - p[2] * r[0],
        p[3] * r[2] - p[0] * r[1] + p[1] * r[0] - p[2] * r[3],
    ];
    // `double_cover_sign` of math.rs, per lane: the 4D dot product of the
    // Darboux quaternion (omega, q1 . q2) and (rest, rest_real(rest)).
    let w = p[0] * r[0] + p[1] * r[1] + p[2] * r[2] + p[3] * r[3];
    let rest2 = rest[0] * rest[0] + rest[1] * rest[1] + rest[2] * rest[2];
    let rest_w = F4((F4::splat(1.0) - rest2).0.map(|x| x.max(0.0))).sqrt();
    let dot4 = omega[0] * rest[0] + omega[1] * rest[1] + omega[2] * rest[2] + w * rest_w;
    let s = F4::select(dot4.lt(F4::splat(0.0)), F4::splat(-1.0), F4::splat(1.0));
    let delta = [
        omega[0] - s * rest[0],
        omega[1] - s * rest[1],
        omega[2] - s * rest[2],
    ];
    let delta2 = delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2];
    let apply = not(delta2.lt(F4::splat(BEND_DEADBAND2)));
    let r1 = qmul_pure(r, delta);
    let r2 = qmul_pure(p, delta);
    let n1 = renormalize([
        p[0] + a * r1[0],
        p[1] + a * r1[1],
        p[2] + a * r1[2],
        p[3] + a * r1[3],
    ]);
    let n2 = renormalize([
        r[0] - b * r2[0],
        r[1] - b * r2[1],
        r[2] - b * r2[2],
        r[3] - b * r2[3],
    ]);
    let zero = F4::splat(0.0);
    *q1 = select4(and(apply, a.gt(zero)), n1, p);
    *q2 = select4(and(apply, b.gt(zero)), n2, r);
}

/// Four strands of the same vertex count, transposed into lanes.
#[derive(Debug, Default)]
pub struct Group {
    p: Vec<P4>,
    q: Vec<Q4>,
    stretch: Vec<Stretch4>,
    rest: Vec<P4>,
    bend_a: Vec<F4>,
    bend_b: Vec<F4>,
    w: Vec<F4>,
    l: Vec<F4>,
    corrections: Vec<P4>,
    /// The physical model's direct solve of the four strands.
    pub direct: Direct<F64x4>,
}

/// What the group reads from one strand's working copy.
pub struct LaneInput<'a> {
    pub p: &'a [V3],
    pub q: &'a [Quat],
    pub stretch: &'a [StretchCoefficients],
    pub rest: &'a [V3],
    pub bend: &'a [[f32; 2]],
    /// Vertex inverse masses and rest lengths (for Follow-The-Leader).
    pub w: &'a [f32],
    pub l: &'a [f32],
}

impl Group {
    /// Loads the constants (coefficients, rest shape) of four strands of
    /// `n` vertices.
    pub fn load_constants(&mut self, lanes: [LaneInput<'_>; LANES], n: usize) {
        let m = n - 1;
        self.stretch.clear();
        self.rest.clear();
        self.bend_a.clear();
        self.bend_b.clear();
        self.w.clear();
        self.l.clear();
        for i in 0..n {
            self.w.push(F4(std::array::from_fn(|l| lanes[l].w[i])));
        }
        for e in 0..m {
            self.l.push(F4(std::array::from_fn(|l| lanes[l].l[e])));
            self.stretch.push(Stretch4::gather(std::array::from_fn(|l| {
                &lanes[l].stretch[e]
            })));
            self.rest.push(std::array::from_fn(|c| {
                F4(std::array::from_fn(|l| lanes[l].rest[e][c]))
            }));
            self.bend_a
                .push(F4(std::array::from_fn(|l| lanes[l].bend[e][0])));
            self.bend_b
                .push(F4(std::array::from_fn(|l| lanes[l].bend[e][1])));
        }
        self.load_state(&lanes, n);
    }

    /// Loads positions and frames.
    pub fn load_state(&mut self, lanes: &[LaneInput<'_>; LANES], n: usize) {
        self.p.clear();
        self.q.clear();
        for i in 0..n {
            self.p.push(std::array::from_fn(|c| {
                F4(std::array::from_fn(|l| lanes[l].p[i][c]))
            }));
        }
        for e in 0..n - 1 {
            self.q.push(std::array::from_fn(|c| {
                F4(std::array::from_fn(|l| lanes[l].q[e][c]))
            }));
        }
    }

    /// Writes positions and frames of lane `lane` back.
    pub fn store(&self, lane: usize, p: &mut [V3], q: &mut [Quat]) {
        for (out, v) in p.iter_mut().zip(&self.p) {
            *out = [v[0].0[lane], v[1].0[lane], v[2].0[lane]];
        }
        for (out, v) in q.iter_mut().zip(&self.q) {
            *out = [v[0].0[lane], v[1].0[lane], v[2].0[lane], v[3].0[lane]];
        }
    }

    /// `follow_the_leader` of constraints.rs, per lane.
    pub fn follow_the_leader(&mut self) {
        let n = self.p.len();
        if self.w.len() != n || self.l.len() + 1 != n {
            return;
        }
        let zero = F4::splat(0.0);
        self.corrections.clear();
        self.corrections.resize(n, [zero; 3]);
        for i in 1..n {
            let a = self.p[i - 1];
            let b = self.p[i];
            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let s = self.l[i - 1].map2(len2.sqrt(), |l, r| l / r);
            let moved = and(
                and(self.w[i].gt(zero), len2.gt(zero)),
                not((s - F4::splat(1.0)).abs().lt(F4::splat(LENGTH_DEADBAND))),
            );
            let next = [a[0] + d[0] * s, a[1] + d[1] * s, a[2] + d[2] * s];
            let correction = [next[0] - b[0], next[1] - b[1], next[2] - b[2]];
            self.corrections[i] = select3(moved, correction, [zero; 3]);
            self.p[i] = select3(moved, next, b);
        }
    }

    /// The corrections of the last `follow_the_leader` for lane `lane`.
    pub fn store_corrections(&self, lane: usize, out: &mut [V3]) {
        for (o, c) in out.iter_mut().zip(&self.corrections) {
            *o = [c[0].0[lane], c[1].0[lane], c[2].0[lane]];
        }
    }

    /// One Gauss-Seidel sweep root to tip, as `Work::sweep`.
    pub fn sweep(&mut self) {
        let m = self.q.len();
        if m == 0 || self.p.len() != m + 1 || self.stretch.len() != m {
            return;
        }
        let mut p_a = self.p[0];
        let mut p_b = self.p[1];
        let mut q_prev = self.q[0];
        stretch_shear(&mut p_a, &mut p_b, &mut q_prev, &self.stretch[0]);
        self.p[0] = p_a;
        p_a = p_b;
        for e in 1..m {
            let mut p_b = self.p[e + 1];
            let mut q_e = self.q[e];
            stretch_shear(&mut p_a, &mut p_b, &mut q_e, &self.stretch[e]);
            bend_twist(
                &mut q_prev,
                &mut q_e,
                self.rest[e],
                self.bend_a[e],
                self.bend_b[e],
            );
            self.p[e] = p_a;
            self.q[e - 1] = q_prev;
            p_a = p_b;
            q_prev = q_e;
        }
        self.p[m] = p_a;
        self.q[m - 1] = q_prev;
    }
}
