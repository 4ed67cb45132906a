//! `widths` and primvars as groom attributes: every interpolation usd-core
//! reads (constant, uniform, vertex, varying), with cubic `varying` values
//! (one per segment end) placed at their points (`docs/formats.md`).

use super::{CurveSet, UsdAttribute, Value};
use crate::ImportError;
use groom::{Attribute, AttributeValues, CurveBasis, Scope};
use std::path::Path;

/// Converts a primvar (or `widths`) to a groom attribute; `Ok(Err(note))`
/// for primvars a groom cannot hold, which are skipped with a note.
pub(super) fn primvar(
    file: &Path,
    attribute: &UsdAttribute,
    name: &str,
    indices: Option<&[f64]>,
    set: &CurveSet,
) -> Result<Result<Attribute, String>, ImportError> {
    let skip = |why: &str| Ok(Err(format!("skipped {}: {why}", attribute.name)));
    let Some(value) = attribute.static_value() else {
        // Declared without a value: nothing to keep.
        return Ok(Err(String::new()));
    };
    if let Some(size) = attribute.element_size.filter(|&s| s != 1.0) {
        return skip(&format!("elementSize {size}"));
    }
    let base_type = attribute.type_name.trim_end_matches("[]");
    let (components, data) = match value {
        Value::Numbers {
            components,
            array: true,
            data,
        } => (*components, data),
        _ => return skip("not a numeric array"),
    };
    if components == 0 || components > 3 {
        return skip("more than 3 components");
    }
    let mut data: Vec<f64> = data.clone();
    if let Some(indices) = indices {
        let element_count = data.len() / components;
        let mut expanded = Vec::with_capacity(indices.len().saturating_mul(components));
        for &index in indices {
            if !(index >= 0.0 && (index as usize) < element_count) {
                return Err(ImportError::malformed(
                    file,
                    attribute.place.clone(),
                    format!("index {index} is out of range of {element_count} values"),
                ));
            }
            let start = index as usize * components;
            expanded.extend_from_slice(data.get(start..start + components).unwrap_or(&[]));
        }
        data = expanded;
    }
    let elements = data.len() / components;
    let vertices = set.points.len();
    let strands = set.counts.len();
    let interpolation = attribute.interpolation.as_deref().unwrap_or(
        // Fallbacks: widths are per vertex, primvars constant.
        if attribute.name == "widths" {
            "vertex"
        } else {
            "constant"
        },
    );
    // One value on a vertex, varying or uniform primvar is read as constant,
    // as usd-core's renderers do (Blender writes widths so).
    let interpolation = if elements == 1 && (vertices != 1 || strands != 1) {
        "constant"
    } else {
        interpolation
    };
    let cubic = set.basis != CurveBasis::Linear;
    let (scope, expected) = match interpolation {
        "vertex" => (Scope::Vertex, vertices),
        "varying" if cubic => (Scope::Vertex, varying_count(set)),
        "varying" if set.wrap == "periodic" => {
            return skip("varying interpolation of periodic linear curves")
        }
        "varying" => (Scope::Vertex, vertices),
        "uniform" => (Scope::Strand, strands),
        "constant" => (Scope::Strand, 1),
        other => return skip(&format!("{other} interpolation")),
    };
    if elements != expected {
        return Err(ImportError::malformed(
            file,
            attribute.place.clone(),
            format!(
                "{} has {elements} values but {interpolation} interpolation needs {expected}",
                attribute.name
            ),
        ));
    }
    if interpolation == "constant" {
        let one = data.clone();
        data = (0..strands).flat_map(|_| one.iter().copied()).collect();
    }
    if interpolation == "varying" && cubic {
        data = varying_to_vertex(&data, components, set);
    }
    let integral = matches!(
        base_type,
        "int" | "uint" | "int64" | "uint64" | "bool" | "uchar"
    );
    let values = match components {
        1 if integral => {
            let mut ints = Vec::with_capacity(data.len());
            for &x in &data {
                if x < f64::from(i32::MIN) || x > f64::from(i32::MAX) {
                    return skip("integers beyond 32 bits");
                }
                ints.push(x as i32);
            }
            AttributeValues::Int(ints)
        }
        1 => AttributeValues::Float(data.iter().map(|&x| x as f32).collect()),
        2 => AttributeValues::Vec2(
            data.chunks_exact(2)
                .map(|c| [c[0] as f32, c[1] as f32])
                .collect(),
        ),
        _ => AttributeValues::Vec3(
            data.chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect(),
        ),
    };
    Ok(Ok(Attribute {
        name: name.to_string(),
        scope,
        values,
    }))
}

/// Vertices from one cubic segment to the next: 3 for bezier, 1 for the
/// others.
fn vstep(basis: CurveBasis) -> usize {
    match basis {
        CurveBasis::Bezier => 3,
        CurveBasis::Hermite => 2,
        CurveBasis::Power => 4,
        _ => 1,
    }
}

/// Values of one cubic curve of `n` vertices under `varying` interpolation
/// (one per segment end), as usd-core counts them: periodic curves
/// `n / vstep`; nonperiodic and pinned ones (pinned curves author no data
/// for their extra segments) `max((n - 4) / vstep, 0) + 2`.
fn varying_of_curve(n: usize, basis: CurveBasis, wrap: &str) -> usize {
    let step = vstep(basis);
    if wrap == "periodic" {
        n / step
    } else {
        n.saturating_sub(4) / step + 2
    }
}

fn varying_count(set: &CurveSet) -> usize {
    set.counts
        .iter()
        .map(|&n| varying_of_curve(n as usize, set.basis, &set.wrap))
        .sum()
}

/// Cubic `varying` values (per segment end) as per-vertex values. Segment
/// end `j` of a curve is at vertex `j * vstep` (bezier, and every periodic
/// curve) or `j + 1` (nonperiodic and pinned bspline and catmullRom, whose
/// first and last vertices only steer the ends): each varying value is kept
/// exactly at its vertex; vertices between ends take the linear blend of
/// the two ends, as renderers interpolate varying data, and the vertices
/// before the first end and after the last take the nearest end's value.
fn varying_to_vertex(data: &[f64], components: usize, set: &CurveSet) -> Vec<f64> {
    let step = vstep(set.basis);
    let periodic = set.wrap == "periodic";
    let offset = if step == 1 && !periodic { 1.0 } else { 0.0 };
    let mut out = Vec::with_capacity(set.points.len() * components);
    let mut start = 0;
    for &n in &set.counts {
        let m = varying_of_curve(n as usize, set.basis, &set.wrap);
        let values = data
            .get(start * components..(start + m) * components)
            .unwrap_or(&[]);
        start += m;
        for k in 0..n as usize {
            let s = (k as f64 - offset) / step as f64;
            let s = if periodic {
                s
            } else {
                s.clamp(0.0, m.saturating_sub(1) as f64)
            };
            let (j, t) = (s.floor() as usize, s.fract());
            let next = if periodic && m > 0 {
                (j + 1) % m
            } else {
                (j + 1).min(m.saturating_sub(1))
            };
            let j = if m > 0 { j % m } else { 0 };
            for c in 0..components {
                let a = values.get(j * components + c).copied().unwrap_or(0.0);
                let b = values.get(next * components + c).copied().unwrap_or(a);
                out.push(if t == 0.0 { a } else { a + (b - a) * t });
            }
        }
    }
    out
}
