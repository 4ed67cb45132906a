//! `groombake generate head` (issue 34 item 1): grooms that look like hair.
//! Each test writes a groom with the real binary, reads the file back and
//! measures it: where the strands are against the head (the exact
//! ellipsoid, or parry3d's distance to `samples/head.obj`), their lengths
//! and curls, determinism, and refusals.

use crate::util::{sample, TestDir};
use parry3d::math::Vector;
use parry3d::query::PointQuery;
use parry3d::shape::{TriMesh, TriMeshFlags};

const RADII: [f64; 3] = [0.08, 0.1, 0.09];

/// Generates `generate head -o g.usda ARGS` and reads it back: strands of
/// points in metres.
fn head(dir: &TestDir, args: &[&str]) -> Vec<Vec<[f64; 3]>> {
    let mut all = vec!["generate", "head", "-o", "g.usda"];
    all.extend_from_slice(args);
    dir.run_ok(&all);
    strands(&dir.path("g.usda"))
}

fn strands(path: &std::path::Path) -> Vec<Vec<[f64; 3]>> {
    let groom = importers::read(path).unwrap();
    let scale = groom.units.meters_per_unit;
    let mut out = Vec::new();
    let mut start = 0;
    for &count in &groom.strand_vertex_counts {
        let count = count as usize;
        out.push(
            groom.points[start..start + count]
                .iter()
                .map(|p| p.map(|c| c as f64 * scale))
                .collect(),
        );
        start += count;
    }
    out
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn arc_length(strand: &[[f64; 3]]) -> f64 {
    strand.windows(2).map(|w| distance(w[0], w[1])).sum()
}

/// Signed distance to the ellipsoid of `RADII` at the origin (negative
/// inside): the closest point `x_i = r_i^2 p_i / (t + r_i^2)` with `t` the
/// root of `sum (r_i p_i / (t + r_i^2))^2 = 1`, found by bisection (the sum
/// falls as `t` grows; Eberly, "Distance from a point to an ellipse, an
/// ellipsoid, or a hyperellipsoid").
fn ellipsoid_distance(p: [f64; 3]) -> f64 {
    let level: f64 = (0..3).map(|k| (p[k] / RADII[k]).powi(2)).sum();
    let f = |t: f64| -> f64 {
        (0..3)
            .map(|k| (RADII[k] * p[k] / (t + RADII[k] * RADII[k])).powi(2))
            .sum::<f64>()
            - 1.0
    };
    let smallest = RADII.iter().fold(f64::MAX, |a, r| a.min(r * r));
    let (mut low, mut high) = (-smallest + 1e-15, 10.0);
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        if f(mid) > 0.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
    let t = 0.5 * (low + high);
    let closest: [f64; 3] =
        std::array::from_fn(|k| RADII[k] * RADII[k] * p[k] / (t + RADII[k] * RADII[k]));
    let d = distance(p, closest);
    if level < 1.0 {
        -d
    } else {
        d
    }
}

fn head_mesh() -> TriMesh {
    let mesh = importers::mesh::read_mesh(&sample("head.obj")).unwrap();
    let vertices = mesh
        .vertices
        .iter()
        .map(|v| Vector::new(v[0], v[1], v[2]))
        .collect();
    TriMesh::with_flags(vertices, mesh.triangles, TriMeshFlags::ORIENTED).unwrap()
}

/// Signed distance to `samples/head.obj` (negative inside).
fn mesh_distance(mesh: &TriMesh, p: [f64; 3]) -> f64 {
    let point = Vector::new(p[0] as f32, p[1] as f32, p[2] as f32);
    let projection = mesh.project_local_point(point, false);
    let d = (projection.point - point).length() as f64;
    if projection.is_inside {
        -d
    } else {
        d
    }
}

/// The acceptance of the layout on a head: roots on the scalp, no other
/// vertex inside the head, every vertex within 5 mm of the scalp over the
/// first 3 cm of arc length, and the hair hangs (tips well below roots).
fn check_lies_on_and_stays_off(strands: &[Vec<[f64; 3]>], distance: impl Fn([f64; 3]) -> f64) {
    let mut worst_inside = f64::MAX;
    let mut worst_near = 0.0f64;
    let (mut long, mut hanging) = (0, 0);
    for strand in strands {
        assert!(
            distance(strand[0]).abs() < 2e-5,
            "root off the scalp by {} m",
            distance(strand[0])
        );
        let mut arc = 0.0;
        for (i, p) in strand.iter().enumerate().skip(1) {
            arc += distance_between(strand[i - 1], *p);
            let d = distance(*p);
            worst_inside = worst_inside.min(d);
            if arc <= 0.03 {
                worst_near = worst_near.max(d);
            }
        }
        let (root, tip) = (strand[0], strand[strand.len() - 1]);
        if arc >= 0.2 {
            long += 1;
            if tip[1] < root[1] - 0.08 {
                hanging += 1;
            }
        }
    }
    assert!(
        worst_inside > 0.0,
        "a vertex {worst_inside} m inside the head"
    );
    assert!(
        worst_near <= 0.005,
        "a vertex within the first 3 cm is {worst_near} m off the scalp"
    );
    assert!(
        hanging * 10 >= long * 9,
        "only {hanging} of {long} strands of 20 cm or more hang down"
    );
}

fn distance_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    distance(a, b)
}

#[test]
fn a_24_cm_head_groom_lies_on_the_ellipsoid_and_never_enters_it() {
    let dir = TestDir::new();
    let strands = head(&dir, &["--strands", "3000", "--length", "0.24"]);
    assert_eq!(strands.len(), 3000);
    check_lies_on_and_stays_off(&strands, ellipsoid_distance);
}

#[test]
fn a_24_cm_head_groom_lies_on_the_head_mesh_and_never_enters_it() {
    let dir = TestDir::new();
    let mesh_path = sample("head.obj").display().to_string();
    let strands = head(
        &dir,
        &[
            "--strands",
            "3000",
            "--length",
            "0.24",
            "--scalp-mesh",
            &mesh_path,
        ],
    );
    let mesh = head_mesh();
    check_lies_on_and_stays_off(&strands, |p| mesh_distance(&mesh, p));
}

#[test]
fn short_and_long_hair_and_curls_stay_off_the_head() {
    let dir = TestDir::new();
    let mesh_path = sample("head.obj").display().to_string();
    let mesh = head_mesh();
    for (length, segment) in [("0.05", "0.005"), ("0.6", "0.01")] {
        let strands = head(
            &dir,
            &[
                "--strands",
                "1500",
                "--length",
                length,
                "--segment-length",
                segment,
            ],
        );
        check_lies_on_and_stays_off(&strands, ellipsoid_distance);
        let strands = head(
            &dir,
            &[
                "--strands",
                "800",
                "--length",
                length,
                "--segment-length",
                segment,
                "--scalp-mesh",
                &mesh_path,
            ],
        );
        check_lies_on_and_stays_off(&strands, |p| mesh_distance(&mesh, p));
    }
    // Long curls (the coil reaches toward the head where the hair leaves it).
    let strands = head(
        &dir,
        &[
            "--strands",
            "1000",
            "--length",
            "0.4",
            "--segment-length",
            "0.004",
            "--curl",
        ],
    );
    check_lies_on_and_stays_off(&strands, ellipsoid_distance);
}

fn mean_and_deviation(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, variance.sqrt())
}

#[test]
fn lengths_follow_the_set_mean_and_spread() {
    let dir = TestDir::new();
    let strands = head(
        &dir,
        &[
            "--strands",
            "2000",
            "--length",
            "0.2",
            "--length-spread",
            "0.2",
            "--clump-size",
            "0",
        ],
    );
    let lengths: Vec<f64> = strands.iter().map(|s| arc_length(s)).collect();
    let (mean, deviation) = mean_and_deviation(&lengths);
    assert!((mean - 0.2).abs() < 0.004, "mean length {mean}");
    assert!(
        (deviation / 0.2 - 0.2).abs() < 0.02,
        "relative spread {}",
        deviation / 0.2
    );
    // No spread: every strand the same length.
    let strands = head(
        &dir,
        &[
            "--strands",
            "500",
            "--length",
            "0.2",
            "--length-spread",
            "0",
            "--clump-size",
            "0",
        ],
    );
    for s in &strands {
        assert!((arc_length(s) - 0.2).abs() < 1e-5, "{}", arc_length(s));
    }
    // Clumps move points but keep the lengths close.
    let strands = head(
        &dir,
        &[
            "--strands",
            "2000",
            "--length",
            "0.2",
            "--length-spread",
            "0.2",
        ],
    );
    let lengths: Vec<f64> = strands.iter().map(|s| arc_length(s)).collect();
    let (mean, _) = mean_and_deviation(&lengths);
    assert!((mean - 0.2).abs() < 0.004, "clumped mean length {mean}");
}

/// Per strand, the curl radius measured where it hangs straight down well
/// below the head: half the horizontal extent of its coils.
fn hanging_curl_radii(strands: &[Vec<[f64; 3]>]) -> Vec<f64> {
    let mut radii = Vec::new();
    for strand in strands {
        let tail: Vec<[f64; 3]> = strand.iter().copied().filter(|p| p[1] < -0.15).collect();
        if tail.len() < 2 || tail[0][1] - tail[tail.len() - 1][1] < 0.07 {
            continue;
        }
        let extent = |k: usize| {
            let (low, high) = tail
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p[k]), h.max(p[k])));
            high - low
        };
        radii.push((extent(0) + extent(2)) / 4.0);
    }
    radii
}

#[test]
fn curl_radii_follow_the_set_mean_and_spread() {
    let dir = TestDir::new();
    let curls = |spread: &str| {
        hanging_curl_radii(&head(
            &dir,
            &[
                "--strands",
                "500",
                "--length",
                "1.5",
                "--segment-length",
                "0.0025",
                "--length-spread",
                "0",
                "--clump-size",
                "0",
                "--curl",
                "--curl-radius",
                "0.01",
                "--curl-pitch",
                "0.03",
                "--curl-radius-spread",
                spread,
            ],
        ))
    };
    let radii = curls("0.2");
    assert!(
        radii.len() >= 400,
        "only {} strands hang long enough",
        radii.len()
    );
    let (mean, deviation) = mean_and_deviation(&radii);
    assert!((mean - 0.01).abs() < 0.0005, "mean curl radius {mean}");
    assert!(
        (deviation / mean - 0.2).abs() < 0.04,
        "relative spread {}",
        deviation / mean
    );
    let radii = curls("0");
    let (mean, deviation) = mean_and_deviation(&radii);
    assert!((mean - 0.01).abs() < 0.0005, "mean curl radius {mean}");
    assert!(
        deviation / mean < 0.02,
        "relative spread {}",
        deviation / mean
    );
    // Without --curl the same hair hangs straight.
    let straight = head(
        &dir,
        &[
            "--strands",
            "200",
            "--length",
            "0.6",
            "--segment-length",
            "0.0025",
            "--clump-size",
            "0",
        ],
    );
    let radii = hanging_curl_radii(&straight);
    let (mean, _) = mean_and_deviation(&radii);
    assert!(mean < 0.001, "straight hair coils by {mean} m");
}

#[test]
fn the_same_seed_gives_the_same_file_for_any_thread_count() {
    let dir = TestDir::new();
    let run = |seed: &str, threads: &str, out: &str| {
        let output = dir
            .command()
            .args([
                "generate",
                "head",
                "-o",
                out,
                "--strands",
                "3000",
                "--seed",
                seed,
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(output.status.success(), "{output:?}");
        std::fs::read(dir.path(out)).unwrap()
    };
    let a = run("7", "1", "a.usda");
    let b = run("7", "3", "b.usda");
    assert!(a == b, "seed 7 on 1 and 3 threads differ");
    let c = run("8", "2", "c.usda");
    assert!(a != c, "seeds 7 and 8 give the same groom");
}

#[test]
fn bad_head_parameters_exit_2_with_one_line() {
    let dir = TestDir::new();
    for (args, expect) in [
        (
            vec!["head", "--curl-radius", "0.5"],
            "'curl_radius': 0.5 is outside its range",
        ),
        (vec!["head", "--clump-strength", "1.5"], "'clump_strength'"),
        (vec!["head", "--hairline", "60,100,200"], "'hairline'"),
        (
            vec!["head", "--curl", "--segment-length", "0.02"],
            "'segment_length'",
        ),
        (
            vec!["straight", "--curl"],
            "'curl': applies to layout = \"head\" only",
        ),
        (vec!["head", "--drape", "10"], "'drape': does not apply"),
    ] {
        let mut all = vec!["generate"];
        all.extend(args.iter().copied());
        all.extend(["-o", "bad.usda"]);
        let stderr = dir.run_fail(&all, 2);
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(!dir.path("bad.usda").exists());
    }
    let stderr = dir.run_fail(
        &[
            "generate",
            "head",
            "--scalp-mesh",
            "no_such.obj",
            "-o",
            "bad.usda",
        ],
        2,
    );
    assert!(stderr.contains("no_such.obj"), "{stderr}");
}

#[test]
fn a_timeline_generates_a_head_on_a_mesh_next_to_it() {
    let dir = TestDir::new();
    std::fs::copy(sample("head.obj"), dir.path("head.obj")).unwrap();
    let timeline = |extra: &str| {
        format!(
            "[groom]\ngenerate = {{ layout = \"head\", strands = 40, length = 0.1, \
             segment_length = 0.01, scalp_mesh = \"head.obj\", curl = true, curl_pitch = 0.04{extra} }}\n\
             [[stage]]\nkind = \"settle\"\nduration = 0.01\n[[export]]\npath = \"rest.usda\"\nwhat = \"rest\"\n"
        )
    };
    std::fs::write(dir.path("t.toml"), timeline("")).unwrap();
    dir.run_ok(&["validate", "t.toml"]);
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let rest = strands(&dir.path("rest.usda"));
    assert_eq!(rest.len(), 40);
    // Out of range, and a key another layout would take: refused by validate.
    std::fs::write(dir.path("t.toml"), timeline(", clump_strength = 2.0")).unwrap();
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert!(stderr.contains("clump_strength"), "{stderr}");
    std::fs::write(dir.path("t.toml"), timeline(", drape = 5.0")).unwrap();
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert!(stderr.contains("drape"), "{stderr}");
}
