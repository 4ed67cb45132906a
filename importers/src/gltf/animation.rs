//! Morph-target animation into frames: frame k is the base pose plus the
//! targets weighted by the k-th keyframe of the `weights` sampler.

use super::document::Document;
use super::lines::{Lines, Target};
use super::scene::{transform, Matrix};
use crate::ImportError;
use gltf::json;
use groom::Frame;
use json::animation::{Interpolation, Property};
use json::validation::Checked;
use std::collections::BTreeMap;

/// The most points all frames together may have (3 GiB of coordinates).
const MAX_FRAME_POINTS: u64 = 1 << 28;

/// One instance of a line primitive in the scene.
pub(super) struct Piece {
    /// Index into the decoded primitives.
    pub lines: usize,
    pub world: Matrix,
    pub node: usize,
}

/// Whether a channel animates morph-target weights. Paths other than the
/// four glTF defines are allowed by its schema (extensions such as
/// KHR_animation_pointer use them): such channels animate nothing here.
pub(super) fn drives_weights(channel: &json::animation::Channel) -> bool {
    matches!(
        channel.target.path,
        Checked::Valid(Property::MorphTargetWeights)
    )
}

/// The keyframes of the first animation that drives morph-target weights.
pub(super) struct Keyframes {
    pub animation: usize,
    /// Seconds.
    pub times: Vec<f32>,
    /// Per node: the weights of each keyframe.
    pub weights_of_node: BTreeMap<usize, Vec<Vec<f32>>>,
}

impl Keyframes {
    /// The weights of `piece`'s targets at keyframe `k`: its node's, else
    /// its mesh's defaults.
    pub fn weights<'w>(&'w self, k: usize, piece: &Piece, lines: &'w Lines) -> &'w [f32] {
        self.weights_of_node
            .get(&piece.node)
            .and_then(|keys| keys.get(k))
            .map(Vec::as_slice)
            .unwrap_or(&lines.default_weights)
    }
}

impl Document<'_> {
    /// Frames from the first animation that drives morph-target weights.
    pub fn frames(&self, decoded: &[Lines], pieces: &[Piece]) -> Result<Vec<Frame>, ImportError> {
        let Some(keyframes) = self.keyframes()? else {
            return Ok(Vec::new());
        };
        self.check_frames(&keyframes, decoded, pieces)?;
        (0..keyframes.times.len())
            .map(|k| self.frame(&keyframes, k, decoded, pieces))
            .collect()
    }

    /// The times and weights of the first animation that drives
    /// morph-target weights (read from the JSON and the sampler
    /// accessors, not the targets); `None` when none does.
    pub fn keyframes(&self) -> Result<Option<Keyframes>, ImportError> {
        let Some((animation_index, animation)) = self
            .root
            .animations
            .iter()
            .enumerate()
            .find(|(_, a)| a.channels.iter().any(drives_weights))
        else {
            return Ok(None);
        };
        let mut times: Option<Vec<f32>> = None;
        // Per node: the weights of each keyframe.
        let mut weights_of_node: BTreeMap<usize, Vec<Vec<f32>>> = BTreeMap::new();
        for (channel_index, channel) in animation.channels.iter().enumerate() {
            if !drives_weights(channel) {
                continue;
            }
            let place = format!("/animations/{animation_index}/channels/{channel_index}");
            let sampler_index = channel.sampler.value();
            let sampler = self.get(&animation.samplers, sampler_index, "sampler", || {
                format!("{place}/sampler")
            })?;
            let sampler_place = format!("/animations/{animation_index}/samplers/{sampler_index}");
            let interpolation = self.valid(&sampler.interpolation, "interpolation", || {
                format!("{sampler_place}/interpolation")
            })?;
            let input = self.accessor(sampler.input, || format!("{sampler_place}/input"))?;
            let input = self.floats(&input, json::accessor::Type::Scalar)?;
            let output = self.accessor(sampler.output, || format!("{sampler_place}/output"))?;
            let output = self.floats(&output, json::accessor::Type::Scalar)?;
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
            let node_index = channel.target.node.value();
            let node = self.get(&self.root.nodes, node_index, "node", || {
                format!("{place}/target/node")
            })?;
            let target_count = match node.mesh {
                Some(mesh) => self
                    .get(&self.root.meshes, mesh.value(), "mesh", || {
                        format!("/nodes/{node_index}/mesh")
                    })?
                    .primitives
                    .first()
                    .map_or(0, |p| p.targets.as_ref().map_or(0, Vec::len)),
                None => 0,
            };
            let per_key = match interpolation {
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
                .map(|chunk| match interpolation {
                    // In-tangents, values, out-tangents: the values are the middle third.
                    Interpolation::CubicSpline => chunk[target_count..2 * target_count].to_vec(),
                    _ => chunk.to_vec(),
                })
                .collect();
            weights_of_node.insert(node_index, keys);
        }
        Ok(Some(Keyframes {
            animation: animation_index,
            times: times.unwrap_or_default(),
            weights_of_node,
        }))
    }

    /// Refuses keyframes whose frames would be too many points to hold.
    pub fn check_frames(
        &self,
        keyframes: &Keyframes,
        decoded: &[Lines],
        pieces: &[Piece],
    ) -> Result<(), ImportError> {
        let (animation_index, times) = (keyframes.animation, &keyframes.times);
        let vertices: usize = pieces.iter().map(|p| decoded[p.lines].point_count()).sum();
        // Few morph targets can drive many keyframes: bound what the frames
        // would take, by a fixed limit and by the bytes the file has, before
        // allocating them.
        let frame_points = (times.len() as u64).saturating_mul(vertices as u64);
        self.charge(frame_points.saturating_mul(12), || {
            format!("/animations/{animation_index}")
        })?;
        if frame_points > MAX_FRAME_POINTS {
            return Err(self.error(
                format!("/animations/{animation_index}"),
                format!(
                    "{} keyframes of {vertices} points are more than the {MAX_FRAME_POINTS} frame points groombake holds",
                    times.len()
                ),
            ));
        }
        Ok(())
    }

    /// Frame `k`: the base pose plus the targets weighted by keyframe `k`,
    /// of every piece in world coordinates. The targets with a nonzero
    /// weight must have been read (a [`super::lines::Target::Deferred`]
    /// one moves nothing).
    pub fn frame(
        &self,
        keyframes: &Keyframes,
        k: usize,
        decoded: &[Lines],
        pieces: &[Piece],
    ) -> Result<Frame, ImportError> {
        let animation_index = keyframes.animation;
        let time = keyframes.times.get(k).copied().unwrap_or_default();
        let vertices: usize = pieces.iter().map(|p| decoded[p.lines].point_count()).sum();
        let mut points = Vec::with_capacity(vertices);
        for piece in pieces {
            let lines = &decoded[piece.lines];
            let weights = keyframes.weights(k, piece, lines);
            for &i in lines.strands.iter().flatten() {
                let mut p = lines.positions.get(i).copied().unwrap_or_default();
                for (target, &w) in lines.targets.iter().zip(weights) {
                    let Target::Deltas(deltas) = target else {
                        continue;
                    };
                    let Some(d) = deltas.get(i) else {
                        continue;
                    };
                    if w != 0.0 {
                        for c in 0..3 {
                            p[c] += w * d[c];
                        }
                    }
                }
                points.push(transform(&piece.world, p));
            }
        }
        if points.iter().flatten().any(|c| !c.is_finite()) {
            return Err(self.error(
                format!("/animations/{animation_index}"),
                format!("keyframe {k} moves a point to a value that is not finite"),
            ));
        }
        Ok(Frame {
            time: time as f64,
            points,
            attributes: Vec::new(),
        })
    }
}
