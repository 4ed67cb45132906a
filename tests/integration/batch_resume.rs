//! `batch --resume` bakes a job again when anything its outputs depend on
//! changed since its report: the timeline, a file it reads, the seed,
//! groombake's version; and skips it when nothing did.

use crate::util::TestDir;
use serde_json::Value;

/// A short timeline of a groom file: wet, dry, the final pose exported.
fn timeline(duration: &str) -> String {
    format!(
        r#"
[groom]
source = "g.hair"
[solver]
# Sideways: the hair swings, so the final pose depends on the durations.
gravity = [9.81, 0.0, 0.0]
[[stage]]
kind = "wet"
duration = {duration}
[[stage]]
kind = "dry"
duration = 0.05
[[export]]
path = "final.usda"
what = "final"
"#
    )
}

fn swatch(dir: &TestDir, name: &str, strands: &str) {
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        name,
        "--strands",
        strands,
        "--length",
        "0.1",
    ]);
}

/// Job `a` bakes the timeline's own groom, job `b` the manifest's `h.hair`.
fn manifest(seed: Option<u64>) -> String {
    let seed = seed.map(|s| format!("seed = {s}\n")).unwrap_or_default();
    format!(
        "out = \"o\"\n[[job]]\nname = \"a\"\ntimeline = \"t.toml\"\n\
         [[job]]\nname = \"b\"\ntimeline = \"t.toml\"\ngroom = \"h.hair\"\n{seed}"
    )
}

/// Runs `batch m.toml --resume`; returns each job's (status, why baked again)
/// and the stderr.
fn resume(dir: &TestDir) -> (Vec<(String, String)>, String) {
    let out = dir.run_ok(&["batch", "m.toml", "--resume"]);
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path("o/batch_report.json")).unwrap()).unwrap();
    let jobs = report["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| {
            (
                j["status"].as_str().unwrap().to_string(),
                j["rebaked_because"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect();
    (jobs, String::from_utf8_lossy(&out.stderr).into_owned())
}

fn skipped() -> (String, String) {
    ("skipped".into(), String::new())
}

fn rebaked(why: &str) -> (String, String) {
    ("ok".into(), why.into())
}

#[test]
fn resume_bakes_again_what_changed_and_only_that() {
    let dir = TestDir::new();
    swatch(&dir, "g.hair", "3");
    swatch(&dir, "h.hair", "4");
    std::fs::write(dir.path("t.toml"), timeline("0.05")).unwrap();
    std::fs::write(dir.path("m.toml"), manifest(None)).unwrap();
    dir.run_ok(&["batch", "m.toml", "-q"]);
    let first = std::fs::read(dir.path("o/a/final.usda")).unwrap();
    assert_eq!(resume(&dir).0, [skipped(), skipped()]);

    // The timeline: both jobs, with new outputs.
    std::fs::write(dir.path("t.toml"), timeline("0.1")).unwrap();
    let (jobs, stderr) = resume(&dir);
    assert_eq!(
        jobs,
        [
            rebaked("the timeline changed"),
            rebaked("the timeline changed")
        ]
    );
    assert!(
        stderr.contains("ok a (") && stderr.contains("baked again: the timeline changed"),
        "{stderr}"
    );
    assert!(
        std::fs::read(dir.path("o/a/final.usda")).unwrap() != first,
        "new outputs"
    );
    assert_eq!(resume(&dir).0, [skipped(), skipped()]);

    // A source: the timeline's groom changes job a only; the manifest's
    // groom (in place of the timeline's) job b only.
    swatch(&dir, "g.hair", "5");
    let (jobs, _) = resume(&dir);
    assert_eq!(jobs[1], skipped());
    assert!(
        jobs[0].0 == "ok"
            && jobs[0].1.starts_with("the groom '")
            && jobs[0].1.ends_with("g.hair' changed"),
        "{jobs:?}"
    );
    swatch(&dir, "h.hair", "6");
    let (jobs, _) = resume(&dir);
    assert_eq!(jobs[0], skipped());
    assert!(jobs[1].1.ends_with("h.hair' changed"), "{jobs:?}");
    // The same bytes again: nothing to do.
    swatch(&dir, "h.hair", "6");
    assert_eq!(resume(&dir).0, [skipped(), skipped()]);

    // An option: the seed of job b.
    std::fs::write(dir.path("m.toml"), manifest(Some(7))).unwrap();
    assert_eq!(
        resume(&dir).0,
        [skipped(), rebaked("the seed changed (the timeline's -> 7)")]
    );

    // groombake's version: a report written by another version.
    let path = dir.path("o/a/groombake_job.json");
    let mut report: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    report["inputs"]["groombake_version"] = "0.0.1".into();
    std::fs::write(&path, serde_json::to_vec(&report).unwrap()).unwrap();
    let (jobs, _) = resume(&dir);
    assert_eq!(
        jobs,
        [
            rebaked(&format!("groombake 0.0.1 -> {}", env!("CARGO_PKG_VERSION"))),
            skipped()
        ]
    );
    // A report of a version that recorded no inputs.
    let mut report: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    report.as_object_mut().unwrap().remove("inputs");
    std::fs::write(&path, serde_json::to_vec(&report).unwrap()).unwrap();
    assert_eq!(
        resume(&dir).0,
        [rebaked("its report records no inputs"), skipped()]
    );
}
