//! `inspect --json` gives the keys the README promises (`format`, `strands`,
//! `vertices`, `bounds`, `units`, `up_axis`, `frames`, `attributes`) for a
//! file of every format.

use crate::util::{test_data, TestDir};

/// The Bangs groom of the shared data (100 strands, 1165 points, cm).
const BANGS_STRANDS: u64 = 100;
const BANGS_VERTICES: u64 = 1165;

fn check_keys(summary: &serde_json::Value, file: &str) {
    for key in [
        "format",
        "strands",
        "vertices",
        "bounds",
        "units",
        "up_axis",
        "frames",
        "attributes",
    ] {
        assert!(
            summary.get(key).is_some(),
            "{file}: no key {key}: {summary}"
        );
    }
    assert!(
        summary["format"].as_str().is_some_and(|f| !f.is_empty()),
        "{file}"
    );
    assert!(summary["strands"].as_u64().is_some_and(|n| n > 0), "{file}");
    assert!(summary["vertices"].as_u64().is_some(), "{file}");
    assert!(summary["frames"].as_u64().is_some(), "{file}");
    assert!(summary["units"].as_str().is_some(), "{file}");
    assert!(
        matches!(summary["up_axis"].as_str(), Some("Y" | "Z")),
        "{file}: up_axis {}",
        summary["up_axis"]
    );
    for end in ["min", "max"] {
        let corner = summary["bounds"][end].as_array();
        assert!(
            corner.is_some_and(|c| c.len() == 3 && c.iter().all(|v| v.is_f64())),
            "{file}: bounds.{end} {}",
            summary["bounds"]
        );
    }
    let attributes = summary["attributes"].as_array();
    assert!(attributes.is_some(), "{file}: attributes is not a list");
    for attribute in attributes.into_iter().flatten() {
        for key in ["name", "scope", "type", "count"] {
            assert!(
                attribute.get(key).is_some(),
                "{file}: attribute without {key}"
            );
        }
    }
}

#[test]
fn inspect_json_has_the_promised_keys_for_every_format() {
    let dir = TestDir::new();
    let bangs = test_data("hairutil_Bangs_100.hair");
    let bangs = bangs.to_str().unwrap();
    // Formats no shared file is in: converted from the Bangs groom.
    for out in [
        "bangs.obj",
        "bangs.glb",
        "bangs.gltf",
        "bangs.usdc",
        "bangs.usd",
    ] {
        dir.run_ok(&["convert", bangs, out]);
    }
    let cases: Vec<(String, &str, &str)> = vec![
        (bangs.to_string(), "hair", "cm"),
        (
            test_data("hairutil_Bangs_100.data").display().to_string(),
            "data",
            "cm",
        ),
        // .obj is written in metres by default (what Blender reads).
        ("bangs.obj".into(), "obj", "m"),
        ("bangs.glb".into(), "gltf", "m"),
        ("bangs.gltf".into(), "gltf", "m"),
        ("bangs.usdc".into(), "usd", "cm"),
        ("bangs.usd".into(), "usd", "cm"),
        (
            test_data("hairutil_Bangs_100.abc").display().to_string(),
            "abc",
            "cm",
        ),
    ];
    for (file, format, units) in &cases {
        let summary = dir.inspect(file);
        check_keys(&summary, file);
        assert_eq!(summary["format"], *format, "{file}");
        assert_eq!(summary["units"], *units, "{file}");
        assert_eq!(summary["strands"], BANGS_STRANDS, "{file}");
        assert_eq!(summary["vertices"], BANGS_VERTICES, "{file}");
        assert_eq!(summary["up_axis"], "Y", "{file}");
        assert_eq!(summary["frames"], 0, "{file}");
        // Bounds hold the first point (in the file's own units).
        let first = summary["first_point"].as_array().unwrap();
        for (k, coordinate) in first.iter().enumerate() {
            let c = coordinate.as_f64().unwrap();
            let (lo, hi) = (
                summary["bounds"]["min"][k].as_f64().unwrap(),
                summary["bounds"]["max"][k].as_f64().unwrap(),
            );
            assert!(lo <= c && c <= hi, "{file}: first point outside the bounds");
        }
    }
    // A USD file another tool wrote (Blender), with its own strand count.
    let blender = test_data("blender501_hair.usda");
    let summary = dir.inspect(blender.to_str().unwrap());
    check_keys(&summary, "blender501_hair.usda");
    assert_eq!(summary["format"], "usd");
}

#[test]
fn inspect_json_counts_the_frames_of_animated_files() {
    let dir = TestDir::new();
    let groom = groom::Groom::from_strands([
        vec![[0.0, 1.0, 0.0], [0.0, 0.5, 0.1], [0.1, 0.0, 0.2]],
        vec![[1.0, 1.0, 0.0], [1.0, 0.4, 0.0]],
    ]);
    for ext in ["glb", "gltf", "usda", "usdc", "abc"] {
        let file = format!("animated.{ext}");
        let options = exporters::AnimationOptions {
            fps: 24.0,
            frame_count: 3,
        };
        let mut writer = exporters::animated(&dir.path(&file), &groom, options).unwrap();
        for index in 0..3 {
            let points = groom
                .points
                .iter()
                .map(|p| [p[0] + 0.1 * index as f32, p[1], p[2]])
                .collect();
            let frame = groom::Frame {
                time: index as f64 / 24.0,
                points,
                attributes: Vec::new(),
            };
            writer.write_frame(&frame).unwrap();
        }
        writer.finish().unwrap();
        let summary = dir.inspect(&file);
        check_keys(&summary, &file);
        assert_eq!(summary["frames"], 3, "{file}: {summary}");
        assert_eq!(summary["strands"], 2, "{file}");
        assert_eq!(summary["vertices"], 5, "{file}");
        // The bounds cover every frame: the last one moved 0.2 along x.
        let max_x = summary["bounds"]["max"][0].as_f64().unwrap();
        let scale = if summary["units"] == "m" { 0.01 } else { 1.0 };
        assert!(
            (max_x - 1.2 * scale).abs() < 1e-5 * scale.max(1.0),
            "{file}: {summary}"
        );
    }
}
