//! Render strands interpolated from guides.
//!
//! Each render strand follows three guides with weights that sum to 1:
//! barycentric weights when its root was scattered inside the triangle of
//! three guide roots ([`RenderHair::grow`]), inverse-distance weights
//! (`1/d^2`, normalised) of the three nearest guide roots otherwise
//! ([`RenderHair::nearest`]).
//!
//! The shape is blended in the guides' root frames, not in world space: a
//! guide's root frame turns its root tangent onto the weighted mean root
//! tangent `e` (the smallest rotation that does it), and the strand is
//!
//! `p(u) = root + sum_k w_k R_k (g_k(u) - g_k(0))`
//!
//! with `u` the fraction of the strand (0 at the root, 1 at the tip) and
//! `R_k` that rotation. Three guides with the same curl on a curved scalp
//! give a render strand with that curl; blending their world positions
//! would average curls turned against each other and shrink them. A strand
//! rooted on a guide's root, with weight 1 on it, is that guide.
//!
//! Optional per strand: clumping toward the nearest guide (growing from
//! root to tip), a small random lean (deterministic for a seed), and the
//! strand's own detail when the source had render strands (its offset from
//! the interpolation at rest, carried in the blended root frame).

use crate::{Attribute, AttributeValues, Groom, Scope};

use crate::math::single::{add, cross, dot, scale, sub, try_normalize as normalize, V3};

/// The smallest rotation taking unit vector `from` onto unit vector `to`.
#[derive(Debug, Clone, Copy)]
struct MinimalRotation {
    axis: V3,
    /// 1 / (1 + cos angle); 0 when `from == to`.
    k: f32,
    /// A half turn about a perpendicular axis (opposite vectors).
    flip: Option<V3>,
}

impl MinimalRotation {
    fn new(from: V3, to: V3) -> MinimalRotation {
        let c = dot(from, to);
        if c < -0.999_999 {
            // Any axis perpendicular to `from` will do; take the most stable.
            let other = if from[0].abs() < 0.6 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let flip = normalize(cross(from, other)).unwrap_or([0.0, 0.0, 1.0]);
            return MinimalRotation {
                axis: [0.0; 3],
                k: 0.0,
                flip: Some(flip),
            };
        }
        MinimalRotation {
            axis: cross(from, to),
            k: 1.0 / (1.0 + c),
            flip: None,
        }
    }

    /// `R v = v + w x v + w x (w x v) / (1 + c)`, `w = from x to`.
    fn apply(&self, v: V3) -> V3 {
        if let Some(n) = self.flip {
            // Half turn: 2 (n.v) n - v.
            return sub(scale(n, 2.0 * dot(n, v)), v);
        }
        let wv = cross(self.axis, v);
        add(add(v, wv), scale(cross(self.axis, wv), self.k))
    }
}

/// Orthonormal axes (x, root tangent, z) of a render strand's root, if
/// its guides give one.
type Frame3 = Option<[V3; 3]>;

/// The axes of space, a frame that turns nothing.
const IDENTITY: [V3; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Render strands interpolated per parallel task: enough to outweigh a
/// task's cost, few enough that the cores share even a thousand strands.
const STRANDS_PER_RUN: usize = 256;

/// The guides of one pose, as render strands read them.
struct Guides<'a> {
    points: &'a [V3],
    /// Where each guide's points start (and the end).
    offsets: Vec<usize>,
    /// Each guide's unit root tangent.
    directions: Vec<V3>,
}

impl<'a> Guides<'a> {
    fn new(counts: &[u32], points: &'a [V3]) -> Guides<'a> {
        let (offsets, directions) = roots_and_directions(counts, points);
        Guides {
            points,
            offsets,
            directions,
        }
    }

    /// Guide `g`'s root (the origin when the pose lacks it).
    fn root(&self, g: usize) -> V3 {
        self.points
            .get(self.offsets[g])
            .copied()
            .unwrap_or([0.0; 3])
    }

    /// Guide `g`'s points (none when the pose lacks them).
    fn strand(&self, g: usize) -> &[V3] {
        self.points
            .get(self.offsets[g]..self.offsets[g + 1])
            .unwrap_or(&[])
    }
}

/// The rotation of a render strand's root from rest to now.
enum Turn {
    /// From the rest frame to the current one.
    Frames([V3; 3], [V3; 3]),
    /// The smallest rotation of the root tangent, when there is no frame.
    Minimal(MinimalRotation),
}

impl Turn {
    /// From the frames where both exist, else from the root tangents.
    fn new(rest: (Frame3, V3), now: (Frame3, V3)) -> Turn {
        match (rest, now) {
            ((Some(rest), _), (Some(now), _)) => Turn::Frames(rest, now),
            ((_, from), (_, to)) => Turn::Minimal(MinimalRotation::new(from, to)),
        }
    }

    fn apply(&self, v: V3) -> V3 {
        match self {
            Turn::Frames(rest, now) => {
                let local = [dot(v, rest[0]), dot(v, rest[1]), dot(v, rest[2])];
                add(
                    add(scale(now[0], local[0]), scale(now[1], local[1])),
                    scale(now[2], local[2]),
                )
            }
            Turn::Minimal(rotation) => rotation.apply(v),
        }
    }
}

/// Options of the interpolation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InterpolationOptions {
    /// Pull toward the nearest guide at the tip, 0..=1 (0 at the root,
    /// growing linearly to this value at the tip).
    pub clump: f32,
    /// Largest random lean at the tip, in the groom's length unit.
    pub noise: f32,
    /// Seed of the lean.
    pub seed: u64,
}

/// How render strands follow the guides; see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderHair {
    /// Per render strand: the guide indices it follows, nearest first.
    pub closest: Vec<[u32; 3]>,
    /// Per render strand: the weights of those guides (sum 1).
    pub weights: Vec<[f32; 3]>,
    /// Per render strand: its vertex count.
    pub counts: Vec<u32>,
    /// Offset of the root from the weighted guide roots at rest (zero when
    /// the root lies in the guides' root triangle).
    root_offsets: Vec<V3>,
    /// The render strand's root frame at rest (see [`RenderHair::frame`])
    /// and its weighted root tangent.
    rest_frames: Vec<(Frame3, V3)>,
    /// The frame of its guides' roots at rest (see
    /// [`RenderHair::scalp_frame`]): the root offset moves with the scalp
    /// only, never with the guides' root tangents, so a root stays on the
    /// scalp however its guides bend at their roots.
    rest_scalp_frames: Vec<Frame3>,
    /// Per render strand: the lean at the tip at rest.
    leans: Vec<V3>,
    /// Per render vertex: the strand's own shape beyond the interpolation
    /// at rest (empty when there is none).
    details: Vec<V3>,
    clump: f32,
    /// Per render strand: its root's UV on the scalp mesh it was grown on
    /// (`None`: the nearest guide's `root_uv`, if any, is kept).
    root_uvs: Option<Vec<[f32; 2]>>,
}

/// SplitMix64: a fixed stream, the same on every platform.
struct SplitMix(u64);
impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Roots and unit root tangents of every strand of a pose.
fn roots_and_directions(counts: &[u32], points: &[V3]) -> (Vec<usize>, Vec<V3>) {
    let mut offsets = Vec::with_capacity(counts.len() + 1);
    let mut directions = Vec::with_capacity(counts.len());
    let mut start = 0usize;
    for &n in counts {
        offsets.push(start);
        let root = points.get(start).copied().unwrap_or([0.0; 3]);
        let next = if n >= 2 {
            points.get(start + 1).copied().unwrap_or(root)
        } else {
            root
        };
        directions.push(normalize(sub(next, root)).unwrap_or([0.0, 1.0, 0.0]));
        start += n as usize;
    }
    offsets.push(start);
    (offsets, directions)
}

/// Every guide's root, as [`Guides::root`] reads it.
fn guide_roots(guides: &Groom) -> Vec<V3> {
    let pose = Guides::new(&guides.strand_vertex_counts, &guides.points);
    (0..guides.strand_count()).map(|g| pose.root(g)).collect()
}

/// Point at fraction `u` of a strand (by vertex index).
fn sample(strand: &[V3], u: f32) -> V3 {
    match strand.len() {
        0 => [0.0; 3],
        1 => strand[0],
        n => {
            let f = u.clamp(0.0, 1.0) * (n - 1) as f32;
            let i = (f.floor() as usize).min(n - 2);
            let t = f - i as f32;
            add(strand[i], scale(sub(strand[i + 1], strand[i]), t))
        }
    }
}

/// Indices and squared distances of the three nearest of `roots` to `p`
/// (fewer when there are fewer roots), nearest first; ties by index.
fn three_nearest(roots: &[V3], p: V3, skip: Option<usize>) -> Vec<(usize, f32)> {
    let mut best: Vec<(usize, f32)> = Vec::with_capacity(4);
    for (i, &r) in roots.iter().enumerate() {
        if Some(i) == skip {
            continue;
        }
        let d = sub(r, p);
        let d2 = dot(d, d);
        if best.len() < 3 || d2 < best[best.len() - 1].1 {
            let at = best.iter().position(|&(_, b)| d2 < b).unwrap_or(best.len());
            best.insert(at, (i, d2));
            best.truncate(3);
        }
    }
    best
}

/// Inverse-square-distance weights (normalised); a root on a guide root
/// takes that guide alone.
fn inverse_distance(nearest: &[(usize, f32)]) -> ([u32; 3], [f32; 3]) {
    let mut closest = [0u32; 3];
    let mut weights = [0.0f32; 3];
    if let Some(&(i, d2)) = nearest.first() {
        if d2 <= 1e-24 {
            return ([i as u32; 3], [1.0, 0.0, 0.0]);
        }
    }
    let mut total = 0.0f32;
    for (k, &(i, d2)) in nearest.iter().enumerate() {
        closest[k] = i as u32;
        weights[k] = 1.0 / d2;
        total += weights[k];
    }
    for k in nearest.len()..3 {
        closest[k] = closest[0];
    }
    for w in &mut weights {
        *w /= total;
    }
    (closest, weights)
}

impl RenderHair {
    /// Render strands rooted at `roots` (same space as `guides`), each
    /// following its three nearest guide roots with inverse-distance
    /// weights, with `counts` vertices each.
    pub fn nearest(
        guides: &Groom,
        roots: &[V3],
        counts: Vec<u32>,
        options: InterpolationOptions,
    ) -> RenderHair {
        let guide_roots = guide_roots(guides);
        let (closest, weights): (Vec<_>, Vec<_>) = roots
            .iter()
            .map(|&p| inverse_distance(&three_nearest(&guide_roots, p, None)))
            .unzip();
        Self::linked(guides, roots, closest, weights, counts, options)
    }

    /// Render strands scattered inside the triangles of guide roots:
    /// each picks a guide (uniformly) and its two nearest neighbours, and
    /// a uniform point of that triangle; the barycentric coordinates are
    /// its weights. It gets the picked guide's vertex count.
    pub fn grow(guides: &Groom, count: usize, options: InterpolationOptions) -> RenderHair {
        let g = guides.strand_count();
        let guide_roots = guide_roots(guides);
        let neighbours: Vec<Vec<(usize, f32)>> = (0..g)
            .map(|i| three_nearest(&guide_roots, guide_roots[i], Some(i)))
            .collect();
        let mut rng = SplitMix(options.seed ^ 0x6775_6964_6573);
        let mut roots = Vec::with_capacity(count);
        let mut closest = Vec::with_capacity(count);
        let mut weights = Vec::with_capacity(count);
        let mut counts = Vec::with_capacity(count);
        for _ in 0..count {
            if g == 0 {
                break;
            }
            let a = ((rng.next() >> 11) % g as u64) as usize;
            let near = &neighbours[a];
            let b = near.first().map_or(a, |n| n.0);
            let c = near.get(1).map_or(b, |n| n.0);
            // Uniform in the triangle: sqrt warps the first coordinate.
            let (r1, r2) = (rng.unit().sqrt(), rng.unit());
            let w = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
            let root = add(
                add(scale(guide_roots[a], w[0]), scale(guide_roots[b], w[1])),
                scale(guide_roots[c], w[2]),
            );
            // Nearest first: order the corners by weight (stable on ties).
            let mut corners = [(a, w[0]), (b, w[1]), (c, w[2])];
            corners.sort_by(|x, y| y.1.total_cmp(&x.1));
            roots.push(root);
            closest.push(corners.map(|(i, _)| i as u32));
            weights.push(corners.map(|(_, w)| w));
            counts.push(guides.strand_vertex_counts[a]);
        }
        Self::linked(guides, &roots, closest, weights, counts, options)
    }

    /// Render strands with given guides and weights (guide indices).
    /// Indices out of range are taken as guide 0.
    pub fn linked(
        guides: &Groom,
        roots: &[V3],
        closest: Vec<[u32; 3]>,
        weights: Vec<[f32; 3]>,
        counts: Vec<u32>,
        options: InterpolationOptions,
    ) -> RenderHair {
        let g = guides.strand_count() as u32;
        let closest: Vec<[u32; 3]> = closest
            .into_iter()
            .map(|c| c.map(|i| if i < g { i } else { 0 }))
            .collect();
        let pose = Guides::new(&guides.strand_vertex_counts, &guides.points);
        let mut rng = SplitMix(options.seed ^ 0x006e_6f69_7365);
        let mut hair = RenderHair {
            closest,
            weights,
            counts,
            root_offsets: Vec::with_capacity(roots.len()),
            rest_frames: Vec::with_capacity(roots.len()),
            rest_scalp_frames: Vec::with_capacity(roots.len()),
            leans: Vec::with_capacity(roots.len()),
            details: Vec::new(),
            clump: options.clump.clamp(0.0, 1.0),
            root_uvs: None,
        };
        for (r, &root) in roots.iter().enumerate() {
            let (blended_root, direction) = hair.blend_roots(r, &pose);
            hair.root_offsets.push(sub(root, blended_root));
            hair.rest_frames
                .push((hair.frame(r, &pose, direction), direction));
            hair.rest_scalp_frames.push(hair.scalp_frame(r, &pose));
            let lean = if options.noise > 0.0 {
                // A random direction across the root tangent, random length.
                let v = [rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5];
                let across = sub(v, scale(direction, dot(v, direction)));
                normalize(across).map_or([0.0; 3], |a| scale(a, options.noise * rng.unit()))
            } else {
                [0.0; 3]
            };
            hair.leans.push(lean);
        }
        hair
    }

    /// Keeps each render strand's own shape: `rest` holds the render
    /// strands (same counts) as the source had them, in the space of the
    /// guides given to the constructor.
    pub fn with_detail(mut self, guides: &Groom, rest: &[V3]) -> RenderHair {
        let interpolated = self.evaluate_plain(&guides.strand_vertex_counts, &guides.points);
        if interpolated.len() != rest.len() {
            return self;
        }
        self.details = rest
            .iter()
            .zip(&interpolated)
            .map(|(&a, &b)| sub(a, b))
            .collect();
        self
    }

    /// Gives each render strand its own `root_uv` (one per strand, as the
    /// roots were given; ignored otherwise).
    pub fn with_root_uvs(mut self, uvs: Vec<[f32; 2]>) -> RenderHair {
        if uvs.len() == self.counts.len() {
            self.root_uvs = Some(uvs);
        }
        self
    }

    pub fn strand_count(&self) -> usize {
        self.counts.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.counts.iter().map(|&c| c as usize).sum()
    }

    /// The render strand's root frame: the weighted root tangent, and
    /// across it the direction from its nearest guide's root to the next
    /// one's (which turns with the scalp); `None` when the guides do not
    /// span one (a strand on a single guide).
    fn frame(&self, r: usize, guides: &Guides<'_>, direction: V3) -> Frame3 {
        let [a, b, c] = self.closest[r];
        let root = |g: u32| guides.root(g as usize);
        let across = [b, c].into_iter().find_map(|other| {
            let v = sub(root(other), root(a));
            normalize(sub(v, scale(direction, dot(v, direction))))
        });
        across.map(|x| [x, direction, cross(x, direction)])
    }

    /// The frame of the roots of a render strand's three guides: from the
    /// first to the second, and the normal of their triangle; `None` when
    /// they span no triangle (then the offset is only translated).
    fn scalp_frame(&self, r: usize, guides: &Guides<'_>) -> Frame3 {
        let [a, b, c] = self.closest[r].map(|g| guides.root(g as usize));
        let x = normalize(sub(b, a))?;
        let n = normalize(cross(sub(b, a), sub(c, a)))?;
        Some([x, n, cross(x, n)])
    }

    /// Weighted guide roots and the normalised weighted root tangent.
    fn blend_roots(&self, r: usize, guides: &Guides<'_>) -> (V3, V3) {
        let mut root = [0.0; 3];
        let mut direction = [0.0; 3];
        for (&g, &w) in self.closest[r].iter().zip(&self.weights[r]) {
            let g = g as usize;
            root = add(root, scale(guides.root(g), w));
            direction = add(direction, scale(guides.directions[g], w));
        }
        let first = guides.directions[self.closest[r][0] as usize];
        (root, normalize(direction).unwrap_or(first))
    }

    fn evaluate_plain(&self, guide_counts: &[u32], guide_points: &[V3]) -> Vec<V3> {
        let plain = RenderHair {
            details: Vec::new(),
            ..self.clone()
        };
        plain.points(guide_counts, guide_points)
    }

    /// The render strands' points for a pose of the guides (`guide_counts`
    /// as the guides the hair was built from). The strands are
    /// interpolated in parallel in fixed runs, each exactly as alone, so
    /// the points do not depend on the thread count.
    pub fn points(&self, guide_counts: &[u32], guide_points: &[V3]) -> Vec<V3> {
        use rayon::prelude::*;
        if guide_counts.is_empty() {
            return Vec::new();
        }
        let guides = Guides::new(guide_counts, guide_points);
        let mut out = vec![[0.0; 3]; self.vertex_count()];
        // Each run's strands, its first vertex and its slice of `out`.
        let mut runs = Vec::with_capacity(self.counts.len().div_ceil(STRANDS_PER_RUN));
        let mut rest = out.as_mut_slice();
        let mut first_vertex = 0;
        for (run, counts) in self.counts.chunks(STRANDS_PER_RUN).enumerate() {
            let size: usize = counts.iter().map(|&c| c as usize).sum();
            let (mine, tail) = std::mem::take(&mut rest).split_at_mut(size);
            rest = tail;
            runs.push((run * STRANDS_PER_RUN, first_vertex, mine));
            first_vertex += size;
        }
        runs.into_par_iter()
            .for_each(|(first_strand, mut vertex, run_out)| {
                let mut at = 0;
                let last = (first_strand + STRANDS_PER_RUN).min(self.counts.len());
                for r in first_strand..last {
                    let n = self.counts[r] as usize;
                    self.strand_points(r, &guides, vertex, &mut run_out[at..at + n]);
                    at += n;
                    vertex += n;
                }
            });
        out
    }

    /// Render strand `r`'s points into `out`, its first vertex being
    /// `first_vertex` of all (where its details start).
    fn strand_points(&self, r: usize, guides: &Guides<'_>, first_vertex: usize, out: &mut [V3]) {
        let (blended_root, direction) = self.blend_roots(r, guides);
        // The render strand's frame turns with its guides.
        let turn = Turn::new(
            self.rest_frames[r],
            (self.frame(r, guides, direction), direction),
        );
        let scalp_turn = match (self.rest_scalp_frames[r], self.scalp_frame(r, guides)) {
            (Some(rest), Some(now)) => Turn::Frames(rest, now),
            _ => Turn::Frames(IDENTITY, IDENTITY),
        };
        let root = add(blended_root, scalp_turn.apply(self.root_offsets[r]));
        let lean = turn.apply(self.leans[r]);
        let frames: [(usize, MinimalRotation, f32); 3] = std::array::from_fn(|k| {
            let g = self.closest[r][k] as usize;
            (
                g,
                MinimalRotation::new(guides.directions[g], direction),
                self.weights[r][k],
            )
        });
        let n = out.len();
        for (i, point) in out.iter_mut().enumerate() {
            let u = if n > 1 {
                i as f32 / (n - 1) as f32
            } else {
                0.0
            };
            let mut local = [0.0; 3];
            for &(g, rotation, w) in &frames {
                let s = guides.strand(g);
                let from_root = sub(sample(s, u), s.first().copied().unwrap_or([0.0; 3]));
                local = add(local, scale(rotation.apply(from_root), w));
            }
            if self.clump > 0.0 {
                let (g, rotation, _) = frames[0];
                let s = guides.strand(g);
                let own = rotation.apply(sub(sample(s, u), s.first().copied().unwrap_or([0.0; 3])));
                local = add(local, scale(sub(own, local), self.clump * u));
            }
            local = add(local, scale(lean, u));
            if let Some(&d) = self.details.get(first_vertex + i) {
                local = add(local, turn.apply(d));
            }
            *point = add(root, local);
        }
    }

    /// The render strands as a groom for a pose of `guides`: their points,
    /// and every guide attribute taken from the strand's nearest guide (a
    /// vertex attribute at the same fraction of the strand).
    pub fn groom(&self, guides: &Groom) -> Groom {
        let points = self.points(&guides.strand_vertex_counts, &guides.points);
        let mut out = Groom {
            strand_vertex_counts: self.counts.clone(),
            points,
            attributes: Vec::new(),
            frames: Vec::new(),
            units: guides.units,
            up_axis: guides.up_axis,
            basis: guides.basis,
            provenance: guides.provenance.clone(),
        };
        let offsets = guides.strand_offsets();
        let nearest: Vec<usize> = self.closest.iter().map(|c| c[0] as usize).collect();
        // Per render vertex: the nearest guide's vertex at the same fraction.
        let mut vertex_source = Vec::with_capacity(out.points.len());
        for (r, &n) in self.counts.iter().enumerate() {
            let g = nearest[r];
            let m = offsets[g + 1] - offsets[g];
            for i in 0..n as usize {
                let u = if n > 1 {
                    i as f32 / (n - 1) as f32
                } else {
                    0.0
                };
                let j = (u * m.saturating_sub(1) as f32).round() as usize;
                vertex_source.push(offsets[g] + j.min(m.saturating_sub(1)));
            }
        }
        for a in &guides.attributes {
            let source = match a.scope {
                Scope::Strand => &nearest,
                Scope::Vertex => &vertex_source,
            };
            if let Some(values) = pick(&a.values, source) {
                out.attributes.push(Attribute {
                    name: a.name.clone(),
                    scope: a.scope,
                    values,
                });
            }
        }
        if let Some(uvs) = &self.root_uvs {
            out.attributes.retain(|a| a.name != ROOT_UV);
            out.attributes.push(Attribute {
                name: ROOT_UV.into(),
                scope: Scope::Strand,
                values: AttributeValues::Vec2(uvs.clone()),
            });
        }
        out
    }

    /// Guides and render strands in one groom with the Unreal attributes
    /// (see [`crate::guides::join`]).
    pub fn joined(&self, guides: &Groom) -> Groom {
        crate::guides::join(guides, &self.groom(guides), &self.closest, &self.weights)
    }

    /// The points of [`RenderHair::joined`] for a pose of the guides.
    pub fn joined_points(&self, guide_counts: &[u32], guide_points: &[V3]) -> Vec<V3> {
        let mut points = guide_points.to_vec();
        points.extend(self.points(guide_counts, guide_points));
        points
    }
}

/// The per-strand attribute the exporters write as the strands' UVs.
const ROOT_UV: &str = "root_uv";

fn pick(values: &AttributeValues, source: &[usize]) -> Option<AttributeValues> {
    fn take<T: Copy>(v: &[T], source: &[usize]) -> Option<Vec<T>> {
        source.iter().map(|&i| v.get(i).copied()).collect()
    }
    Some(match values {
        AttributeValues::Float(v) => AttributeValues::Float(take(v, source)?),
        AttributeValues::Vec2(v) => AttributeValues::Vec2(take(v, source)?),
        AttributeValues::Vec3(v) => AttributeValues::Vec3(take(v, source)?),
        AttributeValues::Int(v) => AttributeValues::Int(take(v, source)?),
    })
}

#[cfg(test)]
mod tests;
