//! Timelines of hair treatments: the TOML schema ([`schema`]), its checks
//! (this module), the stages that drive the simulation ([`stages`]) and the
//! bake that runs them and writes the exports ([`bake`]).

mod applies;
pub mod bake;
pub mod cache;
pub mod drying;
mod error;
pub mod fibre;
pub mod frame_attributes;
mod frame_pipe;
pub mod hold;
pub mod motion;
pub mod outputs;
pub mod plots;
mod prepare;
mod ranges;
pub mod render;
pub mod report;
pub mod schema;
mod shapes;
mod sheet;
pub mod stages;
pub mod surfaces;

/// Perm rod radii, metres: the range `docs/tuning.md` documents.
pub const ROD_RADIUS: std::ops::RangeInclusive<f32> = 0.005..=0.05;

use schema::{ExportWhat, ShapeSpec, StageKind, TimelineFile};
use serde_spanned::Spanned;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A timeline that cannot be used, with where in its file.
/// Shown as `file:line:column: message`, or `file: message` when no place
/// in the file is meant (line 0: the file could not be read).
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {message}", file.display(), place(*line, *column))]
pub struct TimelineError {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// A parsed and checked timeline, with its file's text for later errors.
#[derive(Debug)]
pub struct Timeline {
    pub path: PathBuf,
    pub text: String,
    pub file: TimelineFile,
    /// Time step, seconds.
    pub dt: f64,
}

/// The names of the bond kinds, in the solver's order.
pub const BOND_NAMES: [&str; 4] = ["hydrogen", "ionic", "disulfide", "peptide"];

fn place(line: usize, column: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}:{column}")
    }
}

/// An input named by a timeline must be a regular file: a device, FIFO or
/// directory is refused with its kind (reading one would never end).
pub(crate) fn check_input_file(path: &Path, what: &str) -> Result<(), String> {
    match std::fs::metadata(path) {
        Err(_) => Err(format!("{what} '{}' not found", path.display())),
        Ok(metadata) => match importers::special_kind(&metadata) {
            Some(kind) => Err(format!(
                "{what} '{}' is {kind}, not a regular file",
                path.display()
            )),
            None => Ok(()),
        },
    }
}

/// 1-based line and column of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text.as_bytes()[..offset];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let column = String::from_utf8_lossy(&before[line_start..])
        .chars()
        .count()
        + 1;
    (line, column)
}

impl Timeline {
    /// An error at a span of the file (a default span `0..0` points at the
    /// first line: used for values that were not written in the file).
    pub fn error_at(&self, span: Range<usize>, message: impl Into<String>) -> TimelineError {
        error_at(&self.path, &self.text, span, message)
    }

    /// Reads, parses and checks a timeline. Every check that needs no
    /// simulation happens here, so a bad timeline fails before any work.
    pub fn load(path: &Path) -> Result<Timeline, TimelineError> {
        let fail = |message: String| TimelineError {
            file: path.to_path_buf(),
            line: 0,
            column: 0,
            message: format!("cannot read the timeline: {message}"),
        };
        let bytes = importers::read_limited(path, crate::budget::MAX_TIMELINE_BYTES)
            .map_err(|e| fail(e.to_string()))?;
        let text = String::from_utf8(bytes).map_err(|e| fail(format!("not UTF-8 text ({e})")))?;
        Timeline::parse(path, text)
    }

    /// Parses and checks a timeline's text; `path` names it in errors and
    /// is the folder its relative paths start from.
    pub fn parse(path: &Path, text: String) -> Result<Timeline, TimelineError> {
        let file: TimelineFile = toml::from_str(&text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            error_at(path, &text, span, e.message().trim().to_string())
        })?;
        let mut timeline = Timeline {
            path: path.to_path_buf(),
            text,
            file,
            dt: 0.0,
        };
        timeline.dt = timeline.check()?;
        Ok(timeline)
    }

    /// Steps of every stage at the timeline's `dt` (at least one each).
    pub fn stage_steps(&self) -> Vec<u64> {
        stage_steps_at(self, self.dt)
    }

    /// Checks the work of baking `vertices` and the size of every animated
    /// export against the [`crate::budget`].
    pub fn check_budget(&self, vertices: u64) -> Result<(), TimelineError> {
        self.check_budget_with(vertices, self.dt)
    }

    fn check_budget_with(&self, vertices: u64, dt: f64) -> Result<(), TimelineError> {
        let steps: u64 = stage_steps_at(self, dt)
            .iter()
            .fold(0u64, |a, &b| a.saturating_add(b));
        crate::budget::check_work(vertices, steps)
            .map_err(|m| self.error_at(self.file.stages.span(), m))?;
        let total_time = steps as f64 * dt;
        for e in &self.file.exports {
            if let (Some(fps), ExportWhat::Animated) = (&e.fps, e.what) {
                let frames = (total_time * fps.get_ref() + 1e-6).floor() as u64 + 1;
                crate::budget::check_output(frames, vertices)
                    .map_err(|m| self.error_at(e.path.span(), m))?;
            }
        }
        Ok(())
    }

    /// Warnings about a timeline that is valid but probably not meant.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        if self.file.exports.is_empty() {
            warnings.push(format!(
                "{}: no [[export]]: the bake writes no groom",
                self.path.display()
            ));
        }
        warnings
    }

    /// Resolves a path written in the timeline against the timeline's folder.
    pub fn resolve(&self, relative: &str) -> PathBuf {
        let base = self.path.parent().unwrap_or(Path::new(""));
        base.join(relative)
    }

    /// Total simulated time of all stages, seconds.
    pub fn duration(&self) -> f64 {
        self.file
            .stages
            .get_ref()
            .iter()
            .map(|s| *s.duration.get_ref())
            .sum()
    }

    fn check(&self) -> Result<f64, TimelineError> {
        let f = &self.file;
        let fail = |span: Range<usize>, message: String| Err(self.error_at(span, message));

        // Groom.
        match (&f.groom.source, &f.groom.generate) {
            (Some(_), Some(g)) => {
                return fail(
                    g.span(),
                    "give either `source` or `generate`, not both".into(),
                )
            }
            (None, None) => {
                return fail(
                    0..0,
                    "[groom] needs `source` (a groom file) or `generate`".into(),
                )
            }
            (Some(source), None) => {
                let path = self.resolve(source.get_ref());
                if let Err(message) = check_input_file(&path, "groom file") {
                    return fail(source.span(), message);
                }
            }
            (None, Some(g)) => {
                if let Err(e) = g.get_ref().check() {
                    return fail(g.span(), e.to_string());
                }
                if let Some(mesh) = &g.get_ref().scalp_mesh {
                    let path = self.resolve(&mesh.to_string_lossy());
                    if let Err(message) = check_input_file(&path, "scalp mesh") {
                        return fail(g.span(), message);
                    }
                }
            }
        }
        if let Some(units) = &f.groom.units {
            if let Err(e) = units.get_ref().parse::<groom::Units>() {
                return fail(units.span(), e);
            }
        }
        if let Some(up) = &f.groom.up {
            if let Err(e) = up.get_ref().parse::<groom::UpAxis>() {
                return fail(up.span(), e);
            }
        }
        check_keys(self, &f.groom.motion)?;
        if !f.groom.translate.iter().all(|c| c.is_finite()) {
            return fail(
                ranges::span_of(self, "groom.translate"),
                "[groom] translate must be finite".into(),
            );
        }
        render::check_groom(self)?;

        // Material.
        let m = &f.material;
        if !(0.0..=1.0).contains(m.stiffness.get_ref()) {
            return fail(m.stiffness.span(), "stiffness must be in [0, 1]".into());
        }
        applies::check_material(self)?;
        let positive = |v: f32| v.is_finite() && v > 0.0;
        if !positive(*m.youngs_modulus.get_ref()) {
            return fail(
                m.youngs_modulus.span(),
                "youngs_modulus must be a positive pressure in Pa (hair: 3.5e9)".into(),
            );
        }
        if let Some(g) = &m.shear_modulus {
            if !positive(*g.get_ref()) {
                return fail(
                    g.span(),
                    "shear_modulus must be a positive pressure in Pa".into(),
                );
            }
        }
        if !(-0.99..=0.5).contains(m.poisson_ratio.get_ref()) {
            return fail(
                m.poisson_ratio.span(),
                "poisson_ratio must be in [-0.99, 0.5]".into(),
            );
        }
        if !positive(*m.density.get_ref()) {
            return fail(
                m.density.span(),
                "density must be positive, in kg/m^3 (hair: 1300)".into(),
            );
        }
        if let Some(r) = &m.radius {
            if !(positive(*r.get_ref()) && *r.get_ref() < 0.01) {
                return fail(
                    r.span(),
                    "radius must be a length in (0, 0.01) metres (hair: 4e-5)".into(),
                );
            }
        }
        if !(0.0..=1.0).contains(m.cuticle_peel_per_cm.get_ref()) {
            return fail(
                m.cuticle_peel_per_cm.span(),
                "cuticle_peel_per_cm must be in [0, 1]".into(),
            );
        }
        let bonds = m.bonds.get_ref().as_array();
        if bonds.iter().any(|b| !(b.is_finite() && *b >= 0.0)) || bonds.iter().sum::<f32>() <= 0.0 {
            return fail(
                m.bonds.span(),
                "bond influences must be non-negative with a positive sum".into(),
            );
        }

        // Solver.
        let s = &f.solver;
        let dt = match s.dt.get_ref().seconds() {
            Some(dt) if (crate::budget::MIN_DT..=1.0 / 30.0).contains(&dt) => dt,
            _ => {
                return fail(
                    s.dt.span(),
                    format!(
                        "dt must be a time step in [{}, 1/30] s, as seconds or \"1/360\"",
                        crate::budget::MIN_DT
                    ),
                )
            }
        };
        if let Some(iterations) = &s.iterations {
            if !(1..=100).contains(iterations.get_ref()) {
                return fail(
                    iterations.span(),
                    "iterations must be between 1 and 100".into(),
                );
            }
        }
        if let Some(tolerance) = &s.tolerance {
            let t = *tolerance.get_ref();
            if !(t.is_finite() && (0.0..=0.01).contains(&t)) {
                return fail(
                    tolerance.span(),
                    "tolerance must be a fraction of an edge's length between 0 and 0.01".into(),
                );
            }
        }
        if !s.gravity.iter().all(|g| g.is_finite()) {
            return fail(
                ranges::span_of(self, "solver.gravity"),
                "gravity must be finite".into(),
            );
        }
        if !(s.hair_radius.get_ref().is_finite() && *s.hair_radius.get_ref() > 0.0) {
            return fail(
                s.hair_radius.span(),
                "hair_radius must be a positive length".into(),
            );
        }
        if let Some(hh) = &s.hair_hair {
            if let Some(problem) = hh.get_ref().volumetric().and_then(|v| v.problem()) {
                return fail(hh.span(), format!("hair_hair {problem}"));
            }
            if let Some(problem) = hh.get_ref().friction_problem(*f.material.model.get_ref()) {
                return fail(hh.span(), problem);
            }
            if !(0.0..=10.0).contains(&hh.get_ref().strength) {
                return fail(
                    hh.span(),
                    "hair_hair strength must be in [0, 10] (the paper: stable below 10)".into(),
                );
            }
        }
        let damping = s.damping.get_ref();
        if !(damping.linear >= 0.0
            && damping.angular >= 0.0
            && damping.linear.is_finite()
            && damping.angular.is_finite())
        {
            return fail(s.damping.span(), "damping must be non-negative".into());
        }
        if !(s.quaternion_mass_scale.get_ref().is_finite()
            && *s.quaternion_mass_scale.get_ref() > 0.0)
        {
            return fail(
                s.quaternion_mass_scale.span(),
                "quaternion_mass_scale must be positive".into(),
            );
        }

        // Colliders.
        let mut names: Vec<&str> = Vec::new();
        for c in &f.colliders {
            let name = c.name.get_ref().as_str();
            if names.contains(&name) {
                return fail(c.name.span(), format!("collider name '{name}' used twice"));
            }
            names.push(name);
            self.check_shape(&c.shape)?;
            if !(c.friction.get_ref().is_finite() && *c.friction.get_ref() >= 0.0) {
                return fail(c.friction.span(), "friction must be non-negative".into());
            }
            let keys = c.motion.get_ref();
            let finite = keys.iter().all(|k| {
                k.t.is_finite()
                    && k.translation
                        .iter()
                        .chain(k.rotation.iter())
                        .all(|v| v.is_finite())
            });
            if !finite || keys.windows(2).any(|w| w[1].t <= w[0].t) {
                return fail(
                    c.motion.span(),
                    "motion keys need finite values and increasing times".into(),
                );
            }
        }

        // Stages.
        let stages = f.stages.get_ref();
        if stages.is_empty() {
            return fail(
                f.stages.span(),
                "a timeline needs at least one [[stage]]".into(),
            );
        }
        for stage in stages {
            self.check_stage(stage, &names, dt)?;
        }
        hold::check(self)?;
        // The work and the outputs' sizes: with the generator's vertex
        // count now, a source file's again once it is read (`check_budget`).
        let vertices = match &f.groom.generate {
            Some(g) => {
                let g = g.get_ref();
                g.strands as u64 * (g.edges_per_strand() as u64 + 1)
            }
            None => 0,
        };
        self.check_budget_with(vertices, dt)?;

        // Exports.
        let mut paths: Vec<&str> = Vec::new();
        for e in &f.exports {
            let path = e.path.get_ref().as_str();
            if paths.contains(&path) {
                return fail(e.path.span(), format!("export path '{path}' used twice"));
            }
            paths.push(path);
            let extension = importers::extension_of(Path::new(path));
            if let Err(message) = check_output_extension(Path::new(path)) {
                return fail(e.path.span(), message);
            }
            if e.what == ExportWhat::Animated
                && !exporters::ANIMATED_EXTENSIONS.contains(&extension.as_str())
            {
                return fail(
                    e.path.span(),
                    format!(
                        "'.{extension}' cannot hold animation (animated exports: {})",
                        exporters::ANIMATED_EXTENSIONS.join(", ")
                    ),
                );
            }
            match (&e.fps, e.what) {
                (Some(fps), ExportWhat::Animated) => {
                    let v = *fps.get_ref();
                    if !(v.is_finite() && v > 0.0 && v <= 1.0 / dt) {
                        return fail(
                            fps.span(),
                            format!(
                                "fps must be in (0, {}] (one frame per step at most)",
                                1.0 / dt
                            ),
                        );
                    }
                }
                (Some(fps), _) => {
                    return fail(fps.span(), "fps applies only to animated exports".into())
                }
                (None, _) => {}
            }
            if let Some(target) = &e.target {
                if let Err(message) = target.get_ref().parse::<exporters::Target>() {
                    return fail(target.span(), message);
                }
            }
            if let Some(units) = &e.units {
                if let Err(message) = units.get_ref().parse::<groom::Units>() {
                    return fail(units.span(), message);
                }
            }
            if let Some(up) = &e.up {
                if let Err(message) = up.get_ref().parse::<groom::UpAxis>() {
                    return fail(up.span(), message);
                }
            }
            render::check_export(self, e)?;
            cache::check_export(self, e)?;
        }
        if let Some(preview) = &f.preview {
            let path = Path::new(preview.sheet.get_ref());
            if let Err(message) = check_output_name(path) {
                return fail(preview.sheet.span(), message);
            }
            if importers::extension_of(path) != "png" {
                return fail(
                    preview.sheet.span(),
                    "the preview sheet is a PNG: name it *.png".into(),
                );
            }
            let [w, h] = *preview.size.get_ref();
            if !(1..=4096).contains(&w) || !(1..=4096).contains(&h) {
                return fail(
                    preview.size.span(),
                    "preview size must be 1 to 4096 pixels each way".into(),
                );
            }
            let view = preview.view.get_ref();
            if view != schema::AUTO_VIEW {
                if let Err(e) = view.parse::<crate::preview::View>() {
                    return fail(preview.view.span(), format!("{e}, or auto"));
                }
            }
        }
        // Every number within its documented range (after the checks
        // above, whose messages are more specific).
        ranges::check(self)?;
        Ok(dt)
    }

    fn check_shape(&self, shape: &Spanned<ShapeSpec>) -> Result<(), TimelineError> {
        let positive = |v: &[f32]| v.iter().all(|x| x.is_finite() && *x > 0.0);
        let ok = match shape.get_ref() {
            ShapeSpec::HalfSpace { normal } => {
                normal.iter().all(|x| x.is_finite())
                    && normal.iter().map(|x| x * x).sum::<f32>() > 0.0
            }
            ShapeSpec::Cuboid { half_extents } => positive(half_extents),
            ShapeSpec::Ball { radius } => positive(&[*radius]),
            ShapeSpec::Capsule {
                half_height,
                radius,
            }
            | ShapeSpec::Cylinder {
                half_height,
                radius,
            } => positive(&[*half_height, *radius]),
            ShapeSpec::Mesh { path, scale } => {
                let resolved = self.resolve(path);
                if let Err(message) = check_input_file(&resolved, "mesh file") {
                    return Err(self.error_at(shape.span(), message));
                }
                let extension = importers::extension_of(&resolved);
                if !["obj", "glb", "gltf"].contains(&extension.as_str()) {
                    return Err(self.error_at(
                        shape.span(),
                        "collider meshes are read from .obj, .glb or .gltf",
                    ));
                }
                positive(&[*scale])
            }
        };
        if ok {
            Ok(())
        } else {
            Err(self.error_at(
                shape.span(),
                "shape sizes must be positive and finite (a half-space needs a non-zero normal)",
            ))
        }
    }

    fn check_stage(
        &self,
        stage: &schema::StageSpec,
        colliders: &[&str],
        dt: f64,
    ) -> Result<(), TimelineError> {
        let kind = *stage.kind.get_ref();
        let fail = |span: Range<usize>, message: String| Err(self.error_at(span, message));
        let duration = *stage.duration.get_ref();
        if !(duration.is_finite() && duration > 0.0 && duration <= 86_400.0) {
            return fail(
                stage.duration.span(),
                format!(
                    "{} stage: duration must be positive (seconds, at most a day)",
                    kind.name()
                ),
            );
        }
        if duration < dt {
            return fail(
                stage.duration.span(),
                format!(
                    "{} stage: duration is shorter than one time step",
                    kind.name()
                ),
            );
        }
        for name in &stage.colliders {
            if !colliders.contains(&name.get_ref().as_str()) {
                return fail(
                    name.span(),
                    format!("no collider named '{}'", name.get_ref()),
                );
            }
        }
        for (name, drive) in &stage.bonds {
            if !BOND_NAMES.contains(&name.as_str()) {
                return fail(
                    drive.span(),
                    format!("unknown bond '{name}' (known: {})", BOND_NAMES.join(", ")),
                );
            }
            check_drive(self, drive)?;
        }
        if let Some(w) = &stage.wetness {
            check_drive(self, w)?;
        }
        applies::check_stage_keys(self, stage)?;
        let only = |present: bool, span: Range<usize>, what: &str, kinds: &[StageKind]| {
            if present && !kinds.contains(&kind) {
                let names: Vec<_> = kinds.iter().map(|k| k.name()).collect();
                Err(self.error_at(
                    span,
                    format!(
                        "`{what}` applies to {} stages, not {}",
                        names.join("/"),
                        kind.name()
                    ),
                ))
            } else {
                Ok(())
            }
        };
        only(
            stage.shampoo,
            stage.kind.span(),
            "shampoo",
            &[StageKind::Wet, StageKind::Wash],
        )?;
        if let Some(d) = &stage.drying_time {
            only(
                true,
                d.span(),
                "drying_time",
                &[StageKind::Dry, StageKind::Wash],
            )?;
            if !(d.get_ref().is_finite() && *d.get_ref() > 0.0) {
                return fail(d.span(), "drying_time must be positive".into());
            }
        }
        if let Some(b) = &stage.blower {
            only(true, b.span(), "blower", &[StageKind::Dry])?;
            let v = b.get_ref();
            let finite = v.from.iter().chain(v.to.iter()).all(|x| x.is_finite());
            let length: f32 = (0..3).map(|k| (v.to[k] - v.from[k]).powi(2)).sum();
            let rates_ok = v.strength >= 0.0 && v.hydrogen_rate >= 0.0;
            if !finite || length <= 0.0 || !rates_ok {
                return fail(
                    b.span(),
                    "blower needs distinct finite `from`/`to` and non-negative strength and rate"
                        .into(),
                );
            }
            let cone_ok = v
                .cone_half_angle
                .is_none_or(|a| a.is_finite() && a > 0.0 && a < 90.0);
            if !(v.falloff_length.is_finite() && v.falloff_length > 0.0 && cone_ok) {
                return fail(
                    b.span(),
                    "blower falloff_length must be a positive length in metres and cone_half_angle in (0, 90) degrees"
                        .into(),
                );
            }
        }
        if let Some(r) = &stage.rod {
            only(true, r.span(), "rod", &[StageKind::Perm])?;
            let v = r.get_ref();
            let phases_ok = v.phases[0] > 0.0
                && v.phases[0] < v.phases[1]
                && v.phases[1] < v.phases[2]
                && v.phases[2] <= 1.0;
            let axis_ok = v.axis.is_none_or(|a| {
                a.iter().all(|c| c.is_finite()) && a.iter().map(|c| c * c).sum::<f32>() > 0.0
            });
            if !(v.radius.is_finite()
                && v.radius > 0.0
                && v.root_gap.is_finite()
                && v.root_gap >= 0.0
                && axis_ok
                && (0.0..=1.0).contains(&v.disulfide_cut)
                && phases_ok)
            {
                return fail(r.span(), "rod needs a positive radius, root_gap >= 0, disulfide_cut in [0, 1], increasing phases in (0, 1] and a non-zero axis".into());
            }
            // The documented range (docs/tuning.md): real perm rods. A
            // thinner rod bends edges further than a step can follow.
            if !ROD_RADIUS.contains(&v.radius) {
                return fail(
                    r.span(),
                    format!(
                        "rod radius {} m: outside the documented {} - {} m (perm rods are 5 mm to 5 cm)",
                        v.radius,
                        ROD_RADIUS.start(),
                        ROD_RADIUS.end()
                    ),
                );
            }
        }
        match (&stage.wind, kind) {
            (Some(w), StageKind::Wind) => {
                let v = w.get_ref();
                let schedule_ok = !v.schedule.is_empty()
                    && v.schedule
                        .iter()
                        .all(|k| (0.0..=1.0).contains(&k.v) && k.frame >= 1)
                    && v.schedule.windows(2).all(|p| p[1].frame > p[0].frame);
                if !(v.fps.is_finite() && v.fps > 0.0 && v.direction.is_finite() && schedule_ok) {
                    return fail(w.span(), "wind needs a finite direction, positive fps and a schedule of increasing frames (from 1) with v in [0, 1]".into());
                }
                // Each model frame moves every strand: more than one a step
                // multiplies the work without being seen.
                if v.fps > 1.0 / dt {
                    return fail(
                        w.span(),
                        format!(
                            "wind fps must be at most {} (one model frame per step)",
                            1.0 / dt
                        ),
                    );
                }
                if !v.head.radii.iter().all(|r| r.is_finite() && *r > 0.0)
                    || !v.head.center.iter().all(|c| c.is_finite())
                {
                    return fail(
                        w.span(),
                        "wind head needs finite center and positive radii".into(),
                    );
                }
            }
            (Some(w), _) => only(true, w.span(), "wind", &[StageKind::Wind])?,
            (None, StageKind::Wind) => {
                return fail(
                    stage.kind.span(),
                    "a wind stage needs a `wind` table".into(),
                )
            }
            (None, _) => {}
        }
        Ok(())
    }
}

/// Steps of every stage at `dt` (at least one each); durations were
/// checked to be at most a day and dt at least [`crate::budget::MIN_DT`].
fn stage_steps_at(timeline: &Timeline, dt: f64) -> Vec<u64> {
    timeline
        .file
        .stages
        .get_ref()
        .iter()
        .map(|s| ((s.duration.get_ref() / dt).round() as u64).max(1))
        .collect()
}

/// Whether the exporters know the extension of `path`; the message names
/// what is wrong (no extension, or an unknown one) and the known ones.
pub fn check_output_extension(path: &Path) -> Result<(), String> {
    check_output_name(path)?;
    let extension = importers::extension_of(path);
    if exporters::EXTENSIONS.contains(&extension.as_str()) {
        return Ok(());
    }
    let known = exporters::EXTENSIONS.join(", ");
    Err(if extension.is_empty() {
        format!("no file extension to choose the output format by (known: {known})")
    } else {
        format!(
            "unknown output format {:?} (known: {known})",
            format!(".{}", extension.escape_debug())
        )
    })
}

/// Refuses an output path that cannot name a file, whatever is on disk: a
/// NUL byte (no system call takes it), a trailing separator or a last
/// component of `.` or `..` (a folder). `Path` itself drops a trailing
/// `/`, so the bytes are looked at.
pub fn check_output_name(path: &Path) -> Result<(), String> {
    use std::os::unix::ffi::OsStrExt;
    let bytes = path.as_os_str().as_bytes();
    if bytes.contains(&0) {
        return Err("the path contains a NUL byte".into());
    }
    if bytes.is_empty() {
        return Err("the path is empty".into());
    }
    if bytes.ends_with(b"/") {
        return Err("the path ends with '/': it names a folder, not a file".into());
    }
    if matches!(
        path.components().next_back(),
        Some(std::path::Component::CurDir | std::path::Component::ParentDir) | None
    ) || bytes.ends_with(b"/.")
    {
        return Err("the path names a folder ('.' or '..'), not a file".into());
    }
    Ok(())
}

fn check_keys(
    timeline: &Timeline,
    keys: &Spanned<Vec<schema::KeySpec>>,
) -> Result<(), TimelineError> {
    let list = keys.get_ref();
    let finite = list.iter().all(|k| {
        k.t.is_finite()
            && k.translation
                .iter()
                .chain(k.rotation.iter())
                .all(|v| v.is_finite())
    });
    if !finite || list.windows(2).any(|w| w[1].t <= w[0].t) {
        return Err(timeline.error_at(
            keys.span(),
            "motion keys need finite values and increasing times",
        ));
    }
    Ok(())
}

fn check_drive(
    timeline: &Timeline,
    drive: &Spanned<schema::BondDriveSpec>,
) -> Result<(), TimelineError> {
    let d = drive.get_ref();
    if !((0.0..=1.0).contains(&d.target) && d.time.is_finite() && d.time > 0.0) {
        return Err(timeline.error_at(
            drive.span(),
            "a drive needs target in [0, 1] and a positive time",
        ));
    }
    Ok(())
}

/// An error at a byte span of a TOML text (a manifest's too).
pub fn error_at(
    path: &Path,
    text: &str,
    span: Range<usize>,
    message: impl Into<String>,
) -> TimelineError {
    let (line, column) = line_column(text, span.start);
    TimelineError {
        file: path.to_path_buf(),
        line,
        column,
        message: message.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load_text(text: &str) -> Result<Timeline, TimelineError> {
        let dir = std::env::temp_dir().join(format!("groombake-timeline-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("t{}.toml", text.len()));
        std::fs::write(&path, text).unwrap();
        let result = Timeline::load(&path);
        let _ = std::fs::remove_file(&path);
        result
    }

    const GOOD: &str = r#"
[groom]
generate = { strands = 4, layout = "swatch" }

[[stage]]
kind = "wet"
duration = 0.5
"#;

    #[test]
    fn good_timeline_loads() {
        let t = load_text(GOOD).unwrap();
        assert!((t.dt - 1.0 / 360.0).abs() < 1e-15);
        assert_eq!(t.duration(), 0.5);
    }

    #[test]
    fn typo_names_line_and_column() {
        let text = GOOD.replace("duration = 0.5", "duration = 0.5\ndurtion = 1");
        let e = load_text(&text).unwrap_err();
        assert_eq!((e.line, e.column), (8, 1), "{e}");
        assert!(e.message.contains("durtion"), "{e}");
    }

    #[test]
    fn negative_duration_names_line_and_column() {
        let e = load_text(&GOOD.replace("0.5", "-1.0")).unwrap_err();
        assert_eq!((e.line, e.column), (7, 12), "{e}");
        assert!(e.message.contains("duration must be positive"), "{e}");
    }

    #[test]
    fn missing_groom_file_is_named() {
        let text = GOOD.replace(
            r#"generate = { strands = 4, layout = "swatch" }"#,
            r#"source = "no/such.hair""#,
        );
        let e = load_text(&text).unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.message.contains("not found"), "{e}");
    }

    #[test]
    fn volumetric_hair_hair_reaches_the_solver_and_a_bad_cell_size_is_named() {
        let text = format!(
            "{GOOD}\n[solver]\nhair_hair = {{ mode = \"volumetric\", cell_size = 0.004 }}\n"
        );
        let t = load_text(&text).unwrap();
        let parameters = bake::parameters_of(&t);
        assert_eq!(parameters.hair_hair_strength, None);
        let volumetric = parameters.volumetric.unwrap();
        assert_eq!(volumetric.cell_size, 0.004);
        assert_eq!(
            volumetric.smoothing,
            crate::sim::Volumetric::default().smoothing
        );
        let e = load_text(&text.replace("0.004", "2.0")).unwrap_err();
        assert!(e.message.contains("cell_size must be"), "{e}");
        // The pairwise mode (the default) keeps its strength.
        let pairwise = load_text(&format!(
            "{GOOD}\n[solver]\nhair_hair = {{ strength = 5.0 }}\n"
        ))
        .unwrap();
        let parameters = bake::parameters_of(&pairwise);
        assert_eq!(parameters.hair_hair_strength, Some(5.0));
        assert_eq!(parameters.volumetric, None);
    }

    /// Friction between hairs (issue 33): off unless asked for (its search
    /// is not yet within the step's budget), in the physical model's
    /// pairwise mode; 0 switches it off, out of range or where it does not
    /// apply is an error at the key's line.
    #[test]
    fn hair_friction_defaults_reaches_the_solver_and_bad_values_are_named() {
        let with = |table: &str| format!("{GOOD}\n[solver]\nhair_hair = {{ {table} }}\n");
        let parameters = |table: &str| bake::parameters_of(&load_text(&with(table)).unwrap());
        assert_eq!(parameters("strength = 5.0").hair_friction, None);
        assert_eq!(
            parameters(&format!(
                "strength = 5.0, friction = {}",
                schema::DEFAULT_HAIR_FRICTION
            ))
            .hair_friction,
            Some(schema::DEFAULT_HAIR_FRICTION)
        );
        assert_eq!(
            parameters("strength = 5.0, friction = 0.1").hair_friction,
            Some(0.1)
        );
        assert_eq!(
            parameters("strength = 5.0, friction = 0").hair_friction,
            None
        );
        let volumetric = parameters("mode = \"volumetric\", grid_friction = 500.0");
        assert_eq!(volumetric.hair_friction, None);
        assert_eq!(volumetric.volumetric.unwrap().friction, 500.0);
        for (table, says) in [
            ("strength = 5.0, friction = 0.7", "from 0.05 to 0.5"),
            ("strength = 5.0, friction = 0.01", "from 0.05 to 0.5"),
            ("mode = \"volumetric\", friction = 0.3", "pairwise mode"),
            ("strength = 5.0, grid_friction = 10.0", "volumetric mode"),
            (
                "mode = \"volumetric\", grid_friction = -1.0",
                "grid_friction must be",
            ),
        ] {
            let e = load_text(&with(table)).unwrap_err();
            assert!(e.line == 10 && e.message.contains(says), "{table}: {e}");
        }
        let paper = format!(
            "{GOOD}\n[material]\nmodel = \"paper\"\n[solver]\nhair_hair = {{ strength = 5.0, friction = 0.3 }}\n"
        );
        let e = load_text(&paper).unwrap_err();
        assert!(e.message.contains("physical model only"), "{e}");
        // The paper model's pairwise hair-hair stays frictionless.
        let paper = paper.replace(", friction = 0.3", "");
        assert_eq!(
            bake::parameters_of(&load_text(&paper).unwrap()).hair_friction,
            None
        );
    }

    #[test]
    fn fractional_dt_is_parsed() {
        let t = load_text(&format!("{GOOD}\n[solver]\ndt = \"1/1000\"\n")).unwrap();
        assert!((t.dt - 0.001).abs() < 1e-15);
        let e = load_text(&format!("{GOOD}\n[solver]\ndt = \"1/0\"\n")).unwrap_err();
        assert!(e.message.contains("dt"), "{e}");
    }

    #[test]
    fn unknown_collider_in_stage_is_named() {
        let text = GOOD.replace("duration = 0.5", "duration = 0.5\ncolliders = [\"pillow\"]");
        let e = load_text(&text).unwrap_err();
        assert!(e.message.contains("pillow"), "{e}");
        assert_eq!(e.line, 8);
    }
}
