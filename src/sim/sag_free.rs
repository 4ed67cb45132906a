//! Sag-free start (Hsu, Wang, Wu, Yuksel 2023; METHOD H): the groom as
//! authored is the shape the TD wants to see under gravity, so before the
//! first step the rest shape is solved so that the groomed shape is in
//! static equilibrium under gravity with its roots clamped (contacts are
//! ignored). Physical model only.
//!
//! For a strand with a clamped root the balance is explicit, one sweep
//! from the tip (linear in the vertices): edge `k` carries the weight of
//! the vertices below it, `F_k = g sum_{i>k} m_i`, and the torque joint `k`
//! must put on frame `k` is `T_k = T_{k+1} + (p_{k+1} - p_k) x F_k` (the
//! moment of the hair below). The joint's generalised force on its Darboux
//! vector follows from `G_k^T tau_k = T_k` (`G` the derivative of the
//! Darboux vector, as in direct.rs), and the rest Darboux vectors that
//! hold it are `Omega - A tau` with `A` the joints' flexibility (step.rs
//! `bend_flexibility`): the exact equilibrium of the discrete model.
//!
//! The bonds hold the result: every bond kind's memory moves by the same
//! offset, so the rest Darboux vector of (15) becomes the equilibrium one.
//! The memories are the hair's natural shape (what it would look like
//! without gravity); a set that is later washed out returns to it, i.e. to
//! the authored shape standing under gravity. The clamp at the root keeps
//! its own rest Darboux vector per strand (`RootAnchor::rest`).
//!
//! Stretch is not compensated: an edge carries at most the weight of its
//! strand, `rho A g L` (1.6e-5 N for 24 cm of real hair), against `E A`
//! of about 17.6 N, a strain of 1e-6; the report gives the largest tip
//! shift it makes.

use super::math::{self, V3};
use super::step::bend_flexibility;
use super::{Model, StrandSet};

/// The largest rest Darboux vector the start writes (`sin` of half the
/// turn at a joint: 0.95 is a 144 degree turn). A strand whose balance
/// needs more (long hair held out straight: a 24 cm real hair cannot stand
/// horizontal) is held as far as that allows and counted.
const MAX_REST: f64 = 0.95;

/// What the sag-free start did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SagFreeReport {
    /// Strands whose rest shape was solved.
    pub strands: usize,
    /// Joints whose balance needed a turn beyond `MAX_REST` (clamped).
    pub clamped_joints: usize,
    /// Joints left as they were because no bond holds them (all broken).
    pub unheld_joints: usize,
    /// The largest tip shift the weight's stretch of the edges makes,
    /// metres (not compensated; negligible for hair).
    pub max_stretch: f64,
}

type D3 = [f64; 3];

fn d3(v: V3) -> D3 {
    [v[0] as f64, v[1] as f64, v[2] as f64]
}

fn cross(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `R(q)^T v`: a world vector in the frame's material axes.
fn to_material(q: [f32; 4], v: D3) -> D3 {
    let conj = [-q[0], -q[1], -q[2], q[3]];
    d3(math::rotate(conj, [v[0] as f32, v[1] as f32, v[2] as f32]))
}

/// The mass `rho A l` of an edge whose end vertices have fibre radii `r0`,
/// `r1` (the physical model lumps half to each end).
pub(crate) fn segment_mass(density: f64, r0: f32, r1: f32, length: f64) -> f64 {
    let r = 0.5 * (r0 as f64 + r1 as f64);
    density * std::f64::consts::PI * r * r * length
}

impl StrandSet {
    /// Solves every simulated strand's rest shape so that its current shape
    /// is in static equilibrium under `gravity` (m/s^2) with the root
    /// clamped. Physical model only (the paper's model has no weight in
    /// real units): with `model = "paper"` nothing changes.
    pub fn make_sag_free(&mut self, gravity: [f32; 3]) -> SagFreeReport {
        let mut report = SagFreeReport::default();
        if self.material.model != Model::Physical {
            return report;
        }
        let g = d3(gravity);
        let density = self.material.density as f64;
        let youngs = self.material.youngs_modulus as f64;
        let shear = self.material.shear_modulus() as f64;
        let mut scratch = Scratch::default();
        for strand in 0..self.strand_count() {
            if !self.simulated[strand] || self.frozen[strand] {
                continue;
            }
            let (first, end) = (self.offsets[strand], self.offsets[strand + 1]);
            let n = end - first;
            let m = n - 1;
            scratch.resize(m);
            let lengths: Vec<f32> = self.edges[first..end - 1]
                .iter()
                .map(|e| e.rest_length)
                .collect();
            bend_flexibility(
                youngs,
                shear,
                &lengths,
                &self.radii[first..end],
                &self.joints[first..end],
                &mut scratch.compliance,
            );
            // From the tip: the weight below each edge and the torque on
            // each frame; then the joint's force on its Darboux vector.
            let mut below = 0.0f64; // mass of the vertices below edge k
            let mut torque = [0.0f64; 3];
            let mut stretch = 0.0f64;
            for k in (0..m).rev() {
                let r = &self.radii[first + k..];
                // Vertex k + 1 gets half of edges k and k + 1.
                below += 0.5 * segment_mass(density, r[0], r[1], lengths[k] as f64);
                if k + 1 < m {
                    below += 0.5 * segment_mass(density, r[1], r[2], lengths[k + 1] as f64);
                }
                let force = [g[0] * below, g[1] * below, g[2] * below];
                let edge = d3(math::sub(
                    self.positions[first + k + 1],
                    self.positions[first + k],
                ));
                let c = cross(edge, force);
                torque = [torque[0] + c[0], torque[1] + c[1], torque[2] + c[2]];
                // The edge lengthens by (d3 . F) l / (E A) = (edge . F) / (E A).
                let r = 0.5 * (r[0] as f64 + r[1] as f64);
                let area = std::f64::consts::PI * r * r;
                stretch += dot(edge, force).abs() / (youngs * area);
                // G^T tau = T with G = 1/2 (w I - [Omega]x) R1^T:
                // tau = 2 (w I + [Omega]x)^-1 R1^T T.
                let before = if k == 0 {
                    self.roots[strand].frame
                } else {
                    self.edges[first + k - 1].rotation
                };
                let q = self.edges[first + k].rotation;
                let (omega, w) = math::canonical_darboux(
                    math::darboux(before, q),
                    math::darboux_real(before, q),
                );
                let (omega, w) = (d3(omega), w as f64);
                let y = to_material(before, torque);
                // (w I + [Omega]x)^-1 y = (w^2 y - w Omega x y + (Omega.y) Omega) / w
                // for a unit quaternion (w, Omega), w > 0.
                let oy = cross(omega, y);
                let od = dot(omega, y);
                let w = w.max(1e-6);
                scratch.tau[k] =
                    std::array::from_fn(|i| 2.0 * (w * w * y[i] - w * oy[i] + od * omega[i]) / w);
                scratch.omega[k] = omega;
            }
            report.max_stretch = report.max_stretch.max(stretch);
            // Rest = Omega - A tau, A tridiagonal over the joints.
            for k in 0..m {
                let c = &scratch.compliance[k];
                let diag = [c.bend, c.bend, c.twist];
                let next = [c.bend_next, c.bend_next, c.twist_next];
                let before = k
                    .checked_sub(1)
                    .map(|b| &scratch.compliance[b])
                    .map_or([0.0; 3], |b| [b.bend_next, b.bend_next, b.twist_next]);
                let mut rest = scratch.omega[k];
                for i in 0..3 {
                    let mut a_tau = diag[i] * scratch.tau[k][i];
                    if k + 1 < m {
                        a_tau += next[i] * scratch.tau[k + 1][i];
                    }
                    if k > 0 {
                        a_tau += before[i] * scratch.tau[k - 1][i];
                    }
                    rest[i] -= a_tau;
                }
                let size = dot(rest, rest).sqrt();
                if size > MAX_REST {
                    rest = rest.map(|v| v * MAX_REST / size);
                    report.clamped_joints += 1;
                }
                scratch.rest[k] = rest;
            }
            self.roots[strand].rest = scratch.rest[0].map(|v| v as f32);
            for k in 1..m {
                if !self.hold_rest(first + k, scratch.rest[k]) {
                    report.unheld_joints += 1;
                }
            }
            report.strands += 1;
        }
        report
    }

    /// Moves every bond memory of joint `j` by one offset so that the rest
    /// Darboux vector of (15) becomes `rest` (the offset divided by the
    /// bonded share `sum f_k b_k`). False if no bond holds the joint.
    fn hold_rest(&mut self, j: usize, rest: D3) -> bool {
        let (q1, q2) = (self.edges[j - 1].rotation, self.edges[j].rotation);
        let omega = math::darboux(q1, q2);
        let w = math::darboux_real(q1, q2);
        let joint = &mut self.joints[j];
        let bonded: f64 = joint
            .rates
            .iter()
            .zip(&self.influences)
            .map(|(b, f)| (*b as f64) * (*f as f64))
            .sum();
        if bonded < 1e-6 {
            return false;
        }
        let now = d3(super::bonds::rest_darboux(
            omega,
            w,
            &joint.rates,
            &joint.memories,
            &self.influences,
        ));
        let (canonical, cw) = math::canonical_darboux(omega, w);
        for memory in &mut joint.memories {
            // A memory is used with the sign nearest the current shape (the
            // double cover): move it in that representative.
            let s = math::double_cover_sign(canonical, cw, *memory) as f64;
            for i in 0..3 {
                memory[i] += (s * (rest[i] - now[i]) / bonded) as f32;
            }
        }
        true
    }
}

#[derive(Default)]
struct Scratch {
    compliance: Vec<super::direct::EdgeCompliance>,
    tau: Vec<D3>,
    omega: Vec<D3>,
    rest: Vec<D3>,
}

impl Scratch {
    fn resize(&mut self, m: usize) {
        self.compliance.clear();
        self.compliance
            .resize(m, super::direct::EdgeCompliance::default());
        for v in [&mut self.tau, &mut self.omega, &mut self.rest] {
            v.clear();
            v.resize(m, [0.0; 3]);
        }
    }
}
