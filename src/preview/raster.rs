//! Anti-aliased, back-to-front compositing of strand segments.
//!
//! Strands are sorted far to near (a total order: mean depth, then index),
//! their segments binned into horizontal bands of rows in that order, and
//! each band is composited by one thread. Each pixel keeps its nearest
//! fragments in depth order. Every pixel is blended in the same order
//! whatever the number of threads, so the picture is the same bytes.

use rayon::prelude::*;

/// A projected, shaded strand vertex. Kept small: the bands copy them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenVertex {
    pub x: f32,
    pub y: f32,
    pub depth: f32,
    /// Projected hair width in pixels (before the 1 px minimum).
    pub width: f32,
    /// Screen direction of the strand through this vertex (unit), which cuts
    /// the two segments meeting here along the same line: no gap, no overlap.
    pub joint: [f32; 2],
    /// Linear RGB after shading.
    pub color: [f32; 3],
}

impl ScreenVertex {
    /// A vertex that did not project (not finite, behind the camera).
    pub const INVALID: ScreenVertex = ScreenVertex {
        x: f32::NAN,
        y: f32::NAN,
        depth: f32::NAN,
        width: 0.0,
        joint: [0.0; 2],
        color: [0.0; 3],
    };

    pub fn valid(&self) -> bool {
        self.x.is_finite()
    }
}

/// Rows per band: small enough for a band's accumulation buffer to stay in
/// cache, large enough that few segments straddle bands.
const BAND_ROWS: usize = 16;

/// Bands a thread bins and draws together: enough groups to share out
/// between threads, few enough that each pass over the strands pays.
const GROUP_BANDS: usize = 8;

/// How segments of a picture are drawn.
pub(crate) struct Raster<'a> {
    pub vertices: &'a [ScreenVertex],
    /// First and end (exclusive) vertex of each strand.
    pub strands: Vec<(u32, u32)>,
    pub width: usize,
    pub height: usize,
    /// Opacity of a hair narrower than a pixel never drops below this, so a
    /// sparse groom stays visible while a dense one keeps its soft look.
    pub min_opacity: f32,
    /// Per pixel, the depth beyond which hair is hidden (behind the head);
    /// empty: nothing hides it.
    pub hides_beyond: &'a [f32],
}

/// Order key: far before near, ties by segment index (so the order is total).
fn sort_key(depth: f32, index: u32) -> u64 {
    let bits = depth.to_bits();
    // Map the float onto u32 so that unsigned order is numeric order.
    let ordered = if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    };
    (u64::from(!ordered) << 32) | u64::from(index)
}

/// Layers kept per pixel: the nearest `LAYERS - 1` fragments stay separate
/// and in depth order; the rest merge into the last layer (multi-layer alpha
/// blending, Salvi and Vaidyanathan 2014). The depth order at a pixel then
/// follows each fragment's own depth, not only its segment's.
const LAYERS: usize = 3;

#[derive(Debug, Clone, Copy)]
struct Layer {
    depth: f32,
    /// Premultiplied colour.
    color: [f32; 3],
    /// Light let through.
    transmit: f32,
}

const EMPTY: Layer = Layer {
    depth: f32::INFINITY,
    color: [0.0; 3],
    transmit: 1.0,
};

fn blend(pixel: &mut [Layer; LAYERS], mut fragment: Layer) {
    for layer in pixel.iter_mut() {
        if fragment.depth < layer.depth {
            std::mem::swap(&mut fragment, layer);
        }
    }
    // `fragment` is now the farthest: merge it behind the last layer.
    let last = &mut pixel[LAYERS - 1];
    for k in 0..3 {
        last.color[k] += last.transmit * fragment.color[k];
    }
    last.transmit *= fragment.transmit;
}

fn resolve(pixel: &[Layer; LAYERS], background: [f32; 3]) -> [f32; 3] {
    let mut color = [0.0f32; 3];
    let mut transmit = 1.0;
    for layer in pixel {
        for (c, l) in color.iter_mut().zip(layer.color) {
            *c += transmit * l;
        }
        transmit *= layer.transmit;
    }
    for (c, b) in color.iter_mut().zip(background) {
        *c += transmit * b;
    }
    color
}

impl Raster<'_> {
    /// Composites every segment over `background(row, column)` and returns
    /// RGB8 rows (sRGB encoded).
    pub fn render(self, background: impl Fn(usize, usize) -> [f32; 3] + Sync) -> Vec<u8> {
        let vertices = self.vertices;
        // Strands far to near by their mean depth. Each pixel then orders its
        // nearest fragments by their own depth (see `blend`); keeping a
        // strand's segments together keeps the reads of the vertices in order.
        let mut keyed: Vec<u64> = self
            .strands
            .par_iter()
            .enumerate()
            .map(|(index, &(start, end))| {
                let strand = vertices.get(start as usize..end as usize).unwrap_or(&[]);
                let (sum, count) = strand
                    .iter()
                    .filter(|v| v.valid())
                    .fold((0f64, 0u32), |(sum, count), v| {
                        (sum + f64::from(v.depth), count + 1)
                    });
                let mean = if count > 0 {
                    sum / f64::from(count)
                } else {
                    0.0
                };
                sort_key(mean as f32, index as u32)
            })
            .collect();
        keyed.par_sort_unstable();

        let order: Vec<u32> = keyed.iter().map(|&key| key as u32).collect();
        drop(keyed);
        // The rows each strand may touch, to skip it for groups it misses.
        let extents: Vec<[f32; 2]> = self
            .strands
            .par_iter()
            .map(|&(start, end)| {
                let strand = vertices.get(start as usize..end as usize).unwrap_or(&[]);
                strand.iter().filter(|v| v.valid()).fold(
                    [f32::INFINITY, f32::NEG_INFINITY],
                    |[top, bottom], v| {
                        let reach = 0.5 * v.width.max(1.0) + 1.0;
                        [top.min(v.y - reach), bottom.max(v.y + reach)]
                    },
                )
            })
            .collect();

        let encode = SrgbTable::new();
        let width = self.width;
        let mut out = vec![0u8; width * self.height * 3];
        // Rows go in groups of bands, a group to a thread. Each band of a
        // group gets its own copy of its segments, in order, so drawing reads
        // memory in sequence; copies of only the groups in flight bound the
        // memory that takes.
        let group_rows = BAND_ROWS * GROUP_BANDS;
        out.par_chunks_mut(width * group_rows * 3)
            .enumerate()
            .for_each_init(
                || (vec![Vec::new(); GROUP_BANDS], Vec::new()),
                |(bands, buffer), (group_index, group)| {
                    let group_row0 = group_index * group_rows;
                    let group_row_count = group.len() / (width * 3);
                    self.bin(&order, &extents, group_row0, group_row_count, bands);
                    for (band_index, (rows, segments)) in group
                        .chunks_mut(width * BAND_ROWS * 3)
                        .zip(bands.iter())
                        .enumerate()
                    {
                        let row0 = group_row0 + band_index * BAND_ROWS;
                        let row_count = rows.len() / (width * 3);
                        // Reused between bands: fresh pages cost more than drawing.
                        buffer.clear();
                        buffer.resize(width * row_count, [EMPTY; LAYERS]);
                        for (a, b) in segments {
                            self.draw_segment(a, b, row0, row_count, buffer);
                        }
                        for (r, (line, bytes)) in buffer
                            .chunks_exact(width)
                            .zip(rows.chunks_exact_mut(width * 3))
                            .enumerate()
                        {
                            for (column, (pixel, rgb)) in
                                line.iter().zip(bytes.chunks_exact_mut(3)).enumerate()
                            {
                                let color = resolve(pixel, background(row0 + r, column));
                                for (byte, c) in rgb.iter_mut().zip(color) {
                                    *byte = encode.encode(c);
                                }
                            }
                        }
                    }
                },
            );
        out
    }

    /// Fills `bands` with the segments touching each band of rows
    /// `row0 .. row0 + row_count`, strands in `order`.
    fn bin(
        &self,
        order: &[u32],
        extents: &[[f32; 2]],
        row0: usize,
        row_count: usize,
        bands: &mut [Vec<(ScreenVertex, ScreenVertex)>],
    ) {
        bands.iter_mut().for_each(Vec::clear);
        let (top_row, bottom_row) = (row0 as f32, (row0 + row_count) as f32);
        for &strand in order {
            let Some(&(start, end)) = self.strands.get(strand as usize) else {
                continue;
            };
            let Some(&[top, bottom]) = extents.get(strand as usize) else {
                continue;
            };
            if bottom < top_row || top >= bottom_row {
                continue;
            }
            let vertices = self
                .vertices
                .get(start as usize..end as usize)
                .unwrap_or(&[]);
            for pair in vertices.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                if !(a.valid() && b.valid()) {
                    continue;
                }
                let reach = 0.5 * a.width.max(b.width).max(1.0) + 1.0;
                let top = a.y.min(b.y) - reach;
                let bottom = a.y.max(b.y) + reach;
                if bottom < top_row || top >= bottom_row {
                    continue;
                }
                let first = (top.max(top_row) as usize - row0) / BAND_ROWS;
                let last = (bottom.min(bottom_row - 1.0) as usize).saturating_sub(row0) / BAND_ROWS;
                for band in bands.iter_mut().take(last + 1).skip(first) {
                    band.push((a, b));
                }
            }
        }
    }

    /// Blends a segment into the rows `row0 .. row0 + row_count` held in `buffer`.
    fn draw_segment(
        &self,
        a: &ScreenVertex,
        b: &ScreenVertex,
        row0: usize,
        row_count: usize,
        buffer: &mut [[Layer; LAYERS]],
    ) {
        let dx = b.x - a.x;
        let dy = b.y - a.y;
        let length2 = dx * dx + dy * dy;
        if length2 < 1e-8 {
            return;
        }
        let length = length2.sqrt();
        let nx = -dy / length;
        let ny = dx / length;
        // Drawn at least a pixel wide; thinner hair is drawn more transparent instead.
        let half0 = 0.5 * a.width.max(1.0);
        let half1 = 0.5 * b.width.max(1.0);
        let reach = half0.max(half1) + 0.5;
        let opacity0 = a.width.max(self.min_opacity).min(1.0);
        let opacity1 = b.width.max(self.min_opacity).min(1.0);
        let top = floor_at_least_zero((a.y.min(b.y) - reach).max(row0 as f32));
        let bottom = ceil_at_least_zero(a.y.max(b.y) + reach).min(row0 + row_count);
        // A joint direction that folds back (a hairpin) cannot cut: use the segment's own.
        let cut = |joint: [f32; 2]| {
            if (joint[0] * dx + joint[1] * dy) > 0.3 * length {
                joint
            } else {
                [dx / length, dy / length]
            }
        };
        let (cut_a, cut_b) = (cut(a.joint), cut(b.joint));
        let box_left = (a.x.min(b.x) - reach).max(0.0);
        let box_right = (a.x.max(b.x) + reach).min(self.width as f32);
        if box_left >= box_right {
            return;
        }
        let tk = dx / length2;
        // Where across the line |s| stays within reach, as an x interval per row.
        let inverse_nx = if nx.abs() > 1e-6 { 1.0 / nx } else { 0.0 };
        for row in top..bottom {
            let cy = row as f32 + 0.5;
            // s (signed distance), t (along), and the two cut tests are linear in x.
            let s0 = -a.x * nx + (cy - a.y) * ny;
            let t0 = (-a.x * dx + (cy - a.y) * dy) / length2;
            let ca0 = -a.x * cut_a[0] + (cy - a.y) * cut_a[1];
            let cb0 = -b.x * cut_b[0] + (cy - b.y) * cut_b[1];
            let (mut lo, mut hi) = (box_left, box_right);
            if inverse_nx != 0.0 {
                let center = -s0 * inverse_nx;
                let spread = reach * inverse_nx.abs();
                lo = lo.max(center - spread);
                hi = hi.min(center + spread);
            } else if s0.abs() > reach {
                continue;
            }
            // Pixel centres (column + 0.5) within [lo, hi].
            if lo >= hi || hi < 0.5 {
                continue;
            }
            let first = ceil_at_least_zero(lo - 0.5);
            let last = floor_at_least_zero(hi - 0.5).min(self.width - 1);
            if first > last {
                continue;
            }
            let line = (row - row0) * self.width;
            let hides = self
                .hides_beyond
                .get(row * self.width + first..=row * self.width + last);
            let Some(pixels) = buffer.get_mut(line + first..=line + last) else {
                continue;
            };
            for (column, pixel) in (first..).zip(pixels.iter_mut()) {
                let cx = column as f32 + 0.5;
                // Half-open between the cuts so a joint is drawn by one segment only.
                if ca0 + cut_a[0] * cx < 0.0 || cb0 + cut_b[0] * cx >= 0.0 {
                    continue;
                }
                let s = (s0 + nx * cx).abs();
                let t = (t0 + tk * cx).clamp(0.0, 1.0);
                let half = half0 + (half1 - half0) * t;
                let coverage = (half + 0.5 - s).min(1.0);
                if coverage <= 0.0 {
                    continue;
                }
                let depth = a.depth + (b.depth - a.depth) * t;
                if hides.is_some_and(|h| h.get(column - first).is_some_and(|&h| depth > h)) {
                    continue;
                }
                let alpha = coverage * (opacity0 + (opacity1 - opacity0) * t);
                let color = [0, 1, 2].map(|k| (a.color[k] + (b.color[k] - a.color[k]) * t) * alpha);
                blend(
                    pixel,
                    Layer {
                        depth,
                        color,
                        transmit: 1.0 - alpha,
                    },
                );
            }
        }
    }
}

/// `floor(x)` for the pixel arithmetic, 0 for negative `x` (the libm call
/// costs more than the rest of a row).
fn floor_at_least_zero(x: f32) -> usize {
    if x > 0.0 {
        x as usize
    } else {
        0
    }
}

/// `ceil(x)`, 0 for negative `x`.
fn ceil_at_least_zero(x: f32) -> usize {
    if x > 0.0 {
        let whole = x as usize;
        if (whole as f32) < x {
            whole + 1
        } else {
            whole
        }
    } else {
        0
    }
}

/// Linear to sRGB bytes through a table: the power function per pixel
/// would cost more than drawing the strands.
struct SrgbTable(Vec<u8>);

const SRGB_STEPS: usize = 4096;

impl SrgbTable {
    fn new() -> SrgbTable {
        SrgbTable(
            (0..=SRGB_STEPS)
                .map(|i| encode_srgb(i as f32 / SRGB_STEPS as f32))
                .collect(),
        )
    }

    fn encode(&self, linear: f32) -> u8 {
        let index = (linear.clamp(0.0, 1.0) * SRGB_STEPS as f32 + 0.5) as usize;
        self.0.get(index).copied().unwrap_or(255)
    }
}

/// Linear [0, 1] to an sRGB byte.
pub(crate) fn encode_srgb(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let encoded = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sort_key_orders_far_first_then_index() {
        let mut keys = [
            sort_key(1.0, 3),
            sort_key(5.0, 1),
            sort_key(-2.0, 0),
            sort_key(1.0, 2),
        ];
        keys.sort_unstable();
        let order: Vec<u32> = keys.iter().map(|k| *k as u32).collect();
        assert_eq!(order, vec![1, 2, 3, 0]);
    }

    #[test]
    fn srgb_ends() {
        assert_eq!(encode_srgb(0.0), 0);
        assert_eq!(encode_srgb(1.0), 255);
        assert_eq!(encode_srgb(0.2158), 128);
    }
}
