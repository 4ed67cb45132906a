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
//! hold it are `Omega - A tau` with `A` the joints' flexibility (shape_memory.rs
//! `bend_flexibility`): the exact equilibrium of the discrete model.
//!
//! The bonds hold the result: every bond kind's memory moves by the same
//! offset, so the rest Darboux vector of (15) becomes the equilibrium one.
//! The memories are the hair's natural shape (what it would look like
//! without gravity); a set that is later washed out returns to it, i.e. to
//! the authored shape standing under gravity. The clamp at the root keeps
//! its own rest Darboux vector per strand (`RootAnchor::rest`).
//!
//! Standing is not always stable. The balance is exact (a step from it
//! moves a vertex by f32 round-off, 4e-8 m), but an exact equilibrium of
//! a long heavy rod can be unstable: an upright column buckles beyond
//! Greenhill's length `L_crit = (7.837 EI / w)^(1/3)` (9.5 cm for real
//! hair of 40 um), and a strand held out across gravity or curved needs a
//! strong natural curl (up to 240 /m, a 4 mm radius, for 24 cm of hair
//! held out 10 cm) whose plane gravity then turns over through the cheap
//! twist (`GJ` is about `EI / 1.3`). The start checks this by physics, not
//! by formula: `make_sag_free_checked` lets the solved strands stand alone
//! (no contacts, no hair-hair) for `PROBE_SECONDS` under the bake's solver
//! from a small push and names those that move `PROBE_DRIFT` or more. Only
//! strands longer than half their Greenhill length are probed: below it
//! `w L^3 / EI < 1`, an eighth of what buckles the most vulnerable shape.
//!
//! A strand that cannot stand is never left worse than without the start:
//! the probe gives it back its groomed rest shape (`probe_sag_free`), so
//! it sags exactly as with `sag_free = false`, and the warning names it.
//! The balance itself is bounded: no joint's rest shape changes by more
//! than `MAX_CHANGE` (a 60 degree turn), so the start writes no kink.
//!
//! Hair that rests on a collider at the start (within `SUPPORT_GAP` of the
//! head: the colliders of every stage and of the first stage, at time 0)
//! is not a cantilever: the surface takes the load that presses into it
//! and as much of the rest as its Coulomb friction holds, and the contacts
//! along the strand take the moment of the hair below; only what they
//! cannot hold goes on up the strand. The probe runs against the same
//! colliders.
//!
//! Stretch is not compensated: an edge carries at most the weight of its
//! strand, `rho A g L` (1.6e-5 N for 24 cm of real hair), against `E A`
//! of about 17.6 N, a strain of 1e-6; the report gives the largest tip
//! shift it makes.

use super::shape_memory::bend_flexibility;
use crate::sim::math::{self, V3};
use crate::sim::{ColliderSet, Environment, Model, SimError, Solver, SolverParameters, StrandSet};

/// The largest rest Darboux vector the start writes (`sin` of half the
/// turn at a joint: 0.95 is a 144 degree turn). A strand whose balance
/// needs more (long hair held out straight: a 24 cm real hair cannot stand
/// horizontal) is held as far as that allows and counted.
const MAX_REST: f64 = 0.95;

/// The largest change of a joint's rest Darboux vector the start makes
/// (a 60 degree turn): a balance that needs more is held that far, so the
/// start never writes a kink.
const MAX_CHANGE: f64 = 0.5;

/// How far from a collider's surface (beyond the fibre's radius) the start
/// counts a vertex as resting on it, metres: a groom's hair lies a few
/// millimetres off the scalp it was combed on (the generator keeps it 2 %
/// of the head's radius off, 1.6-2 mm), and falls that far onto it.
pub const SUPPORT_GAP: f32 = 5.0e-3;

/// How long the stability probe lets the solved strands stand, seconds.
pub const PROBE_SECONDS: f32 = 0.5;
/// The speed of the probe's push, m/s: a stable strand answers it with a
/// sway of about `PROBE_SPEED / omega` (0.2 mm for the slowest, a 24 cm
/// hair's pendulum at 5 rad/s); an unstable one grows by `exp(lambda t)`.
pub const PROBE_SPEED: f32 = 1.0e-3;
/// A probed strand that moves this far (metres) cannot stand alone.
pub const PROBE_DRIFT: f32 = 1.0e-3;

/// Greenhill's critical length of a heavy upright column clamped at its
/// base, `(7.837 EI / w)^(1/3)` with `EI = E pi r^4 / 4` and `w = rho pi
/// r^2 g`: metres, for Young's modulus `youngs` (Pa), fibre radius
/// `radius` (m), `density` (kg/m^3) and gravity `gravity` (m/s^2).
pub fn greenhill_length(youngs: f64, radius: f64, density: f64, gravity: f64) -> f64 {
    (7.837 * youngs * radius * radius / (4.0 * density * gravity)).cbrt()
}

/// What the sag-free start did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SagFreeReport {
    /// Strands whose rest shape was solved.
    pub strands: usize,
    /// Joints whose balance needed a turn beyond `MAX_REST` (clamped).
    pub clamped_joints: usize,
    /// Strands whose balance needed a joint's rest shape to change by
    /// more than `MAX_CHANGE`: held as far as that allows.
    pub limited: Vec<usize>,
    /// Joints left as they were because no bond holds them (all broken).
    pub unheld_joints: usize,
    /// The largest tip shift the weight's stretch of the edges makes,
    /// metres (not compensated; negligible for hair).
    pub max_stretch: f64,
    /// Strands that moved `PROBE_DRIFT` or more standing alone for
    /// `PROBE_SECONDS` (only filled by the probe: `make_sag_free_checked`,
    /// `probe_sag_free`).
    pub unstable: Vec<usize>,
    /// The rest shape each solved strand had before the start changed it,
    /// for the probe to give back to the strands that cannot stand.
    groomed: Vec<GroomedRest>,
}

/// One strand's rest shape as groomed: the clamp's and every joint's bond
/// memories.
#[derive(Debug, Clone, PartialEq)]
struct GroomedRest {
    strand: usize,
    root: [f32; 3],
    memories: Vec<[V3; 4]>,
}

impl SagFreeReport {
    /// The TD's one line about the strands that cannot stand as groomed,
    /// or `None` when all can.
    pub fn warning(&self) -> Option<String> {
        let first: Vec<String> = self
            .unstable
            .iter()
            .take(8)
            .map(|s| s.to_string())
            .collect();
        (!self.unstable.is_empty()).then(|| {
            format!(
                "sag-free: {} of {} strands cannot stand as groomed as lone hairs (strands {}{}): balanced, they move {} mm or more within {} s under gravity, so they start from their groomed rest shape and sag as with sag_free = false; thicker or stiffer hair ([material] radius, youngs_modulus), a shorter reach, hair-hair friction ([solver] hair_hair.friction) or a [material] hold keep them",
                self.unstable.len(),
                self.strands,
                first.join(", "),
                if self.unstable.len() > first.len() { ", ..." } else { "" },
                PROBE_DRIFT * 1e3,
                PROBE_SECONDS
            )
        })
    }
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
    super::direct::segment_mass(density, r0 as f64, r1 as f64, length)
}

impl StrandSet {
    /// Solves every simulated strand's rest shape so that its current shape
    /// is in static equilibrium under `gravity` (m/s^2) with the root
    /// clamped. Physical model only (the paper's model has no weight in
    /// real units): with `model = "paper"` nothing changes.
    pub fn make_sag_free(&mut self, gravity: [f32; 3]) -> SagFreeReport {
        self.make_sag_free_supported(gravity, &ColliderSet::new(), 0.0)
    }

    /// [`Self::make_sag_free`] where the hair that rests on `colliders` (within
    /// `SUPPORT_GAP` of a surface, for fibres of `radius`) is held by them.
    pub fn make_sag_free_supported(
        &mut self,
        gravity: [f32; 3],
        colliders: &ColliderSet,
        radius: f32,
    ) -> SagFreeReport {
        let mut report = SagFreeReport::default();
        if self.material.model != Model::Physical {
            return report;
        }
        let prepared = colliders.prepare(radius + SUPPORT_GAP);
        // The outward normal and friction of the surface a vertex rests on.
        let support = |p: V3| {
            if prepared.is_empty() {
                return None;
            }
            let contact = crate::sim::contact::colliders::project_contact(
                &prepared,
                p,
                None,
                radius + SUPPORT_GAP,
                0.0,
            );
            contact.normal.map(|n| (d3(n), contact.friction as f64))
        };
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
            // The force edge k carries: the weight of the vertices below
            // it less what surfaces hold of it.
            let mut force = [0.0f64; 3];
            let mut torque = [0.0f64; 3];
            let mut stretch = 0.0f64;
            for k in (0..m).rev() {
                let r = &self.radii[first + k..];
                // Vertex k + 1 gets half of edges k and k + 1.
                let mut mass = 0.5 * segment_mass(density, r[0], r[1], lengths[k] as f64);
                if k + 1 < m {
                    mass += 0.5 * segment_mass(density, r[1], r[2], lengths[k + 1] as f64);
                }
                force = std::array::from_fn(|i| force[i] + g[i] * mass);
                // A vertex resting on a surface hands it the load that
                // presses into it, and as much of the rest as Coulomb's
                // friction holds; the contacts along the rest take the
                // moment of the hair below (a strand lying on the head is
                // not a cantilever). What they cannot hold goes on up the
                // strand as tension.
                if let Some((n, mu)) = support(self.positions[first + k + 1]) {
                    let pressing = dot(force, n);

                    if pressing < 0.0 {
                        let tangential: D3 = std::array::from_fn(|i| force[i] - pressing * n[i]);
                        let size = dot(tangential, tangential).sqrt();
                        let kept = if size > 0.0 {
                            (1.0 - mu * -pressing / size).max(0.0)
                        } else {
                            0.0
                        };
                        force = tangential.map(|t| t * kept);
                        torque = [0.0; 3];
                    }
                }
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
            report.groomed.push(GroomedRest {
                strand,
                root: self.roots[strand].rest,
                memories: self.joints[first..end].iter().map(|j| j.memories).collect(),
            });
            // Rest = Omega - A tau, A tridiagonal over the joints.
            let mut limited = false;
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
                // A bounded change: where the balance needs more, the
                // strand is held as far as it allows and counted.
                let change: D3 = std::array::from_fn(|i| rest[i] - scratch.omega[k][i]);
                let size = dot(change, change).sqrt();
                if size > MAX_CHANGE {
                    rest = std::array::from_fn(|i| {
                        scratch.omega[k][i] + change[i] * MAX_CHANGE / size
                    });
                    limited = true;
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
            if limited {
                report.limited.push(strand);
            }
            report.strands += 1;
        }
        report
    }

    /// `make_sag_free` under `parameters.gravity`, then the stability probe
    /// (module doc) with the bake's time step, iterations and damping.
    pub fn make_sag_free_checked(
        &mut self,
        parameters: &SolverParameters,
    ) -> Result<SagFreeReport, SimError> {
        self.make_sag_free_with(parameters, &ColliderSet::new())
    }

    /// The sag-free start on hair that rests on `colliders` (their poses at
    /// the start: the head), then the stability probe against them.
    pub fn make_sag_free_with(
        &mut self,
        parameters: &SolverParameters,
        colliders: &ColliderSet,
    ) -> Result<SagFreeReport, SimError> {
        let mut report =
            self.make_sag_free_supported(parameters.gravity, colliders, parameters.hair_radius);
        self.probe_sag_free(parameters, colliders, &mut report)?;
        Ok(report)
    }

    /// The stability probe alone, on strands `make_sag_free` solved (its
    /// `report`): a simulation of `PROBE_SECONDS`, so the bake runs it and
    /// `validate`, which simulates nothing, does not. The strands that
    /// cannot stand get their groomed rest shape back: they start as with
    /// `sag_free = false`, so the start never leaves a strand worse off.
    pub fn probe_sag_free(
        &mut self,
        parameters: &SolverParameters,
        colliders: &ColliderSet,
        report: &mut SagFreeReport,
    ) -> Result<(), SimError> {
        if report.strands == 0 {
            return Ok(());
        }
        report.unstable = self.unstable_standing(parameters, colliders)?;
        for groomed in &report.groomed {
            if report.unstable.binary_search(&groomed.strand).is_err() {
                continue;
            }
            self.roots[groomed.strand].rest = groomed.root;
            let first = self.offsets[groomed.strand];
            for (joint, memories) in self.joints[first..].iter_mut().zip(&groomed.memories) {
                joint.memories = *memories;
            }
        }
        report.groomed = Vec::new();
        Ok(())
    }

    /// The probe: a copy of the strands longer than half their Greenhill
    /// length stands alone for `PROBE_SECONDS` after a push of
    /// `PROBE_SPEED` on every free vertex; the strands that move
    /// `PROBE_DRIFT` or more, in order.
    fn unstable_standing(
        &self,
        parameters: &SolverParameters,
        colliders: &ColliderSet,
    ) -> Result<Vec<usize>, SimError> {
        let g = d3(parameters.gravity);
        let g = dot(g, g).sqrt();
        if g == 0.0 {
            return Ok(Vec::new());
        }
        let mut probe = self.clone();
        let push = PROBE_SPEED / 3.0f32.sqrt();
        let mut probed = Vec::new();
        for strand in 0..self.strand_count() {
            if !self.simulated[strand] || self.frozen[strand] {
                continue;
            }
            let (first, end) = (self.offsets[strand], self.offsets[strand + 1]);
            let length: f64 = self.edges[first..end - 1]
                .iter()
                .map(|e| e.rest_length as f64)
                .sum();
            let radius = self.radii[first..end]
                .iter()
                .map(|r| *r as f64)
                .sum::<f64>()
                / (end - first) as f64;
            // The weakest modulus along the strand (the cuticle's gradient).
            let cuticle = self.joints[first + 1..end - 1]
                .iter()
                .map(|j| j.cuticle as f64)
                .fold(1.0, f64::min);
            let critical = greenhill_length(
                self.material.youngs_modulus as f64 * cuticle,
                radius,
                self.material.density as f64,
                g,
            );
            if length < 0.5 * critical {
                probe.simulated[strand] = false;
                continue;
            }
            probed.push(strand);
            for v in &mut probe.velocities[first + 1..end] {
                *v = [push; 3];
            }
        }
        if probed.is_empty() {
            return Ok(probed);
        }
        let lone = SolverParameters {
            hair_hair_strength: None,
            volumetric: None,
            ..*parameters
        };
        let mut solver = Solver::new(lone)?;
        let start = probe.positions.clone();
        let mut moved = vec![false; self.strand_count()];
        for _ in 0..(PROBE_SECONDS / lone.dt).ceil() as usize {
            solver.step(&mut probe, colliders, &Environment::default())?;
            for &strand in &probed {
                let range = probe.offsets[strand]..probe.offsets[strand + 1];
                moved[strand] |= range
                    .into_iter()
                    .any(|v| math::length(math::sub(probe.positions[v], start[v])) >= PROBE_DRIFT);
            }
        }
        Ok(probed.into_iter().filter(|s| moved[*s]).collect())
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
