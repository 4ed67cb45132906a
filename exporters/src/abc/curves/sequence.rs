//! A groom whose topology changes over time (`importers::read_sequence`) as
//! one Alembic curves object: Alembic stores `nVertices` (and `width`, `uv`
//! and every geometry parameter) per sample, so each stretch of one
//! topology starts with its own values, which the following frames repeat.

use super::{fixed_samples, CurvesExport};
use crate::{AttributeSet, ExportError, FrameWriter};
use groom::{Groom, UpAxis};
use std::path::Path;

/// Frames per second of a sequence (its frames' times give the sampling:
/// uniform at this rate when they fall on its grid, else every time).
const SEQUENCE_FPS: f64 = 24.0;

/// Writes grooms that follow each other in time with different topologies,
/// in time order: every frame of every groom is one sample (a groom without
/// frames is one sample at its time 0). The grooms must have the same
/// properties (attributes, names, types and scopes).
pub fn write_sequence(
    path: &Path,
    grooms: &[Groom],
    attributes: AttributeSet,
) -> Result<(), ExportError> {
    let Some(first) = grooms.first() else {
        return Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: "a sequence needs at least one groom".into(),
        });
    };
    let mut export = CurvesExport::start(path, first, Some(SEQUENCE_FPS), attributes)?;
    for (index, groom) in grooms.iter().enumerate() {
        if index > 0 {
            export.change_topology(groom, attributes)?;
        }
        for frame in groom.frames_or_rest().iter() {
            export.write_frame(frame)?;
        }
    }
    export.finish()
}

impl CurvesExport {
    fn fixed_names(&self) -> Vec<&str> {
        self.fixed.iter().map(|p| p.name()).collect()
    }

    /// Gives the next sample the topology and attribute values of `groom`.
    fn change_topology(
        &mut self,
        groom: &Groom,
        attributes: AttributeSet,
    ) -> Result<(), ExportError> {
        let invalid = |message: &str| ExportError::Invalid {
            file: self.path.clone(),
            message: format!("the grooms of a sequence must {message}"),
        };
        let mut y_up = groom.clone();
        y_up.frames.clear();
        y_up.convert_to(groom.units, UpAxis::Y);
        let fixed = fixed_samples(&y_up);
        let names: Vec<&str> = fixed.iter().map(|f| f.name).collect();
        if names != self.fixed_names() {
            return Err(invalid("have the same widths and root uvs"));
        }
        let (_, sources) = Self::arbitrary_properties(&y_up, 1, attributes);
        let same = sources.len() == self.arbitrary_sources.len()
            && sources.iter().zip(&self.arbitrary_sources).all(|(a, b)| {
                (&a.attribute, a.scope, a.pod, a.extent) == (&b.attribute, b.scope, b.pod, b.extent)
            });
        if !same {
            return Err(invalid("have the same attributes"));
        }
        for (property, value) in self.fixed.iter_mut().zip(fixed) {
            property
                .set_sample(&mut self.archive, &value.bytes)
                .map_err(|e| ExportError::io(&self.path, e))?;
        }
        self.fixed_given = true;
        for (source, new) in self.arbitrary_sources.iter_mut().zip(sources) {
            source.first = new.first;
        }
        self.vertex_count = groom.points.len();
        Ok(())
    }
}
