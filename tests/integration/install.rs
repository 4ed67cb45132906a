//! `completions` and `man`: what an installed groombake gives the shell.

use crate::util::TestDir;
use std::process::Command;

#[test]
fn bash_completions_are_a_valid_script_naming_every_subcommand() {
    let dir = TestDir::new();
    let output = dir.run_ok(&["completions", "bash"]);
    let script = String::from_utf8(output.stdout).unwrap();
    for subcommand in ["bake", "validate", "convert", "preview", "inspect", "man"] {
        assert!(script.contains(subcommand), "no {subcommand} in:\n{script}");
    }
    assert!(script.contains("complete -F _groombake"), "{script}");
    // bash itself parses it (-n: read, do not run).
    std::fs::write(dir.path("groombake.bash"), &script).unwrap();
    let check = Command::new("bash")
        .args(["-n", "groombake.bash"])
        .current_dir(dir.root())
        .output()
        .expect("bash");
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
}

#[test]
fn completions_for_an_unknown_shell_is_a_usage_error() {
    let dir = TestDir::new();
    dir.run_fail(&["completions", "cmd.exe"], 2);
}

#[test]
fn man_page_is_roff_that_man_renders() {
    let dir = TestDir::new();
    let output = dir.run_ok(&["man"]);
    let page = String::from_utf8(output.stdout).unwrap();
    assert!(
        page.starts_with(".ie") || page.contains(".TH groombake 1"),
        "{page}"
    );
    std::fs::write(dir.path("groombake.1"), &page).unwrap();
    // groff, as `man` uses it, renders the page to text.
    let Ok(rendered) = Command::new("groff")
        .args(["-man", "-Tutf8", "groombake.1"])
        .current_dir(dir.root())
        .output()
    else {
        panic!("groff is needed to check the man page");
    };
    assert!(rendered.status.success());
    let text = String::from_utf8_lossy(&rendered.stdout);
    assert!(text.contains("groombake"), "{text}");
    assert!(text.contains("Bakes styled hair grooms"), "{text}");
    for subcommand in ["bake", "completions", "preview"] {
        assert!(text.contains(subcommand), "no {subcommand} in:\n{text}");
    }
}
