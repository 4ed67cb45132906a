//! Refuse or warn, never drop silently: a mesh where curves are expected,
//! frames lost to a static format.

use crate::preview::animated_swatch;
use crate::util::{sample, TestDir};

#[test]
fn converting_a_triangle_mesh_is_refused_with_the_reason() {
    let dir = TestDir::new();
    let head = sample("head.obj");
    let head = head.to_str().unwrap();
    let stderr = dir.run_fail(&["convert", head, "head.abc"], 2);
    assert!(stderr.contains("head.obj"), "{stderr}");
    assert!(stderr.contains("triangle mesh"), "{stderr}");
    assert!(stderr.contains("no curves"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        !dir.path("head.abc").exists(),
        "no output for a refused input"
    );
}

#[test]
fn a_glb_mesh_where_curves_are_expected_is_refused() {
    let dir = TestDir::new();
    let pillow = sample("pillow.glb");
    // `inspect` shows a mesh (tests/integration/guard_rails.rs); where a
    // groom must be read, a mesh is refused, saying why.
    let stderr = dir.run_fail(&["convert", pillow.to_str().unwrap(), "out.usda"], 2);
    assert!(stderr.contains("pillow.glb"), "{stderr}");
    assert!(stderr.contains("triangle mesh"), "{stderr}");
    assert!(!dir.path("out.usda").exists());
}

#[test]
fn animated_to_static_format_warns_that_frames_are_dropped() {
    let dir = TestDir::new();
    let animated = animated_swatch(&dir);
    let output = dir.run_ok(&["convert", &animated, "still.hair"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("warning"), "{stderr}");
    assert!(stderr.contains("3 frames"), "{stderr}");
    assert!(stderr.contains("--frame"), "{stderr}");
    assert!(dir.path("still.hair").exists());
}

#[test]
fn animated_to_static_format_with_frame_writes_that_frame_quietly() {
    let dir = TestDir::new();
    let animated = animated_swatch(&dir);
    let output = dir.run_ok(&["convert", &animated, "frame2.hair", "--frame", "2"]);
    // Only the frames go quiet: attributes .hair cannot hold are still named.
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("frames"), "{stderr}");
    let frame2 = importers::read(&dir.path("frame2.hair")).unwrap();
    let source = importers::read(&dir.path(&animated)).unwrap();
    // Width over height of the pose: a shape, whatever units .hair is read in.
    let aspect = |points: &[[f32; 3]]| {
        let extent = |k: usize| {
            let values = points.iter().map(|p| p[k]);
            values.clone().fold(f32::MIN, f32::max) - values.fold(f32::MAX, f32::min)
        };
        extent(0) / extent(1)
    };
    let expected = aspect(&source.frames[2].points);
    let found = aspect(&frame2.points);
    assert!(
        (found / expected - 1.0).abs() < 1e-5
            && (expected / aspect(&source.points) - 1.0).abs() > 5e-3,
        "frame 2 has aspect {expected}, the base pose {}, the .hair {found}",
        aspect(&source.points)
    );
}

#[test]
fn animated_to_animated_format_does_not_warn() {
    let dir = TestDir::new();
    let animated = animated_swatch(&dir);
    let output = dir.run_ok(&["convert", &animated, "moving.usda"]);
    assert!(
        output.stderr.is_empty(),
        "{:?}",
        String::from_utf8_lossy(&output.stderr)
    );
}
