//! The attributes that change over an animation ([`Frame::attributes`]) as
//! time samples of their properties: both writers give each such primvar
//! a sample per frame beside its default (the groom's value), and leave
//! every other property a default only.

use super::{CurvesPrim, PropertyValue};
use crate::ExportError;
use groom::{AttributeValues, Frame, Scope};
use std::ops::Range;
use std::path::Path;

/// The names of a frame's time-varying attributes, which every frame of
/// an export must share (the first frame sets them).
pub(super) fn check_names(
    path: &Path,
    names: &mut Option<Vec<String>>,
    frame: &Frame,
) -> Result<(), ExportError> {
    let these: Vec<String> = frame.attributes.iter().map(|a| a.name.clone()).collect();
    match names {
        None => {
            *names = Some(these);
            Ok(())
        }
        Some(first) if *first == these => Ok(()),
        Some(first) => Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: format!(
                "frame at {} s animates attributes [{}], the first frame [{}]",
                frame.time,
                these.join(", "),
                first.join(", ")
            ),
        }),
    }
}

/// This prim's part of each of the frame's time-varying attributes:
/// `(property name, value)`, in the frame's order.
pub(super) fn prim_values(
    path: &Path,
    prim: &CurvesPrim,
    frame: &Frame,
) -> Result<Vec<(String, PropertyValue)>, ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    let mut out = Vec::with_capacity(frame.attributes.len());
    for attribute in &frame.attributes {
        if prim.omitted.contains(&attribute.name) {
            continue;
        }
        let Some((_, property)) = prim
            .attribute_properties
            .iter()
            .find(|(name, _)| *name == attribute.name)
        else {
            return Err(invalid(format!(
                "frame at {} s has attribute '{}', which the groom does not",
                frame.time, attribute.name
            )));
        };
        let declared = prim.properties.iter().find(|p| p.name == *property);
        let interpolation = match attribute.scope {
            Scope::Vertex => "vertex",
            Scope::Strand => "uniform",
        };
        let ranges = match attribute.scope {
            Scope::Vertex => &prim.vertex_ranges,
            Scope::Strand => &prim.strand_ranges,
        };
        let value = select(&attribute.values, ranges).ok_or_else(|| {
            invalid(format!(
                "frame at {} s: attribute '{}' has too few values",
                frame.time, attribute.name
            ))
        })?;
        let same_kind = declared.is_some_and(|p| {
            p.interpolation == Some(interpolation)
                && std::mem::discriminant(&p.value) == std::mem::discriminant(&value)
        });
        if !same_kind {
            return Err(invalid(format!(
                "frame at {} s: attribute '{}' is not of the groom's type and scope",
                frame.time, attribute.name
            )));
        }
        out.push((property.clone(), value));
    }
    Ok(out)
}

/// The values at `ranges`, in the element type USD stores; `None` when a
/// range runs past the values.
fn select(values: &AttributeValues, ranges: &[Range<usize>]) -> Option<PropertyValue> {
    fn pick<T: Copy>(v: &[T], ranges: &[Range<usize>]) -> Option<Vec<T>> {
        let mut out = Vec::new();
        for range in ranges {
            out.extend_from_slice(v.get(range.clone())?);
        }
        Some(out)
    }
    Some(match values {
        AttributeValues::Float(v) => PropertyValue::Floats(pick(v, ranges)?),
        AttributeValues::Vec2(v) => PropertyValue::Float2s(pick(v, ranges)?),
        AttributeValues::Vec3(v) => PropertyValue::Float3s(pick(v, ranges)?),
        AttributeValues::Int(v) => PropertyValue::Ints(pick(v, ranges)?),
    })
}
