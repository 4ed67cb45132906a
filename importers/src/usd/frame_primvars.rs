//! Primvars with time samples (a bake's bond rates and wetness) as each
//! frame's [`groom::Frame::attributes`]: the groom at every frame's time
//! code, read as the stage holds it then, gives those primvars' values.

use super::{stage_at, to_groom, Stage, Value};
use crate::ImportError;
use groom::Groom;
use std::path::Path;

/// The groom attribute a curves property becomes (`widths` -> `width`,
/// `primvars:st` -> `root_uv`, `primvars:x` -> `x`), as `curve_set` names
/// them; `None` for other properties and index arrays.
fn attribute_name(property: &str) -> Option<String> {
    if property == "widths" {
        return Some("width".into());
    }
    let name = property.strip_prefix("primvars:")?;
    if name.ends_with(":indices") {
        return None;
    }
    Some(if name == "st" {
        "root_uv".into()
    } else {
        name.into()
    })
}

/// Fills the frames' attributes from the time-sampled primvars of the
/// stage's curves; nothing when the groom has no frames or no primvar has
/// samples.
pub(super) fn add_frame_attributes(
    file: &Path,
    stage: &Stage,
    groom: &mut Groom,
) -> Result<(), ImportError> {
    if groom.frames.is_empty() {
        return Ok(());
    }
    let mut names: Vec<String> = Vec::new();
    let mut codes: Vec<f64> = Vec::new();
    for prim in stage.prims.iter().filter(|p| p.type_name == "BasisCurves") {
        for attribute in &prim.attributes {
            let sampled: Vec<f64> = attribute
                .samples
                .iter()
                .filter(|(_, v)| !matches!(v, Value::Blocked))
                .map(|(c, _)| *c)
                .collect();
            let Some(name) = attribute_name(&attribute.name).filter(|_| !sampled.is_empty()) else {
                continue;
            };
            if !names.contains(&name) {
                names.push(name);
            }
            codes.extend(sampled);
        }
    }
    names.retain(|name| groom.attribute(name).is_some());
    if names.is_empty() {
        return Ok(());
    }
    let codes_per_second = stage
        .time_codes_per_second
        .or(stage.frames_per_second)
        .unwrap_or(24.0);
    for index in 0..groom.frames.len() {
        // The sample's own code where the frame's time is one (times are
        // codes over codes per second, so they round-trip to within 1e-9).
        let wanted = groom.frames[index].time * codes_per_second;
        let code = codes
            .iter()
            .copied()
            .find(|c| (c - wanted).abs() <= 1e-9 * c.abs().max(1.0))
            .unwrap_or(wanted);
        let at = to_groom(file, &stage_at(stage, code))?;
        groom.frames[index].attributes = names
            .iter()
            .filter_map(|name| at.attribute(name).cloned())
            .collect();
    }
    Ok(())
}
