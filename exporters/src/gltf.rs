//! glTF 2.0: `.glb` (binary) and `.gltf` (JSON with the buffer embedded as a
//! base64 data URI).
//!
//! `.gltf` embeds its buffer rather than writing a `.bin` beside it: one
//! file can be renamed into place atomically, and Blender, three.js, Maya's
//! and Houdini's importers and the Khronos validator all read data URIs.
//!
//! The groom becomes one mesh with one `LINES` primitive (a segment per pair
//! of consecutive strand points; a one-point strand is a segment from its
//! point to itself), in metres and Y up as glTF requires. A groom with
//! guides and render strands (`groom_guide`) becomes two primitives, the
//! guides then the render strands, whose accessors are windows of shared
//! views.
//! The root UVs (`root_uv`, 2 floats) are `TEXCOORD_0`, which every glTF
//! client reads, with V flipped to glTF's top-left texture origin. Other
//! attributes are scalar `_NAME` accessors (upper-case name; per-strand
//! attributes are repeated on their strand's vertices): a 2- or 3-vector is
//! one accessor per component (`_NAME_X`, `_NAME_Y`, `_NAME_Z`), integers
//! are floats (two accessors of their u16 halves, `_NAME_LO` and `_NAME_HI`,
//! beyond 2^24), all FLOAT, which Blender imports. One width for all: Blender 5.0.1's importer pairs custom
//! attributes with their buffers in two different orders (a list and a
//! set), so custom attributes of different widths in one primitive fail or
//! land under each other's names.
//! Each attribute accessor's `extras.groombake` keeps what glTF cannot say:
//! the attribute's own name (case and all), its scope (`vertex` or
//! `strand`), the component an accessor holds, and for integers stored as
//! floats or split, `"type": "int"` and the encoding. //! Animation is one
//! morph target per frame (POSITION deltas from the rest pose) and a STEP
//! sampler of the mesh weights that switches target k fully on at frame k's
//! time.
//!
//! Frames are streamed: each frame's deltas go to an anonymous temporary
//! file as they arrive, and `finish` assembles the file from the rest pose,
//! the spilled frames and the sampler, so memory holds one frame plus the
//! rest pose, its indices and attributes.

use crate::{ExportError, FrameWriter};
use groom::{AtomicFile, AttributeValues, Frame, Groom, Scope, Units, UpAxis};
use serde_json::{json, Value};
use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const LINES: u32 = 1;
/// Stands for the base64 payload in the `.gltf` JSON until it is streamed.
const URI_PLACEHOLDER: &str = "@groombake-buffer@";
const DATA_URI_PREFIX: &str = "data:application/octet-stream;base64,";
/// The key of the attribute accessors' extras (read by the importer).
const EXTRAS_KEY: &str = "groombake";
/// The extras' encoding of 32-bit integers as two scalar accessors of
/// their u16 halves (low, high).
const INT_AS_U16_PAIR: &str = "i32_as_u16_pair";
/// The attribute that goes to `TEXCOORD_0`.
const ROOT_UV: &str = "root_uv";

/// A vertex attribute laid out for the buffer.
struct EncodedAttribute {
    semantic: String,
    component_type: u32,
    accessor_type: &'static str,
    /// Element stride; vertex attributes must be 4-byte aligned.
    stride: usize,
    bytes: Vec<u8>,
    /// `{"groombake": {"name", "scope", ["type", "encoding"]}}`.
    extras: Value,
}

/// One primitive: a run of the (reordered) vertices and of the indices.
struct Part {
    vertices: std::ops::Range<usize>,
    indices: std::ops::Range<usize>,
    rest_bounds: ([f32; 3], [f32; 3]),
}

pub struct GltfWriter {
    path: PathBuf,
    binary: bool,
    /// Maps the groom's units and up axis to metres, Y up.
    scale: f32,
    up: UpAxis,
    /// The groom's vertex ranges in the order they are written (guides,
    /// then render strands); `None` when written in the groom's order.
    order: Option<Vec<std::ops::Range<usize>>>,
    /// One primitive, or the guides and the render strands.
    parts: Vec<Part>,
    rest: Vec<[f32; 3]>,
    /// Indices of each part, counted from the part's first vertex.
    indices: Vec<u32>,
    attributes: Vec<EncodedAttribute>,
    spill: BufWriter<File>,
    frame_times: Vec<f32>,
    /// Per frame, the bounds of each part's deltas.
    frame_bounds: Vec<Vec<([f32; 3], [f32; 3])>>,
}

pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    let mut writer = start(path, groom)?;
    for frame in &groom.frames {
        writer.write_frame(frame)?;
    }
    Box::new(writer).finish()
}

pub fn animated(path: &Path, groom: &Groom) -> Result<Box<dyn FrameWriter>, ExportError> {
    Ok(Box::new(start(path, groom)?))
}

fn invalid(path: &Path, message: impl Into<String>) -> ExportError {
    ExportError::Invalid {
        file: path.to_path_buf(),
        message: message.into(),
    }
}

fn start(path: &Path, groom: &Groom) -> Result<GltfWriter, ExportError> {
    let binary = crate::extension_is(path, "glb");
    // Only the rest pose and attributes are converted here; frames are
    // converted one at a time as they stream in.
    let mut rest = Groom {
        strand_vertex_counts: groom.strand_vertex_counts.clone(),
        points: groom.points.clone(),
        attributes: groom.attributes.clone(),
        units: groom.units,
        up_axis: groom.up_axis,
        ..Groom::default()
    };
    // Guides and render strands become two primitives: the guides' strands
    // are written first, then the render strands'.
    let mut order = None;
    let mut part_strands = vec![rest.strand_count()];
    if let Some(split) = rest.split_guides().filter(|_| rest.has_render_split()) {
        let offsets = rest.strand_offsets();
        let strands: Vec<usize> = split
            .guide_indices
            .iter()
            .chain(&split.render_indices)
            .copied()
            .collect();
        let mut ranges: Vec<std::ops::Range<usize>> = Vec::new();
        for &strand in &strands {
            let range = offsets[strand]..offsets[strand + 1];
            match ranges.last_mut() {
                Some(last) if last.end == range.start => last.end = range.end,
                _ => ranges.push(range),
            }
        }
        part_strands = vec![split.guide_indices.len(), split.render_indices.len()];
        rest = rest.subset(&strands);
        order = Some(ranges);
    }
    rest.convert_to(Units::METERS, UpAxis::Y);

    let mut indices = Vec::new();
    let mut parts = Vec::new();
    let mut counts = rest.strand_vertex_counts.iter();
    let mut part_start = 0usize;
    for strands in part_strands {
        let index_start = indices.len();
        let mut first = 0u32;
        for &count in counts.by_ref().take(strands) {
            // A one-point strand (an empty root of USC-HairSalon) becomes a
            // degenerate segment, so that it survives the round trip.
            if count == 1 {
                indices.extend([first, first]);
            }
            for k in 1..count {
                indices.push(first + k - 1);
                indices.push(first + k);
            }
            first = first
                .checked_add(count)
                .ok_or_else(|| invalid(path, "more points than glTF indices can address"))?;
        }
        let vertices = part_start..part_start + first as usize;
        let rest_bounds = groom::bounds_of(&rest.points[vertices.clone()])
            .ok_or_else(|| invalid(path, "the groom has no points"))?;
        parts.push(Part {
            vertices,
            indices: index_start..indices.len(),
            rest_bounds,
        });
        part_start += first as usize;
    }
    if parts.iter().any(|p| p.indices.is_empty()) {
        return Err(invalid(path, "the groom has no segments to draw as lines"));
    }
    let attributes = encode_attributes(&rest);
    let directory = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let spill = tempfile::tempfile_in(&directory)
        .or_else(|_| tempfile::tempfile())
        .map_err(|e| ExportError::io(path, e))?;
    Ok(GltfWriter {
        path: path.to_path_buf(),
        binary,
        scale: (groom.units.meters_per_unit) as f32,
        up: groom.up_axis,
        order,
        parts,
        rest: rest.points,
        indices,
        attributes,
        spill: BufWriter::with_capacity(1 << 20, spill),
        frame_times: Vec::new(),
        frame_bounds: Vec::new(),
    })
}

/// The `_NAME` semantic of an attribute: upper case, characters other than
/// ASCII letters, digits and `_` as `_`, and a `_2`, `_3`, ... suffix where
/// two names would otherwise meet (`width` and `Width`). The name itself
/// goes to the accessor's extras.
fn semantic_for(name: &str, taken: &mut std::collections::BTreeSet<String>) -> String {
    let base: String = std::iter::once('_')
        .chain(name.chars().map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_uppercase()
            } else {
                '_'
            }
        }))
        .collect();
    let mut semantic = base.clone();
    let mut suffix = 1;
    while !taken.insert(semantic.clone()) {
        suffix += 1;
        semantic = format!("{base}_{suffix}");
    }
    semantic
}

/// The largest magnitude up to which every integer is an f32.
const EXACT_FLOAT_INTEGER: i32 = 1 << 24;

fn encode_attributes(groom: &Groom) -> Vec<EncodedAttribute> {
    let mut encoded = Vec::new();
    let mut taken = std::collections::BTreeSet::new();
    let counts = &groom.strand_vertex_counts;
    for attribute in &groom.attributes {
        // Per-strand values are repeated on every vertex of their strand,
        // so that other tools see them; the extras mark the scope so that
        // the importer makes them per strand again.
        let per_vertex = |components: &[f32], width: usize| -> Vec<f32> {
            match attribute.scope {
                Scope::Vertex => components.to_vec(),
                Scope::Strand => counts
                    .iter()
                    .zip(components.chunks_exact(width))
                    .flat_map(|(&n, value)| std::iter::repeat_n(value, n as usize).flatten())
                    .copied()
                    .collect(),
            }
        };
        let marker = json!({
            "name": attribute.name,
            "scope": match attribute.scope {
                Scope::Vertex => "vertex",
                Scope::Strand => "strand",
            },
        });
        let scalar = |semantic: String, component_type: u32, bytes: Vec<u8>, marker: Value| {
            EncodedAttribute {
                semantic,
                component_type,
                accessor_type: "SCALAR",
                stride: 4,
                bytes,
                extras: json!({ EXTRAS_KEY: marker }),
            }
        };
        let float_bytes = |values: &[f32]| values.iter().flat_map(|v| v.to_le_bytes()).collect();
        match &attribute.values {
            AttributeValues::Vec2(uv) if attribute.name == ROOT_UV => {
                let flipped: Vec<f32> = uv.iter().flat_map(|&[u, v]| [u, 1.0 - v]).collect();
                encoded.push(EncodedAttribute {
                    semantic: "TEXCOORD_0".into(),
                    component_type: FLOAT,
                    accessor_type: "VEC2",
                    stride: 8,
                    bytes: float_bytes(&per_vertex(&flipped, 2)),
                    extras: json!({ EXTRAS_KEY: marker }),
                });
            }
            AttributeValues::Float(values) => encoded.push(scalar(
                semantic_for(&attribute.name, &mut taken),
                FLOAT,
                float_bytes(&per_vertex(values, 1)),
                marker,
            )),
            AttributeValues::Vec2(_) | AttributeValues::Vec3(_) => {
                // One scalar accessor per component, `_NAME_X`, `_NAME_Y`
                // (and `_NAME_Z`), marked with the component's place.
                let width = attribute.values.components();
                let flat = per_vertex(&attribute.values.to_f32_flat(), width);
                for (k, axis) in ["X", "Y", "Z"].iter().take(width).enumerate() {
                    let mut marker = marker.clone();
                    marker["component"] = json!(k);
                    marker["components"] = json!(width);
                    let column: Vec<f32> = flat.iter().skip(k).step_by(width).copied().collect();
                    encoded.push(scalar(
                        semantic_for(&format!("{}_{axis}", attribute.name), &mut taken),
                        FLOAT,
                        float_bytes(&column),
                        marker,
                    ));
                }
            }
            AttributeValues::Int(values) => {
                let values: Vec<i32> = match attribute.scope {
                    Scope::Vertex => values.clone(),
                    Scope::Strand => counts
                        .iter()
                        .zip(values)
                        .flat_map(|(&n, &v)| std::iter::repeat_n(v, n as usize))
                        .collect(),
                };
                encoded.extend(encode_integers(
                    &attribute.name,
                    &values,
                    marker,
                    &mut taken,
                ));
            }
        }
    }
    encoded
}

/// Integers as FLOAT scalars, which Blender imports (it drops SHORT and
/// UNSIGNED_SHORT ones): exact when every value is within 2^24, otherwise
/// two accessors holding the u16 low and high halves, marked as components
/// 0 and 1 of an `i32_as_u16_pair`.
fn encode_integers(
    name: &str,
    values: &[i32],
    mut marker: Value,
    taken: &mut std::collections::BTreeSet<String>,
) -> Vec<EncodedAttribute> {
    let fits_float = values
        .iter()
        .all(|&v| v.unsigned_abs() <= EXACT_FLOAT_INTEGER as u32);
    marker["type"] = json!("int");
    let scalar =
        |semantic: String, values: &mut dyn Iterator<Item = f32>, marker: Value| EncodedAttribute {
            semantic,
            component_type: FLOAT,
            accessor_type: "SCALAR",
            stride: 4,
            bytes: values.flat_map(f32::to_le_bytes).collect(),
            extras: json!({ EXTRAS_KEY: marker }),
        };
    if fits_float {
        return vec![scalar(
            semantic_for(name, taken),
            &mut values.iter().map(|&v| v as f32),
            marker,
        )];
    }
    marker["encoding"] = json!(INT_AS_U16_PAIR);
    marker["components"] = json!(2);
    [("LO", 0), ("HI", 16)]
        .into_iter()
        .enumerate()
        .map(|(k, (half, shift))| {
            let mut marker = marker.clone();
            marker["component"] = json!(k);
            scalar(
                semantic_for(&format!("{name}_{half}"), taken),
                &mut values
                    .iter()
                    .map(|&v| ((v as u32 >> shift) & 0xFFFF) as f32),
                marker,
            )
        })
        .collect()
}

impl FrameWriter for GltfWriter {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError> {
        let index = self.frame_times.len();
        if frame.points.len() != self.rest.len() {
            return Err(invalid(
                &self.path,
                format!(
                    "frame {index} has {} points, the groom {}",
                    frame.points.len(),
                    self.rest.len()
                ),
            ));
        }
        let time = frame.time as f32;
        if !(time.is_finite() && time >= 0.0) {
            return Err(invalid(
                &self.path,
                format!(
                    "frame {index}: time {} is not a non-negative number of seconds",
                    frame.time
                ),
            ));
        }
        if self.frame_times.last().is_some_and(|&last| time <= last) {
            return Err(invalid(
                &self.path,
                format!("frame {index}: time {} does not increase", frame.time),
            ));
        }
        let reordered: Vec<[f32; 3]>;
        let points = match &self.order {
            Some(ranges) => {
                reordered = ranges
                    .iter()
                    .flat_map(|r| frame.points[r.clone()].iter().copied())
                    .collect();
                &reordered[..]
            }
            None => &frame.points[..],
        };
        let mut bounds = Vec::with_capacity(self.parts.len());
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        let mut bytes = Vec::with_capacity(12 * frame.points.len());
        for (vertex, (p, rest)) in points.iter().zip(&self.rest).enumerate() {
            if self
                .parts
                .iter()
                .any(|part| part.vertices.start == vertex && vertex > 0)
            {
                bounds.push((min, max));
                min = [f32::INFINITY; 3];
                max = [f32::NEG_INFINITY; 3];
            }
            let moved = self.up.to_y_up(*p).map(|c| c * self.scale);
            let mut delta = [0.0f32; 3];
            for k in 0..3 {
                delta[k] = moved[k] - rest[k];
                if !delta[k].is_finite() {
                    return Err(invalid(
                        &self.path,
                        format!("frame {index}, vertex {vertex}: point is not finite"),
                    ));
                }
                min[k] = min[k].min(delta[k]);
                max[k] = max[k].max(delta[k]);
                bytes.extend_from_slice(&delta[k].to_le_bytes());
            }
        }
        self.spill
            .write_all(&bytes)
            .map_err(|e| ExportError::io(&self.path, e))?;
        bounds.push((min, max));
        self.frame_times.push(time);
        self.frame_bounds.push(bounds);
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<(), ExportError> {
        let path = self.path.clone();
        self.assemble().map_err(|e| ExportError::io(&path, e))?
    }
}

/// Where each part sits in the binary buffer.
struct Layout {
    parts: Vec<(usize, usize)>,
    total: usize,
}

impl Layout {
    fn new(sizes: &[usize]) -> Layout {
        let mut parts = Vec::with_capacity(sizes.len());
        let mut offset = 0;
        for &size in sizes {
            parts.push((offset, size));
            // Every part is a multiple of 4 bytes long, so offsets stay aligned.
            offset += size;
        }
        Layout {
            parts,
            total: offset,
        }
    }
}

fn vec3_json(v: [f32; 3]) -> Value {
    // f32 -> f64 is exact, so the validator's min/max check matches the data.
    json!([v[0] as f64, v[1] as f64, v[2] as f64])
}

impl GltfWriter {
    fn json(&self, layout: &Layout) -> Value {
        let frames = self.frame_times.len();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        let mut part = layout.parts.iter();
        let mut view = |target: Option<u32>, stride: Option<usize>| {
            let (offset, length) = part.next().copied().unwrap_or((0, 0));
            let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": length});
            if let Some(target) = target {
                v["target"] = json!(target);
            }
            if let Some(stride) = stride {
                v["byteStride"] = json!(stride);
            }
            views.push(v);
            views.len() - 1
        };
        // A vertex view that several primitives' accessors share must say
        // its stride.
        let shared = self.parts.len() > 1;
        let position_view = view(Some(ARRAY_BUFFER), shared.then_some(12));
        let index_view = view(Some(ELEMENT_ARRAY_BUFFER), None);
        let attribute_views: Vec<usize> = self
            .attributes
            .iter()
            .map(|a| {
                let stride = shared || a.component_type != FLOAT;
                view(Some(ARRAY_BUFFER), stride.then_some(a.stride))
            })
            .collect();
        let frame_views: Vec<usize> = (0..frames)
            .map(|_| view(Some(ARRAY_BUFFER), shared.then_some(12)))
            .collect();
        // Each part's accessors are windows of the shared views.
        let window = |mut accessor: Value, offset: usize| {
            if offset > 0 {
                accessor["byteOffset"] = json!(offset);
            }
            accessor
        };
        let mut primitives = Vec::new();
        let mut part_targets = Vec::new();
        for part in &self.parts {
            let count = part.vertices.len();
            let start = part.vertices.start;
            accessors.push(window(
                json!({
                    "bufferView": position_view, "componentType": FLOAT, "count": count, "type": "VEC3",
                    "min": vec3_json(part.rest_bounds.0), "max": vec3_json(part.rest_bounds.1),
                }),
                12 * start,
            ));
            let position = accessors.len() - 1;
            accessors.push(window(
                json!({
                    "bufferView": index_view, "componentType": UNSIGNED_INT, "count": part.indices.len(), "type": "SCALAR",
                }),
                4 * part.indices.start,
            ));
            let index = accessors.len() - 1;
            let mut attributes = serde_json::Map::new();
            attributes.insert("POSITION".into(), json!(position));
            for (attribute, &v) in self.attributes.iter().zip(&attribute_views) {
                accessors.push(window(
                    json!({
                        "bufferView": v, "componentType": attribute.component_type, "count": count,
                        "type": attribute.accessor_type, "extras": attribute.extras,
                    }),
                    attribute.stride * start,
                ));
                attributes.insert(attribute.semantic.clone(), json!(accessors.len() - 1));
            }
            primitives.push(json!({"attributes": attributes, "indices": index, "mode": LINES}));
            part_targets.push(Vec::new());
        }
        for (bounds, &v) in self.frame_bounds.iter().zip(&frame_views) {
            for ((part, (min, max)), targets) in
                self.parts.iter().zip(bounds).zip(&mut part_targets)
            {
                accessors.push(window(
                    json!({
                        "bufferView": v, "componentType": FLOAT, "count": part.vertices.len(), "type": "VEC3",
                        "min": vec3_json(*min), "max": vec3_json(*max),
                    }),
                    12 * part.vertices.start,
                ));
                targets.push(json!({"POSITION": accessors.len() - 1}));
            }
        }
        let mut mesh = json!({"name": "groom"});
        let mut document = json!({
            "asset": {"version": "2.0", "generator": concat!("groombake ", env!("CARGO_PKG_VERSION"))},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "name": "groom"}],
        });
        if frames > 0 {
            for (primitive, targets) in primitives.iter_mut().zip(part_targets) {
                primitive["targets"] = json!(targets);
            }
            mesh["weights"] = json!(vec![0.0; frames]);
            let names: Vec<String> = (0..frames).map(|k| format!("frame_{k}")).collect();
            mesh["extras"] = json!({"targetNames": names});
            let times_view = view(None, None);
            let first = self.frame_times.first().copied().unwrap_or(0.0) as f64;
            let last = self.frame_times.last().copied().unwrap_or(0.0) as f64;
            accessors.push(json!({
                "bufferView": times_view, "componentType": FLOAT, "count": frames, "type": "SCALAR",
                "min": [first], "max": [last],
            }));
            let weights_view = view(None, None);
            accessors.push(json!({
                "bufferView": weights_view, "componentType": FLOAT, "count": frames * frames, "type": "SCALAR",
            }));
            document["animations"] = json!([{
                "name": "groom",
                "samplers": [{"input": accessors.len() - 2, "output": accessors.len() - 1, "interpolation": "STEP"}],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            }]);
        }
        mesh["primitives"] = json!(primitives);
        document["meshes"] = json!([mesh]);
        document["accessors"] = json!(accessors);
        document["bufferViews"] = json!(views);
        let mut buffer = json!({"byteLength": layout.total});
        if !self.binary {
            buffer["uri"] = json!(URI_PLACEHOLDER);
        }
        document["buffers"] = json!([buffer]);
        document
    }

    fn layout(&self) -> Layout {
        let vertices = self.rest.len();
        let frames = self.frame_times.len();
        let mut sizes = vec![12 * vertices, 4 * self.indices.len()];
        sizes.extend(self.attributes.iter().map(|a| a.bytes.len()));
        sizes.extend(std::iter::repeat_n(12 * vertices, frames));
        if frames > 0 {
            sizes.push(4 * frames);
            // The weights are frames x frames floats (one-hot rows): quadratic,
            // but 4 bytes per entry stay small next to the frames' points.
            sizes.push(4 * frames * frames);
        }
        Layout::new(&sizes)
    }

    /// Writes the binary buffer: rest pose, indices, attributes, the spilled
    /// frames, then the sampler's times and weights.
    fn write_buffer(&mut self, out: &mut dyn Write) -> io::Result<()> {
        let mut chunk = Vec::with_capacity(1 << 16);
        let flush = |chunk: &mut Vec<u8>, out: &mut dyn Write, force: bool| {
            if force || chunk.len() >= 1 << 16 {
                out.write_all(chunk)?;
                chunk.clear();
            }
            io::Result::Ok(())
        };
        for value in self.rest.iter().flatten() {
            chunk.extend_from_slice(&value.to_le_bytes());
            flush(&mut chunk, out, false)?;
        }
        for value in &self.indices {
            chunk.extend_from_slice(&value.to_le_bytes());
            flush(&mut chunk, out, false)?;
        }
        flush(&mut chunk, out, true)?;
        for attribute in &self.attributes {
            out.write_all(&attribute.bytes)?;
        }
        self.spill.flush()?;
        let spill = self.spill.get_mut();
        spill.rewind()?;
        let copied = io::copy(&mut spill.take(u64::MAX), out)?;
        let expected = (12 * self.rest.len() * self.frame_times.len()) as u64;
        if copied != expected {
            return Err(io::Error::other(format!(
                "frame spill file has {copied} bytes, expected {expected}"
            )));
        }
        let frames = self.frame_times.len();
        if frames > 0 {
            for time in &self.frame_times {
                chunk.extend_from_slice(&time.to_le_bytes());
            }
            flush(&mut chunk, out, true)?;
            for row in 0..frames {
                for column in 0..frames {
                    let weight: f32 = if row == column { 1.0 } else { 0.0 };
                    chunk.extend_from_slice(&weight.to_le_bytes());
                    flush(&mut chunk, out, false)?;
                }
            }
            flush(&mut chunk, out, true)?;
        }
        Ok(())
    }

    fn assemble(mut self) -> io::Result<Result<(), ExportError>> {
        let layout = self.layout();
        let document = self.json(&layout);
        let text = serde_json::to_string(&document).map_err(io::Error::other)?;
        let mut out = AtomicFile::create(&self.path)?;
        if self.binary {
            let json_padded = text.len().next_multiple_of(4);
            let bin_padded = layout.total.next_multiple_of(4);
            let total = 12 + 8 + json_padded + 8 + bin_padded;
            let Ok(total32) = u32::try_from(total) else {
                return Ok(Err(invalid(
                    &self.path,
                    format!("the GLB would be {total} bytes, over the format's 4 GiB limit; write .gltf"),
                )));
            };
            out.write_all(b"glTF")?;
            out.write_all(&2u32.to_le_bytes())?;
            out.write_all(&total32.to_le_bytes())?;
            out.write_all(&(json_padded as u32).to_le_bytes())?;
            out.write_all(b"JSON")?;
            out.write_all(text.as_bytes())?;
            out.write_all(&b"   "[..json_padded - text.len()])?;
            out.write_all(&(bin_padded as u32).to_le_bytes())?;
            out.write_all(b"BIN\0")?;
            self.write_buffer(&mut out)?;
            out.write_all(&[0u8; 3][..bin_padded - layout.total])?;
        } else {
            let placeholder = format!("\"{URI_PLACEHOLDER}\"");
            let Some((before, after)) = text.split_once(&placeholder) else {
                return Err(io::Error::other(
                    "buffer URI placeholder missing from the JSON",
                ));
            };
            out.write_all(before.as_bytes())?;
            out.write_all(b"\"")?;
            out.write_all(DATA_URI_PREFIX.as_bytes())?;
            {
                let mut encoder = base64::write::EncoderWriter::new(
                    &mut out,
                    &base64::engine::general_purpose::STANDARD,
                );
                self.write_buffer(&mut encoder)?;
                encoder.finish()?;
            }
            out.write_all(b"\"")?;
            out.write_all(after.as_bytes())?;
            out.write_all(b"\n")?;
        }
        out.commit()?;
        Ok(Ok(()))
    }
}
