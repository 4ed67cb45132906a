//! Hostile input, third round (issue 37): grids sized from input data are
//! bounded before they are allocated, special files are refused, the
//! Python module's limits, `validate` without simulation, short error
//! lines.

use crate::util::TestDir;
use std::process::Command;

/// Runs groombake in `dir` under a 2 GB address-space limit (an unbounded
/// allocation fails fast instead of swapping): exit code and stderr.
fn run_limited(dir: &TestDir, args: &[&str]) -> (Option<i32>, String) {
    let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
    let output = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 2000000; exec '{}' {}",
            env!("CARGO_BIN_EXE_groombake"),
            quoted.join(" ")
        ))
        .current_dir(dir.root())
        .output()
        .unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

fn assert_one_line(stderr: &str) {
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line:\n{stderr}"
    );
    assert!(stderr.starts_with("groombake: "), "{stderr}");
}

/// A timeline of three swatch strands with one mesh collider `mesh`.
fn collider_timeline(mesh: &str) -> String {
    format!(
        r#"
[groom]
generate = {{ strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03 }}
[[collider]]
name = "m"
shape = {{ mesh = {{ path = "{mesh}" }} }}
[[stage]]
kind = "settle"
duration = 0.05
"#
    )
}

/// The sample head with one coordinate of its first vertex replaced.
fn head_with_first_vertex(y: &str) -> String {
    let head = std::fs::read_to_string(crate::util::sample("head.obj")).unwrap();
    let mut done = false;
    head.lines()
        .map(|line| {
            if !done && line.starts_with("v ") {
                done = true;
                format!("v 0 {y} 0")
            } else {
                line.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_collider_vertex_near_f32_max_is_refused_naming_the_file_and_value() {
    let dir = TestDir::new();
    std::fs::write(dir.path("far.obj"), head_with_first_vertex("3.2e38")).unwrap();
    std::fs::write(dir.path("t.toml"), collider_timeline("far.obj")).unwrap();
    for command in ["validate", "bake"] {
        let (code, stderr) = run_limited(&dir, &[command, "t.toml"]);
        assert_eq!(code, Some(2), "{command}: {stderr}");
        assert!(
            stderr.contains("far.obj") && stderr.contains("y = 3.2e38"),
            "{stderr}"
        );
        assert_one_line(&stderr);
    }
}

#[test]
fn a_collider_grid_over_the_budget_is_refused_before_it_is_built() {
    // Two thousand triangles each across the whole mesh: every one lists
    // every cell of its plane (about 60 thousand), 120 million in all.
    let dir = TestDir::new();
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.001\n");
    for _ in 0..2000 {
        obj.push_str("f 1 2 3\nf 2 4 3\n");
    }
    std::fs::write(dir.path("wide.obj"), obj).unwrap();
    std::fs::write(dir.path("t.toml"), collider_timeline("wide.obj")).unwrap();
    let (code, stderr) = run_limited(&dir, &["validate", "t.toml"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("wide.obj") && stderr.contains("cell entries"),
        "{stderr}"
    );
    assert_one_line(&stderr);
}

// --- Special files -----------------------------------------------------------

/// Runs groombake in `dir` with a 60 s limit (a blocking read fails the
/// test instead of hanging it) and the 2 GB address-space limit.
fn run_bounded(dir: &TestDir, args: &[&str]) -> (Option<i32>, String) {
    let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
    let output = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 2000000; exec timeout 60 '{}' {}",
            env!("CARGO_BIN_EXE_groombake"),
            quoted.join(" ")
        ))
        .current_dir(dir.root())
        .output()
        .unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn devices_fifos_and_directories_are_refused_with_their_kind() {
    let dir = TestDir::new();
    for ext in ["abc", "hair", "glb", "usdc", "usda", "obj", "data"] {
        let name = format!("zero.{ext}");
        std::os::unix::fs::symlink("/dev/zero", dir.path(&name)).unwrap();
        let (code, stderr) = run_bounded(&dir, &["inspect", &name]);
        assert_eq!(code, Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains(&name) && stderr.contains("a character device"),
            "{stderr}"
        );
        assert_one_line(&stderr);
    }
    std::os::unix::fs::symlink("/dev/urandom", dir.path("random.usda")).unwrap();
    let (code, stderr) = run_bounded(&dir, &["convert", "random.usda", "out.abc"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("a character device"), "{stderr}");
    assert!(!dir.path("out.abc").exists());

    let fifo = dir.path("pipe.obj");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let (code, stderr) = run_bounded(&dir, &["inspect", "pipe.obj"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("pipe.obj") && stderr.contains("FIFO"),
        "{stderr}"
    );

    std::fs::create_dir(dir.path("folder.usda")).unwrap();
    let (code, stderr) = run_bounded(&dir, &["inspect", "folder.usda"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("a directory"), "{stderr}");
}

#[test]
fn a_timeline_or_its_inputs_on_a_device_are_refused_with_their_kind() {
    let dir = TestDir::new();
    std::os::unix::fs::symlink("/dev/zero", dir.path("zero.toml")).unwrap();
    let (code, stderr) = run_bounded(&dir, &["validate", "zero.toml"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("zero.toml") && stderr.contains("a character device"),
        "{stderr}"
    );
    assert_one_line(&stderr);

    std::os::unix::fs::symlink("/dev/zero", dir.path("zero.glb")).unwrap();
    let made = Command::new("mkfifo")
        .arg(dir.path("pipe.obj"))
        .status()
        .unwrap();
    assert!(made.success());
    for mesh in ["zero.glb", "pipe.obj"] {
        std::fs::write(dir.path("t.toml"), collider_timeline(mesh)).unwrap();
        let (code, stderr) = run_bounded(&dir, &["validate", "t.toml"]);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(
            stderr.contains("t.toml:")
                && stderr.contains(mesh)
                && stderr.contains("not a regular file"),
            "{stderr}"
        );
        let groom = format!(
            "[groom]\nsource = \"{mesh}\"\n[[stage]]\nkind = \"settle\"\nduration = 0.05\n"
        );
        std::fs::write(dir.path("g.toml"), groom).unwrap();
        let (code, stderr) = run_bounded(&dir, &["bake", "g.toml"]);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(stderr.contains("not a regular file"), "{stderr}");
    }
}

// --- validate simulates nothing -----------------------------------------------

#[test]
fn validate_does_not_run_the_sag_free_probe() {
    // `samples/wind.toml` (10,199 strands, sag-free on) once validated in
    // 11.4 s against 0.03 s with `sag_free = false`: the probe simulated
    // 0.5 s of every long strand. Without it the two take about as long.
    let dir = TestDir::new();
    let wind = std::fs::read_to_string(crate::util::sample("wind.toml")).unwrap();
    std::fs::write(dir.path("on.toml"), &wind).unwrap();
    std::fs::write(
        dir.path("off.toml"),
        format!("{wind}\n[solver]\nsag_free = false\n"),
    )
    .unwrap();
    let time = |name: &str| {
        let started = std::time::Instant::now();
        dir.run_ok(&["validate", name]);
        started.elapsed().as_secs_f64()
    };
    let (mut on, mut off) = (f64::MAX, f64::MAX);
    for _ in 0..3 {
        on = on.min(time("on.toml"));
        off = off.min(time("off.toml"));
    }
    eprintln!("validate wind.toml: sag-free on {on:.3} s, off {off:.3} s");
    assert!(on < 3.0 * off, "on {on:.3} s, off {off:.3} s");
}

// --- Short error lines --------------------------------------------------------

#[test]
fn a_megabyte_token_is_shortened_with_its_length_in_a_line_of_at_most_300_characters() {
    let dir = TestDir::new();
    let token = "9".repeat(500_000) + &"x".repeat(500_000);
    std::fs::write(
        dir.path("long.obj"),
        format!("v 0 {token} 0\nv 0 1 0\nl 1 2\n"),
    )
    .unwrap();
    let stderr = dir.run_fail(&["inspect", "long.obj"], 2);
    assert_one_line(&stderr);
    let line = stderr.trim_end();
    assert!(
        line.chars().count() <= 300 + "groombake: ".len(),
        "{} characters",
        line.len()
    );
    assert!(
        line.contains("long.obj:1") && line.contains("(1000000 bytes)"),
        "{line}"
    );
    std::fs::write(
        dir.path("t.toml"),
        format!(
            "[groom]\n{} = 1\n[[stage]]\nkind = \"settle\"\nduration = 0.1\n",
            "k".repeat(1_000_000)
        ),
    )
    .unwrap();
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert_one_line(&stderr);
    assert!(
        stderr.trim_end().chars().count() <= 311,
        "{} characters",
        stderr.len()
    );
    assert!(stderr.contains("t.toml:2:1"), "{stderr}");
}

// --- Every number in its range, export paths ----------------------------------

/// A timeline with every section the hostile values go into; `{X}`
/// placeholders take them.
const FULL: &str = r#"seed = 1
[groom]
generate = { strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03, swatch_width = {SW} }
translate = [{TX}, 0.0, 0.0]
guides = { count = {GC} }
[material]
youngs_modulus = {E}
[solver]
gravity = [0.0, {G}, 0.0]
[[collider]]
name = "floor"
shape = { half_space = { normal = [0.0, 1.0, 0.0] } }
friction = {MU}
motion = [{ t = 0.0 }, { t = {T1}, translation = [0.0, 0.0, 0.0] }]
[[stage]]
kind = "settle"
duration = 0.05
[[stage]]
kind = "wind"
duration = 0.05
wind = { direction = {DIR}, schedule = [{ frame = 1, v = 0.5 }], head = { center = [0.0, 0.0, 0.0], radii = [0.08, 0.1, 0.09] } }
[[export]]
path = "{PATH}"
what = "final"
"#;

fn full(changes: &[(&str, &str)]) -> String {
    let defaults = [
        ("{SW}", "0.04"),
        ("{TX}", "0.0"),
        ("{GC}", "2"),
        ("{E}", "3.5e9"),
        ("{G}", "-9.8"),
        ("{MU}", "0.3"),
        ("{T1}", "1.0"),
        ("{DIR}", "178.0"),
        ("{PATH}", "out/final.usda"),
    ];
    let mut text = FULL.to_string();
    for (key, default) in defaults {
        let value = changes
            .iter()
            .find(|(k, _)| *k == key)
            .map_or(default, |(_, v)| *v);
        text = text.replace(key, value);
    }
    text
}

/// `file:line:column` of the first occurrence of `needle` in `text`.
fn place_of(text: &str, needle: &str) -> String {
    let at = text.find(needle).unwrap();
    let line = text[..at].matches('\n').count() + 1;
    let column = at - text[..at].rfind('\n').map_or(0, |p| p + 1) + 1;
    format!("t.toml:{line}:{column}")
}

#[test]
fn hostile_numbers_are_refused_by_validate_at_the_key() {
    let dir = TestDir::new();
    let good = full(&[]);
    std::fs::write(dir.path("t.toml"), &good).unwrap();
    dir.run_ok(&["validate", "t.toml"]);
    let cases: &[(&str, &str, &str)] = &[
        ("{TX}", "1e30", "1e30, 0.0"),
        ("{SW}", "-0.04", "-0.04"),
        ("{SW}", "1e30", "1e30 }"),
        ("{E}", "1e30", "1e30"),
        ("{MU}", "1e30", "1e30"),
        ("{DIR}", "1e30", "1e30"),
        ("{GC}", "1000000000000", "1000000000000"),
        ("{G}", "-1e30", "-1e30"),
        ("{T1}", "4.2e-45", "4.2e-45"),
    ];
    for &(key, value, needle) in cases {
        let text = full(&[(key, value)]);
        std::fs::write(dir.path("t.toml"), &text).unwrap();
        let stderr = dir.run_fail(&["validate", "t.toml"], 2);
        assert_one_line(&stderr);
        let place = place_of(&text, needle);
        assert!(
            stderr.contains(&format!("{place}: ")),
            "{key} = {value}: want {place}: {stderr}"
        );
    }
    // Non-finite values that were pointed at 1:1.
    // (The place of the array that holds the value.)
    for (key, value, needle) in [("{TX}", "nan", "[nan, 0.0"), ("{G}", "inf", "[0.0, inf")] {
        let text = full(&[(key, value)]);
        std::fs::write(dir.path("t.toml"), &text).unwrap();
        let stderr = dir.run_fail(&["validate", "t.toml"], 2);
        let place = place_of(&text, needle);
        assert!(
            stderr.contains(&format!("{place}: ")),
            "{key} = {value}: want {place}: {stderr}"
        );
    }
}

#[test]
fn export_paths_that_cannot_name_a_file_are_refused_by_validate_at_the_key() {
    let dir = TestDir::new();
    std::fs::create_dir(dir.path("folder.usda")).unwrap();
    for (path, what) in [
        ("out/final.usda/", "ends with '/'"),
        ("out/a\\u0000b.usda", "NUL"),
        ("folder.usda", "folder"),
        ("out/..", "folder"),
    ] {
        let text = full(&[("{PATH}", path)]);
        std::fs::write(dir.path("t.toml"), &text).unwrap();
        for command in ["validate", "bake"] {
            let stderr = dir.run_fail(&[command, "t.toml"], 2);
            assert_one_line(&stderr);
            assert!(stderr.contains(what), "{path}: {stderr}");
            if path != "folder.usda" {
                let place = place_of(&text, &format!("\"{path}\""));
                assert!(stderr.contains(&place), "{path}: want {place}: {stderr}");
            }
        }
        assert!(!dir.path("out").exists(), "{path}: the bake started");
    }
}

// --- Temporaries of convert and batch -----------------------------------------

/// Every file under `dir` whose name marks a temporary.
fn temporaries_under(dir: &std::path::Path) -> Vec<String> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap().flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() {
                stack.push(path);
            } else if name.ends_with(".tmp") || name.starts_with(".groombake-") {
                found.push(path.display().to_string());
            }
        }
    }
    found
}

#[test]
fn a_convert_past_the_file_size_limit_leaves_no_temporary_and_a_later_one_removes_a_killed_ones() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "g.hair",
        "--strands",
        "200",
        "--length",
        "0.2",
    ]);
    // A file size limit (SIGXFSZ, not ignored by the shell) once killed the
    // convert and left `.x.usda.PID.tmp`.
    let output = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -f 8; exec '{}' convert g.hair x.usda",
            env!("CARGO_BIN_EXE_groombake")
        ))
        .current_dir(dir.root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("x.usda") && stderr.contains("File too large"),
        "{stderr}"
    );
    assert_eq!(temporaries_under(dir.root()), Vec::<String>::new());
    // One a killed convert left (a process id no process has) goes with
    // the next convert to that file; another process's stays.
    let stale = dir.path(".x.usda.4194303.tmp");
    std::fs::write(&stale, b"partial").unwrap();
    let live = dir.path(&format!(".x.usda.{}.tmp", std::process::id()));
    std::fs::write(&live, b"partial").unwrap();
    dir.run_ok(&["convert", "g.hair", "x.usda"]);
    assert!(!stale.exists() && live.exists());
}

#[test]
fn an_interrupted_batch_writes_its_report_with_each_jobs_state() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "g.hair",
        "--strands",
        "50",
        "--length",
        "0.2",
    ]);
    // Long enough that the signal comes while the first job bakes.
    std::fs::write(
        dir.path("long.toml"),
        "[groom]\nsource = \"g.hair\"\n[[stage]]\nkind = \"settle\"\nduration = 600.0\n\
         [[export]]\npath = \"final.usda\"\nwhat = \"final\"\n",
    )
    .unwrap();
    std::fs::write(
        dir.path("m.toml"),
        "out = \"o\"\n[[job]]\nname = \"a\"\ntimeline = \"long.toml\"\n\
         [[job]]\nname = \"b\"\ntimeline = \"long.toml\"\n",
    )
    .unwrap();
    let child = dir
        .command()
        .args(["batch", "m.toml", "--jobs", "1", "-q"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the first job's folder exists, then a moment into its bake.
    let started = std::time::Instant::now();
    while !dir.path("o/a").exists() {
        assert!(started.elapsed().as_secs() < 60, "the batch did not start");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-TERM", &pid])
        .status()
        .unwrap()
        .success());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(128 + 15), "{stderr}");
    assert!(stderr.contains("stopped by signal 15"), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("o/batch_report.json")).unwrap()).unwrap();
    let states: Vec<&str> = report["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["status"].as_str().unwrap())
        .collect();
    assert_eq!(states, ["interrupted", "interrupted"], "{report}");
    assert!(report["jobs"][1]["error"]
        .as_str()
        .unwrap()
        .contains("not started"));
    assert!(dir.path("o/batch_report.html").is_file());
    assert_eq!(temporaries_under(dir.root()), Vec::<String>::new());
    assert!(!dir.path("o/a/final.usda").exists());
}

// --- Primvars in linear time ---------------------------------------------------

/// A usda of one curve with `n` constant primvars.
fn usda_with_primvars(n: usize) -> String {
    let mut text = String::from(
        "#usda 1.0\ndef BasisCurves \"hair\" {\n    uniform token type = \"linear\"\n    \
         int[] curveVertexCounts = [2]\n    point3f[] points = [(0, 0, 0), (0, 1, 0)]\n",
    );
    for i in 0..n {
        text.push_str(&format!(
            "    float[] primvars:p{i} = [{i}] (\n        interpolation = \"constant\"\n    )\n"
        ));
    }
    text.push_str("}\n");
    text
}

#[test]
fn a_hundred_thousand_primvars_are_read_in_linear_time() {
    // 5k, 10k, 20k primvars took 0.14, 0.72, 2.40 s (quadratic); the ratio
    // of a run 4x the size, minimum of interleaved runs, tells linear (4)
    // from quadratic (16) without a wall-clock limit.
    let dir = TestDir::new();
    std::fs::write(dir.path("small.usda"), usda_with_primvars(25_000)).unwrap();
    std::fs::write(dir.path("large.usda"), usda_with_primvars(100_000)).unwrap();
    // CPU seconds (user + system, from bash's `time`): the wall clock of a
    // loaded machine says little.
    let time = |name: &str| {
        let output = Command::new("bash")
            .arg("-c")
            .arg(format!(
                "TIMEFORMAT='%U %S'; {{ time '{}' inspect {name} --json > out.json; }} 2> cpu.txt",
                env!("CARGO_BIN_EXE_groombake")
            ))
            .current_dir(dir.root())
            .output()
            .unwrap();
        assert!(output.status.success(), "{output:?}");
        let cpu: f64 = std::fs::read_to_string(dir.path("cpu.txt"))
            .unwrap()
            .split_whitespace()
            .map(|t| t.parse::<f64>().unwrap())
            .sum();
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path("out.json")).unwrap()).unwrap();
        (cpu, json)
    };
    let (mut small, mut large) = (f64::MAX, f64::MAX);
    for _ in 0..2 {
        let (t, json) = time("small.usda");
        small = small.min(t);
        let (t, large_json) = time("large.usda");
        large = large.min(t);
        assert_eq!(json["strands"], 1);
        assert!(large_json.to_string().contains("\"p99999\""));
    }
    eprintln!(
        "25k primvars {small:.3} s, 100k {large:.3} s: {:.1}x",
        large / small
    );
    assert!(large < 8.0 * small, "25k {small:.3} s, 100k {large:.3} s");
}

// --- No silent loss in convert --------------------------------------------------

const TWO_STRANDS: &str = "#usda 1.0\ndef BasisCurves \"hair\" {\n    uniform token type = \"linear\"\n    \
    int[] curveVertexCounts = [2, 2, 2, 2]\n    \
    point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0), (2, 0, 0), (2, 1, 0), (3, 0, 0), (3, 1, 0)]\n";

#[test]
fn per_vertex_root_uv_survives_a_convert_to_abc() {
    let dir = TestDir::new();
    let text = format!(
        "{TWO_STRANDS}    texCoord2f[] primvars:st = [(0, 0), (0.1, 0.1), (0.2, 0.2), (0.3, 0.3), (0.4, 0.4), (0.5, 0.5), (0.6, 0.6), (0.7, 0.7)] (\n        interpolation = \"vertex\"\n    )\n}}\n"
    );
    std::fs::write(dir.path("uv.usda"), text).unwrap();
    dir.run_ok(&["convert", "uv.usda", "uv.abc"]);
    let json = dir.inspect("uv.abc");
    let root_uv = json["attributes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == "root_uv");
    assert!(
        root_uv.is_some_and(|a| a["scope"] == "vertex" && a["count"] == 8),
        "{json}"
    );
}

#[test]
fn interleaved_guides_and_a_base_pose_off_frame_0_are_said_and_refused_under_strict() {
    let dir = TestDir::new();
    let guides = format!(
        "{TWO_STRANDS}    uniform int[] primvars:groom_guide = [0, 1, 0, 1] (\n        interpolation = \"uniform\"\n    )\n}}\n"
    );
    std::fs::write(dir.path("g.usda"), guides).unwrap();
    for out in ["g.glb", "g2.usda"] {
        let output = dir.run_ok(&["convert", "g.usda", out]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains("interleaved"), "{out}: {stderr}");
        let stderr = dir.run_fail(&["convert", "g.usda", out, "--strict"], 2);
        assert!(stderr.contains("interleaved"), "{stderr}");
    }
    let animated = TWO_STRANDS.replace(
        "point3f[] points = [",
        "point3f[] points.timeSamples = {\n        1: [(0, 0, 5), (0, 1, 5), (1, 0, 5), (1, 1, 5), (2, 0, 5), (2, 1, 5), (3, 0, 5), (3, 1, 5)],\n    }\n    point3f[] points = [",
    ) + "}\n";
    std::fs::write(dir.path("a.usda"), animated).unwrap();
    let output = dir.run_ok(&["convert", "a.usda", "a.abc"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("base pose differs from frame 0"),
        "{stderr}"
    );
    dir.run_fail(&["convert", "a.usda", "a2.abc", "--strict"], 2);
    assert!(!dir.path("a2.abc").exists());
}
