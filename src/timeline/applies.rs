//! No silent parameter: a key the chosen material model or stage kind does
//! not use is refused (exit 2, with its place), never ignored. Keys are
//! told apart from defaults by their span: a default has the empty span
//! `0..0`, a key written in the file does not.

use super::schema::{StageKind, StageSpec};
use super::{Timeline, TimelineError};
use crate::sim::Model;
use std::ops::Range;

fn written(span: &Range<usize>) -> bool {
    span.end > 0
}

/// `[material]` and `[solver]` keys of one model only: `stiffness` and
/// `quaternion_mass_scale` are the paper model's (the physical model bends
/// by `youngs_modulus` and the fibre radius, and its frames have their
/// segments' inertia); the moduli, the Newton `tolerance` and the
/// `integrator` are the physical model's.
pub(super) fn check_material(timeline: &Timeline) -> Result<(), TimelineError> {
    let m = &timeline.file.material;
    let model = *m.model.get_ref();
    let refuse = |span: Range<usize>, key: &str, used_by: &str, instead: &str| {
        Err(timeline.error_at(
            span,
            format!(
                "`{key}` does not apply to the {} model (it is the {used_by} model's){instead}",
                model_name(model)
            ),
        ))
    };
    let s = &timeline.file.solver;
    match model {
        Model::Physical => {
            if written(&s.quaternion_mass_scale.span()) {
                return refuse(
                    s.quaternion_mass_scale.span(),
                    "quaternion_mass_scale",
                    "paper",
                    ": the physical model's frames have their segments' inertia",
                );
            }
            if written(&m.stiffness.span()) {
                return refuse(
                    m.stiffness.span(),
                    "stiffness",
                    "paper",
                    ": the physical model bends by youngs_modulus and the fibre radius; \
                     remove it, or set model = \"paper\"",
                );
            }
        }
        Model::Paper => {
            let physical = [
                ("youngs_modulus", Some(m.youngs_modulus.span())),
                ("shear_modulus", m.shear_modulus.as_ref().map(|g| g.span())),
                ("poisson_ratio", Some(m.poisson_ratio.span())),
            ];
            if let Some(tolerance) = &s.tolerance {
                return refuse(
                    tolerance.span(),
                    "tolerance",
                    "physical",
                    ": the paper model runs `iterations` Gauss-Seidel sweeps",
                );
            }
            if let Some(integrator) = &s.integrator {
                return refuse(
                    integrator.span(),
                    "integrator",
                    "physical",
                    ": the paper model's step is the paper's",
                );
            }
            for (key, span) in physical {
                if let Some(span) = span.filter(written) {
                    return refuse(
                        span,
                        key,
                        "physical",
                        ": the paper model bends by `stiffness` (k_o)",
                    );
                }
            }
        }
    }
    Ok(())
}

fn model_name(model: Model) -> &'static str {
    match model {
        Model::Physical => "physical",
        Model::Paper => "paper",
    }
}

/// Stage keys the stage kind does not use. The wind stage moves the hair
/// by the stochastic wind model alone, without the rod solver: the
/// solver's damping and the colliders do nothing there. The drying air
/// (`air_temperature`, `air_speed`, `humidity`) is a `dry` stage's.
pub(super) fn check_stage_keys(
    timeline: &Timeline,
    stage: &StageSpec,
) -> Result<(), TimelineError> {
    let kind = *stage.kind.get_ref();
    let refuse = |span: Range<usize>, key: &str, why: &str| {
        Err(timeline.error_at(
            span,
            format!("`{key}` does not apply to a {} stage ({why})", kind.name()),
        ))
    };
    if kind == StageKind::Wind {
        if stage.damping.is_some() {
            return refuse(
                stage.kind.span(),
                "damping",
                "the wind model moves the hair without the rod solver",
            );
        }
        if let Some(name) = stage.colliders.first() {
            return refuse(
                name.span(),
                "colliders",
                "the wind model moves the hair without the rod solver",
            );
        }
    }
    if kind != StageKind::Dry {
        for (key, span) in [
            (
                "air_temperature",
                stage.air_temperature.as_ref().map(|v| v.span()),
            ),
            ("air_speed", stage.air_speed.as_ref().map(|v| v.span())),
            ("humidity", stage.humidity.as_ref().map(|v| v.span())),
        ] {
            if let Some(span) = span {
                return refuse(span, key, "the drying air is a dry stage's");
            }
        }
    }
    check_drying_air(timeline, stage)
}

/// The drying air's keys: in range, and not beside `drying_time`, which
/// dries the hair over its time whatever the air.
fn check_drying_air(timeline: &Timeline, stage: &StageSpec) -> Result<(), TimelineError> {
    let ranges = [
        (
            "air_temperature",
            &stage.air_temperature,
            -30.0,
            100.0,
            "degrees Celsius",
        ),
        ("air_speed", &stage.air_speed, 0.0, 50.0, "m/s"),
        ("humidity", &stage.humidity, 0.0, 1.0, "a fraction"),
    ];
    for (key, value, low, high, unit) in ranges {
        let Some(value) = value else { continue };
        if stage.drying_time.is_some() {
            return Err(timeline.error_at(
                value.span(),
                format!(
                    "`{key}` does not apply beside `drying_time` (which dries the hair over                      its time whatever the air): remove one"
                ),
            ));
        }
        let v = *value.get_ref();
        if !(v.is_finite() && (low..=high).contains(&v)) {
            return Err(timeline.error_at(
                value.span(),
                format!("{key} must be in [{low}, {high}] ({unit})"),
            ));
        }
    }
    if let Some(blower) = &stage.blower {
        let b = blower.get_ref();
        let given = b.air_speed.is_some() || b.air_temperature.is_some();
        if given && stage.drying_time.is_some() {
            return Err(timeline.error_at(
                blower.span(),
                "the blower's `air_speed` and `air_temperature` do not apply beside                  `drying_time` (which dries the hair over its time whatever the air): remove one",
            ));
        }
        let speed_ok = b
            .air_speed
            .is_none_or(|v| v.is_finite() && (0.0..=50.0).contains(&v));
        let heat_ok = b
            .air_temperature
            .is_none_or(|v| v.is_finite() && (-30.0..=120.0).contains(&v));
        if !(speed_ok && heat_ok) {
            return Err(timeline.error_at(
                blower.span(),
                "blower air_speed must be in [0, 50] m/s and air_temperature in [-30, 120]                  degrees Celsius",
            ));
        }
    }
    Ok(())
}
