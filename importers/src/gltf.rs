//! glTF 2.0 (`.gltf` with embedded or external buffers, `.glb`) through the
//! `gltf` crate, which parses and validates the JSON. Strands are read from
//! `LINE_STRIP` primitives (one strand each) and `LINES` primitives
//! (consecutive segments that share an end vertex join into one strand);
//! other primitives (a head mesh, points) are skipped by [`read`];
//! [`read_triangles`] reads the triangle primitives instead, for colliders. The scene graph's
//! transforms are applied. Morph-target animation becomes frames: frame k is
//! the base pose plus the targets weighted by the k-th keyframe of the
//! `weights` sampler. `_NAME` vertex attributes come back as attributes named
//! `name` (lower case), unless the accessor's `extras.groombake` (written by
//! groombake's exporter) gives the name, says the attribute is per strand
//! (taken from each strand's first vertex, if every strand's values agree),
//! or says float or split-u16 values are 32-bit integers. glTF is metres and
//! Y up.
//!
//! Accessors are read by this module, not the crate's reader, so that every
//! range is checked against the buffer before it is read.

use crate::mesh::Triangles;
use crate::{ImportError, Place};
use base64::Engine;
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::{Interpolation, Property};
use gltf::mesh::Mode;
use gltf::Semantic;
use groom::{Attribute, AttributeValues, Frame, Groom, Units, UpAxis};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

type Matrix = [[f32; 4]; 4];

const IDENTITY: Matrix = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// The most points all frames together may have (3 GiB of coordinates).
const MAX_FRAME_POINTS: u64 = 1 << 28;

struct Reader<'a> {
    path: &'a Path,
    buffers: Vec<Vec<u8>>,
}

/// The strands of one primitive before they join the groom.
struct Piece {
    /// Vertex indices of each strand, into the primitive's accessors.
    strands: Vec<Vec<usize>>,
    positions: Vec<[f32; 3]>,
    world: Matrix,
    attributes: BTreeMap<String, AttributeValues>,
    /// Attributes marked per strand whose values agree along every strand.
    per_strand: BTreeSet<String>,
    /// Position deltas of each morph target.
    targets: Vec<Vec<[f32; 3]>>,
    default_weights: Vec<f32>,
    node: usize,
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let (document, reader) = load(path, bytes)?;
    let mut pieces = Vec::new();
    walk_scene(path, &document, |node, world| {
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                if let Some(piece) = reader.primitive(&primitive, &mesh, world, node.index())? {
                    pieces.push(piece);
                }
            }
        }
        Ok(())
    })?;

    let mut groom = Groom {
        units: Units::METERS,
        up_axis: UpAxis::Y,
        ..Groom::default()
    };
    // Attributes every line primitive has, with the same type.
    let mut common: Option<BTreeMap<String, AttributeValues>> = None;
    for piece in &pieces {
        let names: BTreeMap<String, AttributeValues> = piece
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
    let mut attributes = common.unwrap_or_default();
    let per_strand: BTreeSet<String> = attributes
        .keys()
        .filter(|name| pieces.iter().all(|p| p.per_strand.contains(*name)))
        .cloned()
        .collect();
    for piece in &pieces {
        for strand in &piece.strands {
            groom.strand_vertex_counts.push(strand.len() as u32);
            for &i in strand {
                let p = piece.positions.get(i).copied().unwrap_or_default();
                groom.points.push(transform(&piece.world, p));
            }
            for (name, values) in attributes.iter_mut() {
                if let Some(source) = piece.attributes.get(name) {
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
    groom.frames = reader.frames(&document, &pieces)?;
    groom.provenance.format = "gltf".into();
    Ok(groom)
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

/// The most vertices, and the most triangles, a collider mesh may have once
/// instanced meshes are expanded (a few shared nodes can multiply a small
/// file into an enormous mesh).
const MAX_MESH_VERTICES: usize = 1 << 24;
const MAX_MESH_TRIANGLES: usize = 1 << 25;

pub fn parse_triangles(path: &Path, bytes: &[u8]) -> Result<Triangles, ImportError> {
    let (document, reader) = load(path, bytes)?;
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    // A primitive shared by several nodes is decoded once.
    let mut decoded: BTreeMap<(usize, usize), Option<Triangles>> = BTreeMap::new();
    walk_scene(path, &document, |node, world| {
        let Some(mesh) = node.mesh() else {
            return Ok(());
        };
        for primitive in mesh.primitives() {
            let local = match decoded.entry((mesh.index(), primitive.index())) {
                std::collections::btree_map::Entry::Occupied(entry) => entry.into_mut(),
                std::collections::btree_map::Entry::Vacant(entry) => {
                    entry.insert(reader.triangles(&primitive, &mesh)?)
                }
            };
            let Some((positions, local_triangles)) = local else {
                continue;
            };
            if vertices.len() + positions.len() > MAX_MESH_VERTICES
                || triangles.len() + local_triangles.len() > MAX_MESH_TRIANGLES
            {
                return Err(ImportError::malformed(
                    path,
                    Place::Path(format!("/nodes/{}", node.index())),
                    format!(
                        "the scene's triangle meshes exceed {MAX_MESH_VERTICES} vertices or \
                         {MAX_MESH_TRIANGLES} triangles (meshes instanced by many nodes?)"
                    ),
                ));
            }
            // Both counts are bounded far below u32::MAX.
            let base = vertices.len() as u32;
            let mirrored = determinant(&world) < 0.0;
            vertices.extend(positions.iter().map(|&p| transform(&world, p)));
            triangles.extend(local_triangles.iter().map(|&[a, b, c]| {
                if mirrored {
                    [base + a, base + c, base + b]
                } else {
                    [base + a, base + b, base + c]
                }
            }));
        }
        Ok(())
    })?;
    Ok((vertices, triangles))
}

/// Parses the JSON (or GLB) and loads every buffer, checking each holds the
/// bytes its `byteLength` announces.
fn load<'a>(path: &'a Path, bytes: &[u8]) -> Result<(gltf::Gltf, Reader<'a>), ImportError> {
    let document = gltf::Gltf::from_slice(bytes).map_err(|e| crate_error(path, e))?;
    let mut reader = Reader {
        path,
        buffers: Vec::new(),
    };
    for buffer in document.buffers() {
        let place = Place::Path(format!("/buffers/{}", buffer.index()));
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => document.blob.clone().ok_or_else(|| {
                ImportError::malformed(
                    path,
                    place.clone(),
                    "refers to a GLB BIN chunk, but there is none",
                )
            })?,
            gltf::buffer::Source::Uri(uri) => load_uri(path, &place, uri)?,
        };
        if data.len() < buffer.length() {
            return Err(ImportError::malformed(
                path,
                place,
                format!(
                    "byteLength is {} but the data has {} bytes",
                    buffer.length(),
                    data.len()
                ),
            ));
        }
        reader.buffers.push(data);
    }
    Ok((document, reader))
}

/// Visits every node instance of the default (or first) scene depth-first,
/// parents before children, with its world matrix.
fn walk_scene(
    path: &Path,
    document: &gltf::Gltf,
    mut visit: impl FnMut(&gltf::Node, Matrix) -> Result<(), ImportError>,
) -> Result<(), ImportError> {
    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => Vec::new(),
    };
    // Depth-first over the scene graph; the depth bound guards against a
    // cycle the validation might let through.
    let mut stack: Vec<(gltf::Node, Matrix, usize)> =
        roots.into_iter().rev().map(|n| (n, IDENTITY, 0)).collect();
    let mut visits = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        // Nodes shared by several parents could make the walk exponential.
        visits += 1;
        if visits > 1 << 20 {
            return Err(ImportError::malformed(
                path,
                Place::Path("/nodes".into()),
                "scene graph has over a million node instances (nodes shared by many parents?)",
            ));
        }
        if depth > 1024 {
            return Err(ImportError::malformed(
                path,
                Place::Path(format!("/nodes/{}", node.index())),
                "node hierarchy deeper than 1024 (a cycle?)",
            ));
        }
        let world = multiply(&parent, &node.transform().matrix());
        visit(&node, world)?;
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }
    Ok(())
}

impl Reader<'_> {
    fn error(&self, place: String, message: impl Into<String>) -> ImportError {
        ImportError::malformed(self.path, Place::Path(place), message)
    }

    fn primitive(
        &self,
        primitive: &gltf::Primitive,
        mesh: &gltf::Mesh,
        world: Matrix,
        node: usize,
    ) -> Result<Option<Piece>, ImportError> {
        let mode = primitive.mode();
        if !matches!(mode, Mode::Lines | Mode::LineStrip) {
            return Ok(None);
        }
        let place = format!("/meshes/{}/primitives/{}", mesh.index(), primitive.index());
        let Some(position) = primitive.get(&Semantic::Positions) else {
            return Err(self.error(place, "line primitive without POSITION"));
        };
        let positions = self.vec3(&position)?;
        let vertex_count = positions.len();
        let indices = self.indices(primitive, vertex_count)?;
        let strands = match mode {
            Mode::LineStrip if indices.len() >= 2 => vec![indices],
            Mode::LineStrip => Vec::new(),
            _ => chain_segments(&indices),
        };
        let mut attributes = BTreeMap::new();
        let mut per_strand = BTreeSet::new();
        for (semantic, accessor) in primitive.attributes() {
            let Semantic::Extras(name) = semantic else {
                continue;
            };
            if accessor.count() != vertex_count {
                return Err(self.error(
                    format!("/accessors/{}", accessor.index()),
                    format!(
                        "attribute _{name} has {} values for {vertex_count} vertices",
                        accessor.count()
                    ),
                ));
            }
            let marker = Marker::of(&accessor);
            // A marker that does not fit the accessor is ignored.
            let split = match marker.split_int {
                true => self.split_integers(&accessor)?,
                false => None,
            };
            let values = match split {
                Some(values) => Some(values),
                None => self.attribute(&accessor)?,
            };
            let Some(mut values) = values else {
                continue;
            };
            if marker.int {
                values = integers_if_exact(values);
            }
            let name = marker.name.unwrap_or_else(|| name.to_lowercase());
            if marker.strand && constant_along(&values, &strands) {
                per_strand.insert(name.clone());
            }
            attributes.insert(name, values);
        }
        let mut targets = Vec::new();
        for target in primitive.morph_targets() {
            let deltas = match target.positions() {
                Some(accessor) => self.vec3(&accessor)?,
                None => vec![[0.0; 3]; vertex_count],
            };
            if deltas.len() != vertex_count {
                return Err(self.error(
                    place.clone(),
                    "morph target POSITION count differs from the base",
                ));
            }
            targets.push(deltas);
        }
        let default_weights = mesh.weights().map(<[f32]>::to_vec).unwrap_or_default();
        Ok(Some(Piece {
            strands,
            positions,
            world,
            attributes,
            per_strand,
            targets,
            default_weights,
            node,
        }))
    }

    /// The vertex indices of a primitive, each checked against the vertex
    /// count; `0..vertex_count` for a primitive without indices.
    fn indices(
        &self,
        primitive: &gltf::Primitive,
        vertex_count: usize,
    ) -> Result<Vec<usize>, ImportError> {
        let Some(accessor) = primitive.indices() else {
            return Ok((0..vertex_count).collect());
        };
        let values = self.integers(&accessor)?;
        if let Some(bad) = values.iter().find(|&&i| i >= vertex_count) {
            return Err(self.error(
                format!("/accessors/{}", accessor.index()),
                format!("index {bad} is out of range ({vertex_count} vertices)"),
            ));
        }
        Ok(values)
    }

    /// The positions and triangles (indices into those positions) of a
    /// TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive; `None` for other
    /// modes. Triangles that repeat a vertex (how strips are joined) are left
    /// out: they have no area.
    fn triangles(
        &self,
        primitive: &gltf::Primitive,
        mesh: &gltf::Mesh,
    ) -> Result<Option<Triangles>, ImportError> {
        let mode = primitive.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            return Ok(None);
        }
        let place = format!("/meshes/{}/primitives/{}", mesh.index(), primitive.index());
        let Some(position) = primitive.get(&Semantic::Positions) else {
            return Err(self.error(place, "triangle primitive without POSITION"));
        };
        let positions = self.vec3(&position)?;
        if positions.len() > MAX_MESH_VERTICES {
            return Err(self.error(
                format!("/accessors/{}", position.index()),
                format!(
                    "{} vertices are more than the {MAX_MESH_VERTICES} a collider mesh may have",
                    positions.len()
                ),
            ));
        }
        let indices = self.indices(primitive, positions.len())?;
        let corner = |k: usize| indices.get(k).map_or(0, |&i| i as u32);
        let mut triangles = Vec::new();
        match mode {
            Mode::Triangles => {
                if indices.len() % 3 != 0 {
                    return Err(self.error(
                        place,
                        format!(
                            "TRIANGLES primitive with {} vertices (indices), not a multiple of 3",
                            indices.len()
                        ),
                    ));
                }
                for k in (0..indices.len()).step_by(3) {
                    triangles.push([corner(k), corner(k + 1), corner(k + 2)]);
                }
            }
            // glTF 2.0 section 3.7.2.1: strip triangle i is (i, i+1, i+2)
            // for even i and (i, i+2, i+1) for odd i, so all face one way;
            // fan triangle i is (i+1, i+2, 0).
            Mode::TriangleStrip => {
                for k in 0..indices.len().saturating_sub(2) {
                    triangles.push(if k % 2 == 0 {
                        [corner(k), corner(k + 1), corner(k + 2)]
                    } else {
                        [corner(k), corner(k + 2), corner(k + 1)]
                    });
                }
            }
            _ => {
                for k in 0..indices.len().saturating_sub(2) {
                    triangles.push([corner(k + 1), corner(k + 2), corner(0)]);
                }
            }
        }
        triangles.retain(|[a, b, c]| a != b && b != c && a != c);
        Ok(Some((positions, triangles)))
    }

    /// The bytes of each element of an accessor, after checking the whole
    /// range lies inside its buffer view and buffer.
    fn elements<'b>(&'b self, accessor: &gltf::Accessor) -> Result<Vec<&'b [u8]>, ImportError> {
        let place = format!("/accessors/{}", accessor.index());
        if accessor.sparse().is_some() {
            return Err(self.error(place, "sparse accessors are not supported"));
        }
        let Some(view) = accessor.view() else {
            return Err(self.error(place, "accessor without bufferView"));
        };
        let element_size = accessor.size();
        let stride = view.stride().unwrap_or(element_size).max(element_size);
        let count = accessor.count();
        let data = self
            .buffers
            .get(view.buffer().index())
            .ok_or_else(|| self.error(place.clone(), "buffer missing"))?;
        let view_end = view.offset().checked_add(view.length());
        let start = view.offset().checked_add(accessor.offset());
        let span = count
            .checked_sub(1)
            .map(|n| {
                n.checked_mul(stride)
                    .and_then(|s| s.checked_add(element_size))
            })
            .unwrap_or(Some(0));
        let end = match (start, span) {
            (Some(start), Some(span)) => start.checked_add(span),
            _ => None,
        };
        match (start, end, view_end) {
            (Some(start), Some(end), Some(view_end)) if end <= view_end && end <= data.len() => {
                Ok((0..count)
                    .map(|k| &data[start + k * stride..start + k * stride + element_size])
                    .collect())
            }
            _ => Err(self.error(
                place,
                format!(
                    "{count} elements of {element_size} bytes (stride {stride}) do not fit in bufferView {} ({} bytes at offset {})",
                    view.index(),
                    view.length(),
                    view.offset()
                ),
            )),
        }
    }

    fn floats(&self, accessor: &gltf::Accessor, dims: Dimensions) -> Result<Vec<f32>, ImportError> {
        let place = format!("/accessors/{}", accessor.index());
        if accessor.data_type() != DataType::F32 || accessor.dimensions() != dims {
            return Err(self.error(
                place,
                format!(
                    "expected {dims:?} of FLOAT, found {:?} of {:?}",
                    accessor.dimensions(),
                    accessor.data_type()
                ),
            ));
        }
        let elements = self.elements(accessor)?;
        let mut values = Vec::with_capacity(elements.len() * dims.multiplicity());
        for element in elements {
            for c in element.chunks_exact(4) {
                let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                if !v.is_finite() {
                    return Err(self.error(place, format!("value {v} is not finite")));
                }
                values.push(v);
            }
        }
        Ok(values)
    }

    fn vec3(&self, accessor: &gltf::Accessor) -> Result<Vec<[f32; 3]>, ImportError> {
        let flat = self.floats(accessor, Dimensions::Vec3)?;
        Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    fn integers(&self, accessor: &gltf::Accessor) -> Result<Vec<usize>, ImportError> {
        let values = self.scalar_integers(accessor)?.ok_or_else(|| {
            self.error(
                format!("/accessors/{}", accessor.index()),
                "indices are not unsigned integers",
            )
        })?;
        Ok(values.into_iter().map(|v| v as usize).collect())
    }

    /// SCALAR integer accessors as i64; `None` for other types.
    fn scalar_integers(&self, accessor: &gltf::Accessor) -> Result<Option<Vec<i64>>, ImportError> {
        if accessor.dimensions() != Dimensions::Scalar || accessor.normalized() {
            return Ok(None);
        }
        let decode: fn(&[u8]) -> i64 = match accessor.data_type() {
            DataType::U8 => |b| b[0] as i64,
            DataType::I8 => |b| b[0] as i8 as i64,
            DataType::U16 => |b| u16::from_le_bytes([b[0], b[1]]) as i64,
            DataType::I16 => |b| i16::from_le_bytes([b[0], b[1]]) as i64,
            DataType::U32 => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64,
            DataType::F32 => return Ok(None),
        };
        Ok(Some(
            self.elements(accessor)?.into_iter().map(decode).collect(),
        ))
    }

    /// A `_NAME` attribute; `None` for types the groom has no place for.
    fn attribute(&self, accessor: &gltf::Accessor) -> Result<Option<AttributeValues>, ImportError> {
        if accessor.data_type() == DataType::F32 {
            let dims = accessor.dimensions();
            return Ok(match dims {
                Dimensions::Scalar => Some(AttributeValues::Float(self.floats(accessor, dims)?)),
                Dimensions::Vec2 => {
                    let flat = self.floats(accessor, dims)?;
                    Some(AttributeValues::Vec2(
                        flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
                    ))
                }
                Dimensions::Vec3 => Some(AttributeValues::Vec3(self.vec3(accessor)?)),
                _ => None,
            });
        }
        Ok(self
            .scalar_integers(accessor)?
            .map(|values| AttributeValues::Int(values.into_iter().map(|v| v as i32).collect())))
    }

    /// A VEC2 UNSIGNED_SHORT accessor holding 32-bit integers (low half
    /// first); `None` if the accessor is not of that type.
    fn split_integers(
        &self,
        accessor: &gltf::Accessor,
    ) -> Result<Option<AttributeValues>, ImportError> {
        if accessor.data_type() != DataType::U16
            || accessor.dimensions() != Dimensions::Vec2
            || accessor.normalized()
        {
            return Ok(None);
        }
        let values = self
            .elements(accessor)?
            .into_iter()
            .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Ok(Some(AttributeValues::Int(values)))
    }

    /// Frames from the first animation that drives morph-target weights.
    fn frames(&self, document: &gltf::Gltf, pieces: &[Piece]) -> Result<Vec<Frame>, ImportError> {
        let Some(animation) = document.animations().find(|a| {
            a.channels()
                .any(|c| c.target().property() == Property::MorphTargetWeights)
        }) else {
            return Ok(Vec::new());
        };
        let mut times: Option<Vec<f32>> = None;
        // Per node: the weights of each keyframe.
        let mut weights_of_node: BTreeMap<usize, Vec<Vec<f32>>> = BTreeMap::new();
        for channel in animation.channels() {
            if channel.target().property() != Property::MorphTargetWeights {
                continue;
            }
            let place = format!(
                "/animations/{}/channels/{}",
                animation.index(),
                channel.index()
            );
            let sampler = channel.sampler();
            let input = self.floats(&sampler.input(), Dimensions::Scalar)?;
            let output = self.floats(&sampler.output(), Dimensions::Scalar)?;
            match &times {
                None => times = Some(input.clone()),
                Some(t) if *t == input => {}
                Some(_) => {
                    return Err(self.error(
                        place,
                        "weights channels with different keyframe times are not supported",
                    ))
                }
            }
            let node = channel.target().node();
            let target_count = node
                .mesh()
                .and_then(|m| m.primitives().next())
                .map(|p| p.morph_targets().count())
                .unwrap_or(0);
            let per_key = match sampler.interpolation() {
                Interpolation::CubicSpline => 3 * target_count,
                _ => target_count,
            };
            if per_key == 0 || output.len() != per_key * input.len() {
                return Err(self.error(
                    place,
                    format!(
                        "{} weights for {} keyframes of {target_count} morph targets",
                        output.len(),
                        input.len()
                    ),
                ));
            }
            let keys = output
                .chunks_exact(per_key)
                .map(|chunk| match sampler.interpolation() {
                    // In-tangents, values, out-tangents: the values are the middle third.
                    Interpolation::CubicSpline => chunk[target_count..2 * target_count].to_vec(),
                    _ => chunk.to_vec(),
                })
                .collect();
            weights_of_node.insert(node.index(), keys);
        }
        let times = times.unwrap_or_default();
        let vertices: usize = pieces
            .iter()
            .flat_map(|p| p.strands.iter().map(Vec::len))
            .sum();
        // Few morph targets can drive many keyframes: bound what the frames
        // would take before allocating them.
        if (times.len() as u64).saturating_mul(vertices as u64) > MAX_FRAME_POINTS {
            return Err(self.error(
                format!("/animations/{}", animation.index()),
                format!(
                    "{} keyframes of {vertices} points are more than the {MAX_FRAME_POINTS} frame points groombake holds",
                    times.len()
                ),
            ));
        }
        let mut frames = Vec::with_capacity(times.len());
        for (k, &time) in times.iter().enumerate() {
            let mut points = Vec::new();
            for piece in pieces {
                let weights: &[f32] = weights_of_node
                    .get(&piece.node)
                    .and_then(|keys| keys.get(k))
                    .map(Vec::as_slice)
                    .unwrap_or(&piece.default_weights);
                for strand in &piece.strands {
                    for &i in strand {
                        let mut p = piece.positions.get(i).copied().unwrap_or_default();
                        for (target, &w) in piece.targets.iter().zip(weights) {
                            if w != 0.0 {
                                let d = target.get(i).copied().unwrap_or_default();
                                for c in 0..3 {
                                    p[c] += w * d[c];
                                }
                            }
                        }
                        points.push(transform(&piece.world, p));
                    }
                }
            }
            frames.push(Frame {
                time: time as f64,
                points,
            });
        }
        Ok(frames)
    }
}

/// Joins `LINES` segments into strands: a segment that starts where the
/// previous one ended continues its strand; a degenerate segment `(i, i)` is
/// a strand of one point.
fn chain_segments(indices: &[usize]) -> Vec<Vec<usize>> {
    let mut strands: Vec<Vec<usize>> = Vec::new();
    for segment in indices.chunks_exact(2) {
        // A segment from a vertex to itself is a one-point strand (how the
        // exporter keeps USC-HairSalon's empty roots).
        if segment[0] == segment[1] {
            strands.push(vec![segment[0]]);
            continue;
        }
        match strands.last_mut() {
            Some(strand) if strand.len() == 1 => strands.push(vec![segment[0], segment[1]]),
            Some(strand) if strand.last() == Some(&segment[0]) => strand.push(segment[1]),
            _ => strands.push(vec![segment[0], segment[1]]),
        }
    }
    strands
}

fn load_uri(path: &Path, place: &Place, uri: &str) -> Result<Vec<u8>, ImportError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(ImportError::malformed(
                path,
                place.clone(),
                "data URI is not base64",
            ));
        };
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| {
                ImportError::malformed(path, place.clone(), format!("bad base64 data: {e}"))
            });
    }
    if uri.contains("://") {
        return Err(ImportError::malformed(
            path,
            place.clone(),
            format!("cannot read remote buffer {uri}"),
        ));
    }
    let decoded = percent_decode(uri);
    let file = path.parent().unwrap_or(Path::new(".")).join(decoded);
    std::fs::read(&file).map_err(|e| {
        ImportError::malformed(
            path,
            place.clone(),
            format!("cannot read buffer file {}: {e}", file.display()),
        )
    })
}

/// Relative URIs may escape characters as `%XX`.
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).unwrap_or("");
            if let Ok(v) = u8::from_str_radix(hex, 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn crate_error(path: &Path, error: gltf::Error) -> ImportError {
    match error {
        gltf::Error::Validation(problems) => {
            let place = problems
                .first()
                .map(|(p, _)| Place::Path(p.to_string()))
                .unwrap_or(Place::File);
            // The place names the first problem; the message adds the others.
            let mut message = problems
                .first()
                .map(|(_, e)| format!("invalid glTF: {e}"))
                .unwrap_or_else(|| "invalid glTF".into());
            for (p, e) in problems.iter().skip(1) {
                message.push_str(&format!("; {p}: {e}"));
            }
            ImportError::malformed(path, place, message)
        }
        gltf::Error::Io(e) => ImportError::io(path, e),
        other => ImportError::malformed(path, Place::File, format!("invalid glTF: {other}")),
    }
}

fn multiply(a: &Matrix, b: &Matrix) -> Matrix {
    // Column-major: m[column][row].
    let mut m = [[0.0f32; 4]; 4];
    for (column, out) in m.iter_mut().enumerate() {
        for (row, value) in out.iter_mut().enumerate() {
            *value = (0..4).map(|k| a[k][row] * b[column][k]).sum();
        }
    }
    m
}

/// Determinant of the linear (upper-left 3x3) part of a transform.
fn determinant(m: &Matrix) -> f32 {
    // Column-major: m[column][row].
    m[0][0] * (m[1][1] * m[2][2] - m[2][1] * m[1][2])
        - m[1][0] * (m[0][1] * m[2][2] - m[2][1] * m[0][2])
        + m[2][0] * (m[0][1] * m[1][2] - m[1][1] * m[0][2])
}

fn transform(m: &Matrix, p: [f32; 3]) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (row, value) in out.iter_mut().enumerate() {
        *value = m[0][row] * p[0] + m[1][row] * p[1] + m[2][row] * p[2] + m[3][row];
    }
    out
}

/// What groombake's exporter keeps in an attribute accessor's
/// `extras.groombake`; all unset for other files.
#[derive(Default)]
struct Marker {
    name: Option<String>,
    strand: bool,
    int: bool,
    split_int: bool,
}

impl Marker {
    fn of(accessor: &gltf::Accessor) -> Marker {
        let Some(raw) = accessor.extras() else {
            return Marker::default();
        };
        let Ok(extras) = serde_json::from_str::<serde_json::Value>(raw.get()) else {
            return Marker::default();
        };
        let marker = &extras["groombake"];
        Marker {
            name: marker["name"]
                .as_str()
                .filter(|name| !name.is_empty())
                .map(String::from),
            strand: marker["scope"] == "strand",
            int: marker["type"] == "int",
            split_int: marker["encoding"] == "i32_as_u16x2",
        }
    }
}

/// Float values that are all whole numbers in i32's range become integers.
fn integers_if_exact(values: AttributeValues) -> AttributeValues {
    match values {
        AttributeValues::Float(floats)
            if floats
                .iter()
                .all(|&v| v.fract() == 0.0 && v >= i32::MIN as f32 && v < i32::MAX as f32) =>
        {
            AttributeValues::Int(floats.into_iter().map(|v| v as i32).collect())
        }
        other => other,
    }
}

/// Whether every strand's vertices (indices into `values`) hold one value.
fn constant_along(values: &AttributeValues, strands: &[Vec<usize>]) -> bool {
    fn constant<T: PartialEq>(values: &[T], strands: &[Vec<usize>]) -> bool {
        strands.iter().all(|strand| {
            let mut picked = strand.iter().map(|&i| values.get(i));
            let first = picked.next().flatten();
            first.is_some() && picked.all(|v| v == first)
        })
    }
    match values {
        AttributeValues::Float(v) => constant(v, strands),
        AttributeValues::Vec2(v) => constant(v, strands),
        AttributeValues::Vec3(v) => constant(v, strands),
        AttributeValues::Int(v) => constant(v, strands),
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-made glTF: a LINE_STRIP under a translated parent and a scaled
    /// child, with a morph target driven by a LINEAR weights sampler, and a
    /// LINES primitive with u16 indices at the root. Returns (JSON, buffer).
    fn hand_made(uri: Option<&str>) -> (String, Vec<u8>) {
        let mut bin = Vec::new();
        let mut floats = |values: &[f32]| {
            for v in values {
                bin.extend_from_slice(&v.to_le_bytes());
            }
        };
        floats(&[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0]); // 0: strip positions
        floats(&[0.1, 0.2, 0.3]); // 36: strip widths
        floats(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0]); // 48: target deltas
        floats(&[0.0, 1.0]); // 84: times
        floats(&[0.0, 0.5]); // 92: weights
        floats(&[5.0, 0.0, 0.0, 5.0, 1.0, 0.0, 6.0, 0.0, 0.0, 6.0, 1.0, 0.0]); // 100: lines positions
        for i in [0u16, 1, 2, 3] {
            bin.extend_from_slice(&i.to_le_bytes()); // 148: indices
        }
        let mut floats = |values: &[f32]| {
            for v in values {
                bin.extend_from_slice(&v.to_le_bytes());
            }
        };
        floats(&[0.4, 0.5, 0.6, 0.7]); // 156: lines widths
        let uri = uri.map(|u| format!(r#","uri":"{u}""#)).unwrap_or_default();
        let view = |offset: usize, length: usize| {
            format!(r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{length}}}"#)
        };
        let views = [
            view(0, 36),
            view(36, 12),
            view(48, 36),
            view(84, 8),
            view(92, 8),
            view(100, 48),
            view(148, 8),
            view(156, 16),
        ]
        .join(",");
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,2]}}],
            "nodes":[{{"translation":[10,0,0],"children":[1]}},{{"scale":[2,2,2],"mesh":0}},{{"mesh":1}}],
            "meshes":[
              {{"primitives":[{{"mode":3,"attributes":{{"POSITION":0,"_WIDTH":1}},"targets":[{{"POSITION":2}}]}}],"weights":[0.25]}},
              {{"primitives":[{{"mode":1,"attributes":{{"POSITION":5,"_WIDTH":7}},"indices":6}}]}}],
            "animations":[{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"weights"}}}}],
              "samplers":[{{"input":3,"output":4,"interpolation":"LINEAR"}}]}}],
            "accessors":[
              {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0,2,0]}},
              {{"bufferView":1,"componentType":5126,"count":3,"type":"SCALAR"}},
              {{"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"}},
              {{"bufferView":3,"componentType":5126,"count":2,"type":"SCALAR"}},
              {{"bufferView":4,"componentType":5126,"count":2,"type":"SCALAR"}},
              {{"bufferView":5,"componentType":5126,"count":4,"type":"VEC3","min":[5,0,0],"max":[6,1,0]}},
              {{"bufferView":6,"componentType":5123,"count":4,"type":"SCALAR"}},
              {{"bufferView":7,"componentType":5126,"count":4,"type":"SCALAR"}}],
            "bufferViews":[{views}],
            "buffers":[{{"byteLength":{}{uri}}}]}}"#,
            bin.len()
        );
        (json, bin)
    }

    fn check_hand_made(groom: &Groom) {
        assert_eq!(groom.strand_vertex_counts, vec![3, 2, 2]);
        assert_eq!(
            groom.points,
            vec![
                [10.0, 0.0, 0.0],
                [10.0, 2.0, 0.0],
                [10.0, 4.0, 0.0],
                [5.0, 0.0, 0.0],
                [5.0, 1.0, 0.0],
                [6.0, 0.0, 0.0],
                [6.0, 1.0, 0.0],
            ]
        );
        assert_eq!(
            groom.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7])
        );
        assert_eq!(groom.frames.len(), 2);
        assert_eq!(groom.frames[0].points, groom.points);
        assert_eq!(groom.frames[1].time, 1.0);
        // Weight 0.5 of a +1 x delta, scaled by 2 by the node.
        assert_eq!(groom.frames[1].points[2], [11.0, 4.0, 0.0]);
        assert_eq!(groom.frames[1].points[3], [5.0, 0.0, 0.0]);
        assert_eq!(groom.units, Units::METERS);
    }

    #[test]
    fn reads_embedded_gltf_with_scene_graph_and_morph_animation() {
        let (_, bin) = hand_made(None);
        let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
        let (json, _) = hand_made(Some(&format!(
            "data:application/octet-stream;base64,{payload}"
        )));
        let groom = parse(Path::new("t.gltf"), json.as_bytes()).unwrap();
        check_hand_made(&groom);
    }

    #[test]
    fn reads_glb_and_external_buffers() {
        let (json, bin) = hand_made(None);
        let mut json = json.into_bytes();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut glb = Vec::new();
        glb.extend_from_slice(b"glTF");
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(&json);
        glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"BIN\0");
        glb.extend_from_slice(&bin);
        check_hand_made(&parse(Path::new("t.glb"), &glb).unwrap());
        for cut in 0..glb.len() {
            assert!(parse(Path::new("t.glb"), &glb[..cut]).is_err(), "cut {cut}");
        }

        let dir = std::env::temp_dir().join(format!("importers-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("hair buffer.bin"), &bin).unwrap();
        let (json, _) = hand_made(Some("hair%20buffer.bin"));
        std::fs::write(dir.join("t.gltf"), &json).unwrap();
        check_hand_made(&read(&dir.join("t.gltf")).unwrap());
        std::fs::write(dir.join("hair buffer.bin"), &bin[..100]).unwrap();
        let error = read(&dir.join("t.gltf")).unwrap_err().to_string();
        assert!(error.contains(":/buffers/0: byteLength is 172"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn accessor_past_its_view_names_the_accessor() {
        let (_, bin) = hand_made(None);
        let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
        let (json, _) = hand_made(Some(&format!(
            "data:application/octet-stream;base64,{payload}"
        )));
        let json = json.replacen(
            r#""count":4,"type":"VEC3""#,
            r#""count":400,"type":"VEC3""#,
            1,
        );
        let error = parse(Path::new("t.gltf"), json.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            error.starts_with("t.gltf:/accessors/5: 400 elements"),
            "{error}"
        );
        let json = hand_made(Some("data:x;base64,@@")).0;
        let error = parse(Path::new("t.gltf"), json.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(error.contains("/buffers/0: bad base64"), "{error}");
    }

    #[test]
    fn extras_markers_name_scope_and_type_attributes() {
        let (_, bin) = hand_made(None);
        let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
        let (json, _) = hand_made(Some(&format!(
            "data:application/octet-stream;base64,{payload}"
        )));
        let marked = |json: &str, extras: &str| {
            // The two _WIDTH accessors (1 and 7): the only SCALAR FLOAT
            // accessors of three elements and of four.
            json.replacen(
                r#""count":3,"type":"SCALAR"}"#,
                &format!(r#""count":3,"type":"SCALAR","extras":{extras}}}"#),
                1,
            )
            .replacen(
                r#""componentType":5126,"count":4,"type":"SCALAR"}"#,
                &format!(r#""componentType":5126,"count":4,"type":"SCALAR","extras":{extras}}}"#),
                1,
            )
        };
        // The strip's widths differ along its strand: the per-strand marker
        // is not honoured, the name is.
        let json_marked = marked(&json, r#"{"groombake":{"name":"Width","scope":"strand"}}"#);
        assert_ne!(json_marked, json);
        let groom = parse(Path::new("t.gltf"), json_marked.as_bytes()).unwrap();
        let width = groom.attribute("Width").unwrap();
        assert_eq!(width.scope, groom::Scope::Vertex);
        assert_eq!(width.values.len(), 7);
        // Fractional floats marked int stay floats; a split encoding on a
        // FLOAT accessor is ignored; unknown extras are harmless.
        for extras in [
            r#"{"groombake":{"type":"int","encoding":"i32_as_u16x2"}}"#,
            r#"{"groombake":7}"#,
            r#"[1,2]"#,
        ] {
            let json_marked = marked(&json, extras);
            let groom = parse(Path::new("t.gltf"), json_marked.as_bytes()).unwrap();
            assert_eq!(
                groom.attribute("width").unwrap().values,
                AttributeValues::Float(vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]),
                "{extras}"
            );
        }
    }

    #[test]
    fn segments_chain_into_strands() {
        assert_eq!(
            chain_segments(&[0, 1, 1, 2, 3, 4, 4, 5, 5, 6, 7, 7, 7, 8]),
            vec![vec![0, 1, 2], vec![3, 4, 5, 6], vec![7], vec![7, 8]]
        );
    }

    #[test]
    fn matrices_compose_parent_first() {
        let translate: Matrix = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [10.0, 0.0, 0.0, 1.0],
        ];
        let scale: Matrix = [
            [2.0, 0.0, 0.0, 0.0],
            [0.0, 2.0, 0.0, 0.0],
            [0.0, 0.0, 2.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        // Parent translates, child scales: the point is scaled, then moved.
        let world = multiply(&translate, &scale);
        assert_eq!(transform(&world, [1.0, 1.0, 1.0]), [12.0, 2.0, 2.0]);
    }

    #[test]
    fn percent_escapes() {
        assert_eq!(percent_decode("my%20hair.bin"), "my hair.bin");
        assert_eq!(percent_decode("odd%2"), "odd%2");
    }

    /// Four vertices of a unit square drawn as TRIANGLES (u8 indices) by a
    /// translated node and a mirroring node, as a TRIANGLE_STRIP, a
    /// TRIANGLE_FAN, and a LINE_STRIP that triangle reading skips.
    fn triangle_scene() -> String {
        let mut bin = Vec::new();
        for v in [
            0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0,
        ] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        bin.extend_from_slice(&[0, 1, 2, 2, 1, 3, 0, 0]);
        let payload = base64::engine::general_purpose::STANDARD.encode(&bin);
        let primitive = |mode: u32, indices: &str| {
            format!(
                r#"{{"primitives":[{{"mode":{mode},"attributes":{{"POSITION":0}}{indices}}}]}}"#
            )
        };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1,2,3,4]}}],
            "nodes":[{{"translation":[10,0,0],"mesh":0}},{{"scale":[-1,1,1],"mesh":0}},{{"mesh":1}},{{"mesh":2}},{{"mesh":3}}],
            "meshes":[{},{},{},{}],
            "accessors":[
              {{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
              {{"bufferView":1,"componentType":5121,"count":6,"type":"SCALAR"}}],
            "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":6}}],
            "buffers":[{{"byteLength":56,"uri":"data:application/octet-stream;base64,{payload}"}}]}}"#,
            primitive(4, r#","indices":1"#),
            primitive(5, ""),
            primitive(6, ""),
            primitive(3, ""),
        )
    }

    fn normal_z(vertices: &[[f32; 3]], [a, b, c]: [u32; 3]) -> f32 {
        let (a, b, c) = (
            vertices[a as usize],
            vertices[b as usize],
            vertices[c as usize],
        );
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn triangles_of_every_mode_with_transforms_and_mirroring() {
        let json = triangle_scene();
        let (vertices, triangles) = parse_triangles(Path::new("t.gltf"), json.as_bytes()).unwrap();
        assert_eq!(vertices.len(), 16);
        assert_eq!(vertices[1], [11.0, 0.0, 0.0]);
        assert_eq!(vertices[5], [-1.0, 0.0, 0.0]);
        assert_eq!(
            triangles,
            vec![
                [0, 1, 2],
                [2, 1, 3],
                // Mirrored by scale -1: winding reversed.
                [4, 6, 5],
                [6, 7, 5],
                // Strip: odd triangles swap their last two corners.
                [8, 9, 10],
                [9, 11, 10],
                // Fan around the first vertex.
                [13, 14, 12],
                [14, 15, 12],
            ]
        );
        // The mirrored copies still face +z, like the originals.
        for &t in &triangles[..6] {
            assert!(normal_z(&vertices, t) > 0.0, "{t:?}");
        }
        // Strokes are no triangles; the curve reader still finds the line.
        let groom = parse(Path::new("t.gltf"), json.as_bytes()).unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![4]);
    }

    #[test]
    fn malformed_triangles_name_the_place() {
        let json = triangle_scene();
        let cases = [
            (
                r#""componentType":5121,"count":6"#,
                r#""componentType":5121,"count":5"#,
                "t.gltf:/meshes/0/primitives/0: TRIANGLES primitive with 5 vertices",
            ),
            (
                r#""count":4,"type":"VEC3""#,
                r#""count":40,"type":"VEC3""#,
                "t.gltf:/accessors/0: 40 elements",
            ),
            (
                r#""componentType":5121,"count":6,"type":"SCALAR""#,
                r#""componentType":5126,"count":1,"type":"SCALAR""#,
                "t.gltf:/accessors/1: indices are not unsigned integers",
            ),
        ];
        for (from, to, expected) in cases {
            let bad = json.replacen(from, to, 1);
            assert_ne!(bad, json);
            let e = parse_triangles(Path::new("t.gltf"), bad.as_bytes())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(expected), "{e}");
        }
        // Index 3 becomes 9, past the four vertices.
        let mut bin = Vec::new();
        for v in [
            0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0,
        ] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        let good = base64::engine::general_purpose::STANDARD
            .encode([&bin[..], &[0, 1, 2, 2, 1, 3, 0, 0]].concat());
        let bad = base64::engine::general_purpose::STANDARD
            .encode([&bin[..], &[0, 1, 2, 2, 1, 9, 0, 0]].concat());
        let json = json.replacen(&good, &bad, 1);
        let e = parse_triangles(Path::new("t.gltf"), json.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.gltf:/accessors/1: index 9 is out of range (4 vertices)"),
            "{e}"
        );
    }

    #[test]
    fn every_cut_of_the_pillow_sample_is_an_error() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/pillow.glb");
        let glb = std::fs::read(&path).unwrap();
        let (vertices, triangles) = parse_triangles(&path, &glb).unwrap();
        assert_eq!((vertices.len(), triangles.len()), (8, 12));
        for cut in 0..glb.len() {
            assert!(parse_triangles(&path, &glb[..cut]).is_err(), "cut {cut}");
        }
    }

    #[test]
    fn garbage_is_an_error() {
        for bytes in [&b""[..], b"{", b"glTF\x02\x00\x00\x00", b"{\"asset\":{}}"] {
            assert!(parse(Path::new("t.glb"), bytes).is_err());
        }
    }
}
