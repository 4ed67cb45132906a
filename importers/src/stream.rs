//! Frame-at-a-time reading: [`FrameStream::open`] reads a groom file's
//! topology (counts, rest points, attributes) and its frame times, then
//! [`FrameStream::frame`] reads frame `k` alone, so a tool that looks at
//! every frame in turn (`inspect`) or at a few (`preview`) holds one frame
//! plus the topology, however large the file.
//!
//! Alembic is read this way from a memory map whose pages are released
//! after each frame (`crate::mapped`). The other formats are read whole
//! and their frames handed out one by one (USD's layer model and glTF's
//! accessors decode every sample on reading; streaming them is to do).

use crate::abc::{archive::Archive, ogawa::Fault, scene};
use crate::mapped::Mapped;
use crate::{extension_of, ImportError};
use groom::{Frame, Groom};
use std::path::{Path, PathBuf};

/// An open groom file read a frame at a time.
pub struct FrameStream {
    path: PathBuf,
    /// The topology and rest pose: [`crate::read`]'s groom without frames.
    groom: Groom,
    times: Vec<f64>,
    source: Source,
}

enum Source {
    /// An Alembic file, each frame read from the map when asked for.
    Abc(Mapped),
    /// A file read whole: its frames, handed out by copy.
    Whole(Vec<Frame>),
}

impl FrameStream {
    /// Opens `path` (format by extension, as [`crate::read`]) and reads
    /// its topology and frame times.
    pub fn open(path: &Path) -> Result<FrameStream, ImportError> {
        if extension_of(path) != "abc" {
            let mut groom = crate::read(path)?;
            let frames = std::mem::take(&mut groom.frames);
            return Ok(FrameStream {
                path: path.to_path_buf(),
                times: frames.iter().map(|f| f.time).collect(),
                groom,
                source: Source::Whole(frames),
            });
        }
        let mut mapped = Mapped::open(path)?;
        let (mut groom, times) = abc_sample(path, &mapped, 0)?;
        mapped.release();
        groom.frames.clear();
        groom.provenance.source = Some(path.to_path_buf());
        if groom.provenance.units_source.is_empty() {
            groom.provenance.units_source = "format".into();
        }
        Ok(FrameStream {
            path: path.to_path_buf(),
            groom,
            times,
            source: Source::Abc(mapped),
        })
    }

    /// The topology, rest points and attributes (no frames).
    pub fn groom(&self) -> &Groom {
        &self.groom
    }

    /// The times of the frames, seconds, in file order.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    pub fn frame_count(&self) -> usize {
        self.times.len()
    }

    /// Frame `index` (0-based; the caller keeps it below
    /// [`FrameStream::frame_count`]).
    pub fn frame(&mut self, index: usize) -> Result<Frame, ImportError> {
        let missing = || {
            ImportError::malformed(
                &self.path,
                crate::Place::File,
                format!("no frame {index}: the file has {}", self.times.len()),
            )
        };
        match &mut self.source {
            Source::Whole(frames) => frames.get(index).cloned().ok_or_else(missing),
            Source::Abc(mapped) => {
                let sample = u32::try_from(index).map_err(|_| missing())?;
                let (mut groom, _) = abc_sample(&self.path, mapped, sample)?;
                mapped.release();
                let mut frame = groom.frames.pop().ok_or_else(missing)?;
                // Objects sampled fewer times hold their last sample; the
                // frame's time is the most-sampled object's, as `read` has it.
                frame.time = self.times.get(index).copied().ok_or_else(missing)?;
                Ok(frame)
            }
        }
    }
}

/// The groom of sample `sample` of an Alembic file (its rest points and
/// single frame) and the times of all its frames.
fn abc_sample(path: &Path, mapped: &Mapped, sample: u32) -> Result<(Groom, Vec<f64>), ImportError> {
    let fail = |fault: Fault| ImportError::malformed(path, fault.place, fault.message);
    let archive = Archive::open(mapped.bytes()).map_err(fail)?;
    scene::read_groom_samples(&archive, Some(sample)).map_err(fail)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frame by frame, the stream gives what reading the file whole gives:
    /// topology, rest points, attributes, and each frame.
    #[test]
    fn frames_read_one_at_a_time_equal_the_whole_read() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xform_cubic_indexed.abc");
        let whole = crate::read(&path).unwrap();
        assert_eq!(whole.frames.len(), 3);
        let mut stream = FrameStream::open(&path).unwrap();
        let mut rest = whole.clone();
        rest.frames.clear();
        assert_eq!(stream.groom(), &rest);
        assert_eq!(stream.frame_count(), 3);
        for (index, frame) in whole.frames.iter().enumerate() {
            assert_eq!(&stream.frame(index).unwrap(), frame, "frame {index}");
        }
        // Again, out of order: each read stands alone.
        assert_eq!(&stream.frame(1).unwrap(), &whole.frames[1]);
        let error = stream.frame(3).unwrap_err().to_string();
        assert!(error.contains("no frame 3: the file has 3"), "{error}");
    }
}
