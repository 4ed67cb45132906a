//! Frame-at-a-time reading: [`FrameStream::open`] reads a groom file's
//! topology (counts, rest points, attributes) and its frame times, then
//! [`FrameStream::frame`] reads frame `k` alone, so a tool that looks at
//! every frame in turn (`inspect`) or at a few (`preview`) holds one frame
//! plus the topology, however large the file.
//!
//! Alembic, USD crate files (`.usdc`, and `.usd` holding a crate) and GLB
//! are read this way from a memory map whose pages are released after each
//! frame (`crate::mapped`); a crate layer that composes other layers, or
//! whose topology changes over time, is read whole (`crate::usd::stream`),
//! as is a GLB whose buffers are not all its BIN chunk
//! (`crate::gltf::stream`). The other formats are read whole and their
//! frames handed out one by one (`.usda` is text parsed whole; a `.gltf`
//! holds its buffers in base64 or in other files).

use crate::abc::{archive::Archive, ogawa::Fault, scene};
use crate::gltf::{self, GltfStream};
use crate::mapped::Mapped;
use crate::usd::stream::{Opened, UsdStream};
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
    /// A USD crate file, each frame decoded from the map when asked for.
    Usd(Mapped, Box<UsdStream>),
    /// A GLB, each frame's morph targets read from the map when asked for.
    Gltf(Mapped, GltfStream),
    /// A file read whole: its frames, handed out by copy.
    Whole(Vec<Frame>),
}

impl FrameStream {
    /// Opens `path` (format by extension, as [`crate::read`]) and reads
    /// its topology and frame times.
    pub fn open(path: &Path) -> Result<FrameStream, ImportError> {
        if let Some(stream) = FrameStream::open_usd_crate(path)? {
            return Ok(stream);
        }
        if let Some(stream) = FrameStream::open_glb(path)? {
            return Ok(stream);
        }
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

    /// A USD file (`.usdc`, `.usd`) opened to stream from its crate
    /// layer; `None` when it is text, or composes other layers, or its
    /// topology changes over time (`crate::usd::stream`): then it is read
    /// whole, by [`FrameStream::open`] or, to follow the changing topology,
    /// by [`crate::read_sequence`].
    pub fn open_usd_crate(path: &Path) -> Result<Option<FrameStream>, ImportError> {
        if !matches!(extension_of(path).as_str(), "usdc" | "usd") {
            return Ok(None);
        }
        let mut mapped = Mapped::open(path)?;
        let opened = UsdStream::open(path, mapped.bytes())?;
        mapped.release();
        Ok(opened.map(
            |Opened {
                 stream,
                 groom,
                 times,
             }| {
                FrameStream::streamed(path, groom, times, Source::Usd(mapped, Box::new(stream)))
            },
        ))
    }

    /// A glTF file (`.glb`, `.gltf`) opened to stream from its memory map;
    /// `None` when it is not a GLB with all its buffers in its BIN chunk,
    /// or holds no animated strands (`crate::gltf::stream`): then it is read
    /// whole.
    fn open_glb(path: &Path) -> Result<Option<FrameStream>, ImportError> {
        if !matches!(extension_of(path).as_str(), "glb" | "gltf") {
            return Ok(None);
        }
        let mut mapped = Mapped::open(path)?;
        let opened = GltfStream::open(path, mapped.bytes())?;
        mapped.release();
        Ok(opened.map(
            |gltf::Opened {
                 stream,
                 groom,
                 times,
             }| {
                FrameStream::streamed(path, groom, times, Source::Gltf(mapped, stream))
            },
        ))
    }

    /// A stream of a USD or glTF file, its groom finished as `crate::read`
    /// finishes one of these formats (which record their units).
    fn streamed(path: &Path, mut groom: Groom, times: Vec<f64>, source: Source) -> FrameStream {
        groom.provenance.source = Some(path.to_path_buf());
        if groom.provenance.units_source.is_empty() {
            groom.provenance.units_source = "file".into();
        }
        FrameStream {
            path: path.to_path_buf(),
            groom,
            times,
            source,
        }
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
            Source::Gltf(mapped, stream) => {
                let frame = stream.frame(&self.path, mapped.bytes(), index);
                mapped.release();
                frame
            }
            Source::Usd(mapped, stream) => {
                let frame = stream.frame(&self.path, mapped.bytes(), index);
                mapped.release();
                frame
            }
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

    /// An animated groom of two strands with a width held still and a
    /// wetness that changes every frame (written per frame), and a bond
    /// rate that changes on some frames only.
    fn animated_groom(frames: usize) -> Groom {
        use groom::{Attribute, AttributeValues};
        let mut groom = Groom::from_strands([
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.5]],
            vec![[1.0, 0.0, 0.0], [1.0, 1.5, 0.25]],
        ]);
        groom.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float(vec![0.1, 0.08, 0.05, 0.1, 0.05]),
        ));
        groom.set_attribute(Attribute::new(
            "wetness",
            AttributeValues::Float(vec![1.0; 5]),
        ));
        groom.set_attribute(Attribute::per_strand(
            "bond_hydrogen",
            AttributeValues::Float(vec![1.0, 1.0]),
        ));
        groom.frames = (0..frames)
            .map(|i| Frame {
                time: i as f64 / 24.0,
                points: groom
                    .points
                    .iter()
                    .map(|p| [p[0] + 0.1 * i as f32, p[1], p[2] - 0.01 * (i * i) as f32])
                    .collect(),
                attributes: vec![
                    Attribute::new(
                        "wetness",
                        AttributeValues::Float(vec![1.0 - 0.1 * i as f32; 5]),
                    ),
                    Attribute::per_strand(
                        "bond_hydrogen",
                        AttributeValues::Float(vec![1.0 - 0.05 * (i / 2) as f32, 0.5]),
                    ),
                ],
            })
            .collect();
        groom
    }

    /// A USD crate file streams: each frame read alone equals the whole
    /// read's, points and per-frame primvars, in any order; the topology
    /// and rest equal the whole read's without frames.
    #[test]
    fn usd_crate_frames_read_one_at_a_time_equal_the_whole_read() {
        let dir = std::env::temp_dir().join(format!("groombake-usd-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["anim.usdc", "anim.usd"] {
            let path = dir.join(name);
            exporters::write(&path, &animated_groom(7)).unwrap();
            let whole = crate::read(&path).unwrap();
            assert_eq!(whole.frames.len(), 7);
            assert!(whole.frames[3].attribute("wetness").is_some(), "{name}");
            let mut stream = FrameStream::open(&path).unwrap();
            assert!(
                matches!(stream.source, Source::Usd(..)),
                "{name} was read whole"
            );
            let mut rest = whole.clone();
            rest.frames.clear();
            assert_eq!(stream.groom(), &rest, "{name}");
            assert_eq!(
                stream.times(),
                whole.frames.iter().map(|f| f.time).collect::<Vec<_>>()
            );
            for index in [6, 0, 3, 1, 2, 5, 4] {
                assert_eq!(
                    &stream.frame(index).unwrap(),
                    &whole.frames[index],
                    "{name} frame {index}"
                );
            }
            let error = stream.frame(7).unwrap_err().to_string();
            assert!(error.contains("no frame 7: the file has 7"), "{error}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A GLB streams: each frame read alone equals the whole read's, in
    /// any order; the topology, rest, attributes and losses equal the whole
    /// read's without frames. A `.gltf` (base64 buffer) is read whole.
    #[test]
    fn glb_frames_read_one_at_a_time_equal_the_whole_read() {
        let dir = std::env::temp_dir().join(format!("groombake-glb-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("anim.glb");
        exporters::write(&path, &animated_groom(7)).unwrap();
        let whole = crate::read(&path).unwrap();
        assert_eq!(whole.frames.len(), 7);
        let mut stream = FrameStream::open(&path).unwrap();
        assert!(matches!(stream.source, Source::Gltf(..)), "read whole");
        let mut rest = whole.clone();
        rest.frames.clear();
        assert_eq!(stream.groom(), &rest);
        assert_eq!(
            stream.times(),
            whole.frames.iter().map(|f| f.time).collect::<Vec<_>>()
        );
        for index in [6, 0, 3, 1, 2, 5, 4] {
            assert_eq!(
                &stream.frame(index).unwrap(),
                &whole.frames[index],
                "frame {index}"
            );
        }
        let error = stream.frame(7).unwrap_err().to_string();
        assert!(error.contains("no frame 7: the file has 7"), "{error}");
        assert_eq!(
            crate::gltf::read_streamed_bytes(&path, &std::fs::read(&path).unwrap())
                .unwrap()
                .unwrap()
                .frames,
            whole.frames
        );

        let path = dir.join("anim.gltf");
        exporters::write(&path, &animated_groom(3)).unwrap();
        let stream = FrameStream::open(&path).unwrap();
        assert!(matches!(stream.source, Source::Whole(_)));
        assert_eq!(stream.frame_count(), 3);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A GLB frame reads only the targets it weights: a value that is not
    /// finite in the target of frame 2 (the exporter writes one target per
    /// frame, switched fully on at its frame) leaves opening and frames 0
    /// and 1 as the whole read would have them, and frame 2 fails with the
    /// whole read's message.
    #[test]
    fn a_bad_glb_target_fails_the_frame_that_weights_it_as_the_whole_read_fails() {
        let dir = std::env::temp_dir().join(format!("groombake-glb-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("anim.glb");
        let groom = animated_groom(3);
        exporters::write(&path, &groom).unwrap();
        let good = crate::read(&path).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        // GLB: 12-byte header, the JSON chunk (8-byte header), the BIN chunk.
        let json_length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_length]).unwrap();
        let bin = 20 + json_length + 8;
        let accessor = json["meshes"][0]["primitives"][0]["targets"][2]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        let accessor = &json["accessors"][accessor];
        let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
        let at = bin
            + view["byteOffset"].as_u64().unwrap_or(0) as usize
            + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
        bytes[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();

        let whole = crate::read(&path).unwrap_err().to_string();
        assert!(whole.contains("is not finite"), "{whole}");
        let mut stream = FrameStream::open(&path).unwrap();
        assert!(matches!(stream.source, Source::Gltf(..)));
        assert_eq!(stream.frame_count(), 3);
        assert_eq!(stream.frame(0).unwrap(), good.frames[0]);
        assert_eq!(stream.frame(1).unwrap(), good.frames[1]);
        assert_eq!(stream.frame(2).unwrap_err().to_string(), whole);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Text USD and a crate file without frames are read whole, as before.
    #[test]
    fn usda_and_still_crate_files_read_whole() {
        let dir = std::env::temp_dir().join(format!("groombake-usd-whole-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("anim.usda");
        exporters::write(&path, &animated_groom(3)).unwrap();
        let stream = FrameStream::open(&path).unwrap();
        assert!(matches!(stream.source, Source::Whole(_)));
        assert_eq!(stream.frame_count(), 3);
        let path = dir.join("still.usdc");
        exporters::write(&path, &animated_groom(0)).unwrap();
        let mut stream = FrameStream::open(&path).unwrap();
        assert_eq!(stream.frame_count(), 0);
        assert_eq!(stream.groom(), &crate::read(&path).unwrap());
        assert!(stream.frame(0).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A file usd-core wrote with the samples a stream must pick as the
    /// whole read does (tests/data/make_streaming_edges.py): out-of-order
    /// and defaulted points, a primvar held between its codes, a blocked
    /// sample, two prims.
    #[test]
    fn usd_core_samples_stream_as_they_read_whole() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/streaming_edges.usdc");
        let whole = crate::read(&path).unwrap();
        assert_eq!(whole.frames.len(), 4);
        assert!(whole
            .frames
            .iter()
            .all(|f| f.attribute("wetness").is_some()));
        let mut stream = FrameStream::open(&path).unwrap();
        assert!(matches!(stream.source, Source::Usd(..)));
        let mut rest = whole.clone();
        rest.frames.clear();
        assert_eq!(stream.groom(), &rest);
        for (index, frame) in whole.frames.iter().enumerate().rev() {
            assert_eq!(&stream.frame(index).unwrap(), frame, "frame {index}");
        }
    }
}
