//! One step of 000 Fig. 1 (METHOD D), fused per strand (or per group of
//! strands in SIMD lanes), in named phases:
//! 1. `predict` (forces): external forces, predicted positions and frames
//!    (with the hold folded in, hold.rs);
//! 2. `rest_shape` (bonds): bond-rate changes, rest shape from the bonds (15);
//! 3. the constraint solve (constraints): `n` iterations of stretch/shear,
//!    bend/twist and collisions (the physical model's Newton iterations,
//!    with the contacts between strands and their Coulomb friction when
//!    `hair_friction` is on: hair_friction.rs), then `end_constraints`:
//!    the inextensibility pass, stuck hair contacts put back, the final
//!    collisions;
//! 4. `velocities` (forces): velocities from positions, the finite check;
//! 5. `update_bonds` (bonds): the bond update (17);
//! 6. `commit` (forces).
//!
//! The physical model's step is backward Euler (the solve balances the
//! forces against the inertia at the step's end, velocities come from the
//! change): stable for hair's stiff stretch/shear at any `dt` and exact in
//! statics, but it damps a mode of angular frequency `w` by about
//! `exp(-pi w dt)` a cycle on top of `damping` (docs/model.md "Time
//! integration", measured by `backward_euler_damps_the_released_hair_as_documented`).
//!
//! Strands run in parallel; each works on a cache-resident copy of its
//! state and commits it only if it is finite. With the phase clock on
//! (`Solver::set_phase_clock`) each phase's time is added up for the
//! step's report.

#[cfg(target_arch = "x86_64")]
use super::avx::{eight_to_lanes, lanes_to_eight};
use super::contact::colliders::{project, project_contact, PreparedCollider};
use super::contact::hair_friction::{self, HairContact, HairContacts};
use super::contact::hair_pairs::EdgeGrid;
use super::contact::volume::VolumeGrid;
use super::forces::blower::blower_dv;
#[cfg(target_arch = "x86_64")]
use super::forces::blower::blower_dv_eight;
use super::forces::hold::{fold, fold_frame};
use super::instructions::{in_widest, Instructions};
use super::math::{self, Quat, V3};
use super::quarantine::all_finite;
use super::rod::bonds::{driven_rates, reform, rest_darboux, still_rates, Drive};
#[cfg(target_arch = "x86_64")]
use super::rod::bonds::{rest_eight, RatesIn};
use super::rod::constraints::{
    bend_coefficients, bend_twist, follow_the_leader, stretch_shear, StretchCoefficients,
};
use super::rod::direct::{edge_flexibility, Direct, DirectInput, EdgeCompliance, RodMaterial};
use super::rod::lanes::{Group, LaneInput, LANES};
use super::rod::real::{F64x8, Real, WIDE};
use super::state::{EdgeState, JointState, Rigid, RootAnchor, VertexControl};
use super::{
    Blower, ColliderSet, Environment, Gravity, Hold, Inextensibility, Model, PhaseTimes, SimError,
    SolverParameters, StepReport, StrandSet,
};
use rayon::prelude::*;

/// Advances strands; owns only scratch memory.
#[derive(Debug)]
pub struct Solver {
    parameters: SolverParameters,
    /// Groups of four in SIMD lanes (off only to test the scalar path).
    simd: bool,
    /// The widest instructions the lanes may use.
    instructions: Instructions,
    grid: EdgeGrid,
    /// Hair-hair contacts with Coulomb friction (physical model).
    contacts: HairContacts,
    volume: VolumeGrid,
    dispatch: Dispatch,
    /// Time the phases of each step (`StepReport::phases`).
    phase_clock: bool,
}

/// Strands per task of the parallel step: a fixed count (so the split does
/// not depend on the thread count, though no result depends on it), eight
/// groups of eight, small enough that the threads finish together.
const TASK_STRANDS: usize = 8 * WIDE;

/// The scratch of the parallel dispatch, kept from step to step so a step
/// allocates nothing once warm.
#[derive(Default)]
struct Dispatch {
    /// Per strand: simulated and not frozen.
    active: Vec<bool>,
    /// The allocation of the per-strand views, empty between steps (see
    /// [`recycle`]).
    views: Vec<StrandMut<'static>>,
    /// The scratch of the tasks: a task takes one and gives it back, so
    /// there are as many as tasks ever ran at once (the threads), and they
    /// stay warm in the cache (one per task made the scratch of a 10k-strand
    /// step 23 MB and the step slower).
    scratch: std::sync::Mutex<Vec<Block>>,
}

impl std::fmt::Debug for Dispatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Dispatch")
            .field("strands", &self.active.len())
            .field(
                "scratch",
                &self.scratch.lock().map_or(0, |blocks| blocks.len()),
            )
            .finish_non_exhaustive()
    }
}

/// One block's scratch.
#[derive(Default)]
struct Block {
    works: [Work; WIDE],
    group: Group,
    /// The physical model's solve of eight strands (AVX-512).
    wide: Direct<F64x8>,
    /// The block's strands that failed this step (capacity for all of them).
    failed: Vec<usize>,
}

/// An empty vector of views of any lifetime holding `views`' allocation:
/// views borrow the strand set for one step, the buffer outlives them.
/// (`Vec`'s in-place collect keeps the allocation, as the views of both
/// lifetimes have one layout; tests/allocations.rs checks that it does.)
// `filter_map` here changes the lifetime, which `filter` cannot.
#[allow(clippy::unnecessary_filter_map)]
fn recycle<'b>(mut views: Vec<StrandMut<'_>>) -> Vec<StrandMut<'b>> {
    views.clear();
    views.into_iter().filter_map(|_| None).collect()
}

/// The mutable view of one strand's state.
struct StrandMut<'a> {
    index: usize,
    active: bool,
    root: RootAnchor,
    first_vertex: usize,
    positions: &'a mut [V3],
    velocities: &'a mut [V3],
    velocity_corrections: &'a mut [V3],
    edges: &'a mut [EdgeState],
    joints: &'a mut [JointState],
    controls: &'a [VertexControl],
    radii: &'a [f32],
    /// The hold's targets (scalp space) and arc fractions.
    groomed: &'a [V3],
    groomed_fraction: &'a [f32],
    groomed_frames: &'a [Quat],
}

/// What every strand's step reads.
struct Context<'a> {
    dt: f32,
    inv_dt: f32,
    iterations: u32,
    /// The physical model's Newton tolerance (`SolverParameters::tolerance`).
    tolerance: f64,
    gravity: V3,
    linear_keep: f32,
    angular_keep: f32,
    quaternion_mass_scale: f32,
    radius: f32,
    /// Follow-The-Leader's velocity correction, when its pass runs: the
    /// paper model only (the physical model's solve keeps the edges'
    /// length), so `None` for the physical model whatever the parameters.
    ftl: Option<f32>,
    influences: [f32; 4],
    /// The bond drive (rate changes this step and targets).
    drive: Drive,
    /// No drive, target or blower changes a bond rate this step.
    bonds_still: bool,
    blower: Option<Blower>,
    extra_acceleration: Option<&'a [V3]>,
    /// The hold toward the groomed shape (hold.rs), when on.
    hold: Option<Hold>,
    hydrogen_reform: Option<&'a [f32]>,
    hair_hair: Option<(f32, &'a EdgeGrid)>,
    /// Contacts between strands with Coulomb friction, solved with the
    /// collider contacts (physical model, pairwise hair-hair).
    hair_contacts: Option<&'a HairContacts>,
    /// Volumetric hair-hair's velocity changes (instead of `hair_hair`).
    volume: Option<&'a VolumeGrid>,
    colliders: &'a [PreparedCollider<'a>],
    root_transform: Rigid,
    simd: bool,
    /// The physical model's strands go eight to a group (AVX-512;
    /// otherwise four).
    wide: bool,
    /// The widest instructions the lanes and the per-strand phases may
    /// use (the baseline without `simd`).
    instructions: Instructions,
    physical: Option<RodMaterial>,
    /// Time the phases (`Solver::set_phase_clock`).
    phase_clock: bool,
}

/// The clock of the phases of a strand's or a group's step, when the
/// solver times them: a reading at each phase's end, the time since the
/// last reading added to that phase. (Timing reads a clock and adds to
/// counters only, so it cannot change a result; off, it reads nothing.)
struct PhaseClock {
    last: Option<std::time::Instant>,
}

impl PhaseClock {
    fn start(on: bool) -> PhaseClock {
        PhaseClock {
            last: on.then(std::time::Instant::now),
        }
    }

    /// Adds the time since the last reading to `phase`.
    #[inline]
    fn lap(&mut self, phase: &mut u64) {
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
struct Work {
    x: Vec<V3>,
    p: Vec<V3>,
    w: Vec<f32>,
    q_old: Vec<Quat>,
    q: Vec<Quat>,
    w_q: Vec<f32>,
    l: Vec<f32>,
    rest: Vec<V3>,
    stretch: Vec<StretchCoefficients>,
    bend: Vec<[f32; 2]>,
    db: Vec<[f32; 4]>,
    corrections: Vec<V3>,
    v: Vec<V3>,
    dv: Vec<V3>,
    omega: Vec<V3>,
    /// The physical model's contacts this step: each touching vertex's
    /// surface normal (zero: none).
    contact_normals: Vec<V3>,
    /// Per touching vertex, the surface's velocity and friction
    /// coefficient (Coulomb friction after the solve).
    contact_velocities: Vec<V3>,
    contact_friction: Vec<f32>,
    /// Per edge, the factor of its frame's inverse inertia (the hold's,
    /// hold.rs; 1 without).
    frame_keep: Vec<f32>,
    /// The predicted positions before any contact (the physical model's
    /// friction measures the normal push from them).
    predicted: Vec<V3>,
    /// The blower's velocity change at each vertex this step.
    blower: Vec<V3>,
    /// The index of the strand this copy steps (its hair contacts).
    strand: usize,
    /// Per vertex, its share of the hair contacts and whether friction
    /// stuck it this step (empty until friction runs).
    touch: Vec<hair_friction::VertexContact>,
    stuck: Vec<bool>,
    direct: Direct<f64>,
    /// The scalp's frame for the first edge this step.
    root_frame: Quat,
    /// Constraint solves (physical model) or sweeps (paper model) of the
    /// strands this working copy stepped, since the step began.
    solves: u64,
    /// The phases' times of the strands this working copy stepped, since
    /// the step began (when the solver times them).
    phases: PhaseTimes,
    /// No bond rate of the strand changes this step (`rest_shape`): the
    /// bond update has nothing to do.
    bonds_unchanged: bool,
}

impl Work {
    fn resize(&mut self, n: usize) {
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

impl Solver {
    pub fn new(parameters: SolverParameters) -> Result<Solver, SimError> {
        parameters.check()?;
        Ok(Solver {
            parameters,
            simd: true,
            instructions: Instructions::of_this_cpu(),
            grid: EdgeGrid::default(),
            contacts: HairContacts::default(),
            volume: VolumeGrid::default(),
            dispatch: Dispatch::default(),
            phase_clock: false,
        })
    }

    /// Whether each step times its phases (`StepReport::phases`), for
    /// `bench`; off by default. The results are the same either way.
    pub fn set_phase_clock(&mut self, on: bool) {
        self.phase_clock = on;
    }

    pub fn parameters(&self) -> &SolverParameters {
        &self.parameters
    }

    /// Steps every strand alone (the scalar path), to check the SIMD path.
    #[cfg(test)]
    pub(crate) fn without_simd(mut self) -> Solver {
        self.simd = false;
        self
    }

    /// Runs the lanes in at most `widest` (a test of a narrower path's bits
    /// on a CPU that has wider).
    #[cfg(test)]
    pub(crate) fn with_instructions_at_most(mut self, widest: Instructions) -> Solver {
        self.instructions = self.instructions.min(widest);
        self
    }

    /// Changes the settings from the next step on (a stage may damp more,
    /// iterate more, switch hair-hair off...).
    /// The contacts between hairs (with Coulomb friction) the last step
    /// found, each counted once from each of its two strands: 0 without
    /// hair-hair friction.
    pub fn hair_contact_count(&self) -> usize {
        match self.parameters.hair_friction {
            Some(mu) if mu > 0.0 => self.contacts.count(),
            _ => 0,
        }
    }

    pub fn set_parameters(&mut self, parameters: SolverParameters) -> Result<(), SimError> {
        parameters.check()?;
        self.parameters = parameters;
        Ok(())
    }

    /// Advances every active strand by `dt`. Strands whose new state is not
    /// finite keep their old state, are frozen and reported.
    pub fn step(
        &mut self,
        strands: &mut StrandSet,
        colliders: &ColliderSet,
        environment: &Environment<'_>,
    ) -> Result<StepReport, SimError> {
        let parameters = self.parameters;
        if let Some(extra) = environment.extra_acceleration {
            if extra.len() != strands.vertex_count() {
                return Err(SimError::Environment(format!(
                    "extra_acceleration has {} values for {} vertices",
                    extra.len(),
                    strands.vertex_count()
                )));
            }
        }
        if let Some(reform) = environment.hydrogen_reform {
            if reform.len() != strands.vertex_count() || reform.iter().any(|r| !r.is_finite()) {
                return Err(SimError::Environment(format!(
                    "hydrogen_reform needs {} finite values, has {}",
                    strands.vertex_count(),
                    reform.len()
                )));
            }
        }
        let targets_nan = environment
            .bond_rate_targets
            .iter()
            .flatten()
            .any(|t| t.is_nan());
        if environment.bond_rate_drive.iter().any(|r| r.is_nan()) || targets_nan {
            return Err(SimError::Environment("a bond rate drive is NaN".into()));
        }
        if let Some(b) = environment.blower {
            let finite = math::is_finite3(b.from)
                && math::is_finite3(b.to)
                && b.strength.is_finite()
                && b.hydrogen_rate.is_finite()
                && b.falloff_length.is_finite()
                && b.falloff_length > 0.0
                && b.cone_half_angle.is_none_or(f32::is_finite);
            if !finite {
                return Err(SimError::Environment(
                    "the blower has a non-finite value".into(),
                ));
            }
        }
        if let Some(problem) = environment.hold.as_ref().and_then(Hold::problem) {
            return Err(SimError::Environment(format!("hold: {problem}")));
        }
        let gravity = match environment.gravity {
            Gravity::Default => parameters.gravity,
            Gravity::Off => [0.0; 3],
            Gravity::Vector(g) if math::is_finite3(g) => g,
            Gravity::Vector(_) => {
                return Err(SimError::Environment("gravity is not finite".into()));
            }
        };
        if strands.prime_iterations != parameters.iterations {
            let n = parameters.iterations as f32;
            for joint in &mut strands.joints {
                // (12): the effect of k does not depend on the iteration count.
                joint.stiffness_prime = 1.0 - (1.0 - joint.stiffness).max(0.0).powf(1.0 / n);
            }
            strands.prime_iterations = parameters.iterations;
        }
        let Solver {
            grid,
            contacts,
            volume,
            dispatch,
            simd,
            instructions,
            phase_clock,
            ..
        } = self;
        dispatch.active.clear();
        dispatch.active.extend(
            strands
                .simulated
                .iter()
                .zip(&strands.frozen)
                .map(|(s, f)| *s && !*f),
        );
        let active = dispatch.active.as_slice();
        let instructions = if *simd {
            *instructions
        } else {
            Instructions::Baseline
        };
        let volumetric = parameters.volumetric.map(|settings| {
            volume.build(
                instructions,
                &strands.positions,
                &strands.velocities,
                &strands.radii,
                &strands.offsets,
                active,
                &settings,
                parameters.dt,
            );
            &*volume
        });
        let rest_longest = || {
            strands
                .edges
                .par_iter()
                .with_min_len(4096)
                .map(|e| e.rest_length)
                .filter(|l| l.is_finite())
                .reduce(|| 0.0, f32::max)
        };
        let mut longest = None;
        let hair_hair = match parameters.hair_hair_strength {
            _ if volumetric.is_some() => None,
            Some(alpha) if alpha > 0.0 => {
                let rest_longest = *longest.get_or_insert_with(rest_longest);
                grid.build(
                    &strands.positions,
                    &strands.offsets,
                    active,
                    parameters.hair_radius,
                    rest_longest,
                );
                Some(alpha)
            }
            _ => None,
        };
        let hair_contacts = match (hair_hair, parameters.hair_friction) {
            (Some(_), Some(mu)) if mu > 0.0 && strands.material.model == Model::Physical => {
                let rest_longest = *longest.get_or_insert_with(rest_longest);
                contacts.build(
                    &strands.positions,
                    &strands.velocities,
                    &strands.offsets,
                    active,
                    parameters.hair_radius,
                    mu,
                    rest_longest,
                    parameters.dt,
                );
                Some(&*contacts)
            }
            _ => None,
        };
        let prepared = colliders.prepare(parameters.hair_radius);
        let dt = parameters.dt;
        let context = Context {
            dt,
            inv_dt: 1.0 / dt,
            iterations: parameters.iterations,
            tolerance: f64::from(parameters.tolerance),
            gravity,
            linear_keep: (-parameters.linear_damping * dt).exp(),
            angular_keep: (-parameters.angular_damping * dt).exp(),
            quaternion_mass_scale: parameters.quaternion_mass_scale,
            radius: parameters.hair_radius,
            ftl: match (parameters.inextensibility, strands.material.model) {
                (Inextensibility::Off, _) | (_, Model::Physical) => None,
                (
                    Inextensibility::FollowTheLeader {
                        velocity_correction,
                    },
                    Model::Paper,
                ) => Some(velocity_correction),
            },
            influences: strands.influences,
            drive: Drive {
                change: environment.bond_rate_drive.map(|r| r * dt),
                targets: environment.bond_rate_targets,
            },
            bonds_still: environment.bond_rate_drive.iter().all(|r| *r * dt == 0.0)
                && environment.bond_rate_targets.iter().all(Option::is_none)
                && environment.blower.is_none()
                && environment.hydrogen_reform.is_none(),
            blower: environment.blower,
            extra_acceleration: environment.extra_acceleration,
            hold: environment.hold.filter(|h| h.strength > 0.0),
            hydrogen_reform: environment.hydrogen_reform,
            hair_hair: hair_hair.map(|alpha| (alpha, &*grid)),
            hair_contacts,
            volume: volumetric,
            colliders: &prepared,
            root_transform: strands.root_transform,
            simd: *simd,
            // (`instructions` is the baseline without `simd`.)
            wide: strands.material.model == Model::Physical && instructions.avx512(),
            instructions,
            physical: match strands.material.model {
                Model::Paper => None,
                Model::Physical => Some(RodMaterial {
                    youngs_modulus: strands.material.youngs_modulus as f64,
                    shear_modulus: strands.material.shear_modulus() as f64,
                    density: strands.material.density as f64,
                }),
            },
            phase_clock: *phase_clock,
        };
        let mut views = recycle(std::mem::take(&mut dispatch.views));
        split_strands(strands, active, &mut views);
        // Strands of one vertex count next to each other so groups of four
        // are uniform (SIMD) even in grooms of mixed lengths; the order is
        // fixed by the data (the keys are unique, so an unstable sort, which
        // needs no buffer, gives one order), and a strand's result does not
        // depend on its group anyway.
        let key = |v: &StrandMut<'_>| (!v.active, v.positions.len(), v.index);
        // (Most grooms are in that order already: checked first, as the
        // other thread waits for this.)
        if !views.is_sorted_by_key(key) {
            views.sort_unstable_by_key(key);
        }
        // Strands go in groups of four or eight (see `step_group`,
        // `step_chunk`), groups in tasks of a fixed size; a strand's result
        // does not depend on its group, task or scratch, so not on the
        // thread count.
        let chunk = if context.wide { WIDE } else { LANES };
        let strand_count = views.len();
        let scratch = dispatch
            .scratch
            .get_mut()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        for block in scratch.iter_mut() {
            block.failed.clear();
            for work in &mut block.works {
                work.solves = 0;
                work.phases = PhaseTimes::default();
            }
        }
        let scratch = &dispatch.scratch;
        let take = || {
            scratch
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .pop()
                .unwrap_or_else(|| Block {
                    // Room for every strand to fail (no allocation then).
                    failed: Vec::with_capacity(strand_count),
                    ..Block::default()
                })
        };
        views.par_chunks_mut(TASK_STRANDS).for_each(|strands| {
            let mut block = take();
            if block.failed.capacity() < strand_count {
                block.failed.reserve(strand_count);
            }
            for group in strands.chunks_mut(chunk) {
                step_chunk(&context, group, &mut block);
            }
            scratch
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .push(block);
        });
        dispatch.views = recycle(views);
        let blocks = dispatch
            .scratch
            .get_mut()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        // Allocates only when a strand failed.
        let mut failed: Vec<usize> = blocks
            .iter()
            .flat_map(|b| b.failed.iter().copied())
            .collect();
        failed.sort_unstable();
        for &strand in &failed {
            strands.frozen[strand] = true;
        }
        let solves = blocks
            .iter()
            .flat_map(|b| b.works.iter().map(|w| w.solves))
            .sum();
        let phases = phase_clock.then(|| {
            blocks
                .iter()
                .flat_map(|b| b.works.iter().map(|w| w.phases))
                .fold(PhaseTimes::default(), |sum, p| sum + p)
        });
        Ok(StepReport {
            frozen_total: strands.frozen.iter().filter(|f| **f).count(),
            contained: failed,
            solves,
            phases,
        })
    }
}

/// Cuts the flat arrays into one view per strand, into `views` (empty).
fn split_strands<'a>(strands: &'a mut StrandSet, active: &[bool], views: &mut Vec<StrandMut<'a>>) {
    let StrandSet {
        offsets,
        roots,
        positions,
        velocities,
        velocity_corrections,
        edges,
        joints,
        controls,
        radii,
        groomed,
        groomed_fraction,
        groomed_frames,
        ..
    } = strands;
    let mut positions = positions.as_mut_slice();
    let mut velocities = velocities.as_mut_slice();
    let mut corrections = velocity_corrections.as_mut_slice();
    let mut edges = edges.as_mut_slice();
    let mut joints = joints.as_mut_slice();
    let mut controls = controls.as_slice();
    let mut radii = radii.as_slice();
    let mut groomed = groomed.as_slice();
    let mut groomed_fraction = groomed_fraction.as_slice();
    let mut groomed_frames = groomed_frames.as_slice();
    views.reserve(roots.len());
    for (index, w) in offsets.windows(2).enumerate() {
        let n = w[1] - w[0];
        let (p, rest_p) = std::mem::take(&mut positions).split_at_mut(n);
        let (v, rest_v) = std::mem::take(&mut velocities).split_at_mut(n);
        let (dv, rest_dv) = std::mem::take(&mut corrections).split_at_mut(n);
        let (e, rest_e) = std::mem::take(&mut edges).split_at_mut(n);
        let (j, rest_j) = std::mem::take(&mut joints).split_at_mut(n);
        let (c, rest_c) = controls.split_at(n);
        let (r, rest_r) = radii.split_at(n);
        radii = rest_r;
        let (g, rest_g) = groomed.split_at(n);
        let (f, rest_f) = groomed_fraction.split_at(n);
        groomed = rest_g;
        groomed_fraction = rest_f;
        let (gq, rest_gq) = groomed_frames.split_at(n);
        groomed_frames = rest_gq;
        positions = rest_p;
        velocities = rest_v;
        corrections = rest_dv;
        edges = rest_e;
        joints = rest_j;
        controls = rest_c;
        views.push(StrandMut {
            index,
            active: active[index],
            root: roots[index],
            first_vertex: w[0],
            positions: p,
            velocities: v,
            velocity_corrections: dv,
            edges: e,
            joints: j,
            controls: c,
            radii: r,
            groomed: g,
            groomed_fraction: f,
            groomed_frames: gq,
        });
    }
}

impl StrandMut<'_> {
    /// The same view for a shorter borrow (to step a strand of a slice).
    fn reborrow(&mut self) -> StrandMut<'_> {
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

/// (ii) of the step, the "forces" phase: external forces and the
/// predicted positions and frames in the working copy.
fn predict(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    in_widest!(ctx.instructions, fn(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
        predict_strand(ctx, s, work)
    })
}

#[inline(always)]
fn predict_strand(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
    let n = s.positions.len();
    let m = n - 1;
    work.resize(n);
    work.strand = s.index;
    work.stuck.clear();
    let dt = ctx.dt;

    // (ii) External forces, then the predicted positions.
    if let Some(blower) = &ctx.blower {
        blow(ctx, blower, s, work);
    }
    for i in 0..n {
        let x = s.positions[i];
        work.x[i] = x;
        let mut blower_dv_here = [0.0f32; 3];
        if ctx.blower.is_some() {
            blower_dv_here = work.blower[i];
        } else {
            work.db[i][0] = 0.0;
        }
        if let Some(reform) = ctx.hydrogen_reform {
            work.db[i][0] += reform[s.first_vertex + i];
        }
        let control = s.controls[i];
        if control.targeted {
            work.p[i] = control.target;
            work.w[i] = 0.0;
            continue;
        }
        if i == 0 {
            work.p[0] = ctx.root_transform.apply(s.root.position);
            work.w[0] = 0.0;
            continue;
        }
        work.w[i] = 1.0;
        let mut a = ctx.gravity;
        if let Some(extra) = ctx.extra_acceleration {
            a = math::add(a, extra[s.first_vertex + i]);
        }
        // Damping slows the motion, not gravity: damping the acceleration
        // too would scale the weight by exp(-c dt) and move the static
        // equilibrium with c and dt.
        // Follow-The-Leader's correction (paper model) acts on the
        // prediction only; the state keeps the real velocity.
        let moving = math::sub(s.velocities[i], s.velocity_corrections[i]);
        let mut v = math::add(math::scale(moving, ctx.linear_keep), math::scale(a, dt));
        v = math::add(v, blower_dv_here);
        if let Some((alpha, grid)) = ctx.hair_hair {
            v = math::add(v, grid.penalty_dv(s.first_vertex + i, alpha, dt));
        }
        if let Some(volume) = ctx.volume {
            v = math::add(v, volume.dv(s.index, i));
        }
        work.p[i] = math::add(x, math::scale(v, dt));
        if let Some(hold) = &ctx.hold {
            let k = hold.at(s.groomed_fraction[i]);
            if k > 0.0 {
                let target = ctx.root_transform.apply(s.groomed[i]);
                (work.p[i], work.w[i]) = fold(work.p[i], target, k, dt);
            }
        }
    }
    work.root_frame = math::qmul(ctx.root_transform.rotation, s.root.frame);
    // The clamp's rest turn (zero unless the sag-free start set one).
    work.rest[0] = s.root.rest;
    for e in 0..m {
        let edge = s.edges[e];
        work.q_old[e] = edge.rotation;
        work.l[e] = edge.rest_length;
        if e == 0 && ctx.physical.is_none() {
            // The root frame is fixed to the scalp.
            work.q[0] = work.root_frame;
            work.w_q[0] = 0.0;
        } else {
            let w = math::scale(edge.angular_velocity, ctx.angular_keep);
            let q = edge.rotation;
            work.q[e] = if w == [0.0; 3] {
                // Renormalising a unit quaternion would only add round-off.
                q
            } else {
                let spin = math::qmul(math::pure(w), q);
                let h = 0.5 * dt;
                math::qnormalize([
                    q[0] + h * spin[0],
                    q[1] + h * spin[1],
                    q[2] + h * spin[2],
                    q[3] + h * spin[3],
                ])
            };
            if ctx.physical.is_none() {
                // (The physical model's inertias come from its constants.)
                work.w_q[e] = ctx.quaternion_mass_scale / (edge.rest_length * edge.rest_length);
            }
            work.frame_keep[e] = 1.0;
            if let Some(hold) = &ctx.hold {
                let f = s.groomed_fraction;
                let k = hold.at(0.5 * (f[e] + f[e + 1]));
                if k > 0.0 {
                    let target = math::qmul(ctx.root_transform.rotation, s.groomed_frames[e]);
                    let keep;
                    (work.q[e], keep) = fold_frame(work.q[e], target, k, dt);
                    work.frame_keep[e] = keep;
                    work.w_q[e] *= keep;
                }
            }
        }
        if ctx.physical.is_none() {
            work.stretch[e] =
                StretchCoefficients::new(work.w[e], work.w[e + 1], work.w_q[e], edge.rest_length);
        }
    }
    if ctx.physical.is_none() {
        // The paper model's sweep coefficients.
        for j in 1..m {
            work.bend[j] =
                bend_coefficients(work.w_q[j - 1], work.w_q[j], s.joints[j].stiffness_prime);
        }
    }
}

/// The blower's velocity change (19) at each vertex of the strand, into
/// `work.blower`, and its drying (21), which re-forms hydrogen bonds (held
/// vertices dry too), into `work.db`: eight vertices at a time in lanes
/// where the CPU has AVX2 (`blow_eights`: the same bits), the rest one by
/// one.
#[inline(always)]
fn blow(ctx: &Context<'_>, blower: &Blower, s: &StrandMut<'_>, work: &mut Work) {
    let n = s.positions.len();
    let m = n - 1;
    #[allow(unused_mut)]
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if ctx.instructions.avx2() {
        // SAFETY: the CPU has AVX2 (`Instructions::of_this_cpu`).
        done = unsafe { blow_eights(blower, s.positions, ctx.dt, work) };
    }
    for i in done..n {
        let x = s.positions[i];
        let edge = if i < m {
            math::sub(s.positions[i + 1], x)
        } else {
            math::sub(x, s.positions[i - 1])
        };
        let dv = blower_dv(blower, x, edge, ctx.dt);
        work.blower[i] = dv;
        work.db[i][0] = blower.hydrogen_rate * math::length(dv);
    }
}

/// `blow` of the strand's vertices in runs of eight, one per lane; returns
/// the vertices done (the rest are fewer than eight).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn blow_eights(blower: &Blower, positions: &[V3], dt: f32, work: &mut Work) -> usize {
    use std::arch::x86_64::*;
    let n = positions.len();
    let m = n - 1;
    // A vertex as four floats; the fourth (the next vertex's x, or 0 at
    // the strand's end) is not used.
    let load = |i: usize| {
        if i + 1 < n {
            // SAFETY: reads vertex i and the first float of vertex i + 1
            // (`[V3]` is contiguous).
            unsafe { _mm_loadu_ps(positions[i].as_ptr()) }
        } else {
            let p = positions[i];
            _mm_setr_ps(p[0], p[1], p[2], 0.0)
        }
    };
    let rate = _mm256_set1_ps(blower.hydrogen_rate);
    let mut start = 0;
    while start + 8 <= n {
        let [x, y, z, _] = eight_to_lanes(std::array::from_fn(|l| load(start + l)));
        let [nx, ny, nz, _] = eight_to_lanes(std::array::from_fn(|l| load((start + l + 1).min(m))));
        let mut edge = [
            _mm256_sub_ps(nx, x),
            _mm256_sub_ps(ny, y),
            _mm256_sub_ps(nz, z),
        ];
        if start + 8 == n {
            // The tip's edge is the last one, `p[m] - p[m - 1]`: lane 6's.
            let last = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 6);
            edge = edge.map(|e| _mm256_permutevar8x32_ps(e, last));
        }
        let dv = blower_dv_eight(blower, [x, y, z], edge, dt);
        // `hydrogen_rate * length(dv)`.
        let [dx, dy, dz] = dv;
        let squared = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
            _mm256_mul_ps(dz, dz),
        );
        let drying = _mm256_mul_ps(rate, _mm256_sqrt_ps(squared));
        for (l, v) in lanes_to_eight([dx, dy, dz, drying]).into_iter().enumerate() {
            let mut four = [0.0f32; 4];
            // SAFETY: stores the four floats of `four`.
            unsafe { _mm_storeu_ps(four.as_mut_ptr(), v) };
            work.blower[start + l] = [four[0], four[1], four[2]];
            work.db[start + l][0] = four[3];
        }
        start += 8;
    }
    start
}

/// (iii) of the step, the "bonds" phase: bond-rate changes and the rest
/// shape from the bonds (15), after `predict` (which fills the old frames
/// and, with a blower, the drying rates).
fn rest_shape(ctx: &Context<'_>, s: &StrandMut<'_>, work: &mut Work) {
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
fn rest_shapes_in_lanes(ctx: &Context<'_>, strands: &[StrandMut<'_>], works: &mut [Work]) -> bool {
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
pub(super) fn bend_flexibility(
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

/// Per-strand sweep state carried in registers: the current edge's first
/// vertex and the previous edge's frame.
struct Sweep {
    p_a: V3,
    q_prev: Quat,
}

impl Work {
    /// Stretch/shear of edge 0 (no joint before it).
    #[inline(always)]
    fn sweep_begin(&mut self) -> Sweep {
        let mut p_a = self.p[0];
        let mut p_b = self.p[1];
        let mut q_prev = self.q[0];
        stretch_shear(&mut p_a, &mut p_b, &mut q_prev, &self.stretch[0]);
        self.p[0] = p_a;
        Sweep { p_a: p_b, q_prev }
    }

    /// Edge `e`'s stretch/shear, then the bend of the joint between edges
    /// `e - 1` and `e` (Gauss-Seidel, root to tip).
    #[inline(always)]
    fn sweep_edge(&mut self, e: usize, state: &mut Sweep) {
        let mut p_b = self.p[e + 1];
        let mut q_e = self.q[e];
        stretch_shear(&mut state.p_a, &mut p_b, &mut q_e, &self.stretch[e]);
        bend_twist(&mut state.q_prev, &mut q_e, self.rest[e], self.bend[e]);
        self.p[e] = state.p_a;
        self.q[e - 1] = state.q_prev;
        state.p_a = p_b;
        state.q_prev = q_e;
    }

    #[inline(always)]
    fn sweep_end(&mut self, m: usize, state: Sweep) {
        self.p[m] = state.p_a;
        self.q[m - 1] = state.q_prev;
    }

    fn sweep(&mut self, m: usize) {
        let mut state = self.sweep_begin();
        for e in 1..m {
            self.sweep_edge(e, &mut state);
        }
        self.sweep_end(m, state);
    }

    /// Collision projection with friction after an iteration.
    fn collide(&mut self, ctx: &Context<'_>, n: usize) {
        if ctx.colliders.is_empty() {
            return;
        }
        for i in 1..n {
            if self.w[i] > 0.0 {
                self.p[i] = project(
                    ctx.colliders,
                    self.p[i],
                    Some(self.x[i]),
                    ctx.radius,
                    ctx.dt,
                );
            }
        }
    }
}

/// One strand's step. Returns false (and commits nothing) when its new
/// state is not finite.
fn step_strand(ctx: &Context<'_>, mut s: StrandMut<'_>, work: &mut Work) -> bool {
    let n = s.positions.len();
    if n < 2 {
        return true;
    }
    let mut clock = PhaseClock::start(ctx.phase_clock);
    predict(ctx, &s, work);
    clock.lap(&mut work.phases.forces);
    rest_shape(ctx, &s, work);
    clock.lap(&mut work.phases.bonds);
    if let Some(material) = ctx.physical {
        work.solve_direct(ctx, material, &s);
    } else {
        // (iv) Constraint iterations (and collisions).
        work.solves += u64::from(ctx.iterations);
        for _ in 0..ctx.iterations {
            work.sweep(n - 1);
            work.collide(ctx, n);
        }
    }
    end_constraints(ctx, work, n, false);
    clock.lap(&mut work.phases.constraints);
    let finite = velocities(ctx, work, n);
    clock.lap(&mut work.phases.forces);
    if finite {
        update_bonds(ctx, &mut s, work);
        clock.lap(&mut work.phases.bonds);
        commit(ctx, s, work);
        clock.lap(&mut work.phases.forces);
    }
    finite
}

impl Work {
    /// (iv) of the physical model: `iterations` Newton-XPBD iterations,
    /// each an exact solve of the strand's linearised compliant system.
    /// Collisions come before each solve and the solve keeps them: a
    /// touching vertex moves along the surface, and hardly across it
    /// (`contact_normals` in direct.rs). Pinning vertices that static
    /// friction holds was tried: a strand pressed between its root and a
    /// held tip buckled into a zig-zag the Newton iterations could not
    /// follow (edges 50 % long). Coulomb friction acts once, after the
    /// last solve (`friction`). A contact or friction that moved a vertex
    /// after the last solve gets one more solve, so the step never ends on
    /// a projection that squeezes or stretches edges.
    fn solve_direct(&mut self, ctx: &Context<'_>, material: RodMaterial, s: &StrandMut<'_>) {
        let n = s.positions.len();
        let m = n - 1;
        self.clear_contacts(n);
        if self.touches(ctx) {
            self.begin_contacts(ctx, n);
        }
        // Taken out so the solve can borrow the rest of the working copy.
        let mut direct = std::mem::take(&mut self.direct);
        direct.begin(&[direct_input(ctx, material, s, self)]);
        newton_iterations(ctx, std::slice::from_mut(self), &mut direct, n);
        direct.end(&mut [(&mut self.p[..n], &mut self.q[..m])]);
        self.direct = direct;
    }

    /// No contact yet this step. The colliders' friction data too: a
    /// vertex that only touches hair has a contact normal but no collider,
    /// and must not read the friction of another strand this working copy
    /// stepped before (that made a bake depend on the thread count).
    fn clear_contacts(&mut self, n: usize) {
        self.contact_normals[..n].fill([0.0; 3]);
        self.contact_velocities[..n].fill([0.0; 3]);
        self.contact_friction[..n].fill(0.0);
    }

    /// The strand's contacts with other strands this step.
    #[inline]
    fn hair_contacts<'c>(&self, ctx: &Context<'c>) -> &'c [HairContact] {
        ctx.hair_contacts.map_or(&[], |h| h.of(self.strand))
    }

    /// Whether the strand may touch anything this step (a collider or
    /// another strand): the solve then keeps contacts.
    #[inline]
    fn touches(&self, ctx: &Context<'_>) -> bool {
        !ctx.colliders.is_empty() || !self.hair_contacts(ctx).is_empty()
    }

    /// Before the solve: the prediction kept (friction measures from it),
    /// the predicted positions projected.
    fn begin_contacts(&mut self, ctx: &Context<'_>, n: usize) {
        self.predicted[..n].copy_from_slice(&self.p[..n]);
        self.collide_contacts(ctx, n);
        self.collide_hairs(ctx, n);
    }

    /// Pushes the strand's contact points with other strands out to two
    /// radii (hair_friction.rs). Returns whether a vertex moved.
    fn collide_hairs(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let Some(hairs) = ctx.hair_contacts else {
            return false;
        };
        self.touch
            .resize(n, hair_friction::VertexContact::default());
        hair_friction::project(
            hairs.of(self.strand),
            &mut self.touch[..n],
            &mut self.p[..n],
            &self.w[..n],
            &mut self.contact_normals[..n],
            hairs.distance(),
            ctx.dt,
            0.01 * ctx.radius,
        )
    }

    /// Coulomb friction at the strand's contacts with other strands, after
    /// the last solve. Returns whether a vertex moved.
    fn hair_friction(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let Some(hairs) = ctx.hair_contacts else {
            return false;
        };
        self.stuck.clear();
        self.stuck.resize(n, false);
        self.touch
            .resize(n, hair_friction::VertexContact::default());
        hair_friction::friction(
            hairs.of(self.strand),
            &mut self.touch[..n],
            &mut self.stuck,
            &mut self.p[..n],
            &self.x[..n],
            &self.predicted[..n],
            &self.w[..n],
            hairs.mu(),
            ctx.dt,
            0.01 * ctx.radius,
        )
    }

    /// After a solve: lane `lane`'s positions projected out of the
    /// colliders, its contacts recorded, after the `last` solve Coulomb
    /// friction applied, all handed back to the solve. Returns whether a
    /// vertex moved.
    fn contacts_after_iteration<T: Real>(
        &mut self,
        direct: &mut Direct<T>,
        lane: usize,
        ctx: &Context<'_>,
        n: usize,
        last: bool,
    ) -> bool {
        direct.positions_f32(lane, &mut self.p[..n]);
        let mut moved = self.collide_contacts(ctx, n);
        moved |= self.collide_hairs(ctx, n);
        if last {
            moved |= self.friction(ctx, n);
            moved |= self.hair_friction(ctx, n);
        }
        direct.set_positions(lane, &self.p[..n]);
        direct.set_contact_normals(lane, &self.contact_normals[..n]);
        moved
    }

    /// Projects the free vertices out of the colliders (with friction) and
    /// records the contacts for the solve: a contact lasts the rest of the
    /// step. Returns whether a vertex moved (more than a hundredth of the
    /// hair radius).
    fn collide_contacts(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let mut moved = false;
        if ctx.colliders.is_empty() {
            return false;
        }
        for i in 1..n {
            if self.w[i] <= 0.0 {
                continue;
            }
            // No friction here: it acts once, after the solve (`friction`).
            let contact = project_contact(ctx.colliders, self.p[i], None, ctx.radius, ctx.dt);
            moved |= math::length(math::sub(contact.position, self.p[i])) > 0.01 * ctx.radius;
            self.p[i] = contact.position;
            if let Some(normal) = contact.normal {
                self.contact_normals[i] = normal;
                self.contact_velocities[i] = contact.surface_velocity;
                self.contact_friction[i] = contact.friction;
            }
        }
        moved
    }

    /// Coulomb friction of the step at each touching vertex (position-level,
    /// as XPBD does it): the step's motion along the surface, relative to
    /// the surface, is held back by `mu` times the distance the contact
    /// pushed the vertex out along the normal (from its prediction, which
    /// gravity and inertia carried into the surface): all of it while it is
    /// smaller (static), else by that much (kinetic). A strand on a slope
    /// of angle `a` so stays put for `mu > tan a` and otherwise slides at
    /// `g (sin a - mu cos a)`. Applied once the solve has moved the strand,
    /// so the solve cannot undo it (applied before it, a resting strand
    /// slid on); per vertex, so in no order. Returns whether a vertex moved.
    fn friction(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let mut moved = false;
        for i in 1..n {
            let normal = self.contact_normals[i];
            let mu = self.contact_friction[i];
            if self.w[i] <= 0.0 || normal == [0.0; 3] || mu <= 0.0 {
                continue;
            }
            let pushed = math::dot(math::sub(self.p[i], self.predicted[i]), normal).max(0.0);
            let surface_motion = math::scale(self.contact_velocities[i], ctx.dt);
            let relative = math::sub(math::sub(self.p[i], self.x[i]), surface_motion);
            let tangential = math::sub(relative, math::scale(normal, math::dot(relative, normal)));
            let slide = math::length(tangential);
            if slide == 0.0 {
                continue;
            }
            let held = if slide <= mu * pushed {
                1.0
            } else {
                mu * pushed / slide
            };
            self.p[i] = math::sub(self.p[i], math::scale(tangential, held));
            moved |= held * slide > 0.01 * ctx.radius;
        }
        moved
    }
}

/// What the direct solve reads of one strand: its working copy, fibre
/// radii and joints.
fn direct_input<'a>(
    ctx: &Context<'_>,
    material: RodMaterial,
    s: &'a StrandMut<'_>,
    work: &'a Work,
) -> DirectInput<'a> {
    let n = s.positions.len();
    let m = n - 1;
    DirectInput {
        p: &work.p[..n],
        q: &work.q[..m],
        free: &work.w[..n],
        frame_free: &work.frame_keep[..m],
        // Empty without contacts: the solve then skips reading zeros.
        contact_normals: if work.touches(ctx) {
            &work.contact_normals[..n]
        } else {
            &[]
        },
        l: &work.l[..m],
        radii: s.radii,
        joints: s.joints,
        material,
        rest: &work.rest[..m],
        root_frame: work.root_frame,
        dt: ctx.dt,
    }
}

/// Where a strand's Newton iterations stand (`newton_iterations`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Progress {
    Iterating,
    /// Its last contact projection or friction moved a vertex: one more
    /// solve, so the step does not end on a projection that squeezes or
    /// stretches edges.
    OneMore,
    Done,
}

/// The physical model's Newton iterations of the strands in `direct`'s
/// lanes (`works[lane]`) with their contacts. A strand iterates until its
/// stretch/shear residual is within `ctx.tolerance` of its edges (checked
/// after each iteration but the last; 0: never) or it has had
/// `ctx.iterations`; collisions are projected after every iteration and
/// Coulomb friction after its last. A strand that is done keeps its
/// state, bit for bit, while the other lanes iterate, so its result is the
/// one it gets alone (`solve_direct`). Adds each strand's solves to its
/// `Work::solves`.
fn newton_iterations<T: Real>(
    ctx: &Context<'_>,
    works: &mut [Work],
    direct: &mut Direct<T>,
    n: usize,
) {
    let lanes = T::WIDTH;
    let mut progress = [Progress::Iterating; WIDE];
    let mut iteration = 0;
    while progress[..lanes].iter().any(|p| *p != Progress::Done) {
        direct.iterate_lanes(ctx.instructions);
        iteration += 1;
        let unconverged = (ctx.tolerance > 0.0 && iteration < ctx.iterations)
            .then(|| direct.unconverged_lanes(ctx.instructions, ctx.tolerance));
        for (lane, work) in works.iter_mut().take(lanes).enumerate() {
            match progress[lane] {
                Progress::Done => {}
                Progress::OneMore => {
                    work.solves += 1;
                    progress[lane] = Progress::Done;
                    direct.set_active(lane, false);
                }
                Progress::Iterating => {
                    work.solves += 1;
                    let last = iteration >= ctx.iterations
                        || unconverged.is_some_and(|u| u.lane(lane) == 0.0);
                    let moved = work.touches(ctx)
                        && work.contacts_after_iteration(direct, lane, ctx, n, last);
                    if last {
                        progress[lane] = if moved {
                            Progress::OneMore
                        } else {
                            Progress::Done
                        };
                        direct.set_active(lane, moved);
                    }
                }
            }
        }
    }
}

/// The physical model's step of four uniform strands: the direct solve in
/// `f64` lanes (bit-identical to `solve_direct` on each), collisions and
/// the rest per strand. Returns the failed ones.
fn step_group_direct<T: Real>(
    ctx: &Context<'_>,
    material: RodMaterial,
    strands: &mut [StrandMut<'_>],
    works: &mut [Work],
    direct: &mut Direct<T>,
    failed: &mut Vec<usize>,
) {
    let n = strands[0].positions.len();
    let m = n - 1;
    let lanes = T::WIDTH;
    // The phases' times go to the first lane's working copy (summed over
    // all of them at the end of the step).
    let mut clock = PhaseClock::start(ctx.phase_clock);
    let mut phases = PhaseTimes::default();
    for (s, work) in strands.iter().zip(works.iter_mut()) {
        predict(ctx, s, work);
    }
    clock.lap(&mut phases.forces);
    if !rest_shapes_in_lanes(ctx, strands, works) {
        for (s, work) in strands.iter().zip(works.iter_mut()) {
            rest_shape(ctx, s, work);
        }
    }
    clock.lap(&mut phases.bonds);
    for work in works.iter_mut().take(lanes) {
        work.clear_contacts(n);
        if work.touches(ctx) {
            work.begin_contacts(ctx, n);
        }
    }
    // (Inputs for the widest group; a narrower one reads its first.)
    let inputs: [DirectInput<'_>; WIDE] = std::array::from_fn(|lane| {
        let lane = lane % T::WIDTH;
        direct_input(ctx, material, &strands[lane], &works[lane])
    });
    direct.begin_lanes(ctx.instructions, &inputs[..T::WIDTH]);
    newton_iterations(ctx, works, direct, n);
    {
        let mut lanes = works.iter_mut().take(T::WIDTH);
        let mut out: [_; WIDE] = std::array::from_fn(|_| {
            lanes
                .next()
                .map(|w| (&mut w.p[..n], &mut w.q[..m]))
                .unwrap_or_default()
        });
        direct.end(&mut out[..T::WIDTH]);
    }
    for work in works.iter_mut().take(lanes) {
        end_constraints(ctx, work, n, false);
    }
    clock.lap(&mut phases.constraints);
    finish_group(ctx, strands, works, failed, clock, phases);
}

/// The end of a group's step, each strand as in `step_strand`: velocities,
/// then, for the strands whose state is finite, the bond update and the
/// commit; the others go to `failed`. Adds the phases' times (from
/// `clock`, started with the step) to the first working copy.
fn finish_group(
    ctx: &Context<'_>,
    strands: &mut [StrandMut<'_>],
    works: &mut [Work],
    failed: &mut Vec<usize>,
    mut clock: PhaseClock,
    mut phases: PhaseTimes,
) {
    let n = strands[0].positions.len();
    let mut finite = [false; WIDE];
    for (ok, work) in finite.iter_mut().zip(works.iter_mut()).take(strands.len()) {
        *ok = velocities(ctx, work, n);
    }
    clock.lap(&mut phases.forces);
    for ((s, work), ok) in strands.iter_mut().zip(works.iter()).zip(finite) {
        if ok {
            update_bonds(ctx, s, work);
        }
    }
    clock.lap(&mut phases.bonds);
    for ((s, work), ok) in strands.iter_mut().zip(works.iter()).zip(finite) {
        if ok {
            commit(ctx, s.reborrow(), work);
        } else {
            failed.push(s.index);
        }
    }
    clock.lap(&mut phases.forces);
    if let Some(first) = works.first_mut() {
        first.phases += phases;
    }
}

/// Up to eight strands' steps: the physical model's direct solve of all
/// eight in lanes when they are active and of one vertex count (`ctx.wide`,
/// bit-identical to `step_strand` on each); otherwise groups of four.
fn step_chunk(ctx: &Context<'_>, strands: &mut [StrandMut<'_>], block: &mut Block) {
    let n = strands.first().map_or(0, |s| s.positions.len());
    let uniform = ctx.wide
        && strands.len() == WIDE
        && n >= 2
        && strands.iter().all(|s| s.active && s.positions.len() == n);
    if let Some(material) = ctx.physical.filter(|_| uniform) {
        step_group_direct(
            ctx,
            material,
            strands,
            &mut block.works,
            &mut block.wide,
            &mut block.failed,
        );
        return;
    }
    for group in strands.chunks_mut(LANES) {
        step_group(
            ctx,
            group,
            &mut block.works[..LANES],
            &mut block.group,
            &mut block.failed,
        );
    }
}

/// Four strands' steps with their constraint sweeps in SIMD lanes when
/// they are all active and of one vertex count (bit-identical to
/// `step_strand` on each); otherwise one by one. Adds the failed ones to
/// `failed`.
fn step_group(
    ctx: &Context<'_>,
    strands: &mut [StrandMut<'_>],
    works: &mut [Work],
    group: &mut Group,
    failed: &mut Vec<usize>,
) {
    let n = strands.first().map_or(0, |s| s.positions.len());
    let uniform = ctx.simd
        && strands.len() == LANES
        && n >= 2
        && strands.iter().all(|s| s.active && s.positions.len() == n);
    if !uniform {
        for (s, work) in strands.iter_mut().zip(works.iter_mut()) {
            let index = s.index;
            if s.active && !step_strand(ctx, s.reborrow(), work) {
                failed.push(index);
            }
        }
        return;
    }
    if let Some(material) = ctx.physical {
        step_group_direct(ctx, material, strands, works, &mut group.direct, failed);
        return;
    }
    let mut clock = PhaseClock::start(ctx.phase_clock);
    let mut phases = PhaseTimes::default();
    for (s, work) in strands.iter().zip(works.iter_mut()) {
        predict(ctx, s, work);
        work.solves += u64::from(ctx.iterations);
    }
    clock.lap(&mut phases.forces);
    for (s, work) in strands.iter().zip(works.iter_mut()) {
        rest_shape(ctx, s, work);
    }
    clock.lap(&mut phases.bonds);
    let m = n - 1;
    group.load_constants(lane_inputs(works, n), n);
    let colliding = !ctx.colliders.is_empty();
    for _ in 0..ctx.iterations {
        group.sweep();
        if colliding {
            for (lane, work) in works.iter_mut().enumerate() {
                group.store(lane, &mut work.p[..n], &mut work.q[..m]);
                work.collide(ctx, n);
            }
            group.load_state(&lane_inputs(works, n), n);
        }
    }
    let ftl_done = ctx.ftl.is_some();
    if ftl_done {
        group.follow_the_leader();
    }
    for (lane, work) in works.iter_mut().enumerate().take(strands.len()) {
        group.store(lane, &mut work.p[..n], &mut work.q[..m]);
        if ftl_done {
            group.store_corrections(lane, &mut work.corrections[..n]);
        }
        end_constraints(ctx, work, n, ftl_done);
    }
    clock.lap(&mut phases.constraints);
    finish_group(ctx, strands, works, failed, clock, phases);
}

fn lane_inputs(works: &[Work], n: usize) -> [LaneInput<'_>; LANES] {
    let m = n - 1;
    std::array::from_fn(|l| LaneInput {
        p: &works[l].p[..n],
        q: &works[l].q[..m],
        stretch: &works[l].stretch[..m],
        rest: &works[l].rest[..m],
        bend: &works[l].bend[..m],
        w: &works[l].w[..n],
        l: &works[l].l[..m],
    })
}

/// The end of the "constraints" phase: the inextensibility pass (paper
/// model, unless it already ran in lanes: `ftl_done`) and the final
/// collision pass, so no vertex ends inside a collider.
fn end_constraints(ctx: &Context<'_>, work: &mut Work, n: usize, ftl_done: bool) {
    let m = n - 1;
    if ctx.ftl.is_some() && !ftl_done {
        follow_the_leader(
            &mut work.p[..n],
            &work.w[..n],
            &work.l[..m],
            &mut work.corrections[..n],
        );
    }
    if let Some(hairs) = ctx.hair_contacts {
        // Stuck vertices stay stuck through the last solve.
        if work.stuck.len() == n && !hairs.of(work.strand).is_empty() {
            hair_friction::restick(
                &work.touch[..n],
                &work.stuck,
                &mut work.p[..n],
                &work.x[..n],
                ctx.dt,
            );
        }
    }
    if !ctx.colliders.is_empty() {
        for i in 1..n {
            if work.w[i] > 0.0 {
                work.p[i] = project(ctx.colliders, work.p[i], None, ctx.radius, ctx.dt);
            }
        }
    }
}

/// (vi) Velocities from the position change; returns whether the new
/// state is finite (the strand is committed only then).
fn velocities(ctx: &Context<'_>, work: &mut Work, n: usize) -> bool {
    in_widest!(ctx.instructions, fn(ctx: &Context<'_>, work: &mut Work, n: usize) -> bool {
        velocities_strand(ctx, work, n)
    })
}

#[inline(always)]
fn velocities_strand(ctx: &Context<'_>, work: &mut Work, n: usize) -> bool {
    let m = n - 1;
    // Follow-The-Leader's correction of the velocities (DFTL) is kept
    // apart: the real velocity is what the state reports.
    for i in 0..n {
        work.v[i] = math::scale(math::sub(work.p[i], work.x[i]), ctx.inv_dt);
        work.dv[i] = [0.0; 3];
        if let Some(correction) = ctx.ftl {
            if i + 1 < n && work.w[i] > 0.0 {
                work.dv[i] = math::scale(work.corrections[i + 1], correction * ctx.inv_dt);
            }
        }
    }
    for e in 0..m {
        // Im(q conj(q_old)) = Im((q - q_old) conj(q_old)) since q_old
        // conj(q_old) is real; the difference form avoids the round-off of
        // a product of two nearly equal frames (noise in a soft system).
        let (q, q_old) = (work.q[e], work.q_old[e]);
        let sign = if math::qdot(q, q_old) < 0.0 {
            -1.0
        } else {
            1.0
        };
        let change = [
            q[0] - sign * q_old[0],
            q[1] - sign * q_old[1],
            q[2] - sign * q_old[2],
            q[3] - sign * q_old[3],
        ];
        let delta = math::qmul(change, math::conj(q_old));
        work.omega[e] = math::scale(math::imag(delta), 2.0 * sign * ctx.inv_dt);
    }
    all_finite(&work.p[..n], &work.v[..n], &work.q[..m], &work.omega[..m])
}

/// (v) of the step, the end of the "bonds" phase: the bond update (17)
/// with the shape after the projection.
fn update_bonds(ctx: &Context<'_>, s: &mut StrandMut<'_>, work: &Work) {
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

/// Commits the strand's new positions, velocities and frames.
fn commit(ctx: &Context<'_>, s: StrandMut<'_>, work: &Work) {
    let n = s.positions.len();
    let m = n - 1;
    s.positions.copy_from_slice(&work.p[..n]);
    s.velocities.copy_from_slice(&work.v[..n]);
    // The physical model has none: they stay zero, so they are written only
    // when not already all +0 (a write would dirty memory for nothing).
    let unchanged = ctx.ftl.is_none()
        && s.velocity_corrections
            .iter()
            .all(|c| c.iter().all(|v| v.to_bits() == 0));
    if !unchanged {
        s.velocity_corrections.copy_from_slice(&work.dv[..n]);
    }
    for e in 0..m {
        s.edges[e].rotation = work.q[e];
        s.edges[e].angular_velocity = work.omega[e];
    }
}
