//! A contact sheet of a given total size (`preview --size` is the size of
//! the whole picture): the largest cells whose sheet, labels and gutters
//! included, fits, with the rest of the picture left as background.

use super::{render_sheet, sheet_size, Image, PreviewError, PreviewOptions, SheetEntry, GUTTER};

/// The sheet's background (as [`super::contact_sheet`] fills it).
const BACKGROUND: [u8; 3] = [28, 28, 30];

/// The largest cell size whose sheet of `count` pictures fits in `width` x
/// `height`; `None` when not even one pixel does.
pub fn cell_size_within(count: usize, width: u32, height: u32) -> Option<(u32, u32)> {
    let n = u32::try_from(count.max(1)).ok()?;
    let columns = n.min(4);
    let rows = n.div_ceil(columns);
    let cell_width = width.checked_sub((columns + 1) * GUTTER)? / columns;
    let mut cell_height = height.checked_sub((rows + 1) * GUTTER)? / rows;
    // The label's height grows with the cell: shrink the cell until the
    // whole sheet fits (a few dozen pixels at most).
    while cell_width > 0 && cell_height > 0 {
        let (w, h) = sheet_size(count, cell_width, cell_height);
        if w <= width && h <= height {
            return Some((cell_width, cell_height));
        }
        cell_height -= 1;
    }
    None
}

/// [`render_sheet`] into a picture of exactly `options.width` x
/// `options.height`.
pub fn render_sheet_within(
    entries: &[SheetEntry],
    options: &PreviewOptions,
) -> Result<Image, PreviewError> {
    let (width, height) = (options.width, options.height);
    let (cell_width, cell_height) =
        cell_size_within(entries.len(), width, height).ok_or(PreviewError::SheetTooSmall {
            count: entries.len(),
            width,
            height,
        })?;
    let cells = PreviewOptions {
        width: cell_width,
        height: cell_height,
        ..options.clone()
    };
    let sheet = render_sheet(entries, &cells)?;
    let mut picture = Image::new(width, height, BACKGROUND);
    picture.blit(&sheet, 0, 0);
    Ok(picture)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_fill_the_picture_without_passing_it() {
        for (count, width, height) in [(3, 900, 300), (1, 40, 40), (6, 1024, 1024), (4, 2000, 300)]
        {
            let (cw, ch) = cell_size_within(count, width, height).unwrap();
            let (w, h) = sheet_size(count, cw, ch);
            assert!(w <= width && h <= height, "{count} in {width}x{height}");
            // One pixel more in each direction no longer fits (or is cut by
            // the division among columns).
            assert!(width - w < 4 + 1 && sheet_size(count, cw, ch + 1).1 > height);
        }
        assert_eq!(cell_size_within(4, 10, 10), None);
    }
}
