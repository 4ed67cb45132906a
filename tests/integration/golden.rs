//! Golden files: every sample's exports are byte-identical across runs and
//! thread counts, and match the SHA-256s checked in under `tests/golden/`.
//!
//! Bless after an intended change of output:
//! `GROOMBAKE_BLESS=1 cargo test --test integration golden`

use crate::util::{hand_to_validators, sample, TestDir};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn golden_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(format!("{name}.sha256"))
}

/// SHA-256 of every file under `dir`, by path relative to it.
fn digests(dir: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let bytes = std::fs::read(&path).unwrap();
                let hex: String = Sha256::digest(&bytes)
                    .iter()
                    .map(|b| format!("{b:02x}"))
                    .collect();
                let relative = path
                    .strip_prefix(dir)
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                out.insert(relative, hex);
            }
        }
    }
    out
}

fn render(digests: &BTreeMap<String, String>) -> String {
    digests
        .iter()
        .map(|(path, hex)| format!("{hex}  {path}\n"))
        .collect()
}

fn bake_sample(name: &str) {
    let dir = TestDir::new();
    let timeline = sample(&format!("{name}.toml"));
    let timeline = timeline.to_str().unwrap();
    dir.run_ok(&["bake", timeline, "--out", "t1", "--threads", "1", "-q"]);
    dir.run_ok(&["bake", timeline, "--out", "t2", "--threads", "2", "-q"]);
    let one = digests(&dir.path("t1"));
    let two = digests(&dir.path("t2"));
    assert!(!one.is_empty(), "{name} wrote nothing");
    assert_eq!(
        render(&one),
        render(&two),
        "{name}: outputs differ between 1 and 2 threads"
    );
    for relative in one.keys() {
        let file = dir.path("t1").join(relative);
        let label = format!("golden_{name}_{}", relative.replace(['/', '.'], "_"));
        hand_to_validators(&file, &label, serde_json::json!({}));
    }
    let golden = golden_file(name);
    if std::env::var_os("GROOMBAKE_BLESS").is_some() {
        std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
        std::fs::write(&golden, render(&one)).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&golden).unwrap_or_else(|_| {
        panic!(
            "no golden file {}: bless with GROOMBAKE_BLESS=1",
            golden.display()
        )
    });
    assert_eq!(
        render(&one),
        expected,
        "{name}: outputs differ from {} (if intended, bless with GROOMBAKE_BLESS=1 cargo test --test integration golden)",
        golden.display()
    );
}

#[test]
fn golden_bed_hair() {
    bake_sample("bed_hair");
}

#[test]
fn golden_blow_dry() {
    bake_sample("blow_dry");
}

#[test]
fn golden_perm() {
    bake_sample("perm");
}

#[test]
fn golden_wind() {
    bake_sample("wind");
}

#[test]
fn golden_bangs() {
    bake_sample("bangs");
}

#[test]
fn golden_bed_head() {
    bake_sample("bed_head");
}
