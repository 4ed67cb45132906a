//! `groombake batch`: a manifest of the four samples x three grooms, killed
//! half-way and resumed, gives the bytes of an uninterrupted run; a failing
//! job does not stop the others; the Slurm script.

use crate::util::{sample, TestDir};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

/// Three small swatch grooms and a manifest of every sample with each.
fn write_manifest(dir: &TestDir) {
    for n in [4, 6, 8] {
        let name = format!("g{n}.hair");
        let strands = n.to_string();
        dir.run_ok(&[
            "generate",
            "swatch",
            "-o",
            &name,
            "--strands",
            &strands,
            "--length",
            "0.1",
        ]);
    }
    let mut manifest = String::new();
    for s in ["bed_hair", "blow_dry", "perm", "wind"] {
        let timeline = sample(&format!("{s}.toml"));
        manifest += &format!(
            "[[glob]]\ntimeline = {:?}\ngrooms = \"g*.hair\"\n",
            timeline.display().to_string()
        );
    }
    std::fs::write(dir.path("m.toml"), manifest).unwrap();
}

/// Every file under `root` but the reports (which hold timings), with its bytes.
fn outputs(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if !path.ends_with("groombake_job.json")
                && !path.ends_with("batch_report.json")
                && !path.ends_with("batch_report.html")
            {
                let key = path.strip_prefix(root).unwrap().display().to_string();
                files.insert(key, std::fs::read(&path).unwrap());
            }
        }
    }
    files
}

fn job_reports(root: &Path) -> usize {
    std::fs::read_dir(root)
        .map(|d| {
            d.flatten()
                .filter(|e| e.path().join("groombake_job.json").is_file())
                .count()
        })
        .unwrap_or(0)
}

fn merged(root: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(root.join("batch_report.json")).unwrap()).unwrap()
}

#[test]
fn killed_and_resumed_gives_the_bytes_of_one_run() {
    let dir = TestDir::new();
    write_manifest(&dir);
    let full = dir.path("batch_out");

    // Killed half-way: once at least 4 of the 12 job reports are there.
    let mut child = dir
        .command()
        .args(["batch", "m.toml", "--jobs", "2", "-q"])
        .spawn()
        .unwrap();
    let started = Instant::now();
    while job_reports(&full) < 4 {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the batch ended before the kill"
        );
        assert!(started.elapsed() < Duration::from_secs(600), "no progress");
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done_before = job_reports(&full);
    assert!(done_before < 12, "killed after every job had finished");

    dir.run_ok(&["batch", "m.toml", "--jobs", "2", "--resume", "-q"]);
    let resumed = merged(&full);
    assert_eq!(resumed["succeeded"], 12, "{resumed}");
    let skipped = resumed["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|j| j["status"] == "skipped")
        .count();
    assert_eq!(
        skipped, done_before,
        "resume skips exactly the finished jobs"
    );
    let resumed_files = outputs(&full);

    // The same manifest uninterrupted, into another folder.
    std::fs::rename(&full, dir.path("resumed")).unwrap();
    dir.run_ok(&["batch", "m.toml", "--jobs", "2", "-q"]);
    let report = merged(&full);
    assert_eq!(report["succeeded"], 12);
    let jobs = report["jobs"].as_array().unwrap();
    assert_eq!(jobs.len(), 12);
    assert!(jobs.iter().all(|j| j["status"] == "ok"));
    // Each output listed with the SHA-256 of its bytes.
    let first = &jobs[0]["outputs"][0];
    let path = full
        .join("bed_hair-g4")
        .join(first["path"].as_str().unwrap());
    let (bytes, sha) = groombake::timeline::report::size_and_sha256(&path).unwrap();
    assert_eq!(
        (
            first["bytes"].as_u64().unwrap(),
            first["sha256"].as_str().unwrap()
        ),
        (bytes, sha.as_str())
    );

    let uninterrupted = outputs(&full);
    let only_one: Vec<_> = uninterrupted
        .keys()
        .filter(|k| !resumed_files.contains_key(*k))
        .chain(
            resumed_files
                .keys()
                .filter(|k| !uninterrupted.contains_key(*k)),
        )
        .collect();
    assert!(only_one.is_empty(), "in one run's files only: {only_one:?}");
    assert!(uninterrupted.len() >= 12 * 2, "{:?}", uninterrupted.keys());
    for (name, bytes) in &uninterrupted {
        assert!(
            resumed_files.get(name) == Some(bytes),
            "{name} differs after the resume"
        );
    }

    // Nothing to do when everything is complete; a changed output is re-baked.
    dir.run_ok(&["batch", "m.toml", "--resume", "-q"]);
    assert!(merged(&full)["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .all(|j| j["status"] == "skipped"));
    let victim = full
        .join("perm-g6")
        .join(jobs[7]["outputs"][0]["path"].as_str().unwrap());
    std::fs::write(&victim, b"damaged").unwrap();
    dir.run_ok(&["batch", "m.toml", "--resume", "-q"]);
    let statuses: Vec<_> = merged(&full)["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["status"].clone())
        .collect();
    assert_eq!(
        statuses.iter().filter(|s| *s == "ok").count(),
        1,
        "{statuses:?}"
    );
    assert_eq!(statuses[7], "ok");
    assert_eq!(
        std::fs::read(&victim).unwrap(),
        uninterrupted[&format!(
            "perm-g6/{}",
            jobs[7]["outputs"][0]["path"].as_str().unwrap()
        )]
    );
}

#[test]
fn a_failing_job_does_not_stop_the_others() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "g.hair",
        "--strands",
        "3",
        "--length",
        "0.1",
    ]);
    std::fs::write(dir.path("broken.hair"), b"not a hair file").unwrap();
    let perm = sample("perm.toml").display().to_string();
    std::fs::write(
        dir.path("m.toml"),
        format!(
            "out = \"o\"\n[[job]]\nname = \"bad\"\ntimeline = {perm:?}\ngroom = \"broken.hair\"\n\
             [[job]]\ntimeline = {perm:?}\ngroom = \"g.hair\"\nout = \"elsewhere\"\n"
        ),
    )
    .unwrap();
    let stderr = dir.run_fail(&["batch", "m.toml", "--jobs", "2"], 1);
    assert!(stderr.contains("1 of 2 job(s) failed"), "{stderr}");
    let report = merged(&dir.path("o"));
    assert_eq!(report["jobs"][0]["status"], "failed");
    assert!(report["jobs"][0]["error"]
        .as_str()
        .unwrap()
        .contains("broken.hair"));
    assert_eq!(report["jobs"][1]["status"], "ok");
    assert!(dir.path("elsewhere/groombake_job.json").is_file());

    // A shard runs its own jobs only; the merge then finds the other missing.
    std::fs::remove_dir_all(dir.path("elsewhere")).unwrap();
    dir.run_fail(&["batch", "m.toml", "--shard", "0/2"], 1);
    assert!(!dir.path("elsewhere").exists());
    let stderr = dir.run_fail(&["batch", "m.toml", "--merge"], 1);
    assert!(stderr.contains("2 of 2"), "{stderr}");
    assert_eq!(merged(&dir.path("o"))["jobs"][1]["status"], "missing");
}

#[test]
fn bad_manifests_exit_2_naming_the_place() {
    let dir = TestDir::new();
    std::fs::write(dir.path("m.toml"), "[[job]]\ntimeline = \"nope.toml\"\n").unwrap();
    let stderr = dir.run_fail(&["batch", "m.toml"], 2);
    assert!(
        stderr.contains("m.toml:1:1") && stderr.contains("nope.toml"),
        "{stderr}"
    );
    std::fs::write(dir.path("m.toml"), "[[job]]\ntimelin = \"x\"\n").unwrap();
    let stderr = dir.run_fail(&["batch", "m.toml"], 2);
    assert!(
        stderr.contains("m.toml:2:1") && stderr.contains("timelin"),
        "{stderr}"
    );
    dir.run_fail(&["batch", "m.toml", "--shard", "2/2"], 2);
}

#[test]
fn slurm_script_is_a_job_array_with_a_merge() {
    let dir = TestDir::new();
    write_manifest(&dir);
    let mut manifest = std::fs::read_to_string(dir.path("m.toml")).unwrap();
    manifest += "[slurm]\ntime = \"00:30:00\"\naccount = \"hair\"\n";
    std::fs::write(dir.path("m.toml"), manifest).unwrap();
    let out = dir.run_ok(&[
        "batch",
        "m.toml",
        "--emit",
        "slurm",
        "--time",
        "01:00:00",
        "--mem",
        "2G",
        "--partition",
        "ci",
    ]);
    let script = String::from_utf8(out.stdout).unwrap();
    assert!(script.starts_with("#!/bin/bash\n"));
    assert!(script.contains("#SBATCH --array=0-11\n"), "{script}");
    // The flags override the manifest's [slurm]; the rest is taken from it.
    for line in [
        "#SBATCH --time=01:00:00\n",
        "#SBATCH --mem=2G\n",
        "#SBATCH --partition=ci\n",
        "#SBATCH --account=hair\n",
    ] {
        assert!(script.contains(line), "{line} in {script}");
    }
    // N is fixed: a task alone bakes the same job as in the whole array.
    assert!(script.contains("jobs=12\n"), "{script}");
    assert!(script.contains("--shard \"$SLURM_ARRAY_TASK_ID/$jobs\""));
    assert!(!script.contains("SLURM_ARRAY_TASK_COUNT"));
    assert!(script.contains("--dependency=\"afterany:$SLURM_ARRAY_JOB_ID\""));
    assert!(script.contains("--merge"));
    std::fs::write(dir.path("bake.sbatch"), &script).unwrap();
    let check = std::process::Command::new("bash")
        .arg("-n")
        .arg(dir.path("bake.sbatch"))
        .status()
        .unwrap();
    assert!(check.success(), "the script is not valid bash");

    // Task 3 run alone, as `sbatch --array=3` runs it (not the lowest task
    // of its submission here, so it submits no merge): job 3 only.
    let task = std::process::Command::new("bash")
        .arg(dir.path("bake.sbatch"))
        .current_dir(dir.root())
        .env("SLURM_ARRAY_TASK_ID", "3")
        .env("SLURM_ARRAY_TASK_MIN", "0")
        .env("SLURM_ARRAY_JOB_ID", "1")
        .output()
        .unwrap();
    assert!(
        task.status.success(),
        "{}",
        String::from_utf8_lossy(&task.stderr)
    );
    let baked: Vec<_> = std::fs::read_dir(dir.path("batch_out"))
        .unwrap()
        .flatten()
        .filter(|e| e.path().join("groombake_job.json").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(baked, ["blow_dry-g4"], "job 3 of the manifest's order");

    // A value sbatch would refuse is refused here, naming it.
    let stderr = dir.run_fail(&["batch", "m.toml", "--emit", "slurm", "--mem", "8GB"], 2);
    assert!(stderr.contains("8GB"), "{stderr}");
    std::fs::write(
        dir.path("bad.toml"),
        "[[job]]\ntimeline = \"t.toml\"\n[slurm]\ntime = \"2h\"\n",
    )
    .unwrap();
    let stderr = dir.run_fail(&["batch", "bad.toml", "--emit", "slurm"], 2);
    assert!(
        stderr.contains("bad.toml:3") && stderr.contains("slurm time '2h'"),
        "{stderr}"
    );
    let stderr = dir.run_fail(&["batch", "m.toml", "--time", "10"], 2);
    assert!(stderr.contains("--emit"), "{stderr}");
}

#[test]
fn html_reports_are_self_contained_pages() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "g.hair",
        "--strands",
        "4",
        "--length",
        "0.1",
    ]);
    let timeline = std::fs::read_to_string(sample("bed_hair.toml"))
        .unwrap()
        .replace("generate = {", "source = \"g.hair\" # {");
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.html"]);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    let html = std::fs::read_to_string(dir.path("r.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert_eq!(
        html.matches("src=\"data:image/png;base64,").count(),
        1,
        "one contact sheet"
    );
    assert_eq!(html.matches("<svg").count(), 3, "three plots");
    for output in json["outputs"].as_array().unwrap() {
        assert!(
            html.contains(output["sha256"].as_str().unwrap()),
            "{output}"
        );
    }
    for stage in ["wet", "press", "dry", "release"] {
        assert!(html.contains(&format!("<td>{stage}</td>")));
    }
    // Nothing outside the page is loaded.
    assert!(
        !html.contains("http://")
            || html.matches("http://").count()
                == html.matches("xmlns=\"http://www.w3.org/2000/svg\"").count()
    );
    assert!(!html.contains("https://"));
}
