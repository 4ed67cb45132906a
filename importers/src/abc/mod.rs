//! Alembic (Ogawa) import: the container ([`ogawa`]), Alembic's objects and
//! properties on it ([`archive`]) and the curves scene ([`scene`]).
//!
//! The whole file is read into memory; every offset, size and count in it is
//! checked against the bytes there before use.

pub mod archive;
pub mod ogawa;
pub mod scene;

use crate::{read_bytes, ImportError};
use groom::Groom;
use std::path::Path;

/// Reads every Curves object of an `.abc` file into one groom.
pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = read_bytes(path)?;
    parse(path, &bytes)
}

/// Reads a groom from the bytes of an `.abc` file; `path` names it in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let fail = |fault: ogawa::Fault| ImportError::malformed(path, fault.place, fault.message);
    let archive = archive::Archive::open(bytes).map_err(fail)?;
    scene::read_groom(&archive).map_err(fail)
}

#[cfg(test)]
mod tests {
    use super::*;
    use groom::{Attribute, AttributeValues, CurveBasis, Frame, Scope, Units, UpAxis};
    use std::path::PathBuf;

    /// A file of the workspace's `tests/data/`.
    fn test_data(name: &str) -> PathBuf {
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data")).join(name)
    }

    struct TempDir(PathBuf);

    impl TempDir {
        fn new(label: &str) -> TempDir {
            let dir =
                std::env::temp_dir().join(format!("groombake-abc-{label}-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            TempDir(dir)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// The points of a Cem Yuksel `.hair` file with segments and points
    /// arrays (enough for the shared Bangs sample).
    fn hair_file(path: &Path) -> (Vec<u32>, Vec<[f32; 3]>) {
        let bytes = std::fs::read(path).unwrap();
        let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let (strands, points, flags) = (u32_at(4) as usize, u32_at(8) as usize, u32_at(12));
        assert_eq!(flags & 3, 3, "segments and points arrays");
        let mut at = 128;
        let counts: Vec<u32> = (0..strands)
            .map(|i| {
                u32::from(u16::from_le_bytes([
                    bytes[at + 2 * i],
                    bytes[at + 2 * i + 1],
                ])) + 1
            })
            .collect();
        at += 2 * strands;
        let f =
            |i: usize| f32::from_le_bytes(bytes[at + 4 * i..at + 4 * i + 4].try_into().unwrap());
        let points = (0..points)
            .map(|i| [f(3 * i), f(3 * i + 1), f(3 * i + 2)])
            .collect();
        (counts, points)
    }

    #[test]
    fn hairutil_bangs_matches_its_hair_file() {
        let groom = read(&test_data("hairutil_Bangs_100.abc")).unwrap();
        let (counts, points) = hair_file(&test_data("hairutil_Bangs_100.hair"));
        assert_eq!(groom.strand_count(), 100);
        assert_eq!(groom.vertex_count(), 1165);
        assert_eq!(groom.strand_vertex_counts, counts);
        assert_eq!(groom.points, points);
        assert_eq!(groom.basis, CurveBasis::Linear);
        assert!(groom.frames.is_empty());
        assert_eq!(groom.provenance.format, "abc");
    }

    /// Values as the Alembic library reads them (alembic3d): the Poly
    /// curves, then the Hair curves (whose animated Xform is identity at its
    /// first sample).
    #[test]
    fn blender_static_matches_the_alembic_library() {
        let groom = read(&test_data("blender501_hair_static.abc")).unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![4, 4, 3, 4, 5]);
        let expected: Vec<[f32; 3]> = [
            (1.0, 0.0),
            (1.0, 0.1),
            (1.0, 0.2),
            (1.0, 0.3),
            (1.1, 0.0),
            (1.1, 0.1),
            (1.1, 0.2),
            (1.1, 0.3),
            (0.0, 0.0),
            (0.0, 0.1),
            (0.0, 0.2),
            (0.1, 0.0),
            (0.1, 0.1),
            (0.1, 0.2),
            (0.1, 0.3),
            (0.2, 0.0),
            (0.2, 0.1),
            (0.2, 0.2),
            (0.2, 0.3),
            (0.2, 0.4),
        ]
        .iter()
        .map(|&(x, y)| [x as f32, y as f32, 0.0])
        .collect();
        assert_eq!(groom.points, expected);
        let mut widths = vec![2.0f32; 8];
        widths.extend([0.02f32; 12]);
        assert_eq!(
            groom.attribute("width").map(|a| &a.values),
            Some(&AttributeValues::Float(widths))
        );
        assert!(groom.validate().iter().all(|p| !p.is_fatal()));
    }

    /// Written by the Alembic library (`tests/data/make_xform_cubic_indexed.py`);
    /// the expected point is Imath's `P * M` as alembic3d computes it.
    #[test]
    fn xform_ops_cubic_basis_and_indexed_uvs() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xform_cubic_indexed.abc");
        let groom = read(&path).unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![4, 4]);
        assert_eq!(groom.basis, CurveBasis::Bspline);
        let expected = [3.23205, 2.0, 2.86603];
        for (got, want) in groom.points[1].iter().zip(expected) {
            assert!((got - want).abs() < 1e-4, "{:?}", groom.points[1]);
        }
        assert_eq!(groom.points[0], [1.0, 2.0, 3.0]);
        let times: Vec<f64> = groom.frames.iter().map(|f| f.time).collect();
        assert_eq!(times.len(), 3);
        for (i, t) in times.iter().enumerate() {
            assert!((t - i as f64 / 30.0).abs() < 1e-12, "{times:?}");
        }
        // Frame 2 moved the curves by 2 along their own x, scaled by 2 and
        // turned 30 degrees about Y.
        let moved = groom.frames[2].points[0];
        let step = [
            4.0 * 30f32.to_radians().cos(),
            0.0,
            -4.0 * 30f32.to_radians().sin(),
        ];
        for k in 0..3 {
            assert!(
                (moved[k] - groom.points[0][k] - step[k]).abs() < 1e-4,
                "{moved:?}"
            );
        }
        assert_eq!(
            groom.attribute("root_uv").map(|a| (&a.values, a.scope)),
            Some((
                &AttributeValues::Vec2(vec![[0.3, 0.4], [0.1, 0.2]]),
                Scope::Strand
            ))
        );
    }

    /// A Curves scene written with the exporter's low-level archive API:
    /// `P` with one stored sample of `points` points repeated `samples` times.
    fn repeated_points_file(points: usize, samples: u32) -> Vec<u8> {
        use exporters::abc::archive::{metadata, ArchiveWriter, Pod, PropertyKind, PropertyWriter};
        let mut archive = ArchiveWriter::new(std::io::Cursor::new(Vec::new())).unwrap();
        let mut p = PropertyWriter::new("P", String::new(), PropertyKind::Array, Pod::F32, 3, 0);
        p.set_sample(&mut archive, &vec![0u8; 12 * points]).unwrap();
        for _ in 1..samples {
            p.repeat_previous();
        }
        let mut n = PropertyWriter::new(
            "nVertices",
            String::new(),
            PropertyKind::Array,
            Pod::I32,
            1,
            0,
        );
        n.set_sample(&mut archive, &(points as i32).to_le_bytes())
            .unwrap();
        let closed = vec![
            p.close(&mut archive).unwrap(),
            n.close(&mut archive).unwrap(),
        ];
        let geom = archive.close_compound(".geom", "", closed).unwrap();
        let schema = metadata(&[("schema", "AbcGeom_Curve_v2")]);
        let curves = archive
            .close_object("curves", &schema, vec![geom], Vec::new())
            .unwrap();
        archive.finish("", vec![curves]).unwrap().into_inner()
    }

    /// Regression: a header may claim many samples that all share one
    /// stored block; the frames they would make must not be built.
    #[test]
    fn regression_shared_samples_cannot_expand_without_bound() {
        let bytes = repeated_points_file(1000, 200_000);
        assert!(bytes.len() < 20_000, "{} bytes", bytes.len());
        let text = assert_clean_error(Path::new("bomb.abc"), &bytes);
        assert!(text.contains("bomb.abc:/curves/.geom/P"), "{text}");
        assert!(text.contains("far more data than the file holds"), "{text}");
        // A few repeats are fine: they are frames.
        let groom = parse(Path::new("ok.abc"), &repeated_points_file(10, 5)).unwrap();
        assert_eq!(groom.frames.len(), 5);
    }

    /// Curves whose vertex counts change between samples cannot be one
    /// groom: refused by property path. The check walks the stored samples,
    /// not the (unchecked) sample count of the header.
    #[test]
    fn changing_topology_is_refused() {
        use exporters::abc::archive::{ArchiveWriter, Pod, PropertyKind, PropertyWriter};
        let mut archive = ArchiveWriter::new(std::io::Cursor::new(Vec::new())).unwrap();
        let mut p = PropertyWriter::new("P", String::new(), PropertyKind::Array, Pod::F32, 3, 0);
        p.set_sample(&mut archive, &[0u8; 24]).unwrap();
        let mut n = PropertyWriter::new(
            "nVertices",
            String::new(),
            PropertyKind::Array,
            Pod::I32,
            1,
            0,
        );
        n.set_sample(&mut archive, &2i32.to_le_bytes()).unwrap();
        for _ in 0..1000 {
            n.repeat_previous();
        }
        n.set_sample(&mut archive, &[1, 0, 0, 0, 1, 0, 0, 0])
            .unwrap();
        let closed = vec![
            p.close(&mut archive).unwrap(),
            n.close(&mut archive).unwrap(),
        ];
        let geom = archive.close_compound(".geom", "", closed).unwrap();
        let curves = archive
            .close_object("hair", "schema=AbcGeom_Curve_v2", vec![geom], Vec::new())
            .unwrap();
        let bytes = archive.finish("", vec![curves]).unwrap().into_inner();
        let text = assert_clean_error(Path::new("topo.abc"), &bytes);
        assert!(
            text.contains("topo.abc:/hair/.geom/nVertices: the curve topology changes"),
            "{text}"
        );
    }

    /// Regression: an object group listed as its own descendant would make
    /// the tree walk endless; the reader refuses a group it has seen.
    #[test]
    fn regression_cyclic_object_tree_is_refused() {
        let dir = TempDir::new("cycle");
        let mut bytes = exported(&dir, "cycle.abc", &sample_groom());
        let (top, groom_object) = {
            let ogawa = ogawa::Ogawa::open(&bytes).unwrap();
            let root = ogawa.group(ogawa.root()).unwrap();
            let top = root[2];
            (top, ogawa.group(top).unwrap()[1])
        };
        // /groom's children: [properties, curves, headers]; point its child
        // at the top object instead.
        let at = groom_object as usize + 8 + 8;
        bytes[at..at + 8].copy_from_slice(&top.to_le_bytes());
        let text = assert_clean_error(Path::new("cycle.abc"), &bytes);
        assert!(text.contains("used twice"), "{text}");
    }

    /// `sample_groom` standing still at three uneven (acyclic) times.
    fn sample_groom_at_uneven_times() -> Groom {
        let mut groom = sample_groom();
        groom.frames = [0.0, 0.1, 0.35]
            .iter()
            .map(|&time| Frame {
                time,
                points: groom.points.clone(),
                attributes: Vec::new(),
            })
            .collect();
        groom
    }

    fn sample_groom() -> Groom {
        let mut groom = Groom::from_strands([
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.5]],
            vec![[1.0, 0.0, 0.0], [1.0, 1.5, 0.0]],
        ]);
        groom.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float(vec![0.1, 0.09, 0.08, 0.1, 0.05]),
        ));
        groom.set_attribute(Attribute::per_strand(
            "root_uv",
            AttributeValues::Vec2(vec![[0.25, 0.5], [0.75, 0.5]]),
        ));
        groom.set_attribute(Attribute::new(
            "wetness",
            AttributeValues::Float(vec![0.0, 0.25, 0.5, 0.75, 1.0]),
        ));
        groom.set_attribute(Attribute::per_strand(
            "bond_rates",
            AttributeValues::Vec3(vec![[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]),
        ));
        groom.set_attribute(Attribute::per_strand(
            "clump",
            AttributeValues::Int(vec![7, -3]),
        ));
        groom
    }

    fn exported(dir: &TempDir, name: &str, groom: &Groom) -> Vec<u8> {
        let path = dir.0.join(name);
        exporters::write(&path, groom).unwrap();
        std::fs::read(&path).unwrap()
    }

    #[test]
    fn static_round_trip_keeps_points_and_attributes() {
        let dir = TempDir::new("static");
        let groom = sample_groom();
        let path = dir.0.join("groom.abc");
        exporters::write(&path, &groom).unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.strand_vertex_counts, groom.strand_vertex_counts);
        assert_eq!(back.points, groom.points);
        assert_eq!(back.units, Units::CENTIMETERS);
        assert_eq!(back.up_axis, UpAxis::Y);
        assert_eq!(back.basis, CurveBasis::Linear);
        for name in ["width", "root_uv", "wetness", "bond_rates", "clump"] {
            assert_eq!(back.attribute(name), groom.attribute(name), "{name}");
        }
        // Unreal's groom_width repeats width: one attribute per meaning.
        assert!(back.attribute("groom_width").is_none());
        assert!(back.attribute("groom_root_uv").is_none());
        // Unreal's defaults (no guides, one group) mean what their absence
        // means: not kept.
        assert!(back.attribute("groom_guide").is_none());
        assert!(back.attribute("groom_group_id").is_none());
        assert!(back.provenance.info.starts_with("groombake "));
    }

    #[test]
    fn empty_groom_round_trips() {
        let dir = TempDir::new("empty");
        let path = dir.0.join("empty.abc");
        exporters::write(&path, &Groom::default()).unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.strand_count(), 0);
        assert_eq!(back.vertex_count(), 0);
    }

    #[test]
    fn export_keeps_its_units_and_marks_them_y_up() {
        let dir = TempDir::new("units");
        let mut groom = sample_groom();
        groom.units = Units::METERS;
        groom.up_axis = UpAxis::Z;
        let path = dir.0.join("m.abc");
        exporters::write(&path, &groom).unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.units, Units::METERS);
        assert_eq!(back.provenance.units_source, "file");
        let mut expected = groom.clone();
        expected.convert_to(Units::METERS, UpAxis::Y);
        assert_eq!(back.points, expected.points);
        assert_eq!(back.attribute("width"), expected.attribute("width"));
    }

    #[test]
    fn application_decides_units_where_no_mark() {
        use archive::Metadata;
        let units = |text: &str| scene::archive_units(&Metadata(text.into()));
        let blender = units("_ai_Application=Blender;blender_version=v5.0.10");
        assert_eq!(blender, (Units::METERS, "application Blender".into()));
        assert_eq!(units("_ai_Application=Houdini 20.5").0, Units::METERS);
        assert_eq!(units("_ai_Application=Maya 2025").0, Units::CENTIMETERS);
        assert_eq!(units("_ai_Application=Unreal Engine").0, Units::CENTIMETERS);
        assert_eq!(units("_ai_Application=Something").0, Units::CENTIMETERS);
        assert_eq!(units("").0, Units::CENTIMETERS);
        assert_eq!(units("").1, "format");
        let marked = units("_ai_Application=Blender;groombake_units=cm");
        assert_eq!(marked, (Units::CENTIMETERS, "file".into()));
    }

    #[test]
    fn animated_round_trip_gives_one_frame_per_sample() {
        let dir = TempDir::new("anim");
        let groom = sample_groom();
        let path = dir.0.join("anim.abc");
        let options = exporters::AnimationOptions {
            fps: 30.0,
            frame_count: 5,
        };
        let mut writer = exporters::animated(&path, &groom, options).unwrap();
        let mut frames = Vec::new();
        for i in 0..5 {
            let frame = Frame {
                time: 1.0 + i as f64 / 30.0,
                points: groom
                    .points
                    .iter()
                    .map(|p| [p[0] + i as f32, p[1], p[2] - 0.5 * i as f32])
                    .collect(),
                attributes: Vec::new(),
            };
            writer.write_frame(&frame).unwrap();
            frames.push(frame);
        }
        writer.finish().unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.frames.len(), 5);
        for (got, want) in back.frames.iter().zip(&frames) {
            assert!(
                (got.time - want.time).abs() < 1e-9,
                "{} vs {}",
                got.time,
                want.time
            );
            assert_eq!(got.points, want.points);
        }
        assert_eq!(back.points, frames[0].points);
        assert_eq!(back.attribute("wetness"), groom.attribute("wetness"));
    }

    #[test]
    fn uneven_frame_times_are_kept() {
        let dir = TempDir::new("acyclic");
        let groom = sample_groom_at_uneven_times();
        let path = dir.0.join("acyclic.abc");
        exporters::write(&path, &groom).unwrap();
        let back = read(&path).unwrap();
        let times: Vec<f64> = back.frames.iter().map(|f| f.time).collect();
        assert_eq!(times, vec![0.0, 0.1, 0.35]);
    }

    /// Regression: a time sampling that stores no time was reported as
    /// "0 stored times (must be 1 to 0)"; it says what is wrong instead, as
    /// does one that stores more times than its block holds.
    #[test]
    fn regression_time_sampling_with_no_stored_times_says_so() {
        let dir = TempDir::new("times");
        let groom = sample_groom_at_uneven_times();
        let bytes = exported(&dir, "times.abc", &groom);
        // The archive's fifth child holds the time samplings, each
        // `u32 max samples, f64 time per cycle, u32 count, f64 times[count]`.
        let (samplings_at, samplings) = {
            let ogawa = ogawa::Ogawa::open(&bytes).unwrap();
            let reference = ogawa.group(ogawa.root()).unwrap()[4];
            let data = ogawa.data(reference).unwrap();
            ((reference & !ogawa::DATA_BIT) as usize + 8, data.to_vec())
        };
        let first_count = u32::from_le_bytes(samplings[12..16].try_into().unwrap());
        assert!(first_count >= 1, "the export stores times");
        let with_count = |count: u32| {
            let mut bytes = bytes.clone();
            let at = samplings_at + 12;
            bytes[at..at + 4].copy_from_slice(&count.to_le_bytes());
            bytes
        };
        let text = assert_clean_error(Path::new("none.abc"), &with_count(0));
        assert!(
            text.ends_with("time sampling 0: no stored times (at least one is needed)"),
            "{text}"
        );
        assert!(!text.contains("must be"), "{text}");
        let room = (samplings.len() - 16) / 8;
        let text = assert_clean_error(Path::new("many.abc"), &with_count(1000));
        assert!(
            text.ends_with(&format!(
                "time sampling 0: 1000 stored times, but the block has room for {room}"
            )),
            "{text}"
        );
    }

    fn assert_clean_error(path: &Path, bytes: &[u8]) -> String {
        match parse(path, bytes) {
            Ok(_) => panic!("{} bytes parsed without error", bytes.len()),
            Err(error) => {
                let text = error.to_string();
                assert!(text.starts_with(&path.display().to_string()), "{text}");
                text
            }
        }
    }

    #[test]
    fn every_truncation_is_a_clean_error() {
        let dir = TempDir::new("truncate");
        let bytes = exported(&dir, "t.abc", &sample_groom());
        let path = Path::new("cut.abc");
        for cut in 0..bytes.len() {
            assert_clean_error(path, &bytes[..cut]);
        }
        let shared = std::fs::read(test_data("blender501_hair_static.abc")).unwrap();
        for cut in 0..shared.len() {
            assert_clean_error(path, &shared[..cut]);
        }
    }

    /// Every byte flipped in turn: the reader may accept the file or refuse
    /// it, but never panics or runs away.
    #[test]
    fn corrupted_bytes_never_panic() {
        let dir = TempDir::new("corrupt");
        let mut groom = sample_groom();
        groom.frames = (0..3)
            .map(|i| Frame {
                time: i as f64 / 24.0,
                points: groom
                    .points
                    .iter()
                    .map(|p| [p[0], p[1] + i as f32, p[2]])
                    .collect(),
                attributes: Vec::new(),
            })
            .collect();
        for bytes in [
            exported(&dir, "c.abc", &groom),
            std::fs::read(test_data("blender501_hair_static.abc")).unwrap(),
        ] {
            for at in 0..bytes.len() {
                for flip in [0xFFu8, 0x01, 0x80] {
                    let mut damaged = bytes.clone();
                    damaged[at] ^= flip;
                    let _ = parse(Path::new("damaged.abc"), &damaged);
                }
            }
        }
    }

    #[test]
    fn unfinished_file_is_refused_by_name() {
        let dir = TempDir::new("unfrozen");
        let mut bytes = exported(&dir, "u.abc", &sample_groom());
        bytes[5] = 0;
        let text = assert_clean_error(Path::new("u.abc"), &bytes);
        assert!(
            text.contains("offset 5") && text.contains("not frozen"),
            "{text}"
        );
    }

    #[test]
    fn not_alembic_is_refused() {
        let text = assert_clean_error(Path::new("x.abc"), b"\x89HDF\r\n\x1a\n........");
        assert!(text.contains("Ogawa"), "{text}");
    }

    #[test]
    fn points_that_do_not_match_n_vertices_are_reported_with_their_path() {
        let dir = TempDir::new("mismatch");
        let groom = sample_groom();
        let mut bytes = exported(&dir, "m.abc", &groom);
        // nVertices [3, 2] is stored as the i32 bytes 3,0,0,0,2,0,0,0 after
        // its digest: make it [3, 3].
        let needle = [3u8, 0, 0, 0, 2, 0, 0, 0];
        let at = bytes.windows(8).position(|w| w == needle).unwrap();
        bytes[at + 4] = 3;
        let text = assert_clean_error(Path::new("m.abc"), &bytes);
        assert!(text.contains("/groom/curves/.geom/P"), "{text}");
        assert!(text.contains("nVertices adds up to 6"), "{text}");
    }
}
