//! A guide cache in USD (`.usdc`/`.usd`): under the `Groom` Xform, the
//! `guides` BasisCurves prim with `points` and `extent` time-sampled per
//! frame (its default is the first frame's pose), and the `render`
//! BasisCurves prim at rest only (no time samples), with per-curve
//! (`uniform`) primvars `groom_closest_guides` (int3: guide `groom_id`s,
//! which are the guides' indices in `guides`) and `groom_guide_weights`
//! (float3, sum 1). A reader deforms the render hair by its guides; the
//! file costs what the guides cost. `docs/formats.md` gives the layout.

use super::{crate_writer::AnimatedCrate, CurvesScene};
use crate::{AnimationOptions, ExportError, FrameWriter};
use groom::Groom;
use std::path::Path;

/// Starts a guide cache of `groom`, which holds guides and render hair
/// (per-strand `groom_guide`; the guides first, as `groom::guides::join`
/// makes it). Each frame gives the guides' points only.
pub fn guide_cache(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    if !(options.fps.is_finite() && options.fps > 0.0) {
        return Err(invalid(format!(
            "frames per second must be positive, not {}",
            options.fps
        )));
    }
    let flags = groom
        .guide_flags()
        .filter(|_| groom.has_render_split())
        .ok_or_else(|| {
            invalid("a guide cache needs guides and render hair (per-strand groom_guide)".into())
        })?;
    let guides = flags.iter().take_while(|&&g| g).count();
    if flags[guides..].iter().any(|&g| g) {
        return Err(invalid(
            "a guide cache needs the guides before the render strands".into(),
        ));
    }
    // Flat prims (never the source's): `guides` then `render`.
    let mut scene = CurvesScene::new_with(path, groom, Some(options.fps), false)?;
    for prim in &mut scene.prims {
        prim.rest_only = prim.strand_ranges.iter().all(|r| r.start >= guides);
    }
    scene.vertex_count = groom.strand_offsets()[guides];
    Ok(Box::new(AnimatedCrate::create(path, scene)?))
}
