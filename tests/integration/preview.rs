//! `groombake preview`: pictures of grooms, contact sheets of frames.

use crate::util::{test_data, TestDir};
use groom::{Attribute, AttributeValues, Frame};
use groombake::generate::{generate, GeneratorParameters, RootLayout, StrandShape};
use std::path::Path;

/// Width, height and RGB pixels of a PNG written by preview.
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    pixels.truncate(info.buffer_size());
    (info.width, info.height, pixels)
}

/// Pixels that are not the neutral grey background: coloured or far from grey.
fn hair_pixels(width: u32, pixels: &[u8]) -> Vec<(u32, u32)> {
    pixels
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| {
            let (r, b) = (p[0] as i32, p[2] as i32);
            // The background is grey (r = g, b a little higher); hair is warm or bright.
            r - b > 6 || r > 150
        })
        .map(|(i, _)| (i as u32 % width, i as u32 / width))
        .collect()
}

/// A small animated groom as a glTF file: a swatch that swings to +X.
pub(crate) fn animated_swatch(dir: &TestDir) -> String {
    let mut groom = generate(&GeneratorParameters {
        strands: 300,
        layout: RootLayout::Swatch,
        shape: StrandShape::Wavy,
        ..GeneratorParameters::default()
    })
    .unwrap();
    let heat: Vec<f32> = (0..groom.strand_count()).map(|s| s as f32).collect();
    groom.set_attribute(Attribute::per_strand(
        "bond_hydrogen",
        AttributeValues::Float(heat),
    ));
    let frames: Vec<Frame> = (0..3)
        .map(|f| Frame {
            time: f as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0] + 0.03 * f as f32 * -p[1], p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    let path = dir.path("swing.glb");
    let options = exporters::AnimationOptions {
        fps: 24.0,
        frame_count: frames.len(),
    };
    let mut writer = exporters::animated(&path, &groom, options).unwrap();
    for frame in &frames {
        writer.write_frame(frame).unwrap();
    }
    writer.finish().unwrap();
    "swing.glb".to_string()
}

#[test]
fn shows_the_bangs() {
    let dir = TestDir::new();
    let bangs = test_data("hairutil_Bangs_100.hair");
    dir.run_ok(&["preview", bangs.to_str().unwrap(), "-o", "p.png"]);
    let (width, height, pixels) = decode(&dir.path("p.png"));
    assert_eq!((width, height), (1024, 1024));
    let hair = hair_pixels(width, &pixels);
    // 100 strands of about 11 vertices, drawn across most of the picture.
    assert!(hair.len() > 5_000, "{} hair pixels", hair.len());
    let min_x = hair.iter().map(|p| p.0).min().unwrap();
    let max_x = hair.iter().map(|p| p.0).max().unwrap();
    let min_y = hair.iter().map(|p| p.1).min().unwrap();
    let max_y = hair.iter().map(|p| p.1).max().unwrap();
    assert!(min_x > 0 && min_y > 0 && max_x < width - 1 && max_y < height - 1);
    assert!(max_x - min_x > width / 2 || max_y - min_y > height / 2);
    // No temporary file is left beside the picture.
    let names: Vec<_> = std::fs::read_dir(dir.root()).unwrap().collect();
    assert_eq!(names.len(), 1);
}

#[test]
fn same_input_same_bytes() {
    let dir = TestDir::new();
    let bangs = test_data("hairutil_Bangs_100.hair");
    let bangs = bangs.to_str().unwrap();
    for (name, view) in [("a.png", "persp"), ("b.png", "persp"), ("c.png", "top")] {
        dir.run_ok(&[
            "preview", bangs, "-o", name, "--view", view, "--size", "300x200",
        ]);
    }
    let a = std::fs::read(dir.path("a.png")).unwrap();
    assert_eq!(a, std::fs::read(dir.path("b.png")).unwrap());
    assert_ne!(a, std::fs::read(dir.path("c.png")).unwrap());
    assert_eq!(decode(&dir.path("c.png")).0, 300);
}

#[test]
fn sheet_of_frames_coloured_by_an_attribute() {
    let dir = TestDir::new();
    let file = animated_swatch(&dir);
    dir.run_ok(&[
        "preview",
        &file,
        "-o",
        "sheet.png",
        "--frames",
        "0,2",
        "--size",
        "200x150",
        "--color",
        "bond_hydrogen",
    ]);
    let (width, height, pixels) = decode(&dir.path("sheet.png"));
    // --size is the whole picture: two pictures side by side under
    // their labels share it.
    assert_eq!((width, height), (200, 150));
    // --panel-size is each picture's: two side by side, a label strip above.
    dir.run_ok(&[
        "preview",
        &file,
        "-o",
        "panels.png",
        "--frames",
        "0,2",
        "--panel-size",
        "200x150",
    ]);
    let (width, height, _) = decode(&dir.path("panels.png"));
    assert!(width > 400 && width < 420, "{width}");
    assert!(height > 150 && height < 190, "{height}");
    // Both ends of the ramp appear (the strands and the legend).
    let red = pixels
        .chunks_exact(3)
        .filter(|p| p[0] > 120 && p[2] < 60 && p[1] < 60)
        .count();
    let blue = pixels
        .chunks_exact(3)
        .filter(|p| p[2] > 120 && p[0] < 60)
        .count();
    assert!(red > 50 && blue > 50, "red {red}, blue {blue}");
    // One frame alone is a single picture.
    dir.run_ok(&[
        "preview", &file, "-o", "one.png", "--frame", "1", "--size", "200x150",
    ]);
    assert_eq!(decode(&dir.path("one.png")).0, 200);
}

#[test]
fn bad_requests_exit_2_with_a_reason() {
    let dir = TestDir::new();
    let bangs = test_data("hairutil_Bangs_100.hair");
    let bangs = bangs.to_str().unwrap();
    let stderr = dir.run_fail(
        &["preview", bangs, "-o", "p.png", "--color", "bond_hydrogen"],
        2,
    );
    assert!(
        stderr.contains("bond_hydrogen") && stderr.contains("hairutil_Bangs_100.hair"),
        "{stderr}"
    );
    for size in ["0x100", "100x0", "16385x10", "big", "100x"] {
        let stderr = dir.run_fail(&["preview", bangs, "-o", "p.png", "--size", size], 2);
        assert!(stderr.contains("WIDTHxHEIGHT"), "{size}: {stderr}");
    }
    let stderr = dir.run_fail(&["preview", bangs, "-o", "p.png", "--frame", "3"], 2);
    assert!(
        stderr.contains("frame 3") && stderr.contains("0 frames"),
        "{stderr}"
    );
    let stderr = dir.run_fail(&["preview", bangs, "-o", "p.png", "--frames", "0,x"], 2);
    assert!(stderr.contains("--frames"), "{stderr}");
    let stderr = dir.run_fail(&["preview", bangs, "-o", "p.png", "--view", "diagonal"], 2);
    assert!(stderr.contains("front, side, top or persp"), "{stderr}");
    let stderr = dir.run_fail(&["preview", bangs, "-o", "p.jpg"], 2);
    assert!(stderr.contains("png"), "{stderr}");
    dir.run_fail(&["preview", "nowhere.hair", "-o", "p.png"], 2);
    // Nothing was written by any of these.
    assert_eq!(std::fs::read_dir(dir.root()).unwrap().count(), 0);
}

#[test]
fn unknown_frame_of_an_animation_is_refused() {
    let dir = TestDir::new();
    let file = animated_swatch(&dir);
    let stderr = dir.run_fail(&["preview", &file, "-o", "p.png", "--frames", "0,7"], 2);
    assert!(
        stderr.contains("frame 7") && stderr.contains("3 frames"),
        "{stderr}"
    );
    assert!(!dir.path("p.png").exists());
}

/// A small swatch that gravity along `gravity` swings off the vertical: the
/// final pose is tilted, the rest shape (bonds intact) hangs straight.
fn swinging_timeline(gravity: [f32; 3], preview: &str) -> String {
    format!(
        r#"seed = 1
[groom]
generate = {{ layout = "swatch", strands = 24, length = 0.12, segment_length = 0.02, swatch_width = 0.04 }}
[solver]
dt = "1/240"
gravity = [{}, {}, {}]
[[stage]]
kind = "settle"
duration = 0.4
[[export]]
path = "rest.usda"
what = "rest"
[[export]]
path = "final.usda"
what = "final"
[[export]]
path = "state.usda"
what = "state"
{preview}
"#,
        gravity[0], gravity[1], gravity[2]
    )
}

fn mean_difference(a: &Path, b: &Path) -> f64 {
    let (wa, ha, pa) = decode(a);
    let (wb, hb, pb) = decode(b);
    assert_eq!((wa, ha), (wb, hb));
    let total: u64 = pa
        .iter()
        .zip(&pb)
        .map(|(&x, &y)| u64::from(x.abs_diff(y)))
        .sum();
    total as f64 / pa.len() as f64
}

#[test]
fn timeline_preview_keeps_the_timelines_view_unless_told() {
    let dir = TestDir::new();
    let toml = swinging_timeline(
        [4.0, -9.0, 0.0],
        "[preview]\nsheet = \"sheet.png\"\nview = \"top\"\nsize = [96, 96]",
    );
    std::fs::write(dir.path("swing.toml"), toml).unwrap();
    dir.run_ok(&[
        "preview",
        "swing.toml",
        "-o",
        "default.png",
        "--size",
        "96x96",
    ]);
    dir.run_ok(&[
        "preview",
        "swing.toml",
        "-o",
        "top.png",
        "--size",
        "96x96",
        "--view",
        "top",
    ]);
    dir.run_ok(&[
        "preview",
        "swing.toml",
        "-o",
        "front.png",
        "--size",
        "96x96",
        "--view",
        "front",
    ]);
    let read = |name: &str| std::fs::read(dir.path(name)).unwrap();
    assert_eq!(
        read("default.png"),
        read("top.png"),
        "[preview] view = top was not used"
    );
    assert_ne!(read("default.png"), read("front.png"));
}

#[test]
fn timeline_preview_picks_the_view_that_shows_the_change() {
    let dir = TestDir::new();
    // Gravity tilted toward +Z: the swatch swings toward the camera of the
    // front view, where nothing would be seen to change; the side view shows it.
    let toml = swinging_timeline([0.0, -9.0, 5.0], "");
    std::fs::write(dir.path("toward.toml"), toml).unwrap();
    dir.run_ok(&[
        "preview",
        "toward.toml",
        "-o",
        "auto.png",
        "--size",
        "96x96",
    ]);
    dir.run_ok(&[
        "preview",
        "toward.toml",
        "-o",
        "side.png",
        "--size",
        "96x96",
        "--view",
        "side",
    ]);
    let read = |name: &str| std::fs::read(dir.path(name)).unwrap();
    assert_eq!(
        read("auto.png"),
        read("side.png"),
        "the swing toward +Z is seen from the side"
    );
    // Swinging toward +X: the front view.
    let toml = swinging_timeline([5.0, -9.0, 0.0], "");
    std::fs::write(dir.path("across.toml"), toml).unwrap();
    dir.run_ok(&[
        "preview",
        "across.toml",
        "-o",
        "auto.png",
        "--size",
        "96x96",
    ]);
    dir.run_ok(&[
        "preview",
        "across.toml",
        "-o",
        "front.png",
        "--size",
        "96x96",
        "--view",
        "front",
    ]);
    assert_eq!(read("auto.png"), read("front.png"));
}

#[test]
fn rest_draws_the_rest_shape_of_a_state_export_and_of_a_timeline() {
    let dir = TestDir::new();
    std::fs::write(
        dir.path("swing.toml"),
        swinging_timeline([6.0, -8.0, 0.0], ""),
    )
    .unwrap();
    dir.run_ok(&["bake", "swing.toml", "-q"]);
    let picture = |args: &[&str]| {
        let mut all = vec!["preview"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--size", "128x128", "--view", "front"]);
        dir.run_ok(&all);
    };
    picture(&["rest.usda", "-o", "rest.png"]);
    picture(&["state.usda", "--rest", "-o", "state_rest.png"]);
    picture(&["final.usda", "-o", "final.png"]);
    let same = mean_difference(&dir.path("rest.png"), &dir.path("state_rest.png"));
    let different = mean_difference(&dir.path("rest.png"), &dir.path("final.png"));
    assert!(
        same < 0.5,
        "--rest of the state differs from the rest export by {same}"
    );
    assert!(
        different > 2.0 * same.max(0.1),
        "rest and final differ only by {different}"
    );
    // A timeline's --rest: one labelled picture of the same shape.
    picture(&["swing.toml", "--rest", "-o", "timeline_rest.png"]);
    assert!(dir.path("timeline_rest.png").exists());
    // A file without simulation state has no rest shape to draw.
    let e = dir.run_fail(&["preview", "final.usda", "--rest", "-o", "x.png"], 2);
    assert!(e.contains("final.usda") && e.contains("state"), "{e}");
}

#[test]
fn timeline_preview_draws_its_colliders() {
    let dir = TestDir::new();
    // A ball behind the middle of the swatch (which hangs from a bar at the
    // origin down to y = -0.12), always active.
    let toml = r#"seed = 1
[groom]
generate = { layout = "swatch", strands = 12, length = 0.12, segment_length = 0.02, swatch_width = 0.06 }
[[collider]]
name = "ball"
active = "listed"
shape = { ball = { radius = 0.025 } }
motion = [{ t = 0.0, translation = [0.0, -0.06, -0.05] }]
[[stage]]
kind = "settle"
duration = 0.05
colliders = ["ball"]
"#;
    std::fs::write(dir.path("ball.toml"), toml).unwrap();
    dir.run_ok(&[
        "preview",
        "ball.toml",
        "-o",
        "ball.png",
        "--frame",
        "0",
        "--view",
        "front",
        "--size",
        "160x160",
    ]);
    let (width, _, pixels) = decode(&dir.path("ball.png"));
    // A collider that comes and goes is drawn in grey-blue: light and
    // bluer than the (warm) hair and the (neutral) background.
    let collider: Vec<usize> = pixels
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| p[0] > 80 && i32::from(p[2]) > i32::from(p[0]) + 8)
        .map(|(i, _)| i)
        .collect();
    assert!(
        collider.len() > 200,
        "only {} collider pixels in a {width} px wide picture",
        collider.len()
    );
}

/// Pixels of the head's skin: light, red above green above blue (the hair
/// is darker, the background neutral grey).
fn skin_pixels(pixels: &[u8]) -> Vec<usize> {
    pixels
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| {
            p[0] > 120
                && i32::from(p[0]) > i32::from(p[1]) + 20
                && i32::from(p[1]) > i32::from(p[2]) + 5
        })
        .map(|(i, _)| i)
        .collect()
}

#[test]
fn a_head_is_drawn_solid_in_skin_under_the_hair() {
    let dir = TestDir::new();
    let head_mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/head.obj");
    let head_mesh = head_mesh.to_str().unwrap();
    // A combed head of 24 cm hair on the ellipsoid head.obj is.
    dir.run_ok(&[
        "generate",
        "head",
        "-o",
        "head.usda",
        "--strands",
        "3000",
        "--length",
        "0.24",
        "--segment-length",
        "0.01",
    ]);
    let view = ["--view", "persp", "--size", "200x200"];
    dir.run_ok(&[&["preview", "head.usda", "-o", "bare.png"][..], &view].concat());
    dir.run_ok(
        &[
            &[
                "preview",
                "head.usda",
                "-o",
                "head.png",
                "--head",
                head_mesh,
            ][..],
            &view,
        ]
        .concat(),
    );
    let (_, _, bare) = decode(&dir.path("bare.png"));
    let (width, _, drawn) = decode(&dir.path("head.png"));
    // The face shows in skin (a few thousand pixels of a 200 x 200 picture);
    // without the head, the inside of the back hair shows there.
    let skin = skin_pixels(&drawn);
    assert!(skin.len() > 1500, "{} skin pixels", skin.len());
    assert!(skin_pixels(&bare).len() < 50);
    // The face is in front, the head at the top of the 24 cm hair: the
    // middle of the skin lies in the middle third across, the top half down.
    let (sx, sy) = skin.iter().fold((0, 0), |(x, y), &i| {
        (x + i % width as usize, y + i / width as usize)
    });
    let centre = (sx / skin.len(), sy / skin.len());
    assert!(
        (66..134).contains(&centre.0) && (20..100).contains(&centre.1),
        "skin centred at {centre:?}"
    );
    // A timeline draws its own head: --head does not apply.
    std::fs::write(
        dir.path("t.toml"),
        "[groom]\ngenerate = { layout = \"swatch\", strands = 4 }\n[[stage]]\nkind = \"settle\"\nduration = 0.01\n",
    )
    .unwrap();
    let stderr = dir.run_fail(
        &["preview", "t.toml", "-o", "t.png", "--head", head_mesh],
        2,
    );
    assert!(
        stderr.contains("--head") && stderr.contains("t.toml"),
        "{stderr}"
    );
    assert!(!dir.path("t.png").exists());
}

#[test]
fn a_collider_in_every_stage_is_the_head() {
    let dir = TestDir::new();
    // The swatch hangs in front of a ball head that is always there.
    let toml = r#"seed = 1
[groom]
generate = { layout = "swatch", strands = 12, length = 0.12, segment_length = 0.02, swatch_width = 0.06 }
[[collider]]
name = "head"
shape = { ball = { radius = 0.05 } }
motion = [{ t = 0.0, translation = [0.0, -0.06, -0.06] }]
[[stage]]
kind = "settle"
duration = 0.05
"#;
    std::fs::write(dir.path("head.toml"), toml).unwrap();
    let args = ["--frame", "0", "--view", "front", "--size", "160x160"];
    dir.run_ok(&[&["preview", "head.toml", "-o", "head.png"][..], &args].concat());
    let (_, _, pixels) = decode(&dir.path("head.png"));
    let skin = skin_pixels(&pixels);
    assert!(skin.len() > 1000, "{} skin pixels", skin.len());
}

/// Pixels of a perm rod's pink: red well above green and blue above green
/// (the hair is brown, blue below green; the background neutral grey).
fn rod_pixels(pixels: &[u8]) -> usize {
    pixels
        .chunks_exact(3)
        .filter(|p| i32::from(p[0]) > i32::from(p[1]) + 25 && p[2] > p[1] + 5)
        .count()
}

#[test]
fn perm_sheet_shows_the_hair_wound_on_its_rods() {
    use groombake::timeline::bake::{bake, BakeOptions};
    use groombake::timeline::Timeline;
    let timeline = Timeline::load(&crate::util::sample("perm.toml")).unwrap();
    let options = BakeOptions {
        dry: true,
        monitor: None,
        ..BakeOptions::default()
    };
    let outcome = bake(&timeline, &options).unwrap();
    let labels: Vec<&str> = outcome.snapshots.iter().map(|(l, _)| l.as_str()).collect();
    assert_eq!(
        labels,
        ["before", "during perm", "after perm", "after release"]
    );
    // One rod per strand, under the "during perm" snapshot only.
    assert_eq!(outcome.rods.len(), 1);
    assert_eq!(outcome.rods[0].snapshot, 1);
    assert_eq!(outcome.rods[0].rods.len(), 100);
    let surfaces =
        groombake::timeline::surfaces::snapshot_surfaces(&timeline, &outcome.rods).unwrap();
    assert_eq!(surfaces.len(), outcome.snapshots.len());
    // The rods are drawn: their pink in the "during perm" picture, none
    // after the perm (the rods are gone).
    let dir = TestDir::new();
    let perm = crate::util::sample("perm.toml");
    let perm = perm.to_str().unwrap();
    let mut counts = Vec::new();
    for frame in ["1", "2"] {
        let out = dir.path(&format!("perm{frame}.png"));
        let out = out.to_str().unwrap();
        dir.run_ok(&[
            "preview", perm, "-o", out, "--frame", frame, "--size", "200x200",
        ]);
        counts.push(rod_pixels(&decode(Path::new(out)).2));
    }
    assert!(
        counts[0] > 100,
        "only {} rod pixels during the perm",
        counts[0]
    );
    assert_eq!(counts[1], 0, "rod pixels after the perm");
}
