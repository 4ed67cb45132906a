//! Test helpers: a temporary directory per test, the real binary, the test
//! data of `tests/data/`, and hand-off of exported files to the external validators
//! that `.ci/run` runs (Khronos glTF-Validator, usd-core, alembic3d).

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A temporary directory for one test, removed when dropped.
pub struct TestDir {
    dir: tempfile::TempDir,
}

impl TestDir {
    pub fn new() -> TestDir {
        TestDir {
            dir: tempfile::tempdir().expect("temporary directory"),
        }
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    pub fn root(&self) -> &Path {
        self.dir.path()
    }

    /// The groombake binary, run inside this directory.
    pub fn command(&self) -> Command {
        let mut command = Command::new(env!("CARGO_BIN_EXE_groombake"));
        command.current_dir(self.dir.path());
        command
    }

    /// Runs groombake with `args`; panics with its output unless it exits 0.
    pub fn run_ok(&self, args: &[&str]) -> Output {
        let output = self.command().args(args).output().expect("run groombake");
        assert!(
            output.status.success(),
            "groombake {args:?} failed ({:?})\nstdout:\n{}\nstderr:\n{}",
            output.status.code(),
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        output
    }

    /// Runs groombake with `args`, expecting exit code `code`; returns stderr.
    pub fn run_fail(&self, args: &[&str], code: i32) -> String {
        let output = self.command().args(args).output().expect("run groombake");
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert_eq!(
            output.status.code(),
            Some(code),
            "groombake {args:?}: expected exit {code}\nstdout:\n{}\nstderr:\n{stderr}",
            String::from_utf8_lossy(&output.stdout)
        );
        assert!(
            !stderr.contains("panicked"),
            "groombake panicked:\n{stderr}"
        );
        stderr
    }

    /// `inspect --json` of a file.
    pub fn inspect(&self, file: &str) -> serde_json::Value {
        let output = self.run_ok(&["inspect", file, "--json"]);
        serde_json::from_slice(&output.stdout).expect("inspect --json prints JSON")
    }
}

/// A file of this repository's `tests/data/` (real grooms from other tools;
/// `tests/data/README.md` names each one's source and licence).
pub fn test_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// A file of this repository's `samples/`.
pub fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name)
}

/// Hands an exported file to the external validators of `.ci/run`: when
/// `GROOMBAKE_ARTIFACTS` is set, copies `file` there as `<label>.<ext>` with
/// `<label>.<ext>.expect.json` holding what the validator must find in it
/// (format-specific keys, e.g. `curves`, `points`, `time_samples`).
pub fn hand_to_validators(file: &Path, label: &str, expect: serde_json::Value) {
    let Some(dir) = std::env::var_os("GROOMBAKE_ARTIFACTS") else {
        return;
    };
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(&dir).expect("artifact directory");
    let ext = file.extension().and_then(|e| e.to_str()).unwrap_or("bin");
    let name = format!("{label}.{ext}");
    std::fs::copy(file, dir.join(&name)).expect("copy artifact");
    std::fs::write(
        dir.join(format!("{name}.expect.json")),
        serde_json::to_vec_pretty(&expect).expect("json"),
    )
    .expect("write expectations");
}
