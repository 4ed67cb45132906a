//! One step of 000 Fig. 1 (METHOD D): the pipeline. Once per step,
//! [`Solver::step`] checks the environment and runs the searches over all
//! strands from the positions at the start of the step (volumetric
//! hair-hair, the pairwise penalty's grid, the hair contacts with friction:
//! `contact/`). Then each strand (or group of four or eight strands in
//! SIMD lanes) runs the named phases on its working copy (work.rs), each
//! phase's body in its room:
//! 1. `predict` (forces, forces/predict.rs): external forces, predicted
//!    positions and frames (with the hold folded in, forces/hold.rs);
//! 2. `rest_shape` (bonds, rod/shape_memory.rs): bond-rate changes, rest
//!    shape from the bonds (15);
//! 3. the constraint solve (constraints, rod/solve.rs): `n` iterations of
//!    stretch/shear, bend/twist and collisions (the physical model's Newton
//!    iterations, with the contacts of contact/solve.rs between them and
//!    Coulomb friction after the last), then `end_constraints`: the
//!    inextensibility pass, stuck hair contacts put back, the final
//!    collisions;
//! 4. `velocities` (forces, here): velocities from positions, the finite
//!    check;
//! 5. `update_bonds` (bonds, rod/shape_memory.rs): the bond update (17);
//! 6. `commit` (forces, here): the working copy written back.
//!
//! The physical model's step is backward Euler, or with
//! `Integrator::Midpoint`, per strand, the midpoint step (rod/midpoint.rs:
//! the phases above over half the step with the half step's context,
//! `Context::half`, then `extrapolate` to the step's end, which also finds
//! the velocities) where it is safe (`takes_midpoint`). Backward Euler (the solve balances the forces against the inertia
//! at the step's end, velocities come from the change): stable for hair's
//! stiff stretch/shear at any `dt` and exact in statics, but it damps a
//! mode of angular frequency `w` by about `exp(-pi w dt)` a cycle on top
//! of `damping` (docs/model.md "Time integration").
//!
//! Strands run in parallel; each works on a cache-resident copy of its
//! state and commits it only if it is finite. With the phase clock on
//! (`Solver::set_phase_clock`) each phase's time is added up for the
//! step's report.

use super::contact::hair_friction::HairContacts;
use super::contact::hair_pairs::EdgeGrid;
use super::contact::volume::VolumeGrid;
use super::forces::predict::predict;
use super::instructions::{in_widest, Instructions};
use super::math;
use super::quarantine::all_finite;
use super::rod::bonds::Drive;
use super::rod::direct::{Direct, DirectInput, RodMaterial};
use super::rod::lanes::{Group, LaneInput, LANES};
use super::rod::midpoint::{extrapolate, takes_midpoint};
use super::rod::real::{F64x8, Real, WIDE};
use super::rod::shape_memory::{rest_shape, rest_shapes_in_lanes, update_bonds};
use super::rod::solve::{direct_input, end_constraints, newton_iterations};
use super::work::{Context, PhaseClock, StrandMut, Work};
use super::{
    ColliderSet, Environment, Gravity, Hold, Inextensibility, Integrator, Model, PhaseTimes,
    SimError, SolverParameters, StepReport, StrandSet,
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
            half: None,
        };
        // The midpoint step (rod/midpoint.rs) where the step allows it:
        // the half step's context is this one with half the `dt`.
        let midpoint = strands.material.model == Model::Physical
            && parameters.integrator == Integrator::Midpoint
            && context.blower.is_none()
            && context.hold.is_none()
            && context.hair_hair.is_none()
            && context.hair_contacts.is_none()
            && context.volume.is_none();
        let half_dt = 0.5 * dt;
        let half = Context {
            dt: half_dt,
            inv_dt: 1.0 / half_dt,
            linear_keep: (-parameters.linear_damping * half_dt).exp(),
            angular_keep: (-parameters.angular_damping * half_dt).exp(),
            ..context.clone()
        };
        let context = Context {
            half: midpoint.then_some(&half),
            ..context
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

/// The context strand's step runs its forces and solve in: the half
/// step's for a midpoint step (`takes_midpoint`), else the step's.
fn of_strand<'c, 'a>(ctx: &'c Context<'a>, midpoint: bool) -> &'c Context<'a> {
    match ctx.half {
        Some(half) if midpoint => half,
        _ => ctx,
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
    work.midpoint = takes_midpoint(ctx, &s);
    predict(of_strand(ctx, work.midpoint), &s, work);
    clock.lap(&mut work.phases.forces);
    rest_shape(ctx, &s, work);
    clock.lap(&mut work.phases.bonds);
    if let Some(material) = ctx.physical {
        work.solve_direct(of_strand(ctx, work.midpoint), material, &s);
        if work.midpoint {
            extrapolate(ctx, &s, work);
        }
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
        work.midpoint = takes_midpoint(ctx, s);
        predict(of_strand(ctx, work.midpoint), s, work);
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
        let work = &works[lane];
        direct_input(
            of_strand(ctx, work.midpoint),
            material,
            &strands[lane],
            work,
        )
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
    for (s, work) in strands.iter().zip(works.iter_mut()).take(lanes) {
        if work.midpoint {
            extrapolate(ctx, s, work);
        }
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
        work.midpoint = false;
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
    if work.midpoint {
        // `extrapolate` found them.
        return all_finite(&work.p[..n], &work.v[..n], &work.q[..m], &work.omega[..m]);
    }
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
        work.omega[e] = math::turn_rate(work.q[e], work.q_old[e], ctx.inv_dt);
    }
    all_finite(&work.p[..n], &work.v[..n], &work.q[..m], &work.omega[..m])
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
