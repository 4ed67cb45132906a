//! `.usdc` crate reader (versions 0.4.0 and later 0.x).
//!
//! Every count and offset read from the file is checked against the bytes
//! there before it is used; buffers grow with the data actually decoded,
//! never with a size the file claims. Compressed integers are bounded
//! twice before they are decoded: by what their compressed bytes can hold
//! at all, and, because LZ4 and the integer coding let one byte stand for
//! about a thousand integers, by a decode budget of a few times the file's
//! size. Errors name the byte offset and the section or value being read.

use super::{Arc, ArcKind, ArcTarget, LayerOffset, Prim, Specifier, Stage, UsdAttribute, Value};
use crate::{ImportError, Place};
use std::cell::Cell;
use std::collections::BTreeMap;
use std::path::Path;

const BOOTSTRAP_SIZE: u64 = 88;
/// Arrays shorter than this are stored raw even when flagged compressed.
const MIN_COMPRESSED_ARRAY_SIZE: u64 = 16;

const ARRAY_BIT: u64 = 1 << 63;
const INLINED_BIT: u64 = 1 << 62;
const COMPRESSED_BIT: u64 = 1 << 61;
const PAYLOAD_MASK: u64 = (1 << 48) - 1;

/// Header bits of a list op (OpenUSD's `_ListOpHeader`).
const LIST_OP_EXPLICIT: u8 = 1 << 1;
const LIST_OP_ADDED: u8 = 1 << 2;
const LIST_OP_DELETED: u8 = 1 << 3;
const LIST_OP_ORDERED: u8 = 1 << 4;
const LIST_OP_PREPENDED: u8 = 1 << 5;
const LIST_OP_APPENDED: u8 = 1 << 6;

/// What the items of a composition list op are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ArcItem {
    /// A path index (inherits, specializes).
    Path,
    /// Asset string, path, layer offset, custom data (references).
    Reference,
    /// Asset string, path, and a layer offset from crate 0.8.0 (payloads).
    Payload,
}

impl ArcItem {
    /// The fewest bytes an item takes in a file of `version`.
    fn min_size(self, version: (u8, u8, u8)) -> u64 {
        match self {
            ArcItem::Path => 4,
            ArcItem::Reference => 4 + 4 + 16 + 8,
            ArcItem::Payload if version >= (0, 8, 0) => 4 + 4 + 16,
            ArcItem::Payload => 4 + 4,
        }
    }
}

/// What the decoded tables, integer arrays and path texts of one file may
/// take: `DECODE_FACTOR` times its bytes plus `DECODE_ALLOWANCE`. Real
/// files decode to about their own size (points are stored raw); a
/// crafted one can make each compressed byte a thousand integers.
const DECODE_FACTOR: u64 = 16;
const DECODE_ALLOWANCE: u64 = 64 << 20;
/// At most this many bytes come out of one byte of an LZ4 block (a
/// match-length byte of 255 adds 255 bytes).
const LZ4_MAX_RATIO: u64 = 255;
/// Path tree depth (the text reader's nesting bound).
const MAX_PATH_DEPTH: usize = 256;

const SPEC_ATTRIBUTE: u32 = 1;
const SPEC_PRIM: u32 = 6;
const SPEC_PSEUDO_ROOT: u32 = 7;

type Result<T> = std::result::Result<T, ImportError>;
/// `(field name, value rep)` of one spec.
type Fields = Vec<(String, u64)>;

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<Stage> {
    let mut reader = CrateReader::new(path, bytes, false);
    reader.structure()?;
    reader.stage()
}

/// [`read`], but the array values of time samples that
/// [`super::stream::deferrable`] names are left undecoded, as
/// [`Value::Deferred`] with their value rep: a frame-at-a-time reader
/// decodes them with [`decode`] when it reaches their frame.
pub(super) fn read_deferred(path: &Path, bytes: &[u8]) -> Result<Stage> {
    let mut reader = CrateReader::new(path, bytes, true);
    reader.structure()?;
    reader.stage()
}

/// Decodes value reps of the crate file `bytes` (ones that
/// [`read_deferred`] left as [`Value::Deferred`]), each with what names it
/// in errors; nothing is read when there are none.
pub(super) fn decode(path: &Path, bytes: &[u8], reps: &[(u64, String)]) -> Result<Vec<Value>> {
    if reps.is_empty() {
        return Ok(Vec::new());
    }
    let mut reader = CrateReader::new(path, bytes, false);
    reader.structure()?;
    reps.iter()
        .map(|(rep, what)| reader.value(*rep, what, 1))
        .collect()
}

/// How the numbers of an element are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    U8,
    I32,
    U32,
    I64,
    U64,
    F16,
    F32,
    F64,
}

impl Scalar {
    fn size(self) -> u64 {
        match self {
            Scalar::U8 => 1,
            Scalar::F16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    fn decode(self, bytes: &[u8]) -> f64 {
        let mut raw = [0u8; 8];
        let n = bytes.len().min(8);
        raw[..n].copy_from_slice(&bytes[..n]);
        let word = u64::from_le_bytes(raw);
        match self {
            Scalar::U8 => f64::from(raw[0]),
            Scalar::I32 => f64::from(word as u32 as i32),
            Scalar::U32 => f64::from(word as u32),
            Scalar::I64 => word as i64 as f64,
            Scalar::U64 => word as f64,
            Scalar::F16 => f64::from(half_to_f32(word as u16)),
            Scalar::F32 => f64::from(f32::from_bits(word as u32)),
            Scalar::F64 => f64::from_bits(word),
        }
    }
}

/// What a crate type id holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Numbers {
        scalar: Scalar,
        components: usize,
        matrix: bool,
        quaternion: bool,
    },
    Token,
    String,
    AssetPath,
    TokenVector,
    StringVector,
    /// `SdfPathListOp` (inherits, specializes).
    PathListOp,
    /// `SdfReferenceListOp`.
    ReferenceListOp,
    /// `SdfPayloadListOp`, and a single `SdfPayload` (older files).
    PayloadListOp,
    Payload,
    DoubleVector,
    Specifier,
    Variability,
    TimeSamples,
    Other,
}

fn kind_of(type_id: u8) -> Kind {
    let numbers = |scalar, components| Kind::Numbers {
        scalar,
        components,
        matrix: false,
        quaternion: false,
    };
    let matrix = |components| Kind::Numbers {
        scalar: Scalar::F64,
        components,
        matrix: true,
        quaternion: false,
    };
    let quaternion = |scalar| Kind::Numbers {
        scalar,
        components: 4,
        matrix: false,
        quaternion: true,
    };
    match type_id {
        1 | 2 => numbers(Scalar::U8, 1),
        3 => numbers(Scalar::I32, 1),
        4 => numbers(Scalar::U32, 1),
        5 => numbers(Scalar::I64, 1),
        6 => numbers(Scalar::U64, 1),
        7 => numbers(Scalar::F16, 1),
        8 => numbers(Scalar::F32, 1),
        9 | 56 => numbers(Scalar::F64, 1),
        10 => Kind::String,
        11 => Kind::Token,
        12 => Kind::AssetPath,
        13 => matrix(4),
        14 => matrix(9),
        15 => matrix(16),
        16 => quaternion(Scalar::F64),
        17 => quaternion(Scalar::F32),
        18 => quaternion(Scalar::F16),
        19 => numbers(Scalar::F64, 2),
        20 => numbers(Scalar::F32, 2),
        21 => numbers(Scalar::F16, 2),
        22 => numbers(Scalar::I32, 2),
        23 => numbers(Scalar::F64, 3),
        24 => numbers(Scalar::F32, 3),
        25 => numbers(Scalar::F16, 3),
        26 => numbers(Scalar::I32, 3),
        27 => numbers(Scalar::F64, 4),
        28 => numbers(Scalar::F32, 4),
        29 => numbers(Scalar::F16, 4),
        30 => numbers(Scalar::I32, 4),
        34 => Kind::PathListOp,
        35 => Kind::ReferenceListOp,
        41 => Kind::TokenVector,
        42 => Kind::Specifier,
        44 => Kind::Variability,
        46 => Kind::TimeSamples,
        47 => Kind::Payload,
        48 => Kind::DoubleVector,
        50 => Kind::StringVector,
        55 => Kind::PayloadListOp,
        _ => Kind::Other,
    }
}

/// IEEE 754 half to single precision.
fn half_to_f32(bits: u16) -> f32 {
    let sign = u32::from(bits >> 15) << 31;
    let exponent = u32::from((bits >> 10) & 0x1f);
    let mantissa = u32::from(bits & 0x3ff);
    let value = match (exponent, mantissa) {
        (0, 0) => sign,
        (0, m) => {
            // Subnormal: value = m * 2^-24.
            let magnitude = m as f32 * f32::from_bits(0x3380_0000);
            return if sign != 0 { -magnitude } else { magnitude };
        }
        (0x1f, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 112) << 23) | (m << 13),
    };
    f32::from_bits(value)
}

/// One entry of the path table.
#[derive(Debug, Clone)]
struct PathEntry {
    text: String,
    parent: Option<u32>,
    /// Depth-first position in the file's path tree.
    order: usize,
}

struct CrateReader<'a> {
    file: &'a Path,
    bytes: &'a [u8],
    version: (u8, u8, u8),
    tokens: Vec<String>,
    /// Token index of each string.
    strings: Vec<u32>,
    /// `(name token, value rep)`.
    fields: Vec<(u32, u64)>,
    fieldsets: Vec<u32>,
    paths: Vec<Option<PathEntry>>,
    /// `(path, fieldset, spec type)`.
    specs: Vec<(u32, u32, u32)>,
    /// Bytes that decoding may still allocate ([`DECODE_FACTOR`]).
    decode_budget: Cell<u64>,
    /// Leave deferrable time samples' arrays undecoded ([`read_deferred`]).
    defer_samples: bool,
}

impl<'a> CrateReader<'a> {
    fn new(file: &'a Path, bytes: &'a [u8], defer_samples: bool) -> CrateReader<'a> {
        CrateReader {
            file,
            bytes,
            version: (0, 0, 0),
            tokens: Vec::new(),
            strings: Vec::new(),
            fields: Vec::new(),
            fieldsets: Vec::new(),
            paths: Vec::new(),
            specs: Vec::new(),
            decode_budget: Cell::new(
                (bytes.len() as u64)
                    .saturating_mul(DECODE_FACTOR)
                    .saturating_add(DECODE_ALLOWANCE),
            ),
            defer_samples,
        }
    }

    fn error(&self, offset: u64, message: impl Into<String>) -> ImportError {
        ImportError::malformed(self.file, Place::Offset(offset), message)
    }

    fn slice(&self, offset: u64, length: u64, what: &str) -> Result<&'a [u8]> {
        let end = offset.checked_add(length);
        match end {
            Some(end) if end <= self.bytes.len() as u64 => {
                Ok(&self.bytes[offset as usize..end as usize])
            }
            _ => Err(self.error(
                offset,
                format!(
                    "{what}: {length} bytes at offset {offset} run past the end of the file ({} bytes)",
                    self.bytes.len()
                ),
            )),
        }
    }

    /// Takes `bytes` from the decode budget before they are allocated.
    fn charge(&self, offset: u64, bytes: u64, what: &str) -> Result<()> {
        let left = self.decode_budget.get();
        if bytes > left {
            return Err(self.error(
                offset,
                format!(
                    "{what}: decoding would take more than {DECODE_FACTOR} times the file's \
                     size (counts far beyond what a file of {} bytes carries)",
                    self.bytes.len()
                ),
            ));
        }
        self.decode_budget.set(left - bytes);
        Ok(())
    }

    fn u64_at(&self, offset: u64, what: &str) -> Result<u64> {
        let bytes = self.slice(offset, 8, what)?;
        let mut raw = [0u8; 8];
        raw.copy_from_slice(bytes);
        Ok(u64::from_le_bytes(raw))
    }

    fn u32_at(&self, offset: u64, what: &str) -> Result<u32> {
        let bytes = self.slice(offset, 4, what)?;
        let mut raw = [0u8; 4];
        raw.copy_from_slice(bytes);
        Ok(u32::from_le_bytes(raw))
    }

    fn at_least(&self, version: (u8, u8, u8)) -> bool {
        self.version >= version
    }

    /// Reads the bootstrap, table of contents and structural sections.
    fn structure(&mut self) -> Result<()> {
        let boot = self.slice(0, BOOTSTRAP_SIZE, "bootstrap header")?;
        if &boot[..8] != b"PXR-USDC" {
            return Err(self.error(0, "not a crate file: no PXR-USDC magic"));
        }
        self.version = (boot[8], boot[9], boot[10]);
        let (major, minor, patch) = self.version;
        if major != 0 || minor < 4 {
            return Err(self.error(
                8,
                format!("crate version {major}.{minor}.{patch} is not supported (0.4.0 to 0.x)"),
            ));
        }
        let toc_offset = self.u64_at(16, "table of contents offset")?;
        let section_count = self.u64_at(toc_offset, "table of contents")?;
        if section_count == 0 || section_count > 64 {
            return Err(self.error(
                toc_offset,
                format!("table of contents lists {section_count} sections"),
            ));
        }
        let mut sections: BTreeMap<String, (u64, u64)> = BTreeMap::new();
        for index in 0..section_count {
            let at = toc_offset + 8 + index * 32;
            let raw = self.slice(at, 32, "table of contents entry")?;
            let name_bytes = &raw[..16];
            let name_len = name_bytes.iter().position(|&b| b == 0).unwrap_or(16);
            let name = String::from_utf8_lossy(&name_bytes[..name_len]).into_owned();
            let start = self.u64_at(at + 16, "section start")?;
            let size = self.u64_at(at + 24, "section size")?;
            self.slice(start, size, &format!("section {name}"))?;
            sections.insert(name, (start, size));
        }
        let section = |name: &str| -> Result<(u64, u64)> {
            sections
                .get(name)
                .copied()
                .ok_or_else(|| self.error(toc_offset, format!("the {name} section is missing")))
        };
        let tokens = section("TOKENS")?;
        let strings = section("STRINGS")?;
        let fields = section("FIELDS")?;
        let fieldsets = section("FIELDSETS")?;
        let paths = section("PATHS")?;
        let specs = section("SPECS")?;
        self.read_tokens(tokens)?;
        self.read_strings(strings)?;
        self.read_fields(fields)?;
        self.read_fieldsets(fieldsets)?;
        self.read_paths(paths)?;
        self.read_specs(specs)?;
        Ok(())
    }

    /// Reads `u64 size` then a TfFastCompression buffer at `offset`,
    /// decoding at most `max_output` bytes; returns the bytes and the offset
    /// after the buffer.
    fn compressed(
        &self,
        offset: u64,
        end: u64,
        max_output: u64,
        what: &str,
    ) -> Result<(Vec<u8>, u64)> {
        let size = self.u64_at(offset, what)?;
        let start = offset + 8;
        if start.checked_add(size).is_none_or(|e| e > end) {
            return Err(self.error(
                offset,
                format!("{what}: compressed size {size} overruns its section"),
            ));
        }
        let input = self.slice(start, size, what)?;
        let output = fast_decompress(input, max_output)
            .map_err(|message| self.error(start, format!("{what}: {message}")))?;
        Ok((output, start + size))
    }

    /// Reads integer-coded values (`count` of them, 4 or 8 bytes wide).
    fn compressed_ints(
        &self,
        offset: u64,
        end: u64,
        count: u64,
        wide: bool,
        what: &str,
    ) -> Result<(Vec<i64>, u64)> {
        let width: u64 = if wide { 8 } else { 4 };
        let max = count
            .checked_mul(width)
            .and_then(|n| n.checked_add(width + count.div_ceil(4)))
            .ok_or_else(|| self.error(offset, format!("{what}: count {count} is too large")))?;
        if count == 0 {
            // Writers may still store an (empty) buffer.
            let size = self.u64_at(offset, what)?;
            let next = (offset + 8)
                .checked_add(size)
                .filter(|&next| next <= end)
                .ok_or_else(|| {
                    self.error(offset, format!("{what}: size {size} overruns its section"))
                })?;
            return Ok((Vec::new(), next));
        }
        // Before anything is decoded: the compressed bytes must be able to
        // hold `count` coded integers (a common value and 2 bits each)...
        let size = (self.u64_at(offset, what)?).min(end.saturating_sub(offset + 8));
        if width + count.div_ceil(4) > size.saturating_mul(LZ4_MAX_RATIO) {
            return Err(self.error(
                offset,
                format!("{what}: {count} integers cannot be coded in {size} compressed bytes"),
            ));
        }
        // ...and the decoded integers must fit the decode budget.
        self.charge(offset, count.saturating_mul(8), what)?;
        let (buffer, next) = self.compressed(offset, end, max, what)?;
        let ints = decode_ints(&buffer, count, wide)
            .map_err(|message| self.error(offset, format!("{what}: {message}")))?;
        Ok((ints, next))
    }

    fn read_tokens(&mut self, (start, size): (u64, u64)) -> Result<()> {
        let end = start + size;
        let count = self.u64_at(start, "TOKENS count")?;
        let uncompressed = self.u64_at(start + 8, "TOKENS size")?;
        let (text, _) = self.compressed(start + 16, end, uncompressed, "TOKENS")?;
        if text.len() as u64 != uncompressed {
            return Err(self.error(
                start,
                format!(
                    "TOKENS: decompressed to {} bytes, the section says {uncompressed}",
                    text.len()
                ),
            ));
        }
        let mut tokens = Vec::new();
        if !text.is_empty() {
            if text.last() != Some(&0) {
                return Err(self.error(start, "TOKENS: last token is not NUL-terminated"));
            }
            for piece in text[..text.len() - 1].split(|&b| b == 0) {
                let token = std::str::from_utf8(piece)
                    .map_err(|_| self.error(start, "TOKENS: a token is not UTF-8"))?;
                tokens.push(token.to_string());
            }
        }
        if tokens.len() as u64 != count {
            return Err(self.error(
                start,
                format!(
                    "TOKENS: the section says {count} tokens but holds {}",
                    tokens.len()
                ),
            ));
        }
        self.tokens = tokens;
        Ok(())
    }

    fn read_strings(&mut self, (start, size): (u64, u64)) -> Result<()> {
        let count = self.u64_at(start, "STRINGS count")?;
        if count
            .checked_mul(4)
            .is_none_or(|n| n > size.saturating_sub(8))
        {
            return Err(self.error(
                start,
                format!("STRINGS: {count} strings do not fit in the section"),
            ));
        }
        let raw = self.slice(start + 8, count * 4, "STRINGS")?;
        let mut strings = Vec::with_capacity(count as usize);
        for chunk in raw.chunks_exact(4) {
            let index = u32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
            if index as usize >= self.tokens.len() {
                return Err(self.error(start, format!("STRINGS: token index {index} out of range")));
            }
            strings.push(index);
        }
        self.strings = strings;
        Ok(())
    }

    fn read_fields(&mut self, (start, size): (u64, u64)) -> Result<()> {
        let end = start + size;
        let count = self.u64_at(start, "FIELDS count")?;
        let (tokens, next) = self.compressed_ints(start + 8, end, count, false, "FIELDS names")?;
        let max = count
            .checked_mul(8)
            .ok_or_else(|| self.error(start, "FIELDS: count too large"))?;
        let (reps, _) = self.compressed(next, end, max, "FIELDS values")?;
        if reps.len() as u64 != max {
            return Err(self.error(
                next,
                format!("FIELDS values: {} bytes for {count} fields", reps.len()),
            ));
        }
        let mut fields = Vec::with_capacity(tokens.len());
        for (token, rep) in tokens.iter().zip(reps.chunks_exact(8)) {
            let token = u32::try_from(*token)
                .ok()
                .filter(|&t| (t as usize) < self.tokens.len())
                .ok_or_else(|| {
                    self.error(start, format!("FIELDS: name token {token} out of range"))
                })?;
            let mut raw = [0u8; 8];
            raw.copy_from_slice(rep);
            fields.push((token, u64::from_le_bytes(raw)));
        }
        self.fields = fields;
        Ok(())
    }

    fn read_fieldsets(&mut self, (start, size): (u64, u64)) -> Result<()> {
        let count = self.u64_at(start, "FIELDSETS count")?;
        let (values, _) =
            self.compressed_ints(start + 8, start + size, count, false, "FIELDSETS")?;
        self.fieldsets = values.into_iter().map(|v| v as u32).collect();
        Ok(())
    }

    fn read_paths(&mut self, (start, size): (u64, u64)) -> Result<()> {
        let end = start + size;
        let path_count = self.u64_at(start, "PATHS count")?;
        let count = self.u64_at(start + 8, "PATHS entries")?;
        // The path table may hold one path the tree does not: the empty
        // path (arcs that name no prim).
        if path_count > count.saturating_add(1) {
            return Err(self.error(
                start,
                format!("PATHS: {path_count} paths but {count} entries"),
            ));
        }
        let (indexes, next) =
            self.compressed_ints(start + 16, end, count, false, "PATHS indexes")?;
        let (elements, next) =
            self.compressed_ints(next, end, count, false, "PATHS element tokens")?;
        let (jumps, _) = self.compressed_ints(next, end, count, false, "PATHS jumps")?;
        let entry_size = std::mem::size_of::<Option<PathEntry>>() as u64;
        self.charge(start, path_count.saturating_mul(entry_size), "PATHS")?;
        let mut paths: Vec<Option<PathEntry>> = vec![None; path_count as usize];
        let bad = |message: String| self.error(start, format!("PATHS: {message}"));
        // (entry, parent path, its depth) still to walk; every entry is
        // visited once.
        let mut pending: Vec<(usize, Option<u32>, usize)> = if count > 0 {
            vec![(0, None, 0)]
        } else {
            Vec::new()
        };
        let mut visits = 0u64;
        let mut order = 0usize;
        while let Some((mut entry, mut parent, mut depth)) = pending.pop() {
            loop {
                let (Some(&index), Some(&element), Some(&jump)) =
                    (indexes.get(entry), elements.get(entry), jumps.get(entry))
                else {
                    return Err(bad(format!("entry {entry} is out of range")));
                };
                visits += 1;
                if visits > count {
                    return Err(bad("the path tree visits an entry twice".into()));
                }
                if depth > MAX_PATH_DEPTH {
                    return Err(bad(format!(
                        "the path tree is nested deeper than {MAX_PATH_DEPTH} at entry {entry}"
                    )));
                }
                let index = u32::try_from(index)
                    .ok()
                    .filter(|&i| (i as u64) < path_count)
                    .ok_or_else(|| bad(format!("path index {index} out of range")))?;
                let text = match parent {
                    None => "/".to_string(),
                    Some(parent_index) => {
                        let parent_text = paths
                            .get(parent_index as usize)
                            .and_then(|p| p.as_ref())
                            .map(|p| p.text.as_str())
                            .ok_or_else(|| bad("a path's parent is unknown".into()))?;
                        let token = self
                            .tokens
                            .get(element.unsigned_abs() as usize)
                            .ok_or_else(|| bad(format!("element token {element} out of range")))?;
                        if element < 0 {
                            format!("{parent_text}.{token}")
                        } else if parent_text == "/" {
                            format!("/{token}")
                        } else {
                            format!("{parent_text}/{token}")
                        }
                    }
                };
                self.charge(start, text.len() as u64, "PATHS")?;
                let slot = paths
                    .get_mut(index as usize)
                    .ok_or_else(|| bad(format!("path index {index} out of range")))?;
                *slot = Some(PathEntry {
                    text,
                    parent,
                    order,
                });
                order += 1;
                let has_child = jump > 0 || jump == -1;
                let has_sibling = jump >= 0;
                if has_child && has_sibling {
                    let sibling = entry
                        .checked_add(jump as usize)
                        .filter(|&s| (s as u64) < count)
                        .ok_or_else(|| {
                            bad(format!("jump {jump} at entry {entry} leaves the table"))
                        })?;
                    pending.push((sibling, parent, depth));
                }
                if has_child {
                    parent = Some(index);
                    depth += 1;
                    entry += 1;
                } else if has_sibling {
                    entry += 1;
                } else {
                    break;
                }
            }
        }
        self.paths = paths;
        Ok(())
    }

    fn read_specs(&mut self, (start, size): (u64, u64)) -> Result<()> {
        let end = start + size;
        let count = self.u64_at(start, "SPECS count")?;
        let (paths, next) = self.compressed_ints(start + 8, end, count, false, "SPECS paths")?;
        let (fieldsets, next) =
            self.compressed_ints(next, end, count, false, "SPECS field sets")?;
        let (types, _) = self.compressed_ints(next, end, count, false, "SPECS types")?;
        self.specs = paths
            .iter()
            .zip(&fieldsets)
            .zip(&types)
            .map(|((&p, &f), &t)| (p as u32, f as u32, t as u32))
            .collect();
        Ok(())
    }

    fn token(&self, index: u64, offset: u64) -> Result<String> {
        self.tokens
            .get(index as usize)
            .cloned()
            .ok_or_else(|| self.error(offset, format!("token index {index} out of range")))
    }

    fn string(&self, index: u64, offset: u64) -> Result<String> {
        let token = self
            .strings
            .get(index as usize)
            .ok_or_else(|| self.error(offset, format!("string index {index} out of range")))?;
        self.token(u64::from(*token), offset)
    }

    /// `u64 count` then `count` u32 indices, for token and string vectors.
    fn index_vector(&self, offset: u64, what: &str) -> Result<Vec<u64>> {
        let count = self.u64_at(offset, what)?;
        let length = count
            .checked_mul(4)
            .ok_or_else(|| self.error(offset, format!("{what}: count {count} too large")))?;
        let raw = self.slice(offset + 8, length, what)?;
        Ok(raw
            .chunks_exact(4)
            .map(|c| u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect())
    }

    fn numbers_at(&self, offset: u64, count: u64, scalar: Scalar, what: &str) -> Result<Vec<f64>> {
        let length = count
            .checked_mul(scalar.size())
            .ok_or_else(|| self.error(offset, format!("{what}: count {count} too large")))?;
        let raw = self.slice(offset, length, what)?;
        Ok(raw
            .chunks_exact(scalar.size() as usize)
            .map(|c| scalar.decode(c))
            .collect())
    }

    /// Decodes a value rep; `what` names it in errors.
    fn value(&self, rep: u64, what: &str, depth: usize) -> Result<Value> {
        let type_id = ((rep >> 48) & 0xff) as u8;
        let payload = rep & PAYLOAD_MASK;
        let array = rep & ARRAY_BIT != 0;
        let inlined = rep & INLINED_BIT != 0;
        let compressed = rep & COMPRESSED_BIT != 0;
        let text = |data: Vec<String>, array| Value::Text { array, data };
        match kind_of(type_id) {
            Kind::Numbers {
                scalar,
                components,
                matrix,
                quaternion,
            } => {
                let mut data = if array {
                    self.numeric_array(payload, scalar, components, compressed, what)?
                } else if inlined {
                    inline_numbers(payload as u32, scalar, components, matrix)
                } else {
                    self.numbers_at(payload, components as u64, scalar, what)?
                };
                if quaternion {
                    // Stored imaginary first, real last; USD text writes real first.
                    for q in data.chunks_exact_mut(4) {
                        q.rotate_right(1);
                    }
                }
                Ok(Value::Numbers {
                    components,
                    array,
                    data,
                })
            }
            Kind::Token if array => {
                let indices = self.raw_index_array(payload, what)?;
                let tokens = indices
                    .into_iter()
                    .map(|i| self.token(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(tokens, true))
            }
            Kind::String if array => {
                let indices = self.raw_index_array(payload, what)?;
                let strings = indices
                    .into_iter()
                    .map(|i| self.string(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(strings, true))
            }
            Kind::Token | Kind::AssetPath if inlined => {
                Ok(text(vec![self.token(payload, payload)?], false))
            }
            Kind::String if inlined => Ok(text(vec![self.string(payload, payload)?], false)),
            Kind::TokenVector => {
                let tokens = self
                    .index_vector(payload, what)?
                    .into_iter()
                    .map(|i| self.token(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(tokens, true))
            }
            Kind::StringVector => {
                let strings = self
                    .index_vector(payload, what)?
                    .into_iter()
                    .map(|i| self.string(i, payload))
                    .collect::<Result<Vec<_>>>()?;
                Ok(text(strings, true))
            }
            Kind::DoubleVector => {
                let count = self.u64_at(payload, what)?;
                let data = self.numbers_at(payload + 8, count, Scalar::F64, what)?;
                Ok(Value::Numbers {
                    components: 1,
                    array: true,
                    data,
                })
            }
            Kind::PathListOp => Ok(Value::Arcs(self.list_op(payload, ArcItem::Path, what)?)),
            Kind::ReferenceListOp => Ok(Value::Arcs(self.list_op(
                payload,
                ArcItem::Reference,
                what,
            )?)),
            Kind::PayloadListOp => Ok(Value::Arcs(self.list_op(
                payload,
                ArcItem::Payload,
                what,
            )?)),
            Kind::Payload => {
                let (target, _) = self.arc_item(payload, ArcItem::Payload, what)?;
                Ok(Value::Arcs(vec![target]))
            }
            Kind::Specifier => Ok(Value::Numbers {
                components: 1,
                array: false,
                data: vec![(payload & 0xffff_ffff) as f64],
            }),
            Kind::TimeSamples if depth > 0 => {
                Err(self.error(payload, format!("{what}: time samples inside time samples")))
            }
            _ => Ok(Value::Other),
        }
    }

    /// The items of a composition list op (OpenUSD's `SdfListOp` as the
    /// crate stores it: a header byte, then each list it flags as `u64
    /// count` and the items). Strongest first: prepended, explicit, added,
    /// appended; deleted and ordered items are read past, as the text
    /// reader skips `delete` and `reorder` lists.
    fn list_op(&self, offset: u64, item: ArcItem, what: &str) -> Result<Vec<ArcTarget>> {
        let header = self.slice(offset, 1, what)?[0];
        let mut at = offset + 1;
        // In the order the crate writes them.
        let mut lists: [(u8, Vec<ArcTarget>); 6] = [
            (LIST_OP_EXPLICIT, Vec::new()),
            (LIST_OP_ADDED, Vec::new()),
            (LIST_OP_PREPENDED, Vec::new()),
            (LIST_OP_APPENDED, Vec::new()),
            (LIST_OP_DELETED, Vec::new()),
            (LIST_OP_ORDERED, Vec::new()),
        ];
        for (bit, items) in &mut lists {
            if header & *bit == 0 {
                continue;
            }
            let count = self.u64_at(at, what)?;
            at += 8;
            // Every item takes at least `min_size` bytes: a count the rest
            // of the file cannot hold is refused before anything is read.
            let room = (self.bytes.len() as u64).saturating_sub(at);
            if count
                .checked_mul(item.min_size(self.version))
                .is_none_or(|n| n > room)
            {
                return Err(self.error(
                    at - 8,
                    format!("{what}: {count} list items do not fit in the file"),
                ));
            }
            for _ in 0..count {
                let (target, next) = self.arc_item(at, item, what)?;
                items.push(target);
                at = next;
            }
        }
        let [explicit, added, prepended, appended, _, _] = lists.map(|(_, items)| items);
        Ok(prepended
            .into_iter()
            .chain(explicit)
            .chain(added)
            .chain(appended)
            .collect())
    }

    /// One item of a list op at `offset`, and the offset after it.
    fn arc_item(&self, offset: u64, item: ArcItem, what: &str) -> Result<(ArcTarget, u64)> {
        let path_at = |at: u64| -> Result<Option<String>> {
            let index = self.u32_at(at, what)?;
            self.arc_path(index, at, what)
        };
        match item {
            ArcItem::Path => Ok((
                ArcTarget {
                    asset: None,
                    prim_path: path_at(offset)?,
                    offset: LayerOffset::default(),
                },
                offset + 4,
            )),
            ArcItem::Reference | ArcItem::Payload => {
                let asset = self.string(u64::from(self.u32_at(offset, what)?), offset)?;
                let prim_path = path_at(offset + 4)?;
                // The layer offset: two doubles, offset then scale.
                let mut next = offset + 8;
                let mut layer_offset = LayerOffset::default();
                if item == ArcItem::Reference || self.at_least((0, 8, 0)) {
                    let bytes = self.slice(next, 16, what)?;
                    let double = |b: &[u8]| -> f64 {
                        let mut raw = [0u8; 8];
                        raw.copy_from_slice(b);
                        f64::from_le_bytes(raw)
                    };
                    layer_offset = LayerOffset {
                        offset: double(&bytes[..8]),
                        scale: double(&bytes[8..16]),
                    };
                    if !(layer_offset.offset.is_finite() && layer_offset.scale.is_finite()) {
                        return Err(
                            self.error(next, format!("{what}: a layer offset is not finite"))
                        );
                    }
                    next += 16;
                }
                if item == ArcItem::Reference {
                    let custom_data = self.u64_at(next, what)?;
                    if custom_data != 0 {
                        return Err(self.error(
                            next,
                            format!("{what}: a reference with customData is not read"),
                        ));
                    }
                    next += 8;
                }
                let target = ArcTarget {
                    asset: (!asset.is_empty()).then_some(asset),
                    prim_path,
                    offset: layer_offset,
                };
                Ok((target, next))
            }
        }
    }

    /// The prim path an arc names by path index; `None` for the empty path
    /// (the target layer's `defaultPrim`).
    fn arc_path(&self, index: u32, at: u64, what: &str) -> Result<Option<String>> {
        // The empty path has an index but no place in the path tree.
        match self.paths.get(index as usize) {
            Some(Some(entry)) => Ok(Some(entry.text.clone())),
            Some(None) => Ok(None),
            None => Err(self.error(at, format!("{what}: path index {index} out of range"))),
        }
    }

    /// An array of u32 indices stored raw (token and string arrays).
    fn raw_index_array(&self, payload: u64, what: &str) -> Result<Vec<u64>> {
        if payload == 0 {
            return Ok(Vec::new());
        }
        let (count, data_start) = self.array_header(payload, what)?;
        let data = self.numbers_at(data_start, count, Scalar::U32, what)?;
        Ok(data.into_iter().map(|x| x as u64).collect())
    }

    /// Element count and the offset after it, for the file's version.
    fn array_header(&self, payload: u64, what: &str) -> Result<(u64, u64)> {
        let mut at = payload;
        if !self.at_least((0, 5, 0)) {
            at += 4; // rank, always 1
        }
        if self.at_least((0, 7, 0)) {
            Ok((self.u64_at(at, what)?, at + 8))
        } else {
            Ok((u64::from(self.u32_at(at, what)?), at + 4))
        }
    }

    fn numeric_array(
        &self,
        payload: u64,
        scalar: Scalar,
        components: usize,
        compressed: bool,
        what: &str,
    ) -> Result<Vec<f64>> {
        if payload == 0 {
            return Ok(Vec::new());
        }
        let (count, data_start) = self.array_header(payload, what)?;
        let integral = matches!(
            scalar,
            Scalar::I32 | Scalar::U32 | Scalar::I64 | Scalar::U64
        );
        let floating = matches!(scalar, Scalar::F16 | Scalar::F32 | Scalar::F64);
        let may_compress = components == 1
            && compressed
            && count >= MIN_COMPRESSED_ARRAY_SIZE
            && ((integral && self.at_least((0, 5, 0))) || (floating && self.at_least((0, 6, 0))));
        if !may_compress {
            let values = count
                .checked_mul(components as u64)
                .ok_or_else(|| self.error(payload, format!("{what}: count {count} too large")))?;
            return self.numbers_at(data_start, values, scalar, what);
        }
        let end = self.bytes.len() as u64;
        if integral {
            let wide = matches!(scalar, Scalar::I64 | Scalar::U64);
            let (ints, _) = self.compressed_ints(data_start, end, count, wide, what)?;
            return Ok(ints
                .into_iter()
                .map(|i| match scalar {
                    Scalar::U32 => f64::from(i as u32),
                    Scalar::U64 => i as u64 as f64,
                    _ => i as f64,
                })
                .collect());
        }
        let code = self.slice(data_start, 1, what)?[0];
        match code {
            b'i' => {
                let (ints, _) = self.compressed_ints(data_start + 1, end, count, false, what)?;
                Ok(ints.into_iter().map(|i| f64::from(i as i32)).collect())
            }
            b't' => {
                let table_size = u64::from(self.u32_at(data_start + 1, what)?);
                let table = self.numbers_at(data_start + 5, table_size, scalar, what)?;
                let after = data_start + 5 + table_size * scalar.size();
                let (indices, _) = self.compressed_ints(after, end, count, false, what)?;
                indices
                    .into_iter()
                    .map(|i| {
                        table.get(i as u32 as usize).copied().ok_or_else(|| {
                            self.error(after, format!("{what}: lookup index {i} out of range"))
                        })
                    })
                    .collect()
            }
            other => Err(self.error(
                data_start,
                format!("{what}: unknown compressed array code {other}"),
            )),
        }
    }

    /// `(time codes, value reps)` of a TimeSamples rep.
    fn time_samples(&self, rep: u64, what: &str, defer: bool) -> Result<Vec<(f64, Value)>> {
        let at = rep & PAYLOAD_MASK;
        let jump = |offset: u64| -> Result<u64> {
            let relative = self.u64_at(offset, what)? as i64;
            offset
                .checked_add_signed(relative)
                .filter(|&target| target < self.bytes.len() as u64)
                .ok_or_else(|| {
                    self.error(
                        offset,
                        format!("{what}: time samples jump {relative} leaves the file"),
                    )
                })
        };
        let times_at = jump(at)?;
        let times_rep = self.u64_at(times_at, what)?;
        let times = match self.value(times_rep, what, 1)? {
            Value::Numbers {
                components: 1,
                data,
                ..
            } => data,
            _ => {
                return Err(self.error(
                    times_at,
                    format!("{what}: time sample times are not doubles"),
                ))
            }
        };
        let values_at = jump(times_at + 8)?;
        let count = self.u64_at(values_at, what)?;
        if count != times.len() as u64 {
            return Err(self.error(
                values_at,
                format!("{what}: {count} values for {} time samples", times.len()),
            ));
        }
        let raw = self.slice(values_at + 8, count * 8, what)?;
        let mut samples = Vec::with_capacity(times.len());
        for (time, chunk) in times.into_iter().zip(raw.chunks_exact(8)) {
            let mut bytes = [0u8; 8];
            bytes.copy_from_slice(chunk);
            let rep = u64::from_le_bytes(bytes);
            let value = if defer && rep & ARRAY_BIT != 0 && rep & INLINED_BIT == 0 {
                Value::Deferred(rep)
            } else {
                self.value(rep, what, 1)?
            };
            samples.push((time, value));
        }
        Ok(samples)
    }

    /// The fields of a spec, by name.
    fn spec_fields(&self, fieldset: u32) -> Result<Fields> {
        let mut fields = Vec::new();
        let mut index = fieldset as usize;
        loop {
            let field = *self.fieldsets.get(index).ok_or_else(|| {
                self.error(0, format!("FIELDSETS: set {fieldset} runs past the table"))
            })?;
            if field == u32::MAX {
                return Ok(fields);
            }
            let (token, rep) = *self
                .fields
                .get(field as usize)
                .ok_or_else(|| self.error(0, format!("FIELDSETS: field {field} out of range")))?;
            fields.push((self.token(u64::from(token), 0)?, rep));
            index += 1;
        }
    }

    /// Sorts prim specs into the order usd-core traverses them: depth
    /// first, each prim's children in its `primChildren` order (the order
    /// they were authored in, which the path table does not keep). Prims no
    /// `primChildren` lists (inside variants) follow in path-table order.
    fn order_as_authored(
        &self,
        prim_specs: &mut [(usize, u32, Fields)],
        root_children: &Option<u64>,
    ) -> Result<()> {
        let by_text: std::collections::HashMap<&str, usize> = prim_specs
            .iter()
            .enumerate()
            .filter_map(|(i, (_, path, _))| {
                let entry = self.paths.get(*path as usize)?.as_ref()?;
                Some((entry.text.as_str(), i))
            })
            .collect();
        let children = |parent: &str, rep: Option<u64>| -> Result<Vec<String>> {
            let Some(rep) = rep else {
                return Ok(Vec::new());
            };
            let names = self.value(rep, &format!("{parent} primChildren"), 0)?;
            Ok(names
                .text()
                .map(|names| {
                    names
                        .iter()
                        .map(|name| match parent {
                            "/" => format!("/{name}"),
                            _ => format!("{parent}/{name}"),
                        })
                        .collect()
                })
                .unwrap_or_default())
        };
        let mut rank = vec![usize::MAX; prim_specs.len()];
        let mut next_rank = 0usize;
        // Depth first; each spec is ranked once, so the walk ends.
        let mut pending: Vec<String> = children("/", *root_children)?;
        pending.reverse();
        while let Some(path) = pending.pop() {
            let Some(&index) = by_text.get(path.as_str()) else {
                continue;
            };
            if rank[index] != usize::MAX {
                continue;
            }
            rank[index] = next_rank;
            next_rank += 1;
            let rep = prim_specs[index]
                .2
                .iter()
                .find(|(name, _)| name == "primChildren")
                .map(|(_, rep)| *rep);
            let mut below = children(&path, rep)?;
            below.reverse();
            pending.extend(below);
        }
        for (index, spec) in prim_specs.iter().enumerate() {
            if rank[index] == usize::MAX {
                rank[index] = next_rank + spec.0;
            }
        }
        let mut ranked: Vec<(usize, usize)> = rank.into_iter().zip(0..).collect();
        ranked.sort_unstable();
        let order: Vec<usize> = ranked.into_iter().map(|(_, i)| i).collect();
        // Apply the permutation through a copy of the keys (the fields
        // move with their spec).
        let mut taken: Vec<Option<(usize, u32, Fields)>> = prim_specs
            .iter_mut()
            .map(|spec| Some((spec.0, spec.1, std::mem::take(&mut spec.2))))
            .collect();
        for (slot, from) in prim_specs.iter_mut().zip(order) {
            if let Some(spec) = taken[from].take() {
                *slot = spec;
            }
        }
        Ok(())
    }

    fn stage(&self) -> Result<Stage> {
        let mut stage = Stage::default();
        // Prims sorted into the path tree's depth-first order.
        let mut prim_specs: Vec<(usize, u32, Fields)> = Vec::new();
        let mut attribute_specs: Vec<(u32, Fields)> = Vec::new();
        let mut root_children = None;
        for &(path, fieldset, spec_type) in &self.specs {
            let entry = self
                .paths
                .get(path as usize)
                .and_then(|p| p.as_ref())
                .ok_or_else(|| self.error(0, format!("SPECS: path index {path} has no path")))?;
            match spec_type {
                SPEC_PSEUDO_ROOT => {
                    for (name, rep) in self.spec_fields(fieldset)? {
                        if name == "primChildren" {
                            root_children = Some(rep);
                            continue;
                        }
                        let value = || self.value(rep, &name, 0);
                        let number = |v: Value| v.numbers(1).and_then(|n| n.first().copied());
                        match name.as_str() {
                            "metersPerUnit" => stage.meters_per_unit = number(value()?),
                            "timeCodesPerSecond" => stage.time_codes_per_second = number(value()?),
                            "framesPerSecond" => stage.frames_per_second = number(value()?),
                            "upAxis" => {
                                stage.up_axis = value()?.text().and_then(|t| t.first().cloned())
                            }
                            "defaultPrim" => {
                                stage.default_prim =
                                    value()?.text().and_then(|t| t.first().cloned())
                            }
                            // The crate calls the layer's doc `documentation`.
                            "documentation" => {
                                stage.doc = value()?.text().and_then(|t| t.first().cloned())
                            }
                            "subLayers" => {
                                let layers = value()?;
                                let layers = layers.text().ok_or_else(|| {
                                    self.error(0, "subLayers is not a list of asset paths")
                                })?;
                                stage.sublayers.extend(layers.iter().map(|asset| {
                                    (
                                        asset.clone(),
                                        Place::Path("/".into()),
                                        LayerOffset::default(),
                                    )
                                }));
                            }
                            _ => {}
                        }
                    }
                }
                SPEC_PRIM => prim_specs.push((entry.order, path, self.spec_fields(fieldset)?)),
                SPEC_ATTRIBUTE => attribute_specs.push((path, self.spec_fields(fieldset)?)),
                _ => {}
            }
        }
        self.order_as_authored(&mut prim_specs, &root_children)?;
        let mut prim_of_path: BTreeMap<u32, usize> = BTreeMap::new();
        for (_, path, fields) in prim_specs {
            let Some(entry) = self.paths.get(path as usize).and_then(|p| p.as_ref()) else {
                continue;
            };
            let parent = entry.parent.and_then(|p| prim_of_path.get(&p).copied());
            let mut prim = Prim {
                path: entry.text.clone(),
                parent,
                type_name: String::new(),
                specifier: Specifier::Over,
                in_variant: entry.text.contains('{'),
                attributes: Vec::new(),
                arcs: Vec::new(),
                place: Place::Path(entry.text.clone()),
            };
            for (name, rep) in fields {
                match name.as_str() {
                    "specifier" => {
                        prim.specifier = match rep & 0xffff_ffff {
                            0 => Specifier::Def,
                            1 => Specifier::Over,
                            _ => Specifier::Class,
                        }
                    }
                    "typeName" => {
                        if let Some(t) = self
                            .value(rep, "typeName", 0)?
                            .text()
                            .and_then(|t| t.first())
                        {
                            prim.type_name = t.clone();
                        }
                    }
                    key @ ("references" | "payload" | "inheritPaths" | "specializes") => {
                        // The crate names inherits by their Sdf field, `inheritPaths`.
                        let kind = match key {
                            "inheritPaths" => ArcKind::Inherit,
                            _ => match ArcKind::of_key(key) {
                                Some(kind) => kind,
                                None => continue,
                            },
                        };
                        let what = format!("{}: {key}", entry.text);
                        let Value::Arcs(targets) = self.value(rep, &what, 0)? else {
                            return Err(
                                self.error(0, format!("{what}: not a list of composition arcs"))
                            );
                        };
                        prim.arcs.push(Arc {
                            kind,
                            targets,
                            place: Place::Path(entry.text.clone()),
                        });
                    }
                    _ => {}
                }
            }
            prim.arcs.sort_by_key(|arc| arc.kind.strength());
            if prim.in_variant && stage.notes.is_empty() {
                stage.notes.push("variant sets not applied".into());
            }
            prim_of_path.insert(path, stage.prims.len());
            stage.prims.push(prim);
        }
        for (path, fields) in attribute_specs {
            let Some(entry) = self.paths.get(path as usize).and_then(|p| p.as_ref()) else {
                continue;
            };
            let Some(&prim_index) = entry.parent.and_then(|p| prim_of_path.get(&p)) else {
                continue;
            };
            let name = entry
                .text
                .rsplit_once('.')
                .map(|(_, n)| n.to_string())
                .unwrap_or_default();
            let mut attribute = UsdAttribute {
                name,
                type_name: String::new(),
                default: None,
                samples: Vec::new(),
                interpolation: None,
                element_size: None,
                place: Place::Path(entry.text.clone()),
            };
            for (field, rep) in fields {
                match field.as_str() {
                    "typeName" => {
                        if let Some(t) = self
                            .value(rep, &entry.text, 0)?
                            .text()
                            .and_then(|t| t.first())
                        {
                            attribute.type_name = t.clone();
                        }
                    }
                    "default" => attribute.default = Some(self.value(rep, &entry.text, 0)?),
                    "timeSamples" => {
                        let defer =
                            self.defer_samples && super::stream::deferrable(&attribute.name);
                        attribute.samples = self.time_samples(rep, &entry.text, defer)?
                    }
                    "elementSize" => {
                        attribute.element_size = self
                            .value(rep, &entry.text, 0)?
                            .numbers(1)
                            .and_then(|n| n.first().copied())
                    }
                    "interpolation" => {
                        attribute.interpolation = self
                            .value(rep, &entry.text, 0)?
                            .text()
                            .and_then(|t| t.first().cloned())
                    }
                    _ => {}
                }
            }
            if let Some(prim) = stage.prims.get_mut(prim_index) {
                prim.attributes.push(attribute);
            }
        }
        Ok(stage)
    }
}

/// Inlined numbers: 32-bit scalars as themselves, doubles as f32, 64-bit
/// ints as 32-bit, vectors as one i8 per component, matrices as an i8
/// diagonal.
fn inline_numbers(payload: u32, scalar: Scalar, components: usize, matrix: bool) -> Vec<f64> {
    let bytes = payload.to_le_bytes();
    if matrix {
        let n = match components {
            4 => 2,
            9 => 3,
            _ => 4,
        };
        let mut data = vec![0.0; components];
        for i in 0..n {
            data[i * n + i] = f64::from(bytes[i] as i8);
        }
        return data;
    }
    if components > 1 {
        return bytes
            .iter()
            .take(components)
            .map(|&b| f64::from(b as i8))
            .collect();
    }
    let value = match scalar {
        Scalar::U8 => f64::from(bytes[0]),
        Scalar::I32 | Scalar::I64 => f64::from(payload as i32),
        Scalar::U32 | Scalar::U64 => f64::from(payload),
        Scalar::F16 => f64::from(half_to_f32(payload as u16)),
        Scalar::F32 | Scalar::F64 => f64::from(f32::from_bits(payload)),
    };
    vec![value]
}

/// TfFastCompression: a chunk-count byte, then one LZ4 block (count 0) or
/// that many `i32 size` + block chunks.
pub(crate) fn fast_decompress(
    input: &[u8],
    max_output: u64,
) -> std::result::Result<Vec<u8>, String> {
    let (&chunks, mut rest) = input
        .split_first()
        .ok_or_else(|| "empty compressed buffer".to_string())?;
    let mut output = Vec::with_capacity((max_output as usize).min(input.len().saturating_mul(4)));
    if chunks == 0 {
        lz4_block(rest, &mut output, max_output)?;
        return Ok(output);
    }
    for chunk in 0..chunks {
        if rest.len() < 4 {
            return Err(format!("chunk {chunk} has no size"));
        }
        let size = i32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]);
        let size = usize::try_from(size).map_err(|_| format!("chunk {chunk} has negative size"))?;
        let block = rest
            .get(4..4 + size)
            .ok_or_else(|| format!("chunk {chunk} of {size} bytes overruns the buffer"))?;
        lz4_block(block, &mut output, max_output)?;
        rest = &rest[4 + size..];
    }
    Ok(output)
}

/// Decodes one LZ4 block, appending to `output` but never beyond `max_output`.
fn lz4_block(
    input: &[u8],
    output: &mut Vec<u8>,
    max_output: u64,
) -> std::result::Result<(), String> {
    let mut i = 0usize;
    let max = usize::try_from(max_output).unwrap_or(usize::MAX);
    let length = |i: &mut usize, mut value: usize| -> std::result::Result<usize, String> {
        if value == 15 {
            loop {
                let byte = *input.get(*i).ok_or("LZ4 length runs past the block")?;
                *i += 1;
                value = value
                    .checked_add(usize::from(byte))
                    .ok_or("LZ4 length overflows")?;
                if byte != 255 {
                    break;
                }
            }
        }
        Ok(value)
    };
    loop {
        let token = *input.get(i).ok_or("LZ4 block ends without a sequence")?;
        i += 1;
        let literals = length(&mut i, usize::from(token >> 4))?;
        let literal_bytes = input
            .get(i..i.saturating_add(literals))
            .ok_or("LZ4 literals run past the block")?;
        if output.len() + literals > max {
            return Err(format!(
                "LZ4 data decompresses to more than the expected {max} bytes"
            ));
        }
        output.extend_from_slice(literal_bytes);
        i += literals;
        if i == input.len() {
            return Ok(());
        }
        let offset_bytes = input
            .get(i..i + 2)
            .ok_or("LZ4 match offset runs past the block")?;
        let offset = usize::from(u16::from_le_bytes([offset_bytes[0], offset_bytes[1]]));
        i += 2;
        if offset == 0 || offset > output.len() {
            return Err(format!("LZ4 match offset {offset} points before the data"));
        }
        let match_length = length(&mut i, usize::from(token & 15))? + 4;
        if output.len() + match_length > max {
            return Err(format!(
                "LZ4 data decompresses to more than the expected {max} bytes"
            ));
        }
        let start = output.len() - offset;
        for k in 0..match_length {
            let byte = output[start + k];
            output.push(byte);
        }
    }
}

/// OpenUSD's integer coding: common value, 2-bit codes, then deltas of
/// 1/2/4 bytes (8-bit ints) or 2/4/8 bytes (64-bit ints).
pub(crate) fn decode_ints(
    buffer: &[u8],
    count: u64,
    wide: bool,
) -> std::result::Result<Vec<i64>, String> {
    let width = if wide { 8 } else { 4 };
    let code_bytes = usize::try_from(count.div_ceil(4)).map_err(|_| "too many integers")?;
    if buffer.len() < width + code_bytes {
        return Err(format!(
            "{} bytes cannot hold {count} coded integers",
            buffer.len()
        ));
    }
    let read = |bytes: &[u8]| -> i64 {
        match bytes.len() {
            1 => i64::from(bytes[0] as i8),
            2 => i64::from(i16::from_le_bytes([bytes[0], bytes[1]])),
            4 => i64::from(i32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
            _ => {
                let mut raw = [0u8; 8];
                raw.copy_from_slice(&bytes[..8]);
                i64::from_le_bytes(raw)
            }
        }
    };
    let common = read(&buffer[..width]);
    let codes = &buffer[width..width + code_bytes];
    let mut data = &buffer[width + code_bytes..];
    let mut output = Vec::with_capacity(count as usize);
    let mut previous = 0i64;
    for index in 0..count as usize {
        let code = (codes[index / 4] >> (2 * (index % 4))) & 3;
        let size = match (code, wide) {
            (0, _) => 0,
            (1, false) => 1,
            (2, false) | (1, true) => 2,
            (3, false) | (2, true) => 4,
            _ => 8,
        };
        let delta = if size == 0 {
            common
        } else {
            let bytes = data
                .get(..size)
                .ok_or("coded integers run past the buffer")?;
            data = &data[size..];
            read(bytes)
        };
        previous = if wide {
            previous.wrapping_add(delta)
        } else {
            i64::from((previous as i32).wrapping_add(delta as i32))
        };
        output.push(previous);
    }
    Ok(output)
}
