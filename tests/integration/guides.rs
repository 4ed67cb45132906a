//! Guides and render hair: the Unreal-style split survives Alembic, bakes
//! simulate the guides and deliver render hair that follows them, smooth
//! curves, and streamed memory.

use crate::util::{hand_to_validators, sample, TestDir};
use groom::guides::{GROOM_CLOSEST_GUIDES, GROOM_GUIDE_WEIGHTS};
use groom::{AttributeValues, Groom};
use serde_json::json;
use std::path::{Path, PathBuf};

fn read(path: &Path) -> Groom {
    importers::read(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
}

/// The Alembic library's Unreal-style groom (exporters/tests/data).
fn unreal_fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("exporters/tests/data/unreal_guides.abc")
}

fn guide_count(groom: &Groom) -> usize {
    groom
        .guide_flags()
        .expect("groom_guide per strand")
        .iter()
        .filter(|&&g| g)
        .count()
}

fn vec3s(groom: &Groom, name: &str) -> Vec<[f32; 3]> {
    match &groom
        .attribute(name)
        .unwrap_or_else(|| panic!("{name}"))
        .values
    {
        AttributeValues::Vec3(v) => v.clone(),
        other => panic!("{name} is {}", other.type_name()),
    }
}

#[test]
fn unreal_alembic_keeps_the_split_and_round_trips_byte_stable() {
    let dir = TestDir::new();
    let fixture = unreal_fixture();
    let source = read(&fixture);
    assert_eq!(source.strand_count(), 9);
    assert_eq!(guide_count(&source), 3);
    let closest = vec3s(&source, GROOM_CLOSEST_GUIDES);
    assert_eq!(closest[3], [0.0, 1.0, 2.0]);
    assert_eq!(vec3s(&source, GROOM_GUIDE_WEIGHTS)[3], [0.6, 0.3, 0.1]);

    // For Unreal: its units (cm) and groom attributes.
    dir.run_ok(&[
        "convert",
        fixture.to_str().unwrap(),
        "a.abc",
        "--target",
        "unreal",
    ]);
    dir.run_ok(&["convert", "a.abc", "b.abc", "--target", "unreal"]);
    let a = std::fs::read(dir.path("a.abc")).unwrap();
    assert_eq!(a, std::fs::read(dir.path("b.abc")).unwrap());
    let back = read(&dir.path("a.abc"));
    assert_eq!(back.guide_flags(), source.guide_flags());
    assert_eq!(vec3s(&back, GROOM_CLOSEST_GUIDES), closest);
    assert_eq!(back.points, source.points);
    hand_to_validators(
        &dir.path("a.abc"),
        "guides_unreal_round_trip",
        json!({"kind": "abc", "curves": 9, "points": 54, "unreal_groom": true, "guides": 3}),
    );
}

/// A scalp of `guides` generated guides with `render` render hairs grown
/// between them, settled for a moment, with `exports`.
fn render_timeline(guides: usize, render: &str, exports: &str) -> String {
    format!(
        r#"
seed = 3
[groom]
generate = {{ layout = "scalp", strands = {guides}, length = 0.12, segment_length = 0.03, scalp_angle = 60.0, drape = 8.0 }}
{render}
[[stage]]
kind = "settle"
duration = 0.1
{exports}
"#
    )
}

#[test]
fn a_bake_grows_render_hair_that_follows_the_guides() {
    let dir = TestDir::new();
    let exports = r#"
[[export]]
path = "final.abc"
what = "final"
target = "unreal"
[[export]]
path = "rest.abc"
what = "rest"
target = "unreal"
[[export]]
path = "anim.abc"
what = "animated"
fps = 20
target = "unreal"
[[export]]
path = "final.glb"
what = "final"
resample = 0.01
"#;
    let timeline = render_timeline(
        40,
        r#"render = { count = 400, seed = 5, clump = 0.2, noise = 0.001 }"#,
        exports,
    );
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let final_pose = read(&dir.path("final.abc"));
    assert_eq!(final_pose.strand_count(), 440);
    assert_eq!(guide_count(&final_pose), 40);
    let anim = read(&dir.path("anim.abc"));
    assert_eq!(anim.frames.len(), 3);
    assert_eq!(anim.frames[2].points, final_pose.points);
    // Each render strand starts in its guides' root triangle and ends near
    // the weighted tips of its guides (combed the same way, 12 cm long).
    let strands: Vec<&[[f32; 3]]> = final_pose.strands().collect();
    let closest = vec3s(&final_pose, GROOM_CLOSEST_GUIDES);
    let weights = vec3s(&final_pose, GROOM_GUIDE_WEIGHTS);
    let blend = |r: usize, point: &dyn Fn(&[[f32; 3]]) -> [f32; 3]| {
        let mut out = [0.0f32; 3];
        for k in 0..3 {
            let p = point(strands[closest[r][k] as usize]);
            for c in 0..3 {
                out[c] += weights[r][k] * p[c];
            }
        }
        out
    };
    let distance = |a: [f32; 3], b: [f32; 3]| -> f32 {
        (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f32>().sqrt()
    };
    for (r, strand) in strands.iter().enumerate().skip(40) {
        let root = blend(r, &|s| s[0]);
        assert!(distance(root, strand[0]) < 1e-3, "strand {r}: root off");
        // Its tip lies among its guides' tips: no farther from their
        // weighted mean than they are from each other (plus 1 cm).
        let tips: Vec<[f32; 3]> = (0..3)
            .map(|k| *strands[closest[r][k] as usize].last().unwrap())
            .collect();
        let spread = (0..3)
            .flat_map(|a| (0..3).map(move |b| (a, b)))
            .map(|(a, b)| distance(tips[a], tips[b]))
            .fold(0.0, f32::max);
        let tip = blend(r, &|s| *s.last().unwrap());
        let gap = distance(tip, *strand.last().unwrap());
        assert!(
            gap < spread + 1.0,
            "strand {r}: tip {gap} cm from its guides' tips, {spread} cm apart"
        );
        // Its length is the guides' (12 cm, in cm in the file).
        let length: f32 = strand.windows(2).map(|w| distance(w[0], w[1])).sum();
        assert!((length - 12.0).abs() < 1.0, "strand {r}: {length} cm long");
    }

    // The same render strands bake the same bytes.
    std::fs::write(
        dir.path("t2.toml"),
        render_timeline(
            40,
            r#"render = { count = 400, seed = 5, clump = 0.2, noise = 0.001 }"#,
            &exports.replace(".abc", "_2.abc").replace(".glb", "_2.glb"),
        ),
    )
    .unwrap();
    dir.run_ok(&["bake", "t2.toml", "-q", "--threads", "1"]);
    assert_eq!(
        std::fs::read(dir.path("final.abc")).unwrap(),
        std::fs::read(dir.path("final_2.abc")).unwrap()
    );
    let glb = read(&dir.path("final.glb"));
    assert_eq!(glb.strand_count(), 440);
    assert_eq!(guide_count(&glb), 40);
    hand_to_validators(&dir.path("final.glb"), "guides_grown_final", json!({}));
    hand_to_validators(
        &dir.path("final.abc"),
        "guides_grown_final",
        json!({"kind": "abc", "curves": 440, "unreal_groom": true, "guides": 40}),
    );
    hand_to_validators(
        &dir.path("anim.abc"),
        "guides_grown_animated",
        json!({"kind": "abc", "curves": 440, "samples": 3, "unreal_groom": true, "guides": 40}),
    );
}

#[test]
fn guides_are_picked_from_a_dense_groom() {
    let dir = TestDir::new();
    let exports = "[[export]]\npath = \"final.abc\"\nwhat = \"final\"\n";
    for (pick, guides) in [("count = 25", 25), ("every = 10", 20)] {
        let timeline = render_timeline(200, &format!("guides = {{ {pick} }}"), exports);
        std::fs::write(dir.path("t.toml"), timeline).unwrap();
        dir.run_ok(&["bake", "t.toml", "-q"]);
        let out = read(&dir.path("final.abc"));
        assert_eq!(out.strand_count(), 200, "{pick}");
        assert_eq!(guide_count(&out), guides, "{pick}");
    }
}

#[test]
fn smooth_curve_exports_and_their_checks() {
    let dir = TestDir::new();
    let exports = r#"
[[export]]
path = "resampled.abc"
what = "final"
resample = 0.005
[[export]]
path = "catmull.usda"
what = "rest"
curves = "catmull_rom"
[[export]]
path = "bspline.abc"
what = "final"
curves = "bspline"
"#;
    let timeline = render_timeline(10, r#"render = { count = 30, seed = 1 }"#, exports);
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let resampled = read(&dir.path("resampled.abc"));
    for strand in resampled.strands() {
        // 12 cm at most 5 mm apart: 24 edges or a few more.
        assert!((25..=28).contains(&strand.len()), "{}", strand.len());
    }
    let catmull = read(&dir.path("catmull.usda"));
    assert_eq!(catmull.basis, groom::CurveBasis::CatmullRom);
    // 5 simulated points plus a padding point at each end.
    assert!(catmull.strand_vertex_counts.iter().all(|&n| n == 7));
    let bspline = read(&dir.path("bspline.abc"));
    assert_eq!(bspline.basis, groom::CurveBasis::Bspline);
    assert!(bspline.strand_vertex_counts.iter().all(|&n| n == 9));
    // The preview draws the cubic curves smooth: it renders, and the
    // B-spline export draws like the resampled polyline of the same pose.
    dir.run_ok(&[
        "preview",
        "catmull.usda",
        "-o",
        "catmull.png",
        "--size",
        "64x64",
    ]);
    assert!(std::fs::metadata(dir.path("catmull.png")).unwrap().len() > 100);
    hand_to_validators(
        &dir.path("catmull.usda"),
        "guides_catmull_rom",
        json!({"kind": "usd", "curves": 40, "basis": "catmullRom"}),
    );
    hand_to_validators(
        &dir.path("bspline.abc"),
        "guides_bspline",
        json!({"kind": "abc", "curves": 40, "basis": "bspline", "guides": 10}),
    );

    // Bad values are named with their place.
    let bad = render_timeline(
        10,
        "",
        "[[export]]\npath = \"x.abc\"\nwhat = \"final\"\nresample = 0.0\n",
    );
    std::fs::write(dir.path("bad.toml"), bad).unwrap();
    let e = dir.run_fail(&["validate", "bad.toml"], 2);
    assert!(e.contains("bad.toml:") && e.contains("resample"), "{e}");
    let bad = render_timeline(
        10,
        "",
        "[[export]]\npath = \"x.usda\"\nwhat = \"state\"\ncurves = \"bspline\"\n",
    );
    std::fs::write(dir.path("bad.toml"), bad).unwrap();
    let e = dir.run_fail(&["validate", "bad.toml"], 2);
    assert!(e.contains("state export"), "{e}");
    let bad = render_timeline(
        10,
        "",
        "[[export]]\npath = \"x.glb\"\nwhat = \"final\"\ncurves = \"catmull_rom\"\n",
    );
    std::fs::write(dir.path("bad.toml"), bad).unwrap();
    let e = dir.run_fail(&["validate", "bad.toml"], 2);
    assert!(e.contains("polylines only"), "{e}");
    let bad = render_timeline(10, "render = { count = 0 }", "");
    std::fs::write(dir.path("bad.toml"), bad).unwrap();
    let e = dir.run_fail(&["validate", "bad.toml"], 2);
    assert!(
        e.contains("bad.toml:5:") && e.contains("render count"),
        "{e}"
    );
}

/// Angles (degrees) between consecutive segments of every strand.
fn corner_angles(strand: &[[f32; 3]]) -> impl Iterator<Item = f64> + '_ {
    strand.windows(3).map(|w| {
        let a: Vec<f64> = (0..3).map(|k| f64::from(w[1][k] - w[0][k])).collect();
        let b: Vec<f64> = (0..3).map(|k| f64::from(w[2][k] - w[1][k])).collect();
        let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
        let na = a.iter().map(|x| x * x).sum::<f64>().sqrt();
        let nb = b.iter().map(|x| x * x).sum::<f64>().sqrt();
        (dot / (na * nb)).clamp(-1.0, 1.0).acos().to_degrees()
    })
}

/// The perm sample with render hair, its rest shape resampled at 5 mm:
/// no corner sharper than 30 degrees, while the simulated polylines have
/// far sharper ones (the set is a real curl, not smoothed away). Coarse
/// guides make the corners: 3 cm edges on a 2 cm rod instead of the
/// sample's 5 mm on 1 cm.
#[test]
fn the_perm_samples_render_hair_resampled_at_5_mm_has_no_sharp_corner() {
    let dir = TestDir::new();
    let perm = std::fs::read_to_string(sample("perm.toml")).unwrap();
    let coarse = perm
        .replace("segment_length = 0.005", "segment_length = 0.03")
        .replace(
            "radius = 0.01, root_gap = 0.03",
            "radius = 0.02, root_gap = 0.03",
        );
    assert_ne!(coarse, perm, "perm.toml's edges and rod");
    let body = coarse.split("[[export]]").next().unwrap();
    let timeline = body.replace(
        "[material]",
        "render = { count = 300, seed = 2 }\n\n[material]",
    ) + r#"
[[export]]
path = "perm_render_rest.abc"
what = "rest"
resample = 0.005
[[export]]
path = "perm_guides_rest.abc"
what = "rest"
"#;
    std::fs::write(dir.path("perm.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "perm.toml", "-q"]);
    let smooth = read(&dir.path("perm_render_rest.abc"));
    assert_eq!(smooth.strand_count(), 400);
    let flags = smooth.guide_flags().unwrap();
    let mut sharpest = 0.0f64;
    for (strand, guide) in smooth.strands().zip(&flags) {
        if !guide {
            sharpest = corner_angles(strand).fold(sharpest, f64::max);
        }
    }
    assert!(sharpest < 30.0, "sharpest corner {sharpest:.1} degrees");
    let coarse = read(&dir.path("perm_guides_rest.abc"));
    let coarse_sharpest = coarse
        .strands()
        .flat_map(corner_angles)
        .fold(0.0f64, f64::max);
    assert!(
        coarse_sharpest > 45.0,
        "the perm set no curl: {coarse_sharpest:.1}"
    );
    eprintln!("perm render hair at 5 mm: sharpest corner {sharpest:.1} deg (simulated polylines {coarse_sharpest:.1} deg)");
}

/// Runs groombake with `args` and returns its peak resident memory in kB:
/// `VmHWM` of its own address space, read from /proc while it runs (the
/// high-water mark only grows; `ru_maxrss` would count the test process,
/// whose address space the child shares until it execs).
fn peak_memory_kb(dir: &TestDir, args: &[&str]) -> u64 {
    let mut child = dir.command().args(args).spawn().expect("run groombake");
    let status_file = format!("/proc/{}/status", child.id());
    let mut peak = 0u64;
    loop {
        if let Ok(status) = std::fs::read_to_string(&status_file) {
            let hwm = status
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok());
            peak = peak.max(hwm.unwrap_or(0));
        }
        if let Some(status) = child.try_wait().expect("wait") {
            assert!(status.success(), "groombake {args:?} failed");
            return peak;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// A reduced full head (samples/full_head.toml takes minutes): render hair
/// streamed to an animated Alembic, 24 and then 96 frames. The peak memory
/// must not grow with the frame count (each frame is interpolated, written
/// and dropped).
#[test]
fn streamed_render_hair_memory_is_flat_in_frame_count() {
    let dir = TestDir::new();
    let mut peaks = Vec::new();
    for frames in [24, 96] {
        let duration = (frames - 1) as f64 / 96.0 + 0.005;
        let timeline = format!(
            r#"
seed = 1
[groom]
generate = {{ layout = "scalp", strands = 100, length = 0.21, segment_length = 0.03, scalp_angle = 95.0, drape = 10.0 }}
render = {{ count = 10000, seed = 1 }}
[[stage]]
kind = "settle"
duration = {duration}
[[export]]
path = "anim_{frames}.abc"
what = "animated"
fps = 96
"#
        );
        let name = format!("t{frames}.toml");
        std::fs::write(dir.path(&name), timeline).unwrap();
        peaks.push(peak_memory_kb(&dir, &["bake", &name, "-q"]));
        let anim = read(&dir.path(&format!("anim_{frames}.abc")));
        assert_eq!(anim.frames.len(), frames);
        assert_eq!(anim.strand_count(), 10100);
    }
    // One frame of the export is 10,100 x 8 points x 12 bytes = 0.97 MB:
    // holding the 72 extra frames would add 70 MB.
    eprintln!(
        "peak memory: 24 frames {} kB, 96 frames {} kB",
        peaks[0], peaks[1]
    );
    assert!(
        peaks[1] < peaks[0] + 4 * 1024,
        "peak memory grew from {} kB to {} kB",
        peaks[0],
        peaks[1]
    );
}

/// A state export holds guides and render hair; a later bake continues
/// from it, simulating the guides only and delivering both again.
#[test]
fn a_state_with_render_hair_continues_in_a_later_bake() {
    let dir = TestDir::new();
    let first = render_timeline(
        10,
        "render = { count = 30, seed = 1 }",
        "[[export]]\npath = \"state.usda\"\nwhat = \"state\"\n",
    );
    std::fs::write(dir.path("first.toml"), first).unwrap();
    dir.run_ok(&["bake", "first.toml", "-q"]);
    let state = read(&dir.path("state.usda"));
    assert_eq!((state.strand_count(), guide_count(&state)), (40, 10));
    let second = r#"
[groom]
source = "state.usda"
[[stage]]
kind = "settle"
duration = 0.05
[[export]]
path = "continued.abc"
what = "final"
"#;
    std::fs::write(dir.path("second.toml"), second).unwrap();
    dir.run_ok(&["bake", "second.toml", "-q", "--report", "report.json"]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("report.json")).unwrap()).unwrap();
    assert_eq!(report["strands"], 10, "only the guides are simulated");
    let continued = read(&dir.path("continued.abc"));
    assert_eq!(
        (continued.strand_count(), guide_count(&continued)),
        (40, 10)
    );
}

/// Render roots scattered on a scalp mesh follow their nearest guides.
#[test]
fn render_hair_grows_on_a_scalp_mesh() {
    let dir = TestDir::new();
    let head = sample("head.obj");
    let timeline = render_timeline(
        20,
        &format!(
            "render = {{ count = 50, seed = 4, scalp = {:?} }}",
            head.to_str().unwrap()
        ),
        "[[export]]\npath = \"final.abc\"\nwhat = \"final\"\n",
    );
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let out = read(&dir.path("final.abc"));
    assert_eq!((out.strand_count(), guide_count(&out)), (70, 20));
    let (vertices, _) = importers::mesh::read_triangles(&head).unwrap();
    let (min, max) = groom::bounds_of(&vertices).unwrap();
    // Roots on the mesh (the file is in cm, the mesh in metres).
    for strand in out.strands().skip(20) {
        let root = strand[0];
        for k in 0..3 {
            let c = root[k] / 100.0;
            assert!(c >= min[k] - 1e-4 && c <= max[k] + 1e-4, "root {root:?}");
        }
    }
    let missing = render_timeline(10, "render = { count = 5, scalp = \"nowhere.obj\" }", "");
    std::fs::write(dir.path("bad.toml"), missing).unwrap();
    let e = dir.run_fail(&["validate", "bad.toml"], 2);
    assert!(e.contains("scalp mesh") && e.contains("nowhere.obj"), "{e}");
}

/// Render roots grown on a scalp mesh with UVs take their `root_uv` from
/// the mesh: on a flat quad whose UVs are linear in x and z, each root's UV
/// is that linear map of its position, and every export carries it.
#[test]
fn render_hair_on_a_scalp_mesh_takes_its_uvs() {
    let dir = TestDir::new();
    // A 10 cm square above the generated scalp; U follows x over
    // [0.25, 0.75], V follows z over [0.5, 1].
    let quad = "v -0.05 0.1 -0.05\nv 0.05 0.1 -0.05\nv 0.05 0.1 0.05\nv -0.05 0.1 0.05\n\
                vt 0.25 0.5\nvt 0.75 0.5\nvt 0.75 1.0\nvt 0.25 1.0\n\
                f 1/1 4/4 3/3 2/2\n";
    std::fs::write(dir.path("quad.obj"), quad).unwrap();
    let timeline = render_timeline(
        20,
        "render = { count = 40, seed = 4, scalp = \"quad.obj\" }",
        "[[export]]\npath = \"rest.abc\"\nwhat = \"rest\"\n\
         [[export]]\npath = \"final.abc\"\nwhat = \"final\"\n\
         [[export]]\npath = \"final.usda\"\nwhat = \"final\"\n\
         [[export]]\npath = \"final.glb\"\nwhat = \"final\"\n",
    );
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let render_uvs = |file: &str| {
        let (_, render) = roles(&read(&dir.path(file)));
        let uvs = match &render.attribute("root_uv").expect("root_uv").values {
            AttributeValues::Vec2(v) => v.clone(),
            other => panic!("root_uv is {}", other.type_name()),
        };
        (render, uvs)
    };
    let (render, uvs) = render_uvs("rest.abc");
    assert_eq!(uvs.len(), 40);
    let roots: Vec<[f32; 3]> = render.strands().map(|s| s[0]).collect();
    for uv in &uvs {
        assert!(
            (0.25..=0.75).contains(&uv[0]) && (0.5..=1.0).contains(&uv[1]),
            "{uv:?} outside the quad's UVs"
        );
    }
    // U follows x and V follows z: roots more than 2 cm apart along an
    // axis (the rest roots sit within millimetres of where they were
    // scattered) have their UVs in the same order.
    for (i, a) in roots.iter().enumerate() {
        for (j, b) in roots.iter().enumerate() {
            for (axis, k) in [(0, 0), (2, 1)] {
                if b[axis] - a[axis] > 0.02 {
                    assert!(
                        uvs[j][k] > uvs[i][k],
                        "roots {a:?} {b:?}: {:?} {:?}",
                        uvs[i],
                        uvs[j]
                    );
                }
            }
        }
    }
    for file in ["final.abc", "final.usda", "final.glb"] {
        let (_, other) = render_uvs(file);
        assert_eq!(other.len(), uvs.len(), "{file}");
        for (a, b) in other.iter().zip(&uvs) {
            assert!(
                (a[0] - b[0]).abs() < 1e-5 && (a[1] - b[1]).abs() < 1e-5,
                "{file}: {a:?} vs {b:?}"
            );
        }
    }
}

/// The guides and the render strands of a groom, each as a groom, with
/// their frames, in metres and Y up (as glTF holds them).
fn roles(groom: &Groom) -> (Groom, Groom) {
    let mut groom = groom.clone();
    groom.convert_to(groom::Units::METERS, groom::UpAxis::Y);
    let split = groom.split_guides().expect("groom_guide per strand");
    (split.guides, split.render)
}

/// USD writes guides and render strands as two BasisCurves prims under the
/// root, glTF as two primitives of one mesh; each reads back as one groom
/// with the split, the points and the frames of each role intact.
#[test]
fn usd_and_gltf_keep_guides_and_render_strands_apart() {
    let dir = TestDir::new();
    let source = read(&unreal_fixture());
    let mut animated = source.clone();
    animated.frames = (1..=3)
        .map(|k| groom::Frame {
            time: k as f64 / 24.0,
            points: source
                .points
                .iter()
                .enumerate()
                .map(|(i, p)| [p[0] + 0.01 * k as f32, p[1], p[2] - 0.001 * (i % 5) as f32])
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    let (source_guides, source_render) = roles(&animated);
    assert_eq!(
        (source_guides.strand_count(), source_render.strand_count()),
        (3, 6)
    );
    // Guides among the render strands: each role is written in groom order.
    let interleaved = animated.subset(&[3, 0, 4, 5, 1, 6, 7, 8, 2]);
    for (groom, stem) in [
        (&source, "static"),
        (&animated, "animated"),
        (&interleaved, "interleaved"),
    ] {
        for ext in ["usda", "usdc", "glb", "gltf"] {
            let path = dir.path(&format!("{stem}.{ext}"));
            exporters::write(&path, groom).unwrap_or_else(|e| panic!("{stem}.{ext}: {e}"));
            let back = read(&path);
            let (guides, render) = roles(&back);
            let (want_guides, want_render) = roles(groom);
            for (role, got, want) in [
                ("guides", &guides, &want_guides),
                ("render", &render, &want_render),
            ] {
                let what = format!("{stem}.{ext} {role}");
                assert_eq!(
                    got.strand_vertex_counts, want.strand_vertex_counts,
                    "{what}"
                );
                assert_points_close(&got.points, &want.points, &what);
                assert_eq!(got.frames.len(), want.frames.len(), "{what}");
                for (a, b) in got.frames.iter().zip(&want.frames) {
                    assert!((a.time - b.time).abs() < 1e-6, "{what}");
                    assert_points_close(&a.points, &b.points, &what);
                }
            }
            assert_eq!(back.guide_flags().map(|f| f.len()), Some(9), "{stem}.{ext}");
            assert!(
                back.attribute("group_id").is_none(),
                "{stem}.{ext}: the split is no group"
            );
            if ext == "usda" {
                let text = std::fs::read_to_string(&path).unwrap();
                for prim in ["def BasisCurves \"guides\"", "def BasisCurves \"render\""] {
                    assert_eq!(text.matches(prim).count(), 1, "{stem}.usda: {prim}");
                }
            }
            if ext == "gltf" {
                let document: serde_json::Value =
                    serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
                let primitives = document["meshes"][0]["primitives"].as_array().unwrap();
                assert_eq!(
                    primitives.len(),
                    2,
                    "{stem}.gltf: guides and render primitives"
                );
                for (primitive, vertices) in primitives.iter().zip([18, 36]) {
                    let position = primitive["attributes"]["POSITION"].as_u64().unwrap();
                    assert_eq!(document["accessors"][position as usize]["count"], vertices);
                    let targets = primitive["targets"].as_array().map_or(0, |t| t.len());
                    assert_eq!(targets, groom.frames.len(), "{stem}.gltf morph targets");
                }
            }
            if stem == "interleaved" {
                continue;
            }
            let label = format!("guides_split_{stem}");
            let frames = groom.frames.len();
            let expect = if ext.starts_with("usd") {
                let mut expect = json!({
                    "kind": "usd", "curves": 9, "points": 54,
                    "prims": {
                        "/Groom/guides": {"curves": 3, "groom_guide": 1},
                        "/Groom/render": {"curves": 6, "groom_guide": 0},
                    },
                });
                if frames > 0 {
                    expect["time_samples"] = json!(frames);
                }
                expect
            } else {
                json!({"kind": "gltf", "primitives": 2, "vertices": 54, "morph_targets": frames > 0})
            };
            hand_to_validators(&path, &label, expect);
        }
    }
}

fn assert_points_close(got: &[[f32; 3]], want: &[[f32; 3]], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: point count");
    for (a, b) in got.iter().zip(want) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-6, "{what}: {a:?} != {b:?}");
        }
    }
}
