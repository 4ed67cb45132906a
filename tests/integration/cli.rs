//! The command line as a whole: usage errors, exit codes.

use crate::util::TestDir;

#[test]
fn unknown_subcommand_is_usage_error() {
    let dir = TestDir::new();
    dir.run_fail(&["frobnicate"], 2);
}

#[test]
fn missing_file_names_it_and_exits_2() {
    let dir = TestDir::new();
    let stderr = dir.run_fail(&["inspect", "nowhere.hair"], 2);
    assert!(stderr.starts_with("groombake: nowhere.hair"), "{stderr}");
}

/// stderr of a usage error: one line, the README's form.
fn usage_error(dir: &TestDir, args: &[&str]) -> String {
    let stderr = dir.run_fail(args, 2);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    stderr
}

#[test]
fn usage_errors_name_the_argument_and_suggest() {
    let dir = TestDir::new();
    let stderr = usage_error(&dir, &["bake"]);
    assert!(
        stderr.contains("bake: the following required arguments were not provided: <TIMELINE>"),
        "{stderr}"
    );
    let stderr = usage_error(&dir, &["bak", "t.toml"]);
    assert!(
        stderr.contains("tip: a similar subcommand exists: 'bake'"),
        "{stderr}"
    );
    let stderr = usage_error(&dir, &["bake", "t.toml", "--thread", "2"]);
    assert!(stderr.contains("'--threads'"), "{stderr}");
    // A bare call shows the commands (on stderr, exit 2).
    let stderr = dir.run_fail(&[], 2);
    for command in ["bake", "batch", "preview", "inspect", "validate"] {
        assert!(
            stderr.contains(&format!("\n  {command} ")),
            "{command}: {stderr}"
        );
    }
}

#[test]
fn dash_j_sets_threads_and_jobs() {
    let dir = TestDir::new();
    let cases: [&[&str]; 2] = [
        &["bake", "t.toml", "-j", "0"],
        &["bench", "--steps", "1", "-j", "0"],
    ];
    for args in cases {
        let stderr = usage_error(&dir, args);
        assert!(stderr.contains("--threads"), "{stderr}");
    }
    let stderr = usage_error(&dir, &["batch", "m.toml", "-j", "x"]);
    assert!(stderr.contains("--jobs"), "{stderr}");
}

#[test]
fn report_dash_is_json_on_stdout() {
    let dir = TestDir::new();
    std::fs::write(
        dir.path("t.toml"),
        "[groom]\ngenerate = { layout = \"swatch\", strands = 2, length = 0.05, segment_length = 0.01 }\n\
         [[stage]]\nkind = \"wet\"\nduration = 0.02\n[[export]]\npath = \"rest.usda\"\nwhat = \"rest\"\n",
    )
    .unwrap();
    let out = dir.run_ok(&["bake", "t.toml", "-q", "--report", "-"]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["status"], "ok");
    assert!(!dir.path("-").exists(), "no file named '-'");
    assert!(dir.path("rest.usda").is_file());
}

#[test]
fn completions_offer_the_values_of_a_flag() {
    let dir = TestDir::new();
    let bash = String::from_utf8(dir.run_ok(&["completions", "bash"]).stdout).unwrap();
    // `--view` completes its words, not file names.
    assert!(
        bash.contains(
            "--view)\n                    COMPREPLY=($(compgen -W \"front side top persp\""
        ),
        "no view words in the bash script"
    );
    let fish = String::from_utf8(dir.run_ok(&["completions", "fish"]).stdout).unwrap();
    let units: Vec<&str> = fish.lines().filter(|l| l.contains(" -l units ")).collect();
    assert!(
        units.len() == 1 && units[0].contains("-a \"m\\t") && fish.contains("\ncm\\t"),
        "{units:?}"
    );
}
