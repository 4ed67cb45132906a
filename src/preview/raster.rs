//! Anti-aliased, back-to-front compositing of strand segments.
//!
//! Segments are sorted far to near once (a total order: depth, then index),
//! binned into horizontal bands of rows, and each band is composited by one
//! thread in that order. Every pixel is therefore blended in the same order
//! whatever the number of threads, so the picture is the same bytes.

use rayon::prelude::*;

/// A projected, shaded strand vertex.
#[derive(Debug, Clone, Copy, Default)]
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
    /// False when the vertex did not project (not finite, behind the camera).
    pub valid: bool,
}

/// Rows per band: small enough for a band's accumulation buffer to stay in
/// cache, large enough that few segments straddle bands.
const BAND_ROWS: usize = 16;

/// How segments of a picture are drawn.
pub(crate) struct Raster<'a> {
    pub vertices: &'a [ScreenVertex],
    /// Index of the first vertex of each drawable segment (its second vertex follows it).
    pub segments: Vec<u32>,
    pub width: usize,
    pub height: usize,
    /// Opacity of a hair narrower than a pixel never drops below this, so a
    /// sparse groom stays visible while a dense one keeps its soft look.
    pub min_opacity: f32,
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

/// The pixel-centre `x` interval where `c + k x` lies in `[lo, hi]`.
fn solve(c: f32, k: f32, lo: f32, hi: f32) -> (f32, f32) {
    if k.abs() < 1e-12 {
        if c >= lo && c <= hi {
            (f32::NEG_INFINITY, f32::INFINITY)
        } else {
            (1.0, 0.0)
        }
    } else {
        let a = (lo - c) / k;
        let b = (hi - c) / k;
        (a.min(b), a.max(b))
    }
}

impl Raster<'_> {
    /// Composites every segment over `background(row)` and returns RGB8
    /// rows (sRGB encoded).
    pub fn render(mut self, background: impl Fn(usize) -> [f32; 3] + Sync) -> Vec<u8> {
        let vertices = self.vertices;
        let mut keyed: Vec<u64> = self
            .segments
            .par_iter()
            .map(|&i| {
                let a = vertices[i as usize];
                let b = vertices[i as usize + 1];
                sort_key(0.5 * (a.depth + b.depth), i)
            })
            .collect();
        keyed.par_sort_unstable();
        self.segments.clear();

        let band_count = self.height.div_ceil(BAND_ROWS);
        let mut bands: Vec<Vec<u32>> = vec![Vec::new(); band_count];
        for key in keyed {
            let i = key as u32;
            let a = vertices[i as usize];
            let b = vertices[i as usize + 1];
            let reach = 0.5 * a.width.max(b.width).max(1.0) + 1.0;
            let top = a.y.min(b.y) - reach;
            let bottom = a.y.max(b.y) + reach;
            if bottom < 0.0 || top >= self.height as f32 {
                continue;
            }
            let first = (top.max(0.0) as usize) / BAND_ROWS;
            let last = ((bottom.min(self.height as f32 - 1.0)) as usize) / BAND_ROWS;
            for band in bands.iter_mut().take(last + 1).skip(first) {
                band.push(i);
            }
        }

        let width = self.width;
        let height = self.height;
        let mut out = vec![0u8; width * height * 3];
        out.par_chunks_mut(width * BAND_ROWS * 3)
            .zip(bands.par_iter())
            .enumerate()
            .for_each(|(band_index, (rows, segments))| {
                let row0 = band_index * BAND_ROWS;
                let row_count = rows.len() / (width * 3);
                let mut buffer = vec![[0f32; 3]; width * row_count];
                for r in 0..row_count {
                    let color = background(row0 + r);
                    buffer[r * width..(r + 1) * width].fill(color);
                }
                for &i in segments {
                    self.draw_segment(i as usize, row0, row_count, &mut buffer);
                }
                for (pixel, rgb) in buffer.iter().zip(rows.chunks_exact_mut(3)) {
                    for k in 0..3 {
                        rgb[k] = encode_srgb(pixel[k]);
                    }
                }
            });
        let _ = height;
        out
    }

    /// Blends segment `i` (vertices `i`, `i + 1`) into the rows
    /// `row0 .. row0 + row_count` held in `buffer`.
    fn draw_segment(&self, i: usize, row0: usize, row_count: usize, buffer: &mut [[f32; 3]]) {
        let (Some(a), Some(b)) = (self.vertices.get(i), self.vertices.get(i + 1)) else {
            return;
        };
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
        let top = (a.y.min(b.y) - reach).floor().max(row0 as f32) as usize;
        let bottom = ((a.y.max(b.y) + reach).ceil() as usize).min(row0 + row_count);
        let width = self.width as f32;
        // A joint direction that folds back (a hairpin) cannot cut: use the segment's own.
        let cut = |joint: [f32; 2]| {
            if (joint[0] * dx + joint[1] * dy) > 0.3 * length {
                joint
            } else {
                [dx / length, dy / length]
            }
        };
        let (cut_a, cut_b) = (cut(a.joint), cut(b.joint));
        for row in top..bottom {
            let cy = row as f32 + 0.5;
            // Signed distance s and parameter t along the segment, both linear in x.
            let s0 = -a.x * nx + (cy - a.y) * ny;
            let t0 = (-a.x * dx + (cy - a.y) * dy) / length2;
            let tk = dx / length2;
            // Past the cut through a, before the cut through b, both linear in x.
            let ca0 = -a.x * cut_a[0] + (cy - a.y) * cut_a[1];
            let cb0 = -b.x * cut_b[0] + (cy - b.y) * cut_b[1];
            let (s_lo, s_hi) = solve(s0, nx, -reach, reach);
            let (a_lo, a_hi) = solve(ca0, cut_a[0], -1e-3, f32::MAX);
            let (b_lo, b_hi) = solve(cb0, cut_b[0], f32::MIN, 1e-3);
            let lo = s_lo.max(a_lo).max(b_lo).max(0.5);
            let hi = s_hi.min(a_hi).min(b_hi).min(width - 0.5);
            if lo > hi {
                continue;
            }
            let first = (lo - 0.5).ceil() as usize;
            let last = (hi - 0.5).floor() as usize;
            let line = (row - row0) * self.width;
            for column in first..=last.min(self.width - 1) {
                let cx = column as f32 + 0.5;
                // Half-open between the cuts so a joint is drawn by one segment only.
                if ca0 + cut_a[0] * cx < 0.0 || cb0 + cut_b[0] * cx >= 0.0 {
                    continue;
                }
                let t = (t0 + tk * cx).clamp(0.0, 1.0);
                let s = (s0 + nx * cx).abs();
                let half = half0 + (half1 - half0) * t;
                let coverage = (half + 0.5 - s).clamp(0.0, 1.0);
                if coverage <= 0.0 {
                    continue;
                }
                let alpha = coverage * (opacity0 + (opacity1 - opacity0) * t);
                let Some(pixel) = buffer.get_mut(line + column) else {
                    continue;
                };
                for k in 0..3 {
                    let color = a.color[k] + (b.color[k] - a.color[k]) * t;
                    pixel[k] += (color - pixel[k]) * alpha;
                }
            }
        }
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
