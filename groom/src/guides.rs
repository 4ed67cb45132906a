//! Guides and render hair in one groom.
//!
//! A groom may hold two kinds of strands: *guides*, which the solver
//! simulates, and *render* strands, which are interpolated from the guides
//! (see [`crate::interpolate`]). The split is the per-strand attribute
//! [`GROOM_GUIDE`] (1 = guide, 0 = render), the convention of Unreal
//! Engine's groom importer, which also names the other attributes here.
//! A groom without that attribute is all guides.

use crate::{Attribute, AttributeValues, Frame, Groom, Scope};

/// Per strand, int: 1 for a guide, 0 for a render strand.
pub const GROOM_GUIDE: &str = "groom_guide";
/// Per strand, int: the strand's id. Guides are numbered first, so a
/// guide's id is its index among the guides.
pub const GROOM_ID: &str = "groom_id";
/// Per strand, int: the group a strand belongs to.
pub const GROOM_GROUP_ID: &str = "groom_group_id";
/// Per strand, three ints: the ids of the three guides a render strand
/// follows. Held as a vec3 inside groombake (ids below 2^24 are exact in
/// f32); the Alembic writer stores it as `int32[3]`, as Unreal reads it.
pub const GROOM_CLOSEST_GUIDES: &str = "groom_closest_guides";
/// Per strand, three floats: the weights of those guides (sum 1).
pub const GROOM_GUIDE_WEIGHTS: &str = "groom_guide_weights";

impl Groom {
    /// Per strand, whether it is a guide; `None` when the groom does not
    /// say (no per-strand `groom_guide`, or one of the wrong length).
    pub fn guide_flags(&self) -> Option<Vec<bool>> {
        let attribute = self.attribute(GROOM_GUIDE)?;
        if attribute.scope != Scope::Strand || attribute.values.len() != self.strand_count() {
            return None;
        }
        Some(match &attribute.values {
            AttributeValues::Int(v) => v.iter().map(|&x| x != 0).collect(),
            AttributeValues::Float(v) => v.iter().map(|&x| x != 0.0).collect(),
            _ => return None,
        })
    }

    /// Whether the groom holds both guides and render strands.
    pub fn has_render_split(&self) -> bool {
        self.guide_flags()
            .is_some_and(|f| f.iter().any(|&g| g) && f.iter().any(|&g| !g))
    }

    /// The strands at `indices` (in that order) with their attributes and
    /// frames. Indices out of range are skipped.
    pub fn subset(&self, indices: &[usize]) -> Groom {
        let offsets = self.strand_offsets();
        let strands = self.strand_count();
        let kept: Vec<usize> = indices
            .iter()
            .copied()
            .filter(|&i| i < strands && offsets[i + 1] <= self.points.len())
            .collect();
        self.select_strands(&kept)
    }

    /// The guides and the render strands as two grooms, with the strand
    /// indices each came from; `None` when the groom has no split.
    pub fn split_guides(&self) -> Option<SplitGroom> {
        let flags = self.guide_flags()?;
        let guide_indices: Vec<usize> = (0..flags.len()).filter(|&i| flags[i]).collect();
        let render_indices: Vec<usize> = (0..flags.len()).filter(|&i| !flags[i]).collect();
        Some(SplitGroom {
            guides: self.subset(&guide_indices),
            render: self.subset(&render_indices),
            guide_indices,
            render_indices,
        })
    }
}

/// A groom taken apart into guides and render strands.
#[derive(Debug, Clone)]
pub struct SplitGroom {
    pub guides: Groom,
    pub render: Groom,
    pub guide_indices: Vec<usize>,
    pub render_indices: Vec<usize>,
}

/// The root (first point) of every strand; `[0; 3]` for an empty strand.
pub fn roots(groom: &Groom) -> Vec<[f32; 3]> {
    let offsets = groom.strand_offsets();
    (0..groom.strand_count())
        .map(|i| {
            if offsets[i + 1] > offsets[i] {
                groom.points.get(offsets[i]).copied().unwrap_or([0.0; 3])
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

fn distance2(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// `count` strands spread evenly over the roots: farthest-point sampling
/// from the root nearest the roots' centre (ties by index). Returns sorted
/// strand indices. Costs `count x roots` distance evaluations.
pub fn pick_spread(roots: &[[f32; 3]], count: usize) -> Vec<usize> {
    let n = roots.len();
    if count >= n {
        return (0..n).collect();
    }
    if count == 0 {
        return Vec::new();
    }
    let mut centre = [0.0f64; 3];
    for r in roots {
        for c in 0..3 {
            centre[c] += f64::from(r[c]) / n as f64;
        }
    }
    let centre = centre.map(|c| c as f32);
    let first = (0..n)
        .min_by(|&a, &b| distance2(roots[a], centre).total_cmp(&distance2(roots[b], centre)))
        .unwrap_or(0);
    let mut nearest: Vec<f32> = roots.iter().map(|&r| distance2(r, roots[first])).collect();
    let mut picked = vec![first];
    while picked.len() < count {
        let next = (0..n)
            .max_by(|&a, &b| nearest[a].total_cmp(&nearest[b]).then(b.cmp(&a)))
            .unwrap_or(0);
        picked.push(next);
        for (d, &r) in nearest.iter_mut().zip(roots) {
            *d = d.min(distance2(r, roots[next]));
        }
    }
    picked.sort_unstable();
    picked
}

/// Every `every`-th strand in the order of a Z-curve over the roots'
/// bounds (so neighbours on the scalp are neighbours in the order, and the
/// picks are spread whatever the file's order). Sorted strand indices.
pub fn pick_every(roots: &[[f32; 3]], every: usize) -> Vec<usize> {
    let every = every.max(1);
    let Some((min, max)) = crate::bounds_of(roots) else {
        return Vec::new();
    };
    let cell = |r: [f32; 3], c: usize| -> u64 {
        let extent = max[c] - min[c];
        if extent > 0.0 {
            (((r[c] - min[c]) / extent) * 1023.0)
                .round()
                .clamp(0.0, 1023.0) as u64
        } else {
            0
        }
    };
    let morton = |r: [f32; 3]| -> u64 {
        let mut code = 0u64;
        for bit in 0..10 {
            for c in 0..3 {
                code |= ((cell(r, c) >> bit) & 1) << (3 * bit + c);
            }
        }
        code
    };
    let mut order: Vec<usize> = (0..roots.len()).collect();
    order.sort_by_key(|&i| (morton(roots[i]), i));
    let mut picked: Vec<usize> = order.into_iter().step_by(every).collect();
    picked.sort_unstable();
    picked
}

/// Guides then render strands as one groom, with the Unreal attributes
/// ([`GROOM_GUIDE`], [`GROOM_ID`], [`GROOM_GROUP_ID`]) set. Attributes
/// the two share (same name, scope and type) are joined; one only a part
/// has is filled with zeros in the other. `closest` and `weights` (one per
/// render strand, guide indices) become [`GROOM_CLOSEST_GUIDES`] and
/// [`GROOM_GUIDE_WEIGHTS`]; a guide follows itself with weight 1.
pub fn join(guides: &Groom, render: &Groom, closest: &[[u32; 3]], weights: &[[f32; 3]]) -> Groom {
    let g = guides.strand_count();
    let r = render.strand_count();
    let mut out = guides.clone();
    out.strand_vertex_counts
        .extend_from_slice(&render.strand_vertex_counts);
    out.points.extend_from_slice(&render.points);
    out.frames.clear();
    if guides.frames.len() == render.frames.len() {
        out.frames = guides
            .frames
            .iter()
            .zip(&render.frames)
            .map(|(a, b)| Frame {
                time: a.time,
                points: a.points.iter().chain(&b.points).copied().collect(),
                attributes: Vec::new(),
            })
            .collect();
    }
    let sizes = |scope: Scope| match scope {
        Scope::Strand => (g, r),
        Scope::Vertex => (guides.vertex_count(), render.vertex_count()),
    };
    let mut attributes = Vec::new();
    for a in &guides.attributes {
        let (_, render_len) = sizes(a.scope);
        let tail = render
            .attribute(&a.name)
            .filter(|b| b.scope == a.scope && b.values.len() == render_len)
            .map(|b| b.values.clone());
        if let Some(values) = concat(&a.values, tail.as_ref(), render_len) {
            attributes.push(Attribute {
                name: a.name.clone(),
                scope: a.scope,
                values,
            });
        }
    }
    for b in &render.attributes {
        if guides.attribute(&b.name).is_none() {
            let (guide_len, _) = sizes(b.scope);
            let head = zeros_like(&b.values, guide_len);
            if let Some(values) = concat(&head, Some(&b.values), b.values.len()) {
                attributes.push(Attribute {
                    name: b.name.clone(),
                    scope: b.scope,
                    values,
                });
            }
        }
    }
    out.attributes = attributes;
    let ids: Vec<i32> = (0..(g + r) as i32).collect();
    let flags: Vec<i32> = (0..g + r).map(|i| i32::from(i < g)).collect();
    out.set_attribute(Attribute::per_strand(
        GROOM_GUIDE,
        AttributeValues::Int(flags),
    ));
    out.set_attribute(Attribute::per_strand(GROOM_ID, AttributeValues::Int(ids)));
    if out.attribute(GROOM_GROUP_ID).is_none() {
        out.set_attribute(Attribute::per_strand(
            GROOM_GROUP_ID,
            AttributeValues::Int(vec![0; g + r]),
        ));
    }
    let mut closest_all: Vec<[f32; 3]> = (0..g).map(|i| [i as f32; 3]).collect();
    let mut weights_all: Vec<[f32; 3]> = vec![[1.0, 0.0, 0.0]; g];
    for k in 0..r {
        let c = closest.get(k).copied().unwrap_or([0; 3]);
        closest_all.push(c.map(|i| i as f32));
        weights_all.push(weights.get(k).copied().unwrap_or([1.0, 0.0, 0.0]));
    }
    out.set_attribute(Attribute::per_strand(
        GROOM_CLOSEST_GUIDES,
        AttributeValues::Vec3(closest_all),
    ));
    out.set_attribute(Attribute::per_strand(
        GROOM_GUIDE_WEIGHTS,
        AttributeValues::Vec3(weights_all),
    ));
    out
}

fn zeros_like(values: &AttributeValues, len: usize) -> AttributeValues {
    match values {
        AttributeValues::Float(_) => AttributeValues::Float(vec![0.0; len]),
        AttributeValues::Vec2(_) => AttributeValues::Vec2(vec![[0.0; 2]; len]),
        AttributeValues::Vec3(_) => AttributeValues::Vec3(vec![[0.0; 3]; len]),
        AttributeValues::Int(_) => AttributeValues::Int(vec![0; len]),
    }
}

/// `head` followed by `tail` (or zeros when the tail is missing or of
/// another type).
fn concat(
    head: &AttributeValues,
    tail: Option<&AttributeValues>,
    tail_len: usize,
) -> Option<AttributeValues> {
    let zeros = zeros_like(head, tail_len);
    let tail = match tail {
        Some(t) if std::mem::discriminant(t) == std::mem::discriminant(head) => t,
        _ => &zeros,
    };
    Some(match (head, tail) {
        (AttributeValues::Float(a), AttributeValues::Float(b)) => {
            AttributeValues::Float([a.as_slice(), b].concat())
        }
        (AttributeValues::Vec2(a), AttributeValues::Vec2(b)) => {
            AttributeValues::Vec2([a.as_slice(), b].concat())
        }
        (AttributeValues::Vec3(a), AttributeValues::Vec3(b)) => {
            AttributeValues::Vec3([a.as_slice(), b].concat())
        }
        (AttributeValues::Int(a), AttributeValues::Int(b)) => {
            AttributeValues::Int([a.as_slice(), b].concat())
        }
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strands(n: usize, x0: f32) -> Groom {
        Groom::from_strands(
            (0..n).map(|i| vec![[x0 + i as f32, 0.0, 0.0], [x0 + i as f32, 1.0, 0.0]]),
        )
    }

    #[test]
    fn join_then_split_gives_the_parts_back() {
        let mut guides = strands(2, 0.0);
        guides.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float(vec![1.0, 2.0, 3.0, 4.0]),
        ));
        let render = strands(3, 10.0);
        let joined = join(
            &guides,
            &render,
            &[[0, 1, 0], [1, 0, 1], [0, 0, 1]],
            &[[0.5, 0.5, 0.0]; 3],
        );
        assert_eq!(joined.strand_count(), 5);
        assert!(joined.has_render_split());
        let split = joined.split_guides().unwrap();
        assert_eq!(split.guides.points, guides.points);
        assert_eq!(split.render.points, render.points);
        assert_eq!(split.render_indices, vec![2, 3, 4]);
        // The render part of a guide-only attribute is zero.
        assert_eq!(
            split.render.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.0; 6])
        );
        assert_eq!(
            joined.attribute(GROOM_CLOSEST_GUIDES).unwrap().values,
            AttributeValues::Vec3(vec![
                [0.0; 3],
                [1.0; 3],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 1.0],
                [0.0, 0.0, 1.0]
            ])
        );
    }

    #[test]
    fn picks_are_spread_and_deterministic() {
        let roots: Vec<[f32; 3]> = (0..100)
            .map(|i| [(i % 10) as f32, 0.0, (i / 10) as f32])
            .collect();
        let spread = pick_spread(&roots, 4);
        assert_eq!(spread.len(), 4);
        assert_eq!(spread, pick_spread(&roots, 4));
        // The four corners' quadrants each hold one pick.
        let quadrants: std::collections::BTreeSet<(bool, bool)> = spread
            .iter()
            .map(|&i| (roots[i][0] < 4.5, roots[i][2] < 4.5))
            .collect();
        assert_eq!(quadrants.len(), 4, "{spread:?}");
        let every = pick_every(&roots, 4);
        assert_eq!(every.len(), 25);
        let quadrants = every
            .iter()
            .filter(|&&i| roots[i][0] < 4.5 && roots[i][2] < 4.5)
            .count();
        assert!((5..=8).contains(&quadrants), "{quadrants}");
    }

    #[test]
    fn a_groom_without_the_attribute_has_no_split() {
        assert!(strands(3, 0.0).guide_flags().is_none());
        assert!(!strands(3, 0.0).has_render_split());
    }
}
