//! The hair solver of `000_*` (shared/METHOD.md A-D): position- and
//! orientation-based Cosserat rods (PBD) whose rest shape comes from four
//! kinds of side-chain bonds that break and re-form (plasticity).
//!
//! No I/O here. The caller (the timeline) owns a [`StrandSet`] (all state),
//! a [`ColliderSet`] and fills an [`Environment`] per step; a [`Solver`]
//! owns only scratch memory and advances the strands by one step.
//!
//! Layout and conventions:
//! - Metres, seconds, Y up. A strand's vertex 0 is its root.
//! - Edge `e` of a strand (from vertex `e` to `e + 1`) is stored in the slot
//!   of vertex `e`; the tip's slot is unused.
//! - Joint `j` (between edges `j - 1` and `j`, the bend at vertex `j`) is
//!   stored in the slot of vertex `j`; root and tip slots are unused.
//! - Masses (physical model, the default): a vertex lumps half of each
//!   adjacent edge's mass `rho pi r^2 l` (the density, the cross-section at
//!   the mean fibre radius of its ends, the rest length), and the frame of
//!   edge `e` has the inertia of its segment, `m (l^2 / 12 + r^2 / 4)`
//!   across the tangent (with a floor) and `m r^2 / 2` about it (METHOD H,
//!   rod/direct/constants.rs). The paper model keeps the paper's unit
//!   masses: inverse mass 1 for a vertex, `quaternion_mass_scale / l_e^2`
//!   for the frame of edge `e` (METHOD G). In both the root vertex and the
//!   root edge's frame are fixed to the scalp.
//! - Per-step order (METHOD D): forces and bond-rate changes, rest shape
//!   (15), `iterations` x (stretch/shear, bend/twist, collisions), one
//!   Follow-The-Leader pass, final collision pass, velocities, bond update
//!   (17). The physical model's Newton iterations stop early for a strand
//!   whose edges are within `SolverParameters::tolerance` (and its constants,
//!   masses and compliances, are found in the solve's lanes, rod/direct/).
//!   With pairwise hair-hair and `hair_friction` (physical model) the
//!   contacts between strands are found at the start of the step and
//!   solved with the collider contacts, Coulomb friction included, each
//!   strand against the others as kinematic targets (contact/hair_friction.rs).
//!   Strands run in parallel in groups of four or eight (SIMD lanes); every
//!   strand's arithmetic is the same in any group, so results are
//!   bit-identical for any thread count.
//! - Before the first step the caller may solve the sag-free rest shape
//!   (`StrandSet::make_sag_free`, rod/sag_free.rs): the groom then stands still
//!   under gravity (physical model), except strands a lone hair cannot
//!   hold, which `make_sag_free_checked` names.
//! - With a hold ([`Environment::hold`], forces/hold.rs: off unless asked for)
//!   every free vertex is pulled toward its groomed position, carried with
//!   the scalp, by an implicit spring folded into its prediction and its
//!   inverse mass in the solve.
//! - The state's velocity is the real one, `(x_new - x_old) / dt`; the
//!   Follow-The-Leader correction (paper model) is kept apart and applied
//!   to the next prediction only.
//!
//! Where things are: step.rs is the pipeline of a step (its phases named,
//! each calling into a room, on the working copy of work.rs); `rod/` holds
//! what acts within one strand (constraints and their SIMD lanes, the
//! physical model's direct solve, the bonds, the sag-free start); `contact/`
//! what a strand touches (colliders, other strands pairwise or through the
//! hair's volume, friction); `forces/` the outside forces (gravity and drag
//! in the prediction, the blower, the hold). Beside them: the state
//! (state.rs), its rest pose (rest_pose.rs), the containment of strands
//! that blow up (quarantine.rs), the choice of CPU instructions
//! (instructions.rs, avx.rs) and the small vector algebra (math.rs).
//!
//! ```
//! use groombake::sim::*;
//! let groom = bench_groom(8, 12).unwrap();
//! let mut strands = StrandSet::from_groom(&groom, &Material::default()).unwrap();
//! let mut solver = Solver::new(SolverParameters::default()).unwrap();
//! let colliders = ColliderSet::new();
//! // Wet: hydrogen bonds break at 10 per second.
//! let wet = Environment { bond_rate_drive: [-10.0, 0.0, 0.0, 0.0], ..Environment::default() };
//! for _ in 0..60 {
//!     let report = solver.step(&mut strands, &colliders, &wet).unwrap();
//!     assert!(report.contained.is_empty());
//! }
//! assert!(strands.bond_rates(BondKind::Hydrogen).iter().all(|b| *b == 0.0));
//! let rest = strands.rest_pose();
//! assert_eq!(rest.len(), strands.vertex_count());
//! ```

mod avx;
pub(crate) mod contact;
mod forces;
#[cfg(test)]
mod group_tests;
mod instructions;
mod math;
mod quarantine;
mod rest_pose;
mod rod;
mod state;
mod step;
#[cfg(test)]
mod tests;
mod work;

/// A fixed sequence of numbers in `[0, 1)` for tests (xorshift64*: no
/// dependency), from `seed` (not zero).
#[cfg(test)]
pub(crate) fn test_sequence(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        let bits = state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40;
        bits as f32 / (1u64 << 24) as f32
    }
}

pub use contact::colliders::{Collider, ColliderSet};
pub use contact::volume::Volumetric;
pub use forces::blower::blower_reach;
pub use forces::hold::Hold;
pub use instructions::Instructions;
pub use parry3d;
pub use parry3d::math::Pose;
pub use quarantine::{
    contain_blowups, contain_blowups_watching, unsimulated_strands, Blowup, StrainWatch,
    MAX_STRAIN, WARN_STRAIN,
};
pub use rod::sag_free::SagFreeReport;
pub use state::{attribute_names, StrandSet};
pub use step::Solver;

use serde::{Deserialize, Serialize};

/// The four kinds of side-chain bonds (000 §5.1), in storage order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BondKind {
    /// Broken by water, re-forms on drying (bed hair).
    Hydrogen,
    /// Broken by a pH change (shampoo, styling products).
    Ionic,
    /// Broken chemically by perm lotion.
    Disulfide,
    /// Never breaks in practice.
    Peptide,
}

impl BondKind {
    pub const ALL: [BondKind; 4] = [
        BondKind::Hydrogen,
        BondKind::Ionic,
        BondKind::Disulfide,
        BondKind::Peptide,
    ];

    /// Index into the per-kind arrays (`[f32; 4]`).
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            BondKind::Hydrogen => "hydrogen",
            BondKind::Ionic => "ionic",
            BondKind::Disulfide => "disulfide",
            BondKind::Peptide => "peptide",
        }
    }
}

/// Which elastic model the rods use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Model {
    /// Real units (METHOD H): masses from density, compliant (XPBD)
    /// stretch/shear and bend/twist from Young's and shear moduli, solved
    /// per strand by a direct block-tridiagonal solve. The result converges
    /// as edges shrink and `dt` falls.
    #[default]
    Physical,
    /// The paper's PBD model (000 §4): unit vertex masses, stiffness as the
    /// fraction `k_o`, Gauss-Seidel iterations and Follow-The-Leader. Kept to
    /// reproduce Table 1; the result depends on edge length and `dt`.
    Paper,
}

impl Model {
    /// Iterations per step when the timeline does not say. The paper's
    /// Table 1 uses 5 Gauss-Seidel sweeps. The physical model's iteration
    /// is an exact solve of the linearised system, and by default a strand
    /// stops as soon as its edges are within [`Model::default_tolerance`]
    /// (free and hanging hair after one iteration: the cantilever and
    /// frequency tests hold at one, within 1.2 % of the elastica at 8-32
    /// edges and dt 1/120-1/1000); two is the most a strand gets, which
    /// hair whipping onto the head needs to keep its edges' length.
    pub fn default_iterations(self) -> u32 {
        match self {
            Model::Physical => 2,
            Model::Paper => 5,
        }
    }

    /// The Newton tolerance when the timeline sets neither `iterations`
    /// nor `tolerance` (`SolverParameters::tolerance`): a tenth of a
    /// percent of each edge for the physical model; the paper model's
    /// sweeps always run all.
    pub fn default_tolerance(self) -> f32 {
        match self {
            Model::Physical => DEFAULT_TOLERANCE,
            Model::Paper => 0.0,
        }
    }
}

/// See [`Model::default_tolerance`].
pub const DEFAULT_TOLERANCE: f32 = 1e-3;

/// The hair material (000 Table 1 and METHOD H).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    pub model: Model,
    /// `k_o`, the bend/twist stiffness of healthy hair, in [0, 1] (paper
    /// model only).
    pub stiffness: f32,
    /// Young's modulus `E`, Pa (physical model).
    pub youngs_modulus: f32,
    /// Shear modulus `G`, Pa; `None`: `E / (2 (1 + poisson_ratio))`.
    pub shear_modulus: Option<f32>,
    /// Poisson ratio, for `G` when `shear_modulus` is not given.
    pub poisson_ratio: f32,
    /// Density, kg/m^3.
    pub density: f32,
    /// Fibre radius, metres; `None`: half the groom's `width` attribute
    /// where it has one, else 40 um.
    pub radius: Option<f32>,
    /// The cuticle peel rate `s` of (14), per metre of arc length from the
    /// root (0.33 %/cm = 0.33 /m).
    pub cuticle_peel_per_meter: f32,
    /// Influences `f_j` of hydrogen, ionic, disulfide and peptide bonds
    /// (fractions of the restoring force when fully bonded; normalised by
    /// their sum).
    pub bond_influences: [f32; 4],
}

/// The fibre radius when neither the material nor the groom gives one.
pub const DEFAULT_RADIUS: f32 = 4.0e-5;

impl Default for Material {
    fn default() -> Self {
        Material {
            model: Model::Physical,
            stiffness: 0.05,
            youngs_modulus: 3.5e9,
            shear_modulus: None,
            poisson_ratio: 0.3,
            density: 1300.0,
            radius: None,
            cuticle_peel_per_meter: 0.33,
            // Table 1, scene 3, with the paper's 63% of hydrogen + ionic split
            // 0.35 / 0.28 (ours to choose, METHOD E/G).
            bond_influences: [0.35, 0.28, 0.20, 0.17],
        }
    }
}

/// `k_cut = 0.5764 k_o`: the cuticle's share of bending stiffness (13).
pub const CUTICLE_SHARE: f32 = 0.5764;

impl Material {
    pub fn check(&self) -> Result<(), SimError> {
        let fail = |name: &'static str, message: &str| {
            Err(SimError::Parameter {
                name,
                message: message.to_string(),
            })
        };
        if !(self.stiffness.is_finite() && (0.0..=1.0).contains(&self.stiffness)) {
            return fail("stiffness", "must be in [0, 1]");
        }
        if !(self.youngs_modulus.is_finite() && self.youngs_modulus > 0.0) {
            return fail("youngs_modulus", "must be a positive pressure in Pa");
        }
        if let Some(g) = self.shear_modulus {
            if !(g.is_finite() && g > 0.0) {
                return fail("shear_modulus", "must be a positive pressure in Pa");
            }
        }
        if !(self.poisson_ratio.is_finite() && (-0.99..=0.5).contains(&self.poisson_ratio)) {
            return fail("poisson_ratio", "must be in [-0.99, 0.5]");
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return fail("density", "must be a positive density in kg/m^3");
        }
        if let Some(r) = self.radius {
            if !(r.is_finite() && r > 0.0 && r < 0.01) {
                return fail("radius", "must be a length in (0, 0.01) metres");
            }
        }
        if !(self.cuticle_peel_per_meter.is_finite() && self.cuticle_peel_per_meter >= 0.0) {
            return fail("cuticle_peel_per_meter", "must be a non-negative number");
        }
        if self
            .bond_influences
            .iter()
            .any(|f| !(f.is_finite() && *f >= 0.0))
        {
            return fail("bond_influences", "must be non-negative numbers");
        }
        if self.bond_influences.iter().sum::<f32>() <= 0.0 {
            return fail("bond_influences", "must not all be zero");
        }
        Ok(())
    }

    /// `k` at arc length `d` from the root, (13)-(14).
    pub fn stiffness_at(&self, arc_length: f32) -> f32 {
        let sd = self.cuticle_peel_per_meter * arc_length;
        let c = if sd < 1.0 { 1.0 - sd } else { 0.0 };
        self.stiffness - CUTICLE_SHARE * self.stiffness * (1.0 - c)
    }

    /// The share of the healthy modulus left at arc length `d` from the
    /// root, (13)-(14): the cuticle gradient of the physical model.
    pub fn cuticle_factor(&self, arc_length: f32) -> f32 {
        let sd = self.cuticle_peel_per_meter * arc_length;
        let c = if sd < 1.0 { 1.0 - sd } else { 0.0 };
        1.0 - CUTICLE_SHARE * (1.0 - c)
    }

    /// `G`, Pa.
    pub fn shear_modulus(&self) -> f32 {
        self.shear_modulus
            .unwrap_or(self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio)))
    }

    /// The influences divided by their sum.
    pub fn normalized_influences(&self) -> [f32; 4] {
        let total: f32 = self.bond_influences.iter().sum();
        self.bond_influences.map(|f| f / total)
    }
}

/// How edge lengths are kept exactly (METHOD G: plain Gauss-Seidel PBD
/// stretches under gravity).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Inextensibility {
    /// Only the stretch/shear constraint (the papers' method).
    Off,
    /// After the constraint iterations, one root-to-tip Follow-The-Leader
    /// pass (Mueller, Kim, Chentanez 2012) restores every rest length; the
    /// velocity of vertex `i` is corrected by `-velocity_correction *
    /// d_{i+1} / dt` (their DFTL) so the pass does not damp motion.
    FollowTheLeader { velocity_correction: f32 },
}

impl Default for Inextensibility {
    fn default() -> Self {
        Inextensibility::FollowTheLeader {
            velocity_correction: 0.9,
        }
    }
}

/// The physical model's time integrator (docs/model.md "Time
/// integration").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Backward Euler (the default): the solve balances the forces at the
    /// step's end. Stable and exact in statics, but it damps a mode of
    /// angular frequency `w` by about `exp(-pi w dt)` a cycle by itself.
    #[default]
    BackwardEuler,
    /// A backward-Euler half step, then the state extrapolated to the
    /// step's end (the implicit midpoint rule) with the stiff modes
    /// projected and the extrapolation smoothed along the strand
    /// (rod/midpoint.rs): second order, with little damping of the slow
    /// modes. A strand the extrapolation is not safe for this step (near
    /// a collider, held, blown, touching hair, its root moved, edges too
    /// fine for the `dt`, turning fast) takes backward Euler's step.
    Midpoint,
}

/// Solver settings (000 Table 1 and METHOD G).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverParameters {
    /// Time step, seconds.
    pub dt: f32,
    /// Constraint iterations per step (`n` of (12)); with a `tolerance`
    /// (physical model), the most a strand gets.
    pub iterations: u32,
    /// The physical model's Newton tolerance: a strand stops iterating
    /// once every edge's stretch/shear residual `|p_{k+1} - p_k - l d3|`
    /// is within this fraction of its rest length (checked after each
    /// iteration but the last). 0 runs all `iterations`. Range 0 - 0.01.
    pub tolerance: f32,
    /// Gravity, m/s^2.
    pub gravity: [f32; 3],
    /// Hair radius `r`, metres: collision offset and hair-hair distance.
    pub hair_radius: f32,
    /// `alpha` of the hair-hair penalty (20); `None` switches it off.
    pub hair_hair_strength: Option<f32>,
    /// Coulomb friction coefficient between hairs (pairwise hair-hair,
    /// physical model; 0 - 1, 0.05 - 0.5 for real hair): with it, each
    /// contact between edges of two strands keeps them two radii apart and
    /// sticks or slides by Coulomb's law inside the solve (contact/hair_friction.rs).
    /// `None` (or 0): the penalty (20) alone.
    pub hair_friction: Option<f32>,
    /// Volumetric hair-hair for dense grooms (see [`Volumetric`]); when
    /// set, it replaces the pairwise penalty.
    pub volumetric: Option<Volumetric>,
    /// Velocity damping, per second (`v *= exp(-c dt)` each step).
    pub linear_damping: f32,
    /// Angular velocity damping, per second.
    pub angular_damping: f32,
    /// `w_q = scale * w_p / l^2` for each edge frame.
    pub quaternion_mass_scale: f32,
    pub inextensibility: Inextensibility,
    /// The physical model's time integrator (docs/model.md "Time
    /// integration"; `[solver] integrator`, which the paper model refuses:
    /// its step is the paper's).
    pub integrator: Integrator,
}

impl Default for SolverParameters {
    fn default() -> Self {
        SolverParameters {
            dt: 1.0 / 360.0,
            iterations: 5,
            tolerance: 0.0,
            gravity: [0.0, -9.8, 0.0],
            hair_radius: 4.0e-5,
            hair_hair_strength: None,
            hair_friction: None,
            volumetric: None,
            linear_damping: 2.0,
            angular_damping: 2.0,
            quaternion_mass_scale: 1.0,
            inextensibility: Inextensibility::default(),
            integrator: Integrator::default(),
        }
    }
}

impl SolverParameters {
    pub fn check(&self) -> Result<(), SimError> {
        let fail = |name: &'static str, message: &str| {
            Err(SimError::Parameter {
                name,
                message: message.to_string(),
            })
        };
        if !(self.dt.is_finite() && self.dt > 0.0 && self.dt <= 1.0) {
            return fail("dt", "must be in (0, 1] seconds");
        }
        if self.iterations == 0 || self.iterations > 1000 {
            return fail("iterations", "must be between 1 and 1000");
        }
        if !(self.tolerance.is_finite() && (0.0..=0.01).contains(&self.tolerance)) {
            return fail(
                "tolerance",
                "must be a fraction of an edge between 0 and 0.01",
            );
        }
        if self.gravity.iter().any(|g| !g.is_finite()) {
            return fail("gravity", "must be finite");
        }
        if !(self.hair_radius.is_finite() && self.hair_radius > 0.0) {
            return fail("hair_radius", "must be a positive length");
        }
        if let Some(alpha) = self.hair_hair_strength {
            if !(alpha.is_finite() && alpha >= 0.0) {
                return fail("hair_hair_strength", "must be a non-negative number");
            }
        }
        if let Some(mu) = self.hair_friction {
            if !(mu.is_finite() && (0.0..=1.0).contains(&mu)) {
                return fail("hair_friction", "must be a coefficient between 0 and 1");
            }
        }
        if let Some(problem) = self.volumetric.as_ref().and_then(Volumetric::problem) {
            return fail("volumetric", problem);
        }
        for (name, value) in [
            ("linear_damping", self.linear_damping),
            ("angular_damping", self.angular_damping),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return fail(name, "must be a non-negative rate per second");
            }
        }
        if !(self.quaternion_mass_scale.is_finite() && self.quaternion_mass_scale > 0.0) {
            return fail("quaternion_mass_scale", "must be positive");
        }
        if let Inextensibility::FollowTheLeader {
            velocity_correction,
        } = self.inextensibility
        {
            if !(velocity_correction.is_finite() && (0.0..=1.0).contains(&velocity_correction)) {
                return fail("inextensibility.velocity_correction", "must be in [0, 1]");
            }
        }
        Ok(())
    }
}

/// Gravity of one step.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gravity {
    /// `SolverParameters::gravity`.
    #[default]
    Default,
    Off,
    Vector([f32; 3]),
}

/// A blower, eq. (19) and (21).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Blower {
    /// `p_blower`, metres.
    pub from: [f32; 3],
    /// `p_target`, metres.
    pub to: [f32; 3],
    /// `alpha` of (19), m/s^2.
    pub strength: f32,
    /// The factor of (21): `db_hyd = hydrogen_rate * |dv_w|` per step while
    /// `b_hyd < 1` (0.003 in the paper's scene 2).
    pub hydrogen_rate: f32,
    /// The length scale `L` of the falloff, metres: strength falls with the
    /// distance `d` from the wind's axis as `1 / (d / L + 1)^2` (the paper's
    /// `d` has no unit; `L = 1` m is its formula read in metres).
    pub falloff_length: f32,
    /// Half-angle of the blower's cone, degrees: no wind outside it (`None`:
    /// the whole half-space in front of the nozzle). Nothing blows behind the
    /// nozzle in any case.
    pub cone_half_angle: Option<f32>,
}

/// What the world does to the hair during one step; the timeline fills it.
#[derive(Debug, Clone, Copy, Default)]
pub struct Environment<'a> {
    pub gravity: Gravity,
    pub blower: Option<Blower>,
    /// `d b_j / dt` per bond kind, per second, applied at every joint as
    /// `db = rate * dt` with `b` clamped to [0, 1]: positive re-forms (and
    /// remembers the current shape, (17)), negative breaks.
    pub bond_rate_drive: [f32; 4],
    /// Per bond kind, a target rate: with `Some(t)` the drive's magnitude
    /// moves every joint's rate toward `t` (up or down, stopping there);
    /// with `None` the signed drive applies as it is.
    pub bond_rate_targets: [Option<f32>; 4],
    /// An extra acceleration per vertex (m/s^2, one per vertex of the
    /// strand set, in its order): the wind hook.
    pub extra_acceleration: Option<&'a [[f32; 3]]>,
    /// The hold toward the groomed shape (forces/hold.rs); `None`: off.
    pub hold: Option<Hold>,
    /// Hydrogen bonds re-formed this step per vertex (one per vertex of
    /// the strand set, a rate change in 0..1 added to the joint's hydrogen
    /// rate): the drying hook, the water that evaporated this step
    /// (`timeline::drying`). Added to the blower's (21), if any.
    pub hydrogen_reform: Option<&'a [f32]>,
}

/// Why the solver cannot start or go on.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SimError {
    #[error("solver parameter '{name}': {message}")]
    Parameter { name: &'static str, message: String },
    #[error("groom: {0}")]
    Groom(String),
    #[error("groom strand {strand} vertex {vertex}: position is not finite")]
    NonFinite { strand: usize, vertex: usize },
    #[error("groom attribute '{name}': {message}")]
    Attribute { name: String, message: String },
    #[error("environment: {0}")]
    Environment(String),
    #[error("strand {strand} vertex {vertex}: {message}")]
    Index {
        strand: usize,
        vertex: usize,
        message: &'static str,
    },
}

/// The benchmark's groom: `strands` straight strands of `vertices`
/// vertices, 24 cm long, on a scalp cap (metres, Y up).
pub fn bench_groom(
    strands: usize,
    vertices: usize,
) -> Result<groom::Groom, crate::generate::GeneratorError> {
    let length = 0.24;
    crate::generate::generate(&crate::generate::GeneratorParameters {
        strands,
        length,
        segment_length: length / (vertices.max(2) - 1) as f32,
        ..Default::default()
    })
}

/// What a step did besides moving the hair.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    /// Strands whose state turned non-finite during this step: restored to
    /// their state before the step and frozen from now on.
    pub contained: Vec<usize>,
    /// All frozen strands so far.
    pub frozen_total: usize,
    /// Constraint solves run this step, summed over the strands: the
    /// physical model's Newton iterations (each strand stops at
    /// `SolverParameters::tolerance`, plus one after a contact moved it),
    /// the paper model's sweeps.
    pub solves: u64,
    /// The time the strands' steps spent in each phase, summed over the
    /// threads (when `Solver::set_phase_clock` is on).
    pub phases: Option<PhaseTimes>,
}

/// Nanoseconds the strands' steps spent in each phase, summed over the
/// threads (the hair-hair grid and the collider preparation run before
/// the strands' steps and are not in it).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PhaseTimes {
    /// External forces and the prediction (ii), the velocities (vi) and
    /// the commit.
    pub forces: u64,
    /// The constraint solve (iv): the physical model's Newton iterations
    /// or the paper model's sweeps, with their collision projections,
    /// Follow-The-Leader and the final collision pass.
    pub constraints: u64,
    /// The side-chain bonds: rate changes and the rest shape (iii)-(15),
    /// and the bond update (v)-(17).
    pub bonds: u64,
}

impl PhaseTimes {
    /// `f` of each phase's two times.
    fn each(self, o: PhaseTimes, f: impl Fn(u64, u64) -> u64) -> PhaseTimes {
        PhaseTimes {
            forces: f(self.forces, o.forces),
            constraints: f(self.constraints, o.constraints),
            bonds: f(self.bonds, o.bonds),
        }
    }
}

impl std::ops::Add for PhaseTimes {
    type Output = PhaseTimes;
    fn add(self, o: PhaseTimes) -> PhaseTimes {
        self.each(o, u64::saturating_add)
    }
}

impl std::ops::Sub for PhaseTimes {
    type Output = PhaseTimes;
    /// The time between two readings of the totals (`saturating`, as the
    /// sums are).
    fn sub(self, o: PhaseTimes) -> PhaseTimes {
        self.each(o, u64::saturating_sub)
    }
}

impl std::ops::AddAssign for PhaseTimes {
    fn add_assign(&mut self, o: PhaseTimes) {
        *self = *self + o;
    }
}
