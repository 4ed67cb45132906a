//! What a groom read from a glTF leaves out of the file, one line each for
//! `Provenance::losses` (`convert` and `inspect` warn of them, `--strict`
//! refuses them): primitives that are not lines (a head mesh, points) and
//! animation channels other than the morph-target weights of the strands.

use super::animation::{drives_weights, Piece};
use super::document::Document;
use gltf::json;
use json::animation::Property;
use json::mesh::Mode;
use json::validation::Checked;

/// How many places a loss line lists before "and N more".
const LISTED: usize = 3;

/// A primitive of the scene that is not read as strands.
pub(super) struct Skipped {
    pub mesh: usize,
    pub primitive: usize,
    pub mode: Mode,
}

fn listed(places: &[String]) -> String {
    let mut text = places
        .iter()
        .take(LISTED)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if places.len() > LISTED {
        text.push_str(&format!(" and {} more", places.len() - LISTED));
    }
    text
}

fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

/// The scene's primitives that are not lines, as one loss line.
pub(super) fn skipped_primitives(skipped: &[Skipped]) -> Option<String> {
    if skipped.is_empty() {
        return None;
    }
    let places: Vec<String> = skipped
        .iter()
        .map(|s| {
            format!(
                "/meshes/{}/primitives/{} ({})",
                s.mesh,
                s.primitive,
                mode_name(s.mode)
            )
        })
        .collect();
    Some(format!(
        "{} primitive(s) not read (a groom is LINES and LINE_STRIP; a mesh is a \
         collider): {}",
        skipped.len(),
        listed(&places)
    ))
}

impl Document<'_> {
    /// The animation channels that do not become frames, as one loss line:
    /// only the morph-target weights of nodes that hold strands, in the
    /// first animation that has weights, are read (`frames`).
    pub(super) fn unread_channels(&self, pieces: &[Piece]) -> Option<String> {
        let read_animation = self
            .root
            .animations
            .iter()
            .position(|a| a.channels.iter().any(drives_weights));
        let mut places = Vec::new();
        for (a, animation) in self.root.animations.iter().enumerate() {
            for (c, channel) in animation.channels.iter().enumerate() {
                if let Some((_, _, path)) = self
                    .nodeless_channels
                    .iter()
                    .find(|(na, nc, _)| (*na, *nc) == (a, c))
                {
                    places.push(format!(
                        "/animations/{a}/channels/{c} ({}, no node: an extension's target)",
                        crate::escape_controls(&path.chars().take(40).collect::<String>())
                    ));
                    continue;
                }
                let node = channel.target.node.value();
                let read = Some(a) == read_animation
                    && drives_weights(channel)
                    && pieces.iter().any(|p| p.node == node);
                if read {
                    continue;
                }
                let path = match channel.target.path {
                    Checked::Valid(Property::Translation) => "translation",
                    Checked::Valid(Property::Rotation) => "rotation",
                    Checked::Valid(Property::Scale) => "scale",
                    Checked::Valid(Property::MorphTargetWeights) => "weights",
                    Checked::Invalid => "a path glTF does not define",
                };
                places.push(format!(
                    "/animations/{a}/channels/{c} ({path} of node {node})"
                ));
            }
        }
        if places.is_empty() {
            return None;
        }
        Some(format!(
            "{} animation channel(s) not read (frames are the strands' morph-target \
             weights, from the first animation with them): {}",
            places.len(),
            listed(&places)
        ))
    }
}
