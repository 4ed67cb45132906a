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

mod compression;
mod values;

pub(crate) use compression::{decode_ints, fast_decompress};
use values::Scalar;

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
/// [`deferrable`] names are left undecoded, as
/// [`Value::Deferred`] with their value rep: a frame-at-a-time reader
/// decodes them with [`decode`] when it reaches their frame.
pub(super) fn read_deferred(path: &Path, bytes: &[u8]) -> Result<Stage> {
    let mut reader = CrateReader::new(path, bytes, true);
    reader.structure()?;
    reader.stage()
}

/// Whether [`read_deferred`] may leave the time samples of attribute `name`
/// undecoded. Not `curveVertexCounts`: whether the topology changes is
/// decided from all its samples at once.
fn deferrable(name: &str) -> bool {
    name != "curveVertexCounts"
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
                        let defer = self.defer_samples && deferrable(&attribute.name);
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
