//! Preparing a bake: the timeline's groom loaded (or generated) and split
//! into guides and render hair, its material and solver parameters, the
//! strands and colliders built and the sag-free start solved, everything
//! checked before the first step ([`prepare`]).

use super::error::BakeError;
use super::motion::pose_at;
use super::schema::{ColliderActivity, ShapeSpec, StageKind};
use super::shapes::{pose_of, shape_of};
use super::{Timeline, TimelineError};
use crate::sim::{
    self, attribute_names, Collider, ColliderSet, Material, SolverParameters, StrandSet,
};
use groom::{Groom, Units, UpAxis};

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
pub(super) fn start_colliders(timeline: &Timeline, colliders: &ColliderSet) -> ColliderSet {
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
