//! Alembic's layout on top of Ogawa (what the reference calls AbcCoreOgawa):
//! properties with their samples, compounds, objects with their headers and
//! hashes, the archive's time samplings and indexed metadata.
//!
//! Everything is built bottom-up: a property is closed into its group, a
//! header and a hash; compounds and objects are closed from closed children.

use super::hashes::{digest_bytes, murmur3_x64_128, spooky_short_end, SpookyHash};
use super::ogawa::{OgawaWriter, EMPTY_DATA};
use std::collections::BTreeMap;
use std::io::{self, Seek, Write};

/// Plain old data types, numbered as in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pod {
    Bool = 0,
    U8 = 1,
    I16 = 4,
    I32 = 6,
    F32 = 10,
    F64 = 11,
}

impl Pod {
    pub fn size(self) -> usize {
        match self {
            Pod::Bool | Pod::U8 => 1,
            Pod::I16 => 2,
            Pod::I32 | Pod::F32 => 4,
            Pod::F64 => 8,
        }
    }

    /// The name geometry parameters give in their `podName` metadata.
    pub fn name(self) -> &'static str {
        match self {
            Pod::Bool => "bool_t",
            Pod::U8 => "uint8_t",
            Pod::I16 => "int16_t",
            Pod::I32 => "int32_t",
            Pod::F32 => "float32_t",
            Pod::F64 => "float64_t",
        }
    }
}

/// A time sampling: uniform (`time_per_cycle` = 1/fps, one stored time) or
/// acyclic (every time stored).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSampling {
    pub time_per_cycle: f64,
    pub stored_times: Vec<f64>,
}

impl TimeSampling {
    /// Index 0 of every archive: one sample at time 0.
    pub fn identity() -> TimeSampling {
        TimeSampling {
            time_per_cycle: 1.0,
            stored_times: vec![0.0],
        }
    }

    pub fn uniform(fps: f64, start: f64) -> TimeSampling {
        TimeSampling {
            time_per_cycle: 1.0 / fps,
            stored_times: vec![start],
        }
    }

    pub fn acyclic(times: Vec<f64>) -> TimeSampling {
        TimeSampling {
            time_per_cycle: f64::MAX / 32.0,
            stored_times: times,
        }
    }
}

/// `k=v;k=v` with keys in byte order and empty values left out.
pub fn metadata(pairs: &[(&str, &str)]) -> String {
    let sorted: BTreeMap<&str, &str> = pairs
        .iter()
        .copied()
        .filter(|(_, v)| !v.is_empty())
        .collect();
    sorted
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(";")
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropertyKind {
    Scalar,
    Array,
}

/// A property being written, sample by sample. Mirrors the reference writer:
/// a sample equal to the previous one is not stored again, repeats before a
/// change are stored as references to the earlier block, and the running
/// hash folds in each sample's digest.
pub struct PropertyWriter {
    name: String,
    metadata: String,
    kind: PropertyKind,
    pod: Pod,
    extent: u8,
    time_sampling: u32,
    children: Vec<u64>,
    next_sample: u32,
    first_changed: u32,
    last_changed: u32,
    previous: Option<WrittenSample>,
    hash: [u64; 2],
    scalar_like: bool,
    homogeneous: bool,
}

#[derive(Clone, Copy)]
struct WrittenSample {
    digest: [u64; 2],
    byte_count: u64,
    reference: u64,
    points: u64,
}

/// A closed property or compound: its group, its header bytes, its hash.
pub struct ClosedProperty {
    group: u64,
    header: Vec<u8>,
    hash: (u64, u64),
}

/// A closed object: its group, header fields and hash.
pub struct ClosedObject {
    group: u64,
    name: String,
    metadata: String,
    hash: (u64, u64),
}

impl PropertyWriter {
    pub fn new(
        name: &str,
        metadata: String,
        kind: PropertyKind,
        pod: Pod,
        extent: u8,
        time_sampling: u32,
    ) -> PropertyWriter {
        PropertyWriter {
            name: name.to_string(),
            metadata,
            kind,
            pod,
            extent,
            time_sampling,
            children: Vec::new(),
            next_sample: 0,
            first_changed: 0,
            last_changed: 0,
            previous: None,
            hash: [0, 0],
            scalar_like: true,
            homogeneous: true,
        }
    }

    /// Adds the next sample: the values as little-endian bytes.
    pub fn set_sample<W: Write + Seek>(
        &mut self,
        archive: &mut ArchiveWriter<W>,
        bytes: &[u8],
    ) -> io::Result<()> {
        let digest = murmur3_x64_128(bytes, 0);
        let byte_count = bytes.len() as u64;
        let element = (self.pod.size() * usize::from(self.extent)).max(1) as u64;
        let points = byte_count / element;
        let changed = match self.previous {
            Some(previous) => previous.digest != digest || previous.byte_count != byte_count,
            None => true,
        };
        if self.next_sample == 0 || changed {
            if self.first_changed != 0 {
                if let Some(previous) = self.previous {
                    for _ in self.last_changed + 1..self.next_sample {
                        self.push_stored(previous.reference);
                    }
                }
            }
            let reference = archive.sample_data(digest, bytes)?;
            let points_in_id = u64::from(self.extent) * points;
            if self.kind == PropertyKind::Array && points != 1 {
                self.scalar_like = false;
            }
            // The reference compares the new sample's point count with the
            // extent times the point count it recorded for the sample.
            if self.kind == PropertyKind::Array && self.homogeneous && points != points_in_id {
                self.homogeneous = false;
            }
            self.previous = Some(WrittenSample {
                digest,
                byte_count,
                reference,
                points,
            });
            self.push_stored(reference);
            if self.first_changed == 0 {
                self.first_changed = self.next_sample;
            }
            self.last_changed = self.next_sample;
        }
        self.fold_previous();
        Ok(())
    }

    /// Adds the next sample as a repeat of the previous one (the reference's
    /// `setFromPreviousSample`): nothing is stored, the hash goes on.
    pub fn repeat_previous(&mut self) {
        if self.previous.is_some() {
            self.fold_previous();
        }
    }

    fn fold_previous(&mut self) {
        let Some(previous) = self.previous else {
            return;
        };
        let sample_digest = match self.kind {
            PropertyKind::Array => dimensions_digest(previous.points, previous.digest),
            PropertyKind::Scalar => previous.digest,
        };
        if self.next_sample == 0 {
            self.hash = sample_digest;
        } else {
            let mut h = [
                self.hash[0],
                self.hash[1],
                sample_digest[0],
                sample_digest[1],
            ];
            spooky_short_end(&mut h);
            self.hash = [h[0], h[1]];
        }
        self.next_sample += 1;
    }

    fn push_stored(&mut self, reference: u64) {
        self.children.push(reference);
        if self.kind == PropertyKind::Array {
            // Rank-1 numeric arrays store no dimensions: readers derive them
            // from the data size.
            self.children.push(EMPTY_DATA);
        }
    }

    /// The property's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of samples set so far.
    pub fn sample_count(&self) -> u32 {
        self.next_sample
    }

    /// Writes the property's group and returns it with its header and hash.
    pub fn close<W: Write + Seek>(
        self,
        archive: &mut ArchiveWriter<W>,
    ) -> io::Result<ClosedProperty> {
        let stored_samples = if self.last_changed == 0 && self.next_sample > 0 {
            1
        } else {
            self.next_sample
        };
        archive.note_samples(self.time_sampling, stored_samples);
        let sampling = archive.time_sampling(self.time_sampling);
        let mut hash = SpookyHash::new(0, 0);
        hash.update(&self.property_hash_bytes(&sampling));
        if stored_samples != 0 {
            let mut digest = [0u8; 16];
            digest[..8].copy_from_slice(&self.hash[0].to_le_bytes());
            digest[8..].copy_from_slice(&self.hash[1].to_le_bytes());
            hash.update(&digest);
        }
        let group = archive.ogawa.group(&self.children)?;
        let header = self.header_bytes(archive);
        Ok(ClosedProperty {
            group,
            header,
            hash: hash.finish(),
        })
    }

    /// What the reference hashes of a property header.
    fn property_hash_bytes(&self, sampling: &TimeSampling) -> Vec<u8> {
        let mut data = Vec::new();
        data.extend_from_slice(self.name.as_bytes());
        data.extend_from_slice(self.metadata.as_bytes());
        data.push(self.pod as u8);
        data.push(self.extent);
        if self.kind == PropertyKind::Scalar {
            data.push(0);
        }
        data.extend_from_slice(&sampling.time_per_cycle.to_le_bytes());
        data.extend_from_slice(&(sampling.stored_times.len() as u32).to_le_bytes());
        for time in &sampling.stored_times {
            data.extend_from_slice(&time.to_le_bytes());
        }
        data
    }

    fn header_bytes<W: Write + Seek>(&self, archive: &mut ArchiveWriter<W>) -> Vec<u8> {
        let metadata_index = archive.metadata_index(&self.metadata);
        let max_size = (self.metadata.len() as u64)
            .max(self.name.len() as u64)
            .max(u64::from(self.next_sample))
            .max(u64::from(self.time_sampling));
        let size_hint = size_hint(max_size);
        let mut info: u32 = (size_hint << 2) & 0x0c;
        info |= (metadata_index << 20) & 0x0ff0_0000;
        info |= match self.kind {
            PropertyKind::Scalar => 1,
            PropertyKind::Array => 2,
        };
        if self.kind == PropertyKind::Array && self.scalar_like {
            info |= 1;
        }
        info |= ((self.pod as u32) << 4) & 0xf0;
        if self.time_sampling != 0 {
            info |= 0x100;
        }
        let mut needs_first_last = false;
        if self.first_changed == 0 && self.last_changed == 0 {
            info |= 0x800;
        } else if self.first_changed != 1 || self.last_changed != self.next_sample.saturating_sub(1)
        {
            info |= 0x200;
            needs_first_last = true;
        }
        info |= (u32::from(self.extent) << 12) & 0xff000;
        if self.homogeneous {
            info |= 0x400;
        }
        let mut out = Vec::new();
        out.extend_from_slice(&info.to_le_bytes());
        push_with_hint(&mut out, self.next_sample, size_hint);
        if needs_first_last {
            push_with_hint(&mut out, self.first_changed, size_hint);
            push_with_hint(&mut out, self.last_changed, size_hint);
        }
        if self.time_sampling != 0 {
            push_with_hint(&mut out, self.time_sampling, size_hint);
        }
        push_name_and_metadata(
            &mut out,
            &self.name,
            &self.metadata,
            metadata_index,
            size_hint,
        );
        out
    }
}

/// The sample digest mixed with the array's dimensions, as the reference
/// hashes array samples.
fn dimensions_digest(points: u64, digest: [u64; 2]) -> [u64; 2] {
    let mut hash = SpookyHash::new(0, 0);
    hash.update(&points.to_le_bytes());
    hash.update(&digest_bytes(digest));
    let (a, b) = hash.finish();
    [a, b]
}

fn size_hint(max_size: u64) -> u32 {
    if max_size < 256 {
        0
    } else if max_size < 65536 {
        1
    } else {
        2
    }
}

fn push_with_hint(out: &mut Vec<u8>, value: u32, hint: u32) {
    let bytes = value.to_le_bytes();
    match hint {
        0 => out.push(bytes[0]),
        1 => out.extend_from_slice(&bytes[..2]),
        _ => out.extend_from_slice(&bytes),
    }
}

fn push_name_and_metadata(out: &mut Vec<u8>, name: &str, metadata: &str, index: u32, hint: u32) {
    push_with_hint(out, name.len() as u32, hint);
    out.extend_from_slice(name.as_bytes());
    if index == 0xff {
        push_with_hint(out, metadata.len() as u32, hint);
        out.extend_from_slice(metadata.as_bytes());
    }
}

/// An archive being written.
pub struct ArchiveWriter<W: Write + Seek> {
    ogawa: OgawaWriter<W>,
    /// Stored samples by (digest, byte count): equal samples share a block.
    written: BTreeMap<([u64; 2], u64), u64>,
    indexed_metadata: Vec<String>,
    time_samplings: Vec<TimeSampling>,
    max_samples: Vec<u32>,
}

impl<W: Write + Seek> ArchiveWriter<W> {
    pub fn new(out: W) -> io::Result<ArchiveWriter<W>> {
        Ok(ArchiveWriter {
            ogawa: OgawaWriter::new(out)?,
            written: BTreeMap::new(),
            indexed_metadata: Vec::new(),
            time_samplings: vec![TimeSampling::identity()],
            max_samples: vec![0],
        })
    }

    /// Adds a time sampling (or finds an equal one); returns its index.
    pub fn add_time_sampling(&mut self, sampling: TimeSampling) -> u32 {
        if let Some(index) = self.time_samplings.iter().position(|t| *t == sampling) {
            return index as u32;
        }
        self.time_samplings.push(sampling);
        self.max_samples.push(0);
        (self.time_samplings.len() - 1) as u32
    }

    /// Replaces a time sampling added earlier (an animation's sampling is
    /// only known once every frame is in).
    pub fn set_time_sampling(&mut self, index: u32, sampling: TimeSampling) {
        if let Some(slot) = self.time_samplings.get_mut(index as usize) {
            *slot = sampling;
        }
    }

    fn time_sampling(&self, index: u32) -> TimeSampling {
        self.time_samplings
            .get(index as usize)
            .cloned()
            .unwrap_or_else(TimeSampling::identity)
    }

    fn note_samples(&mut self, index: u32, samples: u32) {
        if let Some(max) = self.max_samples.get_mut(index as usize) {
            *max = (*max).max(samples);
        }
    }

    /// The reference of a sample's block, writing it (digest then bytes)
    /// unless an equal one was written before.
    fn sample_data(&mut self, digest: [u64; 2], bytes: &[u8]) -> io::Result<u64> {
        if bytes.is_empty() {
            return Ok(EMPTY_DATA);
        }
        let key = (digest, bytes.len() as u64);
        if let Some(&reference) = self.written.get(&key) {
            return Ok(reference);
        }
        let reference = self.ogawa.data(&[&digest_bytes(digest), bytes])?;
        self.written.insert(key, reference);
        Ok(reference)
    }

    /// 0 for empty metadata, 1.. for the indexed strings, 0xff for inline.
    fn metadata_index(&mut self, metadata: &str) -> u32 {
        if metadata.is_empty() {
            return 0;
        }
        if metadata.len() < 256 {
            if let Some(i) = self.indexed_metadata.iter().position(|m| m == metadata) {
                return i as u32 + 1;
            }
            if self.indexed_metadata.len() < 254 {
                self.indexed_metadata.push(metadata.to_string());
                return self.indexed_metadata.len() as u32;
            }
        }
        0xff
    }

    /// Writes a compound property from its closed children.
    pub fn close_compound(
        &mut self,
        name: &str,
        metadata: &str,
        children: Vec<ClosedProperty>,
    ) -> io::Result<ClosedProperty> {
        let mut hash = SpookyHash::new(0, 0);
        for child in &children {
            hash.update(&child.hash.0.to_le_bytes());
            hash.update(&child.hash.1.to_le_bytes());
        }
        hash.update(name.as_bytes());
        hash.update(metadata.as_bytes());
        let group = self.properties_group(&children)?;
        let metadata_index = self.metadata_index(metadata);
        let hint = size_hint((metadata.len() as u64).max(name.len() as u64));
        let info: u32 = ((hint << 2) & 0x0c) | ((metadata_index << 20) & 0x0ff0_0000);
        let mut header = info.to_le_bytes().to_vec();
        push_name_and_metadata(&mut header, name, metadata, metadata_index, hint);
        Ok(ClosedProperty {
            group,
            header,
            hash: hash.finish(),
        })
    }

    /// The group of a compound: one child group per property, then the
    /// headers of all of them.
    fn properties_group(&mut self, children: &[ClosedProperty]) -> io::Result<u64> {
        let mut refs: Vec<u64> = children.iter().map(|c| c.group).collect();
        let headers: Vec<u8> = children
            .iter()
            .flat_map(|c| c.header.iter().copied())
            .collect();
        if !headers.is_empty() {
            refs.push(self.ogawa.data(&[&headers])?);
        }
        self.ogawa.group(&refs)
    }

    /// Writes an object from its properties and closed child objects.
    pub fn close_object(
        &mut self,
        name: &str,
        metadata: &str,
        properties: Vec<ClosedProperty>,
        children: Vec<ClosedObject>,
    ) -> io::Result<ClosedObject> {
        let (group, data_hash) = self.object_group(properties, &children)?;
        let mut hash = SpookyHash::new(0, 0);
        for child in &children {
            hash.update(&child.hash.0.to_le_bytes());
            hash.update(&child.hash.1.to_le_bytes());
        }
        hash.update(&data_hash.0.to_le_bytes());
        hash.update(&data_hash.1.to_le_bytes());
        hash.update(metadata.as_bytes());
        hash.update(name.as_bytes());
        Ok(ClosedObject {
            group,
            name: name.to_string(),
            metadata: metadata.to_string(),
            hash: hash.finish(),
        })
    }

    /// An object's group: its properties, its children, then the child
    /// headers followed by the properties hash and the children hash.
    fn object_group(
        &mut self,
        properties: Vec<ClosedProperty>,
        children: &[ClosedObject],
    ) -> io::Result<(u64, (u64, u64))> {
        let mut properties_hash = SpookyHash::new(0, 0);
        for property in &properties {
            properties_hash.update(&property.hash.0.to_le_bytes());
            properties_hash.update(&property.hash.1.to_le_bytes());
        }
        let data_hash = properties_hash.finish();
        let children_hash = if children.is_empty() {
            (0, 0)
        } else {
            let mut hash = SpookyHash::new(0, 0);
            for child in children {
                hash.update(&child.hash.0.to_le_bytes());
                hash.update(&child.hash.1.to_le_bytes());
            }
            hash.finish()
        };
        let mut headers = Vec::new();
        for child in children {
            headers.extend_from_slice(&(child.name.len() as u32).to_le_bytes());
            headers.extend_from_slice(child.name.as_bytes());
            let index = self.metadata_index(&child.metadata);
            headers.push(index as u8);
            if index == 0xff {
                headers.extend_from_slice(&(child.metadata.len() as u32).to_le_bytes());
                headers.extend_from_slice(child.metadata.as_bytes());
            }
        }
        for word in [data_hash.0, data_hash.1, children_hash.0, children_hash.1] {
            headers.extend_from_slice(&word.to_le_bytes());
        }
        let properties_group = self.properties_group(&properties)?;
        let headers_ref = self.ogawa.data(&[&headers])?;
        let mut refs = vec![properties_group];
        refs.extend(children.iter().map(|c| c.group));
        refs.push(headers_ref);
        Ok((self.ogawa.group(&refs)?, data_hash))
    }

    /// Writes the top object, the archive metadata, the time samplings and
    /// the indexed metadata, then freezes the file.
    pub fn finish(mut self, archive_metadata: &str, children: Vec<ClosedObject>) -> io::Result<W> {
        let (top, _) = self.object_group(Vec::new(), &children)?;
        let version = self.ogawa.data(&[&0i32.to_le_bytes()])?;
        let library_version = self.ogawa.data(&[&LIBRARY_VERSION.to_le_bytes()])?;
        let metadata = self.ogawa.data(&[archive_metadata.as_bytes()])?;
        let mut samplings = Vec::new();
        for (sampling, max) in self.time_samplings.iter().zip(&self.max_samples) {
            samplings.extend_from_slice(&max.to_le_bytes());
            samplings.extend_from_slice(&sampling.time_per_cycle.to_le_bytes());
            samplings.extend_from_slice(&(sampling.stored_times.len() as u32).to_le_bytes());
            for time in &sampling.stored_times {
                samplings.extend_from_slice(&time.to_le_bytes());
            }
        }
        let samplings = self.ogawa.data(&[&samplings])?;
        let mut indexed = Vec::new();
        for entry in &self.indexed_metadata {
            indexed.push(entry.len() as u8);
            indexed.extend_from_slice(entry.as_bytes());
        }
        let indexed = self.ogawa.data(&[&indexed])?;
        let root =
            self.ogawa
                .group(&[version, library_version, top, metadata, samplings, indexed])?;
        self.ogawa.finish(root)
    }
}

/// The Alembic library version whose layout this writer follows (1.8.12).
pub const LIBRARY_VERSION: i32 = 10812;
