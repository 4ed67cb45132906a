//! Hostile input and hostile moments (issues 11 and 12, bake side): the
//! resource budget, validation before any simulation, outputs compared by
//! canonical path, non-finite values refused after unit conversion,
//! crash-consistent outputs under signals and SIGKILL, the physical sanity
//! watchdog, one-line messages and the report written on failure too.

use crate::util::TestDir;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A small timeline: three swatch strands, one short stage, and `extra`.
fn timeline(extra: &str) -> String {
    format!(
        r#"
[groom]
generate = {{ strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03 }}
[[stage]]
kind = "settle"
duration = 0.05
{extra}"#
    )
}

const FINAL_USDA: &str = "[[export]]\npath = \"final.usda\"\nwhat = \"final\"\n";

/// Every file name under `dir`, recursively, relative to it.
fn files_under(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.push(path.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

/// Temporaries a bake may leave: staged outputs and atomic-file temporaries.
fn temporaries(dir: &Path) -> Vec<String> {
    files_under(dir)
        .into_iter()
        .filter(|f| f.contains(".groombake-") || f.ends_with(".tmp"))
        .collect()
}

fn assert_one_line(stderr: &str) {
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line:\n{stderr}"
    );
    assert!(stderr.starts_with("groombake: "), "{stderr}");
}

// --- The resource budget ---------------------------------------------------

/// Runs groombake through `sh` after the shell commands `setup` (limits,
/// traps), in the test's folder: exit code and standard error.
fn run_in_shell(dir: &TestDir, setup: &str, args: &str) -> (Option<i32>, String) {
    let output = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "{setup}; exec '{}' {args}",
            env!("CARGO_BIN_EXE_groombake")
        ))
        .current_dir(dir.root())
        .output()
        .unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// Runs groombake with its address space limited to 2 GB: a run that tried
/// to allocate the groom would abort instead of exiting 2.
fn run_limited(dir: &TestDir, args: &str) -> (Option<i32>, String) {
    run_in_shell(dir, "ulimit -v 2000000", args)
}

#[test]
fn budget_refuses_ten_million_strands_of_ten_thousand_segments_without_allocating() {
    let dir = TestDir::new();
    let huge = r#"
[groom]
generate = { strands = 10000000, length = 1.0, segment_length = 0.0001 }
[[stage]]
kind = "settle"
duration = 0.01
"#;
    std::fs::write(dir.path("huge.toml"), huge).unwrap();
    let (code, stderr) = run_limited(&dir, "validate huge.toml");
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("vertices"), "{stderr}");
    assert_one_line(&stderr);
    let (code, stderr) = run_limited(
        &dir,
        "generate straight -o g.usda --strands 10000000 --length 1 --segment-length 0.0001",
    );
    assert_eq!(code, Some(2), "{stderr}");
    let (code, stderr) = run_limited(&dir, "generate straight -o g.usda --strands 10000000");
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("vertices"), "{stderr}");
    assert!(!dir.path("g.usda").exists());
}

#[test]
fn budget_bounds_every_rate_that_multiplies_work() {
    let dir = TestDir::new();
    let cases = [
        // Wind model frames: a billion a second.
        (
            "wind_fps",
            r#"
[groom]
generate = { strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03 }
[[stage]]
kind = "wind"
duration = 0.1
wind = { direction = 178.0, fps = 1e9, schedule = [{ frame = 1, v = 0.5 }], head = { center = [0.0, 0.0, 0.0], radii = [0.1, 0.1, 0.1] } }
"#
            .to_string(),
        ),
        (
            "tiny_dt",
            format!("{}\n[solver]\ndt = 1e-300\n", timeline("")),
        ),
        // Each stage under a day, together billions of steps.
        (
            "total_steps",
            format!(
                "[solver]\ndt = 1e-6\n{}",
                timeline("").replace("duration = 0.05", "duration = 80000.0")
            ),
        ),
        // Animated frames times vertices: more bytes than the budget.
        (
            "frames",
            r#"
[groom]
generate = { strands = 1000000, layout = "swatch", length = 0.1, segment_length = 0.01 }
[solver]
dt = 1e-5
[[stage]]
kind = "settle"
duration = 1.0
[[export]]
path = "a.abc"
what = "animated"
fps = 100000.0
"#
            .to_string(),
        ),
    ];
    for (name, text) in cases {
        let file = format!("{name}.toml");
        std::fs::write(dir.path(&file), text).unwrap();
        let started = Instant::now();
        let stderr = dir.run_fail(&["validate", &file], 2);
        assert_one_line(&stderr);
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "{name}: validate took {:?}",
            started.elapsed()
        );
    }
}

#[test]
fn threads_and_units_outside_their_range_are_usage_errors() {
    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), timeline(FINAL_USDA)).unwrap();
    let stderr = dir.run_fail(&["bake", "t.toml", "--threads", "100000"], 2);
    assert_one_line(&stderr);
    assert!(stderr.contains("--threads"), "{stderr}");
    assert!(!dir.path("final.usda").exists());
    dir.run_ok(&["generate", "swatch", "-o", "g.usda", "--strands", "2"]);
    for units in ["1e-300", "1e300"] {
        let stderr = dir.run_fail(&["convert", "g.usda", "out.abc", "--units", units], 2);
        assert_one_line(&stderr);
        assert!(!dir.path("out.abc").exists());
    }
}

// --- Validation before any simulation ---------------------------------------

/// A timeline whose first export is fine and whose problem comes later:
/// exit 2 and nothing written shows it was found before the simulation.
fn assert_refused_before_simulation(dir: &TestDir, text: &str, args: &[&str], what: &str) {
    std::fs::write(dir.path("t.toml"), text).unwrap();
    let mut all = vec!["bake", "t.toml", "-q"];
    all.extend_from_slice(args);
    let stderr = dir.run_fail(&all, 2);
    assert_one_line(&stderr);
    assert!(stderr.contains(what), "expected {what:?} in {stderr}");
    assert!(!stderr.contains("File exists"), "{stderr}");
    assert!(!dir.path("first.usda").exists(), "an output was written");
    assert!(temporaries(dir.root()).is_empty());
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert_one_line(&stderr);
}

#[test]
fn bad_outputs_and_values_are_found_before_simulating() {
    let dir = TestDir::new();
    let first = "[[export]]\npath = \"first.usda\"\nwhat = \"final\"\n";
    std::fs::write(dir.path("afile"), "not a folder").unwrap();
    // A folder of the export path is a file.
    let text = timeline(&format!(
        "{first}[[export]]\npath = \"afile/sub/x.usda\"\nwhat = \"final\"\n"
    ));
    assert_refused_before_simulation(&dir, &text, &[], "is a file, not a folder");
    // An export path that is a folder.
    std::fs::create_dir(dir.path("adir.usda")).unwrap();
    let text = timeline(&format!(
        "{first}[[export]]\npath = \"adir.usda\"\nwhat = \"final\"\n"
    ));
    assert_refused_before_simulation(&dir, &text, &[], "is a folder");
    // An unknown preview colour.
    let text = timeline(&format!(
        "{first}[preview]\nsheet = \"s.png\"\ncolor = \"bond_hydrogne\"\n"
    ));
    assert_refused_before_simulation(&dir, &text, &[], "bond_hydrogne");
    // Rod radius inf, rod axis zero.
    for rod in ["{ radius = inf }", "{ axis = [0.0, 0.0, 0.0] }"] {
        let text = format!(
            "{}\n{first}",
            timeline("")
                .replace("\"settle\"", "\"perm\"")
                .replace("duration = 0.05", &format!("duration = 0.05\nrod = {rod}"))
        );
        assert_refused_before_simulation(&dir, &text, &[], "rod");
    }
    // An unwritable report (under /proc nothing can be created).
    let text = timeline(first);
    std::fs::write(dir.path("t.toml"), &text).unwrap();
    let stderr = dir.run_fail(
        &["bake", "t.toml", "-q", "--report", "/proc/groombake/r.json"],
        2,
    );
    assert_one_line(&stderr);
    assert!(!dir.path("first.usda").exists());
    // A report whose folder is a file.
    let stderr = dir.run_fail(&["bake", "t.toml", "-q", "--report", "afile/r.json"], 2);
    assert!(stderr.contains("is a file, not a folder"), "{stderr}");
    assert!(!dir.path("first.usda").exists());
}

#[test]
fn an_empty_groom_is_bad_input() {
    let dir = TestDir::new();
    std::fs::write(dir.path("empty.obj"), "# no curves\n").unwrap();
    let text = timeline(FINAL_USDA).replace(
        r#"generate = { strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03 }"#,
        r#"source = "empty.obj""#,
    );
    std::fs::write(dir.path("t.toml"), text).unwrap();
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert!(stderr.contains("no strands"), "{stderr}");
    dir.run_fail(&["bake", "t.toml", "-q"], 2);
    assert!(!dir.path("final.usda").exists());
}

#[test]
fn unknown_output_extension_is_refused_before_reading_the_input() {
    let dir = TestDir::new();
    for out in ["out.xyz", "out.", "out"] {
        let stderr = dir.run_fail(&["convert", "no_such_input.hair", out], 2);
        assert_one_line(&stderr);
        assert!(stderr.contains(out), "{stderr}");
        assert!(
            !stderr.contains("no_such_input"),
            "read the input: {stderr}"
        );
        assert!(!stderr.contains("'.'"), "{stderr}");
        let stderr = dir.run_fail(&["generate", "straight", "-o", out], 2);
        assert!(!stderr.contains("'.'"), "{stderr}");
    }
    let stderr = dir.run_fail(&["convert", "no_such_input.hair", "out."], 2);
    assert!(stderr.contains("no file extension"), "{stderr}");
    // An output that cannot be written, likewise, with the OS's words once.
    std::fs::write(dir.path("afile"), "not a folder").unwrap();
    let stderr = dir.run_fail(&["convert", "no_such_input.hair", "afile/out.usda"], 2);
    assert!(stderr.contains("is a file, not a folder"), "{stderr}");
    let stderr = dir.run_fail(&["convert", "no_such_input.hair", "/proc/x/out.usda"], 2);
    assert_one_line(&stderr);
    assert_eq!(stderr.matches("os error").count(), 1, "{stderr}");
}

#[test]
fn a_timeline_without_exports_validates_with_a_warning() {
    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), timeline("")).unwrap();
    let output = dir.run_ok(&["validate", "t.toml"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("warning") && stderr.contains("[[export]]"),
        "{stderr}"
    );
    let output = dir.run_ok(&["bake", "t.toml", "-q"]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("[[export]]"));
}

#[test]
fn outputs_are_compared_by_canonical_path() {
    let dir = TestDir::new();
    std::fs::create_dir(dir.path("sub")).unwrap();
    let absolute = dir.path("final.usda").display().to_string();
    for other in ["./final.usda", "sub/../final.usda", absolute.as_str()] {
        let text = timeline(&format!(
            "{FINAL_USDA}[[export]]\npath = \"{other}\"\nwhat = \"rest\"\n"
        ));
        std::fs::write(dir.path("t.toml"), text).unwrap();
        let stderr = dir.run_fail(&["bake", "t.toml", "-q"], 2);
        assert_one_line(&stderr);
        assert!(stderr.contains("same file"), "{other}: {stderr}");
        dir.run_fail(&["validate", "t.toml"], 2);
        assert!(!dir.path("final.usda").exists());
    }
    // The report may not overwrite an export.
    std::fs::write(dir.path("t.toml"), timeline(FINAL_USDA)).unwrap();
    for report in ["final.usda", "./sub/../final.usda"] {
        let stderr = dir.run_fail(&["bake", "t.toml", "-q", "--report", report], 2);
        assert!(stderr.contains("report"), "{stderr}");
        assert!(!dir.path("final.usda").exists());
    }
}

// --- Non-finite values after unit conversion ----------------------------------

#[test]
fn no_output_holds_a_value_that_overflows_in_the_files_units() {
    let dir = TestDir::new();
    // 1.7e38 m is a finite f32; in centimetres it is infinite.
    std::fs::write(
        dir.path("big.obj"),
        "v 1.7e38 0 0\nv 1.7e38 1 0\nv 1.7e38 2 0\nl 1 2 3\n",
    )
    .unwrap();
    let stderr = dir.run_fail(
        &[
            "convert",
            "big.obj",
            "big.abc",
            "--source-units",
            "m",
            "--units",
            "cm",
        ],
        2,
    );
    // Bad input, found before writing (it was exit 1, from the exporter).
    assert!(stderr.contains("not finite"), "{stderr}");
    assert!(stderr.contains("32-bit floats"), "{stderr}");
    assert!(!dir.path("big.abc").exists());
    let text = timeline(
        "[[export]]\npath = \"anim.abc\"\nwhat = \"animated\"\nunits = \"cm\"\n\
         [[export]]\npath = \"final.abc\"\nwhat = \"final\"\nunits = \"cm\"\n",
    )
    .replace("[[stage]]", "translate = [1.7e38, 0.0, 0.0]\n[[stage]]");
    std::fs::write(dir.path("t.toml"), text).unwrap();
    // Now refused before anything runs: a translation past 10 km is
    // outside its range (limits.rs).
    let stderr = dir.run_fail(&["bake", "t.toml", "-q"], 2);
    assert!(
        stderr.contains("groom.translate") && !stderr.contains(".groombake-"),
        "{stderr}"
    );
    assert!(!dir.path("anim.abc").exists() && !dir.path("final.abc").exists());
    assert!(
        temporaries(dir.root()).is_empty(),
        "{:?}",
        files_under(dir.root())
    );
}

// --- Crash-consistent outputs ---------------------------------------------------

/// Four exports (two animated, streamed; two written at the end) of a bake
/// that takes a second or two.
const FOUR_EXPORTS: &str = r#"
seed = 3
[groom]
generate = { strands = 300, layout = "scalp", length = 0.2, segment_length = 0.01 }
[[stage]]
kind = "wet"
duration = 0.4
[[stage]]
kind = "dry"
duration = 0.4
[[export]]
path = "out/anim.abc"
what = "animated"
[[export]]
path = "out/anim.usdc"
what = "animated"
[[export]]
path = "out/final.glb"
what = "final"
[[export]]
path = "out/state.usda"
what = "state"
"#;

const FINALS: [&str; 4] = [
    "out/anim.abc",
    "out/anim.usdc",
    "out/final.glb",
    "out/state.usda",
];

/// A small deterministic stream (SplitMix64) for the kill moments.
fn next_random(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[test]
fn sigkill_at_ten_moments_leaves_no_partial_output_and_nothing_the_next_bake_keeps() {
    let reference = TestDir::new();
    std::fs::write(reference.path("t.toml"), FOUR_EXPORTS).unwrap();
    let started = Instant::now();
    reference.run_ok(&["bake", "t.toml", "-q", "--report", "out/report.json"]);
    let full = started.elapsed();
    let expected: Vec<Vec<u8>> = FINALS
        .iter()
        .map(|f| std::fs::read(reference.path(f)).unwrap())
        .collect();

    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), FOUR_EXPORTS).unwrap();
    let mut seed = 0x5eed_u64;
    for round in 0..10 {
        let at = Duration::from_micros(next_random(&mut seed) % (full.as_micros() as u64 + 1));
        let mut child = dir
            .command()
            .args(["bake", "t.toml", "-q", "--report", "out/report.json"])
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(at);
        let _ = child.kill();
        child.wait().unwrap();
        // Whatever is under a final name is whole: the reference bytes.
        for (name, bytes) in FINALS.iter().zip(&expected) {
            if let Ok(found) = std::fs::read(dir.path(name)) {
                assert!(
                    found == *bytes,
                    "round {round} (killed at {at:?}): {name} is partial"
                );
            }
        }
        // A report exists only beside a complete set.
        if let Ok(text) = std::fs::read_to_string(dir.path("out/report.json")) {
            let report: Value = serde_json::from_str(&text).unwrap();
            for output in report["outputs"].as_array().unwrap() {
                let path = output["path"].as_str().unwrap();
                assert!(dir.root().join(path).exists(), "round {round}: {path}");
            }
        }
    }
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "out/report.json"]);
    assert!(
        temporaries(dir.root()).is_empty(),
        "left behind: {:?}",
        temporaries(dir.root())
    );
    for (name, bytes) in FINALS.iter().zip(&expected) {
        assert!(std::fs::read(dir.path(name)).unwrap() == *bytes, "{name}");
    }
}

#[test]
fn a_signal_stops_the_bake_removes_its_temporaries_and_replaces_no_output() {
    for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        let dir = TestDir::new();
        std::fs::write(dir.path("t.toml"), FOUR_EXPORTS).unwrap();
        std::fs::create_dir(dir.path("out")).unwrap();
        std::fs::write(dir.path("out/final.glb"), b"old").unwrap();
        let child = dir
            .command()
            .args(["bake", "t.toml", "-q", "--report", "r.json"])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until the animated exports are open (staged files exist).
        let deadline = Instant::now() + Duration::from_secs(60);
        while temporaries(dir.root()).is_empty() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(!temporaries(dir.root()).is_empty(), "no staged file seen");
        // SAFETY: signals a child process of this test.
        unsafe { libc::kill(child.id() as libc::pid_t, signal) };
        let output = child.wait_with_output().unwrap();
        assert_eq!(output.status.code(), Some(128 + signal), "signal {signal}");
        assert!(
            temporaries(dir.root()).is_empty(),
            "{:?}",
            files_under(dir.root())
        );
        assert_eq!(std::fs::read(dir.path("out/final.glb")).unwrap(), b"old");
        let report: Value =
            serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
        assert_eq!(report["status"], "interrupted");
        assert_eq!(report["exit_code"], 128 + signal);
    }
}

#[test]
fn a_later_bake_removes_stale_temporaries_of_dead_processes_only() {
    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), timeline(FINAL_USDA)).unwrap();
    // A process that has ended: its id is free (or reused by a live one,
    // which the bake then leaves alone).
    let mut gone = Command::new("true").spawn().unwrap();
    let dead = gone.id();
    gone.wait().unwrap();
    let me = std::process::id();
    let stale = [
        format!(".groombake-{dead}.final.usda"),
        format!("..groombake-{dead}.final.usda.{dead}.tmp"),
        format!(".final.usda.{dead}.tmp"),
    ];
    for name in &stale {
        std::fs::write(dir.path(name), b"partial").unwrap();
    }
    let alive = format!(".groombake-{me}.final.usda");
    std::fs::write(dir.path(&alive), b"in use").unwrap();
    let unrelated = format!(".notes.txt.{dead}.tmp");
    std::fs::write(dir.path(&unrelated), b"mine").unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    for name in &stale {
        assert!(!dir.path(name).exists(), "{name} was kept");
    }
    assert!(
        dir.path(&alive).exists(),
        "a live process's file was removed"
    );
    assert!(
        dir.path(&unrelated).exists(),
        "an unrelated file was removed"
    );
}

/// Runs groombake with no file allowed to grow past `max_bytes`
/// (RLIMIT_FSIZE, in 512-byte blocks, through the shell's `ulimit -f`) and
/// SIGXFSZ ignored, so a write past the limit fails with EFBIG as a write
/// to a full disk fails with ENOSPC: the same failed `write` to the bake.
fn run_with_file_size_limit(dir: &TestDir, max_bytes: u64, args: &str) -> (Option<i32>, String) {
    run_in_shell(
        dir,
        &format!("trap '' XFSZ; ulimit -f {}", max_bytes / 512),
        args,
    )
}

fn file_size(dir: &TestDir, name: &str) -> u64 {
    std::fs::metadata(dir.path(name))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .len()
}

/// Three swatch strands, a small `.usda` export and a contact sheet, which
/// (like the HTML report) is written after the simulation.
const WITH_SHEET: &str = "[[export]]\npath = \"out/final.usda\"\nwhat = \"final\"\n\
                          [preview]\nsheet = \"out/sheet.png\"\nsize = [400, 400]\n";

#[test]
fn disk_full_on_the_sheet_written_last_fails_and_leaves_nothing_partial() {
    let reference = TestDir::new();
    std::fs::write(reference.path("t.toml"), timeline(WITH_SHEET)).unwrap();
    reference.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let (export, sheet, report) = (
        file_size(&reference, "out/final.usda"),
        file_size(&reference, "out/sheet.png"),
        file_size(&reference, "r.json"),
    );
    // Room for the export and the report, not for the sheet.
    let limit = (export.max(report) / 512 + 1) * 512;
    assert!(
        sheet > limit,
        "sheet {sheet} B, export {export} B, report {report} B"
    );

    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), timeline(WITH_SHEET)).unwrap();
    let (code, stderr) = run_with_file_size_limit(&dir, limit, "bake t.toml -q --report r.json");
    assert_eq!(code, Some(1), "{stderr}");
    assert_one_line(&stderr);
    assert!(stderr.contains("out/sheet.png"), "names the file: {stderr}");
    assert!(stderr.contains("File too large"), "says why: {stderr}");
    assert!(
        !stderr.contains(".groombake-"),
        "names a staged file: {stderr}"
    );
    // Nothing under a final name (the export waited for the sheet), no
    // temporary, and a report that says the bake failed.
    assert_eq!(
        files_under(dir.root()),
        vec!["r.json".to_string(), "t.toml".to_string()]
    );
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    assert_eq!(report["status"], "failed");
    assert_eq!(report["exit_code"], 1);
}

#[test]
fn disk_full_on_the_html_report_written_last_fails_and_leaves_nothing_partial() {
    let text = timeline("[[export]]\npath = \"final.usda\"\nwhat = \"final\"\n");
    let reference = TestDir::new();
    std::fs::write(reference.path("t.toml"), &text).unwrap();
    reference.run_ok(&["bake", "t.toml", "-q", "--report", "r.html"]);
    let (export, html) = (
        file_size(&reference, "final.usda"),
        file_size(&reference, "r.html"),
    );
    let limit = (export / 512 + 1) * 512;
    assert!(html > limit, "report {html} B, export {export} B");

    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), &text).unwrap();
    // An old report is not left to describe the new outputs.
    std::fs::write(dir.path("r.html"), b"old report").unwrap();
    let (code, stderr) = run_with_file_size_limit(&dir, limit, "bake t.toml -q --report r.html");
    assert_eq!(code, Some(1), "{stderr}");
    assert_one_line(&stderr);
    assert!(stderr.contains("r.html"), "names the file: {stderr}");
    assert!(stderr.contains("File too large"), "says why: {stderr}");
    // The export is whole (the same bytes as without the limit); there is
    // no report, old or partial, and no temporary.
    assert_eq!(
        std::fs::read(dir.path("final.usda")).unwrap(),
        std::fs::read(reference.path("final.usda")).unwrap()
    );
    assert_eq!(
        files_under(dir.root()),
        vec!["final.usda".to_string(), "t.toml".to_string()]
    );
}

// --- The physical sanity watchdog -------------------------------------------------

fn bake_report(dir: &TestDir, text: &str) -> (Value, String) {
    std::fs::write(dir.path("t.toml"), text).unwrap();
    let output = dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let report = serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    (report, String::from_utf8_lossy(&output.stderr).into_owned())
}

#[test]
fn blow_ups_are_contained_and_reported() {
    // (A gravity of 1e30 m/s^2 blew up every strand too; validate now
    // refuses it, outside its range: limits.rs.)
    let cases = [(
        "ball",
        timeline(FINAL_USDA).replace(
            "[[stage]]",
            "[[collider]]\nname = \"ball\"\nshape = { ball = { radius = 100.0 } }\n[[stage]]",
        ),
    )];
    for (name, text) in cases {
        let dir = TestDir::new();
        let (report, stderr) = bake_report(&dir, &text);
        let stage = &report["stages"][0];
        assert_eq!(
            stage["contained_strands"].as_array().unwrap().len(),
            3,
            "{name}: {report:#}"
        );
        assert_eq!(stage["watchdog"].as_array().unwrap().len(), 3, "{name}");
        assert!(
            stderr.contains("warning") && stderr.contains("blew up"),
            "{name}: {stderr}"
        );
        assert!(!report["warnings"].as_array().unwrap().is_empty());
        // Contained strands are put back: every edge near its rest length.
        let groom = importers::read(&dir.path("final.usda")).unwrap();
        for strand in groom.strands() {
            for w in strand.windows(2) {
                let l: f32 = (0..3)
                    .map(|k| (w[1][k] - w[0][k]).powi(2))
                    .sum::<f32>()
                    .sqrt();
                assert!((0.02..0.04).contains(&l), "{name}: edge of {l} m");
            }
        }
    }
}

#[test]
fn strands_with_identical_consecutive_points_are_reported_not_silently_skipped() {
    let dir = TestDir::new();
    std::fs::write(
        dir.path("dup.obj"),
        "v 0 0 0\nv 0 -1 0\nv 0 -1 0\nv 0 -2 0\nv 1 0 0\nv 1 -1 0\nv 1 -2 0\nl 1 2 3 4\nl 5 6 7\n",
    )
    .unwrap();
    let text = timeline(FINAL_USDA).replace(
        r#"generate = { strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03 }"#,
        r#"source = "dup.obj""#,
    );
    let (report, stderr) = bake_report(&dir, &text);
    assert_eq!(report["unsimulated_strands"], serde_json::json!([0]));
    assert!(stderr.contains("identical"), "{stderr}");
    let output = dir.run_ok(&["validate", "t.toml"]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("identical"));
}

// --- Messages -----------------------------------------------------------------------

#[test]
fn messages_are_one_line_without_repeats_or_raw_control_bytes() {
    let dir = TestDir::new();
    let stderr = dir.run_fail(&["validate", "nosuch.toml"], 2);
    assert_one_line(&stderr);
    assert!(!stderr.contains(":0:0:"), "{stderr}");
    assert_eq!(stderr.matches("os error").count(), 1, "{stderr}");
    // A usage error: one line in the README's form.
    let stderr = dir.run_fail(&["bake", "--threds", "3", "t.toml"], 2);
    assert_one_line(&stderr);
    assert!(stderr.starts_with("groombake: bake"), "{stderr}");
    let stderr = dir.run_fail(&["no-such-command"], 2);
    assert_one_line(&stderr);
    // Control bytes in a name are shown escaped.
    let stderr = dir.run_fail(&["validate", "a\u{1}\u{1b}[31mb.toml"], 2);
    assert!(
        !stderr.contains('\u{1}') && !stderr.contains('\u{1b}'),
        "{stderr:?}"
    );
    assert_one_line(&stderr);
    // One stage is "1 stage".
    std::fs::write(dir.path("t.toml"), timeline(FINAL_USDA)).unwrap();
    let output = dir.run_ok(&["validate", "t.toml"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains("1 stage ") && stdout.contains("1 export"),
        "{stdout}"
    );
}

// --- The report ------------------------------------------------------------------------

fn sha256_hex(path: &Path) -> String {
    use sha2::{Digest, Sha256};
    let digest = Sha256::digest(std::fs::read(path).unwrap());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

fn assert_rfc3339_utc(text: &Value) {
    let text = text.as_str().unwrap();
    assert!(humantime::parse_rfc3339(text).is_ok(), "{text}");
    assert!(text.ends_with('Z'), "{text}");
}

#[test]
fn the_report_says_status_hashes_times_and_memory_on_success_and_failure() {
    let dir = TestDir::new();
    dir.run_ok(&["generate", "swatch", "-o", "g.hair", "--strands", "3"]);
    let text = timeline(FINAL_USDA).replace(
        r#"generate = { strands = 3, layout = "swatch", length = 0.1, segment_length = 0.03 }"#,
        "source = \"g.hair\"\nunits = \"m\"",
    );
    let good = text.replace("duration = 0.05", "duration = 0.1");
    let (report, _) = bake_report(&dir, &good);
    assert_eq!(report["status"], "ok");
    assert_eq!(report["exit_code"], 0);
    assert_eq!(report["schema_version"], 2);
    assert_eq!(report["timeline_sha256"], sha256_hex(&dir.path("t.toml")));
    assert_eq!(
        report["sources"][0]["sha256"],
        sha256_hex(&dir.path("g.hair"))
    );
    assert_rfc3339_utc(&report["started"]);
    assert_rfc3339_utc(&report["finished"]);
    assert!(report["peak_memory_bytes"].as_u64().unwrap() > 1 << 20);
    // 36 steps of 1/360 s: 0.1, not 0.10000000000000002.
    let json = std::fs::read_to_string(dir.path("r.json")).unwrap();
    assert!(json.contains("\"simulated_seconds\": 0.1,"), "{json}");
    assert_eq!(
        report["outputs"][0]["sha256"],
        sha256_hex(&dir.path("final.usda"))
    );

    // A failure (bad input found before simulating) still writes it.
    std::fs::write(
        dir.path("bad.toml"),
        good.replace("duration = 0.1", "duration = -1.0"),
    )
    .unwrap();
    dir.run_fail(&["bake", "bad.toml", "-q", "--report", "bad.json"], 2);
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path("bad.json")).unwrap()).unwrap();
    assert_eq!(report["status"], "invalid");
    assert_eq!(report["exit_code"], 2);
    assert!(report["error"].as_str().unwrap().contains("duration"));
    assert_eq!(report["timeline_sha256"], sha256_hex(&dir.path("bad.toml")));
    assert_rfc3339_utc(&report["finished"]);
}
