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
//! frame and the first edge's frame, the clamp, with half a Voronoi
//! length) and the stretch/shear of edge `k`. Each block shares unknowns only with its
//! neighbours, so `J W J^T + alpha/dt^2` is block-tridiagonal and one
//! Newton-XPBD iteration costs O(edges). Hand-written rather than a sparse
//! crate: the 6x6 blocks are fixed-size and the solve must not allocate per
//! step; it runs in f64 because hair is very stiff for its mass (the
//! system's entries span ~1e-3 to ~1e12).

// Dense 3x3 and 6x6 algebra reads as the formulas with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::math::{Quat, V3};

/// The largest frame rotation one iteration applies, radians: a trust
/// region for the linearisation. At 0.5 a perm rod's moving targets left
/// the frames lagging at dt 1/360 (the set came out at a quarter of its
/// size); 0.1 follows them and is far above a frame's turn per iteration in
/// free motion.
const MAX_TURN: f64 = 0.1;

/// How much of a touching vertex's inverse mass along the contact normal
/// the solve removes: it is 100 times heavier across the surface than
/// along it. A full lock (1) makes the stretch block of an edge lying on a
/// surface singular up to its tiny compliance, and the Cholesky pivots
/// lost to round-off blew short pressed strands up; at 0.99 the edges of
/// the bed-hair press stay within 0.001 % of rest and the vertex moves
/// across the surface by 1 % of a free vertex's correction (the
/// projection after the solve takes that back).
const CONTACT_LOCK: f64 = 0.99;

type M6 = [[f64; 6]; 6];
type V6 = [f64; 6];
type M3 = [[f64; 3]; 3];
type D3 = [f64; 3];

/// Per-step constants of one edge (block) of a strand.
#[derive(Debug, Clone, Copy, Default)]
pub struct EdgeCompliance {
    /// Stretch/shear compliance `l / (G A)` (across) and `l / (E A)` (along
    /// the frame's tangent), m/N.
    pub shear: f64,
    pub stretch: f64,
    /// Bend/twist compliance of the joint at the edge's first vertex on the
    /// Darboux vector: `l_j / (4 E I)` and `l_j / (4 G J)`, 1/(N m).
    pub bend: f64,
    pub twist: f64,
}

/// Scratch of one strand's direct solve (reused across steps).
#[derive(Debug, Default)]
pub struct Direct {
    p: Vec<D3>,
    q: Vec<[f64; 4]>,
    lambda: Vec<V6>,
    diag: Vec<M6>,
    upper: Vec<M6>,
    rhs: Vec<V6>,
    /// Per block: `D'^-1 U` and `D'^-1 b'` of the forward sweep.
    y_mat: Vec<M6>,
    y_vec: Vec<V6>,
    g: Vec<M3>,
    d3: Vec<D3>,
}

/// What one strand's solve reads.
pub struct DirectInput<'a> {
    /// Vertex inverse masses (0: pinned or driven).
    pub w: &'a [f32],
    /// Per vertex, the unit normal of a contact the solve must hardly move
    /// the vertex along (zero: no contact), or empty when nothing touches.
    /// The contact is folded into the vertex's inverse mass,
    /// `w (I - CONTACT_LOCK n n^T)`: the strand keeps its length by sliding
    /// along the surface instead of being pushed into it or having its
    /// edges squeezed by a projection after the solve.
    pub contact_normals: &'a [V3],
    /// Frame inverse rotational inertias across the tangent (0: fixed).
    pub w_q: &'a [f32],
    /// Frame inverse rotational inertias about the tangent (twist).
    pub w_twist: &'a [f32],
    pub l: &'a [f32],
    /// Rest Darboux vectors per joint slot (canonical, real part >= 0).
    pub rest: &'a [V3],
    pub compliance: &'a [EdgeCompliance],
    /// The fixed frame the first edge is clamped to (the scalp's).
    pub root_frame: Quat,
    pub dt: f32,
}

impl Direct {
    /// Loads the predicted positions and frames and resets the multipliers.
    pub fn begin(&mut self, p: &[V3], q: &[Quat]) {
        let n = p.len();
        let m = n - 1;
        self.p.clear();
        self.p
            .extend(p.iter().map(|v| [v[0] as f64, v[1] as f64, v[2] as f64]));
        self.q.clear();
        self.q.extend(
            q[..m]
                .iter()
                .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64, v[3] as f64]),
        );
        for v in [&mut self.lambda, &mut self.rhs, &mut self.y_vec] {
            v.clear();
            v.resize(m, [0.0; 6]);
        }
        for v in [&mut self.diag, &mut self.upper, &mut self.y_mat] {
            v.clear();
            v.resize(m, [[0.0; 6]; 6]);
        }
        self.g.clear();
        self.g.resize(m, [[0.0; 3]; 3]);
        self.d3.clear();
        self.d3.resize(m, [0.0; 3]);
    }

    /// Writes the positions and frames back (f32).
    pub fn end(&self, p: &mut [V3], q: &mut [Quat]) {
        for (o, v) in p.iter_mut().zip(&self.p) {
            *o = [v[0] as f32, v[1] as f32, v[2] as f32];
        }
        for (o, v) in q.iter_mut().zip(&self.q) {
            *o = [v[0] as f32, v[1] as f32, v[2] as f32, v[3] as f32];
        }
    }

    /// Positions moved by something else (collisions) between iterations.
    pub fn set_positions(&mut self, p: &[V3]) {
        for (o, v) in self.p.iter_mut().zip(p) {
            *o = [v[0] as f64, v[1] as f64, v[2] as f64];
        }
    }

    pub fn positions_f32(&self, p: &mut [V3]) {
        for (o, v) in p.iter_mut().zip(&self.p) {
            *o = [v[0] as f32, v[1] as f32, v[2] as f32];
        }
    }

    /// One Newton-XPBD iteration: linearise every constraint at the current
    /// state, solve `(J W J^T + alpha~) dlambda = -(C + alpha~ lambda)`
    /// exactly, apply `dx = W J^T dlambda`. Returns the largest residual
    /// `|C + alpha~ lambda|` before the update (a convergence measure).
    pub fn iterate(&mut self, input: &DirectInput<'_>) -> f64 {
        let m = self.q.len();
        let inv_dt2 = 1.0 / (input.dt as f64 * input.dt as f64);
        let mut residual = 0.0f64;
        // Jacobian pieces and right-hand sides.
        for k in 0..m {
            let q = self.q[k];
            let d3 = tangent(q);
            self.d3[k] = d3;
            let l = input.l[k] as f64;
            let c = &input.compliance[k];
            let lam = self.lambda[k];
            // Stretch/shear: C = p_{k+1} - p_k - l d3, compliance in world
            // axes (shear across, stretch along d3).
            let a_sh = c.shear * inv_dt2;
            let a_st = c.stretch * inv_dt2;
            let mut alpha_s = [[0.0; 3]; 3];
            for (r, row) in alpha_s.iter_mut().enumerate() {
                for (col, v) in row.iter_mut().enumerate() {
                    let delta = if r == col { 1.0 } else { 0.0 };
                    *v = a_sh * (delta - d3[r] * d3[col]) + a_st * d3[r] * d3[col];
                }
            }
            let mut rhs = [0.0; 6];
            for r in 0..3 {
                let cs = self.p[k + 1][r] - self.p[k][r] - l * d3[r];
                let mut al = 0.0;
                for col in 0..3 {
                    al += alpha_s[r][col] * lam[3 + col];
                }
                rhs[3 + r] = -(cs + al);
            }
            let mut block = [[0.0; 6]; 6];
            let (a_b, a_t) = (c.bend * inv_dt2, c.twist * inv_dt2);
            {
                let (before, w_before) = if k >= 1 {
                    (self.q[k - 1], input.w_q[k - 1] as f64)
                } else {
                    let r = input.root_frame;
                    ([r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64], 0.0)
                };
                let (omega, g) = bend_linearisation(before, q, input.rest[k]);
                self.g[k] = g;
                let alpha_b = [a_b, a_b, a_t];
                for r in 0..3 {
                    rhs[r] = -(omega[r] - input.rest[k][r] as f64 + alpha_b[r] * lam[r]);
                }
                let mut w_sum = inverse_inertia(input, k, d3);
                if w_before > 0.0 {
                    let before_w = inverse_inertia(input, k - 1, self.d3[k - 1]);
                    for r in 0..3 {
                        for c in 0..3 {
                            w_sum[r][c] += before_w[r][c];
                        }
                    }
                }
                let gwg = mul_abt(&mul_ab(&g, &w_sum), &g);
                for r in 0..3 {
                    for col in 0..3 {
                        block[r][col] = gwg[r][col];
                    }
                    block[r][r] += alpha_b[r];
                }
                // B-S coupling through frame k: w_k G (l [d3]x)^T = -w_k l G [d3]x.
                let wk = input.w_q[k] as f64;
                let gx = mul_ab(&g, &skew(d3));
                for r in 0..3 {
                    for col in 0..3 {
                        let v = -wk * l * gx[r][col];
                        block[r][3 + col] = v;
                        block[3 + col][r] = v;
                    }
                }
            }
            let (m0, m1, wq) = (
                vertex_mobility(input, k),
                vertex_mobility(input, k + 1),
                input.w_q[k] as f64,
            );
            for r in 0..3 {
                for col in 0..3 {
                    let delta = if r == col { 1.0 } else { 0.0 };
                    block[3 + r][3 + col] = m0[r][col]
                        + m1[r][col]
                        + wq * l * l * (delta - d3[r] * d3[col])
                        + alpha_s[r][col];
                }
            }
            for v in &rhs {
                residual = residual.max(v.abs());
            }
            self.diag[k] = block;
            self.rhs[k] = rhs;
        }
        // Couplings between block k and k + 1.
        for k in 0..m.saturating_sub(1) {
            let wq = input.w_q[k] as f64;
            let wp = vertex_mobility(input, k + 1);
            let l = input.l[k] as f64;
            let g_next = self.g[k + 1];
            let mut u = [[0.0; 6]; 6];
            let w_k = inverse_inertia(input, k, self.d3[k]);
            let bb = mul_abt(&mul_ab(&self.g[k], &w_k), &g_next);
            for r in 0..3 {
                for col in 0..3 {
                    u[r][col] = -bb[r][col];
                }
            }
            let sb = mul_abt(&skew(self.d3[k]), &g_next);
            for r in 0..3 {
                for col in 0..3 {
                    u[3 + r][col] = -wq * l * sb[r][col];
                    u[3 + r][3 + col] = -wp[r][col];
                }
            }
            self.upper[k] = u;
        }
        self.solve_tridiagonal();
        // A solve that went non-finite (only from non-finite input) leaves
        // the state as it is; the quarantine judges the strand.
        if self.rhs.iter().flatten().all(|v| v.is_finite()) {
            self.apply(input);
        }
        residual
    }

    /// Block Thomas algorithm on the symmetric block-tridiagonal system;
    /// the solution replaces `rhs`.
    fn solve_tridiagonal(&mut self) {
        let m = self.diag.len();
        for k in 0..m {
            if k > 0 {
                // D'_k = D_k - U_{k-1}^T Y_{k-1}; b'_k = b_k - U_{k-1}^T y_{k-1}.
                let u = self.upper[k - 1];
                let ym = self.y_mat[k - 1];
                let yv = self.y_vec[k - 1];
                let d = &mut self.diag[k];
                let b = &mut self.rhs[k];
                for r in 0..6 {
                    for col in 0..6 {
                        let mut s = 0.0;
                        for i in 0..6 {
                            s += u[i][r] * ym[i][col];
                        }
                        d[r][col] -= s;
                    }
                    let mut s = 0.0;
                    for i in 0..6 {
                        s += u[i][r] * yv[i];
                    }
                    b[r] -= s;
                }
            }
            let chol = cholesky(&self.diag[k]);
            self.y_vec[k] = chol_solve(&chol, &self.rhs[k]);
            if k + 1 < m {
                let u = self.upper[k];
                let mut ym = [[0.0; 6]; 6];
                for col in 0..6 {
                    let column: V6 = std::array::from_fn(|r| u[r][col]);
                    let x = chol_solve(&chol, &column);
                    for r in 0..6 {
                        ym[r][col] = x[r];
                    }
                }
                self.y_mat[k] = ym;
            }
        }
        // Back substitution: x_k = y_k - Y_k x_{k+1}.
        for k in (0..m).rev() {
            let mut x = self.y_vec[k];
            if k + 1 < m {
                let next = self.rhs[k + 1];
                for (r, xr) in x.iter_mut().enumerate() {
                    let mut s = 0.0;
                    for (c, n) in next.iter().enumerate() {
                        s += self.y_mat[k][r][c] * n;
                    }
                    *xr -= s;
                }
            }
            self.rhs[k] = x;
        }
    }

    /// `lambda += dlambda`, `dx = W J^T dlambda`.
    fn apply(&mut self, input: &DirectInput<'_>) {
        let m = self.q.len();
        for k in 0..m {
            let dl = self.rhs[k];
            for (lam, d) in self.lambda[k].iter_mut().zip(&dl) {
                *lam += d;
            }
        }
        for i in 0..=m {
            let w = input.w[i] as f64;
            if w == 0.0 {
                continue;
            }
            // S_{i-1} has +I on p_i, S_i has -I.
            let mut d = [0.0; 3];
            if i >= 1 {
                for (c, dc) in d.iter_mut().enumerate() {
                    *dc += self.rhs[i - 1][3 + c];
                }
            }
            if i < m {
                for (c, dc) in d.iter_mut().enumerate() {
                    *dc -= self.rhs[i][3 + c];
                }
            }
            let d = mul_av(&vertex_mobility(input, i), d);
            for c in 0..3 {
                self.p[i][c] += d[c];
            }
        }
        for e in 0..m {
            let w = input.w_q[e] as f64;
            if w == 0.0 {
                continue;
            }
            let l = input.l[e] as f64;
            let ds: D3 = [self.rhs[e][3], self.rhs[e][4], self.rhs[e][5]];
            // (l [d3]x)^T ds = l ds x d3.
            let mut t = scale3(cross3(ds, self.d3[e]), l);
            let db: D3 = [self.rhs[e][0], self.rhs[e][1], self.rhs[e][2]];
            t = add3(t, mul_at_v(&self.g[e], db));
            if e + 1 < m {
                let db: D3 = [self.rhs[e + 1][0], self.rhs[e + 1][1], self.rhs[e + 1][2]];
                t = sub3(t, mul_at_v(&self.g[e + 1], db));
            }
            let mut dtheta = mul_av(&inverse_inertia(input, e, self.d3[e]), t);
            // The linearisation holds for small turns: a frame that must
            // turn far in one step (a kinematic target jumping) gets there
            // over several iterations and steps instead of overshooting.
            let turn = dot3(dtheta, dtheta).sqrt();
            if turn > MAX_TURN {
                dtheta = scale3(dtheta, MAX_TURN / turn);
            }
            let q = self.q[e];
            // q += 1/2 (dtheta, 0) q, renormalised.
            let s = qmul_d([dtheta[0], dtheta[1], dtheta[2], 0.0], q);
            let n = [
                q[0] + 0.5 * s[0],
                q[1] + 0.5 * s[1],
                q[2] + 0.5 * s[2],
                q[3] + 0.5 * s[3],
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] + n[3] * n[3]).sqrt();
            self.q[e] = if len > 0.0 {
                [n[0] / len, n[1] / len, n[2] / len, n[3] / len]
            } else {
                q
            };
        }
    }
}

/// The Darboux vector of frames `q1`, `q2` as the representative nearest
/// the rest (the double cover, METHOD A: the 4D test on the full Darboux
/// quaternion) and its derivative with respect to a world rotation of `q2`
/// (the negative for `q1`): `G = 1/2 (w I - [Omega]x) R1^T`.
fn bend_linearisation(q1: [f64; 4], q2: [f64; 4], rest: V3) -> (D3, M3) {
    let d = qmul_d(conj_d(q1), q2);
    let rest = [rest[0] as f64, rest[1] as f64, rest[2] as f64];
    let rest_w = (1.0 - dot3(rest, rest)).max(0.0).sqrt();
    let sign = if dot3([d[0], d[1], d[2]], rest) + d[3] * rest_w < 0.0 {
        -1.0
    } else {
        1.0
    };
    let omega = [sign * d[0], sign * d[1], sign * d[2]];
    let w = sign * d[3];
    let r1t = transpose(rotation_matrix(q1));
    let mut a = [[0.0; 3]; 3];
    let so = skew(omega);
    for r in 0..3 {
        for c in 0..3 {
            a[r][c] = 0.5 * ((if r == c { w } else { 0.0 }) - so[r][c]);
        }
    }
    (omega, mul_ab(&a, &r1t))
}

/// The world inverse inertia of frame `k` with tangent `d3`:
/// `w_q (I - d3 d3^T) + w_twist d3 d3^T`.
fn inverse_inertia(input: &DirectInput<'_>, k: usize, d3: D3) -> M3 {
    let (wb, wt) = (input.w_q[k] as f64, input.w_twist[k] as f64);
    std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let delta = if r == c { 1.0 } else { 0.0 };
            wb * delta + (wt - wb) * d3[r] * d3[c]
        })
    })
}

/// The inverse mass of vertex `i` as a matrix: `w I`, or
/// `w (I - CONTACT_LOCK n n^T)` when it touches a collider with normal `n`
/// (hardly any motion into or out of the surface during the solve).
fn vertex_mobility(input: &DirectInput<'_>, i: usize) -> M3 {
    let w = input.w[i] as f64;
    let lock = CONTACT_LOCK;
    let n = input
        .contact_normals
        .get(i)
        .map_or([0.0; 3], |n| [n[0] as f64, n[1] as f64, n[2] as f64]);
    std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let delta = if r == c { 1.0 } else { 0.0 };
            w * (delta - lock * n[r] * n[c])
        })
    })
}

/// `a v`.
fn mul_av(a: &M3, v: D3) -> D3 {
    std::array::from_fn(|r| (0..3).map(|i| a[r][i] * v[i]).sum())
}

/// Cholesky factor (lower) of a symmetric positive definite 6x6 block. A
/// non-positive pivot (only from non-finite input) gives a unit pivot so
/// the quarantine sees the NaN rather than a panic.
fn cholesky(a: &M6) -> M6 {
    let mut l = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                l[i][i] = if s > 0.0 { s.sqrt() } else { 1.0 };
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    l
}

fn chol_solve(l: &M6, b: &V6) -> V6 {
    let mut y = [0.0; 6];
    for i in 0..6 {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0; 6];
    for i in (0..6).rev() {
        let mut s = y[i];
        for k in i + 1..6 {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    x
}

fn tangent(q: [f64; 4]) -> D3 {
    let [x, y, z, w] = q;
    [
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        1.0 - 2.0 * (x * x + y * y),
    ]
}

fn rotation_matrix(q: [f64; 4]) -> M3 {
    let [x, y, z, w] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

fn qmul_d(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

fn conj_d(q: [f64; 4]) -> [f64; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

fn skew(v: D3) -> M3 {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

fn transpose(a: M3) -> M3 {
    std::array::from_fn(|r| std::array::from_fn(|c| a[c][r]))
}

fn mul_ab(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|i| a[r][i] * b[i][c]).sum()))
}

/// `a b^T`.
fn mul_abt(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|i| a[r][i] * b[c][i]).sum()))
}

/// `a^T v`.
fn mul_at_v(a: &M3, v: D3) -> D3 {
    std::array::from_fn(|c| (0..3).map(|i| a[i][c] * v[i]).sum())
}

fn dot3(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross3(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn scale3(a: D3, s: f64) -> D3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn add3(a: D3, b: D3) -> D3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub3(a: D3, b: D3) -> D3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
