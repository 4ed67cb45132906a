//! Per-strand variation of the `head` layout: length, width, layer height
//! and curl drawn from each strand's own seeded stream, the curl laid
//! around the combed line, and clumps.
//!
//! Lengths, widths and curl radii are normal draws about their means with
//! the given relative spread, clamped to three deviations (a TD's "mean and
//! spread"; the clamp keeps every draw positive over the documented
//! ranges). Each strand's stream is its own ([`SplitMix64::for_item`]), so
//! no draw depends on how threads share the strands.
//!
//! Curl is a helix of the drawn radius and `curl_pitch` around the combed
//! line, its radius growing from 0 over the first half turn (the root
//! stays put). While the strand lies on the head the helix is flattened to
//! a wave in the scalp's tangent plane (lying hair cannot coil into the
//! head), and it opens over the 1 cm after the strand leaves the head. The
//! hair's arc length is kept: the line is walked at `cos(a)` of the hair's
//! step, `tan(a)` the coil's slope, so curly hair reaches less far, as it
//! does.
//!
//! Clumps (as in groom tools' clump nodes): clump centres are a second,
//! sparser even spread of roots (one per `clump_size` squared of scalp),
//! each growing a clump strand like any other; every strand is drawn
//! toward the nearest centre's strand combed the same way (never one across
//! the parting, where the blend would cut through the head) at the same arc
//! length by
//! `clump_strength (s / length)^clump_profile`, its edges then set back to
//! their lengths along their new directions (the length is kept); it also
//! takes its clump's curl phase, so a clump's curls turn together.

use super::{GeneratorParameters, SplitMix64, CLEARANCE};
use groom::math::double::{add, cross, dot, length, scale, sub, try_normalize, V3};
use std::collections::HashMap;
use std::f64::consts::TAU;

/// Random streams of the strands and of the clump strands.
pub(super) const STREAM_STRAND: u64 = 21;
pub(super) const STREAM_CLUMP: u64 = 22;

/// One strand's draws.
#[derive(Debug, Clone, Copy)]
pub(super) struct Draw {
    pub edges: usize,
    pub step: f64,
    pub width: f32,
    /// Height of its place in the hair layer, metres.
    pub layer: f64,
    pub curl_radius: f64,
    /// Curl phase, radians.
    pub curl_phase: f64,
}

pub(super) fn draw(p: &GeneratorParameters, stream: u64, index: usize) -> Draw {
    let mut random = SplitMix64::for_item(p.seed, stream, index as u64);
    let length = p.length as f64 * random.relative(p.length_spread);
    let edges = ((length / p.segment_length as f64).round() as usize).max(1);
    let width = (p.width as f64 * random.relative(p.width_spread)) as f32;
    let clearance = CLEARANCE as f64;
    let layer = clearance + random.next_f64() * (p.volume as f64 - clearance).max(0.0);
    let curl_radius = p.curl_radius as f64 * random.relative(p.curl_radius_spread);
    let spread = (p.curl_phase_spread as f64).to_radians();
    let curl_phase = (p.curl_phase as f64).to_radians() + (2.0 * random.next_f64() - 1.0) * spread;
    Draw {
        edges,
        step: length / edges as f64,
        width,
        layer,
        curl_radius,
        curl_phase,
    }
}

fn unit(a: V3, fallback: V3) -> V3 {
    try_normalize(a).unwrap_or(fallback)
}

/// The line's point and frame at arc `s` (linear between vertices).
fn at(line: &[V3], frames: &[(V3, V3)], step: f64, s: f64) -> (V3, V3, V3) {
    let last = line.len() - 1;
    let x = (s / step).max(0.0);
    let i = (x.floor() as usize).min(last.saturating_sub(1));
    let f = if last == 0 {
        0.0
    } else {
        (x - i as f64).min(1.0)
    };
    let j = (i + 1).min(last);
    let point = add(scale(line[i], 1.0 - f), scale(line[j], f));
    let n = unit(
        add(scale(frames[i].0, 1.0 - f), scale(frames[j].0, f)),
        frames[i].0,
    );
    let b = unit(
        add(scale(frames[i].1, 1.0 - f), scale(frames[j].1, f)),
        frames[i].1,
    );
    (point, n, b)
}

/// Curls the combed `line` (edges of `step`), which lies on the head up to
/// arc `lying_until`; `normal` is the scalp's at the root.
pub(super) fn curl(
    line: &[V3],
    step: f64,
    lying_until: f64,
    normal: V3,
    d: &Draw,
    p: &GeneratorParameters,
) -> Vec<V3> {
    // Frames parallel-transported along the line, starting from the scalp
    // normal: N leaves the scalp, B lies in it.
    let mut frames = Vec::with_capacity(line.len());
    let tangent_at = |i: usize| {
        let (a, b) = if i + 1 < line.len() {
            (line[i], line[i + 1])
        } else {
            (line[i.saturating_sub(1)], line[i])
        };
        unit(sub(b, a), normal)
    };
    let t0 = tangent_at(0);
    let mut n = unit(sub(normal, scale(t0, dot(normal, t0))), [0.0, 1.0, 0.0]);
    for i in 0..line.len() {
        let t = tangent_at(i);
        n = unit(sub(n, scale(t, dot(n, t))), n);
        frames.push((n, cross(t, n)));
    }
    let pitch = p.curl_pitch as f64;
    let radius_at = |s: f64| {
        let ramp = (s / (0.5 * pitch)).clamp(0.0, 1.0);
        d.curl_radius * ramp * ramp * (3.0 - 2.0 * ramp)
    };
    let open_at = |s: f64| ((s - lying_until) / 0.01).clamp(0.0, 1.0);
    let slope = |s: f64, psi: f64| {
        let r = TAU * radius_at(s) / pitch;
        let open = open_at(s);
        // A helix's slope is r; a wave's, r |sin psi|; between, their mix.
        r * (open + (1.0 - open) * psi.sin().abs())
    };
    let mut out = Vec::with_capacity(line.len());
    let mut s = 0.0;
    for _ in 0..line.len() {
        let psi = TAU * s / pitch + d.curl_phase;
        let (point, n, b) = at(line, &frames, step, s);
        let r = radius_at(s);
        let offset = add(
            scale(b, r * psi.cos()),
            scale(n, r * open_at(s) * psi.sin()),
        );
        out.push(add(point, offset));
        s += step / (1.0 + slope(s, psi).powi(2)).sqrt();
    }
    // The root stays where it grows.
    out[0] = line[0];
    out
}

/// Draws `strand` (edges of `step`) toward `centre` (edges of
/// `centre_step`) at the same arc lengths.
pub(super) fn clump(
    strand: &mut [V3],
    step: f64,
    centre: &[V3],
    centre_step: f64,
    p: &GeneratorParameters,
) {
    let total = step * (strand.len() - 1).max(1) as f64;
    let edges: Vec<f64> = strand.windows(2).map(|w| length(sub(w[1], w[0]))).collect();
    let last = centre.len() - 1;
    for (k, point) in strand.iter_mut().enumerate().skip(1) {
        let s = k as f64 * step;
        let x = s / centre_step;
        let i = (x.floor() as usize).min(last.saturating_sub(1));
        let f = if last == 0 {
            0.0
        } else {
            (x - i as f64).min(1.0)
        };
        let target = add(
            scale(centre[i], 1.0 - f),
            scale(centre[(i + 1).min(last)], f),
        );
        let c = p.clump_strength as f64 * (s / total).powf(p.clump_profile as f64);
        *point = add(*point, scale(sub(target, *point), c));
    }
    // Each edge back to its length along its clumped direction: the strand
    // keeps its length and takes the clump's shape.
    let mut previous = strand[0];
    let mut before = strand[0];
    for (k, point) in strand.iter_mut().enumerate().skip(1) {
        let direction = try_normalize(sub(*point, before)).unwrap_or([0.0, -1.0, 0.0]);
        before = *point;
        *point = add(previous, scale(direction, edges[k - 1]));
        previous = *point;
    }
}

/// The nearest clump centre of a root: a hash grid of the centres' roots.
pub(super) struct ClumpIndex {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
    roots: Vec<V3>,
}

impl ClumpIndex {
    pub fn new(roots: Vec<V3>, cell: f64) -> ClumpIndex {
        let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, r) in roots.iter().enumerate() {
            cells.entry(Self::key(*r, cell)).or_default().push(i);
        }
        ClumpIndex { cell, cells, roots }
    }

    fn key(x: V3, cell: f64) -> [i64; 3] {
        x.map(|c| (c / cell).floor() as i64)
    }

    /// The nearest centre that `accept`s (the lowest index of equals):
    /// rings of cells outward until one more ring cannot hold a nearer
    /// one; none beyond 64 cells.
    pub fn nearest(&self, x: V3, accept: impl Fn(usize) -> bool) -> Option<usize> {
        let k = Self::key(x, self.cell);
        let mut best: Option<(f64, usize)> = None;
        for ring in 0..64i64 {
            for dx in -ring..=ring {
                for dy in -ring..=ring {
                    for dz in -ring..=ring {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != ring {
                            continue;
                        }
                        let Some(list) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                            continue;
                        };
                        for &i in list.iter().filter(|&&i| accept(i)) {
                            let d = length(sub(self.roots[i], x));
                            if best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                                best = Some((d, i));
                            }
                        }
                    }
                }
            }
            if let Some((d, _)) = best {
                if d <= ring as f64 * self.cell {
                    break;
                }
            }
        }
        best.map(|(_, i)| i)
    }
}
