//! Issue 2's round trip over every format pair: a groom with strands of
//! different lengths, a per-vertex `width` and a per-strand `root_uv` is
//! written to every format, read back, written to every other format and
//! read back again. Counts and points must survive everywhere (to f32
//! precision after the unit conversions each format makes), and each
//! attribute wherever both formats of the pair can hold it.

use crate::util::{hand_to_validators, TestDir};
use groom::{Attribute, AttributeValues, Groom, Units, UpAxis};
use serde_json::json;
use std::path::Path;

const FORMATS: [&str; 8] = ["hair", "data", "obj", "glb", "gltf", "usda", "usdc", "abc"];

/// Formats that cannot record units: a file of them written in anything but
/// the centimetres their reader assumes reads back only with `--source-units`
/// (the writer warns). Every other format reads back in the units written.
const UNRECORDED: [&str; 2] = ["hair", "data"];

/// The units a test writes files in: `None` for each format's default (no
/// `--units`), as `convert` and the bake choose them.
const EXPORT_UNITS: [Option<Units>; 3] = [Some(Units::CENTIMETERS), Some(Units::METERS), None];

/// The formats that hold each attribute of the test groom.
fn holds(format: &str, attribute: &str) -> bool {
    match attribute {
        "width" => matches!(format, "hair" | "glb" | "gltf" | "usda" | "usdc" | "abc"),
        "root_uv" => matches!(format, "glb" | "gltf" | "usda" | "usdc" | "abc"),
        _ => false,
    }
}

/// Five strands of 2 to 9 points, in centimetres, Y up, with coordinates
/// that are not round in binary or decimal.
fn test_groom() -> Groom {
    let lengths = [2usize, 5, 9, 3, 7];
    let strands: Vec<Vec<[f32; 3]>> = lengths
        .iter()
        .enumerate()
        .map(|(s, &n)| {
            let root = [
                -4.3 + 2.17 * s as f32,
                160.0 + 0.731 * s as f32,
                -1.9 + 0.37 * (s * s) as f32,
            ];
            (0..n)
                .map(|i| {
                    let t = i as f32;
                    [
                        root[0] + 0.113 * t * t,
                        root[1] - 1.37 * t,
                        root[2] + 0.29 * t.sin() + 0.001 * s as f32,
                    ]
                })
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands);
    groom.units = Units::CENTIMETERS;
    groom.up_axis = UpAxis::Y;
    let vertices = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(
            (0..vertices)
                .map(|i| 0.0081 - 0.0002 * (i % 11) as f32)
                .collect(),
        ),
    ));
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(
            (0..lengths.len())
                .map(|s| [0.125 + 0.17 * s as f32, 0.9 - 0.21 * s as f32])
                .collect(),
        ),
    ));
    groom
}

/// Writes `groom` as `convert` would: in `units`, else the format's default.
/// Returns the units the file holds.
fn write_as_convert(path: &Path, groom: &Groom, units: Option<Units>) -> Units {
    let units = units.unwrap_or_else(|| exporters::default_units(path, groom.units));
    let mut out = groom.clone();
    out.convert_to(units, out.up_axis);
    exporters::write(path, &out).unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
    exporters::file_units(path, units)
}

/// Reads a file of format `ext` written in `written_in` units by the units
/// rule, stating the units only where the format cannot record them and
/// they are not its convention (what the writer's warning asks for).
fn read_by_rule(path: &Path, ext: &str, written_in: Units) -> Groom {
    let mut groom =
        importers::read(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    if UNRECORDED.contains(&ext) {
        assert_eq!(
            exporters::units_warning(path, written_in).is_some(),
            written_in != Units::CENTIMETERS,
            "{}: the writer warns exactly when the units do not read back",
            path.display()
        );
        groom.units = written_in;
    } else {
        assert_eq!(
            groom.units,
            written_in,
            "{}: read back in other units ({})",
            path.display(),
            groom.provenance.units_source
        );
    }
    groom
}

/// In the test groom's centimetres, Y up.
fn normalised(groom: &Groom) -> Groom {
    let mut groom = groom.clone();
    groom.convert_to(Units::CENTIMETERS, UpAxis::Y);
    groom
}

/// Whether `got` is `want` to a few f32 ulps of relative error (each unit
/// conversion rounds once; a round trip through two formats makes several).
fn close(got: f32, want: f32, floor: f32) -> bool {
    (got - want).abs() <= 16.0 * f32::EPSILON * want.abs().max(floor)
}

fn check(original: &Groom, back: &Groom, attributes: &[&str], context: &str) {
    assert_eq!(
        back.strand_vertex_counts, original.strand_vertex_counts,
        "{context}: strand vertex counts"
    );
    assert_eq!(back.points.len(), original.points.len(), "{context}");
    assert_eq!(back.basis, original.basis, "{context}: basis");
    assert!(back.frames.is_empty(), "{context}: frames appeared");
    for (i, (got, want)) in back.points.iter().zip(&original.points).enumerate() {
        assert!(
            (0..3).all(|k| close(got[k], want[k], 1.0)),
            "{context}: point {i} is {got:?}, expected {want:?}"
        );
    }
    for &name in attributes {
        let want = original.attribute(name).unwrap();
        let got = back
            .attribute(name)
            .unwrap_or_else(|| panic!("{context}: attribute {name} lost"));
        assert_eq!(got.scope, want.scope, "{context}: scope of {name}");
        let (got_values, want_values) = (got.values.to_f32_flat(), want.values.to_f32_flat());
        assert_eq!(
            got.values.type_name(),
            want.values.type_name(),
            "{context}: type of {name}"
        );
        assert_eq!(got_values.len(), want_values.len(), "{context}: {name}");
        for (i, (&g, &w)) in got_values.iter().zip(&want_values).enumerate() {
            // Widths are tiny: compare them relative to themselves.
            assert!(
                close(g, w, f32::MIN_POSITIVE),
                "{context}: {name} value {i} is {g}, expected {w}"
            );
        }
    }
}

/// What the validator of `ext` must find in a file holding the test groom;
/// `None` for the formats no validator checks.
fn expectation(
    ext: &str,
    groom: &Groom,
    units: Units,
    widths: bool,
    root_uv: bool,
) -> Option<serde_json::Value> {
    let strands = groom.strand_count();
    let vertices = groom.vertex_count();
    match ext {
        "glb" | "gltf" => Some(json!({"kind": "gltf", "primitives": 1, "vertices": vertices})),
        "usda" | "usdc" => {
            let mut expect = json!({
                "curves": strands,
                "points": vertices,
                "basis": "linear",
                "up_axis": "Y",
                "meters_per_unit": units.meters_per_unit,
            });
            if widths {
                expect["widths"] = json!("vertex");
            }
            if root_uv {
                expect["primvars"] = json!({"st": "uniform"});
            }
            Some(expect)
        }
        "abc" => {
            let mut expect = json!({
                "kind": "abc",
                "curves": strands,
                "points": vertices,
                "samples": 1,
                "basis": "linear",
            });
            if widths {
                expect["width"] = json!("vertex");
            }
            Some(expect)
        }
        _ => None,
    }
}

#[test]
fn every_format_pair_round_trips_points_and_attributes_at_m_and_cm() {
    let dir = TestDir::new();
    let original = test_groom();
    assert!(original.validate().iter().all(|p| !p.is_fatal()));
    for export_units in EXPORT_UNITS {
        let units_label = export_units.map_or("default".to_string(), |u| u.name());
        for a in FORMATS {
            let first = dir.path(&format!("first_{units_label}.{a}"));
            let written = write_as_convert(&first, &original, export_units);
            // As read, in the file's own units: what the next writer gets.
            let through_a = read_by_rule(&first, a, written);
            let kept: Vec<&str> = ["width", "root_uv"]
                .into_iter()
                .filter(|name| holds(a, name))
                .collect();
            check(
                &original,
                &normalised(&through_a),
                &kept,
                &format!("{a} in {units_label}"),
            );

            for b in FORMATS.into_iter().filter(|&b| b != a) {
                let context = format!("{a} -> {b} in {units_label}");
                let second = dir.path(&format!("{a}_to_{b}_{units_label}.{b}"));
                let written = write_as_convert(&second, &through_a, export_units);
                let back = read_by_rule(&second, b, written);
                let both: Vec<&str> = kept.iter().copied().filter(|n| holds(b, n)).collect();
                check(&original, &normalised(&back), &both, &context);
                // A few of the second-generation files, for the external validators.
                let handed = matches!(
                    (a, b),
                    ("gltf", "abc")
                        | ("abc", "usda")
                        | ("usdc", "glb")
                        | ("hair", "usdc")
                        | ("usda", "gltf")
                );
                if handed && export_units.is_none() {
                    let has = |n: &str| both.contains(&n);
                    if let Some(expect) =
                        expectation(b, &original, written, has("width"), has("root_uv"))
                    {
                        hand_to_validators(&second, &format!("roundtrip_{a}_to_{b}"), expect);
                    }
                }
            }
        }
    }
}

/// The Alembic units acceptance: the same groom written with `units = "m"`
/// and `"cm"` holds points that differ by exactly 100x (checked again by
/// alembic3d in CI), and each reads back in the units it was written in.
#[test]
fn alembic_in_metres_and_centimetres_differs_by_100x() {
    let dir = TestDir::new();
    let original = test_groom();
    let mut files = Vec::new();
    for units in [Units::METERS, Units::CENTIMETERS] {
        let path = dir.path(&format!("units_{}.abc", units.name()));
        write_as_convert(&path, &original, Some(units));
        let back = importers::read(&path).unwrap();
        assert_eq!(back.units, units);
        assert_eq!(back.provenance.units_source, "file");
        let mut expect = expectation("abc", &original, units, true, true).unwrap();
        if units == Units::METERS {
            expect["scaled"] = json!({"of": "units_cm.abc", "by": 0.01});
        }
        hand_to_validators(&path, &format!("units_{}", units.name()), expect);
        files.push(back);
    }
    let (metres, centimetres) = (&files[0], &files[1]);
    for (m, cm) in metres.points.iter().zip(&centimetres.points) {
        for k in 0..3 {
            let ratio = cm[k] / m[k];
            assert!(
                (ratio - 100.0).abs() <= 100.0 * 4.0 * f32::EPSILON,
                "cm {} / m {} = {ratio}",
                cm[k],
                m[k]
            );
        }
    }
}

/// `.hair` cannot record metres: `convert --units m` warns on stderr with
/// the flag that reads it back; `--strict` refuses (exit 2) and writes nothing.
#[test]
fn unrecordable_units_warn_and_strict_refuses() {
    let dir = TestDir::new();
    exporters::write(&dir.path("in.usda"), &test_groom()).unwrap();
    let output = dir.run_ok(&["convert", "in.usda", "m.hair", "--units", "m"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    // One line per kind: the units, and root_uv, which .hair cannot hold.
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 2, "{stderr}");
    assert!(
        lines.iter().all(|l| l.starts_with("groombake: warning: ")),
        "{stderr}"
    );
    assert!(lines[0].contains("--source-units m"), "{stderr}");
    assert!(lines[1].contains("root_uv: dropped"), "{stderr}");
    let message = dir.run_fail(
        &[
            "convert",
            "in.usda",
            "strict.hair",
            "--units",
            "m",
            "--strict",
        ],
        2,
    );
    assert!(message.contains("--strict"), "{message}");
    assert!(!dir.path("strict.hair").exists());
    // The default (centimetres) needs no units warning.
    let output = dir.run_ok(&["convert", "in.usda", "cm.hair"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("--source-units"), "{stderr}");
    // A file that can hold it all needs no warning at all.
    let output = dir.run_ok(&["convert", "in.usda", "same.usdc", "--strict"]);
    assert!(output.stderr.is_empty());
}

/// A bake's static export in units its format cannot record warns in the
/// report (and on stderr); `bake --strict` refuses before simulating and
/// writes nothing. A `.hair` export by default is centimetres and reads back
/// as the bake's groom, with no warning.
#[test]
fn bake_exports_follow_the_units_rule_and_strict_refuses() {
    let dir = TestDir::new();
    let timeline = r#"
seed = 1
[groom]
generate = { layout = "swatch", strands = 2, length = 0.06, segment_length = 0.02, swatch_width = 0.02, head_center = [0.0, 0.30, 0.0] }
[[stage]]
kind = "settle"
duration = 0.01
[[export]]
path = "final.hair"
what = "final"
[[export]]
path = "final_m.data"
what = "final"
units = "m"
[[export]]
path = "final.usda"
what = "final"
"#;
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    let message = dir.run_fail(&["bake", "t.toml", "--strict", "-q"], 2);
    assert!(message.contains("t.toml: --strict: "), "{message}");
    assert!(!dir.path("final.hair").exists() && !dir.path("final.usda").exists());

    dir.run_ok(&["bake", "t.toml", "-q", "--report", "report.json"]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("report.json")).unwrap()).unwrap();
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("--source-units m")),
        "{report}"
    );
    assert!(
        !warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("final.hair: written")),
        "{report}"
    );
    // The .hair (cm by default) and the .usda (metres) hold the same groom.
    let hair = normalised(&importers::read(&dir.path("final.hair")).unwrap());
    let usd = normalised(&importers::read(&dir.path("final.usda")).unwrap());
    assert_eq!(hair.units, usd.units);
    for (a, b) in hair.points.iter().zip(&usd.points) {
        assert!((0..3).all(|k| close(a[k], b[k], 1.0)), "{a:?} vs {b:?}");
    }
}
