//! The working copy of a step: the view of one strand's state that a step
//! writes ([`StrandMut`]), what every strand's step reads ([`Context`]),
//! the per-thread copy of a strand the phases work on ([`Work`]) and the
//! clock of the phases. Apart from step.rs so that the phases, in their
//! rooms, and the pipeline that calls them share them without a circle.

use crate::sim::contact::colliders::PreparedCollider;
use crate::sim::contact::hair_friction::{self, HairContacts};
use crate::sim::contact::hair_pairs::EdgeGrid;
use crate::sim::contact::volume::VolumeGrid;
use crate::sim::instructions::Instructions;
use crate::sim::math::{self, Quat, V3};
use crate::sim::rod::bonds::Drive;
use crate::sim::rod::constraints::StretchCoefficients;
use crate::sim::rod::direct::{Direct, RodMaterial};
use crate::sim::state::{EdgeState, JointState, Rigid, RootAnchor, VertexControl};
use crate::sim::{Blower, Hold, PhaseTimes};

/// The mutable view of one strand's state.
pub(in crate::sim) struct StrandMut<'a> {
    pub(in crate::sim) index: usize,
    pub(in crate::sim) active: bool,
    pub(in crate::sim) root: RootAnchor,
    pub(in crate::sim) first_vertex: usize,
    pub(in crate::sim) positions: &'a mut [V3],
    pub(in crate::sim) velocities: &'a mut [V3],
    pub(in crate::sim) velocity_corrections: &'a mut [V3],
    pub(in crate::sim) edges: &'a mut [EdgeState],
    pub(in crate::sim) joints: &'a mut [JointState],
    pub(in crate::sim) controls: &'a [VertexControl],
    pub(in crate::sim) radii: &'a [f32],
    /// The hold's targets (scalp space) and arc fractions.
    pub(in crate::sim) groomed: &'a [V3],
    pub(in crate::sim) groomed_fraction: &'a [f32],
    pub(in crate::sim) groomed_frames: &'a [Quat],
}

/// What every strand's step reads.
#[derive(Clone)]
pub(in crate::sim) struct Context<'a> {
    pub(in crate::sim) dt: f32,
    pub(in crate::sim) inv_dt: f32,
    pub(in crate::sim) iterations: u32,
    /// The physical model's Newton tolerance (`SolverParameters::tolerance`).
    pub(in crate::sim) tolerance: f64,
    pub(in crate::sim) gravity: V3,
    pub(in crate::sim) linear_keep: f32,
    pub(in crate::sim) angular_keep: f32,
    pub(in crate::sim) quaternion_mass_scale: f32,
    pub(in crate::sim) radius: f32,
    /// Follow-The-Leader's velocity correction, when its pass runs: the
    /// paper model only (the physical model's solve keeps the edges'
    /// length), so `None` for the physical model whatever the parameters.
    pub(in crate::sim) ftl: Option<f32>,
    pub(in crate::sim) influences: [f32; 4],
    /// The bond drive (rate changes this step and targets).
    pub(in crate::sim) drive: Drive,
    /// No drive, target or blower changes a bond rate this step.
    pub(in crate::sim) bonds_still: bool,
    pub(in crate::sim) blower: Option<Blower>,
    pub(in crate::sim) extra_acceleration: Option<&'a [V3]>,
    /// The hold toward the groomed shape (forces/hold.rs), when on.
    pub(in crate::sim) hold: Option<Hold>,
    pub(in crate::sim) hydrogen_reform: Option<&'a [f32]>,
    pub(in crate::sim) hair_hair: Option<(f32, &'a EdgeGrid)>,
    /// Contacts between strands with Coulomb friction, solved with the
    /// collider contacts (physical model, pairwise hair-hair).
    pub(in crate::sim) hair_contacts: Option<&'a HairContacts>,
    /// Volumetric hair-hair's velocity changes (instead of `hair_hair`).
    pub(in crate::sim) volume: Option<&'a VolumeGrid>,
    pub(in crate::sim) colliders: &'a [PreparedCollider<'a>],
    pub(in crate::sim) root_transform: Rigid,
    pub(in crate::sim) simd: bool,
    /// The physical model's strands go eight to a group (AVX-512;
    /// otherwise four).
    pub(in crate::sim) wide: bool,
    /// The widest instructions the lanes and the per-strand phases may
    /// use (the baseline without `simd`).
    pub(in crate::sim) instructions: Instructions,
    pub(in crate::sim) physical: Option<RodMaterial>,
    /// Time the phases (`Solver::set_phase_clock`).
    pub(in crate::sim) phase_clock: bool,
    /// The context of a midpoint step's half step (the same with half the
    /// `dt`), when this step allows the midpoint step (rod/midpoint.rs).
    pub(in crate::sim) half: Option<&'a Context<'a>>,
}

/// The clock of the phases of a strand's or a group's step, when the
/// solver times them: a reading at each phase's end, the time since the
/// last reading added to that phase. (Timing reads a clock and adds to
/// counters only, so it cannot change a result; off, it reads nothing.)
pub(in crate::sim) struct PhaseClock {
    pub(in crate::sim) last: Option<std::time::Instant>,
}

impl PhaseClock {
    pub(in crate::sim) fn start(on: bool) -> PhaseClock {
        PhaseClock {
            last: on.then(std::time::Instant::now),
        }
    }

    /// Adds the time since the last reading to `phase`.
    #[inline]
    pub(in crate::sim) fn lap(&mut self, phase: &mut u64) {
        if let Some(last) = self.last {
            let now = std::time::Instant::now();
            let elapsed = u64::try_from(now.duration_since(last).as_nanos()).unwrap_or(u64::MAX);
            *phase = phase.saturating_add(elapsed);
            self.last = Some(now);
        }
    }
}

/// Per-thread working copy of one strand.
#[derive(Default)]
pub(in crate::sim) struct Work {
    pub(in crate::sim) x: Vec<V3>,
    pub(in crate::sim) p: Vec<V3>,
    pub(in crate::sim) w: Vec<f32>,
    pub(in crate::sim) q_old: Vec<Quat>,
    pub(in crate::sim) q: Vec<Quat>,
    pub(in crate::sim) w_q: Vec<f32>,
    pub(in crate::sim) l: Vec<f32>,
    pub(in crate::sim) rest: Vec<V3>,
    pub(in crate::sim) stretch: Vec<StretchCoefficients>,
    pub(in crate::sim) bend: Vec<[f32; 2]>,
    pub(in crate::sim) db: Vec<[f32; 4]>,
    pub(in crate::sim) corrections: Vec<V3>,
    pub(in crate::sim) v: Vec<V3>,
    pub(in crate::sim) dv: Vec<V3>,
    pub(in crate::sim) omega: Vec<V3>,
    /// The physical model's contacts this step: each touching vertex's
    /// surface normal (zero: none).
    pub(in crate::sim) contact_normals: Vec<V3>,
    /// Per touching vertex, the surface's velocity and friction
    /// coefficient (Coulomb friction after the solve).
    pub(in crate::sim) contact_velocities: Vec<V3>,
    pub(in crate::sim) contact_friction: Vec<f32>,
    /// Per edge, the factor of its frame's inverse inertia (the hold's,
    /// forces/hold.rs; 1 without).
    pub(in crate::sim) frame_keep: Vec<f32>,
    /// The predicted positions before any contact (the physical model's
    /// friction measures the normal push from them).
    pub(in crate::sim) predicted: Vec<V3>,
    /// The blower's velocity change at each vertex this step.
    pub(in crate::sim) blower: Vec<V3>,
    /// The index of the strand this copy steps (its hair contacts).
    pub(in crate::sim) strand: usize,
    /// Per vertex, its share of the hair contacts and whether friction
    /// stuck it this step (empty until friction runs).
    pub(in crate::sim) touch: Vec<hair_friction::VertexContact>,
    pub(in crate::sim) stuck: Vec<bool>,
    pub(in crate::sim) direct: Direct<f64>,
    /// The scalp's frame for the first edge this step.
    pub(in crate::sim) root_frame: Quat,
    /// Constraint solves (physical model) or sweeps (paper model) of the
    /// strands this working copy stepped, since the step began.
    pub(in crate::sim) solves: u64,
    /// The phases' times of the strands this working copy stepped, since
    /// the step began (when the solver times them).
    pub(in crate::sim) phases: PhaseTimes,
    /// No bond rate of the strand changes this step (`rest_shape`): the
    /// bond update has nothing to do.
    pub(in crate::sim) bonds_unchanged: bool,
    /// The strand takes the midpoint step this step (rod/midpoint.rs).
    pub(in crate::sim) midpoint: bool,
    /// The midpoint step's scratch: the half step's positions and
    /// velocities, the extrapolated displacements and velocity changes.
    pub(in crate::sim) mid: Vec<V3>,
    pub(in crate::sim) v_mid: Vec<V3>,
    pub(in crate::sim) ext_dx: Vec<V3>,
    pub(in crate::sim) ext_dv: Vec<V3>,
    pub(in crate::sim) smooth_scratch: Vec<V3>,
}

impl Work {
    /// Room for the midpoint step's scratch of a strand of `n` vertices.
    pub(in crate::sim) fn resize_midpoint(&mut self, n: usize) {
        for v in [
            &mut self.mid,
            &mut self.v_mid,
            &mut self.ext_dx,
            &mut self.ext_dv,
        ] {
            v.resize(n, [0.0; 3]);
        }
        self.smooth_scratch.reserve(n);
    }

    pub(in crate::sim) fn resize(&mut self, n: usize) {
        for v in [
            &mut self.x,
            &mut self.p,
            &mut self.rest,
            &mut self.corrections,
            &mut self.v,
            &mut self.dv,
            &mut self.omega,
            &mut self.contact_normals,
            &mut self.contact_velocities,
            &mut self.predicted,
            &mut self.blower,
        ] {
            v.resize(n, [0.0; 3]);
        }
        for v in [
            &mut self.w,
            &mut self.w_q,
            &mut self.l,
            &mut self.contact_friction,
        ] {
            v.resize(n, 0.0);
        }
        self.frame_keep.resize(n, 1.0);
        self.direct.reserve(n);
        self.stretch.resize(n, StretchCoefficients::default());
        self.bend.resize(n, [0.0; 2]);
        self.q_old.resize(n, math::IDENTITY);
        self.q.resize(n, math::IDENTITY);
        self.db.resize(n, [0.0; 4]);
    }
}

impl StrandMut<'_> {
    /// The same view for a shorter borrow (to step a strand of a slice).
    pub(in crate::sim) fn reborrow(&mut self) -> StrandMut<'_> {
        StrandMut {
            index: self.index,
            active: self.active,
            root: self.root,
            first_vertex: self.first_vertex,
            positions: self.positions,
            velocities: self.velocities,
            velocity_corrections: self.velocity_corrections,
            edges: self.edges,
            joints: self.joints,
            controls: self.controls,
            radii: self.radii,
            groomed: self.groomed,
            groomed_fraction: self.groomed_fraction,
            groomed_frames: self.groomed_frames,
        }
    }
}
