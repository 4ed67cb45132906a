//! `[[export]] cache`: what an animated export stores per frame.
//!
//! - `"full"` (the default): every strand's points each frame, render hair
//!   interpolated from the simulated guides.
//! - `"guides"`: a *guide cache*, the simulated guides' points each frame
//!   and the render hair once, at rest, with the three guides each render
//!   strand follows and their weights (`groom_closest_guides`,
//!   `groom_guide_weights`): the layout of Unreal Engine's *Guides* groom
//!   cache in Alembic, `guides` and `render` prims in USD (see
//!   `docs/formats.md`). A reader interpolates the render hair, so the file
//!   costs what its guides cost.
//!
//! A guide cache needs render hair (`[groom] render`, `[groom] guides`, or
//! a source that holds guides and render strands), an animated export to
//! `.abc`, `.usdc` or `.usd`, and the strands as simulated (no `resample`
//! or `curves`, which would re-shape the guides and break the weights).

use super::error::BakeError;
use super::schema::{ExportSpec, ExportWhat};
use super::{Timeline, TimelineError};

/// The values of `cache`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CacheMode {
    Full,
    Guides,
}

/// The cache mode of an export (checked by [`check_export`]).
pub fn cache_of(e: &ExportSpec) -> CacheMode {
    match e.cache.as_ref().map(|c| c.get_ref().as_str()) {
        Some("guides") => CacheMode::Guides,
        _ => CacheMode::Full,
    }
}

/// Checks an export's `cache` (before any work).
pub fn check_export(timeline: &Timeline, e: &ExportSpec) -> Result<(), TimelineError> {
    let Some(cache) = &e.cache else {
        return Ok(());
    };
    let fail = |message: String| Err(timeline.error_at(cache.span(), message));
    match cache.get_ref().as_str() {
        "full" => return Ok(()),
        "guides" => {}
        _ => return fail("cache must be \"full\" or \"guides\"".into()),
    }
    if e.what != ExportWhat::Animated {
        return fail("cache = \"guides\" is for animated exports (what = \"animated\")".into());
    }
    let extension = importers::extension_of(std::path::Path::new(e.path.get_ref()));
    if !exporters::GUIDE_CACHE_EXTENSIONS.contains(&extension.as_str()) {
        return fail(format!(
            "a guide cache is written to .abc, .usdc or .usd, not '.{extension}'"
        ));
    }
    if e.resample.is_some() || e.curves.is_some() {
        return fail("a guide cache keeps the simulated guides: no resample or curves".into());
    }
    Ok(())
}

/// Refuses a guide cache of a bake without render hair (known once the
/// groom is loaded and split, before any simulation).
pub fn check_render_hair(timeline: &Timeline, has_render_hair: bool) -> Result<(), BakeError> {
    if has_render_hair {
        return Ok(());
    }
    for e in &timeline.file.exports {
        if let (CacheMode::Guides, Some(cache)) = (cache_of(e), &e.cache) {
            return Err(timeline
                .error_at(
                    cache.span(),
                    "cache = \"guides\" needs render hair: add [groom] render or [groom] guides, \
                     or bake a source that holds guides and render strands",
                )
                .into());
        }
    }
    Ok(())
}
