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
