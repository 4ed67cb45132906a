//! Alembic's layout on top of Ogawa: the archive's time samplings and
//! indexed metadata, the object tree, property headers and samples.

use super::ogawa::{is_data, Fault, Ogawa};
use std::collections::BTreeSet;

/// Deeper object or compound nesting than this is refused (real scenes
/// are a few levels deep; the limit keeps recursion bounded).
const MAX_DEPTH: usize = 256;

/// Plain old data types, numbered as in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pod {
    Bool,
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F16,
    F32,
    F64,
    String,
    WString,
}

impl Pod {
    fn from_code(code: u32) -> Option<Pod> {
        Some(match code {
            0 => Pod::Bool,
            1 => Pod::U8,
            2 => Pod::I8,
            3 => Pod::U16,
            4 => Pod::I16,
            5 => Pod::U32,
            6 => Pod::I32,
            7 => Pod::U64,
            8 => Pod::I64,
            9 => Pod::F16,
            10 => Pod::F32,
            11 => Pod::F64,
            12 => Pod::String,
            13 => Pod::WString,
            _ => return None,
        })
    }

    /// Bytes per component; strings have no fixed size.
    pub fn size(self) -> Option<usize> {
        match self {
            Pod::Bool | Pod::U8 | Pod::I8 => Some(1),
            Pod::U16 | Pod::I16 | Pod::F16 => Some(2),
            Pod::U32 | Pod::I32 | Pod::F32 => Some(4),
            Pod::U64 | Pod::I64 | Pod::F64 => Some(8),
            Pod::String | Pod::WString => None,
        }
    }

    pub fn is_integer(self) -> bool {
        !matches!(
            self,
            Pod::F16 | Pod::F32 | Pod::F64 | Pod::String | Pod::WString
        )
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Compound,
    Scalar,
    Array,
}

/// A time sampling: sample `i` is at `stored[i % n] + (i / n) * time_per_cycle`
/// (uniform and cyclic), or at `stored[i]` (acyclic).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSampling {
    pub time_per_cycle: f64,
    pub stored: Vec<f64>,
}

impl TimeSampling {
    pub fn is_acyclic(&self) -> bool {
        self.time_per_cycle == f64::MAX / 32.0
    }

    /// Time of sample `index`; `None` past the stored times of an acyclic
    /// sampling.
    pub fn time(&self, index: usize) -> Option<f64> {
        if self.is_acyclic() {
            return self.stored.get(index).copied();
        }
        let n = self.stored.len();
        let base = self.stored.get(index % n.max(1)).copied()?;
        Some(base + (index / n) as f64 * self.time_per_cycle)
    }
}

/// `k=v;k=v` metadata.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Metadata(pub String);

impl Metadata {
    pub fn get(&self, key: &str) -> Option<&str> {
        self.0.split(';').find_map(|pair| {
            let (k, v) = pair.split_once('=')?;
            (k == key).then_some(v)
        })
    }
}

/// A property header and where its samples are.
#[derive(Debug, Clone)]
pub struct Property {
    pub name: String,
    /// Path of the property in the file, for messages.
    pub path: String,
    pub kind: Kind,
    pub pod: Pod,
    pub extent: u8,
    pub sample_count: u32,
    pub first_changed: u32,
    pub last_changed: u32,
    pub time_sampling: u32,
    pub metadata: Metadata,
    /// The property's group: samples, or sub-properties of a compound.
    pub group: u64,
    /// The references of the stored samples (scalar and array properties).
    pub samples: Vec<u64>,
    /// Sub-properties of a compound.
    pub children: Vec<Property>,
}

impl Property {
    pub fn child(&self, name: &str) -> Option<&Property> {
        self.children.iter().find(|p| p.name == name)
    }

    /// The stored sample that holds sample `index`: samples before the first
    /// change and after the last are not stored again.
    pub fn stored_index(&self, index: u32) -> u32 {
        if self.first_changed == 0 && self.last_changed == 0 {
            return 0;
        }
        if index < self.first_changed {
            0
        } else if index >= self.last_changed {
            self.last_changed
                .saturating_sub(self.first_changed)
                .saturating_add(1)
        } else {
            index.saturating_sub(self.first_changed).saturating_add(1)
        }
    }
}

/// An object with its properties and children.
#[derive(Debug, Clone)]
pub struct Object {
    pub name: String,
    pub path: String,
    pub metadata: Metadata,
    /// The top compound's properties.
    pub properties: Vec<Property>,
    pub children: Vec<Object>,
    /// The 32 bytes after the child headers: properties hash, children hash.
    pub hashes: Option<[u8; 32]>,
}

impl Object {
    pub fn property(&self, name: &str) -> Option<&Property> {
        self.properties.iter().find(|p| p.name == name)
    }
}

/// An archive: its metadata, time samplings and object tree.
pub struct Archive<'a> {
    pub ogawa: Ogawa<'a>,
    pub metadata: Metadata,
    pub time_samplings: Vec<TimeSampling>,
    pub top: Object,
}

struct Reader<'r, 'a> {
    ogawa: &'r Ogawa<'a>,
    indexed_metadata: Vec<Metadata>,
    time_samplings: &'r [TimeSampling],
    visited: BTreeSet<u64>,
}

fn u32_at(bytes: &[u8], pos: usize) -> Option<u32> {
    let word: [u8; 4] = bytes.get(pos..pos.checked_add(4)?)?.try_into().ok()?;
    Some(u32::from_le_bytes(word))
}

fn f64_at(bytes: &[u8], pos: usize) -> Option<f64> {
    let word: [u8; 8] = bytes.get(pos..pos.checked_add(8)?)?.try_into().ok()?;
    Some(f64::from_le_bytes(word))
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

impl<'a> Archive<'a> {
    pub fn open(bytes: &'a [u8]) -> Result<Archive<'a>, Fault> {
        let ogawa = Ogawa::open(bytes)?;
        let root = ogawa.group(ogawa.root())?;
        let expected = [true, true, false, true, true, true];
        let shape_ok = root.len() >= 6
            && root
                .iter()
                .zip(expected)
                .all(|(&child, data)| is_data(child) == data);
        if !shape_ok {
            return Err(Fault::at(
                ogawa.root(),
                "root group is not an Alembic archive (expected data, data, group, data, data, data)",
            ));
        }
        let version = ogawa.data(root[0])?;
        match version {
            [a, b, c, d] if i32::from_le_bytes([*a, *b, *c, *d]) == 0 => {}
            _ => {
                return Err(Fault::at(
                    root[0] & !super::ogawa::DATA_BIT,
                    "unsupported Alembic Ogawa file version (expected 0)",
                ))
            }
        }
        let library = ogawa.data(root[1])?;
        let library_version = match library {
            [a, b, c, d] => i32::from_le_bytes([*a, *b, *c, *d]),
            _ => -1,
        };
        if library_version < 9999 {
            return Err(Fault::at(
                root[1] & !super::ogawa::DATA_BIT,
                format!("unsupported Alembic library version {library_version}"),
            ));
        }
        let metadata = Metadata(text(ogawa.data(root[3])?));
        let time_samplings = read_time_samplings(&ogawa, root[4])?;
        let indexed_metadata = read_indexed_metadata(&ogawa, root[5])?;
        let top = {
            let mut reader = Reader {
                ogawa: &ogawa,
                indexed_metadata,
                time_samplings: &time_samplings,
                visited: BTreeSet::new(),
            };
            reader.object(root[2], "ABC".into(), String::new(), metadata.clone(), 0)?
        };
        Ok(Archive {
            ogawa,
            metadata,
            time_samplings,
            top,
        })
    }

    /// The data of stored sample `stored` of a scalar or array property,
    /// without its 16-byte digest.
    pub fn stored_sample(&self, property: &Property, stored: u32) -> Result<&'a [u8], Fault> {
        let children = &property.samples;
        let step = if property.kind == Kind::Array { 2 } else { 1 };
        let index = stored as usize * step;
        let reference = *children.get(index).ok_or_else(|| {
            Fault::path(
                &property.path,
                format!(
                    "sample {stored} is not stored (the property has {} stored samples)",
                    children.len() / step
                ),
            )
        })?;
        if !is_data(reference) {
            return Err(Fault::path(
                &property.path,
                format!("sample {stored} is a group, expected data"),
            ));
        }
        let data = self.ogawa.data(reference)?;
        // The first 16 bytes are the sample's digest; a shorter block is an
        // empty sample.
        Ok(data.get(16..).unwrap_or(&[]))
    }

    /// The data of sample `index` (which stored sample holds it is worked out).
    pub fn sample(&self, property: &Property, index: u32) -> Result<&'a [u8], Fault> {
        self.stored_sample(property, property.stored_index(index))
    }

    /// The time of sample `index` of a property.
    pub fn sample_time(&self, property: &Property, index: u32) -> Result<f64, Fault> {
        let sampling = self
            .time_samplings
            .get(property.time_sampling as usize)
            .ok_or_else(|| {
                Fault::path(
                    &property.path,
                    format!("time sampling {} does not exist", property.time_sampling),
                )
            })?;
        sampling.time(index as usize).ok_or_else(|| {
            Fault::path(
                &property.path,
                format!("sample {index} has no time in its acyclic time sampling"),
            )
        })
    }
}

fn read_time_samplings(ogawa: &Ogawa, reference: u64) -> Result<Vec<TimeSampling>, Fault> {
    let bytes = ogawa.data(reference)?;
    let at = reference & !super::ogawa::DATA_BIT;
    let mut samplings = Vec::new();
    let mut pos = 0usize;
    while pos < bytes.len() {
        let bad = |what: &str| Fault::at(at, format!("time sampling {}: {what}", samplings.len()));
        let _max_samples = u32_at(bytes, pos).ok_or_else(|| bad("truncated"))?;
        let time_per_cycle = f64_at(bytes, pos + 4).ok_or_else(|| bad("truncated"))?;
        let count = u32_at(bytes, pos + 12).ok_or_else(|| bad("truncated"))? as usize;
        pos += 16;
        let available = (bytes.len() - pos.min(bytes.len())) / 8;
        if count == 0 {
            return Err(bad("no stored times (at least one is needed)"));
        }
        if count > available {
            return Err(bad(&format!(
                "{count} stored times, but the block has room for {available}"
            )));
        }
        let stored: Vec<f64> = (0..count)
            .map(|i| f64_at(bytes, pos + 8 * i).unwrap_or(f64::NAN))
            .collect();
        pos += 8 * count;
        if !time_per_cycle.is_finite()
            || time_per_cycle <= 0.0
            || stored.iter().any(|t| !t.is_finite())
        {
            return Err(bad(
                "time per cycle or a stored time is not a finite number",
            ));
        }
        samplings.push(TimeSampling {
            time_per_cycle,
            stored,
        });
    }
    if samplings.is_empty() {
        samplings.push(TimeSampling {
            time_per_cycle: 1.0,
            stored: vec![0.0],
        });
    }
    Ok(samplings)
}

fn read_indexed_metadata(ogawa: &Ogawa, reference: u64) -> Result<Vec<Metadata>, Fault> {
    let bytes = ogawa.data(reference)?;
    let at = reference & !super::ogawa::DATA_BIT;
    let mut entries = vec![Metadata::default()];
    let mut pos = 0usize;
    while pos < bytes.len() {
        let size = bytes[pos] as usize;
        pos += 1;
        let entry = bytes.get(pos..pos + size).ok_or_else(|| {
            Fault::at(
                at,
                format!("indexed metadata {} runs past its block", entries.len()),
            )
        })?;
        entries.push(Metadata(text(entry)));
        pos += size;
    }
    Ok(entries)
}

/// Reads an unsigned number of 1, 2 or 4 bytes.
fn read_hinted(bytes: &[u8], pos: &mut usize, hint: u32) -> Option<u32> {
    let size = match hint {
        0 => 1,
        1 => 2,
        2 => 4,
        _ => return None,
    };
    let slice = bytes.get(*pos..pos.checked_add(size)?)?;
    *pos += size;
    let mut word = [0u8; 4];
    word[..size].copy_from_slice(slice);
    Some(u32::from_le_bytes(word))
}

impl Reader<'_, '_> {
    fn enter(&mut self, group: u64, path: &str, depth: usize) -> Result<Vec<u64>, Fault> {
        if depth > MAX_DEPTH {
            return Err(Fault::path(
                path,
                format!("nested more than {MAX_DEPTH} levels deep"),
            ));
        }
        if group != 0 && !self.visited.insert(group) {
            return Err(Fault::path(
                path,
                format!("group at offset {group} is used twice (the file's tree has a cycle or shared node)"),
            ));
        }
        self.ogawa.group(group)
    }

    fn object(
        &mut self,
        group: u64,
        name: String,
        path: String,
        metadata: Metadata,
        depth: usize,
    ) -> Result<Object, Fault> {
        let shown = if path.is_empty() { "/" } else { &path };
        let children = self.enter(group, shown, depth)?;
        let mut object = Object {
            name,
            path: path.clone(),
            metadata,
            properties: Vec::new(),
            children: Vec::new(),
            hashes: None,
        };
        if children.is_empty() {
            return Ok(object);
        }
        let properties_group = children[0];
        if is_data(properties_group) {
            return Err(Fault::path(
                shown,
                "object's first child is data, expected its property group",
            ));
        }
        object.properties = self.compound(properties_group, &path, depth + 1)?;
        let last = children.len() - 1;
        if last == 0 || !is_data(children[last]) {
            return Ok(object);
        }
        let headers = self.ogawa.data(children[last])?;
        let child_groups = &children[1..last];
        let (entries, hashes) = self.object_headers(headers, shown)?;
        object.hashes = hashes;
        if entries.len() != child_groups.len() {
            return Err(Fault::path(
                shown,
                format!(
                    "{} child headers for {} child groups",
                    entries.len(),
                    child_groups.len()
                ),
            ));
        }
        for ((child_name, child_metadata), &child_group) in entries.into_iter().zip(child_groups) {
            if is_data(child_group) {
                return Err(Fault::path(
                    shown,
                    format!("child object '{child_name}' is data, expected a group"),
                ));
            }
            let child_path = format!("{path}/{child_name}");
            let child = self.object(
                child_group,
                child_name,
                child_path,
                child_metadata,
                depth + 1,
            )?;
            object.children.push(child);
        }
        Ok(object)
    }

    #[allow(clippy::type_complexity)]
    fn object_headers(
        &self,
        bytes: &[u8],
        path: &str,
    ) -> Result<(Vec<(String, Metadata)>, Option<[u8; 32]>), Fault> {
        if bytes.len() < 32 {
            return Ok((Vec::new(), None));
        }
        let (body, trailer) = bytes.split_at(bytes.len() - 32);
        let hashes: Option<[u8; 32]> = trailer.try_into().ok();
        let mut entries = Vec::new();
        let mut pos = 0usize;
        let bad = |what: String| Fault::path(path, format!("child headers: {what}"));
        while pos < body.len() {
            let size = u32_at(body, pos).ok_or_else(|| bad("truncated name size".into()))? as usize;
            pos += 4;
            if size == 0 || size > body.len() - pos {
                return Err(bad(format!("name of {size} bytes does not fit")));
            }
            let name = text(&body[pos..pos + size]);
            pos += size;
            let index = *body
                .get(pos)
                .ok_or_else(|| bad("truncated metadata index".into()))?;
            pos += 1;
            let metadata = if index == 0xff {
                let size = u32_at(body, pos).ok_or_else(|| bad("truncated metadata size".into()))?
                    as usize;
                pos += 4;
                if size > body.len() - pos {
                    return Err(bad(format!("metadata of {size} bytes does not fit")));
                }
                let metadata = Metadata(text(&body[pos..pos + size]));
                pos += size;
                metadata
            } else {
                self.indexed_metadata
                    .get(index as usize)
                    .cloned()
                    .ok_or_else(|| bad(format!("metadata index {index} does not exist")))?
            };
            if name.contains('/') {
                return Err(bad(format!("object name '{name}' contains '/'")));
            }
            entries.push((name, metadata));
        }
        Ok((entries, hashes))
    }

    /// The properties of a compound group.
    fn compound(&mut self, group: u64, path: &str, depth: usize) -> Result<Vec<Property>, Fault> {
        let shown = if path.is_empty() { "/" } else { path };
        let children = self.enter(group, shown, depth)?;
        let Some((&headers_ref, property_groups)) = children.split_last() else {
            return Ok(Vec::new());
        };
        if !is_data(headers_ref) {
            return Err(Fault::path(
                shown,
                "compound property's last child is a group, expected its headers",
            ));
        }
        let headers = self.ogawa.data(headers_ref)?;
        let mut properties = self.property_headers(headers, path)?;
        if properties.len() != property_groups.len() {
            return Err(Fault::path(
                shown,
                format!(
                    "{} property headers for {} property groups",
                    properties.len(),
                    property_groups.len()
                ),
            ));
        }
        for (property, &group) in properties.iter_mut().zip(property_groups) {
            if is_data(group) {
                return Err(Fault::path(
                    &property.path,
                    "property is data, expected a group",
                ));
            }
            property.group = group;
            if property.kind == Kind::Compound {
                let sub_path = property.path.clone();
                property.children = self.compound(group, &sub_path, depth + 1)?;
            } else {
                // Claimed like every other group, so no node can share it.
                property.samples = self.enter(group, &property.path, depth + 1)?;
            }
        }
        Ok(properties)
    }

    fn property_headers(&self, bytes: &[u8], parent: &str) -> Result<Vec<Property>, Fault> {
        let mut properties = Vec::new();
        let mut pos = 0usize;
        let shown = if parent.is_empty() { "/" } else { parent };
        while pos < bytes.len() {
            let number = properties.len();
            let bad = |what: &str| Fault::path(shown, format!("property header {number}: {what}"));
            let info = u32_at(bytes, pos).ok_or_else(|| bad("truncated"))?;
            pos += 4;
            let kind = match info & 3 {
                0 => Kind::Compound,
                1 => Kind::Scalar,
                _ => Kind::Array,
            };
            let hint = (info >> 2) & 3;
            let mut property = Property {
                name: String::new(),
                path: String::new(),
                kind,
                pod: Pod::U8,
                extent: 0,
                sample_count: 0,
                first_changed: 0,
                last_changed: 0,
                time_sampling: 0,
                metadata: Metadata::default(),
                group: 0,
                samples: Vec::new(),
                children: Vec::new(),
            };
            let read =
                |pos: &mut usize| read_hinted(bytes, pos, hint).ok_or_else(|| bad("truncated"));
            if kind != Kind::Compound {
                property.pod = Pod::from_code((info >> 4) & 0xf)
                    .ok_or_else(|| bad(&format!("unknown data type {}", (info >> 4) & 0xf)))?;
                property.extent = ((info >> 12) & 0xff) as u8;
                if property.extent == 0 {
                    return Err(bad("extent 0"));
                }
                property.sample_count = read(&mut pos)?;
                if info & 0x200 != 0 {
                    property.first_changed = read(&mut pos)?;
                    property.last_changed = read(&mut pos)?;
                } else if info & 0x800 != 0 {
                    property.first_changed = 0;
                    property.last_changed = 0;
                } else {
                    property.first_changed = 1;
                    property.last_changed = property.sample_count.saturating_sub(1);
                }
                if info & 0x100 != 0 {
                    property.time_sampling = read(&mut pos)?;
                    if property.time_sampling as usize >= self.time_samplings.len() {
                        return Err(bad(&format!(
                            "time sampling {} does not exist ({} in the file)",
                            property.time_sampling,
                            self.time_samplings.len()
                        )));
                    }
                }
            }
            let name_size = read(&mut pos)? as usize;
            if name_size == 0 || name_size > bytes.len() - pos {
                return Err(bad(&format!("name of {name_size} bytes does not fit")));
            }
            property.name = text(&bytes[pos..pos + name_size]);
            pos += name_size;
            property.path = format!("{parent}/{}", property.name);
            let metadata_index = (info >> 20) & 0xff;
            property.metadata = if metadata_index == 0xff {
                let size = read(&mut pos)? as usize;
                if size > bytes.len() - pos {
                    return Err(bad(&format!("metadata of {size} bytes does not fit")));
                }
                let metadata = Metadata(text(&bytes[pos..pos + size]));
                pos += size;
                metadata
            } else {
                self.indexed_metadata
                    .get(metadata_index as usize)
                    .cloned()
                    .ok_or_else(|| {
                        bad(&format!("metadata index {metadata_index} does not exist"))
                    })?
            };
            properties.push(property);
        }
        Ok(properties)
    }
}
