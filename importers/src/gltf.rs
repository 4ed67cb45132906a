//! glTF 2.0 (`.gltf` with embedded or external buffers, `.glb`) through the
//! `gltf` crate, which parses and validates the JSON. Strands are read from
//! `LINE_STRIP` primitives (one strand each) and `LINES` primitives
//! (consecutive segments that share an end vertex join into one strand);
//! other primitives (a head mesh, points) are skipped. The scene graph's
//! transforms are applied. Morph-target animation becomes frames: frame k is
//! the base pose plus the targets weighted by the k-th keyframe of the
//! `weights` sampler. `_NAME` vertex attributes come back as attributes named
//! `name` (lower case). glTF is metres and Y up.
//!
//! Accessors are read by this module, not the crate's reader, so that every
//! range is checked against the buffer before it is read.

use crate::{ImportError, Place};
use base64::Engine;
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::{Interpolation, Property};
use gltf::mesh::Mode;
use gltf::Semantic;
use groom::{Attribute, AttributeValues, Frame, Groom, Units, UpAxis};
use std::collections::BTreeMap;
use std::path::Path;

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

type Matrix = [[f32; 4]; 4];

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
    /// Position deltas of each morph target.
    targets: Vec<Vec<[f32; 3]>>,
    default_weights: Vec<f32>,
    node: usize,
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
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

    let mut pieces = Vec::new();
    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => Vec::new(),
    };
    let identity: Matrix = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    // Depth-first over the scene graph; the depth bound guards against a
    // cycle the validation might let through.
    let mut stack: Vec<(gltf::Node, Matrix, usize)> =
        roots.into_iter().rev().map(|n| (n, identity, 0)).collect();
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
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                if let Some(piece) = reader.primitive(&primitive, &mesh, world, node.index())? {
                    pieces.push(piece);
                }
            }
        }
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }

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
    for piece in &pieces {
        for strand in &piece.strands {
            groom.strand_vertex_counts.push(strand.len() as u32);
            for &i in strand {
                let p = piece.positions.get(i).copied().unwrap_or_default();
                groom.points.push(transform(&piece.world, p));
            }
            for (name, values) in attributes.iter_mut() {
                if let Some(source) = piece.attributes.get(name) {
                    append_selected(values, source, strand);
                }
            }
        }
    }
    for (name, values) in attributes {
        groom.attributes.push(Attribute::new(name, values));
    }
    groom.frames = reader.frames(&document, &pieces)?;
    groom.provenance.format = "gltf".into();
    Ok(groom)
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
        let indices: Vec<usize> = match primitive.indices() {
            Some(accessor) => {
                let values = self.integers(&accessor)?;
                if let Some(bad) = values.iter().find(|&&i| i >= vertex_count) {
                    return Err(self.error(
                        format!("/accessors/{}", accessor.index()),
                        format!("index {bad} is out of range ({vertex_count} vertices)"),
                    ));
                }
                values
            }
            None => (0..vertex_count).collect(),
        };
        let strands = match mode {
            Mode::LineStrip if indices.len() >= 2 => vec![indices],
            Mode::LineStrip => Vec::new(),
            _ => chain_segments(&indices),
        };
        let mut attributes = BTreeMap::new();
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
            if let Some(values) = self.attribute(&accessor)? {
                attributes.insert(name.to_lowercase(), values);
            }
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
            targets,
            default_weights,
            node,
        }))
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

fn transform(m: &Matrix, p: [f32; 3]) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (row, value) in out.iter_mut().enumerate() {
        *value = m[0][row] * p[0] + m[1][row] * p[1] + m[2][row] * p[2] + m[3][row];
    }
    out
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

    #[test]
    fn garbage_is_an_error() {
        for bytes in [&b""[..], b"{", b"glTF\x02\x00\x00\x00", b"{\"asset\":{}}"] {
            assert!(parse(Path::new("t.glb"), bytes).is_err());
        }
    }
}
