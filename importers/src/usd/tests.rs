use super::*;
use groom::{Attribute, AttributeValues, CurveBasis, Frame, Groom, Scope, Units, UpAxis};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// A file of the workspace's `tests/data/` (real grooms from other tools).
fn workspace_data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data")).join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("groombake-usd-import-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn values(groom: &Groom, name: &str) -> AttributeValues {
    groom
        .attribute(name)
        .unwrap_or_else(|| panic!("no attribute {name}"))
        .values
        .clone()
}

#[test]
fn blender_hair_usda() {
    let groom = read(&workspace_data("blender501_hair.usda")).unwrap();
    assert_eq!(groom.strand_vertex_counts, vec![3, 4, 5, 4, 4]);
    assert_eq!(groom.vertex_count(), 20);
    assert_eq!(groom.units, Units::METERS);
    assert_eq!(groom.up_axis, UpAxis::Z);
    // The Hair Xform translates by (0, 0, 1); Poly has no transform.
    assert_eq!(groom.points[0], [0.0, 0.0, 1.0]);
    assert_eq!(groom.points[11], [0.2, 0.0, 1.4]);
    assert_eq!(groom.points[12], [1.0, 0.0, 0.0]);
    assert_eq!(groom.points[19], [1.1, 0.0, 0.3]);
    assert_eq!(groom.basis, CurveBasis::CatmullRom);
    assert_eq!(
        values(&groom, "group_id"),
        AttributeValues::Int(vec![0, 0, 0, 1, 1])
    );
    assert_eq!(
        values(&groom, "curve_basis"),
        AttributeValues::Int(vec![3, 3, 3, 0, 0])
    );
    let mut widths = vec![0.02; 12];
    widths.extend([2.0; 8]);
    assert_eq!(values(&groom, "width"), AttributeValues::Float(widths));
    // Only Poly has tilt; Hair's strands get zeros.
    assert_eq!(
        values(&groom, "tilt"),
        AttributeValues::Float(vec![0.0; 20])
    );
    assert!(groom.validate().is_empty());
}

#[test]
fn blender_hair_as_crate_reads_like_the_text() {
    let text = read(&workspace_data("blender501_hair.usda")).unwrap();
    let mut binary = read(&data("blender501_hair_by_usd_core.usdc")).unwrap();
    binary.provenance.source = text.provenance.source.clone();
    assert_eq!(binary, text);
}

/// A file written by usd-core (the reference implementation), read back
/// against the world-space values usd-core computes for it: compressed
/// int and float arrays, LZ4 with matches, orient/rotate/scale/matrix ops
/// through two Xforms, indexed and constant primvars, time samples.
#[test]
fn reference_files_match_usd_core() {
    let expected: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data("reference.json")).unwrap()).unwrap();
    for name in ["reference.usdc", "reference.usda"] {
        let groom = read(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(groom.units.meters_per_unit, 0.01, "{name}");
        assert_eq!(groom.up_axis, UpAxis::Z, "{name}");
        let curves = &expected["prims"][0];
        let other = &expected["prims"][1];
        let as_f32 = |v: &serde_json::Value| v.as_f64().unwrap() as f32;
        let points = |v: &serde_json::Value| -> Vec<[f32; 3]> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|p| [as_f32(&p[0]), as_f32(&p[1]), as_f32(&p[2])])
                .collect()
        };
        let close = |a: &[[f32; 3]], b: &[[f32; 3]]| {
            assert_eq!(a.len(), b.len(), "{name}");
            for (p, q) in a.iter().zip(b) {
                for k in 0..3 {
                    assert!((p[k] - q[k]).abs() < 1e-5, "{name}: {p:?} vs {q:?}");
                }
            }
        };
        let mut all = points(&curves["points"]);
        all.extend(points(&other["points"]));
        close(&groom.points, &all);
        assert_eq!(groom.strand_count(), 21, "{name}");
        assert_eq!(groom.frames.len(), 3, "{name}");
        for (frame, sample) in groom
            .frames
            .iter()
            .zip(curves["samples"].as_array().unwrap())
        {
            assert_eq!(frame.time, sample[0].as_f64().unwrap() / 30.0, "{name}");
            let mut expected_points = points(&sample[1]);
            expected_points.extend(points(&other["points"]));
            close(&frame.points, &expected_points);
        }
        let floats = |v: &serde_json::Value| -> Vec<f32> {
            v.as_array().unwrap().iter().map(as_f32).collect()
        };
        let mut widths = floats(&curves["widths"]);
        widths.extend([0.0; 4]);
        assert_eq!(
            values(&groom, "width"),
            AttributeValues::Float(widths),
            "{name}"
        );
        let mut wetness = floats(&curves["primvars"]["wetness"]);
        wetness.extend([0.0; 4]);
        assert_eq!(
            values(&groom, "wetness"),
            AttributeValues::Float(wetness),
            "{name}"
        );
        let mut clump: Vec<i32> = curves["primvars"]["clump"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_i64().unwrap() as i32)
            .collect();
        clump.push(0);
        assert_eq!(
            values(&groom, "clump"),
            AttributeValues::Int(clump),
            "{name}"
        );
        let mut level = floats(&curves["primvars"]["level"]);
        level.push(0.0);
        assert_eq!(
            values(&groom, "level"),
            AttributeValues::Float(level),
            "{name}"
        );
        let uv = values(&groom, "root_uv");
        let AttributeValues::Vec2(uv) = uv else {
            panic!("root_uv is not vec2")
        };
        assert_eq!(uv[3], [0.15, 0.85], "{name}");
        let tint = groom.attribute("tint").unwrap();
        assert_eq!(tint.scope, Scope::Strand);
        assert_eq!(tint.values.len(), 21);
        assert_eq!(groom.basis, CurveBasis::Bspline, "{name}");
        assert!(groom.attribute("pair").is_none(), "{name}");
        assert!(
            groom
                .provenance
                .losses
                .iter()
                .any(|l| l.contains("primvars:pair: elementSize 2")),
            "{name}"
        );
        let mut groups = vec![0; 20];
        groups.push(1);
        assert_eq!(
            values(&groom, "group_id"),
            AttributeValues::Int(groups),
            "{name}"
        );
        assert!(groom.validate().is_empty(), "{name}");
    }
}

fn sample_groom() -> Groom {
    let mut groom = Groom::from_strands([
        vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.1, 2.0, 0.5]],
        vec![
            [1.0, 0.0, 0.0],
            [1.0, 1.5, 0.0],
            [1.0, 1.75, -0.25],
            [1.0, 2.0, -0.5],
        ],
    ]);
    groom.units = Units::CENTIMETERS;
    groom.up_axis = UpAxis::Z;
    groom.basis = CurveBasis::CatmullRom;
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(vec![0.1, 0.08, 0.05, 0.1, 0.07, 0.06, 0.05]),
    ));
    groom.set_attribute(Attribute::new(
        "wetness",
        AttributeValues::Float(vec![0.0, 0.5, 1.0, 0.25, 0.5, 0.75, 1.0]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(vec![[0.1, 0.2], [0.3, 0.4]]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "clump",
        AttributeValues::Int(vec![3, -4]),
    ));
    groom.set_attribute(Attribute::new(
        "rest_tangent",
        AttributeValues::Vec3(vec![[1.0 / 3.0, 2.0, 3.0]; 7]),
    ));
    groom
}

fn animated_groom(frames: usize) -> Groom {
    let mut groom = sample_groom();
    for i in 0..frames {
        let points = groom
            .points
            .iter()
            .map(|p| [p[0] + i as f32 * 0.1, p[1] - 1e-3 * i as f32, p[2]])
            .collect();
        groom.frames.push(Frame {
            time: i as f64 / 24.0,
            points,
            attributes: Vec::new(),
        });
    }
    groom
}

#[test]
fn round_trips_static_and_animated() {
    for ext in ["usda", "usdc", "usd"] {
        for groom in [sample_groom(), animated_groom(5)] {
            let path = scratch(&format!("round_trip_{}.{ext}", groom.frames.len()));
            exporters::write(&path, &groom).unwrap();
            let mut back = read(&path).unwrap();
            back.provenance = groom.provenance.clone();
            back.attributes.sort_by(|a, b| a.name.cmp(&b.name));
            let mut expected = groom.clone();
            expected.attributes.sort_by(|a, b| a.name.cmp(&b.name));
            assert_eq!(back, expected, "{}", path.display());
        }
    }
}

#[test]
fn exports_are_deterministic() {
    for ext in ["usda", "usdc"] {
        let a = scratch(&format!("det_a.{ext}"));
        let b = scratch(&format!("det_b.{ext}"));
        exporters::write(&a, &animated_groom(3)).unwrap();
        exporters::write(&b, &animated_groom(3)).unwrap();
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{ext}"
        );
    }
}

fn read_str(text: &str) -> Result<Groom, ImportError> {
    read_bytes(std::path::Path::new("bad.usda"), text.as_bytes())
}

fn error_text(text: &str) -> String {
    read_str(text)
        .expect_err("malformed input must fail")
        .to_string()
}

#[test]
fn malformed_usda_names_line_and_column() {
    let cases = [
        (
            "#usda 1.0\ndef BasisCurves Strands {}\n",
            "bad.usda:2:17: expected the prim's name in quotes",
        ),
        (
            "#usda 1.0\ndef \"A\" {\n    point3f[] points = [(0, 0), (1, 1, 1)]\n}\n",
            "bad.usda:3:25: tuple has 2 numbers, expected 3",
        ),
        (
            "#usda 1.0\ndef \"A\" {\n    int[] curveVertexCounts = [1, x]\n}\n",
            "bad.usda:3:35: expected a number, found 'x'",
        ),
        (
            "#usda 1.0\ndef \"A\" {\n    int[] curveVertexCounts = [1, 2\n",
            "bad.usda:3:31: array never closed",
        ),
        (
            "#usda 1.0\ndef \"A\" {\n",
            "bad.usda:3:1: prim body never closed",
        ),
        ("#usda 2.0\n", "bad.usda:1:1: unsupported usda version"),
        (
            "#usda 1.0\n(\n    metersPerUnit = \"cm\"\n)\n",
            "bad.usda:3:5: metersPerUnit must be a number",
        ),
        (
            "#usda 1.0\ndef \"A\" {\n    string s = \"open\n}\n",
            "bad.usda:3:16: string without closing quote",
        ),
        (
            "#usda 1.0\ndef \"A\" { float f = 1 } $\n",
            "bad.usda:2:25: unexpected character '$'",
        ),
        (
            "#usda 1.0\ndef Xform \"A\" {}\n",
            "bad.usda: no BasisCurves prim",
        ),
    ];
    for (text, expected) in cases {
        let error = error_text(text);
        assert!(
            error.starts_with(expected),
            "got: {error}\nexpected: {expected}"
        );
    }
}

#[test]
fn malformed_curves_are_reported_with_their_place() {
    let counts = "#usda 1.0\ndef BasisCurves \"C\" {\n    int[] curveVertexCounts = [2, 2]\n    point3f[] points = [(0, 0, 0), (1, 1, 1), (2, 2, 2)]\n}\n";
    assert!(error_text(counts)
        .starts_with("bad.usda:4:5: points has 3 points but curveVertexCounts add up to 4"));
    let sized = "#usda 1.0\ndef BasisCurves \"C\" {\n    int[] curveVertexCounts = [2]\n    point3f[] points = [(0, 0, 0), (1, 1, 1)]\n    float[] primvars:pair = [1, 2, 3, 4] (interpolation = \"vertex\"\n        elementSize = 2)\n}\n";
    let groom = read_str(sized).unwrap();
    assert!(groom.attribute("pair").is_none());
    assert!(groom
        .provenance
        .losses
        .iter()
        .any(|l| l.contains("skipped primvars:pair: elementSize 2")));
    let widths = "#usda 1.0\ndef BasisCurves \"C\" {\n    int[] curveVertexCounts = [2]\n    point3f[] points = [(0, 0, 0), (1, 1, 1)]\n    float[] widths = [1, 2, 3] (interpolation = \"vertex\")\n}\n";
    assert!(error_text(widths)
        .starts_with("bad.usda:5:5: widths has 3 values but vertex interpolation needs 2"));
    let op = "#usda 1.0\ndef Xform \"X\" {\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n    def BasisCurves \"C\" {\n        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0), (1, 1, 1)]\n    }\n}\n";
    assert!(error_text(op)
        .starts_with("bad.usda:3:5: xformOpOrder names 'xformOp:translate', which the prim lacks"));
}

#[test]
fn transforms_compose_through_parents() {
    let text = r#"#usda 1.0
def Xform "A" {
    double3 xformOp:translate = (10, 0, 0)
    float xformOp:rotateZ = 90
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateZ"]
    def Xform "B" {
        matrix4d xformOp:transform = ( (2, 0, 0, 0), (0, 2, 0, 0), (0, 0, 2, 0), (0, 0, 1, 1) )
        float3 xformOp:scale:undo = (2, 2, 2)
        uniform token[] xformOpOrder = ["xformOp:transform", "!invert!xformOp:scale:undo"]
        def BasisCurves "C" {
            uniform token type = "linear"
            int[] curveVertexCounts = [2]
            point3f[] points = [(1, 0, 0), (0, 1, 0)]
        }
    }
}
"#;
    let groom = read_str(text).unwrap();
    // B: scale 1/2 then 2 = identity, then translate z by 1; A: rotate 90
    // about z, then translate x by 10.
    let expect = [[10.0, 1.0, 1.0], [9.0, 0.0, 1.0]];
    for (p, q) in groom.points.iter().zip(expect) {
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() < 1e-6, "{p:?} vs {q:?}");
        }
    }
    assert_eq!(groom.basis, CurveBasis::Linear);
}

#[test]
fn classes_overs_and_variants_are_not_curves() {
    let text = r#"#usda 1.0
class BasisCurves "Template" {
    int[] curveVertexCounts = [2]
    point3f[] points = [(0, 0, 0), (1, 1, 1)]
}
def Xform "A" (
    variants = { string v = "x" }
    prepend variantSets = "v"
)
{
    variantSet "v" = {
        "x" {
            def BasisCurves "InVariant" {
                int[] curveVertexCounts = [2]
                point3f[] points = [(0, 0, 0), (1, 1, 1)]
            }
        }
    }
    rel material:binding = </M>
    prepend rel proxyPrim = </P>
    reorder properties = ["b", "a"]
    custom float3 a.connect = </X.y>
    def BasisCurves "Real" {
        int[] curveVertexCounts = [3]
        point3f[] points = [(0, 0, 0), (1, 1, 1), (2, 2, 2)]
        point3f[] points.timeSamples = {
            2: [(0, 0, 0), (1, 1, 1), (2, 2, 3)],
            1: [(0, 0, 0), (1, 1, 1), (2, 2, 2.5)],
        }
    }
}
"#;
    let groom = read_str(text).unwrap();
    // usd-core would select variant "x"; this importer applies no variants
    // and says so.
    assert_eq!(groom.strand_vertex_counts, vec![3]);
    assert!(groom
        .provenance
        .info
        .contains("/A: variant set 'v' not applied"));
    assert!(groom.attribute("group_id").is_none());
    assert_eq!(
        groom.units,
        Units::CENTIMETERS,
        "USD's fallback metersPerUnit"
    );
    // Samples sorted by time code, 24 codes per second by default.
    let times: Vec<f64> = groom.frames.iter().map(|f| f.time).collect();
    assert_eq!(times, vec![1.0 / 24.0, 2.0 / 24.0]);
    assert_eq!(groom.frames[0].points[2], [2.0, 2.0, 2.5]);
    // Cubic bezier is the schema's fallback.
    assert_eq!(groom.basis, CurveBasis::Bezier);
}

#[test]
fn wrong_magic_is_rejected() {
    let error = read_bytes(std::path::Path::new("x.usd"), b"PK\x03\x04 not usd").unwrap_err();
    assert_eq!(
        error.to_string(),
        "x.usd:offset 0: not a USD file: it starts with neither `#usda` (text) nor `PXR-USDC` (crate)"
    );
}

/// Every prefix of a valid file fails cleanly or reads; none panics.
#[test]
fn cut_files_never_panic() {
    for name in ["reference.usdc", "reference.usda"] {
        let bytes = std::fs::read(data(name)).unwrap();
        let path = std::path::Path::new(name);
        // Every length near the ends (headers, sections, table of
        // contents), every seventh in between.
        let lengths = (0..bytes.len()).filter(|&n| n < 256 || n + 2048 > bytes.len() || n % 7 == 0);
        for length in lengths {
            let result = read_bytes(path, &bytes[..length]);
            if name.ends_with(".usdc") {
                // The table of contents is at the end: any cut loses it.
                let error = result.expect_err("cut crate file must fail").to_string();
                assert!(error.starts_with(name), "{error}");
            }
        }
    }
}

/// Each byte of a crate file overwritten with a few values: errors or
/// values, never a panic or a runaway allocation.
#[test]
fn corrupted_crate_bytes_never_panic() {
    let bytes = std::fs::read(data("reference.usdc")).unwrap();
    let path = std::path::Path::new("corrupt.usdc");
    let mut copy = bytes.clone();
    // Every byte of the bootstrap and the structural sections at the end,
    // every eleventh of the value data between.
    let indices = (0..bytes.len()).filter(|&i| i < 88 || i + 1536 > bytes.len() || i % 11 == 0);
    for index in indices {
        for value in [0x00, 0xff, bytes[index] ^ 0x10] {
            copy[index] = value;
            let _ = read_bytes(path, &copy);
        }
        copy[index] = bytes[index];
    }
}

#[test]
fn bad_crate_offsets_are_reported() {
    let mut bytes = std::fs::read(data("reference.usdc")).unwrap();
    bytes[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
    let error = read_bytes(std::path::Path::new("c.usdc"), &bytes)
        .unwrap_err()
        .to_string();
    assert!(error.starts_with("c.usdc:offset "), "{error}");
    assert!(error.contains("past the end of the file"), "{error}");

    let mut bytes = std::fs::read(data("reference.usdc")).unwrap();
    bytes[8] = 1;
    let error = read_bytes(std::path::Path::new("c.usdc"), &bytes)
        .unwrap_err()
        .to_string();
    assert_eq!(
        error,
        "c.usdc:offset 8: crate version 1.8.0 is not supported (0.4.0 to 0.x)"
    );
}

#[test]
fn lz4_and_integer_coding_reject_bad_input() {
    use super::crate_reader::{decode_ints, fast_decompress};
    // A match reaching before the start of the output.
    assert!(fast_decompress(&[0, 0x10, b'a', 0x05, 0x00], 100).is_err());
    // More output than allowed.
    assert!(fast_decompress(&[0, 0x50, 1, 2, 3, 4, 5], 4).is_err());
    // Literal run past the end.
    assert!(fast_decompress(&[0, 0x50, 1, 2], 100).is_err());
    // A valid match that copies overlapping bytes.
    assert_eq!(
        fast_decompress(&[0, 0x14, b'a', 0x01, 0x00, 0x00], 100).unwrap(),
        b"aaaaaaaaa".to_vec()
    );
    // Codes for 5 ints need 2 bytes after the 4-byte common value.
    assert!(decode_ints(&[0, 0, 0, 0, 0], 5, false).is_err());
    // Common value 1 for every delta: 1, 2, 3.
    assert_eq!(
        decode_ints(&[1, 0, 0, 0, 0], 3, false).unwrap(),
        vec![1, 2, 3]
    );
}

#[test]
fn element_kinds() {
    use super::ElementKind::*;
    assert_eq!(
        element_kind("point3f"),
        Some(Numbers {
            components: 3,
            single: true
        })
    );
    assert_eq!(
        element_kind("texCoord2d"),
        Some(Numbers {
            components: 2,
            single: false
        })
    );
    assert_eq!(
        element_kind("color4f"),
        Some(Numbers {
            components: 4,
            single: true
        })
    );
    assert_eq!(
        element_kind("matrix4d"),
        Some(Numbers {
            components: 16,
            single: false
        })
    );
    assert_eq!(element_kind("token"), Some(Text));
    assert_eq!(element_kind("point4f"), None);
    assert_eq!(element_kind("rel"), None);
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let depth = 5000;
    let mut text = String::from("#usda 1.0\n");
    for i in 0..depth {
        text.push_str(&format!("def \"P{i}\" {{\n"));
    }
    text.push_str(&"}\n".repeat(depth));
    let error = error_text(&text);
    assert!(error.contains("prims nested too deeply"), "{error}");

    let brackets = format!(
        "#usda 1.0\n(\n    customData = {}{}\n)\n",
        "{".repeat(depth),
        "}".repeat(depth)
    );
    let error = error_text(&brackets);
    assert!(error.contains("nested too deeply"), "{error}");
}

/// A USD fixture of the workspace's `tests/data/usd/`.
fn usd_fixture(name: &str) -> PathBuf {
    workspace_data("usd").join(name)
}

/// The crate copies usd-core wrote of the composed text fixtures (arcs in
/// the crate's list-op encodings: sublayers, external and internal
/// references, payloads, inherits, specializes, instancing) compose to the
/// same strands as the text fixtures.
#[test]
fn crate_layers_compose_like_their_text() {
    for (text, binary) in [
        ("reference_internal.usda", "reference_internal.usdc"),
        ("payload_main.usda", "payload_main.usdc"),
        ("payload_main.usda", "crate_payload_text.usdc"),
        ("sublayer_main.usda", "sublayer_main.usdc"),
        ("instancing.usda", "instancing.usdc"),
        ("inherits.usda", "inherits.usdc"),
    ] {
        let expected = read(&usd_fixture(text)).unwrap();
        let groom = read(&usd_fixture(binary)).unwrap_or_else(|e| panic!("{binary}: {e}"));
        assert_eq!(
            groom.strand_vertex_counts, expected.strand_vertex_counts,
            "{binary}"
        );
        assert_eq!(groom.points, expected.points, "{binary}");
        assert_eq!(
            groom.provenance.metadata.get(groom::PRIMS_KEY),
            expected.provenance.metadata.get(groom::PRIMS_KEY),
            "{binary}: the same composed prim paths"
        );
    }
}

/// Bad arcs in crate layers give the errors the text path gives: the arc
/// and the missing file, a cycle.
#[test]
fn bad_crate_arcs_are_named() {
    let missing = read(&usd_fixture("crate_missing_reference.usdc"))
        .unwrap_err()
        .to_string();
    assert!(
        missing.contains("crate_missing_reference.usdc:/Head: references @./not_here.usdc@</Hair>")
            && missing.contains("not_here.usdc: No such file"),
        "{missing}"
    );
    let cycle = read(&usd_fixture("crate_cycle_a.usdc"))
        .unwrap_err()
        .to_string();
    assert!(cycle.contains("(a cycle?)"), "{cycle}");
}

/// A list op claiming more items than the file holds is refused before
/// anything is allocated for them.
#[test]
fn crate_list_op_counts_are_bounded() {
    let path = usd_fixture("crate_missing_reference.usdc");
    let mut bytes = std::fs::read(&path).unwrap();
    // The reference list op: header byte (prepended items), then the count.
    let original = read_bytes(&path, &bytes).unwrap_err().to_string();
    assert!(original.contains("not_here.usdc"), "{original}");
    let count_at = bytes
        .windows(9)
        .position(|w| w[0] == 1 << 5 && w[1..] == 1u64.to_le_bytes())
        .expect("the prepended reference list");
    bytes[count_at + 1..count_at + 9].copy_from_slice(&u64::MAX.to_le_bytes());
    let message = read_bytes(&path, &bytes).unwrap_err().to_string();
    assert!(
        message.contains("list items do not fit in the file"),
        "{message}"
    );
}

/// A topology that changes over time is refused by `read` (the bake) with
/// the time it changes at, and read by `read_sequence` as one groom per
/// topology: counts held between samples, points interpolated where their
/// lengths agree, as usd-core evaluates them.
#[test]
fn time_varying_topology_reads_as_a_sequence() {
    let path = usd_fixture("time_sampled_counts_held.usda");
    let refusal = read(&path).unwrap_err().to_string();
    assert!(refusal.contains("topology changes at time 3"), "{refusal}");
    let sequence = read_sequence(&path).unwrap();
    assert_eq!(sequence.len(), 2);
    let (first, second) = (&sequence[0], &sequence[1]);
    assert_eq!(first.strand_vertex_counts, [2]);
    assert_eq!(second.strand_vertex_counts, [3]);
    let times: Vec<f64> = first.frames.iter().map(|f| f.time).collect();
    assert_eq!(times, [0.0, 1.0 / 24.0, 2.0 / 24.0]);
    // The Groom Xform translates by (0, 5, 0).
    let points: Vec<_> = first.frames.iter().map(|f| f.points.clone()).collect();
    assert_eq!(
        points,
        [
            vec![[0.0, 5.0, 0.0], [0.0, 6.0, 0.0]],
            vec![[0.0, 5.0, 0.0], [0.0, 7.0, 0.0]],
            vec![[0.0, 5.0, 0.0], [0.0, 8.0, 0.0]],
        ]
    );
    assert_eq!(first.points, points[0], "the rest pose is the first frame");
    assert_eq!(second.frames.len(), 1);
    assert_eq!(second.frames[0].time, 3.0 / 24.0);
    assert_eq!(second.points[2], [0.0, 7.0, 1.0]);
    // A file of one topology is one groom, as `read` gives it.
    let one = read_sequence(&usd_fixture("payload_main.usda")).unwrap();
    assert_eq!(one, vec![read(&usd_fixture("payload_main.usda")).unwrap()]);
}

/// An arc to a device is refused before anything is read from it.
#[test]
fn arcs_to_devices_are_refused() {
    let text =
        "#usda 1.0\ndef Xform \"Head\" (\n    prepend references = @/dev/zero@</Hair>\n)\n{\n}\n";
    let message = read_bytes(Path::new("device.usda"), text.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("device.usda:3:")
            && message.contains("references @/dev/zero@</Hair>: /dev/zero is not a regular file"),
        "{message}"
    );
}

/// Many samples of a changing topology over many prims are refused before
/// the stage is evaluated at each time code.
#[test]
fn changing_topology_work_is_bounded() {
    let mut text = String::from(
        "#usda 1.0\ndef BasisCurves \"C\"\n{\n    int[] curveVertexCounts.timeSamples = {\n",
    );
    for code in 0..10_001 {
        text.push_str(&format!("        {code}: [{}],\n", 2 + code % 2));
    }
    text.push_str("    }\n}\n");
    for prim in 0..10_001 {
        text.push_str(&format!("def \"P{prim}\"\n{{\n}}\n"));
    }
    let message = read_sequence_bytes(Path::new("many.usda"), text.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("10001 time codes of a changing topology over 10002 prims"),
        "{message}"
    );
}

/// A compressed integer array as the crate stores it (`u64` size, then
/// TfFastCompression: chunk count 0 and one LZ4 block) whose bytes decode
/// to `head`, `zeros` zero bytes and `tail`: a match of offset 1 repeats
/// the zero after `head`, 255 bytes for each length byte.
fn compressed_run(head: &[u8], zeros: usize, tail: &[u8]) -> Vec<u8> {
    assert!(head.len() < 15 && tail.len() < 15 && zeros >= 5);
    let mut block = vec![0u8];
    let literals = [head, &[0]].concat();
    let extra = zeros - 1 - 4;
    block.push(((literals.len() as u8) << 4) | extra.min(15) as u8);
    block.extend_from_slice(&literals);
    block.extend_from_slice(&[1, 0]);
    if extra >= 15 {
        let mut rest = extra - 15;
        while rest >= 255 {
            block.push(255);
            rest -= 255;
        }
        block.push(rest as u8);
    }
    block.push((tail.len() as u8) << 4);
    block.extend_from_slice(tail);
    let mut out = (block.len() as u64).to_le_bytes().to_vec();
    out.extend_from_slice(&block);
    out
}

/// A PATHS section of `entries` paths in one chain, /a/a/a/...: indexes
/// 0, 1, 2, ... (delta 1 coded as the common value), element token 0 and
/// jump -1 (a child, no sibling) for every entry. A few kilobytes hold
/// millions of entries.
fn chain_paths_section(entries: u64) -> Vec<u8> {
    let code_bytes = entries.div_ceil(4) as usize;
    let mut section = entries.to_le_bytes().to_vec();
    section.extend_from_slice(&entries.to_le_bytes());
    // First delta 0 (a 1-byte code), then the common value 1.
    section.extend(compressed_run(&[1, 0, 0, 0, 1], code_bytes - 1, &[0]));
    section.extend(compressed_run(&[0, 0, 0, 0], code_bytes, &[]));
    // First delta -1, then the common value 0.
    section.extend(compressed_run(&[0, 0, 0, 0, 1], code_bytes - 1, &[0xff]));
    section
}

/// `reference.usdc` with its PATHS section replaced by `section`, appended
/// after the table of contents.
fn with_paths_section(section: &[u8]) -> Vec<u8> {
    let mut bytes = std::fs::read(data("reference.usdc")).unwrap();
    let u64_at =
        |bytes: &[u8], at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    let toc = u64_at(&bytes, 16) as usize;
    let entry = (0..u64_at(&bytes, toc) as usize)
        .map(|i| toc + 8 + 32 * i)
        .find(|&at| bytes[at..at + 16].starts_with(b"PATHS\0"))
        .expect("a PATHS section");
    let start = bytes.len() as u64;
    bytes[entry + 16..entry + 24].copy_from_slice(&start.to_le_bytes());
    bytes[entry + 24..entry + 32].copy_from_slice(&(section.len() as u64).to_le_bytes());
    bytes.extend_from_slice(section);
    bytes
}

/// Regression: a PATHS section of a few kilobytes could claim about a
/// thousand path entries per byte (LZ4 and the integer coding compress a
/// regular table that far); the reader decoded them all and sized its path
/// table by the count, gigabytes for this 140 KB file. The decode budget
/// stops it before the integers are decoded.
#[test]
fn regression_compressed_path_count_is_bounded_by_the_file_before_decoding() {
    let entries = 40_000_000;
    let bytes = with_paths_section(&chain_paths_section(entries));
    assert!(bytes.len() < 200_000, "{} bytes", bytes.len());
    let error = read_bytes(std::path::Path::new("bomb.usdc"), &bytes)
        .unwrap_err()
        .to_string();
    assert!(error.starts_with("bomb.usdc:offset "), "{error}");
    assert!(
        error.contains("PATHS indexes: decoding would take more than 16 times the file's size"),
        "{error}"
    );
}

/// Regression: a count no compressed bytes could hold is refused before
/// anything is decoded.
#[test]
fn regression_compressed_count_beyond_its_bytes_is_refused() {
    let mut section = chain_paths_section(1000);
    let count = 1u64 << 40;
    section[..8].copy_from_slice(&count.to_le_bytes());
    section[8..16].copy_from_slice(&count.to_le_bytes());
    let bytes = with_paths_section(&section);
    let error = read_bytes(std::path::Path::new("count.usdc"), &bytes)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(&format!(
            "PATHS indexes: {count} integers cannot be coded in"
        )),
        "{error}"
    );
}

/// Regression: a chain of path entries, each the child of the one before,
/// made path texts whose total length grew with the square of the chain
/// (100,000 entries: gigabytes). The path tree's depth is bounded as the
/// text reader's nesting is.
#[test]
fn regression_path_chain_depth_is_bounded() {
    let bytes = with_paths_section(&chain_paths_section(100_000));
    let error = read_bytes(std::path::Path::new("chain.usdc"), &bytes)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("PATHS: the path tree is nested deeper than 256 at entry 257"),
        "{error}"
    );
    // 200 entries: not refused for its depth (but for its last entry,
    // which claims a child after the end of the table).
    let bytes = with_paths_section(&chain_paths_section(200));
    let error = read_bytes(std::path::Path::new("short.usdc"), &bytes)
        .unwrap_err()
        .to_string();
    assert!(
        error.ends_with("PATHS: entry 200 is out of range"),
        "{error}"
    );
}
