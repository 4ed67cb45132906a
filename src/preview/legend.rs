//! The legend of a coloured picture (the ramp, the attribute's name and its
//! range) and the font scale of labels.

use super::{font, ramp, raster, Image};

/// Font scale for a picture of this size.
pub(crate) fn text_scale(side: u32) -> u32 {
    (side / 320).clamp(1, 4)
}

pub(crate) fn legend_width(width: u32, height: u32) -> u32 {
    let scale = text_scale(width.min(height));
    // Room for "-0.000e-00".
    (font::text_width("-1.23e-45", scale) + 8 * scale).min(width / 3)
}

/// Formats a legend number with about three significant digits.
pub fn format_number(v: f32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if !(1e-3..1e4).contains(&a) {
        return format!("{v:.2e}");
    }
    let decimals = (2 - a.log10().floor() as i32).clamp(0, 4) as usize;
    format!("{v:.decimals$}")
}

/// A vertical ramp bar at the right with the attribute name and the range.
pub(crate) fn draw_legend(
    image: &mut Image,
    legend_width: u32,
    name: &str,
    range: Option<(f32, f32)>,
) {
    let scale = text_scale(image.width.min(image.height));
    let (width, height) = (i64::from(image.width), i64::from(image.height));
    let left = width - i64::from(legend_width);
    let line = i64::from((font::GLYPH_HEIGHT + 4) * scale);
    let bar_width = i64::from(6 * scale);
    let bar_x = left + i64::from(4 * scale);
    let bar_top = height / 6 + 2 * line;
    let bar_bottom = height - height / 6 - line;
    let white = [235, 235, 235];
    // The name, right-aligned so a long one runs into the picture, not off it.
    let name_width = i64::from(font::text_width(name, scale));
    let name_x = (width - name_width - i64::from(4 * scale)).max(0);
    font::draw_text(image, name_x, height / 6, scale, white, name);
    let Some((lo, hi)) = range else {
        font::draw_text(image, bar_x, bar_top, scale, white, "no data");
        return;
    };
    let span = (bar_bottom - bar_top).max(1);
    for row in bar_top..bar_bottom {
        let x = 1.0 - (row - bar_top) as f32 / span as f32;
        let rgb = ramp(x).map(raster::encode_srgb);
        image.fill_rect(bar_x, row, bar_width, 1, rgb);
    }
    font::draw_text(
        image,
        bar_x,
        bar_top - line,
        scale,
        white,
        &format_number(hi),
    );
    font::draw_text(
        image,
        bar_x,
        bar_bottom + i64::from(4 * scale),
        scale,
        white,
        &format_number(lo),
    );
}
