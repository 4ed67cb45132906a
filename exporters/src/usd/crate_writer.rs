//! `.usdc` crate writer (file version 0.8.0).
//!
//! Layout: the 88-byte bootstrap, then value data (arrays, doubles, token
//! vectors, time samples) in the order it is produced, then the structural
//! sections TOKENS, STRINGS, FIELDS, FIELDSETS, PATHS, SPECS and the table of
//! contents, whose offset is patched into the bootstrap last. Animated
//! exports write each frame's points as it arrives, so memory holds one
//! frame plus a value rep and an extent per frame.
//!
//! Arrays are written uncompressed (the reader takes either); structural
//! sections use the integer coding (deltas, 2-bit width codes) inside an LZ4
//! block made only of literals, which any LZ4 decoder accepts.

use super::structure::{children_of, default_prim, layout, roots, Step};
use super::{time_code, CurvesPrim, CurvesScene, PropertyValue};
use crate::{ExportError, FrameWriter};
use groom::{AtomicFile, Frame};
use std::collections::BTreeMap;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"PXR-USDC";
const VERSION: [u8; 3] = [0, 8, 0];
const BOOTSTRAP_SIZE: u64 = 88;

/// Crate value type ids (OpenUSD `crateDataTypes.h`).
mod type_id {
    pub const INT: u8 = 3;
    pub const FLOAT: u8 = 8;
    pub const DOUBLE: u8 = 9;
    pub const STRING: u8 = 10;
    pub const TOKEN: u8 = 11;
    pub const VEC2F: u8 = 20;
    pub const VEC3F: u8 = 24;
    pub const VEC3I: u8 = 26;
    pub const TOKEN_VECTOR: u8 = 41;
    pub const SPECIFIER: u8 = 42;
    pub const VARIABILITY: u8 = 44;
    pub const TIME_SAMPLES: u8 = 46;
    pub const DOUBLE_VECTOR: u8 = 48;
}

/// `SdfSpecType` values.
const SPEC_ATTRIBUTE: u32 = 1;
const SPEC_PRIM: u32 = 6;
const SPEC_PSEUDO_ROOT: u32 = 7;

const ARRAY_BIT: u64 = 1 << 63;
const INLINED_BIT: u64 = 1 << 62;
const PAYLOAD_MASK: u64 = (1 << 48) - 1;

/// LZ4's largest block input; bigger sections would need TfFastCompression's
/// chunked form, which we do not write.
const LZ4_MAX_INPUT: usize = 0x7E00_0000;

fn value_rep(type_id: u8, array: bool, inlined: bool, payload: u64) -> u64 {
    let mut rep = (u64::from(type_id) << 48) | (payload & PAYLOAD_MASK);
    if array {
        rep |= ARRAY_BIT;
    }
    if inlined {
        rep |= INLINED_BIT;
    }
    rep
}

fn inlined(type_id: u8, payload: u64) -> u64 {
    value_rep(type_id, false, true, payload)
}

/// Writes a static scene, or one whose prims hold time-sampled properties
/// ([`CurvesPrim::sampled`](super::CurvesPrim)).
pub(super) fn write_static(path: &Path, scene: &CurvesScene) -> Result<(), ExportError> {
    let mut writer = CrateWriter::create(path, scene)?;
    if scene.codes.is_empty() {
        return writer.finish(scene, None);
    }
    let mut samples = Samples {
        times: scene.codes.clone(),
        reps: BTreeMap::new(),
    };
    for (index, prim) in scene.prims.iter().enumerate() {
        for (name, values) in &prim.sampled {
            let mut reps = Vec::with_capacity(values.len());
            for value in values {
                if let Some(rep) = writer.write_value(value)? {
                    reps.push(rep);
                }
            }
            samples.reps.insert((index, name.clone()), reps);
        }
    }
    writer.finish(scene, Some(samples))
}

/// Time samples: one rep per time of each sampled property, by prim index
/// and property name (`points` and `extent` of an animated export).
struct Samples {
    times: Vec<f64>,
    reps: BTreeMap<(usize, String), Vec<u64>>,
}

/// The open file plus the reps of the static property values.
struct CrateWriter {
    path: PathBuf,
    file: AtomicFile,
    position: u64,
    /// Rep of each property's default value, by prim index and property
    /// name.
    defaults: BTreeMap<(usize, String), u64>,
    scratch: Vec<u8>,
}

impl CrateWriter {
    fn create(path: &Path, scene: &CurvesScene) -> Result<CrateWriter, ExportError> {
        let file = AtomicFile::create(path).map_err(|e| ExportError::io(path, e))?;
        let mut writer = CrateWriter {
            path: path.to_path_buf(),
            file,
            position: 0,
            defaults: BTreeMap::new(),
            scratch: Vec::new(),
        };
        // The bootstrap is written again with the table-of-contents offset.
        writer.write_bytes(&[0u8; BOOTSTRAP_SIZE as usize])?;
        for (prim, property) in scene
            .prims
            .iter()
            .enumerate()
            .flat_map(|(k, p)| p.properties.iter().map(move |q| (k, p, q)))
            .filter(|(_, p, q)| p.samples_of(&q.name).is_none())
            .map(|(k, _, q)| (k, q))
        {
            // Tokens are inlined once their index is known, in `finish`.
            if let Some(rep) = writer.write_value(&property.value)? {
                writer.defaults.insert((prim, property.name.clone()), rep);
            }
        }
        Ok(writer)
    }

    /// Writes an array value; `None` for tokens (inlined in `finish`).
    fn write_value(&mut self, value: &PropertyValue) -> Result<Option<u64>, ExportError> {
        Ok(Some(match value {
            PropertyValue::Token(_) => return Ok(None),
            PropertyValue::Ints(v) => self.write_array(
                type_id::INT,
                v.len(),
                v.iter().flat_map(|x| x.to_le_bytes()),
            )?,
            PropertyValue::Floats(v) => self.write_array(
                type_id::FLOAT,
                v.len(),
                v.iter().flat_map(|x| x.to_le_bytes()),
            )?,
            PropertyValue::Float2s(v) => self.write_array(
                type_id::VEC2F,
                v.len(),
                v.iter().flatten().flat_map(|x| x.to_le_bytes()),
            )?,
            PropertyValue::Float3s(v) => self.write_float3s(v)?,
            PropertyValue::Int3s(v) => self.write_array(
                type_id::VEC3I,
                v.len(),
                v.iter().flatten().flat_map(|x| x.to_le_bytes()),
            )?,
        }))
    }

    fn io_error(&self, error: io::Error) -> ExportError {
        ExportError::io(&self.path, error)
    }

    fn write_bytes(&mut self, bytes: &[u8]) -> Result<u64, ExportError> {
        let start = self.position;
        if let Err(e) = self.file.write_all(bytes) {
            return Err(self.io_error(e));
        }
        self.position += bytes.len() as u64;
        Ok(start)
    }

    /// Writes `u64 count` then the elements' bytes; returns the array rep.
    fn write_array(
        &mut self,
        type_id: u8,
        count: usize,
        bytes: impl Iterator<Item = u8>,
    ) -> Result<u64, ExportError> {
        if count == 0 {
            // An empty array is a rep with payload 0 and no data.
            return Ok(value_rep(type_id, true, false, 0));
        }
        // Arrays start on 8-byte boundaries, as OpenUSD writes them, so a
        // reader mapping the file may use the data in place.
        let padding = (8 - self.position % 8) % 8;
        self.write_bytes(&[0u8; 8][..padding as usize])?;
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        scratch.extend_from_slice(&(count as u64).to_le_bytes());
        scratch.extend(bytes);
        let start = self.write_bytes(&scratch);
        self.scratch = scratch;
        Ok(value_rep(type_id, true, false, start?))
    }

    fn write_float3s(&mut self, values: &[[f32; 3]]) -> Result<u64, ExportError> {
        self.write_array(
            type_id::VEC3F,
            values.len(),
            values.iter().flatten().flat_map(|x| x.to_le_bytes()),
        )
    }

    fn write_double(&mut self, value: f64) -> Result<u64, ExportError> {
        let start = self.write_bytes(&value.to_le_bytes())?;
        Ok(value_rep(type_id::DOUBLE, false, false, start))
    }

    fn write_token_vector(&mut self, indices: &[u32]) -> Result<u64, ExportError> {
        let mut bytes = (indices.len() as u64).to_le_bytes().to_vec();
        bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
        let start = self.write_bytes(&bytes)?;
        Ok(value_rep(type_id::TOKEN_VECTOR, false, false, start))
    }

    /// Writes the times once and the time samples structure of one property:
    /// recursive offset (8) to the times rep, the rep, recursive offset (8)
    /// to the count, the count, the value reps.
    fn write_time_samples(&mut self, times_rep: u64, reps: &[u64]) -> Result<u64, ExportError> {
        let mut bytes = Vec::with_capacity(32 + 8 * reps.len());
        bytes.extend_from_slice(&8i64.to_le_bytes());
        bytes.extend_from_slice(&times_rep.to_le_bytes());
        bytes.extend_from_slice(&8i64.to_le_bytes());
        bytes.extend_from_slice(&(reps.len() as u64).to_le_bytes());
        bytes.extend(reps.iter().flat_map(|r| r.to_le_bytes()));
        let start = self.write_bytes(&bytes)?;
        Ok(value_rep(type_id::TIME_SAMPLES, false, false, start))
    }

    /// The specs of curves prim `index` and its properties, under `parent`.
    fn curves_specs(
        &mut self,
        layer: &mut Layer,
        parent: u32,
        index: usize,
        prim: &CurvesPrim,
        sampled: &BTreeMap<(usize, String), u64>,
    ) -> Result<(), ExportError> {
        let curves_path = layer.path(Some(parent), &prim.name, false);
        let property_tokens: Vec<u32> = prim
            .properties
            .iter()
            .map(|p| layer.token(&p.name))
            .collect();
        let basis_curves = layer.token("BasisCurves");
        let fields = [
            ("specifier", inlined(type_id::SPECIFIER, 0)),
            ("typeName", inlined(type_id::TOKEN, basis_curves.into())),
            ("properties", self.write_token_vector(&property_tokens)?),
        ];
        layer.spec(curves_path, SPEC_PRIM, &fields);

        for property in &prim.properties {
            let path = layer.path(Some(curves_path), &property.name, true);
            let type_name = layer.token(property.type_name);
            let mut fields = vec![("typeName", inlined(type_id::TOKEN, type_name.into()))];
            if property.uniform {
                fields.push(("variability", inlined(type_id::VARIABILITY, 1)));
            }
            if let Some(interpolation) = property.interpolation {
                let token = layer.token(interpolation);
                fields.push(("interpolation", inlined(type_id::TOKEN, token.into())));
            }
            let default = match &property.value {
                PropertyValue::Token(token) => {
                    Some(inlined(type_id::TOKEN, layer.token(token).into()))
                }
                _ => self.defaults.get(&(index, property.name.clone())).copied(),
            };
            if let Some(default) = default {
                fields.push(("default", default));
            }
            if let Some(&rep) = sampled.get(&(index, property.name.clone())) {
                fields.push(("timeSamples", rep));
            }
            layer.spec(path, SPEC_ATTRIBUTE, &fields);
        }
        Ok(())
    }

    /// Writes the specs, the structural sections and the table of contents,
    /// then patches the bootstrap and renames the file into place.
    fn finish(mut self, scene: &CurvesScene, samples: Option<Samples>) -> Result<(), ExportError> {
        let mut layer = Layer::default();
        let mut strings: Vec<u32> = Vec::new();

        // Time samples: one shared times vector.
        let mut sampled: BTreeMap<(usize, String), u64> = BTreeMap::new();
        let mut time_range = None;
        if let Some(samples) = &samples {
            let mut bytes = (samples.times.len() as u64).to_le_bytes().to_vec();
            bytes.extend(samples.times.iter().flat_map(|t| t.to_le_bytes()));
            let start = self.write_bytes(&bytes)?;
            let times_rep = value_rep(type_id::DOUBLE_VECTOR, false, false, start);
            for (key, reps) in &samples.reps {
                let rep = self.write_time_samples(times_rep, reps)?;
                sampled.insert(key.clone(), rep);
            }
            time_range = samples.times.first().zip(samples.times.last());
        }

        // The pseudo-root: stage metadata.
        let mut root_fields = Vec::new();
        let root_token = layer.token(default_prim(&scene.prims));
        root_fields.push(("defaultPrim", inlined(type_id::TOKEN, root_token.into())));
        let doc = layer.token("Written by groombake");
        strings.push(doc);
        root_fields.push(("documentation", inlined(type_id::STRING, 0)));
        if let (Some(timing), Some((&start, &end))) = (scene.timing, time_range) {
            root_fields.push(("endTimeCode", self.write_double(end)?));
            root_fields.push(("framesPerSecond", self.write_double(timing.fps)?));
            root_fields.push(("metersPerUnit", self.write_double(scene.meters_per_unit)?));
            root_fields.push(("startTimeCode", self.write_double(start)?));
            root_fields.push(("timeCodesPerSecond", self.write_double(timing.fps)?));
        } else {
            root_fields.push(("metersPerUnit", self.write_double(scene.meters_per_unit)?));
        }
        let up = layer.token(scene.up_axis);
        root_fields.push(("upAxis", inlined(type_id::TOKEN, up.into())));
        let root_tokens: Vec<u32> = roots(&scene.prims)
            .into_iter()
            .map(|name| layer.token(name))
            .collect();
        root_fields.push(("primChildren", self.write_token_vector(&root_tokens)?));
        let root_path = layer.path(None, "", false);
        layer.spec(root_path, SPEC_PSEUDO_ROOT, &root_fields);

        // The Xform parents and the curves prims, depth-first.
        let mut open: Vec<(u32, Vec<String>)> = Vec::new();
        for step in layout(&scene.prims) {
            match step {
                Step::Open { name, depth } => {
                    open.truncate(depth);
                    let parent = open.last().map_or(root_path, |(path, _)| *path);
                    let xform_path = layer.path(Some(parent), &name, false);
                    let mut prefix = open.last().map(|(_, p)| p.clone()).unwrap_or_default();
                    prefix.push(name);
                    let child_tokens: Vec<u32> = children_of(&scene.prims, &prefix)
                        .into_iter()
                        .map(|child| layer.token(child))
                        .collect();
                    let xform = layer.token("Xform");
                    let fields = [
                        ("specifier", inlined(type_id::SPECIFIER, 0)),
                        ("typeName", inlined(type_id::TOKEN, xform.into())),
                        ("primChildren", self.write_token_vector(&child_tokens)?),
                    ];
                    layer.spec(xform_path, SPEC_PRIM, &fields);
                    open.push((xform_path, prefix));
                }
                Step::Close { depth } => open.truncate(depth),
                Step::Curves { index, depth } => {
                    let Some(prim) = scene.prims.get(index) else {
                        continue;
                    };
                    open.truncate(depth);
                    let parent = open.last().map_or(root_path, |(path, _)| *path);
                    self.curves_specs(&mut layer, parent, index, prim, &sampled)?;
                }
            }
        }

        // Structural sections.
        let mut sections: Vec<(&str, u64, u64)> = Vec::new();
        let contents = [
            ("TOKENS", layer.tokens_section()),
            ("STRINGS", strings_section(&strings)),
            ("FIELDS", layer.fields_section()),
            ("FIELDSETS", layer.fieldsets_section()),
            ("PATHS", layer.paths_section()),
            ("SPECS", layer.specs_section()),
        ];
        for (name, bytes) in contents {
            let bytes = bytes.map_err(|message| ExportError::Invalid {
                file: self.path.clone(),
                message,
            })?;
            let start = self.write_bytes(&bytes)?;
            sections.push((name, start, bytes.len() as u64));
        }
        let mut toc = (sections.len() as u64).to_le_bytes().to_vec();
        for (name, start, size) in &sections {
            let mut padded = [0u8; 16];
            padded[..name.len()].copy_from_slice(name.as_bytes());
            toc.extend_from_slice(&padded);
            toc.extend_from_slice(&start.to_le_bytes());
            toc.extend_from_slice(&size.to_le_bytes());
        }
        let toc_offset = self.write_bytes(&toc)?;

        let mut bootstrap = Vec::with_capacity(BOOTSTRAP_SIZE as usize);
        bootstrap.extend_from_slice(MAGIC);
        bootstrap.extend_from_slice(&VERSION);
        bootstrap.extend_from_slice(&[0u8; 5]);
        bootstrap.extend_from_slice(&toc_offset.to_le_bytes());
        bootstrap.resize(BOOTSTRAP_SIZE as usize, 0);
        let path = self.path.clone();
        let io_error = |e| ExportError::io(&path, e);
        self.file.seek(SeekFrom::Start(0)).map_err(io_error)?;
        self.file.write_all(&bootstrap).map_err(io_error)?;
        self.file.commit().map_err(io_error)
    }
}

/// Tokens, fields, field sets, paths and specs being collected.
#[derive(Default)]
struct Layer {
    tokens: Vec<String>,
    token_index: BTreeMap<String, u32>,
    /// `(name token, value rep)`, deduplicated.
    fields: Vec<(u32, u64)>,
    field_index: BTreeMap<(u32, u64), u32>,
    /// Field indices of each spec, each set ended by `u32::MAX`.
    fieldsets: Vec<u32>,
    /// `(parent, element token, is property)` in depth-first order: every
    /// path is added right after its parent's earlier descendants.
    paths: Vec<(Option<u32>, u32, bool)>,
    /// `(path, fieldset start, spec type)`.
    specs: Vec<(u32, u32, u32)>,
}

impl Layer {
    fn token(&mut self, text: &str) -> u32 {
        if let Some(&index) = self.token_index.get(text) {
            return index;
        }
        let index = self.tokens.len() as u32;
        self.tokens.push(text.to_string());
        self.token_index.insert(text.to_string(), index);
        index
    }

    fn path(&mut self, parent: Option<u32>, element: &str, property: bool) -> u32 {
        let token = self.token(element);
        self.paths.push((parent, token, property));
        (self.paths.len() - 1) as u32
    }

    fn spec(&mut self, path: u32, spec_type: u32, fields: &[(&str, u64)]) {
        let start = self.fieldsets.len() as u32;
        for &(name, rep) in fields {
            let token = self.token(name);
            let next = self.fields.len() as u32;
            let index = *self.field_index.entry((token, rep)).or_insert(next);
            if index == next {
                self.fields.push((token, rep));
            }
            self.fieldsets.push(index);
        }
        self.fieldsets.push(u32::MAX);
        self.specs.push((path, start, spec_type));
    }

    fn tokens_section(&self) -> Result<Vec<u8>, String> {
        let mut text = Vec::new();
        for token in &self.tokens {
            text.extend_from_slice(token.as_bytes());
            text.push(0);
        }
        let mut out = (self.tokens.len() as u64).to_le_bytes().to_vec();
        out.extend_from_slice(&(text.len() as u64).to_le_bytes());
        push_compressed(&mut out, &text)?;
        Ok(out)
    }

    fn fields_section(&self) -> Result<Vec<u8>, String> {
        let mut out = (self.fields.len() as u64).to_le_bytes().to_vec();
        let tokens: Vec<i64> = self.fields.iter().map(|f| i64::from(f.0)).collect();
        push_compressed(&mut out, &encode_ints32(&tokens))?;
        let reps: Vec<u8> = self.fields.iter().flat_map(|f| f.1.to_le_bytes()).collect();
        push_compressed(&mut out, &reps)?;
        Ok(out)
    }

    fn fieldsets_section(&self) -> Result<Vec<u8>, String> {
        let mut out = (self.fieldsets.len() as u64).to_le_bytes().to_vec();
        // The terminator u32::MAX is stored as the 32-bit integer -1.
        let values: Vec<i64> = self
            .fieldsets
            .iter()
            .map(|&i| i64::from(i as i32))
            .collect();
        push_compressed(&mut out, &encode_ints32(&values))?;
        Ok(out)
    }

    /// Path tree in depth-first order with, per entry: path index, element
    /// token (negated for properties), and the jump: -2 leaf, -1 child
    /// only, 0 sibling only, n > 0 child next and sibling n entries on.
    fn paths_section(&self) -> Result<Vec<u8>, String> {
        let count = self.paths.len();
        let children = |parent: Option<u32>| -> Vec<u32> {
            (0..count as u32)
                .filter(|&i| self.paths.get(i as usize).is_some_and(|p| p.0 == parent))
                .collect()
        };
        // (path, has next sibling); explicit stack, children pushed reversed.
        let mut stack: Vec<(u32, bool)> = children(None).into_iter().map(|p| (p, false)).collect();
        let mut entries: Vec<(u32, bool, bool)> = Vec::with_capacity(count);
        while let Some((path, has_sibling)) = stack.pop() {
            let kids = children(Some(path));
            entries.push((path, !kids.is_empty(), has_sibling));
            let last = kids.len().saturating_sub(1);
            for (i, kid) in kids.into_iter().enumerate().rev() {
                stack.push((kid, i != last));
            }
        }
        // Subtree sizes give the sibling jumps.
        let mut subtree = vec![1i64; entries.len()];
        for index in (0..entries.len()).rev() {
            let path = entries[index].0;
            let mut size = 1i64;
            let mut next = index + 1;
            while next < entries.len() && self.is_descendant(entries[next].0, path) {
                size += 1;
                next += 1;
            }
            subtree[index] = size;
        }
        let mut path_indexes = Vec::with_capacity(count);
        let mut element_tokens = Vec::with_capacity(count);
        let mut jumps = Vec::with_capacity(count);
        for (index, &(path, has_child, has_sibling)) in entries.iter().enumerate() {
            let (_, token, property) = self.paths[path as usize];
            if property && token == 0 {
                return Err("a property name is token 0, which cannot be negated".into());
            }
            path_indexes.push(i64::from(path));
            element_tokens.push(if property {
                -i64::from(token)
            } else {
                i64::from(token)
            });
            jumps.push(match (has_child, has_sibling) {
                (false, false) => -2,
                (true, false) => -1,
                (false, true) => 0,
                (true, true) => subtree[index],
            });
        }
        let mut out = (count as u64).to_le_bytes().to_vec();
        out.extend_from_slice(&(count as u64).to_le_bytes());
        push_compressed(&mut out, &encode_ints32(&path_indexes))?;
        push_compressed(&mut out, &encode_ints32(&element_tokens))?;
        push_compressed(&mut out, &encode_ints32(&jumps))?;
        Ok(out)
    }

    fn is_descendant(&self, mut path: u32, ancestor: u32) -> bool {
        while let Some(&(Some(parent), _, _)) = self.paths.get(path as usize) {
            if parent == ancestor {
                return true;
            }
            path = parent;
        }
        false
    }

    fn specs_section(&self) -> Result<Vec<u8>, String> {
        let mut out = (self.specs.len() as u64).to_le_bytes().to_vec();
        let column = |f: fn(&(u32, u32, u32)) -> u32| -> Vec<i64> {
            self.specs.iter().map(|s| i64::from(f(s) as i32)).collect()
        };
        push_compressed(&mut out, &encode_ints32(&column(|s| s.0)))?;
        push_compressed(&mut out, &encode_ints32(&column(|s| s.1)))?;
        push_compressed(&mut out, &encode_ints32(&column(|s| s.2)))?;
        Ok(out)
    }
}

fn strings_section(strings: &[u32]) -> Result<Vec<u8>, String> {
    let mut out = (strings.len() as u64).to_le_bytes().to_vec();
    out.extend(strings.iter().flat_map(|s| s.to_le_bytes()));
    Ok(out)
}

/// Appends `u64 compressed size` and the TfFastCompression form of `data`:
/// a zero chunk-count byte and one LZ4 block of literals.
fn push_compressed(out: &mut Vec<u8>, data: &[u8]) -> Result<(), String> {
    if data.len() > LZ4_MAX_INPUT {
        return Err(format!(
            "a section of {} bytes is larger than one LZ4 block",
            data.len()
        ));
    }
    let block = lz4_literal_block(data);
    out.extend_from_slice(&((block.len() + 1) as u64).to_le_bytes());
    out.push(0);
    out.extend_from_slice(&block);
    Ok(())
}

/// An LZ4 block holding `data` as one run of literals (no matches).
pub(crate) fn lz4_literal_block(data: &[u8]) -> Vec<u8> {
    let mut block = Vec::with_capacity(data.len() + data.len() / 255 + 2);
    let length = data.len();
    if length < 15 {
        block.push((length as u8) << 4);
    } else {
        block.push(0xF0);
        let mut rest = length - 15;
        while rest >= 255 {
            block.push(255);
            rest -= 255;
        }
        block.push(rest as u8);
    }
    block.extend_from_slice(data);
    block
}

/// OpenUSD's integer coding of 32-bit ints: the most common delta (ties go
/// to the smallest), 2-bit codes four to a byte (0 common, 1 i8, 2 i16,
/// 3 i32), then the deltas that are not the common one.
pub(crate) fn encode_ints32(values: &[i64]) -> Vec<u8> {
    let mut previous = 0i64;
    let deltas: Vec<i32> = values
        .iter()
        .map(|&v| {
            let delta = (v as i32).wrapping_sub(previous as i32);
            previous = v;
            delta
        })
        .collect();
    let mut frequency: BTreeMap<i32, usize> = BTreeMap::new();
    for &d in &deltas {
        *frequency.entry(d).or_default() += 1;
    }
    let common = frequency
        .iter()
        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
        .map_or(0, |(&d, _)| d);
    let mut out = common.to_le_bytes().to_vec();
    let codes_start = out.len();
    out.resize(codes_start + (deltas.len() * 2).div_ceil(8), 0);
    for (index, &delta) in deltas.iter().enumerate() {
        let code: u8 = if delta == common {
            0
        } else if i8::try_from(delta).is_ok() {
            out.extend_from_slice(&(delta as i8).to_le_bytes());
            1
        } else if i16::try_from(delta).is_ok() {
            out.extend_from_slice(&(delta as i16).to_le_bytes());
            2
        } else {
            out.extend_from_slice(&delta.to_le_bytes());
            3
        };
        if let Some(byte) = out.get_mut(codes_start + index / 4) {
            *byte |= code << (2 * (index % 4));
        }
    }
    out
}

/// Streams the frames of an animated `.usdc` export.
pub(super) struct AnimatedCrate {
    writer: CrateWriter,
    scene: CurvesScene,
    samples: Samples,
    /// The time-varying attributes every frame carries (the first sets them).
    animated: Option<Vec<String>>,
    /// The last value written of each time-varying property and its rep: a
    /// value that holds from one frame to the next is stored once.
    last: BTreeMap<(usize, String), (PropertyValue, u64)>,
}

impl AnimatedCrate {
    pub fn create(path: &Path, mut scene: CurvesScene) -> Result<AnimatedCrate, ExportError> {
        let writer = CrateWriter::create(path, &scene)?;
        // The arrays are in the file; `finish` needs only their reps.
        scene.forget_values();
        let prims = scene.prims.len();
        let rest_only: Vec<bool> = scene.prims.iter().map(|p| p.rest_only).collect();
        Ok(AnimatedCrate {
            writer,
            scene,
            samples: Samples {
                times: Vec::new(),
                reps: (0..prims)
                    .filter(|&k| !rest_only[k])
                    .flat_map(|k| {
                        [
                            ((k, "points".into()), Vec::new()),
                            ((k, "extent".into()), Vec::new()),
                        ]
                    })
                    .collect(),
            },
            animated: None,
            last: BTreeMap::new(),
        })
    }
}

impl FrameWriter for AnimatedCrate {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError> {
        self.scene.check_frame(&self.writer.path, frame)?;
        let fps = self.scene.timing.map_or(1.0, |t| t.fps);
        let code = time_code(frame.time, fps);
        if self.samples.times.last().is_some_and(|&last| code <= last) {
            return Err(ExportError::Invalid {
                file: self.writer.path.clone(),
                message: format!("frame time codes must increase (time code {code})"),
            });
        }
        super::frame_values::check_names(&self.writer.path, &mut self.animated, frame)?;
        for (index, prim) in self.scene.prims.iter().enumerate() {
            // A guide cache's render hair: its rest pose is its default.
            if prim.rest_only {
                continue;
            }
            let points = prim.points_of(&frame.points);
            let points_rep = self.writer.write_float3s(&points)?;
            let extent_rep = self.writer.write_float3s(&prim.extent(&points))?;
            for (name, rep) in [("points", points_rep), ("extent", extent_rep)] {
                if let Some(reps) = self.samples.reps.get_mut(&(index, name.to_string())) {
                    reps.push(rep);
                }
            }
            for (property, value) in
                super::frame_values::prim_values(&self.writer.path, prim, frame)?
            {
                let key = (index, property);
                let rep = match self.last.get(&key) {
                    Some((last, rep)) if *last == value => *rep,
                    _ => {
                        let rep = self.writer.write_value(&value)?.unwrap_or_default();
                        self.last.insert(key.clone(), (value, rep));
                        rep
                    }
                };
                self.samples.reps.entry(key).or_default().push(rep);
            }
        }
        self.samples.times.push(code);
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<(), ExportError> {
        let this = *self;
        if this.samples.times.is_empty() {
            return Err(ExportError::Invalid {
                file: this.writer.path.clone(),
                message: "an animated export needs at least one frame".into(),
            });
        }
        this.writer.finish(&this.scene, Some(this.samples))
    }
}
