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

// --- What a fresh clone ships (issue 11: install, licences, binary size) ---

/// A file at the repository's root, as text.
fn repo_text(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn cargo_toml() -> toml::Table {
    repo_text("Cargo.toml").parse().expect("Cargo.toml is TOML")
}

/// The text with every run of white space made one space (line wrapping and
/// indentation are not part of a licence).
fn words(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn sha256_hex(text: &str) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The README's install line keeps `Cargo.lock`'s versions (`--locked`):
/// without it `cargo install` resolves the newest versions instead.
#[test]
fn readme_install_line_is_locked() {
    let readme = repo_text("README.md");
    let installs: Vec<&str> = readme
        .lines()
        .map(str::trim)
        .filter(|line| line.starts_with("cargo install"))
        .collect();
    assert!(
        !installs.is_empty(),
        "README.md has no `cargo install` line"
    );
    for line in installs {
        let args: Vec<&str> = line.split_whitespace().collect();
        assert!(args.contains(&"--locked"), "not --locked: {line}");
        assert!(
            args.windows(2).any(|w| w == ["--path", "."]),
            "does not install this repository: {line}"
        );
    }
}

/// Cargo.toml's licence is MIT OR Apache-2.0 and both texts ship at the
/// root, unaltered: the terms compared word for word (as SHA-256 of their
/// words) with the texts the licences publish.
#[test]
fn licence_files_are_the_real_texts_cargo_toml_names() {
    let manifest = cargo_toml();
    let license = manifest["workspace"]["package"]["license"].as_str();
    assert_eq!(license, Some("MIT OR Apache-2.0"));
    assert_eq!(
        manifest["package"]["license"]["workspace"].as_bool(),
        Some(true),
        "the package takes the workspace's licence"
    );

    // Apache-2.0 (apache.org/licenses/LICENSE-2.0.txt): from the title to
    // the end of the terms; the appendix after it is an example notice.
    let apache = words(&repo_text("LICENSE-APACHE"));
    let start = apache.find("Apache License Version 2.0, January 2004");
    let end_mark = "END OF TERMS AND CONDITIONS";
    let end = apache.find(end_mark);
    let (Some(start), Some(end)) = (start, end) else {
        panic!("LICENSE-APACHE is not the Apache License 2.0 text");
    };
    assert_eq!(
        sha256_hex(&apache[start..end + end_mark.len()]),
        "59d8f0ba87ad9a2f1a431123c8d16646e5b89ba53653e818f16d136d77263c99",
        "LICENSE-APACHE's terms differ from the Apache License 2.0"
    );

    // MIT (opensource.org/license/mit): a copyright line, then the
    // permission notice and the warranty disclaimer.
    let mit = words(&repo_text("LICENSE-MIT"));
    assert!(mit.starts_with("MIT License Copyright (c) "), "{mit}");
    let notice = mit
        .find("Permission is hereby granted")
        .expect("LICENSE-MIT has the permission notice");
    assert_eq!(
        sha256_hex(&mit[notice..]),
        "fe2a9817987f862eaced948f0468c7f51d2fedfc48c5c505b246a49a3870e9a5",
        "LICENSE-MIT's notice differs from the MIT licence"
    );
}

/// The release binary carries no debug info: the standard library's own
/// debug info is linked in unless it is stripped, so with `debug =
/// "line-tables-only"` alone the binary was 50 MB (8 MB stripped). The
/// `profiling` profile keeps it. `.ci/run` checks the size of the binary
/// the README's command builds.
#[test]
fn release_profile_strips_debug_info_and_profiling_keeps_it() {
    let manifest = cargo_toml();
    let profile = |name: &str| {
        manifest["profile"][name]
            .as_table()
            .unwrap_or_else(|| panic!("Cargo.toml has no [profile.{name}]"))
            .clone()
    };
    let release = profile("release");
    let strips = match release.get("strip") {
        Some(toml::Value::Boolean(on)) => *on,
        Some(toml::Value::String(what)) => what == "debuginfo" || what == "symbols",
        // Cargo strips debug info by default when the profile has none.
        None => matches!(
            release.get("debug"),
            None | Some(toml::Value::Boolean(false)) | Some(toml::Value::Integer(0))
        ),
        Some(other) => panic!("profile.release.strip = {other}"),
    };
    assert!(strips, "profile.release keeps debug info: {release:?}");

    let profiling = profile("profiling");
    assert_eq!(profiling["inherits"].as_str(), Some("release"));
    assert_eq!(profiling["debug"].as_bool(), Some(true), "{profiling:?}");
    assert_eq!(profiling["strip"].as_str(), Some("none"), "{profiling:?}");
}

/// The commands `groombake --help` lists (clap's "Commands:" section).
fn commands(dir: &TestDir) -> Vec<String> {
    let help = String::from_utf8(dir.run_ok(&["--help"]).stdout).unwrap();
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect()
}

#[test]
fn man_writes_a_page_for_every_command_that_groff_renders() {
    let dir = TestDir::new();
    let commands = commands(&dir);
    assert!(commands.len() >= 10, "{commands:?}");
    dir.run_ok(&["man", "pages"]);
    let mut written: Vec<String> = std::fs::read_dir(dir.path("pages"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    let mut expected: Vec<String> = commands
        .iter()
        .map(|c| format!("groombake-{c}.1"))
        .chain(["groombake.1".to_string()])
        .collect();
    expected.sort();
    assert_eq!(written, expected);
    for command in &commands {
        let rendered = Command::new("groff")
            .args(["-man", "-Tutf8", &format!("pages/groombake-{command}.1")])
            .current_dir(dir.root())
            .output()
            .expect("groff is needed to check the man pages");
        assert!(rendered.status.success(), "{command}");
        let text = String::from_utf8_lossy(&rendered.stdout);
        assert!(
            text.contains(&format!("groombake-{command}")),
            "{command}:\n{text}"
        );
        // Its own help text is on its page.
        let help = String::from_utf8(dir.run_ok(&[command, "--help"]).stdout).unwrap();
        let about = help.lines().next().unwrap().trim();
        let first_words: String = about
            .split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ");
        assert!(
            text.split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
                .contains(&first_words),
            "{command}: no {first_words:?} in:\n{text}"
        );
    }
}

#[test]
fn man_into_a_file_is_a_one_line_usage_error() {
    let dir = TestDir::new();
    std::fs::write(dir.path("taken"), "x").unwrap();
    let stderr = dir.run_fail(&["man", "taken"], 2);
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("taken") && stderr.contains("not a folder"),
        "{stderr}"
    );
}

/// The README's completions line, run as written in a home that has never
/// had bash completions (no `~/.local/share`).
#[test]
fn readme_completions_line_works_in_a_fresh_home() {
    let dir = TestDir::new();
    let readme = include_str!("../../README.md");
    let line = readme
        .lines()
        .find(|l| l.contains("completions bash >"))
        .expect("the README has a completions line");
    let script = line
        .trim()
        .trim_start_matches('`')
        .split('`')
        .next()
        .unwrap();
    std::fs::create_dir(dir.path("home")).unwrap();
    let bin = std::path::Path::new(env!("CARGO_BIN_EXE_groombake"))
        .parent()
        .unwrap()
        .to_path_buf();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let run = Command::new("bash")
        .args(["-c", script])
        .env("HOME", dir.path("home"))
        .env("PATH", path)
        .output()
        .expect("bash");
    assert!(
        run.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let written = std::fs::read_to_string(
        dir.path("home/.local/share/bash-completion/completions/groombake"),
    )
    .unwrap();
    assert!(written.contains("complete -F _groombake"), "{written}");
}
