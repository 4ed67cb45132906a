//! The round-trip fuzz: damaged copies of real groom files through the
//! command line as a user runs it: **mutate, inspect, convert, diff**.
//! Each mutant (the mutations of `importers/tests/mutation`) is inspected,
//! converted to two other formats (picked by the seed), and every
//! conversion that exits 0 is checked:
//! - with warnings: `convert --strict` must refuse it (exit 2, no output);
//! - without a warning: `groombake diff MUTANT OUTPUT` must find them equal
//!   (1e-6 m plus 1e-6 of the value's size: float32 formats and unit
//!   changes round), or the conversion lost something silently.
//!
//! Every run of the binary must exit 0 or 2 (1 is a failure found after the
//! input was accepted), within 20 s, with no panic, no abort (a signal), no
//! stderr line over 300 characters, and a refused convert must leave no
//! output and no temporary.
//!
//! Environment: `GROOMBAKE_ROUNDTRIP_MUTANTS` mutants per format (default
//! 4,000), `GROOMBAKE_ROUNDTRIP_SECONDS` a wall-time budget after which no
//! new mutant starts (formats take turns, so a bounded run covers every
//! format alike), `GROOMBAKE_ROUNDTRIP_JOBS` parallel mutants (default 2),
//! `GROOMBAKE_ROUNDTRIP_SEED` the seed (default 37), `GROOMBAKE_ROUNDTRIP_BIN`
//! the groombake binary to run (default: the one built with this test),
//! `GROOMBAKE_ROUNDTRIP_FAILURES` a folder where failing mutants are kept
//! with a note of what failed, `GROOMBAKE_ROUNDTRIP_TABLE` a file for the
//! result table (Markdown). Ignored in the ordinary test run; CI (`.ci/run`)
//! runs it for 150 s, and fuzz/README.md gives the longer run and its
//! results: `cargo test --release --test roundtrip_fuzz -- --ignored --nocapture`.

// Test code: a failed setup step may panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../importers/tests/mutation/mod.rs"]
mod mutation;

use mutation::{mutate, Kinds, Rng};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

const TIMEOUT: Duration = Duration::from_secs(20);
const MAX_LINE: usize = 300;
const TARGETS: [&str; 8] = ["gltf", "glb", "usda", "usdc", "abc", "hair", "data", "obj"];

struct Format {
    name: &'static str,
    kinds: Kinds,
    /// Seed files and the extension each mutant of it is given.
    seeds: Vec<(Vec<u8>, &'static str)>,
}

fn env_number<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The binary under test: `GROOMBAKE_ROUNDTRIP_BIN` (CI gives its release
/// build, so the debug test binary that `cargo test` built needs no
/// rebuild), else the one cargo built with this test.
fn groombake() -> Command {
    match std::env::var_os("GROOMBAKE_ROUNDTRIP_BIN") {
        Some(bin) => Command::new(bin),
        None => Command::new(env!("CARGO_BIN_EXE_groombake")),
    }
}

/// Seeds: the repository's real files of each format, and real files
/// converted by groombake into every format (animated, with attributes,
/// where the format holds them).
fn formats(dir: &Path) -> Vec<Format> {
    let sources = [
        "importers/tests/data/reference.usda",
        "tests/data/hairutil_Bangs_100.hair",
        "tests/data/blender501_hair.usda",
    ];
    let mut converted: Vec<(PathBuf, &str)> = Vec::new();
    for (k, source) in sources.iter().enumerate() {
        for ext in TARGETS {
            let out = dir.join(format!("seed{k}.{ext}"));
            let status = groombake()
                .arg("convert")
                .arg(repo(source))
                .arg(&out)
                .stderr(Stdio::null())
                .status()
                .unwrap();
            if status.success() {
                converted.push((out, ext));
            }
        }
    }
    let seeds = |exts: &[&'static str], files: &[&str]| -> Vec<(Vec<u8>, &'static str)> {
        let mut seeds: Vec<(Vec<u8>, &'static str)> = Vec::new();
        for file in files {
            let ext = exts
                .iter()
                .find(|e| file.ends_with(&format!(".{e}")))
                .unwrap();
            seeds.push((std::fs::read(repo(file)).unwrap(), ext));
        }
        for (path, ext) in &converted {
            if let Some(e) = exts.iter().find(|e| *e == ext) {
                seeds.push((std::fs::read(path).unwrap(), e));
            }
        }
        assert!(!seeds.is_empty(), "no seed for {exts:?}");
        seeds
    };
    let kinds = |text, json| Kinds { text, json };
    vec![
        Format {
            name: "glTF (.gltf, .glb)",
            kinds: kinds(true, true),
            seeds: seeds(&["gltf", "glb"], &[]),
        },
        Format {
            name: "USD text (.usda)",
            kinds: kinds(true, false),
            seeds: seeds(
                &["usda"],
                &[
                    "importers/tests/data/reference.usda",
                    "tests/data/blender501_hair.usda",
                ],
            ),
        },
        Format {
            name: "USD crate (.usdc)",
            kinds: kinds(false, false),
            seeds: seeds(
                &["usdc"],
                &[
                    "importers/tests/data/reference.usdc",
                    "importers/tests/data/blender501_hair_by_usd_core.usdc",
                ],
            ),
        },
        Format {
            name: "Alembic (.abc)",
            kinds: kinds(false, false),
            seeds: seeds(
                &["abc"],
                &[
                    "importers/tests/data/xform_cubic_indexed.abc",
                    "tests/data/hairutil_Bangs_100.abc",
                    "tests/data/blender501_hair_static.abc",
                ],
            ),
        },
        Format {
            name: "Cem Yuksel .hair",
            kinds: kinds(false, false),
            seeds: seeds(&["hair"], &["tests/data/hairutil_Bangs_100.hair"]),
        },
        Format {
            name: "USC-HairSalon .data",
            kinds: kinds(false, false),
            seeds: seeds(&["data"], &["tests/data/hairutil_Bangs_100.data"]),
        },
        Format {
            name: "Wavefront .obj",
            kinds: kinds(true, false),
            seeds: seeds(&["obj"], &[]),
        },
    ]
}

/// One run of the binary: how it ended and its stderr.
struct Run {
    status: Option<ExitStatus>,
    timed_out: bool,
    stdout: String,
    stderr: String,
}

impl Run {
    fn code(&self) -> Option<i32> {
        self.status.and_then(|s| s.code())
    }

    fn signal(&self) -> Option<i32> {
        use std::os::unix::process::ExitStatusExt;
        self.status.and_then(|s| s.signal())
    }
}

/// Runs groombake with `args` in `dir`, output to files (no pipe to fill),
/// killed after [`TIMEOUT`].
fn run(dir: &Path, args: &[&str]) -> Run {
    let out_path = dir.join("stdout.txt");
    let err_path = dir.join("stderr.txt");
    let mut child = groombake()
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            timed_out = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let read =
        |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    Run {
        status,
        timed_out,
        stdout: read(&out_path),
        stderr: read(&err_path),
    }
}

/// What one mutant did; each field counts runs or conversions.
#[derive(Default, Clone)]
struct Tally {
    mutants: usize,
    inspected: usize,
    converts: usize,
    clean: usize,
    warned: usize,
    refused: usize,
    panics: usize,
    aborts: usize,
    timeouts: usize,
    exit_one: usize,
    long_lines: usize,
    silent: usize,
    strict: usize,
    leftovers: usize,
    longest_line: usize,
    failures: Vec<String>,
}

impl Tally {
    fn add(&mut self, other: &Tally) {
        self.mutants += other.mutants;
        self.inspected += other.inspected;
        self.converts += other.converts;
        self.clean += other.clean;
        self.warned += other.warned;
        self.refused += other.refused;
        self.panics += other.panics;
        self.aborts += other.aborts;
        self.timeouts += other.timeouts;
        self.exit_one += other.exit_one;
        self.long_lines += other.long_lines;
        self.silent += other.silent;
        self.strict += other.strict;
        self.leftovers += other.leftovers;
        self.longest_line = self.longest_line.max(other.longest_line);
        self.failures.extend(other.failures.iter().cloned());
    }

    fn failed(&self) -> bool {
        self.panics
            + self.aborts
            + self.timeouts
            + self.exit_one
            + self.long_lines
            + self.silent
            + self.strict
            + self.leftovers
            > 0
    }

    /// Checks common to every run; false when the run failed. `diff`
    /// exits 1 for "different", the other commands for a late failure.
    fn check(&mut self, label: &str, run: &Run) -> bool {
        self.check_codes(label, run, &[0, 2])
    }

    fn check_codes(&mut self, label: &str, run: &Run, codes: &[i32]) -> bool {
        let longest = run
            .stderr
            .lines()
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0);
        self.longest_line = self.longest_line.max(longest);
        let mut problem = None;
        if run.timed_out {
            self.timeouts += 1;
            problem = Some(format!("timed out after {} s", TIMEOUT.as_secs()));
        } else if run.stderr.contains("panicked") || run.code() == Some(101) {
            self.panics += 1;
            problem = Some("panicked".into());
        } else if let Some(signal) = run.signal() {
            self.aborts += 1;
            problem = Some(format!("killed by signal {signal}"));
        } else if longest > MAX_LINE {
            self.long_lines += 1;
            problem = Some(format!("a stderr line of {longest} characters"));
        } else if !run.code().is_some_and(|c| codes.contains(&c)) {
            self.exit_one += 1;
            problem = Some(format!("exit {:?}", run.code()));
        }
        match problem {
            Some(problem) => {
                let first: String = run.stderr.chars().take(400).collect();
                self.failures.push(format!("{label}: {problem}: {first}"));
                false
            }
            None => true,
        }
    }
}

/// Whether `diff --json`'s deviations are all within rounding: 1e-6 plus
/// 1e-6 of the larger value (float32 formats and unit changes round).
fn within_rounding(report: &serde_json::Value) -> Result<(), String> {
    if let Some(structural) = report["structural"].as_array() {
        if let Some(first) = structural.first() {
            return Err(format!("structural: {first}"));
        }
    }
    let listed = report["largest"].as_array().cloned().unwrap_or_default();
    if report["above_tolerance"].as_u64().unwrap_or(0) > listed.len() as u64 {
        return Err("more deviations than listed".into());
    }
    for d in &listed {
        let size = |key: &str| {
            d[key]
                .as_array()
                .map(|v| {
                    v.iter()
                        .map(|x| x.as_f64().unwrap_or(f64::INFINITY).abs())
                        .fold(0.0, f64::max)
                })
                .unwrap_or(f64::INFINITY)
        };
        let allowed = 1e-6 + 1e-6 * size("a").max(size("b"));
        let amount = d["amount"].as_f64().unwrap_or(f64::INFINITY);
        if amount.is_nan() || amount > allowed {
            return Err(format!(
                "{} strand {} vertex {}: A {} B {}",
                d["what"], d["strand"], d["vertex"], d["a"], d["b"]
            ));
        }
    }
    Ok(())
}

/// Mutant `n` of `format`: inspect, two conversions, their diffs.
fn one_mutant(dir: &Path, format: &Format, format_index: usize, n: usize, seed: u64) -> Tally {
    let mut tally = Tally {
        mutants: 1,
        ..Tally::default()
    };
    // Each mutant's generator depends only on the seed, the format and
    // `n`: the same mutants whatever the jobs and their order.
    let mut rng = Rng(seed ^ ((format_index as u64) << 56) ^ (n as u64).wrapping_mul(0x9E37_79B9));
    let seed_index = n % format.seeds.len();
    let (seed_bytes, ext) = &format.seeds[seed_index];
    let (what, bytes) = mutate(&mut rng, seed_bytes, format.kinds);
    let input = format!("mutant.{ext}");
    std::fs::write(dir.join(&input), &bytes).unwrap();
    let label = format!("{} mutant {n} (seed {seed_index}, {what})", format.name);
    let keep = |tally: &Tally, dir: &Path| {
        if let Ok(folder) = std::env::var("GROOMBAKE_ROUNDTRIP_FAILURES") {
            let folder = PathBuf::from(folder);
            std::fs::create_dir_all(&folder).unwrap();
            let name = format!("f{format_index}_m{n}.{ext}");
            std::fs::copy(dir.join(&input), folder.join(&name)).unwrap();
            let note = tally.failures.join("\n");
            std::fs::write(folder.join(format!("{name}.txt")), note).unwrap();
        }
    };

    let inspect = run(dir, &["inspect", &input]);
    if !tally.check(&format!("{label}: inspect"), &inspect) {
        keep(&tally, dir);
        return tally;
    }
    tally.inspected += usize::from(inspect.code() == Some(0));

    let first = rng.below(TARGETS.len());
    let second = (first + 1 + rng.below(TARGETS.len() - 1)) % TARGETS.len();
    for target in [TARGETS[first], TARGETS[second]] {
        let output = format!("out.{target}");
        let _ = std::fs::remove_file(dir.join(&output));
        tally.converts += 1;
        let step = format!("{label}: convert to .{target}");
        let convert = run(dir, &["convert", &input, &output]);
        if !tally.check(&step, &convert) {
            continue;
        }
        let leftovers: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|name| name.ends_with(".tmp"))
            .collect();
        if !leftovers.is_empty() {
            tally.leftovers += 1;
            tally.failures.push(format!("{step}: left {leftovers:?}"));
            for name in leftovers {
                let _ = std::fs::remove_file(dir.join(name));
            }
        }
        if convert.code() != Some(0) {
            tally.refused += 1;
            if dir.join(&output).exists() {
                tally.leftovers += 1;
                tally
                    .failures
                    .push(format!("{step}: refused, but wrote {output}"));
            }
            continue;
        }
        let warned = convert.stderr.contains("warning:");
        if warned {
            tally.warned += 1;
            let _ = std::fs::remove_file(dir.join(&output));
            let strict = run(dir, &["convert", "--strict", &input, &output]);
            if !tally.check(&format!("{step} --strict"), &strict) {
                continue;
            }
            if strict.code() != Some(2) || dir.join(&output).exists() {
                tally.strict += 1;
                tally.failures.push(format!(
                    "{step} --strict: exit {:?}, output {}, after the warning {}",
                    strict.code(),
                    dir.join(&output).exists(),
                    convert
                        .stderr
                        .lines()
                        .find(|l| l.contains("warning:"))
                        .unwrap_or("")
                ));
            }
            continue;
        }
        tally.clean += 1;
        let diff = run(
            dir,
            &[
                "diff",
                &input,
                &output,
                "--json",
                "--show",
                "100000",
                "--tolerance",
                "1e-6",
            ],
        );
        if !tally.check_codes(&format!("{step}: diff"), &diff, &[0, 1, 2]) {
            continue;
        }
        let verdict = match diff.code() {
            Some(0) => Ok(()),
            Some(1) => match serde_json::from_str::<serde_json::Value>(&diff.stdout) {
                Ok(report) => within_rounding(&report),
                Err(e) => Err(format!("diff printed no JSON ({e})")),
            },
            _ => Err(format!(
                "diff cannot read them: {}",
                diff.stderr.lines().next().unwrap_or("")
            )),
        };
        if let Err(difference) = verdict {
            tally.silent += 1;
            tally.failures.push(format!(
                "{step}: exit 0, no warning, but differs: {difference}"
            ));
        }
    }
    if tally.failed() {
        keep(&tally, dir);
    }
    tally
}

#[test]
#[ignore = "minutes: CI runs it with a time budget (.ci/run), fuzz/README.md the full run"]
fn mutants_inspect_convert_and_diff_without_panic_or_silent_loss() {
    let per_format: usize = env_number("GROOMBAKE_ROUNDTRIP_MUTANTS", 4000);
    let budget = Duration::from_secs(env_number("GROOMBAKE_ROUNDTRIP_SECONDS", u64::MAX / 4));
    let jobs: usize = env_number("GROOMBAKE_ROUNDTRIP_JOBS", 2).max(1);
    let seed: u64 = env_number("GROOMBAKE_ROUNDTRIP_SEED", 37);
    let work = tempfile::tempdir().unwrap();
    let seeds_dir = work.path().join("seeds");
    std::fs::create_dir_all(&seeds_dir).unwrap();
    let formats = formats(&seeds_dir);
    let started = Instant::now();
    let next = AtomicUsize::new(0);
    let tallies: Mutex<Vec<Tally>> = Mutex::new(vec![Tally::default(); formats.len()]);
    let total = per_format * formats.len();
    std::thread::scope(|scope| {
        for job in 0..jobs {
            let dir = work.path().join(format!("job{job}"));
            std::fs::create_dir_all(&dir).unwrap();
            let (next, tallies, formats) = (&next, &tallies, &formats);
            scope.spawn(move || loop {
                if started.elapsed() > budget {
                    break;
                }
                // Formats take turns, so a run cut by its budget covers
                // every format alike.
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= total {
                    break;
                }
                let (n, f) = (k / formats.len(), k % formats.len());
                let tally = one_mutant(&dir, &formats[f], f, n, seed);
                tallies.lock().unwrap()[f].add(&tally);
            });
        }
    });
    let seconds = started.elapsed().as_secs_f64();
    let tallies = tallies.into_inner().unwrap();
    let mut table = String::from(
        "| format | mutants | inspected | converts: clean / warned / refused | panics | aborts | timeouts | exit 1 | silent differences | strict not refusing | leftovers | longest error line |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut all = Tally::default();
    for (format, t) in formats.iter().zip(&tallies) {
        table.push_str(&format!(
            "| {} | {} | {} | {} / {} / {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            format.name,
            t.mutants,
            t.inspected,
            t.clean,
            t.warned,
            t.refused,
            t.panics,
            t.aborts,
            t.timeouts,
            t.exit_one,
            t.silent,
            t.strict,
            t.leftovers,
            t.longest_line
        ));
        all.add(t);
    }
    let summary = format!(
        "{} mutants in {seconds:.0} s ({:.2} mutants/s, {jobs} jobs, seed {seed}); {} failures",
        all.mutants,
        all.mutants as f64 / seconds,
        all.failures.len()
    );
    println!("{table}\n{summary}");
    if let Ok(path) = std::env::var("GROOMBAKE_ROUNDTRIP_TABLE") {
        std::fs::write(path, format!("{table}\n{summary}\n")).unwrap();
    }
    for failure in all.failures.iter().take(30) {
        println!("FAILED {failure}");
    }
    assert!(all.mutants > 0, "no mutant ran");
    assert!(!all.failed(), "{summary}");
}
