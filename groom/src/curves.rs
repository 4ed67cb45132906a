//! Smooth curves from simulated polylines.
//!
//! The solver computes a point every few centimetres; a renderer wants
//! smooth hair. A [`CurveMap`] turns each strand's points into either a
//! polyline resampled along the Catmull-Rom spline through them (a point
//! every `segment` metres of arc) or the control points of a cubic curve
//! (Catmull-Rom or B-spline) with the end points padded so that the curve
//! starts at the root and ends at the tip, as USD's non-periodic cubic
//! curves require (USD draws a Catmull-Rom or B-spline curve of `n` control
//! points over the spans between points 1 and n-2).
//!
//! The map is built once, from the rest or first pose, and then applied to
//! every frame with the same weights: the vertex counts stay the same for
//! the whole animation and memory does not grow with the frame count.
//! Each output point is a fixed combination of four input points.

use crate::{Attribute, AttributeValues, CurveBasis, Groom, Scope};

/// How exported strands are shaped.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum CurveForm {
    /// The points as they are.
    #[default]
    Polyline,
    /// A polyline with a point every `segment` (in the groom's units) along
    /// the Catmull-Rom spline through the points.
    Resampled { segment: f32 },
    /// The points as control points of a cubic curve of this basis
    /// (`CatmullRom` or `Bspline`), padded at the ends.
    Cubic(CurveBasis),
}

/// One output point: four input points (strand-local indices, clamped
/// at the ends) and their weights, plus the linear blend used for vertex
/// attributes (`near`, `t`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tap {
    /// Index of the first point of the span in the strand.
    span: u32,
    /// Position in the span, 0..=1.
    t: f32,
    kind: TapKind,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum TapKind {
    /// On the uniform Catmull-Rom spline through the points; outside the
    /// strand the points are reflected (`p[-1] = 2 p[0] - p[1]`).
    CatmullRom,
    /// A padding copy of the end point (B-spline) or its reflection
    /// (Catmull-Rom): `t` 0 at the root end, 1 at the tip end.
    Reflect,
}

/// A fixed re-shaping of every strand; see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveMap {
    form: CurveForm,
    source_counts: Vec<u32>,
    counts: Vec<u32>,
    taps: Vec<Tap>,
}

/// Catmull-Rom weights of the four points around a span at `t`.
fn catmull_rom_weights(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        0.5 * (-t + 2.0 * t2 - t3),
        0.5 * (2.0 - 5.0 * t2 + 3.0 * t3),
        0.5 * (t + 4.0 * t2 - 3.0 * t3),
        0.5 * (-t2 + t3),
    ]
}

/// Uniform cubic B-spline weights of the four points around a span at `t`.
fn bspline_weights(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    let s = 1.0 - t;
    [
        s * s * s / 6.0,
        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
        t3 / 6.0,
    ]
}

/// Point `i` of a strand, reflected beyond the ends.
fn point_at(strand: &[[f32; 3]], i: i64) -> [f32; 3] {
    let n = strand.len() as i64;
    if n == 0 {
        return [0.0; 3];
    }
    if n == 1 {
        return strand[0];
    }
    let reflect =
        |a: [f32; 3], b: [f32; 3]| [2.0 * a[0] - b[0], 2.0 * a[1] - b[1], 2.0 * a[2] - b[2]];
    if i < 0 {
        reflect(strand[0], strand[1])
    } else if i >= n {
        reflect(strand[(n - 1) as usize], strand[(n - 2) as usize])
    } else {
        strand[i as usize]
    }
}

/// The point on the Catmull-Rom spline through `strand` in span `span` at `t`.
pub fn catmull_rom_point(strand: &[[f32; 3]], span: usize, t: f32) -> [f32; 3] {
    let w = catmull_rom_weights(t);
    let mut out = [0.0f32; 3];
    for (k, wk) in w.iter().enumerate() {
        let p = point_at(strand, span as i64 - 1 + k as i64);
        for c in 0..3 {
            out[c] += wk * p[c];
        }
    }
    out
}

fn distance(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Samples per span when measuring the spline's arc length.
const ARC_SAMPLES: usize = 16;
/// The most output points one strand may get (guards against a tiny
/// segment length on a long strand).
pub const MAX_POINTS_PER_STRAND: usize = 100_000;

impl CurveMap {
    /// The map for `groom`'s strands in their current points.
    pub fn new(groom: &Groom, form: CurveForm) -> CurveMap {
        let mut counts = Vec::with_capacity(groom.strand_count());
        let mut taps = Vec::new();
        for strand in groom.strands() {
            let before = taps.len();
            match form {
                CurveForm::Polyline => {
                    taps.extend((0..strand.len()).map(|i| Tap {
                        span: i as u32,
                        t: 0.0,
                        kind: TapKind::CatmullRom,
                    }));
                }
                CurveForm::Resampled { segment } => resample_taps(strand, segment, &mut taps),
                CurveForm::Cubic(basis) => {
                    let pad = if basis == CurveBasis::Bspline { 2 } else { 1 };
                    let n = strand.len();
                    let reflect = |t| Tap {
                        span: 0,
                        t,
                        kind: TapKind::Reflect,
                    };
                    if n >= 2 {
                        taps.extend((0..pad).map(|_| reflect(0.0)));
                    }
                    taps.extend((0..n).map(|i| Tap {
                        span: i as u32,
                        t: 0.0,
                        kind: TapKind::CatmullRom,
                    }));
                    if n >= 2 {
                        taps.extend((0..pad).map(|_| reflect(1.0)));
                    }
                }
            }
            counts.push((taps.len() - before) as u32);
        }
        CurveMap {
            form,
            source_counts: groom.strand_vertex_counts.clone(),
            counts,
            taps,
        }
    }

    pub fn form(&self) -> CurveForm {
        self.form
    }

    /// Vertex count of each output strand.
    pub fn counts(&self) -> &[u32] {
        &self.counts
    }

    fn basis(&self) -> CurveBasis {
        match self.form {
            CurveForm::Cubic(basis) => basis,
            _ => CurveBasis::Linear,
        }
    }

    /// The output points of one pose (same topology as the groom the map
    /// was built from).
    pub fn points(&self, points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        let mut out = Vec::with_capacity(self.taps.len());
        let bspline = self.basis() == CurveBasis::Bspline;
        let mut start = 0usize;
        let mut tap_start = 0usize;
        for (&n, &m) in self.source_counts.iter().zip(&self.counts) {
            let end = (start + n as usize).min(points.len());
            let strand = points.get(start..end).unwrap_or(&[]);
            for tap in &self.taps[tap_start..tap_start + m as usize] {
                out.push(match tap.kind {
                    TapKind::CatmullRom if tap.t == 0.0 => point_at(strand, tap.span as i64),
                    TapKind::CatmullRom => catmull_rom_point(strand, tap.span as usize, tap.t),
                    TapKind::Reflect => {
                        let (at, next) = if tap.t == 0.0 {
                            (0, 1)
                        } else {
                            (strand.len() as i64 - 1, strand.len() as i64 - 2)
                        };
                        if bspline {
                            point_at(strand, at)
                        } else {
                            let a = point_at(strand, at);
                            let b = point_at(strand, next);
                            [2.0 * a[0] - b[0], 2.0 * a[1] - b[1], 2.0 * a[2] - b[2]]
                        }
                    }
                });
            }
            start += n as usize;
            tap_start += m as usize;
        }
        out
    }

    /// Per output vertex: the input vertex (global index) and the linear
    /// weight of the next one, for carrying vertex attributes.
    fn vertex_blend(&self) -> Vec<(usize, usize, f32)> {
        let mut out = Vec::with_capacity(self.taps.len());
        let mut start = 0usize;
        let mut tap_start = 0usize;
        for (&n, &m) in self.source_counts.iter().zip(&self.counts) {
            let last = (n as usize).saturating_sub(1);
            for tap in &self.taps[tap_start..tap_start + m as usize] {
                let (i, t) = match tap.kind {
                    TapKind::Reflect if tap.t == 0.0 => (0, 0.0),
                    TapKind::Reflect => (last, 0.0),
                    TapKind::CatmullRom => ((tap.span as usize).min(last), tap.t),
                };
                out.push((start + i, start + (i + 1).min(last), t));
            }
            start += n as usize;
            tap_start += m as usize;
        }
        out
    }

    /// The groom re-shaped: points, frames, vertex attributes (blended
    /// linearly, ints from the nearer point) and the curve basis.
    pub fn apply(&self, groom: &Groom) -> Groom {
        let mut out = groom.clone();
        out.points = self.points(&groom.points);
        let blend = self.vertex_blend();
        let reshape = |attributes: &[Attribute]| -> Vec<Attribute> {
            attributes
                .iter()
                .map(|a| match a.scope {
                    Scope::Strand => a.clone(),
                    Scope::Vertex => Attribute {
                        name: a.name.clone(),
                        scope: Scope::Vertex,
                        values: blend_values(&a.values, &blend),
                    },
                })
                .collect()
        };
        for frame in &mut out.frames {
            frame.points = self.points(&frame.points);
            frame.attributes = reshape(&frame.attributes);
        }
        out.strand_vertex_counts = self.counts.clone();
        out.basis = self.basis();
        out.attributes = reshape(&groom.attributes);
        out
    }
}

fn blend_values(values: &AttributeValues, blend: &[(usize, usize, f32)]) -> AttributeValues {
    fn lerp<const N: usize>(v: &[[f32; N]], blend: &[(usize, usize, f32)]) -> Vec<[f32; N]> {
        blend
            .iter()
            .map(|&(i, j, t)| {
                let a = v.get(i).copied().unwrap_or([0.0; N]);
                let b = v.get(j).copied().unwrap_or(a);
                std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t)
            })
            .collect()
    }
    match values {
        AttributeValues::Float(v) => {
            let wrapped: Vec<[f32; 1]> = v.iter().map(|&x| [x]).collect();
            AttributeValues::Float(lerp(&wrapped, blend).into_iter().map(|[x]| x).collect())
        }
        AttributeValues::Vec2(v) => AttributeValues::Vec2(lerp(v, blend)),
        AttributeValues::Vec3(v) => AttributeValues::Vec3(lerp(v, blend)),
        AttributeValues::Int(v) => AttributeValues::Int(
            blend
                .iter()
                .map(|&(i, j, t)| {
                    let k = if t < 0.5 { i } else { j };
                    v.get(k).copied().unwrap_or(0)
                })
                .collect(),
        ),
    }
}

/// Taps at equal arc length along the spline through `strand`, at most
/// `segment` apart.
fn resample_taps(strand: &[[f32; 3]], segment: f32, taps: &mut Vec<Tap>) {
    let spans = strand.len().saturating_sub(1);
    if spans == 0 {
        taps.extend((0..strand.len()).map(|i| Tap {
            span: i as u32,
            t: 0.0,
            kind: TapKind::CatmullRom,
        }));
        return;
    }
    // Arc length at each of ARC_SAMPLES steps of every span.
    let mut arc = Vec::with_capacity(spans * ARC_SAMPLES + 1);
    arc.push(0.0f32);
    let mut previous = strand[0];
    for span in 0..spans {
        for k in 1..=ARC_SAMPLES {
            let p = catmull_rom_point(strand, span, k as f32 / ARC_SAMPLES as f32);
            let last = *arc.last().unwrap_or(&0.0);
            arc.push(last + distance(previous, p));
            previous = p;
        }
    }
    let length = *arc.last().unwrap_or(&0.0);
    let edges = if segment > 0.0 && length.is_finite() {
        ((length / segment).ceil() as usize).clamp(1, MAX_POINTS_PER_STRAND - 1)
    } else {
        spans
    };
    let mut j = 0usize;
    for k in 0..=edges {
        let s = length * k as f32 / edges as f32;
        while j + 1 < arc.len() - 1 && arc[j + 1] < s {
            j += 1;
        }
        let (a, b) = (arc[j], arc[j + 1]);
        let f = if b > a {
            ((s - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let u = (j as f32 + f) / ARC_SAMPLES as f32;
        let span = (u.floor() as usize).min(spans - 1);
        let t = (u - span as f32).clamp(0.0, 1.0);
        // The ends exactly on the root and the tip.
        let (span, t) = match k {
            0 => (0, 0.0),
            k if k == edges => (spans, 0.0),
            _ => (span, t),
        };
        taps.push(Tap {
            span: span as u32,
            t,
            kind: TapKind::CatmullRom,
        });
    }
}

/// A cubic groom (Catmull-Rom or B-spline control points) as a polyline of
/// `per_span` points per span, for drawing; frames likewise. Other grooms
/// come back as they are (borrowed). Vertex attributes follow the nearest
/// control point.
pub fn tessellate(groom: &Groom, per_span: usize) -> std::borrow::Cow<'_, Groom> {
    let basis = groom.basis;
    if !matches!(basis, CurveBasis::CatmullRom | CurveBasis::Bspline) {
        return std::borrow::Cow::Borrowed(groom);
    }
    let per_span = per_span.max(1);
    let weights = move |t: f32| match basis {
        CurveBasis::Bspline => bspline_weights(t),
        _ => catmull_rom_weights(t),
    };
    // Per output point: the four control points (global indices) and
    // their weights, and the nearest control point.
    let mut taps: Vec<([usize; 4], [f32; 4])> = Vec::new();
    let mut nearest = Vec::new();
    let mut counts = Vec::with_capacity(groom.strand_count());
    let mut start = 0usize;
    for strand in groom.strands() {
        let n = strand.len();
        let before = taps.len();
        if n < 4 {
            for i in start..start + n {
                taps.push(([i; 4], [1.0, 0.0, 0.0, 0.0]));
                nearest.push(i);
            }
        } else {
            for span in 1..n - 2 {
                let last = if span == n - 3 {
                    per_span
                } else {
                    per_span - 1
                };
                for k in 0..=last {
                    let t = k as f32 / per_span as f32;
                    let first = start + span - 1;
                    taps.push(([first, first + 1, first + 2, first + 3], weights(t)));
                    nearest.push(start + span + usize::from(t >= 0.5));
                }
            }
        }
        counts.push((taps.len() - before) as u32);
        start += n;
    }
    let evaluate = |points: &[[f32; 3]]| -> Vec<[f32; 3]> {
        taps.iter()
            .map(|(index, w)| {
                let mut p = [0.0f32; 3];
                for (q, wq) in index.iter().zip(w) {
                    let c = points.get(*q).copied().unwrap_or([0.0; 3]);
                    for k in 0..3 {
                        p[k] += wq * c[k];
                    }
                }
                p
            })
            .collect()
    };
    let mut out = groom.clone();
    out.basis = CurveBasis::Linear;
    out.points = evaluate(&groom.points);
    out.strand_vertex_counts = counts;
    let blend: Vec<(usize, usize, f32)> = nearest.iter().map(|&i| (i, i, 0.0)).collect();
    let frame_attributes = out.frames.iter_mut().flat_map(|f| &mut f.attributes);
    for a in out.attributes.iter_mut().chain(frame_attributes) {
        if a.scope == Scope::Vertex {
            a.values = blend_values(&a.values, &blend);
        }
    }
    for frame in &mut out.frames {
        frame.points = evaluate(&frame.points);
    }
    std::borrow::Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zigzag() -> Groom {
        Groom::from_strands([vec![
            [0.0, 0.0, 0.0],
            [0.03, 0.03, 0.0],
            [0.0, 0.06, 0.0],
            [0.03, 0.09, 0.0],
            [0.0, 0.12, 0.0],
        ]])
    }

    #[test]
    fn resampling_keeps_the_ends_and_the_segment_length() {
        let groom = zigzag();
        let map = CurveMap::new(&groom, CurveForm::Resampled { segment: 0.005 });
        let points = map.points(&groom.points);
        assert_eq!(points.first(), groom.points.first());
        assert_eq!(points.last(), groom.points.last());
        let lengths: Vec<f32> = points.windows(2).map(|w| distance(w[0], w[1])).collect();
        let max = lengths.iter().cloned().fold(0.0, f32::max);
        let min = lengths.iter().cloned().fold(1.0, f32::min);
        assert!(max <= 0.0051 && min > 0.0045, "{min}..{max}");
    }

    #[test]
    fn catmull_rom_padding_draws_the_resampled_curve() {
        let groom = zigzag();
        let cubic = CurveMap::new(&groom, CurveForm::Cubic(CurveBasis::CatmullRom)).apply(&groom);
        assert_eq!(cubic.strand_vertex_counts, vec![7]);
        assert_eq!(cubic.basis, CurveBasis::CatmullRom);
        let drawn = tessellate(&cubic, 8);
        assert_eq!(drawn.points.first(), groom.points.first());
        assert_eq!(drawn.points.last(), groom.points.last());
        // Half way along the second span, the same point as the resampler's spline.
        let mid = catmull_rom_point(&groom.points, 1, 0.5);
        let drawn_mid = drawn.points[8 + 4];
        assert!(distance(mid, drawn_mid) < 1e-6, "{mid:?} {drawn_mid:?}");
    }

    #[test]
    fn bspline_padding_ends_on_the_root_and_tip() {
        let groom = zigzag();
        let cubic = CurveMap::new(&groom, CurveForm::Cubic(CurveBasis::Bspline)).apply(&groom);
        assert_eq!(cubic.strand_vertex_counts, vec![9]);
        let drawn = tessellate(&cubic, 4);
        assert!(distance(drawn.points[0], groom.points[0]) < 1e-6);
        let last = *drawn.points.last().unwrap();
        assert!(distance(last, groom.points[4]) < 1e-6);
    }

    #[test]
    fn vertex_attributes_follow_the_resampling() {
        let mut groom = zigzag();
        groom.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float(vec![1.0, 2.0, 3.0, 4.0, 5.0]),
        ));
        let out = CurveMap::new(&groom, CurveForm::Resampled { segment: 0.01 }).apply(&groom);
        let AttributeValues::Float(w) = &out.attribute("width").unwrap().values else {
            panic!()
        };
        assert_eq!(w.len(), out.vertex_count());
        assert_eq!((w[0], *w.last().unwrap()), (1.0, 5.0));
        assert!(w.windows(2).all(|p| p[1] >= p[0]));
    }
}
