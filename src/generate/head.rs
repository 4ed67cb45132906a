//! The `head` layout put together: the scalp and its roots ([`super::scalp`]),
//! each strand's draws, combed line, curl and clump ([`super::comb`],
//! [`super::variation`]), kept off the head by [`super::CLEARANCE`].
//!
//! Strands are built in parallel, each from its own seeded stream, and
//! collected in root order: the groom is the same for any thread count.

use super::comb::{keep_off, Comb};
use super::scalp::{angles, Root, Scalp};
use super::variation::{self, ClumpIndex, Draw, STREAM_CLUMP, STREAM_STRAND};
use super::{GeneratorError, GeneratorParameters, SplitMix64, CLEARANCE};
use groom::math::double::{dot, V3};
use groom::{Attribute, AttributeValues, Groom};
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// The combed and curled line of one strand (before clumping).
fn line(p: &GeneratorParameters, scalp: &Scalp, comb: &Comb, root: &Root, d: &Draw) -> Vec<V3> {
    let (spine, lying_until) = comb.grow(scalp, root, d.edges, d.step, d.layer);
    if p.curl {
        variation::curl(&spine, d.step, lying_until, root.normal, d, p)
    } else {
        spine
    }
}

/// Clump centres: their strands (with their steps and curl phases), the
/// index of their roots and the comb's direction at each.
type Clumps = (Vec<(Vec<V3>, f64, f64)>, ClumpIndex, Vec<V3>);

fn clumps(
    p: &GeneratorParameters,
    scalp: &Scalp,
    comb: &Comb,
    area: f64,
    random: &mut SplitMix64,
) -> Option<Clumps> {
    if p.clump_size <= 0.0 || p.clump_strength <= 0.0 {
        return None;
    }
    let size = p.clump_size as f64;
    let count = ((area / (size * size)).round() as usize).clamp(1, p.strands);
    let (roots, _) = scalp.roots(count, random);
    let strands = roots
        .par_iter()
        .enumerate()
        .map(|(i, root)| {
            let d = variation::draw(p, STREAM_CLUMP, i);
            (line(p, scalp, comb, root, &d), d.step, d.curl_phase)
        })
        .collect();
    let index = ClumpIndex::new(roots.iter().map(|r| r.point).collect(), size);
    let directions = roots.iter().map(|r| comb.field(r.u)).collect();
    Some((strands, index, directions))
}

pub(super) fn generate_head(p: &GeneratorParameters) -> Result<Groom, GeneratorError> {
    let scalp = match &p.scalp_mesh {
        Some(path) => Scalp::mesh(path, p)?,
        None => Scalp::ellipsoid(p),
    };
    let comb = Comb::new(p, &scalp);
    let mut random = SplitMix64::new(p.seed);
    let (roots, area) = scalp.roots(p.strands, &mut random);
    let clumps = clumps(p, &scalp, &comb, area, &mut random);
    let strands: Vec<(Vec<[f32; 3]>, f32)> = roots
        .par_iter()
        .enumerate()
        .map(|(i, root)| {
            let mut d = variation::draw(p, STREAM_STRAND, i);
            // The nearest centre combed the same way: never one across the
            // parting (between the two, the clump would cut through the head).
            let along = comb.field(root.u);
            let centre = clumps.as_ref().and_then(|(centres, index, directions)| {
                let same_way = |j: usize| dot(directions[j], along) > 0.5;
                index.nearest(root.point, same_way).map(|j| &centres[j])
            });
            // A clump's curls turn together (ringlets): its strands take
            // its phase; `curl_phase_spread` varies it from clump to clump.
            if let Some((_, _, phase)) = centre {
                d.curl_phase = *phase;
            }
            let mut points = line(p, &scalp, &comb, root, &d);
            if let Some((centre, step, _)) = centre {
                variation::clump(&mut points, d.step, centre, *step, p);
            }
            keep_off(&scalp, &mut points, CLEARANCE as f64);
            (
                points.iter().map(|x| x.map(|c| c as f32)).collect(),
                d.width,
            )
        })
        .collect();
    let mut groom = super::empty_groom();
    let total: usize = strands.iter().map(|(s, _)| s.len()).sum();
    groom.points.reserve(total);
    let mut widths = Vec::with_capacity(total);
    for (points, width) in &strands {
        groom.points.extend_from_slice(points);
        widths.extend(std::iter::repeat_n(*width, points.len()));
        groom.strand_vertex_counts.push(points.len() as u32);
    }
    // The root's spherical coordinates on the head: azimuth from the front
    // in turns, polar angle from the top over pi.
    let root_uv = roots
        .iter()
        .map(|r| {
            let (polar, azimuth) = angles(r.u);
            [(azimuth.rem_euclid(TAU) / TAU) as f32, (polar / PI) as f32]
        })
        .collect();
    groom
        .attributes
        .push(Attribute::new("width", AttributeValues::Float(widths)));
    groom.attributes.push(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(root_uv),
    ));
    Ok(groom)
}
