//! glTF 2.0 (`.gltf` with embedded or external buffers, `.glb`). Strands are
//! read from `LINE_STRIP` primitives (one strand each) and `LINES`
//! primitives (consecutive segments that share an end vertex join into one
//! strand); other primitives (a head mesh, points) are skipped by [`read`]
//! and named in the groom's `provenance.losses`, as are animation channels
//! other than the strands' morph-target weights (`losses`);
//! [`read_triangles`] reads the triangle primitives instead, for colliders.
//! The scene graph's transforms are applied. Morph-target animation becomes
//! frames: frame k is the base pose plus the targets weighted by the k-th
//! keyframe of the `weights` sampler. `TEXCOORD_0` comes back as `root_uv`.
//! `_NAME` vertex attributes come back as attributes named `name` (lower
//! case), unless the accessor's `extras.groombake` (written by groombake's
//! exporter) gives the name, says the attribute is per strand (taken from
//! each strand's first vertex, if every strand's values agree), says float
//! or split values are 32-bit integers, or says which component of a
//! vector (or which half of an integer) the accessor holds.
//! glTF is metres and Y up.
//!
//! The parts: `document` turns bytes into a document whose every index
//! and enum is checked where it is used (the `gltf` crate's loader panics on
//! some bad ones), `accessors` reads accessor data checked against the
//! buffers, `scene` walks the node graph, `lines` and `triangles`
//! decode primitives, `animation` makes frames, and `stream` reads a
//! `.glb` a frame at a time for [`crate::stream`], reading only the morph
//! targets each frame weights ([`read_streamed_bytes`] reads that way from
//! memory).

mod accessors;
mod animation;
mod document;
mod lines;
mod losses;
mod scene;
mod stream;
#[cfg(test)]
mod tests;
mod triangles;

pub(crate) use stream::{GltfStream, Opened};

use crate::mesh_types::{Mesh, Triangles};
use crate::ImportError;
use animation::Piece;
use document::Document;
use gltf::json::validation::Checked;
use groom::{Attribute, AttributeValues, Groom, Units, UpAxis};
use lines::{Lines, Targets};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use triangles::{TrianglePrimitive, MAX_MESH_TRIANGLES, MAX_MESH_VERTICES};

/// The most points the groom may have once instanced meshes are expanded.
const MAX_GROOM_POINTS: usize = 1 << 26;

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let document = Document::load(path, bytes)?;
    let (decoded, pieces, skipped) = line_pieces(&document, Targets::Read)?;
    let mut groom = rest_groom(&document, &decoded, &pieces)?;
    groom.frames = document.frames(&decoded, &pieces)?;
    add_losses(&mut groom, &document, &pieces, &skipped);
    Ok(groom)
}

/// Reads a `.glb` from bytes in memory the way [`crate::stream`] reads one
/// from disk: its rest groom and frame times, then each frame alone, in
/// turn, reading only the morph targets it weights. `None` when such a
/// file is read whole (see [`crate::stream::FrameStream::open`]). For tests
/// and fuzzing of the frame-at-a-time path; `path` names the bytes in
/// errors.
pub fn read_streamed_bytes(path: &Path, bytes: &[u8]) -> Result<Option<Groom>, ImportError> {
    let Some(opened) = stream::GltfStream::open(path, bytes)? else {
        return Ok(None);
    };
    let mut groom = opened.groom;
    for index in 0..opened.times.len() {
        groom.frames.push(opened.stream.frame(path, bytes, index)?);
    }
    Ok(Some(groom))
}

/// The skipped primitives and unread animation channels, as losses.
fn add_losses(
    groom: &mut Groom,
    document: &Document,
    pieces: &[Piece],
    skipped: &[losses::Skipped],
) {
    groom.provenance.losses.extend(
        losses::skipped_primitives(skipped)
            .into_iter()
            .chain(document.unread_channels(pieces)),
    );
}

/// The groom of the scene's line pieces without frames or losses: points
/// in world coordinates, strand counts and attributes.
fn rest_groom(
    document: &Document,
    decoded: &[Lines],
    pieces: &[Piece],
) -> Result<Groom, ImportError> {
    let mut groom = Groom {
        units: Units::METERS,
        up_axis: UpAxis::Y,
        ..Groom::default()
    };
    let common = common_attributes(decoded, pieces);
    let per_strand: BTreeSet<String> = common
        .keys()
        .filter(|name| {
            pieces
                .iter()
                .all(|p| decoded[p.lines].per_strand.contains(*name))
        })
        .cloned()
        .collect();
    let mut attributes = common;
    for piece in pieces {
        let lines = &decoded[piece.lines];
        for strand in &lines.strands {
            groom.strand_vertex_counts.push(strand.len() as u32);
            for &i in strand {
                let p = lines.positions.get(i).copied().unwrap_or_default();
                let p = scene::transform(&piece.world, p);
                if p.iter().any(|c| !c.is_finite()) {
                    return Err(document.error(
                        format!("/nodes/{}", piece.node),
                        "the node's transform moves a point to a value that is not finite",
                    ));
                }
                groom.points.push(p);
            }
            for (name, values) in attributes.iter_mut() {
                if let Some(source) = lines.attributes.get(name) {
                    let selected = if per_strand.contains(name) {
                        &strand[..strand.len().min(1)]
                    } else {
                        strand
                    };
                    append_selected(values, source, selected);
                }
            }
        }
    }
    for (name, values) in attributes {
        groom.attributes.push(if per_strand.contains(&name) {
            Attribute::per_strand(name, values)
        } else {
            Attribute::new(name, values)
        });
    }
    groom.provenance.format = "gltf".into();
    Ok(groom)
}

/// Every line primitive of the scene decoded once, each of its instances
/// with its world matrix, and the scene's primitives that are not lines.
type LinePieces = (Vec<Lines>, Vec<Piece>, Vec<losses::Skipped>);

/// The scene's [`LinePieces`].
fn line_pieces(document: &Document, targets: Targets) -> Result<LinePieces, ImportError> {
    let mut pieces = Vec::new();
    let mut skipped = Vec::new();
    let mut points = 0usize;
    let decoded = scene::walk_primitives(
        document,
        |mesh_index, mesh, primitive_index, primitive| {
            let lines = document.lines(mesh_index, mesh, primitive_index, primitive, targets)?;
            if let (None, Checked::Valid(mode)) = (&lines, primitive.mode) {
                skipped.push(losses::Skipped {
                    mesh: mesh_index,
                    primitive: primitive_index,
                    mode,
                });
            }
            Ok(lines)
        },
        |node_index, world, slot, lines| {
            points += lines.point_count();
            if points > MAX_GROOM_POINTS {
                return Err(document.error(
                    format!("/nodes/{node_index}"),
                    format!(
                        "the scene's line primitives exceed {MAX_GROOM_POINTS} points \
                         (meshes instanced by many nodes?)"
                    ),
                ));
            }
            pieces.push(Piece {
                lines: slot,
                world,
                node: node_index,
            });
            Ok(())
        },
    )?;
    Ok((decoded, pieces, skipped))
}

/// Attributes every line primitive has, with the same type, empty.
fn common_attributes(decoded: &[Lines], pieces: &[Piece]) -> BTreeMap<String, AttributeValues> {
    let mut common: Option<BTreeMap<String, AttributeValues>> = None;
    for piece in pieces {
        let names: BTreeMap<String, AttributeValues> = decoded[piece.lines]
            .attributes
            .iter()
            .map(|(name, values)| (name.clone(), empty_like(values)))
            .collect();
        common = Some(match common {
            None => names,
            Some(so_far) => so_far
                .into_iter()
                .filter(|(name, values)| names.get(name).is_some_and(|v| same_type(v, values)))
                .collect(),
        });
    }
    common.unwrap_or_default()
}

/// Reads the triangles of every TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN
/// primitive of the scene's meshes, in world coordinates (node transforms
/// applied; a node that mirrors gets its triangles' winding reversed, as the
/// glTF specification asks, so they keep facing outwards). Line and point
/// primitives, morph targets and skins are ignored: a collider is rigid.
pub fn read_triangles(path: &Path) -> Result<Triangles, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse_triangles(path, &bytes)
}

/// [`read_triangles`] with corner UVs (see [`parse_mesh`]).
pub fn read_mesh(path: &Path) -> Result<Mesh, ImportError> {
    parse_mesh(path, &crate::read_bytes(path)?)
}

pub fn parse_triangles(path: &Path, bytes: &[u8]) -> Result<Triangles, ImportError> {
    let mesh = parse_mesh(path, bytes)?;
    Ok((mesh.vertices, mesh.triangles))
}

/// [`parse_triangles`] with the corner UVs of the triangles when every
/// triangle primitive has a float TEXCOORD_0 (V flipped back, as for
/// strands).
pub fn parse_mesh(path: &Path, bytes: &[u8]) -> Result<Mesh, ImportError> {
    let document = Document::load(path, bytes)?;
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut corner_uvs: Option<Vec<[[f32; 2]; 3]>> = Some(Vec::new());
    scene::walk_primitives(
        &document,
        |mesh_index, _, primitive_index, primitive| {
            document.triangles(mesh_index, primitive_index, primitive)
        },
        |node_index, world, _, primitive| {
            let TrianglePrimitive {
                positions,
                triangles: local_triangles,
                uvs,
            } = primitive;
            if vertices.len() + positions.len() > MAX_MESH_VERTICES
                || triangles.len() + local_triangles.len() > MAX_MESH_TRIANGLES
            {
                return Err(document.error(
                    format!("/nodes/{node_index}"),
                    format!(
                        "the scene's triangle meshes exceed {MAX_MESH_VERTICES} vertices or \
                         {MAX_MESH_TRIANGLES} triangles (meshes instanced by many nodes?)"
                    ),
                ));
            }
            // Both counts are bounded far below u32::MAX.
            let base = vertices.len() as u32;
            let mirrored = scene::determinant(&world) < 0.0;
            for &p in positions.iter() {
                let p = scene::transform(&world, p);
                if p.iter().any(|c| !c.is_finite()) {
                    return Err(document.error(
                        format!("/nodes/{node_index}"),
                        "the node's transform moves a vertex to a value that is not finite",
                    ));
                }
                vertices.push(p);
            }
            triangles.extend(local_triangles.iter().map(|&[a, b, c]| {
                if mirrored {
                    [base + a, base + c, base + b]
                } else {
                    [base + a, base + b, base + c]
                }
            }));
            // Corner UVs in the same (possibly reversed) order; indices are
            // below the primitive's vertex count, as its UVs are.
            corner_uvs = match (corner_uvs.take(), uvs) {
                (Some(mut all), Some(uvs)) => {
                    let uv = |i: u32| uvs.get(i as usize).copied().unwrap_or([0.0; 2]);
                    all.extend(local_triangles.iter().map(|&[a, b, c]| {
                        if mirrored {
                            [uv(a), uv(c), uv(b)]
                        } else {
                            [uv(a), uv(b), uv(c)]
                        }
                    }));
                    Some(all)
                }
                _ => None,
            };
            Ok(())
        },
    )?;
    Ok(Mesh {
        vertices,
        triangles,
        corner_uvs: corner_uvs.filter(|uvs| !uvs.is_empty()),
    })
}

fn empty_like(values: &AttributeValues) -> AttributeValues {
    match values {
        AttributeValues::Float(_) => AttributeValues::Float(Vec::new()),
        AttributeValues::Vec2(_) => AttributeValues::Vec2(Vec::new()),
        AttributeValues::Vec3(_) => AttributeValues::Vec3(Vec::new()),
        AttributeValues::Int(_) => AttributeValues::Int(Vec::new()),
    }
}

fn same_type(a: &AttributeValues, b: &AttributeValues) -> bool {
    std::mem::discriminant(a) == std::mem::discriminant(b)
}

fn append_selected(into: &mut AttributeValues, from: &AttributeValues, indices: &[usize]) {
    match (into, from) {
        (AttributeValues::Float(o), AttributeValues::Float(s)) => {
            o.extend(indices.iter().filter_map(|&i| s.get(i)))
        }
        (AttributeValues::Vec2(o), AttributeValues::Vec2(s)) => {
            o.extend(indices.iter().filter_map(|&i| s.get(i)))
        }
        (AttributeValues::Vec3(o), AttributeValues::Vec3(s)) => {
            o.extend(indices.iter().filter_map(|&i| s.get(i)))
        }
        (AttributeValues::Int(o), AttributeValues::Int(s)) => {
            o.extend(indices.iter().filter_map(|&i| s.get(i)))
        }
        _ => {}
    }
}
