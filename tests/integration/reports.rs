//! What a TD reads in the reports: plots sampled every frame with the bond
//! kinds told apart, the set kept after each stage, links relative to the
//! page, and a merged batch page with the jobs' time and grooms.

use crate::util::{sample, TestDir};
use serde_json::Value;

/// bed_hair with 20 of its strands (0.2 + 3.0 + 1.0 + 0.5 s of stages).
fn bed_hair(dir: &TestDir) {
    let timeline = std::fs::read_to_string(sample("bed_hair.toml")).unwrap();
    assert!(timeline.contains("strands = 200,"));
    std::fs::write(
        dir.path("t.toml"),
        timeline.replace("strands = 200,", "strands = 20,"),
    )
    .unwrap();
}

/// bed_hair on a 4-strand swatch file.
fn bed_hair_on_a_swatch(dir: &TestDir) {
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "g.usda",
        "--strands",
        "4",
        "--length",
        "0.1",
    ]);
    let timeline = std::fs::read_to_string(sample("bed_hair.toml"))
        .unwrap()
        .replace("generate = {", "source = \"g.usda\" # {");
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
}

#[test]
fn bake_page_plots_every_frame_and_says_the_set_kept() {
    let dir = TestDir::new();
    bed_hair(&dir);
    std::fs::create_dir(dir.path("review")).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "review/r.html"]);
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let html = std::fs::read_to_string(dir.path("review/r.html")).unwrap();
    let json: Value = serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();

    // One point per frame (24 a second) and per stage end, not five.
    let simulated = json["simulated_seconds"].as_f64().unwrap();
    let first = html.split("<polyline").nth(1).unwrap();
    let points = first
        .split("points=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap();
    let count = points.split(' ').count();
    assert!(
        count as f64 >= simulated * 24.0,
        "{count} points for {simulated} s"
    );
    // The four bond kinds have four line styles: solid and three dashes.
    let start = html.find("Mean bond rate per kind").unwrap();
    let bond_plot = &html[start..];
    let bond_plot = &bond_plot[..bond_plot.find("</svg>").unwrap()];
    for dash in [
        "stroke-dasharray=\"7 4\"",
        "stroke-dasharray=\"2 3\"",
        "stroke-dasharray=\"9 3 2 3\"",
    ] {
        assert_eq!(
            bond_plot.matches(dash).count(),
            2,
            "{dash}: the curve and its legend"
        );
    }

    // Set kept per stage, in JSON and HTML: nothing kept while pressed wet,
    // some after drying under the pillow.
    let kept: Vec<Option<f64>> = json["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["set_kept"].as_f64())
        .collect();
    assert_eq!(kept.len(), 4);
    let dry = kept[2].expect("the hair moved by the end of the dry stage");
    let release = kept[3].expect("and after the release");
    assert!(dry > 0.05 && dry <= 1.0, "{kept:?}");
    assert!(release > 0.05 && release <= 1.0, "{kept:?}");
    assert!(html.contains("<th>set kept</th>"));
    assert!(
        html.contains(&format!("{:.0} %", dry * 100.0)),
        "the dry stage's share"
    );

    // Outputs link relative to the page's folder.
    for output in json["outputs"].as_array().unwrap() {
        let path = output["path"].as_str().unwrap();
        let href = format!("../{}", path.trim_start_matches("./"));
        assert!(
            html.contains(&format!("<a href=\"{href}\">{path}</a>")),
            "{path}"
        );
    }
}

#[test]
fn merged_batch_page_shows_the_jobs_time_and_grooms() {
    let dir = TestDir::new();
    bed_hair_on_a_swatch(&dir);
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "h.usda",
        "--strands",
        "3",
        "--length",
        "0.1",
    ]);
    std::fs::write(
        dir.path("m.toml"),
        "[[glob]]\ntimeline = \"t.toml\"\ngrooms = \"*.usda\"\n",
    )
    .unwrap();
    dir.run_ok(&["batch", "m.toml", "-q"]);
    dir.run_ok(&["batch", "m.toml", "--merge", "-q"]);
    let html = std::fs::read_to_string(dir.path("batch_out/batch_report.html")).unwrap();
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path("batch_out/batch_report.json")).unwrap())
            .unwrap();
    let jobs: f64 = report["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["wall_seconds"].as_f64().unwrap())
        .sum();
    assert!(jobs > 0.05, "{jobs}");
    assert!(
        html.contains(&format!("jobs took {jobs:.1} s in all")),
        "{html}"
    );
    for groom in ["g.usda", "h.usda"] {
        assert!(
            html.contains("<br>groom ") && html.contains(groom),
            "{groom}"
        );
    }
    assert!(
        html.contains("<a href=\"t-g/"),
        "outputs link into the job folders"
    );
}
