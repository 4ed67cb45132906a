//! Runs a timeline: builds the strands and colliders, steps the solver
//! through every stage, streams animated exports, writes the final, rest
//! and state exports, and reports.

pub use super::error::BakeError;
use super::motion::pose_at;
use super::outputs::{self, Staging};
use super::report::{size_and_sha256, BakeReport, OutputReport, StageReport, WatchdogReport};
use super::schema::{ColliderActivity, ExportWhat, ShapeSpec, StageKind};
use super::shapes::{pose_of, shape_of};
use super::stages::{drive_wetness, PermRods, StagePlan, WindPlan};
use super::{Timeline, TimelineError};
use crate::sim::{
    self, attribute_names, Collider, ColliderSet, Material, Solver, SolverParameters, StrandSet,
};
use groom::{Frame, Groom, Units, UpAxis};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
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
    /// Progress, and a request to stop, shared with another thread or a
    /// signal handler (the CLI's signals, the Python module's Ctrl-C).
    pub monitor: Option<std::sync::Arc<BakeMonitor>>,
    /// Where the caller will write the report: checked with the outputs,
    /// and the old one removed before the outputs are renamed into place.
    pub report: Option<PathBuf>,
    /// Refuse, before simulating, exports that would change the data
    /// (`exporters::warnings`), instead of warning.
    pub strict: bool,
}

impl BakeOptions {
    /// Whether the caller asked the bake to stop.
    fn interrupted(&self) -> Result<(), BakeError> {
        self.monitor
            .as_ref()
            .map_or(Ok(()), |monitor| monitor.stop_requested())
    }
}

/// The steps a running bake has done, and a request to stop it: the one
/// way to stop a bake, for a signal handler and for another thread alike.
#[derive(Debug, Default)]
pub struct BakeMonitor {
    pub steps_done: std::sync::atomic::AtomicU64,
    /// Known once the bake is prepared (0 before).
    pub steps_total: std::sync::atomic::AtomicU64,
    /// Index of the stage running (or last run) in the timeline's stages.
    pub stage: AtomicUsize,
    /// 0 while the bake may run. A signal handler stores the signal's
    /// number ([`BakeError::Interrupted`]); [`BakeMonitor::cancel`] stores
    /// [`BakeMonitor::CANCELLED`] ([`BakeError::Cancelled`]). The bake stops
    /// before its next step or output, removes its temporaries and
    /// replaces no output. An `Arc` so a signal handler can hold it.
    pub stop: Arc<AtomicUsize>,
}

impl BakeMonitor {
    /// The `stop` value of a caller's request (no signal has this number).
    pub const CANCELLED: usize = usize::MAX;

    /// Asks the bake to stop ([`BakeError::Cancelled`]).
    pub fn cancel(&self) {
        self.stop.store(Self::CANCELLED, Ordering::Relaxed);
    }

    fn stop_requested(&self) -> Result<(), BakeError> {
        match self.stop.load(Ordering::Relaxed) {
            0 => Ok(()),
            Self::CANCELLED => Err(BakeError::Cancelled),
            signal => Err(BakeError::Interrupted { signal }),
        }
    }
}

/// What a bake leaves besides its files: the report and the groom before
/// the first stage and after each stage (with bond rates and wetness).
pub struct BakeOutcome {
    pub report: BakeReport,
    pub snapshots: Vec<(String, Groom)>,
    /// The perm rods of the snapshots taken during a perm.
    pub rods: Vec<super::surfaces::RodSnapshot>,
    /// The plastic rest shape at the end (as the `rest` export writes it).
    pub rest: Groom,
    /// Bond rates, wetness and strain sampled every frame (the report's plots).
    pub plot_samples: Vec<super::plots::PlotSample>,
}

/// The likely cause of strands blowing up, and what to do: the words
/// `docs/tuning.md` ("Troubleshooting") explains.
fn blowup_remedy(colliders: bool) -> &'static str {
    if colliders {
        "likely cause: a collider inside the hair's roots (move it off the scalp) or a step too large (lower [solver] dt)"
    } else {
        "likely cause: a step too large for the stage's forces (lower [solver] dt)"
    }
}

/// Everything a bake starts from, prepared (and so checked) before any step.
pub struct Prepared {
    /// The simulated strands (the guides, when there is render hair).
    pub groom: Groom,
    /// Render strands that follow the guides (see [`super::render`]).
    pub render: Option<groom::interpolate::RenderHair>,
    pub strands: StrandSet,
    pub colliders: ColliderSet,
    pub parameters: SolverParameters,
    pub seed: u64,
    /// What the sag-free start did (`None`: off, or a continued bake);
    /// its `unstable` strands are found by the bake's probe, not here.
    pub sag_free: Option<sim::SagFreeReport>,
    /// The fibre radii the strands use, and where they came from.
    pub fibre_radius: super::fibre::FibreRadius,
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
    let model = *timeline.file.material.model.get_ref();
    SolverParameters {
        dt: timeline.dt as f32,
        iterations: s
            .iterations
            .as_ref()
            .map_or_else(|| model.default_iterations(), |i| *i.get_ref()),
        // An iteration count given alone is the count every strand gets.
        tolerance: match (&s.tolerance, &s.iterations) {
            (Some(t), _) => *t.get_ref(),
            (None, Some(_)) => 0.0,
            (None, None) => model.default_tolerance(),
        },
        gravity: s.gravity,
        integrator: s
            .integrator
            .as_ref()
            .map_or_else(Default::default, |i| *i.get_ref()),
        hair_radius: *s.hair_radius.get_ref(),
        hair_hair_strength: s
            .hair_hair
            .as_ref()
            .map(|h| h.get_ref())
            .filter(|h| h.mode == super::schema::HairHairMode::Pairwise)
            .map(|h| h.strength),
        // Friction between hairs: the physical model's pairwise mode, when
        // the timeline asks for it. Off by default while its contact search
        // costs about 21 times the frictionless step (docs/performance.md);
        // `DEFAULT_HAIR_FRICTION` is the value for dry hair (docs/model.md).
        hair_friction: s
            .hair_hair
            .as_ref()
            .map(|h| h.get_ref())
            .filter(|h| h.mode == super::schema::HairHairMode::Pairwise)
            .filter(|_| model == crate::sim::Model::Physical)
            .and_then(|h| h.friction)
            .filter(|mu| *mu > 0.0),
        volumetric: s.hair_hair.as_ref().and_then(|h| h.get_ref().volumetric()),
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
                    groom.provenance.units_source = "stated".into();
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
        (None, Some(parameters)) => {
            // A scalp mesh is named relative to the timeline.
            let mut resolved = parameters.get_ref().clone();
            if let Some(mesh) = &resolved.scalp_mesh {
                resolved.scalp_mesh = Some(timeline.resolve(&mesh.to_string_lossy()));
            }
            crate::generate::generate(&resolved)
                .map_err(|e| timeline.error_at(parameters.span(), e.to_string()))?
        }
        (None, None) => {
            return Err(timeline
                .error_at(0..0, "[groom] needs `source` or `generate`")
                .into())
        }
    };
    if groom.strand_count() == 0 {
        let file = match &spec.source {
            Some(source) => timeline.resolve(source.get_ref()),
            None => timeline.path.clone(),
        };
        return Err(BakeError::Input {
            file,
            message: "the groom has no strands".into(),
        });
    }
    timeline.check_budget(groom.points.len() as u64)?;
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

/// Imports the groom, builds the strands and colliders. Everything that can
/// be wrong with the inputs shows here, before the first step; nothing is
/// simulated (`validate` runs this), so the sag-free stability probe is
/// left to the bake.
pub fn prepare(timeline: &Timeline, seed_override: Option<u64>) -> Result<Prepared, BakeError> {
    let seed = seed_override.or(timeline.file.seed).unwrap_or(0);
    let (groom, render) = super::render::split_or_grow(timeline, load_groom(timeline)?, seed)?;
    super::cache::check_render_hair(timeline, render.is_some())?;
    let material = material_of(timeline);
    // A groom written by a `state` export continues where it stopped; any
    // other starts fresh (bond rates and wetness taken where present).
    let mut strands = StrandSet::from_state(&groom, &material)?;
    // Sag-free start: the groom as authored is the shape under gravity. A
    // groom that continues a bake (it has the solver's frames) keeps the
    // rest shape it carries.
    let continues = groom.attribute(attribute_names::FRAME_XYZ).is_some();
    let parameters = parameters_of(timeline);
    parameters.check()?;
    // The wind stage moves the hair without the rod solver: a timeline of
    // wind stages only has no rest shape to balance. The stability probe
    // simulates: the bake runs it (`probe_sag_free`), not this preparation
    // that `validate` shares.
    let rod_solver = timeline
        .file
        .stages
        .get_ref()
        .iter()
        .any(|s| *s.kind.get_ref() != StageKind::Wind);
    let mut colliders = ColliderSet::new();
    for c in &timeline.file.colliders {
        let shape = shape_of(timeline, c.shape.get_ref())?;
        let pose = pose_of(pose_at(c.motion.get_ref(), 0.0));
        let collider =
            Collider::checked(c.name.get_ref().clone(), shape, pose, *c.friction.get_ref())
                .map_err(|message| match c.shape.get_ref() {
                    ShapeSpec::Mesh { path, .. } => BakeError::Input {
                        file: timeline.resolve(path),
                        message,
                    },
                    _ => BakeError::Timeline(timeline.error_at(c.shape.span(), message)),
                })?;
        colliders.insert(collider);
    }
    let sag_free = if timeline.file.solver.sag_free && !continues && rod_solver {
        Some(strands.make_sag_free_supported(
            parameters.gravity,
            &start_colliders(timeline, &colliders),
            parameters.hair_radius,
        ))
    } else {
        None
    };
    check_preview_color(timeline, &groom)?;
    let fibre_radius = super::fibre::fibre_radius(timeline, &groom, strands.radii());
    Ok(Prepared {
        groom,
        render,
        strands,
        colliders,
        parameters,
        seed,
        sag_free,
        fibre_radius,
    })
}

/// The colliders the groom rests on at the start (the sag-free start's
/// supports): those in every stage and those the first stage lists, posed
/// at time 0.
fn start_colliders(timeline: &Timeline, colliders: &ColliderSet) -> ColliderSet {
    let first = timeline.file.stages.get_ref().first();
    let mut start = ColliderSet::new();
    for (collider, spec) in colliders.colliders.iter().zip(&timeline.file.colliders) {
        let listed = first.is_some_and(|stage| {
            stage
                .colliders
                .iter()
                .any(|n| n.get_ref() == spec.name.get_ref())
        });
        if spec.active == ColliderActivity::Always || listed {
            start.insert(collider.clone());
        }
    }
    start
}

/// Refuses a `[preview] color` that names no attribute of the snapshots
/// (the groom's own, the bond rates and wetness).
fn check_preview_color(timeline: &Timeline, groom: &Groom) -> Result<(), TimelineError> {
    let Some(color) = timeline
        .file
        .preview
        .as_ref()
        .and_then(|p| p.color.as_ref())
    else {
        return Ok(());
    };
    let name = color.get_ref().as_str();
    let mut names: Vec<&str> = groom.attributes.iter().map(|a| a.name.as_str()).collect();
    names.extend(attribute_names::BOND_RATES);
    names.push(attribute_names::WETNESS);
    if names.contains(&name) {
        return Ok(());
    }
    names.sort_unstable();
    names.dedup();
    Err(timeline.error_at(
        color.span(),
        format!(
            "no attribute {:?} to colour by (there are: {})",
            name.escape_debug().to_string(),
            names.join(", ")
        ),
    ))
}

/// The final paths of the bake's outputs (exports, then the sheet), each
/// checked to be writable, and none the same file as another or as the
/// report: all before any simulation.
pub fn plan_outputs(timeline: &Timeline, options: &BakeOptions) -> Result<Vec<PathBuf>, BakeError> {
    let mut planned: Vec<(PathBuf, std::ops::Range<usize>)> = Vec::new();
    if !options.dry {
        for e in &timeline.file.exports {
            planned.push((output_path(options, e.path.get_ref()), e.path.span()));
        }
        if let Some(preview) = &timeline.file.preview {
            planned.push((
                output_path(options, preview.sheet.get_ref()),
                preview.sheet.span(),
            ));
        }
    }
    let mut seen: Vec<(PathBuf, &Path)> = Vec::new();
    if let Some(report) = &options.report {
        let canonical = outputs::canonical(report).map_err(|source| BakeError::Io {
            file: report.clone(),
            source,
        })?;
        seen.push((canonical, report));
    }
    for (path, span) in &planned {
        let canonical = outputs::canonical(path).map_err(|source| BakeError::Io {
            file: path.clone(),
            source,
        })?;
        if let Some((_, other)) = seen.iter().find(|(c, _)| *c == canonical) {
            if options.report.as_deref() == Some(*other) {
                return Err(BakeError::Report {
                    file: other.to_path_buf(),
                    message: format!(
                        "would overwrite the output '{}' ({})",
                        path.display(),
                        timeline
                            .error_at(span.clone(), "")
                            .to_string()
                            .trim_end_matches([' ', ':'])
                    ),
                });
            }
            let message = format!(
                "'{}' and '{}' are the same file",
                other.display(),
                path.display()
            );
            return Err(timeline.error_at(span.clone(), message).into());
        }
        seen.push((canonical, path));
    }
    for (path, _) in seen.iter().rev() {
        outputs::check_writable(path).map_err(|message| {
            if options.report.as_deref() == Some(path.as_ref()) {
                BakeError::Report {
                    file: path.to_path_buf(),
                    message,
                }
            } else {
                BakeError::Output {
                    file: path.to_path_buf(),
                    message,
                }
            }
        })?;
    }
    Ok(planned.into_iter().map(|(p, _)| p).collect())
}

/// An animated export under way.
struct AnimatedExport {
    index: usize,
    delivery: super::render::Delivery,
    writer: Box<dyn exporters::FrameWriter>,
    fps: f64,
    frames_written: usize,
    frame_count: usize,
    units: Units,
    up: UpAxis,
    /// A guide cache: frames give the guides' points only.
    guides_only: bool,
}

/// What export `index` is written as: its `units`/`up`, else its `target`'s
/// preset, else the format's default (`exporters::destination`).
fn export_destination(timeline: &Timeline, index: usize) -> exporters::Destination {
    let e = &timeline.file.exports[index];
    exporters::destination(
        Path::new(e.path.get_ref()),
        e.target.as_ref().and_then(|t| t.get_ref().parse().ok()),
        e.units.as_ref().and_then(|u| u.get_ref().parse().ok()),
        e.up.as_ref().and_then(|u| u.get_ref().parse().ok()),
        Units::METERS,
        UpAxis::Y,
    )
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

/// The preview options of the timeline's `[preview]` (or the defaults). The
/// view, unless the timeline names one, is the one that shows most of the
/// change from the first to the last snapshot.
pub fn sheet_options(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
) -> crate::preview::PreviewOptions {
    let mut options = crate::preview::PreviewOptions::default();
    let named_view = timeline
        .file
        .preview
        .as_ref()
        .and_then(|p| p.view.get_ref().parse().ok());
    options.view = match (named_view, snapshots.first(), snapshots.last()) {
        (Some(view), _, _) => view,
        (None, Some((_, first)), Some((_, last))) => {
            crate::preview::view_showing_change(first, last)
        }
        _ => options.view,
    };
    if let Some(p) = &timeline.file.preview {
        let [w, h] = *p.size.get_ref();
        options.width = w;
        options.height = h;
        options.color_by = p.color.as_ref().map(|c| c.get_ref().clone());
    }
    options
}

/// The curve form of the sheet's pictures: `[preview] resample`, if given.
fn sheet_curve_form(timeline: &Timeline) -> groom::curves::CurveForm {
    match timeline.file.preview.as_ref().and_then(|p| p.resample) {
        Some(segment) => groom::curves::CurveForm::Resampled { segment },
        None => groom::curves::CurveForm::Polyline,
    }
}

/// Renders the before/after sheet of a bake and writes it as a PNG.
fn write_sheet(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
    rods: &[super::surfaces::RodSnapshot],
    path: &Path,
) -> Result<(), BakeError> {
    crate::preview::write_png(&sheet_image(timeline, snapshots, rods)?, path)?;
    Ok(())
}

/// The before/after contact sheet of a bake's snapshots, with the colliders
/// active in each and a perm's rods (the sheet export and the HTML report
/// draw the same).
pub fn sheet_image(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
    rods: &[super::surfaces::RodSnapshot],
) -> Result<crate::preview::Image, BakeError> {
    let options = sheet_options(timeline, snapshots);
    let surfaces = super::surfaces::snapshot_surfaces(timeline, rods)?;
    let entries: Vec<crate::preview::SheetEntry> = snapshots
        .iter()
        .zip(&surfaces)
        .map(|((label, groom), surfaces)| crate::preview::SheetEntry {
            label,
            groom,
            frame: None,
            surfaces,
        })
        .collect();
    Ok(crate::preview::render_sheet(&entries, &options)?)
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

/// The report line of an output written to `staged` for `path`: its size
/// and SHA-256.
fn output_report(
    staged: &Path,
    path: &Path,
    what: String,
    frames: Option<usize>,
) -> Result<OutputReport, BakeError> {
    let (bytes, sha256) = size_and_sha256(staged).map_err(|source| BakeError::Io {
        file: staged.to_path_buf(),
        source,
    })?;
    Ok(OutputReport {
        path: path.display().to_string(),
        what,
        bytes,
        sha256,
        frames,
        written_in: None,
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
        attribute_names::VELOCITY_CORRECTION,
        attribute_names::ANGULAR_VELOCITY,
    ] {
        groom.remove_attribute(name);
    }
    Ok(StrandSet::from_state(&groom, material)?)
}

/// What each export must change about the groom's data, one line per kind
/// (checked before simulating, so `--strict` refuses before any work).
fn export_warnings_of(timeline: &Timeline, options: &BakeOptions, groom: &Groom) -> Vec<String> {
    if options.dry {
        return Vec::new();
    }
    (0..timeline.file.exports.len())
        .flat_map(|index| {
            let e = &timeline.file.exports[index];
            let path = output_path(options, e.path.get_ref());
            let destination = export_destination(timeline, index);
            let mut converted = groom.clone();
            converted.convert_to(destination.units, destination.up);
            let mut warnings = exporters::warnings(&path, &converted, destination.units);
            if e.what == ExportWhat::Animated {
                let names = super::frame_attributes::changing_in(timeline);
                warnings.extend(exporters::frame_attributes_warning(&path, &names));
            }
            warnings
        })
        .collect()
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

/// Runs the timeline and writes its exports, in three phases like a
/// physics pipeline's step: `BakeRun::prepare` (everything checked and
/// every output opened before the first step), `BakeRun::run_stages`
/// (the simulation, streaming animated frames) and `BakeRun::write` (the
/// final, rest, state and sheet outputs and the report's lines).
pub fn bake(timeline: &Timeline, options: &BakeOptions) -> Result<BakeOutcome, BakeError> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(threads) = options.threads {
        builder = builder.num_threads(threads);
    }
    let pool = builder
        .build()
        .map_err(|e| BakeError::Threads(e.to_string()))?;
    let result = pool.install(|| {
        let mut run = BakeRun::prepare(timeline, options, pool.current_num_threads())?;
        run.run_stages()?;
        run.write()
    });
    // Errors of outputs name the staged file: say the final one.
    result.map_err(|e| match e {
        BakeError::Export(_) | BakeError::Io { .. } | BakeError::Preview(_) => {
            BakeError::Write(outputs::final_names(&e.to_string()))
        }
        e => e,
    })
}

/// A bake under way: the prepared state, the open animated exports, the
/// snapshots and the report so far.
struct BakeRun<'a> {
    timeline: &'a Timeline,
    options: &'a BakeOptions,
    started: Instant,
    groom: Groom,
    /// Render strands that follow the simulated guides, if any.
    render: Option<groom::interpolate::RenderHair>,
    strands: StrandSet,
    colliders: ColliderSet,
    parameters: SolverParameters,
    seed: u64,
    dt: f64,
    plans: Vec<StagePlan>,
    stage_steps: Vec<u64>,
    total_time: f64,
    /// The exports this run writes (none for a dry run).
    exports: &'a [super::schema::ExportSpec],
    /// Final paths of the exports and then the sheet, and where each is
    /// staged until the end.
    finals: Vec<PathBuf>,
    staged: Vec<PathBuf>,
    staging: Staging,
    animated: Vec<AnimatedExport>,
    /// The attributes the stages change, written with every animated frame.
    frame_attributes: Vec<&'static str>,
    /// Steps done over all stages.
    step_index: u64,
    snapshots: Vec<(String, Groom)>,
    rods: Vec<super::surfaces::RodSnapshot>,
    report: BakeReport,
    plots: super::plots::Plotter,
}

/// What one stage runs with: its solver and colliders, rods and wind.
struct StageRun<'p> {
    plan: &'p StagePlan,
    solver: Solver,
    colliders: ColliderSet,
    motions: Vec<&'p [super::schema::KeySpec]>,
    rods: Option<PermRods>,
    wind: Option<WindPlan>,
    unrolled: bool,
    /// Evaporation in a `dry` stage without `drying_time`.
    drying: Option<super::drying::Drying>,
    /// Positions before the step, for the watchdog to put a strand back.
    before: Vec<[f32; 3]>,
    /// The strands the watchdog saw strained beyond `sim::WARN_STRAIN`.
    strain: sim::StrainWatch,
}

impl<'a> BakeRun<'a> {
    /// Phase 1: prepares the strands and colliders, plans the stages, opens
    /// the animated exports and writes their frame 0.
    fn prepare(
        timeline: &'a Timeline,
        options: &'a BakeOptions,
        threads: usize,
    ) -> Result<BakeRun<'a>, BakeError> {
        let started = Instant::now();
        let finals = plan_outputs(timeline, options)?;
        let Prepared {
            groom,
            render,
            mut strands,
            colliders,
            parameters,
            seed,
            mut sag_free,
            fibre_radius,
        } = prepare(timeline, options.seed)?;
        if let Some(sag_free) = &mut sag_free {
            let start = start_colliders(timeline, &colliders);
            strands.probe_sag_free(&parameters, &start, sag_free)?;
        }
        // What the reader left out of the source, then what the exports
        // must change.
        let source = timeline.file.groom.source.as_ref();
        let mut export_warnings: Vec<String> = groom
            .provenance
            .losses
            .iter()
            .map(|loss| match source {
                Some(source) => format!("{}: {loss}", timeline.resolve(source.get_ref()).display()),
                None => loss.clone(),
            })
            .collect();
        export_warnings.extend(export_warnings_of(timeline, options, &groom));
        if let (true, Some(first)) = (options.strict, export_warnings.first()) {
            return Err(BakeError::Input {
                file: timeline.path.clone(),
                message: format!("--strict: {first}"),
            });
        }
        let dt = timeline.dt;
        let plans: Vec<StagePlan> = timeline
            .file
            .stages
            .get_ref()
            .iter()
            .map(|spec| StagePlan {
                hold: super::hold::of_stage(&timeline.file, spec),
                ..StagePlan::new(spec)
            })
            .collect();
        let stage_steps = timeline.stage_steps();
        let total_steps: u64 = stage_steps.iter().sum();
        if let Some(monitor) = &options.monitor {
            monitor.steps_total.store(total_steps, Ordering::Relaxed);
        }
        let mut report = BakeReport {
            seed,
            threads,
            strands: strands.strand_count(),
            vertices: strands.vertex_count(),
            warnings: export_warnings,
            ..BakeReport::start(&timeline.path)
        };
        report.record_sources(timeline);
        report.warnings.extend(fibre_radius.warning());
        report.fibre_radius = Some(fibre_radius);
        if let Some(warning) = sag_free.as_ref().and_then(sim::SagFreeReport::warning) {
            report.warnings.push(warning);
        }
        // Strands the solver cannot move are said, not skipped silently.
        let unsimulated = sim::unsimulated_strands(&strands);
        if let Some(first) = unsimulated.first() {
            report.warnings.push(format!(
                "{} strand(s) are not simulated (first: strand {}: {})",
                unsimulated.len(),
                first.strand,
                first.reason
            ));
        }
        report.unsimulated_strands = unsimulated.iter().map(|b| b.strand).collect();
        // A dry run (a preview of the timeline) writes no file.
        let exports: &[super::schema::ExportSpec] = if options.dry {
            &[]
        } else {
            &timeline.file.exports
        };
        // Temporaries of killed bakes into the same folders go first.
        let mut ours = finals.clone();
        ours.extend(options.report.clone());
        let removed = outputs::remove_stale_temporaries(&ours);
        let mut staging = Staging::default();
        let mut staged = Vec::new();
        for path in &finals {
            create_parent(path)?;
            staged.push(staging.stage(path));
        }
        let frame_attributes = super::frame_attributes::changing(&plans);
        let plots = super::plots::Plotter::new(&strands);
        let mut run = BakeRun {
            timeline,
            options,
            started,
            groom,
            render,
            strands,
            colliders,
            parameters,
            seed,
            dt,
            plans,
            stage_steps,
            total_time: total_steps as f64 * dt,
            exports,
            finals,
            staged,
            staging,
            animated: Vec::new(),
            frame_attributes,
            step_index: 0,
            snapshots: Vec::new(),
            rods: Vec::new(),
            report,
            plots,
        };
        if !removed.is_empty() {
            run.report.warnings.push(format!(
                "removed {} temporary file(s) left by a stopped bake",
                removed.len()
            ));
        }
        run.open_animated()?;
        run.write_due_frames()?;
        run.snapshot("before".to_string());
        Ok(run)
    }

    /// Opens every animated export with the groom as it starts.
    fn open_animated(&mut self) -> Result<(), BakeError> {
        for (index, e) in self.exports.iter().enumerate() {
            if e.what != ExportWhat::Animated {
                continue;
            }
            let fps = e.fps.as_ref().map_or(24.0, |f| *f.get_ref());
            let frame_count = (self.total_time * fps + 1e-6).floor() as usize + 1;
            let destination = export_destination(self.timeline, index);
            let (units, up) = (destination.units, destination.up);
            let guides = self.groom_now(false);
            let delivery = super::render::Delivery::new(
                self.render.as_ref(),
                &guides,
                super::render::curve_form(e),
            );
            let mut base = delivery.groom(self.render.as_ref(), &guides);
            base.convert_to(units, up);
            let guides_only = super::cache::cache_of(e) == super::cache::CacheMode::Guides;
            let open = if guides_only {
                exporters::guide_cache
            } else {
                exporters::animated_as
            };
            let writer = open(
                &self.staged[index],
                &base,
                exporters::AnimationOptions { fps, frame_count },
                destination.attributes,
            )?;
            self.animated.push(AnimatedExport {
                index,
                delivery,
                writer,
                fps,
                frames_written: 0,
                frame_count,
                units,
                up,
                guides_only,
            });
        }
        Ok(())
    }

    /// Writes the animated frames due by the current step: frame k belongs
    /// to the step nearest k / fps.
    fn write_due_frames(&mut self) -> Result<(), BakeError> {
        let due = |a: &AnimatedExport| {
            a.frames_written < a.frame_count
                && ((a.frames_written as f64 / a.fps) / self.dt).round() as u64 <= self.step_index
        };
        // The guides' pose with the attributes that change, once for all
        // exports with a frame due.
        let guides = (!self.frame_attributes.is_empty() && self.animated.iter().any(due))
            .then(|| self.groom_now(false));
        for a in self.animated.iter_mut() {
            while a.frames_written < a.frame_count {
                let k = a.frames_written;
                let due = ((k as f64 / a.fps) / self.dt).round() as u64;
                if due > self.step_index {
                    break;
                }
                let mut points = if a.guides_only {
                    self.strands.positions().to_vec()
                } else {
                    a.delivery
                        .points(self.render.as_ref(), self.strands.positions())
                };
                groom::convert_points(&mut points, (Units::METERS, UpAxis::Y), (a.units, a.up));
                let attributes = guides.as_ref().map_or_else(Vec::new, |g| {
                    if a.guides_only {
                        return super::frame_attributes::of_guides(g, &self.frame_attributes);
                    }
                    super::frame_attributes::delivered(
                        &a.delivery,
                        self.render.as_ref(),
                        g,
                        &self.frame_attributes,
                    )
                });
                let frame = Frame {
                    time: k as f64 / a.fps,
                    points,
                    attributes,
                };
                a.writer.write_frame(&frame)?;
                a.frames_written += 1;
            }
        }
        Ok(())
    }

    /// The groom as it is now (see [`groom_now`]).
    fn groom_now(&self, with_state: bool) -> Groom {
        groom_now(
            &self.groom,
            &self.strands,
            self.strands.positions().to_vec(),
            with_state,
        )
    }

    /// Keeps the delivered pose (render hair in the sheet's curve form)
    /// for the contact sheet.
    fn snapshot(&mut self, label: String) {
        let guides = self.groom_now(false);
        let groom = super::render::deliver(
            self.render.as_ref(),
            &guides,
            sheet_curve_form(self.timeline),
        );
        self.snapshots.push((label, groom));
    }

    /// Keeps the hair wound on its perm rods, with the rods, at the step
    /// whose start ends the set phase (the rods unroll in it); the stage's
    /// name labels it ("during perm").
    fn snapshot_before_unroll(
        &mut self,
        stage: &StageRun<'_>,
        stage_index: usize,
        t_local: f64,
        time: f64,
    ) {
        let (Some(rods), Some(perm)) = (&stage.rods, &stage.plan.perm) else {
            return;
        };
        if stage.unrolled || t_local < perm.set_end {
            return;
        }
        let name = self.timeline.file.stages.get_ref()[stage_index]
            .name
            .clone()
            .unwrap_or_else(|| stage.plan.kind.name().to_string());
        self.rods.push(super::surfaces::RodSnapshot {
            snapshot: self.snapshots.len(),
            stage: stage_index,
            time,
            rods: rods.cylinders(),
        });
        self.snapshot(format!("during {name}"));
    }

    /// Phase 2: runs every stage in order.
    fn run_stages(&mut self) -> Result<(), BakeError> {
        let total_steps: u64 = self.stage_steps.iter().sum();
        let (_multi, overall, stage_bar) = progress_bars(self.options, total_steps);
        let mut global_time = 0.0f64;
        for stage_index in 0..self.plans.len() {
            let stage_report = self.run_stage(stage_index, global_time, &overall, &stage_bar)?;
            global_time += stage_report.steps as f64 * self.dt;
            self.report.warnings.extend(
                stage_report
                    .warnings
                    .iter()
                    .map(|w| format!("stage {stage_index}: {w}")),
            );
            self.report.stages.push(stage_report);
        }
        stage_bar.finish_and_clear();
        overall.finish_and_clear();
        Ok(())
    }

    /// Runs one stage from `global_time` and reports it.
    fn run_stage(
        &mut self,
        stage_index: usize,
        global_time: f64,
        overall: &ProgressBar,
        stage_bar: &ProgressBar,
    ) -> Result<StageReport, BakeError> {
        let timeline = self.timeline;
        let spec = &timeline.file.stages.get_ref()[stage_index];
        // A copy, so the stage can borrow it while the run changes.
        let plan = &self.plans[stage_index].clone();
        let steps = self.stage_steps[stage_index];
        let dt = self.dt;
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
            hold: plan.hold,
            name,
            simulated_seconds: steps as f64 * dt,
            steps,
            ..StageReport::default()
        };
        if let Some(monitor) = &self.options.monitor {
            monitor.stage.store(stage_index, Ordering::Relaxed);
        }
        let mut stage = self.start_stage(spec, plan, global_time)?;
        for local_step in 0..steps {
            self.options.interrupted()?;
            let t_local = local_step as f64 * dt;
            let t_end = global_time + (local_step + 1) as f64 * dt;
            self.snapshot_before_unroll(&stage, stage_index, t_local, global_time + t_local);
            let (contained, blowups) = self.advance(&mut stage, t_local, t_end)?;
            stage_report.contained_strands.extend(contained);
            for b in blowups {
                stage_report.contained_strands.push(b.strand);
                stage_report.watchdog.push(WatchdogReport {
                    strand: b.strand,
                    step: local_step,
                    reason: b.reason,
                });
            }
            self.step_index += 1;
            self.plots.after_step(t_end, &self.strands);
            if let Some(monitor) = &self.options.monitor {
                monitor.steps_done.store(self.step_index, Ordering::Relaxed);
            }
            self.write_due_frames()?;
            stage_bar.inc(1);
            overall.inc(1);
        }
        if stage.wind.is_some() {
            let rebuilt =
                with_frames_from_positions(&self.groom, &self.strands, &material_of(timeline))?;
            let old = std::mem::replace(&mut self.strands, rebuilt);
            // The hold's targets stay the groom's.
            self.strands.keep_groomed_of(&old);
        }
        self.snapshot(format!("after {}", stage_report.name));
        stage_report.set_kept = self
            .plots
            .stage_end(global_time + steps as f64 * dt, &self.strands);
        let non_finite = stage_report.contained_strands.len() - stage_report.watchdog.len();
        if non_finite > 0 {
            stage_report.warnings.push(format!(
                "{non_finite} strand(s) turned non-finite and were frozen: {:?}",
                &stage_report.contained_strands[..]
            ));
        }
        if let Some(warning) = stage.strain.warning(&stage_report.name) {
            stage_report.warnings.push(warning);
        }
        if let Some(first) = stage_report.watchdog.first() {
            stage_report.warnings.push(format!(
                "{} strand(s) blew up and were put back and frozen (first: strand {} at step {}: {}); {}",
                stage_report.watchdog.len(),
                first.strand,
                first.step,
                first.reason,
                blowup_remedy(!stage.colliders.is_empty())
            ));
        }
        stage_report.wall_seconds = stage_started.elapsed().as_secs_f64();
        Ok(stage_report)
    }

    /// Sets a stage up: its active colliders where their motion has them
    /// at `global_time`, its solver, rods and wind.
    fn start_stage<'p>(
        &mut self,
        spec: &super::schema::StageSpec,
        plan: &'p StagePlan,
        global_time: f64,
    ) -> Result<StageRun<'p>, BakeError>
    where
        'a: 'p,
    {
        let timeline = self.timeline;
        let mut stage_parameters = self.parameters;
        if let Some(d) = &spec.damping {
            stage_parameters.linear_damping = d.linear;
            stage_parameters.angular_damping = d.angular;
        }
        let solver = Solver::new(stage_parameters)?;
        let mut colliders = ColliderSet::new();
        let mut motions = Vec::new();
        for (collider, collider_spec) in self
            .colliders
            .colliders
            .iter()
            .zip(&timeline.file.colliders)
        {
            let on = collider_spec.active == ColliderActivity::Always
                || spec
                    .colliders
                    .iter()
                    .any(|n| n.get_ref() == collider_spec.name.get_ref());
            if on {
                let keys = collider_spec.motion.get_ref().as_slice();
                let mut collider = collider.clone();
                collider.set_pose(pose_of(pose_at(keys, global_time)));
                colliders.insert(collider);
                motions.push(keys);
            }
        }
        if plan.release_targets {
            self.strands.clear_kinematic_targets();
        }
        let rods = plan
            .perm
            .as_ref()
            .map(|p| PermRods::new(&self.strands, p, self.parameters.hair_radius));
        let wind = match (plan.kind, &plan.wind) {
            (StageKind::Wind, Some(wind)) => {
                Some(WindPlan::new(&self.strands, wind.clone(), self.seed))
            }
            _ => None,
        };
        let drying = plan.drying.map(|air| {
            let material = &timeline.file.material;
            let radius = material
                .radius
                .as_ref()
                .map_or(self.parameters.hair_radius, |r| *r.get_ref());
            super::drying::Drying::new(
                &air,
                plan.blower,
                f64::from(radius),
                f64::from(*material.density.get_ref()),
                self.dt,
            )
        });
        Ok(StageRun {
            plan,
            solver,
            colliders,
            motions,
            rods,
            wind,
            unrolled: false,
            drying,
            before: Vec::new(),
            strain: sim::StrainWatch::default(),
        })
    }

    /// One step of a stage at stage time `t_local` (ending at global time
    /// `t_end`), then the watchdog; returns the strands contained in it:
    /// by the quarantine (non-finite) and by the watchdog (with why).
    fn advance(
        &mut self,
        stage: &mut StageRun<'_>,
        t_local: f64,
        t_end: f64,
    ) -> Result<(Vec<usize>, Vec<sim::Blowup>), BakeError> {
        stage.before.clear();
        stage.before.extend_from_slice(self.strands.positions());
        let contained = self.step(stage, t_local, t_end)?;
        let blowups =
            sim::contain_blowups_watching(&mut self.strands, &stage.before, &mut stage.strain);
        Ok((contained, blowups))
    }

    /// The stage's drives and the solver (or the wind model) for one step.
    fn step(
        &mut self,
        stage: &mut StageRun<'_>,
        t_local: f64,
        t_end: f64,
    ) -> Result<Vec<usize>, BakeError> {
        let dt = self.dt;
        let strands = &mut self.strands;
        let plan = stage.plan;
        // The scalp and the kinematic colliders take their pose at the
        // end of the step; colliders also the velocity that gets them
        // there (friction drags hair along).
        let scalp = self.timeline.file.groom.motion.get_ref();
        if !scalp.is_empty() {
            strands.set_root_transform(&pose_of(pose_at(scalp, t_end)));
        }
        for (collider, keys) in stage.colliders.colliders.iter_mut().zip(&stage.motions) {
            collider.move_to(pose_of(pose_at(keys, t_end)), dt as f32);
        }
        if let (Some(rods), Some(perm)) = (&stage.rods, &plan.perm) {
            if t_local < perm.set_end {
                rods.wind(strands, ((t_local + dt) / perm.roll_end).min(1.0))?;
            } else if !stage.unrolled {
                rods.unroll(strands)?;
                stage.unrolled = true;
            }
        }
        let (mut environment, wetness) = plan.environment_at(t_local);
        if let Some((target, rate)) = wetness {
            drive_wetness(strands, target, rate, dt as f32);
        }
        if let Some(drying) = stage.drying.as_mut() {
            let mut water = strands.wetness().to_vec();
            drying.step(strands.positions(), &mut water);
            strands.wetness_mut().copy_from_slice(&water);
            environment.hydrogen_reform = Some(&drying.reform);
        }
        if let Some(wind) = stage.wind.as_mut() {
            if wind.advance_to(t_local + dt) {
                wind.apply(strands);
            }
            Ok(Vec::new())
        } else {
            let step_report = stage.solver.step(strands, &stage.colliders, &environment)?;
            Ok(step_report.contained)
        }
    }

    /// Phase 3: finishes the animated exports, writes the static ones and
    /// the sheet, and completes the report.
    fn write(mut self) -> Result<BakeOutcome, BakeError> {
        let mut frames_of = vec![None; self.exports.len()];
        for a in std::mem::take(&mut self.animated) {
            frames_of[a.index] = Some(a.frames_written);
            a.writer.finish()?;
        }
        for (index, e) in self.exports.iter().enumerate() {
            self.options.interrupted()?;
            let (path, staged) = (&self.finals[index], &self.staged[index]);
            let destination = export_destination(self.timeline, index);
            if e.what != ExportWhat::Animated {
                let (units, up) = (destination.units, destination.up);
                let mut out = match e.what {
                    ExportWhat::Final => self.groom_now(false),
                    ExportWhat::Rest => {
                        groom_now(&self.groom, &self.strands, self.strands.rest_pose(), false)
                    }
                    ExportWhat::State => self.groom_now(true),
                    ExportWhat::Animated => continue,
                };
                out = super::render::deliver(
                    self.render.as_ref(),
                    &out,
                    super::render::curve_form(e),
                );
                out.convert_to(units, up);
                exporters::write_as(staged, &out, destination.attributes)?;
            }
            let what = format!("{:?}", e.what).to_lowercase();
            let mut output = output_report(staged, path, what, frames_of[index])?;
            output.written_in = exporters::written_in(path, destination.units, destination.up);
            self.report.outputs.push(output);
        }
        if let (Some(_), false) = (&self.timeline.file.preview, self.options.dry) {
            let index = self.exports.len();
            let (path, staged) = (&self.finals[index], &self.staged[index]);
            write_sheet(self.timeline, &self.snapshots, &self.rods, staged)?;
            self.report
                .outputs
                .push(output_report(staged, path, "sheet".into(), None)?);
        }
        // Everything is written: into place together, the report after.
        self.options.interrupted()?;
        let staging = std::mem::take(&mut self.staging);
        staging
            .commit(self.options.report.as_deref())
            .map_err(|source| BakeError::Io {
                file: self.finals.first().cloned().unwrap_or_default(),
                source,
            })?;
        self.report.simulated_seconds = self.total_time;
        self.report.wall_seconds = self.started.elapsed().as_secs_f64();
        let rest = groom_now(&self.groom, &self.strands, self.strands.rest_pose(), false);
        Ok(BakeOutcome {
            report: self.report,
            snapshots: self.snapshots,
            rods: self.rods,
            rest,
            plot_samples: self.plots.samples,
        })
    }
}
