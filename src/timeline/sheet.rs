//! The contact sheet of a bake: its snapshots (before the first stage and
//! after each) drawn with the colliders active in each and a perm's rods,
//! in the view and colours of the timeline's `[preview]`.

use super::error::BakeError;
use super::Timeline;
use groom::Groom;
use std::path::Path;

/// The preview options of the timeline's `[preview]` (or the defaults). The
/// view, unless the timeline names one, is three quarters in front for a
/// timeline with a head, else the one that shows most of the change from the
/// first to the last snapshot.
pub fn sheet_options(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
) -> crate::preview::PreviewOptions {
    let mut options = crate::preview::PreviewOptions::default();
    let named_view = timeline
        .file
        .preview
        .as_ref()
        .and_then(|p| p.view.get_ref().parse().ok());
    options.view = match (named_view, snapshots.first(), snapshots.last()) {
        (Some(view), _, _) => view,
        // A head is seen as a TD first looks at a groom: from three quarters.
        _ if super::surfaces::draws_a_head(timeline) => crate::preview::View::Persp,
        (None, Some((_, first)), Some((_, last))) => {
            crate::preview::view_showing_change(first, last)
        }
        _ => options.view,
    };
    if let Some(p) = &timeline.file.preview {
        let [w, h] = *p.size.get_ref();
        options.width = w;
        options.height = h;
        options.color_by = p.color.as_ref().map(|c| c.get_ref().clone());
    }
    options
}

/// The curve form of the sheet's pictures: `[preview] resample`, if given.
pub(super) fn sheet_curve_form(timeline: &Timeline) -> groom::curves::CurveForm {
    match timeline.file.preview.as_ref().and_then(|p| p.resample) {
        Some(segment) => groom::curves::CurveForm::Resampled { segment },
        None => groom::curves::CurveForm::Polyline,
    }
}

/// Renders the before/after sheet of a bake and writes it as a PNG.
pub(super) fn write_sheet(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
    rods: &[super::surfaces::RodSnapshot],
    path: &Path,
) -> Result<(), BakeError> {
    crate::preview::write_png(&sheet_image(timeline, snapshots, rods)?, path)?;
    Ok(())
}

/// The before/after contact sheet of a bake's snapshots, with the colliders
/// active in each and a perm's rods (the sheet export and the HTML report
/// draw the same).
pub fn sheet_image(
    timeline: &Timeline,
    snapshots: &[(String, Groom)],
    rods: &[super::surfaces::RodSnapshot],
) -> Result<crate::preview::Image, BakeError> {
    let options = sheet_options(timeline, snapshots);
    let surfaces = super::surfaces::snapshot_surfaces(timeline, rods)?;
    let entries: Vec<crate::preview::SheetEntry> = snapshots
        .iter()
        .zip(&surfaces)
        .map(|((label, groom), surfaces)| crate::preview::SheetEntry {
            label,
            groom,
            frame: None,
            surfaces,
        })
        .collect();
    Ok(crate::preview::render_sheet(&entries, &options)?)
}
