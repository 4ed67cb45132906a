//! Guide caches (`[[export]] cache = "guides"`, issue 38 item 4): the
//! simulated guides animated, the render hair once at rest with the guides
//! and weights it follows. The cache is a tenth of the full cache or less,
//! and interpolating the render hair from it gives the full cache's render
//! hair. The readers themselves (usd-core, the Alembic library) open the
//! files in `.ci/check_guide_cache.py`, from what these tests leave in
//! `GROOMBAKE_ARTIFACTS`.

use crate::util::{hand_to_validators, TestDir};
use groom::guides::{GROOM_CLOSEST_GUIDES, GROOM_GUIDE_WEIGHTS};
use groom::interpolate::{InterpolationOptions, RenderHair};
use groom::{AttributeValues, Groom};
use serde_json::json;
use std::path::Path;

const GUIDES: usize = 40;
/// 2 % of the strands are guides.
const RENDER: usize = 1960;
/// 5 s at 24 fps.
const FRAMES: usize = 121;

/// A scalp of guides with render hair grown between them, in a gusty wind
/// for 5 s, written as a full and as a guide cache to `extension`.
fn timeline(extension: &str) -> String {
    format!(
        r#"
seed = 3
[groom]
generate = {{ layout = "scalp", strands = {GUIDES}, length = 0.2, segment_length = 0.02, scalp_angle = 60.0, drape = 8.0 }}
render = {{ count = {RENDER}, seed = 5 }}
[[stage]]
kind = "wind"
duration = 5.0
wind = {{ direction = 178.0, fps = 24.0, head = {{ center = [0.0, 0.0, 0.0], radii = [0.082, 0.102, 0.092] }}, schedule = [ {{ frame = 1, v = 0.5 }}, {{ frame = 40, v = 0.8 }}, {{ frame = 80, v = 0.4 }} ] }}
[[export]]
path = "full.{extension}"
what = "animated"
fps = 24
[[export]]
path = "guides.{extension}"
what = "animated"
fps = 24
cache = "guides"
"#
    )
}

fn read(path: &Path) -> Groom {
    importers::read(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
}

fn vec3s(groom: &Groom, name: &str) -> Vec<[f32; 3]> {
    match &groom.attribute(name).map(|a| &a.values) {
        Some(AttributeValues::Vec3(v)) => v.clone(),
        _ => panic!("{name}: no per-strand vec3"),
    }
}

/// Bakes both caches to `extension`, checks the sizes and that the render
/// hair interpolated from the guide cache is the full cache's; returns the
/// bytes per vertex-frame of the full and the guide cache.
fn bake_and_compare(extension: &str) -> (f64, f64) {
    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), timeline(extension)).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let (full_path, cache_path) = (
        dir.path(&format!("full.{extension}")),
        dir.path(&format!("guides.{extension}")),
    );
    let full = read(&full_path);
    let cache = read(&cache_path);
    assert_eq!(full.strand_count(), GUIDES + RENDER);
    assert_eq!(cache.strand_count(), GUIDES + RENDER);
    assert_eq!(cache.frames.len(), FRAMES, "{extension}");
    assert_eq!(full.frames.len(), FRAMES, "{extension}");

    // Size: bytes per vertex-frame of each, and the ratio.
    let vertex_frames = (full.points.len() * FRAMES) as f64;
    let full_size = std::fs::metadata(&full_path).unwrap().len() as f64;
    let cache_size = std::fs::metadata(&cache_path).unwrap().len() as f64;
    let (full_b, cache_b) = (full_size / vertex_frames, cache_size / vertex_frames);
    eprintln!(
        "{extension}: full {full_size} B ({full_b:.2} B per vertex-frame), guide cache \
         {cache_size} B ({cache_b:.2} B), ratio {:.3}",
        cache_size / full_size
    );
    assert!(
        cache_size * 10.0 <= full_size,
        "{extension}: guide cache {cache_size} B is more than a tenth of the full {full_size} B"
    );

    // The guide cache: guides first (they move), render hair after (it
    // holds its rest pose at every frame).
    let flags = cache.guide_flags().expect("groom_guide");
    assert!(flags[..GUIDES].iter().all(|&g| g) && flags[GUIDES..].iter().all(|&g| !g));
    let guide_vertices = cache.strand_offsets()[GUIDES];
    let last = &cache.frames[FRAMES - 1].points;
    assert_ne!(
        cache.frames[0].points[..guide_vertices],
        last[..guide_vertices]
    );
    let render_rest = &cache.frames[0].points[guide_vertices..];
    for frame in &cache.frames {
        assert_eq!(&frame.points[guide_vertices..], render_rest);
    }
    // ... and the guides are the full cache's, frame by frame.
    for (a, b) in cache.frames.iter().zip(&full.frames) {
        assert_eq!(a.points[..guide_vertices], b.points[..guide_vertices]);
    }
    let closest = vec3s(&cache, GROOM_CLOSEST_GUIDES);
    let weights = vec3s(&cache, GROOM_GUIDE_WEIGHTS);
    for r in GUIDES..GUIDES + RENDER {
        assert!(closest[r]
            .iter()
            .all(|&g| g >= 0.0 && (g as usize) < GUIDES));
        assert!(weights[r].iter().all(|&w| (0.0..=1.0).contains(&w)));
        assert!((weights[r].iter().sum::<f32>() - 1.0).abs() < 1e-5);
    }

    // groombake's interpolation of the render hair from the cache: the
    // rest guides and render hair, the stored guides and weights.
    let mut guides = cache.subset(&(0..GUIDES).collect::<Vec<_>>());
    guides.points = cache.frames[0].points[..guide_vertices].to_vec();
    let render_counts = cache.strand_vertex_counts[GUIDES..].to_vec();
    let offsets = cache.strand_offsets();
    let roots: Vec<[f32; 3]> = (GUIDES..GUIDES + RENDER)
        .map(|s| cache.frames[0].points[offsets[s]])
        .collect();
    let hair = RenderHair::linked(
        &guides,
        &roots,
        closest[GUIDES..]
            .iter()
            .map(|c| c.map(|g| g as u32))
            .collect(),
        weights[GUIDES..].to_vec(),
        render_counts,
        InterpolationOptions::default(),
    )
    .with_detail(&guides, render_rest);
    let mut worst = 0.0f32;
    for (frame, want) in cache.frames.iter().zip(&full.frames) {
        let got = hair.points(
            &guides.strand_vertex_counts,
            &frame.points[..guide_vertices],
        );
        for (g, w) in got.iter().zip(&want.points[guide_vertices..]) {
            let d = (0..3).map(|c| (g[c] - w[c]).powi(2)).sum::<f32>().sqrt();
            worst = worst.max(d);
        }
    }
    // Metres, on 20 cm strands: a micrometre is float rounding.
    assert!(
        worst < 1e-6,
        "{extension}: render hair from the guide cache is {worst} m from the full cache's"
    );

    let label = format!("guide_cache_{extension}");
    let expect = |curves: usize, samples: usize| json!({"kind": extension, "curves": curves, "samples": samples});
    hand_to_validators(
        &full_path,
        &format!("{label}.full"),
        expect(GUIDES + RENDER, FRAMES),
    );
    hand_to_validators(
        &cache_path,
        &format!("{label}.cache"),
        expect(GUIDES + RENDER, FRAMES),
    );
    if let Some(artifacts) = std::env::var_os("GROOMBAKE_ARTIFACTS") {
        let spec = json!({
            "cache": format!("{label}.cache.{extension}"),
            "full": format!("{label}.full.{extension}"),
            "guides": GUIDES,
            "render": RENDER,
            "samples": FRAMES,
            "tolerance": 0.05,
        });
        std::fs::write(
            Path::new(&artifacts).join(format!("{label}.guide_cache.json")),
            serde_json::to_vec_pretty(&spec).unwrap(),
        )
        .unwrap();
    }
    (full_b, cache_b)
}

#[test]
fn an_alembic_guide_cache_is_a_tenth_of_the_full_cache_and_interpolates_back() {
    bake_and_compare("abc");
}

#[test]
fn a_usd_guide_cache_is_a_tenth_of_the_full_cache_and_interpolates_back() {
    bake_and_compare("usdc");
}

#[test]
fn a_guide_cache_that_does_not_apply_is_refused_before_baking() {
    let dir = TestDir::new();
    let groom = |render: &str| {
        format!(
            "seed = 3\n[groom]\ngenerate = {{ layout = \"scalp\", strands = 10, length = 0.1, \
             segment_length = 0.02 }}\n{render}\n[[stage]]\nkind = \"settle\"\nduration = 0.1\n"
        )
    };
    let render = "render = { count = 50 }";
    let cases = [
        (
            groom(""),
            "path = \"g.abc\"\nwhat = \"animated\"\ncache = \"guides\"",
            "needs render hair",
        ),
        (
            groom(render),
            "path = \"g.abc\"\nwhat = \"final\"\ncache = \"guides\"",
            "for animated exports",
        ),
        (
            groom(render),
            "path = \"g.usda\"\nwhat = \"animated\"\ncache = \"guides\"",
            "written to .abc, .usdc or .usd",
        ),
        (
            groom(render),
            "path = \"g.glb\"\nwhat = \"animated\"\ncache = \"guides\"",
            "written to .abc, .usdc or .usd",
        ),
        (
            groom(render),
            "path = \"g.abc\"\nwhat = \"animated\"\ncache = \"guides\"\nresample = 0.01",
            "no resample or curves",
        ),
        (
            groom(render),
            "path = \"g.abc\"\nwhat = \"animated\"\ncache = \"guide\"",
            "cache must be \"full\" or \"guides\"",
        ),
    ];
    for (k, (head, export, want)) in cases.iter().enumerate() {
        let name = format!("t{k}.toml");
        std::fs::write(dir.path(&name), format!("{head}[[export]]\n{export}\n")).unwrap();
        let stderr = dir.run_fail(&["bake", &name, "-q"], 2);
        assert!(
            stderr.contains(want) && stderr.contains(&format!("t{k}.toml:")),
            "case {k}: {stderr}"
        );
        assert_eq!(stderr.trim().lines().count(), 1, "case {k}: {stderr}");
        for file in ["g.abc", "g.usda", "g.glb"] {
            assert!(!dir.path(file).exists(), "case {k}: {file} written");
        }
    }
    // `full` is the default and may be said.
    std::fs::write(
        dir.path("ok.toml"),
        format!(
            "{}[[export]]\npath = \"g.abc\"\nwhat = \"final\"\ncache = \"full\"\n",
            groom(render)
        ),
    )
    .unwrap();
    dir.run_ok(&["bake", "ok.toml", "-q"]);
}
