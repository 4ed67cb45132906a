//! The workload `groombake bench` and the criterion benches time: a
//! generated scalp groom (the default head's cap, ellipsoid 0.08 x 0.10 x
//! 0.09 m), optionally with hair-hair on and a head collider, stepped on a
//! given thread pool.
//!
//! Phase shares come from ablation: the same workload is also run
//! without hair-hair and without the collider, and each phase's share is
//! the difference in CPU time per step. The run without them has the
//! solver's phase clock on (`Solver::set_phase_clock`: a clock read at
//! each phase's end of a strand group's step; it reads and adds only, so
//! it cannot touch a result), which splits the rod solver's share into
//! forces, constraints and bonds. With render hair the
//! simulated strands are guides: every frame (24 per second) the render
//! hairs are interpolated from them with the groom crate's
//! [`RenderHair`] (as a bake's animated export does) and written to an
//! animated Alembic file in the temporary folder (removed after); those
//! two phases are timed by the process's CPU clock around them, outside
//! the solver.

use crate::sim::parry3d::math::Vector;
use crate::sim::parry3d::shape::SharedShape;
use crate::sim::{
    self, Collider, ColliderSet, Environment, Material, Model, PhaseTimes, Pose, SimError, Solver,
    SolverParameters, StrandSet,
};
use groom::interpolate::{InterpolationOptions, RenderHair};
use std::path::PathBuf;
use std::time::Instant;

/// The head collider of the workload.
#[derive(Debug, Clone, PartialEq)]
pub enum HeadCollider {
    None,
    /// A ball of the head's smallest semi-axis (0.08 m) at its centre.
    Ball,
    /// A triangle mesh in metres, Y up, centred on the head (the sample
    /// `samples/head.obj` fits the scalp).
    Mesh(PathBuf),
}

/// What to time.
#[derive(Debug, Clone, PartialEq)]
pub struct Workload {
    pub strands: usize,
    pub vertices: usize,
    /// The elastic model (real hair's defaults for the physical one).
    pub model: Model,
    pub iterations: u32,
    /// The physical model's Newton tolerance (`SolverParameters::tolerance`;
    /// 0: every strand gets all `iterations`).
    pub tolerance: f32,
    /// `alpha` of the hair-hair penalty (20); `None` leaves it off.
    pub hair_hair: Option<f32>,
    /// Coulomb friction between hairs with pairwise hair-hair (physical
    /// model; `SolverParameters::hair_friction`); `None`: frictionless.
    pub hair_friction: Option<f32>,
    /// Volumetric hair-hair (replaces the pairwise penalty when set).
    pub volumetric: Option<crate::sim::Volumetric>,
    pub collider: HeadCollider,
    /// Render hairs grown between the strands (which are then guides),
    /// interpolated and exported every frame; `None`: none.
    pub render: Option<usize>,
    /// A pillow: a slab (8 x 40 x 40 cm) that moves in from outside the hair
    /// and presses against the left side of
    /// the head, as in `samples/full_head.toml`.
    pub pillow: bool,
    /// The bond treatment of every step.
    pub treatment: Treatment,
}

/// The bond treatment of every step of a workload: what a stage's bond
/// drive costs (the rest shape and bond update of a driven step do more
/// than those of a still one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Treatment {
    /// No drive: a press or settle stage.
    #[default]
    Still,
    /// A wet stage: hydrogen bonds driven to 0 over 0.2 s (then held there,
    /// still driven).
    Wet,
    /// A blow-dry stage as in `samples/blow_dry.toml`: a blower from the
    /// left side across the crown, whose wind re-forms hydrogen bonds (21).
    BlowDry,
}

impl Treatment {
    /// Every treatment, in the order `bench --help` lists them.
    pub const ALL: [Treatment; 3] = [Treatment::Still, Treatment::Wet, Treatment::BlowDry];

    /// The name `bench --treatment` takes.
    pub fn name(self) -> &'static str {
        match self {
            Treatment::Still => "still",
            Treatment::Wet => "wet",
            Treatment::BlowDry => "blow-dry",
        }
    }

    /// The treatment of a name of [`Treatment::name`].
    pub fn from_name(name: &str) -> Option<Treatment> {
        Treatment::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The step's environment (gravity on, as in a stage).
    pub fn environment(self) -> Environment<'static> {
        match self {
            Treatment::Still => Environment::default(),
            Treatment::Wet => Environment {
                bond_rate_drive: [1.0 / 0.2, 0.0, 0.0, 0.0],
                bond_rate_targets: [Some(0.0), None, None, None],
                ..Environment::default()
            },
            Treatment::BlowDry => Environment {
                blower: Some(crate::sim::Blower {
                    from: [-0.30, 0.10, 0.0],
                    to: [0.0, 0.10, 0.0],
                    strength: 40.0,
                    hydrogen_rate: 0.003,
                    falloff_length: 1.0,
                    cone_half_angle: None,
                }),
                ..Environment::default()
            },
        }
    }
}

/// The time step of every workload, seconds (the solver's default).
pub fn step_dt() -> f32 {
    SolverParameters::default().dt
}

/// Frames per second of the render hair's export.
pub const EXPORT_FPS: f64 = 24.0;
/// The most render hairs a bench may ask for (as a timeline).
pub const MAX_RENDER: usize = crate::timeline::render::MAX_RENDER_STRANDS;

impl Workload {
    /// `strands` x `vertices` of free hair (no collider, hair-hair, render
    /// hair or pillow) in still steps: the physical model at its default
    /// iterations and tolerance.
    pub fn free_hair(strands: usize, vertices: usize) -> Workload {
        Workload {
            strands,
            vertices,
            model: Model::Physical,
            iterations: Model::Physical.default_iterations(),
            tolerance: Model::Physical.default_tolerance(),
            hair_hair: None,
            hair_friction: None,
            volumetric: None,
            collider: HeadCollider::None,
            render: None,
            pillow: false,
            treatment: Treatment::Still,
        }
    }

    /// The full-head preset of issue 16: 5,000 guides x 32 vertices driving
    /// 100,000 render hairs, the mesh head `head`, a pillow, pairwise
    /// hair-hair on (alpha 5), the physical model at its default iterations
    /// (dt 1/360 is the solver's default).
    pub fn full_head(head: PathBuf) -> Workload {
        Workload {
            hair_hair: Some(5.0),
            collider: HeadCollider::Mesh(head),
            render: Some(100_000),
            pillow: true,
            ..Workload::free_hair(5_000, 32)
        }
    }
}

/// Why the workload cannot run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Generator(#[from] crate::generate::GeneratorError),
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error(transparent)]
    Import(#[from] importers::ImportError),
    #[error("{0} strands turned non-finite")]
    NonFinite(usize),
}

/// Everything one run steps: state, solver and colliders.
pub struct Scene {
    pub strands: StrandSet,
    pub solver: Solver,
    pub colliders: ColliderSet,
    /// Every step's environment (the workload's treatment).
    environment: Environment<'static>,
    delivery: Option<Delivery>,
    steps: u64,
    /// Constraint solves of all strands so far (`StepReport::solves`).
    solves: u64,
    /// The solver's phase times so far, when its phase clock is on
    /// (`StepReport::phases`).
    phases: PhaseTimes,
}

/// The render hair and its animated export.
struct Delivery {
    hair: RenderHair,
    guide_counts: Vec<u32>,
    writer: Option<Box<dyn exporters::FrameWriter>>,
    path: PathBuf,
    /// A frame every this many steps.
    every: u64,
    frames: usize,
    /// CPU nanoseconds (all threads) spent in each phase so far.
    interpolation_ns: u64,
    export_ns: u64,
}

impl Drop for Delivery {
    fn drop(&mut self) {
        // An unfinished writer removes its temporary file as it drops; a
        // finished one left the file in place.
        if self.writer.take().is_none() {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

impl Workload {
    pub fn check(&self) -> Result<(), BenchError> {
        if self.vertices < 2 || self.vertices > 10_001 {
            return Err(BenchError::Input(
                "--vertices must be between 2 and 10001".into(),
            ));
        }
        if self.strands == 0 || self.strands.saturating_mul(self.vertices) > 50_000_000 {
            return Err(BenchError::Input(
                "--strands must be at least 1 and --strands x --vertices at most 50,000,000".into(),
            ));
        }
        if !(self.tolerance.is_finite() && (0.0..=0.01).contains(&self.tolerance)) {
            return Err(BenchError::Input(
                "--tolerance must be between 0 and 0.01".into(),
            ));
        }
        if self.render.is_some_and(|r| r == 0 || r > MAX_RENDER) {
            return Err(BenchError::Input(format!(
                "--render must be between 1 and {MAX_RENDER}"
            )));
        }
        Ok(())
    }

    /// The strands, solver and collider of this workload.
    pub fn scene(&self) -> Result<Scene, BenchError> {
        self.check()?;
        let groom = sim::bench_groom(self.strands, self.vertices)?;
        let solver = Solver::new(SolverParameters {
            iterations: self.iterations,
            tolerance: self.tolerance,
            hair_hair_strength: self.hair_hair,
            hair_friction: self.hair_friction,
            volumetric: self.volumetric,
            ..SolverParameters::default()
        })?;
        let material = Material {
            model: self.model,
            ..Material::default()
        };
        let strands = StrandSet::from_groom(&groom, &material)?;
        let mut colliders = ColliderSet::new();
        let shape = match &self.collider {
            HeadCollider::None => None,
            HeadCollider::Ball => Some(SharedShape::ball(0.08)),
            HeadCollider::Mesh(path) => {
                let (vertices, triangles) = importers::mesh::read_triangles(path)?;
                let vertices = vertices
                    .iter()
                    .map(|v| Vector::new(v[0], v[1], v[2]))
                    .collect();
                Some(SharedShape::trimesh(vertices, triangles).map_err(|e| {
                    BenchError::Input(format!(
                        "{}: not a usable collider mesh: {e}",
                        path.display()
                    ))
                })?)
            }
        };
        if let Some(shape) = shape {
            colliders.insert(Collider::new("head", shape, Pose::IDENTITY, 0.3));
        }
        if self.pillow {
            let slab = SharedShape::cuboid(0.04, 0.2, 0.2);
            let pose = pillow_pose(0.0);
            colliders.insert(Collider::new(PILLOW, slab, pose, 0.6));
        }
        let delivery = match self.render {
            Some(count) => Some(Delivery::start(&groom, &solver, count)?),
            None => None,
        };
        Ok(Scene {
            strands,
            solver,
            colliders,
            environment: self.treatment.environment(),
            delivery,
            steps: 0,
            solves: 0,
            phases: PhaseTimes::default(),
        })
    }
}

/// Hair resting on hair for the friction bench (issue 33): `strands`
/// strands of 24 cm real hair x `vertices`, combed down (drape 12 rad/m,
/// as `samples/wind.toml` was before its combed head) from the cap of a
/// head-size ball (radius 8 cm,
/// also the collider, friction 0.3), pairwise hair-hair on (alpha 5) and
/// `hair_friction` (`None`: frictionless), then `settle` steps of gravity
/// without hair-hair friction, so the hair lies on the ball and on itself
/// (the same start with and without friction).
pub fn resting_hair(
    strands: usize,
    vertices: usize,
    hair_friction: Option<f32>,
    settle: usize,
) -> Result<Scene, BenchError> {
    let groom = crate::generate::generate(&crate::generate::GeneratorParameters {
        strands,
        length: 0.24,
        segment_length: 0.24 / (vertices.max(2) - 1) as f32,
        head_radii: [0.08; 3],
        drape: 12.0,
        ..Default::default()
    })?;
    let parameters = SolverParameters {
        hair_hair_strength: Some(5.0),
        ..SolverParameters::default()
    };
    let mut scene = Scene {
        strands: StrandSet::from_groom(&groom, &Material::default())?,
        solver: Solver::new(parameters)?,
        colliders: ColliderSet::new(),
        environment: Environment::default(),
        delivery: None,
        steps: 0,
        solves: 0,
        phases: PhaseTimes::default(),
    };
    scene.colliders.insert(Collider::new(
        "head",
        SharedShape::ball(0.08),
        Pose::IDENTITY,
        0.3,
    ));
    for _ in 0..settle {
        scene.step()?;
    }
    scene.solver.set_parameters(SolverParameters {
        hair_friction,
        ..parameters
    })?;
    Ok(scene)
}

impl Delivery {
    /// Grows `count` render hairs between the guides (as `[groom] render`
    /// does) and opens the animated export.
    fn start(guides: &groom::Groom, solver: &Solver, count: usize) -> Result<Delivery, BenchError> {
        let hair = RenderHair::grow(
            guides,
            count,
            InterpolationOptions {
                clump: 0.15,
                noise: 0.002,
                seed: 1,
            },
        );
        let path = std::env::temp_dir().join(format!(
            "groombake-bench-{}-{}.abc",
            std::process::id(),
            NEXT_EXPORT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        let joined = hair.joined(guides);
        let steps_per_second = 1.0 / f64::from(solver.parameters().dt);
        let writer = exporters::animated(
            &path,
            &joined,
            exporters::AnimationOptions {
                fps: EXPORT_FPS,
                frame_count: 1,
            },
        )
        .map_err(|e| BenchError::Input(e.to_string()))?;
        Ok(Delivery {
            hair,
            guide_counts: guides.strand_vertex_counts.clone(),
            writer: Some(writer),
            path,
            every: (steps_per_second / EXPORT_FPS).round().max(1.0) as u64,
            frames: 0,
            interpolation_ns: 0,
            export_ns: 0,
        })
    }

    /// Interpolates the render hair of the guides' pose and writes it.
    fn frame(&mut self, guide_points: &[[f32; 3]]) -> Result<(), BenchError> {
        let clock = || process_cpu_ns().unwrap_or(0);
        let start = clock();
        let points = self.hair.joined_points(&self.guide_counts, guide_points);
        let interpolated = clock();
        if let Some(writer) = self.writer.as_mut() {
            writer
                .write_frame(&groom::Frame {
                    time: self.frames as f64 / EXPORT_FPS,
                    points,
                    attributes: Vec::new(),
                })
                .map_err(|e| BenchError::Input(e.to_string()))?;
        }
        let written = clock();
        self.frames += 1;
        self.interpolation_ns += interpolated.saturating_sub(start);
        self.export_ns += written.saturating_sub(interpolated);
        Ok(())
    }
}

/// The pillow collider's name.
const PILLOW: &str = "pillow";

/// Where the pillow is `t` seconds into the run. It comes in from outside
/// the hair (its inner face starts at x = -0.36 m, beyond the 24 cm strands'
/// reach) at the full-head sample's 18 cm/s and stops pressed against the
/// left of the head at x = -0.135 m (after about 1.5 s): a collider placed
/// inside the hair would cut strands apart, not press them.
fn pillow_pose(t: f32) -> Pose {
    const START_X: f32 = -0.40;
    const PRESSED_X: f32 = -0.135;
    const SPEED: f32 = 0.18;
    Pose::from_parts(
        Vector::new((START_X + SPEED * t).min(PRESSED_X), 0.0, 0.0),
        crate::sim::parry3d::math::Rot3::from_axis_angle(Vector::Z, (-10.0f32).to_radians()),
    )
}

/// Distinguishes the exports of one process.
static NEXT_EXPORT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

impl Scene {
    /// One step of the workload.
    pub fn step(&mut self) -> Result<(), BenchError> {
        let dt = self.solver.parameters().dt;
        if let Some(pillow) = self.colliders.get_mut(PILLOW) {
            pillow.move_to(pillow_pose((self.steps + 1) as f32 * dt), dt);
        }
        let report = self
            .solver
            .step(&mut self.strands, &self.colliders, &self.environment)?;
        if !report.contained.is_empty() {
            return Err(BenchError::NonFinite(report.contained.len()));
        }
        self.steps += 1;
        self.solves += report.solves;
        if let Some(phases) = report.phases {
            self.phases += phases;
        }
        if let Some(delivery) = self.delivery.as_mut() {
            if self.steps.is_multiple_of(delivery.every) {
                delivery.frame(self.strands.positions())?;
            }
        }
        Ok(())
    }

    /// CPU seconds spent interpolating and exporting so far.
    fn delivery_cpu(&self) -> (f64, f64) {
        self.delivery.as_ref().map_or((0.0, 0.0), |d| {
            (d.interpolation_ns as f64 * 1e-9, d.export_ns as f64 * 1e-9)
        })
    }
}

/// Timing of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    pub steps: usize,
    pub seconds: f64,
    /// Constraint solves of all strands in the timed steps.
    pub solves: u64,
    /// CPU time of all threads of the process, when the platform says.
    pub cpu_seconds: Option<f64>,
    /// Of that, CPU seconds interpolating the render hair and exporting it.
    pub interpolation_seconds: f64,
    pub export_seconds: f64,
    /// The solver's phase times in the timed steps (zero unless its phase
    /// clock was on).
    pub phases: PhaseTimes,
}

impl Timing {
    /// CPU seconds per step (wall seconds where CPU time is unknown).
    pub fn cpu_per_step(&self) -> f64 {
        self.cpu_seconds.unwrap_or(self.seconds) / self.steps as f64
    }
}

/// Steps `scene` 10 times untimed, then `steps` times (by default as many
/// as fit in about `budget` seconds; with render hair, rounded up to whole
/// frame periods) on the current thread pool.
pub fn time(scene: &mut Scene, steps: Option<usize>, budget: f64) -> Result<Timing, BenchError> {
    // With render hair, whole frame periods: the timed steps then hold
    // exactly one frame per period, as a bake's do.
    let period = scene.delivery.as_ref().map_or(1, |d| d.every as usize);
    for _ in 0..10usize.next_multiple_of(period) {
        scene.step()?;
    }
    let steps = match steps {
        Some(steps) => steps.max(1),
        None => {
            let start = Instant::now();
            scene.step()?;
            let one = start.elapsed().as_secs_f64().max(1e-6);
            ((budget / one) as usize).clamp(3, 10_000)
        }
    };
    if !scene.steps.is_multiple_of(period as u64) {
        // The budget's probe step: back on a period boundary.
        for _ in scene.steps % period as u64..period as u64 {
            scene.step()?;
        }
    }
    let steps = steps.next_multiple_of(period);
    let delivered = scene.delivery_cpu();
    let solves_before = scene.solves;
    let phases_before = scene.phases;
    let cpu_start = process_cpu_ns();
    let start = Instant::now();
    for _ in 0..steps {
        scene.step()?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let solves = scene.solves - solves_before;
    let (interpolation, export) = scene.delivery_cpu();
    if let Some(writer) = scene.delivery.as_mut().and_then(|d| d.writer.take()) {
        // The file is complete, as a bake's; `Delivery`'s drop removes it.
        writer
            .finish()
            .map_err(|e| BenchError::Input(e.to_string()))?;
    }
    let cpu_seconds = match (cpu_start, process_cpu_ns()) {
        (Some(a), Some(b)) => Some(b.saturating_sub(a) as f64 * 1e-9),
        _ => None,
    };
    Ok(Timing {
        steps,
        seconds,
        solves,
        cpu_seconds,
        interpolation_seconds: interpolation - delivered.0,
        export_seconds: export - delivered.1,
        phases: scene.phases - phases_before,
    })
}

/// Shares of the step's CPU time, by ablation (fractions summing to 1;
/// `None` for phases not in the workload).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Shares {
    /// The rod solver: forces, constraints, bonds, velocities.
    pub solver: f64,
    /// The solver's share split by its phase clock
    /// (`Solver::set_phase_clock`): external forces, prediction,
    /// velocities and commit; the constraint solve; the bonds.
    pub forces: f64,
    pub constraints: f64,
    pub bonds: f64,
    pub collisions: Option<f64>,
    pub hair_hair: Option<f64>,
    pub interpolation: Option<f64>,
    pub export: Option<f64>,
}

/// The full report of `groombake bench`.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub workload: Workload,
    pub threads: usize,
    pub timing: Timing,
    pub shares: Shares,
    /// Peak resident memory of the process, bytes (Linux).
    pub peak_memory: Option<u64>,
}

impl Report {
    fn vertex_count(&self) -> f64 {
        (self.workload.strands * self.workload.vertices) as f64
    }

    /// Wall nanoseconds per vertex per step.
    pub fn ns_per_vertex_step(&self) -> f64 {
        self.timing.seconds * 1e9 / (self.timing.steps as f64 * self.vertex_count())
    }

    /// Constraint solves (Newton iterations, paper sweeps) a strand got
    /// per step, on average over the timed steps.
    pub fn solves_per_strand_step(&self) -> f64 {
        self.timing.solves as f64 / (self.timing.steps as f64 * self.workload.strands as f64)
    }

    /// Wall nanoseconds per vertex per constraint iteration (as many as
    /// the strands got on average).
    pub fn ns_per_vertex_iteration(&self) -> f64 {
        self.ns_per_vertex_step() / self.solves_per_strand_step().max(1.0)
    }

    /// Wall seconds per simulated second (steps of `dt`, with the frames
    /// the render hair delivers in that time).
    pub fn seconds_per_simulated_second(&self, dt: f32) -> f64 {
        self.timing.seconds / (self.timing.steps as f64 * f64::from(dt))
    }

    /// CPU seconds (user + system, all threads of the process) per
    /// simulated second: unlike wall time, not stretched by other
    /// processes sharing the cores.
    pub fn cpu_seconds_per_simulated_second(&self, dt: f32) -> Option<f64> {
        self.timing
            .cpu_seconds
            .map(|cpu| cpu / (self.timing.steps as f64 * f64::from(dt)))
    }

    /// CPU nanoseconds (all threads) per vertex per step.
    pub fn cpu_ns_per_vertex_step(&self) -> Option<f64> {
        self.timing
            .cpu_seconds
            .map(|cpu| cpu * 1e9 / (self.timing.steps as f64 * self.vertex_count()))
    }
}

/// Times `workload` on the current thread pool; then the same workload
/// without hair-hair, colliders and render hair with the solver's phase
/// clock on (the solver's share and its split into forces, constraints
/// and bonds); with hair-hair or a collider, also the run with the
/// collider alone (the collisions' share).
pub fn run(
    workload: &Workload,
    steps: Option<usize>,
    budget: f64,
    threads: usize,
) -> Result<Report, BenchError> {
    let timing = time(&mut workload.scene()?, steps, budget)?;
    // Before the runs below, which only add to it.
    let peak = peak_memory();
    let with_collider = workload.collider != HeadCollider::None || workload.pillow;
    let delivering = workload.render.is_some();
    let hair_hair_on = workload.hair_hair.is_some() || workload.volumetric.is_some();
    let base_timing = {
        let mut scene = Workload {
            hair_hair: None,
            volumetric: None,
            collider: HeadCollider::None,
            pillow: false,
            render: None,
            ..workload.clone()
        }
        .scene()?;
        scene.solver.set_phase_clock(true);
        time(&mut scene, Some(timing.steps), budget)?
    };
    let mut shares = Shares {
        solver: 1.0,
        ..Shares::default()
    };
    if hair_hair_on || with_collider || delivering {
        let cost = |w: Workload| -> Result<f64, BenchError> {
            Ok(time(&mut w.scene()?, Some(timing.steps), budget)?.cpu_per_step())
        };
        let steps = timing.steps as f64;
        let interpolation = delivering.then_some(timing.interpolation_seconds / steps);
        let export = delivering.then_some(timing.export_seconds / steps);
        let total = timing.cpu_per_step() - interpolation.unwrap_or(0.0) - export.unwrap_or(0.0);
        let base = base_timing.cpu_per_step();
        let collisions = if with_collider {
            let with = cost(Workload {
                hair_hair: None,
                volumetric: None,
                render: None,
                ..workload.clone()
            })?;
            Some((with - base).max(0.0))
        } else {
            None
        };
        let hair_hair = hair_hair_on.then(|| (total - base - collisions.unwrap_or(0.0)).max(0.0));
        let sum = base
            + collisions.unwrap_or(0.0)
            + hair_hair.unwrap_or(0.0)
            + interpolation.unwrap_or(0.0)
            + export.unwrap_or(0.0);
        shares = Shares {
            solver: base / sum,
            collisions: collisions.map(|c| c / sum),
            hair_hair: hair_hair.map(|h| h / sum),
            interpolation: interpolation.map(|i| i / sum),
            export: export.map(|e| e / sum),
            ..Shares::default()
        };
    }
    // The solver's share in the proportions of its phases' clocked times
    // (the time between phases, a small remainder, goes with them).
    let phases = base_timing.phases;
    let clocked = (phases.forces + phases.constraints + phases.bonds) as f64;
    if clocked > 0.0 {
        shares.forces = shares.solver * phases.forces as f64 / clocked;
        shares.constraints = shares.solver * phases.constraints as f64 / clocked;
        shares.bonds = shares.solver * phases.bonds as f64 / clocked;
    }
    Ok(Report {
        workload: workload.clone(),
        threads,
        timing,
        shares,
        peak_memory: peak,
    })
}

/// CPU time of every thread of this process so far, in nanoseconds
/// (`CLOCK_PROCESS_CPUTIME_ID`: it keeps the time of threads that have
/// ended, so it never falls between two readings; summing the live
/// threads' `/proc/self/task/*/schedstat` did when a thread pool ended in
/// between, and a short run's CPU time came out as 0). `None` where the
/// clock is not available.
fn process_cpu_ns() -> Option<u64> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid timespec the call writes.
    if unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut now) } != 0 {
        return None;
    }
    let seconds = u64::try_from(now.tv_sec).ok()?;
    let nanoseconds = u64::try_from(now.tv_nsec).ok()?;
    Some(
        seconds
            .saturating_mul(1_000_000_000)
            .saturating_add(nanoseconds),
    )
}

/// Peak resident set size (`VmHWM` of `/proc/self/status`), bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Positions after 30 steps on the mesh head on `threads` threads.
    fn positions_bits(threads: usize, hair_hair: Option<f32>) -> Vec<u32> {
        positions_bits_with(threads, hair_hair, None)
    }

    /// [`positions_bits`] with Coulomb friction between hairs `mu`.
    fn positions_bits_with(threads: usize, hair_hair: Option<f32>, mu: Option<f32>) -> Vec<u32> {
        let workload = Workload {
            iterations: 5,
            hair_hair,
            hair_friction: mu,
            collider: HeadCollider::Mesh(
                concat!(env!("CARGO_MANIFEST_DIR"), "/samples/head.obj").into(),
            ),
            ..Workload::free_hair(300, 24)
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        // Built inside: a scene with render hair holds its exporter,
        // which stays on one thread.
        pool.install(|| {
            let mut scene = workload.scene().unwrap();
            (0..30).try_for_each(|_| scene.step()).unwrap();
            scene
                .strands
                .positions()
                .iter()
                .flat_map(|p| p.map(f32::to_bits))
                .collect()
        })
    }

    /// Each treatment does what its name says: a wet step breaks the
    /// hydrogen bonds at its rate, a blow-dry step blows the hair downwind
    /// (from the left, -x, to +x), a still step does neither.
    #[test]
    fn treatments_break_bonds_and_blow_the_hair_as_named() {
        let run = |treatment| {
            let workload = Workload {
                treatment,
                ..Workload::free_hair(64, 16)
            };
            let mut scene = workload.scene().unwrap();
            // 0.1 s: half of the wet stage's 0.2 s soak.
            (0..36).try_for_each(|_| scene.step()).unwrap();
            scene.strands
        };
        let mean_x = |s: &StrandSet| {
            s.positions().iter().map(|p| p[0] as f64).sum::<f64>() / s.vertex_count() as f64
        };
        let hydrogen = |s: &StrandSet| s.bond_rates(crate::sim::BondKind::Hydrogen).to_vec();
        let still = run(Treatment::Still);
        let wet = run(Treatment::Wet);
        let blown = run(Treatment::BlowDry);
        assert!(hydrogen(&still).iter().all(|b| *b == 1.0));
        // Intact bonds stay so under the blower (it only re-forms them).
        assert!(hydrogen(&blown).iter().all(|b| *b == 1.0));
        for b in hydrogen(&wet) {
            assert!((b - 0.5).abs() < 0.02, "{b}");
        }
        // Wetting alone does not move the hair; the wind does, downwind.
        let drift = mean_x(&blown) - mean_x(&still);
        eprintln!(
            "blow-dry drift along x: {drift} m; wet: {}",
            mean_x(&wet) - mean_x(&still)
        );
        assert!(drift > 0.01, "blow-dry moved the hair {drift} m along x");
        assert!((mean_x(&wet) - mean_x(&still)).abs() < 1e-4);
    }

    #[test]
    fn hair_hair_on_a_mesh_head_is_bit_identical_for_any_thread_count() {
        let one = positions_bits(1, Some(5.0));
        assert_eq!(one, positions_bits(2, Some(5.0)));
        assert_eq!(one, positions_bits(3, Some(5.0)));
        // Hair touched hair: the penalty changed the result.
        assert_ne!(one, positions_bits(1, None));
    }

    /// Friction between hairs (issue 33): contacts found from the state at
    /// the start of the step, each strand solved against the others as
    /// kinematic targets, so no result depends on the thread count.
    #[test]
    fn hair_friction_on_a_mesh_head_is_bit_identical_for_any_thread_count() {
        let one = positions_bits_with(1, Some(5.0), Some(0.3));
        assert_eq!(one, positions_bits_with(3, Some(5.0), Some(0.3)));
        // The contacts acted: friction changed the result.
        assert_ne!(one, positions_bits(1, Some(5.0)));
    }

    #[test]
    fn render_hair_is_interpolated_and_exported_every_frame_and_the_file_removed() {
        let workload = Workload {
            render: Some(400),
            pillow: true,
            ..Workload::free_hair(40, 8)
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let report = pool.install(|| run(&workload, Some(20), 1.0, 1)).unwrap();
        // Whole frame periods: 20 steps become 30 (a frame every 15).
        assert_eq!(report.timing.steps, 30);
        let shares = report.shares;
        // Both phases ran and were timed; their sizes are the bench's
        // measurement, not this test's (a share found by ablation can come
        // out as 0 on a loaded machine).
        assert!(shares.interpolation.is_some_and(|s| s >= 0.0), "{shares:?}");
        assert!(shares.export.is_some_and(|s| s >= 0.0), "{shares:?}");
        assert!(shares.collisions.is_some(), "the pillow is a collider");
        let sum = shares.solver
            + shares.collisions.unwrap_or(0.0)
            + shares.interpolation.unwrap_or(0.0)
            + shares.export.unwrap_or(0.0);
        assert!((sum - 1.0).abs() < 1e-9, "{sum}");
        // The solver's share, split by its phase clock.
        let split = shares.forces + shares.constraints + shares.bonds;
        assert!((split - shares.solver).abs() < 1e-9, "{shares:?}");
        assert!(
            shares.forces > 0.0 && shares.constraints > 0.0 && shares.bonds > 0.0,
            "{shares:?}"
        );
        let prefix = format!("groombake-bench-{}-", std::process::id());
        let left: Vec<_> = std::fs::read_dir(std::env::temp_dir())
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }
}
