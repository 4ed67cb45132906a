//! The documented range of every numeric key of a timeline (the table in
//! `docs/tuning.md`, "Every number's range"), checked by `validate` before
//! any work, the error at the value's line and column.
//!
//! The schema's types keep a span for a few keys only, so the ranges are
//! checked on the text's own spanned tree (`toml::de::DeTable`): every
//! number, in tables, inline tables, arrays and arrays of tables, is found
//! with its key path (`stage.wind.direction`, array indices left out) and
//! compared with its rule. A value inside its range can still be refused
//! by the checks of its key in `timeline::check` (e.g. positivity); a value
//! outside it never reaches the simulation, where a friction of 1e30 or a
//! groom moved by 1e30 m bakes to garbage without a warning.

use super::{Timeline, TimelineError};
use crate::budget::{MAX_COORDINATE, MIN_DT};
use toml::de::{DeTable, DeValue};

/// A day, seconds: the longest stage and the latest key time.
const DAY: f64 = 86_400.0;

/// One key's range: `min..=max` in `unit`.
struct Rule {
    /// Key path with array indices left out; `*` matches any one key.
    path: &'static str,
    min: f64,
    max: f64,
    unit: &'static str,
}

const fn rule(path: &'static str, min: f64, max: f64, unit: &'static str) -> Rule {
    Rule {
        path,
        min,
        max,
        unit,
    }
}

/// Every numeric key and its range. Coordinates and lengths in a scene are
/// within [`MAX_COORDINATE`]; times within a day; angles within a turn
/// either way; shares and fractions within [0, 1]. The material and solver
/// ranges are the tuning guide's.
const RULES: &[Rule] = &[
    rule("seed", 0.0, u64::MAX as f64, ""),
    // [groom]
    rule("groom.translate", -MAX_COORDINATE, MAX_COORDINATE, "m"),
    rule("groom.motion.t", -DAY, DAY, "s"),
    rule(
        "groom.motion.translation",
        -MAX_COORDINATE,
        MAX_COORDINATE,
        "m",
    ),
    rule("groom.motion.rotation", -360.0, 360.0, "degrees"),
    rule("groom.generate.strands", 1.0, 10_000_000.0, ""),
    rule("groom.generate.length", 1e-4, 10.0, "m"),
    rule("groom.generate.segment_length", 1e-5, 1.0, "m"),
    rule("groom.generate.seed", 0.0, u64::MAX as f64, ""),
    rule(
        "groom.generate.head_center",
        -MAX_COORDINATE,
        MAX_COORDINATE,
        "m",
    ),
    rule("groom.generate.head_radii", 1e-3, 10.0, "m"),
    rule("groom.generate.scalp_angle", 0.0, 180.0, "degrees"),
    rule("groom.generate.swatch_width", 0.0, 10.0, "m"),
    rule("groom.generate.wave_amplitude", -10.0, 10.0, ""),
    rule("groom.generate.wave_frequency", -1e4, 1e4, "rad/m"),
    rule("groom.generate.wave_start", 0.0, 10.0, "m"),
    rule("groom.generate.width", 0.0, 0.01, "m"),
    rule("groom.generate.drape", -1e3, 1e3, "rad/m"),
    rule("groom.generate.hairline", 30.0, 170.0, "degrees"),
    rule("groom.generate.parting", -60.0, 60.0, "degrees"),
    rule("groom.generate.whorl_angle", 0.0, 80.0, "degrees"),
    rule("groom.generate.whorl_swirl", -180.0, 180.0, "degrees"),
    rule("groom.generate.lift", 1.0, 60.0, "degrees"),
    rule("groom.generate.volume", 2e-4, 0.05, "m"),
    rule("groom.generate.contact_length", 0.0, 0.3, "m"),
    rule("groom.generate.length_spread", 0.0, 0.3, ""),
    rule("groom.generate.width_spread", 0.0, 0.3, ""),
    rule("groom.generate.curl_radius", 0.001, 0.05, "m"),
    rule("groom.generate.curl_radius_spread", 0.0, 0.3, ""),
    rule("groom.generate.curl_pitch", 0.002, 0.5, "m"),
    rule("groom.generate.curl_phase", -360.0, 360.0, "degrees"),
    rule("groom.generate.curl_phase_spread", 0.0, 180.0, "degrees"),
    rule("groom.generate.clump_size", 0.0, 0.1, "m"),
    rule("groom.generate.clump_strength", 0.0, 1.0, ""),
    rule("groom.generate.clump_profile", 0.1, 10.0, ""),
    rule("groom.guides.count", 1.0, 10_000_000.0, ""),
    rule("groom.guides.every", 1.0, 10_000_000.0, ""),
    rule("groom.render.count", 1.0, 2_000_000.0, ""),
    rule("groom.render.seed", 0.0, u64::MAX as f64, ""),
    rule("groom.render.clump", 0.0, 1.0, ""),
    rule("groom.render.noise", 0.0, 0.05, "m"),
    // [material]
    rule("material.stiffness", 0.0, 1.0, ""),
    rule("material.youngs_modulus", 1e8, 1e10, "Pa"),
    rule("material.shear_modulus", 1e8, 5e9, "Pa"),
    rule("material.poisson_ratio", -0.99, 0.5, ""),
    rule("material.density", 500.0, 3000.0, "kg/m^3"),
    rule("material.radius", 1e-5, 1e-4, "m"),
    rule("material.cuticle_peel_per_cm", 0.0, 1.0, "1/cm"),
    rule("material.bonds.*", 0.0, 1.0, ""),
    // [solver]
    rule("solver.dt", MIN_DT, 1.0 / 30.0, "s"),
    rule("solver.iterations", 1.0, 100.0, ""),
    rule("solver.tolerance", 0.0, 0.01, ""),
    rule("solver.gravity", -100.0, 100.0, "m/s^2"),
    rule("solver.hair_radius", 1e-6, 0.01, "m"),
    rule("solver.hair_hair.strength", 0.0, 10.0, "m/s^2"),
    rule("solver.hair_hair.cell_size", 0.001, 0.05, "m"),
    rule("solver.hair_hair.smoothing", 0.0, 1000.0, "1/s"),
    rule("solver.hair_hair.repulsion", 0.0, 1000.0, "m^2/s^2"),
    rule("solver.damping.*", 0.0, 100.0, "1/s"),
    rule("solver.quaternion_mass_scale", 1e-3, 1e3, ""),
    // [[collider]]
    rule("collider.friction", 0.0, 10.0, ""),
    rule(
        "collider.shape.half_space.normal",
        -MAX_COORDINATE,
        MAX_COORDINATE,
        "",
    ),
    rule("collider.shape.*.half_extents", 0.0, MAX_COORDINATE, "m"),
    rule("collider.shape.*.radius", 0.0, MAX_COORDINATE, "m"),
    rule("collider.shape.*.half_height", 0.0, MAX_COORDINATE, "m"),
    rule("collider.shape.mesh.scale", 1e-6, 1e6, ""),
    rule("collider.motion.t", -DAY, DAY, "s"),
    rule(
        "collider.motion.translation",
        -MAX_COORDINATE,
        MAX_COORDINATE,
        "m",
    ),
    rule("collider.motion.rotation", -360.0, 360.0, "degrees"),
    // [[stage]]
    rule("stage.duration", 0.0, DAY, "s"),
    rule("stage.bonds.*.target", 0.0, 1.0, ""),
    rule("stage.bonds.*.time", 0.0, DAY, "s"),
    rule("stage.wetness.target", 0.0, 1.0, ""),
    rule("stage.wetness.time", 0.0, DAY, "s"),
    rule("stage.drying_time", 0.0, DAY, "s"),
    rule("stage.blower.from", -MAX_COORDINATE, MAX_COORDINATE, "m"),
    rule("stage.blower.to", -MAX_COORDINATE, MAX_COORDINATE, "m"),
    rule("stage.blower.strength", 0.0, 1e3, "m/s^2"),
    rule("stage.blower.hydrogen_rate", 0.0, 1.0, "s/m"),
    rule("stage.blower.falloff_length", 1e-4, MAX_COORDINATE, "m"),
    rule("stage.blower.cone_half_angle", 0.0, 180.0, "degrees"),
    rule("stage.rod.radius", 1e-4, 1.0, "m"),
    rule("stage.rod.root_gap", 0.0, 10.0, "m"),
    rule("stage.rod.phases", 0.0, 1.0, ""),
    rule("stage.rod.disulfide_cut", 0.0, 1.0, ""),
    rule("stage.rod.axis", -MAX_COORDINATE, MAX_COORDINATE, ""),
    rule("stage.wind.direction", -360.0, 360.0, "degrees"),
    rule("stage.wind.fps", 0.0, 1.0 / MIN_DT, "1/s"),
    rule("stage.wind.schedule.frame", 1.0, 1e6, ""),
    rule("stage.wind.schedule.v", 0.0, 1.0, ""),
    rule(
        "stage.wind.head.center",
        -MAX_COORDINATE,
        MAX_COORDINATE,
        "m",
    ),
    rule("stage.wind.head.radii", 1e-3, 10.0, "m"),
    rule("stage.damping.*", 0.0, 100.0, "1/s"),
    // [[export]], [preview]
    rule("export.fps", 0.0, 1.0 / MIN_DT, "1/s"),
    rule("export.resample", 1e-5, 1.0, "m"),
    rule("preview.size", 1.0, 4096.0, "pixels"),
    rule("preview.resample", 1e-5, 1.0, "m"),
];

/// Key times (`motion.t`) other than 0 closer to 0 than this are refused:
/// 4.2e-45 s is no time a file can store (a USD time code rounds it to 0
/// and then two keys share one code).
const TIME_RESOLUTION: f64 = MIN_DT;

fn matches(pattern: &str, path: &[String]) -> bool {
    let parts: Vec<&str> = pattern.split('.').collect();
    parts.len() == path.len() && parts.iter().zip(path).all(|(p, k)| *p == "*" || p == k)
}

/// The rule of a key path, if it has one.
fn rule_of(path: &[String]) -> Option<&'static Rule> {
    RULES.iter().find(|r| matches(r.path, path))
}

/// A TOML number as f64 (integers exactly up to 2^53, enough for ranges).
fn number(value: &DeValue<'_>) -> Option<f64> {
    match value {
        DeValue::Integer(i) => i128::from_str_radix(&i.as_str().replace('_', ""), i.radix())
            .ok()
            .map(|v| v as f64),
        DeValue::Float(f) => f.as_str().replace('_', "").parse().ok(),
        _ => None,
    }
}

fn shown(value: f64) -> String {
    if value != 0.0 && (value.abs() >= 1e6 || value.abs() < 1e-3) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

/// Checks every number of the timeline's text against [`RULES`].
pub(super) fn check(timeline: &Timeline) -> Result<(), TimelineError> {
    // The text parsed as the schema did; a failure was reported there.
    let Ok(root) = DeTable::parse(&timeline.text) else {
        return Ok(());
    };
    let mut path = Vec::new();
    walk_table(timeline, root.get_ref(), &mut path)
}

/// The span of the value of a key path without array indices
/// (`solver.gravity`), for checks of keys whose schema type keeps none;
/// `0..0` (the first line) when the key is not written.
pub(super) fn span_of(timeline: &Timeline, key: &str) -> std::ops::Range<usize> {
    let Ok(root) = DeTable::parse(&timeline.text) else {
        return 0..0;
    };
    let mut value: Option<&toml::Spanned<DeValue<'_>>> = None;
    let mut table = root.get_ref();
    for part in key.split('.') {
        let Some((_, found)) = table.iter().find(|(k, _)| k.get_ref() == part) else {
            return 0..0;
        };
        value = Some(found);
        if let DeValue::Table(inner) = found.get_ref() {
            table = inner;
        }
    }
    value.map_or(0..0, |v| v.span())
}

fn walk_table(
    timeline: &Timeline,
    table: &DeTable<'_>,
    path: &mut Vec<String>,
) -> Result<(), TimelineError> {
    for (key, value) in table {
        path.push(key.get_ref().to_string());
        walk(timeline, value, path)?;
        path.pop();
    }
    Ok(())
}

fn walk(
    timeline: &Timeline,
    value: &toml::Spanned<DeValue<'_>>,
    path: &mut Vec<String>,
) -> Result<(), TimelineError> {
    match value.get_ref() {
        DeValue::Table(table) => walk_table(timeline, table, path),
        DeValue::Array(items) => {
            for item in items.iter() {
                walk(timeline, item, path)?;
            }
            Ok(())
        }
        other => {
            let (Some(v), Some(rule)) = (number(other), rule_of(path)) else {
                return Ok(());
            };
            let key = path.join(".");
            if !(rule.min..=rule.max).contains(&v) {
                let unit = if rule.unit.is_empty() {
                    String::new()
                } else {
                    format!(" {}", rule.unit)
                };
                return Err(timeline.error_at(
                    value.span(),
                    format!(
                        "{key} = {}: outside its range, {} to {}{unit}",
                        shown(v),
                        shown(rule.min),
                        shown(rule.max)
                    ),
                ));
            }
            if key.ends_with("motion.t") && v != 0.0 && v.abs() < TIME_RESOLUTION {
                return Err(timeline.error_at(
                    value.span(),
                    format!(
                        "{key} = {}: a key time other than 0 is at least {} s",
                        shown(v),
                        shown(TIME_RESOLUTION)
                    ),
                ));
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rule_names_a_key_of_the_schema_once() {
        for (i, r) in RULES.iter().enumerate() {
            assert!(r.min <= r.max, "{}", r.path);
            assert!(
                !RULES[..i].iter().any(|o| o.path == r.path),
                "{} twice",
                r.path
            );
        }
    }

    /// A number as the table writes it: `1e-4`, `1/30`, `2^64-1`.
    fn table_number(text: &str) -> f64 {
        if text == "2^64-1" {
            return u64::MAX as f64;
        }
        if let Some((a, b)) = text.split_once('/') {
            return table_number(a) / table_number(b);
        }
        text.parse()
            .unwrap_or_else(|_| panic!("not a number in the table: {text}"))
    }

    /// The table a TD reads (`docs/tuning.md`, "Every number's range") is
    /// the one `validate` applies: the same keys, bounds and units.
    #[test]
    fn the_documented_table_is_the_checked_one() {
        let doc = include_str!("../../docs/tuning.md");
        let section = doc
            .split("## Every number's range")
            .nth(1)
            .expect("docs/tuning.md has the section");
        let rows: Vec<[String; 4]> = section
            .lines()
            .skip_while(|l| !l.starts_with("| key"))
            .skip(2)
            .take_while(|l| l.starts_with('|'))
            .map(|l| {
                let cells: Vec<String> = l
                    .trim_matches('|')
                    .split('|')
                    .map(|c| c.trim().trim_matches('`').to_string())
                    .collect();
                assert_eq!(cells.len(), 4, "row {l}");
                [
                    cells[0].clone(),
                    cells[1].clone(),
                    cells[2].clone(),
                    cells[3].clone(),
                ]
            })
            .collect();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        let mut wrong = Vec::new();
        for r in RULES {
            let Some(row) = rows.iter().find(|row| row[0] == r.path) else {
                wrong.push(format!("{} has no row", r.path));
                continue;
            };
            let unit = if r.unit.is_empty() { "-" } else { r.unit };
            if row[3] != unit {
                wrong.push(format!(
                    "{}: unit {} in the table, {unit} checked",
                    r.path, row[3]
                ));
            }
            if !close(table_number(&row[1]), r.min) || !close(table_number(&row[2]), r.max) {
                wrong.push(format!(
                    "{}: {} to {} in the table, {} to {} checked",
                    r.path, row[1], row[2], r.min, r.max
                ));
            }
        }
        for row in &rows {
            if !RULES.iter().any(|r| r.path == row[0]) {
                wrong.push(format!("{} is in the table, not checked", row[0]));
            }
        }
        assert!(wrong.is_empty(), "docs/tuning.md:\n{}", wrong.join("\n"));
    }
}
