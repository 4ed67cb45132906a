//! Frame-at-a-time reading of a `.usdc` crate file ([`crate::stream`]).
//!
//! The crate reader leaves the arrays of time samples undecoded
//! ([`super::crate_reader::read_deferred`]: each is a [`Value::Deferred`]
//! holding where it is in the file), so opening costs the file's structure,
//! not its samples. Frame `k` is then the layer with every deferred
//! attribute cut down to the samples that frame needs, decoded, and read
//! by the same [`to_groom`] and frame attributes as a whole read: the
//! frames equal [`super::read`]'s (a test compares them).
//!
//! Only a single crate layer with one topology streams: a layer with
//! sublayers or composition arcs brings values from other files, and a
//! `curveVertexCounts` that changes over time splits the file into several
//! grooms; those (and `.usda` text, which is parsed whole) are read whole.

use super::frame_primvars::add_frame_attributes;
use super::{crate_reader, to_groom, Stage, UsdAttribute, Value};
use crate::{ImportError, Place};
use groom::{Frame, Groom};
use std::path::Path;

/// An open crate layer whose frames are decoded one at a time.
pub(crate) struct UsdStream {
    /// The layer as read, its deferrable samples undecoded.
    stage: Stage,
    /// The time codes of the frames, ascending.
    codes: Vec<f64>,
}

/// The groom a stream starts from: rest points, topology and attributes
/// (no frames), and the frames' times in seconds.
pub(crate) struct Opened {
    pub stream: UsdStream,
    pub groom: Groom,
    pub times: Vec<f64>,
}

impl UsdStream {
    /// Opens the crate file `bytes` (named `path` in errors); `None` when
    /// it is not one that streams (see the module doc), to be read whole.
    pub(crate) fn open(path: &Path, bytes: &[u8]) -> Result<Option<Opened>, ImportError> {
        if !bytes.starts_with(b"PXR-USDC") {
            return Ok(None);
        }
        let stage = crate_reader::read_deferred(path, bytes)?;
        let simple = stage.sublayers.is_empty() && stage.prims.iter().all(|p| p.arcs.is_empty());
        if !simple || super::topology_is_sampled(&stage) {
            return Ok(None);
        }
        let Some(codes) = frame_codes(&stage) else {
            // Curves sampled at different codes: the whole read says where.
            return Ok(None);
        };
        let rest_stage = decoded(path, bytes, &stage, |attribute| {
            if attribute.name == "points" {
                // The rest is the default, else the earliest sample.
                earliest_sample(attribute).into_iter().collect()
            } else {
                // Every other attribute reads as its default, else its
                // first sample in file order.
                (!attribute.samples.is_empty())
                    .then_some(0)
                    .into_iter()
                    .collect()
            }
        })?;
        let mut groom = to_groom(path, &rest_stage)?;
        if groom.strand_count() == 0 {
            return Ok(None);
        }
        groom.frames.clear();
        groom.provenance.format = "usd".into();
        let per_second = codes_per_second(&stage);
        let times = codes.iter().map(|code| code / per_second).collect();
        Ok(Some(Opened {
            stream: UsdStream { stage, codes },
            groom,
            times,
        }))
    }

    /// Frame `index` of the crate file `bytes` this stream was opened on.
    pub(crate) fn frame(
        &self,
        path: &Path,
        bytes: &[u8],
        index: usize,
    ) -> Result<Frame, ImportError> {
        let code = *self.codes.get(index).ok_or_else(|| {
            ImportError::malformed(
                path,
                Place::File,
                format!("no frame {index}: the file has {}", self.codes.len()),
            )
        })?;
        let stage = decoded(path, bytes, &self.stage, |attribute| {
            if attribute.name == "points" {
                // The first sample at the frame's code, as the whole read
                // keeps the first of equal codes.
                sorted_samples(attribute)
                    .into_iter()
                    .find(|&i| attribute.samples[i].0 == code)
                    .into_iter()
                    .collect()
            } else {
                // The first sample (what the attribute reads as in the
                // groom) and the one held at the code (the frame's value).
                let mut keep: Vec<usize> = (!attribute.samples.is_empty())
                    .then_some(0)
                    .into_iter()
                    .collect();
                if let Some(held) = held_sample(attribute, code) {
                    if held != 0 {
                        keep.push(held);
                    }
                }
                keep
            }
        })?;
        let mut groom = to_groom(path, &stage)?;
        add_frame_attributes(path, &stage, &mut groom)?;
        let mut frame = groom.frames.pop().ok_or_else(|| {
            ImportError::malformed(path, Place::File, format!("frame {index} has no points"))
        })?;
        frame.time = code / codes_per_second(&self.stage);
        Ok(frame)
    }
}

fn codes_per_second(stage: &Stage) -> f64 {
    stage
        .time_codes_per_second
        .or(stage.frames_per_second)
        .unwrap_or(24.0)
}

/// The indices of the attribute's unblocked samples, sorted by code (stable:
/// equal codes keep file order).
fn sorted_samples(attribute: &UsdAttribute) -> Vec<usize> {
    let mut order: Vec<usize> = (0..attribute.samples.len())
        .filter(|&i| !matches!(attribute.samples[i].1, Value::Blocked))
        .collect();
    order.sort_by(|&a, &b| attribute.samples[a].0.total_cmp(&attribute.samples[b].0));
    order
}

fn earliest_sample(attribute: &UsdAttribute) -> Option<usize> {
    sorted_samples(attribute).first().copied()
}

/// The sample a whole read holds at `code` ([`super::value_at`] without
/// the interpolation of points): the unblocked sample before the first one
/// past `code`, in file order; the first when the first is past it, the
/// last when none is.
fn held_sample(attribute: &UsdAttribute, code: f64) -> Option<usize> {
    let unblocked: Vec<usize> = (0..attribute.samples.len())
        .filter(|&i| !matches!(attribute.samples[i].1, Value::Blocked))
        .collect();
    match unblocked
        .iter()
        .position(|&i| attribute.samples[i].0 > code)
    {
        Some(0) => unblocked.first().copied(),
        Some(after) => Some(unblocked[after - 1]),
        None => unblocked.last().copied(),
    }
}

/// The frame codes of a deferred stage: the unblocked, finite codes of
/// every sampled `points`, which must be the same for every curves prim;
/// `None` when they differ or one is not finite (the whole read refuses
/// such a file with its message).
fn frame_codes(stage: &Stage) -> Option<Vec<f64>> {
    let mut codes: Option<Vec<f64>> = None;
    for prim in stage.prims.iter().filter(|p| p.type_name == "BasisCurves") {
        let Some(points) = prim.attribute("points") else {
            continue;
        };
        let mut these: Vec<f64> = sorted_samples(points)
            .into_iter()
            .map(|i| points.samples[i].0)
            .collect();
        these.dedup();
        if these.is_empty() {
            continue;
        }
        if these.iter().any(|code| !code.is_finite()) {
            return None;
        }
        match &codes {
            Some(first) if *first != these => return None,
            Some(_) => {}
            None => codes = Some(these),
        }
    }
    Some(codes.unwrap_or_default())
}

/// `stage` with each attribute that has deferred samples cut down to the
/// samples `keep` picks (indices, in the order to keep), decoded from
/// `bytes` in one pass; attributes without deferred samples stay whole.
fn decoded(
    path: &Path,
    bytes: &[u8],
    stage: &Stage,
    keep: impl Fn(&UsdAttribute) -> Vec<usize>,
) -> Result<Stage, ImportError> {
    // Cheap: a deferred sample is its code and a file offset.
    let mut out = stage.clone();
    let mut wanted: Vec<(usize, usize, usize, u64)> = Vec::new();
    for (p, prim) in stage.prims.iter().enumerate() {
        for (a, attribute) in prim.attributes.iter().enumerate() {
            let deferred = attribute
                .samples
                .iter()
                .any(|(_, value)| matches!(value, Value::Deferred(_)));
            if !deferred {
                continue;
            }
            let samples = &mut out.prims[p].attributes[a].samples;
            samples.clear();
            for index in keep(attribute) {
                let (code, value) = &attribute.samples[index];
                if let Value::Deferred(rep) = value {
                    wanted.push((p, a, samples.len(), *rep));
                }
                samples.push((*code, value.clone()));
            }
        }
    }
    let reps: Vec<(u64, String)> = wanted
        .iter()
        .map(|&(p, a, _, rep)| {
            let prim = &stage.prims[p];
            (rep, format!("{}.{}", prim.path, prim.attributes[a].name))
        })
        .collect();
    let values = crate_reader::decode(path, bytes, &reps)?;
    for ((p, a, s, _), value) in wanted.into_iter().zip(values) {
        out.prims[p].attributes[a].samples[s].1 = value;
    }
    Ok(out)
}
