//! Runs a timeline: builds the strands and colliders, steps the solver
//! through every stage, streams animated exports, writes the final, rest
//! and state exports, and reports.

use super::motion::{pose_at, Pose as KeyPose};
use super::report::{size_and_sha256, BakeReport, OutputReport, StageReport};
use super::schema::{ColliderActivity, ExportWhat, ShapeSpec, StageKind};
use super::stages::{drive_wetness, PermRods, StagePlan, WindPlan};
use super::{Timeline, TimelineError};
use crate::sim::{
    self, attribute_names, Collider, ColliderSet, Material, Solver, SolverParameters, StrandSet,
};
use groom::{Frame, Groom, Units, UpAxis};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run a bake.
#[derive(Debug, Clone, Default)]
pub struct BakeOptions {
    /// Folder that relative export paths are taken from.
    pub out_dir: PathBuf,
    /// Worker threads; `None` = rayon's default.
    pub threads: Option<usize>,
    /// Overrides the timeline's seed.
    pub seed: Option<u64>,
    /// Show progress bars (the caller decides: `-q`, not a terminal).
    pub progress: bool,
    /// Run without writing the timeline's exports and sheet (a preview of
    /// the timeline keeps only the snapshots).
    pub dry: bool,
}

/// What a bake leaves besides its files: the report and the groom before
/// the first stage and after each stage (with bond rates and wetness).
pub struct BakeOutcome {
    pub report: BakeReport,
    pub snapshots: Vec<(String, Groom)>,
}

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Timeline(#[from] TimelineError),
    #[error(transparent)]
    Import(#[from] importers::ImportError),
    #[error(transparent)]
    Export(#[from] exporters::ExportError),
    #[error("{}: {message}", file.display())]
    Input { file: PathBuf, message: String },
    #[error("simulation: {0}")]
    Simulation(#[from] sim::SimError),
    #[error("{}: {source}", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("thread pool: {0}")]
    Threads(String),
    #[error(transparent)]
    Preview(#[from] crate::preview::PreviewError),
}

impl BakeError {
    /// Bad input (exit 2) rather than a failure during the work (exit 1).
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            BakeError::Timeline(_) | BakeError::Import(_) | BakeError::Input { .. }
        )
    }
}

/// Everything a bake starts from, prepared (and so checked) before any step.
pub struct Prepared {
    pub groom: Groom,
    pub strands: StrandSet,
    pub colliders: ColliderSet,
    pub parameters: SolverParameters,
    pub seed: u64,
}

/// The material of the timeline in the solver's terms.
pub fn material_of(timeline: &Timeline) -> Material {
    let m = &timeline.file.material;
    Material {
        model: *m.model.get_ref(),
        stiffness: *m.stiffness.get_ref(),
        youngs_modulus: *m.youngs_modulus.get_ref(),
        shear_modulus: m.shear_modulus.as_ref().map(|g| *g.get_ref()),
        poisson_ratio: *m.poisson_ratio.get_ref(),
        density: *m.density.get_ref(),
        radius: m.radius.as_ref().map(|r| *r.get_ref()),
        // Per cm in the file, per metre in the solver.
        cuticle_peel_per_meter: *m.cuticle_peel_per_cm.get_ref() * 100.0,
        bond_influences: m.bonds.get_ref().as_array(),
    }
}

/// The solver parameters of the timeline.
pub fn parameters_of(timeline: &Timeline) -> SolverParameters {
    let s = &timeline.file.solver;
    let damping = s.damping.get_ref();
    SolverParameters {
        dt: timeline.dt as f32,
        iterations: *s.iterations.get_ref(),
        gravity: s.gravity,
        hair_radius: *s.hair_radius.get_ref(),
        hair_hair_strength: s.hair_hair.as_ref().map(|h| h.get_ref().strength),
        linear_damping: damping.linear,
        angular_damping: damping.angular,
        quaternion_mass_scale: *s.quaternion_mass_scale.get_ref(),
        ..SolverParameters::default()
    }
}

/// Loads the groom of a timeline in metres, Y up.
pub fn load_groom(timeline: &Timeline) -> Result<Groom, BakeError> {
    let spec = &timeline.file.groom;
    let mut groom = match (&spec.source, &spec.generate) {
        (Some(source), _) => {
            let path = timeline.resolve(source.get_ref());
            let mut groom = importers::read(&path)?;
            // Only formats that do not record units take the timeline's word.
            if !matches!(groom.provenance.format.as_str(), "usd" | "gltf") {
                if let Some(units) = &spec.units {
                    groom.units = units
                        .get_ref()
                        .parse()
                        .map_err(|m: String| timeline.error_at(units.span(), m))?;
                }
                if let Some(up) = &spec.up {
                    groom.up_axis = up
                        .get_ref()
                        .parse()
                        .map_err(|m: String| timeline.error_at(up.span(), m))?;
                }
            }
            if let Some(problem) = groom.first_fatal_problem() {
                return Err(BakeError::Input {
                    file: path,
                    message: problem.to_string(),
                });
            }
            groom
        }
        (None, Some(parameters)) => crate::generate::generate(parameters.get_ref())
            .map_err(|e| timeline.error_at(parameters.span(), e.to_string()))?,
        (None, None) => {
            return Err(timeline
                .error_at(0..0, "[groom] needs `source` or `generate`")
                .into())
        }
    };
    groom.convert_to(Units::METERS, UpAxis::Y);
    groom.frames.clear();
    if spec.translate != [0.0; 3] {
        for p in &mut groom.points {
            for (c, t) in p.iter_mut().zip(spec.translate) {
                *c += t;
            }
        }
    }
    Ok(groom)
}

fn shape_of(
    timeline: &Timeline,
    spec: &ShapeSpec,
) -> Result<sim::parry3d::shape::SharedShape, BakeError> {
    use sim::parry3d::math::Vector;
    use sim::parry3d::shape::SharedShape;
    Ok(match spec {
        ShapeSpec::HalfSpace { normal } => {
            SharedShape::halfspace(Vector::new(normal[0], normal[1], normal[2]).normalize())
        }
        ShapeSpec::Cuboid { half_extents: h } => SharedShape::cuboid(h[0], h[1], h[2]),
        ShapeSpec::Ball { radius } => SharedShape::ball(*radius),
        ShapeSpec::Capsule {
            half_height,
            radius,
        } => SharedShape::capsule_y(*half_height, *radius),
        ShapeSpec::Cylinder {
            half_height,
            radius,
        } => SharedShape::cylinder(*half_height, *radius),
        ShapeSpec::Mesh { path, scale } => {
            let file = timeline.resolve(path);
            let (vertices, triangles) = importers::mesh::read_triangles(&file)?;
            let vertices: Vec<Vector> = vertices
                .iter()
                .map(|v| Vector::new(v[0] * scale, v[1] * scale, v[2] * scale))
                .collect();
            SharedShape::trimesh(vertices, triangles).map_err(|e| BakeError::Input {
                file,
                message: format!("not a usable collider mesh: {e}"),
            })?
        }
    })
}

fn pose_of(pose: KeyPose) -> sim::Pose {
    let t = pose.translation.map(|c| c as f32);
    let r = pose.rotation.map(|c| c as f32);
    sim::Pose::from_parts(
        sim::parry3d::math::Vector::new(t[0], t[1], t[2]),
        sim::parry3d::math::Rot3::from_xyzw(r[0], r[1], r[2], r[3]),
    )
}

/// Imports the groom, builds the strands and colliders. Everything that can
/// be wrong with the inputs shows here, before the first step.
pub fn prepare(timeline: &Timeline, seed_override: Option<u64>) -> Result<Prepared, BakeError> {
    let groom = load_groom(timeline)?;
    let material = material_of(timeline);
    // A groom written by a `state` export continues where it stopped; any
    // other starts fresh (bond rates and wetness taken where present).
    let strands = StrandSet::from_state(&groom, &material)?;
    let mut colliders = ColliderSet::new();
    for c in &timeline.file.colliders {
        let shape = shape_of(timeline, c.shape.get_ref())?;
        let pose = pose_of(pose_at(c.motion.get_ref(), 0.0));
        colliders.insert(Collider::new(
            c.name.get_ref().clone(),
            shape,
            pose,
            *c.friction.get_ref(),
        ));
    }
    let parameters = parameters_of(timeline);
    parameters.check()?;
    Ok(Prepared {
        groom,
        strands,
        colliders,
        parameters,
        seed: seed_override.or(timeline.file.seed).unwrap_or(0),
    })
}

/// An animated export under way.
struct AnimatedExport {
    index: usize,
    writer: Box<dyn exporters::FrameWriter>,
    fps: f64,
    frames_written: usize,
    frame_count: usize,
    units: Units,
    up: UpAxis,
}

fn export_units(timeline: &Timeline, index: usize) -> (Units, UpAxis) {
    let e = &timeline.file.exports[index];
    let units = e
        .units
        .as_ref()
        .and_then(|u| u.get_ref().parse().ok())
        .unwrap_or(Units::METERS);
    let up =
        e.up.as_ref()
            .and_then(|u| u.get_ref().parse().ok())
            .unwrap_or(UpAxis::Y);
    (units, up)
}

/// The groom with the current pose and the simulation's per-vertex
/// attributes (bond rates, wetness), and state attributes when asked.
fn groom_now(base: &Groom, strands: &StrandSet, points: Vec<[f32; 3]>, with_state: bool) -> Groom {
    let mut groom = base.clone();
    groom.points = points;
    groom.frames.clear();
    let exported = |name: &str| {
        with_state
            || attribute_names::BOND_RATES.contains(&name)
            || name == attribute_names::WETNESS
    };
    for attribute in strands.to_groom_attributes() {
        if exported(&attribute.name) {
            groom.set_attribute(attribute);
        }
    }
    groom
}

/// The preview options of the timeline's `[preview]` (or the defaults).
pub fn sheet_options(timeline: &Timeline) -> crate::preview::PreviewOptions {
    let mut options = crate::preview::PreviewOptions::default();
    if let Some(p) = &timeline.file.preview {
        let [w, h] = *p.size.get_ref();
        options.width = w;
        options.height = h;
        options.view = p.view.get_ref().parse().unwrap_or(options.view);
        options.color_by = p.color.as_ref().map(|c| c.get_ref().clone());
    }
    options
}

/// Renders the before/after sheet of a bake and writes it as a PNG.
fn write_sheet(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
    path: &Path,
) -> Result<(), BakeError> {
    let options = sheet_options(timeline);
    let entries: Vec<crate::preview::SheetEntry> = snapshots
        .iter()
        .map(|(label, groom)| crate::preview::SheetEntry {
            label,
            groom,
            frame: None,
        })
        .collect();
    let image = crate::preview::render_sheet(&entries, &options)?;
    create_parent(path)?;
    crate::preview::write_png(&image, path)?;
    Ok(())
}

/// Creates the folder an output goes into.
fn create_parent(path: &Path) -> Result<(), BakeError> {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => {
            std::fs::create_dir_all(parent).map_err(|source| BakeError::Io {
                file: path.to_path_buf(),
                source,
            })
        }
        _ => Ok(()),
    }
}

/// The report line of a written output: its size and SHA-256.
fn output_report(
    path: &Path,
    what: String,
    frames: Option<usize>,
) -> Result<OutputReport, BakeError> {
    let (bytes, sha256) = size_and_sha256(path).map_err(|source| BakeError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    Ok(OutputReport {
        path: path.display().to_string(),
        what,
        bytes,
        sha256,
        frames,
    })
}

/// The same state with edge frames rebuilt from the current positions
/// (after a stage that moved the points directly, as the stochastic wind
/// does); bonds, memories, wetness and rest lengths are kept.
fn with_frames_from_positions(
    base: &Groom,
    strands: &StrandSet,
    material: &Material,
) -> Result<StrandSet, BakeError> {
    let mut groom = base.clone();
    groom.points = strands.positions().to_vec();
    for attribute in strands.to_groom_attributes() {
        groom.set_attribute(attribute);
    }
    for name in [
        attribute_names::FRAME_XYZ,
        attribute_names::FRAME_W,
        attribute_names::VELOCITY,
        attribute_names::ANGULAR_VELOCITY,
    ] {
        groom.remove_attribute(name);
    }
    Ok(StrandSet::from_state(&groom, material)?)
}

fn output_path(options: &BakeOptions, path: &str) -> PathBuf {
    let p = Path::new(path);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        options.out_dir.join(p)
    }
}

fn progress_bars(
    options: &BakeOptions,
    total_steps: u64,
) -> (MultiProgress, ProgressBar, ProgressBar) {
    let multi = MultiProgress::with_draw_target(if options.progress {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    });
    let style =
        ProgressStyle::with_template("{prefix:>10} [{bar:40}] {percent:>3}% {msg} (ETA {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
    let overall = multi.add(ProgressBar::new(total_steps));
    overall.set_style(style.clone());
    overall.set_prefix("bake");
    let stage = multi.add(ProgressBar::new(1));
    stage.set_style(style);
    (multi, overall, stage)
}

/// Runs the timeline and writes its exports.
pub fn bake(timeline: &Timeline, options: &BakeOptions) -> Result<BakeOutcome, BakeError> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(threads) = options.threads {
        builder = builder.num_threads(threads);
    }
    let pool = builder
        .build()
        .map_err(|e| BakeError::Threads(e.to_string()))?;
    pool.install(|| bake_in_pool(timeline, options, pool.current_num_threads()))
}

fn bake_in_pool(
    timeline: &Timeline,
    options: &BakeOptions,
    threads: usize,
) -> Result<BakeOutcome, BakeError> {
    let started = Instant::now();
    let Prepared {
        groom,
        mut strands,
        colliders,
        parameters,
        seed,
    } = prepare(timeline, options.seed)?;
    let dt = timeline.dt;
    let plans: Vec<StagePlan> = timeline
        .file
        .stages
        .get_ref()
        .iter()
        .map(StagePlan::new)
        .collect();
    let stage_steps: Vec<u64> = plans
        .iter()
        .map(|p| ((p.duration / dt).round() as u64).max(1))
        .collect();
    let total_steps: u64 = stage_steps.iter().sum();
    let total_time = total_steps as f64 * dt;

    // Open the animated exports and write frame 0.
    let mut animated = Vec::new();
    // A dry run (a preview of the timeline) writes no file.
    let exports: &[super::schema::ExportSpec] = if options.dry {
        &[]
    } else {
        &timeline.file.exports
    };
    for (index, e) in exports.iter().enumerate() {
        if e.what != ExportWhat::Animated {
            continue;
        }
        let fps = e.fps.as_ref().map_or(24.0, |f| *f.get_ref());
        let frame_count = (total_time * fps + 1e-6).floor() as usize + 1;
        let (units, up) = export_units(timeline, index);
        let mut base = groom_now(&groom, &strands, strands.positions().to_vec(), false);
        base.convert_to(units, up);
        let path = output_path(options, e.path.get_ref());
        create_parent(&path)?;
        let writer = exporters::animated(
            &path,
            &base,
            exporters::AnimationOptions { fps, frame_count },
        )?;
        animated.push(AnimatedExport {
            index,
            writer,
            fps,
            frames_written: 0,
            frame_count,
            units,
            up,
        });
    }
    let write_frames = |animated: &mut Vec<AnimatedExport>,
                        strands: &StrandSet,
                        step: u64|
     -> Result<(), BakeError> {
        for a in animated.iter_mut() {
            // Frame k belongs to the step nearest k / fps.
            while a.frames_written < a.frame_count {
                let k = a.frames_written;
                let due = ((k as f64 / a.fps) / dt).round() as u64;
                if due > step {
                    break;
                }
                let mut points = strands.positions().to_vec();
                groom::convert_points(&mut points, (Units::METERS, UpAxis::Y), (a.units, a.up));
                let frame = Frame {
                    time: k as f64 / a.fps,
                    points,
                };
                a.writer.write_frame(&frame)?;
                a.frames_written += 1;
            }
        }
        Ok(())
    };
    write_frames(&mut animated, &strands, 0)?;
    let mut snapshots = vec![(
        "before".to_string(),
        groom_now(&groom, &strands, strands.positions().to_vec(), false),
    )];

    let (_multi, overall, stage_bar) = progress_bars(options, total_steps);
    let mut report = BakeReport {
        timeline: timeline.path.display().to_string(),
        groombake_version: env!("CARGO_PKG_VERSION").to_string(),
        seed,
        threads,
        strands: strands.strand_count(),
        vertices: strands.vertex_count(),
        ..BakeReport::default()
    };
    let mut step_index: u64 = 0;
    let mut global_time = 0.0f64;
    for (stage_index, (plan, &steps)) in plans.iter().zip(&stage_steps).enumerate() {
        let spec = &timeline.file.stages.get_ref()[stage_index];
        let stage_started = Instant::now();
        let name = spec
            .name
            .clone()
            .unwrap_or_else(|| plan.kind.name().to_string());
        stage_bar.reset();
        stage_bar.set_length(steps);
        stage_bar.set_prefix(name.clone());
        let mut stage_report = StageReport {
            index: stage_index,
            kind: plan.kind.name().to_string(),
            name,
            simulated_seconds: steps as f64 * dt,
            steps,
            ..StageReport::default()
        };
        let active: Vec<bool> = timeline
            .file
            .colliders
            .iter()
            .map(|c| {
                c.active == ColliderActivity::Always
                    || spec
                        .colliders
                        .iter()
                        .any(|n| n.get_ref() == c.name.get_ref())
            })
            .collect();
        let mut stage_parameters = parameters;
        if let Some(d) = &spec.damping {
            stage_parameters.linear_damping = d.linear;
            stage_parameters.angular_damping = d.angular;
        }
        let mut solver = Solver::new(stage_parameters)?;
        // The colliders of this stage, where their motion has them now.
        let mut stage_colliders = ColliderSet::new();
        let mut stage_motions = Vec::new();
        for ((collider, spec), &on) in colliders
            .colliders
            .iter()
            .zip(&timeline.file.colliders)
            .zip(&active)
        {
            if on {
                let keys = spec.motion.get_ref().as_slice();
                let mut collider = collider.clone();
                collider.set_pose(pose_of(pose_at(keys, global_time)));
                stage_colliders.insert(collider);
                stage_motions.push(keys);
            }
        }
        if plan.release_targets {
            strands.clear_kinematic_targets();
        }
        let rods = plan
            .perm
            .as_ref()
            .map(|p| PermRods::new(&strands, p, parameters.hair_radius));
        let mut wind = match (plan.kind, &plan.wind) {
            (StageKind::Wind, Some(spec)) => Some(WindPlan::new(&strands, spec.clone(), seed)),
            _ => None,
        };
        let mut unrolled = false;
        for local_step in 0..steps {
            let t_local = local_step as f64 * dt;
            let t_end = global_time + (local_step + 1) as f64 * dt;
            // The scalp and the kinematic colliders take their pose at the
            // end of the step; colliders also the velocity that gets them
            // there (friction drags hair along).
            if !timeline.file.groom.motion.get_ref().is_empty() {
                strands.set_root_transform(&pose_of(pose_at(
                    timeline.file.groom.motion.get_ref(),
                    t_end,
                )));
            }
            for (collider, keys) in stage_colliders.colliders.iter_mut().zip(&stage_motions) {
                collider.move_to(pose_of(pose_at(keys, t_end)), dt as f32);
            }
            if let (Some(rods), Some(perm)) = (&rods, &plan.perm) {
                if t_local < perm.set_end {
                    rods.wind(&mut strands, ((t_local + dt) / perm.roll_end).min(1.0))?;
                } else if !unrolled {
                    rods.unroll(&mut strands)?;
                    unrolled = true;
                }
            }
            let (environment, wetness) = plan.environment_at(t_local);
            if let Some((target, rate)) = wetness {
                drive_wetness(&mut strands, target, rate, dt as f32);
            }
            if let Some(wind) = wind.as_mut() {
                if wind.advance_to(t_local + dt) {
                    wind.apply(&mut strands);
                }
            } else {
                let step_report = solver.step(&mut strands, &stage_colliders, &environment)?;
                stage_report.contained_strands.extend(step_report.contained);
            }
            step_index += 1;
            write_frames(&mut animated, &strands, step_index)?;
            stage_bar.inc(1);
            overall.inc(1);
        }
        if wind.is_some() {
            strands = with_frames_from_positions(&groom, &strands, &material_of(timeline))?;
        }
        global_time += steps as f64 * dt;
        snapshots.push((
            format!("after {}", stage_report.name),
            groom_now(&groom, &strands, strands.positions().to_vec(), false),
        ));
        if !stage_report.contained_strands.is_empty() {
            stage_report.warnings.push(format!(
                "{} strand(s) turned non-finite and were frozen: {:?}",
                stage_report.contained_strands.len(),
                stage_report.contained_strands
            ));
        }
        stage_report.wall_seconds = stage_started.elapsed().as_secs_f64();
        report.warnings.extend(
            stage_report
                .warnings
                .iter()
                .map(|w| format!("stage {stage_index}: {w}")),
        );
        report.stages.push(stage_report);
    }
    stage_bar.finish_and_clear();
    overall.finish_and_clear();

    // Finish the animated exports, then write the static ones.
    let mut frames_of = vec![None; exports.len()];
    for a in animated {
        frames_of[a.index] = Some(a.frames_written);
        a.writer.finish()?;
    }
    for (index, e) in exports.iter().enumerate() {
        let path = output_path(options, e.path.get_ref());
        if e.what != ExportWhat::Animated {
            let (units, up) = export_units(timeline, index);
            let mut out = match e.what {
                ExportWhat::Final => {
                    groom_now(&groom, &strands, strands.positions().to_vec(), false)
                }
                ExportWhat::Rest => groom_now(&groom, &strands, strands.rest_pose(), false),
                ExportWhat::State => {
                    groom_now(&groom, &strands, strands.positions().to_vec(), true)
                }
                ExportWhat::Animated => continue,
            };
            out.convert_to(units, up);
            create_parent(&path)?;
            exporters::write(&path, &out)?;
        }
        let what = format!("{:?}", e.what).to_lowercase();
        report
            .outputs
            .push(output_report(&path, what, frames_of[index])?);
    }
    if let (Some(preview), false) = (&timeline.file.preview, options.dry) {
        let path = output_path(options, preview.sheet.get_ref());
        write_sheet(timeline, &snapshots, &path)?;
        report
            .outputs
            .push(output_report(&path, "sheet".into(), None)?);
    }
    report.simulated_seconds = total_time;
    report.wall_seconds = started.elapsed().as_secs_f64();
    Ok(BakeOutcome { report, snapshots })
}
