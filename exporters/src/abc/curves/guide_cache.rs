//! A guide cache in Alembic: the layout of Unreal Engine's *Guides* groom
//! cache. One groom Alembic holding two curves objects under `/groom`:
//! `guides` (`groom_guide` = 1), whose `P` has a sample per frame, and
//! `render` (`groom_guide` = 0), the render hair at rest, one sample, with
//! `groom_closest_guides` (`int32[3]`, guide `groom_id`s) and
//! `groom_guide_weights` (`float[3]`, sum 1) per curve. A reader interpolates
//! the render hair from the animated guides (Unreal: the groom asset with
//! imported guides, then a groom cache of import type *Guides*), so the
//! file costs what the guides cost.

use super::{close_curves, fixed_samples, CurvesExport};
use crate::abc::archive::{
    metadata, ArchiveWriter, ClosedObject, Pod, PropertyKind, PropertyWriter,
};
use crate::{AnimationOptions, AttributeSet, ExportError, FrameWriter};
use groom::{AtomicFile, Groom, UpAxis};
use std::path::Path;

/// The curves objects of a guide cache, under `/groom`.
const GUIDES_OBJECT: &str = "guides";
const RENDER_OBJECT: &str = "render";

/// Starts a guide cache of `groom`, which holds guides and render hair
/// (per-strand `groom_guide`). Each frame gives the guides' points only
/// (the groom's guide strands, in order).
pub fn guide_cache(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
    attributes: AttributeSet,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    let split = groom
        .split_guides()
        .filter(|_| groom.has_render_split())
        .ok_or_else(|| ExportError::Invalid {
            file: path.to_path_buf(),
            message: "a guide cache needs guides and render hair (per-strand groom_guide)".into(),
        })?;
    if !(options.fps.is_finite() && options.fps > 0.0) {
        return Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: format!("frame rate {} is not a positive number", options.fps),
        });
    }
    let mut export = CurvesExport::start(path, &split.guides, Some(options.fps), attributes)?;
    export.object_name = GUIDES_OBJECT;
    export.rest = Some((RENDER_OBJECT, split.render, attributes));
    Ok(Box::new(export))
}

/// A curves object with one sample of every property (sampling 0): the
/// render hair of a guide cache.
pub(super) fn static_curves(
    archive: &mut ArchiveWriter<AtomicFile>,
    name: &str,
    groom: &Groom,
    attributes: AttributeSet,
) -> std::io::Result<ClosedObject> {
    let mut y_up = groom.clone();
    y_up.frames.clear();
    y_up.convert_to(groom.units, UpAxis::Y);
    let mut fixed = Vec::new();
    for sample in fixed_samples(&y_up) {
        let mut property = PropertyWriter::new(
            sample.name,
            sample.metadata,
            sample.kind,
            sample.pod,
            sample.extent,
            0,
        );
        property.set_sample(archive, &sample.bytes)?;
        fixed.push(property);
    }
    let (mut arbitrary, sources) = CurvesExport::arbitrary_properties(&y_up, 0, attributes);
    for (property, source) in arbitrary.iter_mut().zip(sources) {
        if let Some(bytes) = source.first {
            property.set_sample(archive, &bytes)?;
        }
    }
    let mut positions = PropertyWriter::new(
        "P",
        metadata(&[("geoScope", "vtx"), ("interpretation", "point")]),
        PropertyKind::Array,
        Pod::F32,
        3,
        0,
    );
    positions.set_sample(
        archive,
        &super::f32_bytes(y_up.points.iter().flatten().copied()),
    )?;
    let mut bounds = PropertyWriter::new(
        ".selfBnds",
        metadata(&[("interpretation", "box")]),
        PropertyKind::Scalar,
        Pod::F64,
        6,
        0,
    );
    bounds.set_sample(archive, &super::bounds_bytes(&y_up.points))?;
    close_curves(archive, name, bounds, positions, fixed, arbitrary)
}
