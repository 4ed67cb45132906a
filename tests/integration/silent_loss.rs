//! No silent loss in `convert`: the cases the round-trip fuzz kept
//! (`tests/roundtrip_fuzz.rs`). What a file holds that the groom cannot
//! keep is a one-line warning naming the file and what is lost, a refusal
//! (exit 2, no output) under `--strict`; a file with nothing readable as
//! hair is refused with a one-line error naming it. The glTF fixtures are
//! built per the glTF 2.0 specification by `tests/data/gltf/make_fixtures.py`.

use crate::util::{test_data, TestDir};

/// A fixture of `tests/data/gltf/` copied into the test's folder (a short
/// path keeps the whole warning within its 300 characters).
fn fixture(dir: &TestDir, name: &str) -> String {
    std::fs::copy(test_data(&format!("gltf/{name}")), dir.path(name)).unwrap();
    name.to_string()
}

/// One stderr line, with `groombake:` and the file's name on it.
fn assert_one_line_naming(stderr: &str, file: &str) {
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("groombake: "), "{stderr}");
    assert!(stderr.contains(file), "{stderr}");
    assert!(stderr.trim_end().chars().count() <= 300, "{stderr}");
}

const OUTPUTS: [&str; 8] = [
    "out.gltf", "out.glb", "out.usda", "out.usdc", "out.abc", "out.hair", "out.data", "out.obj",
];

#[test]
fn an_obj_with_no_curves_is_refused_for_every_output_format() {
    // Found by the fuzz as truncated .obj files: convert wrote an empty
    // .abc/.usd/.hair (exit 0) and failed late for glTF ("cannot export:
    // the groom has no points", exit 1).
    let dir = TestDir::new();
    std::fs::write(dir.path("empty.obj"), "# written by hand: no curves\n").unwrap();
    std::fs::write(dir.path("zero.obj"), "").unwrap();
    for input in ["empty.obj", "zero.obj"] {
        for output in OUTPUTS {
            let stderr = dir.run_fail(&["convert", input, output], 2);
            assert_one_line_naming(&stderr, input);
            assert!(stderr.contains("no strands"), "{stderr}");
            assert!(!dir.path(output).exists(), "{input} -> {output}: an output");
        }
        let stderr = dir.run_fail(&["inspect", input], 2);
        assert_one_line_naming(&stderr, input);
    }
}

#[test]
fn a_gltf_animation_channel_groombake_does_not_read_is_warned_and_strict_refuses_it() {
    // A `translation` channel and a KHR_animation_pointer channel (no
    // `target.node`, which the JSON types refused as "missing field node").
    let dir = TestDir::new();
    let input = fixture(&dir, "strand_translation_animation.gltf");
    let input = input.as_str();
    let output = dir.run_ok(&["convert", input, "out.usda"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_one_line_naming(&stderr, "strand_translation_animation.gltf");
    assert!(stderr.contains("warning:"), "{stderr}");
    assert!(
        stderr.contains("2 animation channel(s) not read"),
        "{stderr}"
    );
    assert!(
        stderr.contains("/animations/0/channels/0 (translation of node 0)"),
        "{stderr}"
    );
    assert!(
        stderr.contains("/animations/0/channels/1 (pointer"),
        "{stderr}"
    );
    // The strand itself is kept.
    assert_eq!(dir.inspect("out.usda")["strands"], 1);
    let stderr = dir.run_fail(&["convert", "--strict", input, "strict.usda"], 2);
    assert_one_line_naming(&stderr, "strand_translation_animation.gltf");
    assert!(stderr.contains("--strict"), "{stderr}");
    assert!(!dir.path("strict.usda").exists());
    // inspect shows the same warning.
    let output = dir.run_ok(&["inspect", input]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("animation channel(s) not read"), "{stderr}");
}

#[test]
fn a_triangles_only_gltf_read_as_a_groom_is_refused_and_a_head_beside_strands_is_warned() {
    let dir = TestDir::new();
    // Only a quantized TRIANGLES primitive (KHR_mesh_quantization): no
    // curves, and no triangles groombake decodes either; it read as
    // "0 strands" (exit 0).
    let quantized = fixture(&dir, "quantized_triangles.gltf");
    let quantized = quantized.as_str();
    for output in ["out.usda", "out.glb"] {
        let stderr = dir.run_fail(&["convert", quantized, output], 2);
        assert_one_line_naming(&stderr, "quantized_triangles.gltf");
        assert!(stderr.contains("no strands"), "{stderr}");
        assert!(
            stderr.contains("/meshes/0/primitives/0 (TRIANGLES)"),
            "{stderr}"
        );
        assert!(!dir.path(output).exists());
    }
    let stderr = dir.run_fail(&["inspect", quantized], 2);
    assert_one_line_naming(&stderr, "quantized_triangles.gltf");
    // A strand beside a head mesh: the strand is converted, the mesh is
    // named as not read.
    let mixed = fixture(&dir, "strand_and_head_triangle.gltf");
    let mixed = mixed.as_str();
    let output = dir.run_ok(&["convert", mixed, "mixed.usda"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_one_line_naming(&stderr, "strand_and_head_triangle.gltf");
    assert!(stderr.contains("1 primitive(s) not read"), "{stderr}");
    assert!(
        stderr.contains("/meshes/1/primitives/0 (TRIANGLES)"),
        "{stderr}"
    );
    assert_eq!(dir.inspect("mixed.usda")["strands"], 1);
    dir.run_fail(&["convert", "--strict", mixed, "strict.usda"], 2);
    assert!(!dir.path("strict.usda").exists());
}

#[test]
fn frames_dropped_by_a_static_format_are_refused_under_strict() {
    // The fuzz found `convert --strict animated.abc out.obj` writing the
    // base pose with exit 0: the warning was printed, never refused.
    let dir = TestDir::new();
    let animated = crate::preview::animated_swatch(&dir);
    let stderr = dir.run_fail(&["convert", "--strict", &animated, "still.obj"], 2);
    assert_one_line_naming(&stderr, "still.obj");
    assert!(stderr.contains("frames"), "{stderr}");
    assert!(!dir.path("still.obj").exists());
}

#[test]
fn a_point_that_overflows_in_the_output_units_is_bad_input() {
    // 3e38 cm is 3e39 mm, beyond float32: the exporter failed late
    // ("cannot export: point is not finite", exit 1) after the fuzz
    // flipped a bit of an Alembic file's points.
    let dir = TestDir::new();
    std::fs::write(
        dir.path("big.obj"),
        "v 0 0 0\nv 0 -1 0\nv 0 -2 3e38\nl 1 2 3\n",
    )
    .unwrap();
    let stderr = dir.run_fail(&["convert", "big.obj", "big.usda", "--units", "mm"], 2);
    assert_one_line_naming(&stderr, "big.obj");
    assert!(stderr.contains("32-bit floats"), "{stderr}");
    assert!(!dir.path("big.usda").exists());
}

/// A hand-written USD curves prim (USD's BasisCurves schema) carrying
/// `curve_basis` and `curve_wrap` primvars: groombake's own names for the
/// per-strand curve kind of grooms that mix kinds.
fn curves_with_kind_primvars(basis_codes: &str) -> String {
    format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\n\
         def BasisCurves \"Hair\"\n{{\n    uniform token type = \"linear\"\n\
         \x20   int[] curveVertexCounts = [4, 4]\n\
         \x20   point3f[] points = [(0, 0, 0), (0, -0.01, 0), (0, -0.02, 0), (0, -0.03, 0), \
         (0.01, 0, 0), (0.01, -0.01, 0), (0.01, -0.02, 0), (0.01, -0.03, 0)]\n\
         \x20   int[] primvars:curve_basis = [{basis_codes}] (\n        interpolation = \"uniform\"\n    )\n\
         \x20   float[] primvars:curve_wrap = [0, 1, 2, 3, 4, 5, 6, 7] (\n        interpolation = \"vertex\"\n    )\n}}\n"
    )
}

#[test]
fn curve_kind_attributes_round_trip_through_usd_unchanged() {
    // Found by the fuzz: an unknown curve_basis code became a prim named
    // `Strands_basis7`, which USD (and groombake) refuse to read back; a
    // curve_wrap that is no wrap code (per vertex, float) was dropped when
    // the strands were split by curve type; and that split read back with
    // a group_id the source never had.
    let dir = TestDir::new();
    for (name, codes) in [("known.usda", "0, 2"), ("unknown.usda", "7, 0")] {
        std::fs::write(dir.path(name), curves_with_kind_primvars(codes)).unwrap();
        for output in ["out.usda", "out.usdc"] {
            let convert = dir.run_ok(&["convert", name, output]);
            let stderr = String::from_utf8_lossy(&convert.stderr);
            assert!(stderr.is_empty(), "{name} -> {output}: {stderr}");
            let diff = dir.command().args(["diff", name, output]).output().unwrap();
            assert!(
                diff.status.success(),
                "{name} -> {output}: {}{}",
                String::from_utf8_lossy(&diff.stdout),
                String::from_utf8_lossy(&diff.stderr)
            );
        }
    }
}
