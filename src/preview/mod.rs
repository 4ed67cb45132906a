//! Preview pictures of grooms: a software renderer that draws strands as
//! anti-aliased, depth-ordered lines with their width and Kajiya-Kay
//! shading, framed automatically, over a solid, lit head that hides the hair
//! behind it (`head.rs`) and semi-transparent colliders (`surfaces.rs`); optional colouring of a scalar attribute
//! through a blue-to-red ramp with a legend; contact sheets of several
//! pictures with labels; deterministic PNG files.

mod camera;
mod fit;
mod font;
mod head;
mod legend;
mod raster;
mod shading;
mod shadow;
mod surfaces;

pub use camera::Camera;
pub use surfaces::Surface;

use camera::{dot, normalize, sub, Vec3};
use groom::{AttributeValues, Groom, Scope};
pub use legend::format_number;
use legend::{draw_legend, legend_width, text_scale};
use raster::{Raster, ScreenVertex};
use rayon::prelude::*;
use shading::Lights;
use std::path::{Path, PathBuf};

/// Largest picture side the renderer accepts, pixels.
pub const MAX_SIZE: u32 = 16384;

/// Largest contact sheet, pixels, so a long list of frames cannot ask for
/// an unbounded allocation.
pub const MAX_SHEET_PIXELS: u64 = 1 << 28;

/// Where the camera looks from (Y up).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum View {
    /// From +Z towards -Z.
    #[default]
    Front,
    /// From +X towards -X.
    Side,
    /// From +Y down, the front (+Z) at the bottom of the picture.
    Top,
    /// Perspective from the front right, a little above.
    Persp,
}

impl std::str::FromStr for View {
    type Err = String;

    fn from_str(s: &str) -> Result<View, String> {
        match s {
            "front" => Ok(View::Front),
            "side" => Ok(View::Side),
            "top" => Ok(View::Top),
            "persp" => Ok(View::Persp),
            _ => Err(format!(
                "unknown view '{s}' (expected front, side, top or persp)"
            )),
        }
    }
}

/// The axis view (front, side or top) that shows most of the change from
/// `before` to `after` (same topology): the one looking along the direction
/// the points moved least in. With no change to show, the view of
/// [`view_showing_spread`].
pub fn view_showing_change(before: &Groom, after: &Groom) -> View {
    let moved = |axis: usize| -> f64 {
        before
            .points
            .iter()
            .zip(&after.points)
            .map(|(&a, &b)| {
                let (a, b) = (before.up_axis.to_y_up(a), after.up_axis.to_y_up(b));
                let d = f64::from(b[axis] - a[axis]);
                if d.is_finite() {
                    d * d
                } else {
                    0.0
                }
            })
            .sum()
    };
    let along = [moved(0), moved(1), moved(2)];
    if before.points.len() != after.points.len() || along.iter().sum::<f64>() <= 0.0 {
        return view_showing_spread(after);
    }
    least_axis_view(along)
}

/// The axis view looking along the groom's thinnest extent, so it shows the
/// most of it (a swatch face on, not one strand thick from its edge).
pub fn view_showing_spread(groom: &Groom) -> View {
    let mut low = [f64::INFINITY; 3];
    let mut high = [f64::NEG_INFINITY; 3];
    for &p in &groom.points {
        let p = groom.up_axis.to_y_up(p);
        for k in 0..3 {
            if p[k].is_finite() {
                low[k] = low[k].min(f64::from(p[k]));
                high[k] = high[k].max(f64::from(p[k]));
            }
        }
    }
    let extent = [0, 1, 2].map(|k| (high[k] - low[k]).max(0.0));
    if extent.iter().any(|e| !e.is_finite()) {
        return View::Front;
    }
    least_axis_view(extent)
}

/// The view along the axis (x, y, z; Y up) of the smallest value; ties go to
/// front, then side.
fn least_axis_view(along: [f64; 3]) -> View {
    let [x, y, z] = along;
    if z <= x && z <= y {
        View::Front
    } else if x <= y {
        View::Side
    } else {
        View::Top
    }
}

/// What to draw and how.
#[derive(Debug, Clone, PartialEq)]
pub struct PreviewOptions {
    pub width: u32,
    pub height: u32,
    pub view: View,
    /// Index into [`Groom::frames`] of the pose to draw; `None` draws
    /// [`Groom::points`]. The camera frames every pose either way, so the
    /// pictures of several frames line up.
    pub frame: Option<usize>,
    /// A scalar attribute to colour through the blue-to-red ramp.
    pub color_by: Option<String>,
    /// The `(min, max)` the ramp spans; `None` takes the attribute's range.
    pub color_range: Option<(f32, f32)>,
    /// Hair colour (linear RGB) when no attribute colours the strands.
    pub hair_color: [f32; 3],
}

impl Default for PreviewOptions {
    fn default() -> Self {
        PreviewOptions {
            width: 512,
            height: 512,
            view: View::Front,
            frame: None,
            color_by: None,
            color_range: None,
            // A mid brown.
            hair_color: [0.085, 0.035, 0.013],
        }
    }
}

/// Why a preview could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    #[error("picture size {width}x{height}: each side must be between 1 and {MAX_SIZE} pixels")]
    BadSize { width: u32, height: u32 },
    #[error("no attribute '{name}' to colour by (the groom has: {available})")]
    UnknownAttribute { name: String, available: String },
    #[error("attribute '{name}' cannot colour strands: {reason}")]
    UnusableAttribute { name: String, reason: String },
    #[error("frame {frame}: the groom has {count} frames (0 to {last})", last = count.saturating_sub(1))]
    NoSuchFrame { frame: usize, count: usize },
    #[error("frame {frame} has {found} points, the groom {expected}")]
    FrameMismatch {
        frame: usize,
        found: usize,
        expected: usize,
    },
    #[error("the groom has more than 4,294,967,295 points, too many to preview")]
    TooManyPoints,
    #[error("a picture of {width}x{height} cannot hold a sheet of {count} labelled pictures")]
    SheetTooSmall {
        count: usize,
        width: u32,
        height: u32,
    },
    #[error("a contact sheet of {count} pictures of {width}x{height} would exceed {MAX_SHEET_PIXELS} pixels")]
    SheetTooLarge {
        count: usize,
        width: u32,
        height: u32,
    },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: PNG encoding: {source}", path.display())]
    Png {
        path: PathBuf,
        #[source]
        source: png::EncodingError,
    },
}

impl PreviewError {
    /// True when the caller asked for something impossible (as opposed to a
    /// failure while writing).
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, PreviewError::Io { .. } | PreviewError::Png { .. })
    }
}

/// An RGB picture, 8 bits per channel (sRGB), rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// `width * height * 3` bytes.
    pub pixels: Vec<u8>,
}

impl Image {
    pub fn new(width: u32, height: u32, color: [u8; 3]) -> Image {
        let count = width as usize * height as usize;
        let mut pixels = Vec::with_capacity(count * 3);
        for _ in 0..count {
            pixels.extend_from_slice(&color);
        }
        Image {
            width,
            height,
            pixels,
        }
    }

    /// The pixel at (`x`, `y`), `None` outside.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let at = (y as usize * self.width as usize + x as usize) * 3;
        let rgb = self.pixels.get(at..at + 3)?;
        Some([rgb[0], rgb[1], rgb[2]])
    }

    /// Fills a rectangle, clipped to the picture.
    pub fn fill_rect(&mut self, x: i64, y: i64, width: i64, height: i64, color: [u8; 3]) {
        let x0 = x.max(0);
        let y0 = y.max(0);
        let x1 = (x + width).min(i64::from(self.width));
        let y1 = (y + height).min(i64::from(self.height));
        for row in y0..y1 {
            for column in x0..x1 {
                let at = (row as usize * self.width as usize + column as usize) * 3;
                if let Some(rgb) = self.pixels.get_mut(at..at + 3) {
                    rgb.copy_from_slice(&color);
                }
            }
        }
    }

    /// Copies `other` with its top-left corner at (`x`, `y`), clipped.
    pub fn blit(&mut self, other: &Image, x: i64, y: i64) {
        for row in 0..i64::from(other.height) {
            let target_row = y + row;
            if target_row < 0 || target_row >= i64::from(self.height) {
                continue;
            }
            let x0 = x.max(0);
            let x1 = (x + i64::from(other.width)).min(i64::from(self.width));
            if x0 >= x1 {
                continue;
            }
            let source = (row as usize * other.width as usize + (x0 - x) as usize) * 3;
            let target = (target_row as usize * self.width as usize + x0 as usize) * 3;
            let bytes = (x1 - x0) as usize * 3;
            if let (Some(from), Some(to)) = (
                other.pixels.get(source..source + bytes),
                self.pixels.get_mut(target..target + bytes),
            ) {
                to.copy_from_slice(from);
            }
        }
    }
}

/// One picture of a contact sheet: a label and a pose of a groom.
#[derive(Debug, Clone, Copy)]
pub struct SheetEntry<'a> {
    pub label: &'a str,
    pub groom: &'a Groom,
    /// As [`PreviewOptions::frame`].
    pub frame: Option<usize>,
    /// Surfaces to draw with the hair (Y up, the groom's units): a solid
    /// one (a head) opaque, hiding the hair behind it; the other colliders
    /// semi-transparent.
    pub surfaces: &'a [Surface],
}

/// Draws a groom.
pub fn render(groom: &Groom, options: &PreviewOptions) -> Result<Image, PreviewError> {
    render_with_surfaces(groom, &[], options)
}

/// Draws a groom with surfaces (a head: [`Surface::head`]), as
/// [`SheetEntry::surfaces`].
pub fn render_with_surfaces(
    groom: &Groom,
    surfaces: &[Surface],
    options: &PreviewOptions,
) -> Result<Image, PreviewError> {
    let groom = &*smooth(groom);
    let entry = SheetEntry {
        label: "",
        groom,
        frame: options.frame,
        surfaces,
    };
    let scene = Scene::new(&[entry], options)?;
    scene.draw(&entry)
}

/// Cubic curves (Catmull-Rom, B-spline) drawn as the smooth curves they
/// are: 8 points per span.
fn smooth(groom: &Groom) -> std::borrow::Cow<'_, Groom> {
    groom::curves::tessellate(groom, 8)
}

pub use fit::render_sheet_within;

/// Draws several poses (of one groom or several) with one camera and one
/// colour range, so they compare, and lays them out with their labels.
pub fn render_sheet(
    entries: &[SheetEntry],
    options: &PreviewOptions,
) -> Result<Image, PreviewError> {
    check_sheet_size(entries.len(), options.width, options.height)?;
    let smoothed: Vec<std::borrow::Cow<'_, Groom>> =
        entries.iter().map(|e| smooth(e.groom)).collect();
    let entries: Vec<SheetEntry> = entries
        .iter()
        .zip(&smoothed)
        .map(|(e, groom)| SheetEntry { groom, ..*e })
        .collect();
    let entries = &entries[..];
    let scene = Scene::new(entries, options)?;
    let pictures = entries
        .iter()
        .map(|entry| Ok((entry.label.to_string(), scene.draw(entry)?)))
        .collect::<Result<Vec<_>, PreviewError>>()?;
    Ok(contact_sheet(&pictures))
}

fn check_sheet_size(count: usize, width: u32, height: u32) -> Result<(), PreviewError> {
    let pixels = (count as u64).saturating_mul(u64::from(width) * u64::from(height));
    if pixels > MAX_SHEET_PIXELS {
        return Err(PreviewError::SheetTooLarge {
            count,
            width,
            height,
        });
    }
    Ok(())
}

/// Gap between pictures of a sheet, pixels.
const GUTTER: u32 = 4;

/// How [`contact_sheet`] lays out `count` pictures of `cell_width` x
/// `cell_height`: columns, label height and the sheet's size.
struct SheetLayout {
    columns: u32,
    label_height: u32,
    scale: u32,
    width: u32,
    height: u32,
}

fn sheet_layout(count: usize, cell_width: u32, cell_height: u32) -> SheetLayout {
    let scale = text_scale(cell_width.min(cell_height));
    let label_height = font::GLYPH_HEIGHT * scale + 6 * scale;
    let count = u32::try_from(count.max(1)).unwrap_or(u32::MAX);
    let columns = count.min(4);
    let rows = count.div_ceil(columns);
    SheetLayout {
        columns,
        label_height,
        scale,
        width: columns * cell_width + (columns + 1) * GUTTER,
        height: rows * (cell_height + label_height) + (rows + 1) * GUTTER,
    }
}

/// The size of a contact sheet of `count` pictures of `cell_width` x
/// `cell_height` (labels and gutters included).
pub fn sheet_size(count: usize, cell_width: u32, cell_height: u32) -> (u32, u32) {
    let layout = sheet_layout(count, cell_width, cell_height);
    (layout.width, layout.height)
}

/// Lays pictures out side by side (up to four a row), each under its label.
pub fn contact_sheet(pictures: &[(String, Image)]) -> Image {
    let cell_width = pictures.iter().map(|(_, i)| i.width).max().unwrap_or(1);
    let cell_height = pictures.iter().map(|(_, i)| i.height).max().unwrap_or(1);
    let SheetLayout {
        columns,
        label_height,
        scale,
        width,
        height,
    } = sheet_layout(pictures.len(), cell_width, cell_height);
    let mut sheet = Image::new(width, height, [28, 28, 30]);
    for (index, (label, picture)) in pictures.iter().enumerate() {
        let index = index as u32;
        let x = GUTTER + (index % columns) * (cell_width + GUTTER);
        let y = GUTTER + (index / columns) * (cell_height + label_height + GUTTER);
        font::draw_text(
            &mut sheet,
            i64::from(x + 2 * scale),
            i64::from(y + 3 * scale),
            scale,
            [235, 235, 235],
            label,
        );
        sheet.blit(picture, i64::from(x), i64::from(y + label_height));
    }
    sheet
}

/// A picture as 8-bit RGB PNG bytes. Fixed compression and filter settings
/// and no time chunk make the bytes depend on the pixels only.
pub fn png_bytes(image: &Image) -> Result<Vec<u8>, png::EncodingError> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, image.width, image.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_deflate_compression(png::DeflateCompression::Level(6));
        encoder.set_filter(png::Filter::Paeth);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&image.pixels)?;
        writer.finish()?;
    }
    Ok(bytes)
}

/// Writes a picture as an 8-bit RGB PNG ([`png_bytes`]), atomically.
pub fn write_png(image: &Image, path: &Path) -> Result<(), PreviewError> {
    let io = |source| PreviewError::Io {
        path: path.to_path_buf(),
        source,
    };
    let bytes = png_bytes(image).map_err(|source| PreviewError::Png {
        path: path.to_path_buf(),
        source,
    })?;
    let mut file = groom::AtomicFile::create(path).map_err(io)?;
    std::io::Write::write_all(&mut file, &bytes).map_err(io)?;
    file.commit().map_err(io)
}

/// The finite `(min, max)` of a scalar attribute, checked for use as a
/// colour; `None` when it has no finite value.
pub fn attribute_range(groom: &Groom, name: &str) -> Result<Option<(f32, f32)>, PreviewError> {
    let values = scalar_values(groom, name)?.0;
    Ok(finite_range(values.iter().copied()))
}

/// The range an attribute means, whatever values a groom holds: bond rates
/// and wetness are fractions of 0 to 1. A fixed range gives a value the same
/// colour in every picture (alone or in a contact sheet beside others).
pub fn natural_range(name: &str) -> Option<(f32, f32)> {
    use crate::sim::attribute_names::{BOND_RATES, WETNESS};
    let fraction = BOND_RATES.contains(&name) || name == WETNESS;
    fraction.then_some((0.0, 1.0))
}

/// A constant attribute spans nothing: the ramp from 0 to its value (0 to 1
/// for zero), so it is drawn at one end, with a legend that reads.
fn widen_constant((lo, hi): (f32, f32)) -> (f32, f32) {
    if lo < hi {
        return (lo, hi);
    }
    match lo {
        v if v > 0.0 => (0.0, v),
        v if v < 0.0 => (v, 0.0),
        _ => (0.0, 1.0),
    }
}

fn finite_range(values: impl Iterator<Item = f32>) -> Option<(f32, f32)> {
    values
        .filter(|v| v.is_finite())
        .fold(None, |range, v| match range {
            None => Some((v, v)),
            Some((lo, hi)) => Some((f32::min(lo, v), f32::max(hi, v))),
        })
}

/// The values of a scalar attribute as floats, and whether one is per strand.
fn scalar_values(groom: &Groom, name: &str) -> Result<(Vec<f32>, bool), PreviewError> {
    let Some(attribute) = groom.attribute(name) else {
        let mut names: Vec<&str> = groom.attributes.iter().map(|a| a.name.as_str()).collect();
        names.sort_unstable();
        let available = if names.is_empty() {
            "no attributes".to_string()
        } else {
            names.join(", ")
        };
        return Err(PreviewError::UnknownAttribute {
            name: name.to_string(),
            available,
        });
    };
    let unusable = |reason: String| PreviewError::UnusableAttribute {
        name: name.to_string(),
        reason,
    };
    let values = match &attribute.values {
        AttributeValues::Float(v) => v.clone(),
        AttributeValues::Int(v) => v.iter().map(|&i| i as f32).collect(),
        other => {
            return Err(unusable(format!(
                "it is a {} attribute, only scalar (float or int) attributes map to colours",
                other.type_name()
            )))
        }
    };
    let per_strand = attribute.scope == Scope::Strand;
    let expected = if per_strand {
        groom.strand_count()
    } else {
        groom.vertex_count()
    };
    if values.len() != expected {
        let what = if per_strand { "strands" } else { "vertices" };
        return Err(unusable(format!(
            "it has {} values for {expected} {what}",
            values.len()
        )));
    }
    Ok((values, per_strand))
}

/// What all pictures of a sheet share: the camera, the colour range, the layout.
struct Scene<'o> {
    options: &'o PreviewOptions,
    camera: Option<Camera>,
    range: Option<(f32, f32)>,
    /// Near and far depth of every pose, for depth cueing.
    depth_range: (f32, f32),
    legend_width: u32,
}

impl<'o> Scene<'o> {
    fn new(entries: &[SheetEntry], options: &'o PreviewOptions) -> Result<Scene<'o>, PreviewError> {
        let (width, height) = (options.width, options.height);
        if !(1..=MAX_SIZE).contains(&width) || !(1..=MAX_SIZE).contains(&height) {
            return Err(PreviewError::BadSize { width, height });
        }
        let mut range = options.color_range;
        if let Some(name) = &options.color_by {
            let mut combined: Option<(f32, f32)> = None;
            for entry in entries {
                if let Some((lo, hi)) = attribute_range(entry.groom, name)? {
                    combined = Some(match combined {
                        None => (lo, hi),
                        Some((a, b)) => (a.min(lo), b.max(hi)),
                    });
                }
            }
            range = range
                .or(natural_range(name))
                .or(combined.map(widen_constant));
        }
        for entry in entries {
            pose(entry.groom, entry.frame)?;
        }
        let legend_width = if options.color_by.is_some() {
            legend_width(width, height)
        } else {
            0
        };
        let framed_width = width.saturating_sub(legend_width).max(1);
        // Every pose of every groom, in Y-up coordinates.
        let all_points: Vec<Vec3> = entries
            .iter()
            .flat_map(|e| {
                let up = e.groom.up_axis;
                e.groom
                    .points
                    .iter()
                    .chain(e.groom.frames.iter().flat_map(|f| f.points.iter()))
                    .map(move |&p| up.to_y_up(p))
            })
            .collect();
        // The head is framed too (the face below short hair); a pillow that
        // comes from afar is not.
        let solid_points = entries
            .iter()
            .flat_map(|e| e.surfaces.iter().filter(|s| s.solid))
            .flat_map(|s| s.triangles.iter().flatten());
        let camera = Camera::framing(
            options.view,
            all_points.iter().chain(solid_points),
            [0.0, 0.0],
            framed_width as f32,
            height as f32,
        );
        let mut depth_range = (f32::INFINITY, f32::NEG_INFINITY);
        if let Some(camera) = &camera {
            for p in &all_points {
                let depth = dot(sub(*p, camera.eye), camera.forward);
                if depth.is_finite() {
                    depth_range = (depth_range.0.min(depth), depth_range.1.max(depth));
                }
            }
        }
        Ok(Scene {
            options,
            camera,
            range,
            depth_range,
            legend_width,
        })
    }

    fn draw(&self, entry: &SheetEntry) -> Result<Image, PreviewError> {
        let options = self.options;
        let (width, height) = (options.width as usize, options.height as usize);
        let points = pose(entry.groom, entry.frame)?;
        if points.len() > u32::MAX as usize {
            return Err(PreviewError::TooManyPoints);
        }
        let (solids, others): (Vec<&Surface>, Vec<&Surface>) =
            entry.surfaces.iter().partition(|s| s.solid);
        let head = self
            .camera
            .as_ref()
            .and_then(|camera| head::rasterize(&solids, camera, width, height));
        let head_depth = |pixel: usize| {
            head.as_ref()
                .and_then(|h| h.depth.get(pixel).copied())
                .unwrap_or(f32::INFINITY)
        };
        let mut backdrop = match (&self.camera, others.is_empty()) {
            (Some(camera), false) => surfaces::rasterize(&others, camera, width, height),
            _ => Vec::new(),
        };
        // A surface behind the head does not show.
        for (pixel, surface) in backdrop.iter_mut().enumerate() {
            if surface.is_some_and(|(_, depth)| depth > head_depth(pixel)) {
                *surface = None;
            }
        }
        let background = |row: usize, column: usize| {
            // A neutral grey, a little lighter at the top.
            let f = row as f32 / height.max(1) as f32;
            let v = 0.16 - 0.09 * f;
            let pixel = row * width + column;
            let plain = match &head {
                Some(head) => head.over(pixel, [v, v, v * 1.04]),
                None => [v, v, v * 1.04],
            };
            match backdrop.get(pixel) {
                Some(Some((surface, _))) => surfaces::mix(plain, *surface, surfaces::BEHIND_HAIR),
                _ => plain,
            }
        };
        let hides_beyond = head.as_ref().map_or(&[][..], |h| &h.hides_beyond[..]);
        let colors = match &options.color_by {
            Some(name) => Some(scalar_values(entry.groom, name)?),
            None => None,
        };
        let pixels = match &self.camera {
            Some(camera) => {
                let mut vertices = self.shade(entry.groom, points, camera, colors.as_ref());
                set_joints(entry.groom, &mut vertices);
                let strands = strand_ranges(entry.groom, vertices.len());
                let min_opacity = min_opacity(&vertices, &strands, width, height);
                Raster {
                    vertices: &vertices,
                    strands,
                    width,
                    height,
                    min_opacity,
                    hides_beyond,
                }
                .render(background)
            }
            None => Raster {
                vertices: &[],
                strands: Vec::new(),
                width,
                height,
                min_opacity: 1.0,
                hides_beyond,
            }
            .render(background),
        };
        let mut pixels = pixels;
        // The surfaces again, faintly over the hair: hair in front of a
        // surface shows, and so does the surface behind hair.
        for (rgb, surface) in pixels.chunks_exact_mut(3).zip(&backdrop) {
            if let Some((surface, _)) = surface {
                let over = surface.map(raster::encode_srgb);
                for (byte, s) in rgb.iter_mut().zip(over) {
                    let mixed =
                        f32::from(*byte) + (f32::from(s) - f32::from(*byte)) * surfaces::OVER_HAIR;
                    *byte = mixed.round().clamp(0.0, 255.0) as u8;
                }
            }
        }
        let mut image = Image {
            width: options.width,
            height: options.height,
            pixels,
        };
        if let (Some(name), true) = (&options.color_by, self.legend_width > 0) {
            draw_legend(&mut image, self.legend_width, name, self.range);
        }
        Ok(image)
    }

    /// Projects and shades every vertex (Kajiya-Kay).
    fn shade(
        &self,
        groom: &Groom,
        points: &[[f32; 3]],
        camera: &Camera,
        colors: Option<&(Vec<f32>, bool)>,
    ) -> Vec<ScreenVertex> {
        let up = groom.up_axis;
        let offsets = groom.strand_offsets();
        let strand_of: Vec<u32> = groom
            .strand_vertex_counts
            .iter()
            .enumerate()
            .flat_map(|(s, &n)| std::iter::repeat_n(s as u32, n as usize))
            .take(points.len())
            .collect();
        let widths = width_values(groom);
        let lights = Lights::new(camera);
        let (near, far) = self.depth_range;
        let depth_span = (far - near).max(1e-9);
        let range = self.range;
        let hair = self.options.hair_color;
        let default_width = default_width(groom);
        let width_of = |strand: usize, i: usize| {
            widths
                .as_ref()
                .and_then(|(values, per_strand)| {
                    values.get(if *per_strand { strand } else { i }).copied()
                })
                .filter(|w| w.is_finite() && *w >= 0.0)
                .unwrap_or(default_width)
        };
        let y_up: Vec<Vec3> = points.par_iter().map(|&p| up.to_y_up(p)).collect();
        // The hair area each vertex stands for: its width times half of each
        // segment it ends.
        let cross_sections: Vec<f32> = (0..strand_of.len())
            .into_par_iter()
            .map(|i| {
                let strand = strand_of[i] as usize;
                let (Some(&start), Some(&end)) = (offsets.get(strand), offsets.get(strand + 1))
                else {
                    return 0.0;
                };
                let at = |j: usize| y_up.get(j).copied();
                let half_length = |j: usize, k: usize| match (at(j), at(k)) {
                    (Some(a), Some(b)) if j != k => 0.5 * dot(sub(b, a), sub(b, a)).sqrt(),
                    _ => 0.0,
                };
                let length = half_length(i.saturating_sub(1).max(start), i)
                    + half_length(i, (i + 1).min(end.saturating_sub(1)));
                width_of(strand, i) * length
            })
            .collect();
        let key_light = shadow::key_light(&y_up, &cross_sections, lights.key);
        let mut vertices = vec![ScreenVertex::INVALID; strand_of.len()];
        vertices.par_iter_mut().enumerate().for_each(|(i, vertex)| {
            let Some(&strand) = strand_of.get(i) else {
                return;
            };
            let strand = strand as usize;
            let (Some(&start), Some(&end)) = (offsets.get(strand), offsets.get(strand + 1)) else {
                return;
            };
            let point = |j: usize| y_up.get(j).copied();
            let Some(p) = point(i) else {
                return;
            };
            let Some(projected) = camera.project(p) else {
                return;
            };
            let before = point(i.saturating_sub(1).max(start)).unwrap_or(p);
            let after = point((i + 1).min(end.saturating_sub(1))).unwrap_or(p);
            let tangent = normalize(sub(after, before));
            let along = if end - start > 1 {
                (i - start) as f32 / (end - start - 1) as f32
            } else {
                0.0
            };
            let base = match (colors, range) {
                (Some((values, per_strand)), Some((lo, hi))) => {
                    let value = values.get(if *per_strand { strand } else { i });
                    match value {
                        Some(v) if v.is_finite() => {
                            let x = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
                            ramp(x)
                        }
                        _ => [0.3, 0.3, 0.3],
                    }
                }
                (Some(_), None) => [0.3, 0.3, 0.3],
                _ => {
                    // A little variation between strands reads as hair, not a surface.
                    let jitter = 0.8 + 0.4 * unit_hash(strand as u64);
                    hair.map(|c| c * jitter)
                }
            };
            let depth_cue = 1.0 - 0.45 * ((projected.depth - near) / depth_span).clamp(0.0, 1.0);
            // Roots sit under the other hair: darker.
            let root_shade = 0.7 + 0.3 * smoothstep(0.0, 0.3, along);
            let occlusion = depth_cue * root_shade;
            let view = camera.toward_eye(p);
            let lit = key_light.get(i).copied().unwrap_or(1.0);
            let color = lights.shade(tangent, view, base, occlusion, lit, colors.is_some());
            let width = width_of(strand, i);
            *vertex = ScreenVertex {
                x: projected.x,
                y: projected.y,
                depth: projected.depth,
                width: width * projected.pixels_per_unit,
                joint: [0.0, 0.0],
                color,
            };
        });
        vertices
    }
}

/// The points of the pose to draw.
fn pose(groom: &Groom, frame: Option<usize>) -> Result<&[[f32; 3]], PreviewError> {
    let Some(frame) = frame else {
        return Ok(&groom.points);
    };
    let Some(sample) = groom.frames.get(frame) else {
        return Err(PreviewError::NoSuchFrame {
            frame,
            count: groom.frames.len(),
        });
    };
    if sample.points.len() != groom.points.len() {
        return Err(PreviewError::FrameMismatch {
            frame,
            found: sample.points.len(),
            expected: groom.points.len(),
        });
    }
    Ok(&sample.points)
}

/// A human hair is about 70 micrometres wide: the width to draw when the
/// groom has none.
fn default_width(groom: &Groom) -> f32 {
    (7.0e-5 / groom.units.meters_per_unit) as f32
}

/// The groom's hair widths, if it has a usable width attribute.
fn width_values(groom: &Groom) -> Option<(Vec<f32>, bool)> {
    ["width", "widths", "groom_width"]
        .iter()
        .find_map(|name| scalar_values(groom, name).ok())
}

/// The screen direction of each strand through each vertex.
fn set_joints(groom: &Groom, vertices: &mut [ScreenVertex]) {
    let mut start = 0usize;
    for &count in &groom.strand_vertex_counts {
        let end = start.saturating_add(count as usize).min(vertices.len());
        for i in start..end {
            let before = vertices[i.saturating_sub(1).max(start)];
            let after = vertices[(i + 1).min(end - 1)];
            let (dx, dy) = (after.x - before.x, after.y - before.y);
            let length = (dx * dx + dy * dy).sqrt();
            vertices[i].joint = if length > 1e-12 {
                [dx / length, dy / length]
            } else {
                [0.0, 0.0]
            };
        }
        start = end;
    }
}

/// First and end vertex of each strand (clipped to the vertices there are).
fn strand_ranges(groom: &Groom, vertex_count: usize) -> Vec<(u32, u32)> {
    let mut ranges = Vec::with_capacity(groom.strand_count());
    let mut start = 0usize;
    for &count in &groom.strand_vertex_counts {
        let end = start.saturating_add(count as usize).min(vertex_count);
        ranges.push((start as u32, end as u32));
        start = end;
    }
    ranges
}

/// How opaque a sub-pixel hair is drawn: its true coverage where the hair
/// piles up (dense grooms), more where strands are few, so both read.
fn min_opacity(
    vertices: &[ScreenVertex],
    strands: &[(u32, u32)],
    width: usize,
    height: usize,
) -> f32 {
    let drawn: f64 = strands
        .par_iter()
        .map(|&(start, end)| {
            let strand = vertices.get(start as usize..end as usize).unwrap_or(&[]);
            strand
                .windows(2)
                .filter(|pair| pair[0].valid() && pair[1].valid())
                .map(|pair| {
                    let (a, b) = (pair[0], pair[1]);
                    f64::from(((b.x - a.x).powi(2) + (b.y - a.y).powi(2)).sqrt())
                })
                .sum::<f64>()
        })
        .sum();
    // Average number of 1 px hairs over a pixel of the framed area.
    let layers = drawn / (width as f64 * height as f64 * 0.5);
    (3.0 / layers.max(1e-9)).min(1.0) as f32
}

fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A fixed hash of an integer to [0, 1) (SplitMix64 finaliser).
fn unit_hash(x: u64) -> f32 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// The blue-to-red ramp (linear RGB), `x` in [0, 1]: blue, cyan, yellow, red.
pub fn ramp(x: f32) -> [f32; 3] {
    const STOPS: [[f32; 3]; 4] = [
        [0.02, 0.06, 0.90],
        [0.01, 0.55, 0.70],
        [0.90, 0.62, 0.02],
        [0.80, 0.01, 0.005],
    ];
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let position = x * (STOPS.len() - 1) as f32;
    let index = (position.floor() as usize).min(STOPS.len() - 2);
    let f = position - index as f32;
    let (a, b) = (STOPS[index], STOPS[index + 1]);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

#[cfg(test)]
mod tests;
