//! The mutant harness: every reader on thousands of damaged copies of real
//! files (truncations, bit flips, 4- and 8-byte fields set to 0, 0x7FFFFFFF
//! and 0xFFFFFFFF, number swaps in text formats, JSON-level edits for glTF),
//! in-process, with a deterministic seed. Each mutant must give a groom or
//! an error: no panic (caught with `catch_unwind`), none over 20 s, and
//! none whose reading allocates more than 256 MB at its peak (measured by
//! this binary's counting global allocator; this file is its own test
//! binary, and its one test runs the mutants one after another, so the
//! count is the reader's alone).
//!
//! `GROOMBAKE_MUTANTS` sets the mutants per format (2,000 by default, to
//! keep CI short; the acceptance run uses 20,000), `GROOMBAKE_MUTANT_SEED`
//! the seed. Run it optimised for the full count:
//! `GROOMBAKE_MUTANTS=20000 cargo test --release -p importers --test mutants -- --nocapture`.

// Test code: a failed setup step may panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod mutation;

use groom::{Attribute, AttributeValues, Frame, Groom, Units};
use mutation::{mutate, Kinds, Rng};
use std::alloc::{GlobalAlloc, Layout, System};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Counts the bytes live on the heap and the most live at once.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded unchanged to the system allocator.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded unchanged to the system allocator.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                let grown = new_size - layout.size();
                let live = LIVE.fetch_add(grown, Ordering::Relaxed) + grown;
                PEAK.fetch_max(live, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

const MAX_SECONDS: f64 = 20.0;
const MAX_PEAK_BYTES: usize = 256 << 20;

/// A reader under test: the file name it is given and the function.
type Reader = fn(&Path, &[u8]) -> Result<(), String>;

struct Format {
    name: &'static str,
    /// Text formats get number swaps; glTF JSON gets JSON edits too.
    text: bool,
    json: bool,
    seeds: Vec<Vec<u8>>,
    readers: Vec<(&'static str, Reader)>,
}

fn ok<T, E: std::fmt::Display>(result: Result<T, E>) -> Result<(), String> {
    result.map(|_| ()).map_err(|e| e.to_string())
}

/// A small groom with every attribute type, a per-strand one and frames.
fn sample_groom(frames: bool) -> Groom {
    let strands: Vec<Vec<[f32; 3]>> = (0..4)
        .map(|s| {
            (0..3 + s)
                .map(|i| [s as f32 * 0.7, 160.0 - 1.3 * i as f32, 0.2 * (i * s) as f32])
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands);
    groom.units = Units::CENTIMETERS;
    let n = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float((0..n).map(|i| 0.008 + 0.0001 * i as f32).collect()),
    ));
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(vec![[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "clump",
        AttributeValues::Int(vec![3, -1, 70_000, i32::MIN]),
    ));
    if frames {
        groom.frames = (1..3)
            .map(|k| Frame {
                time: k as f64 / 24.0,
                points: groom
                    .points
                    .iter()
                    .map(|p| [p[0] + 0.1 * k as f32, p[1], p[2]])
                    .collect(),
                attributes: Vec::new(),
            })
            .collect();
    }
    groom
}

/// The groom written by groombake's own exporter (animated where the
/// format holds frames), as the first seed of each format.
fn exported(dir: &Path, ext: &str) -> Vec<u8> {
    let path = dir.join(format!("seed.{ext}"));
    if exporters::write(&path, &sample_groom(true)).is_err() {
        exporters::write(&path, &sample_groom(false))
            .unwrap_or_else(|e| panic!("writing a {ext} seed: {e}"));
    }
    std::fs::read(&path).unwrap()
}

fn repo_file(relative: &str) -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(relative);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn formats(dir: &Path) -> Vec<Format> {
    let format = |name, text, json, seeds, readers| Format {
        name,
        text,
        json,
        seeds,
        readers,
    };
    vec![
        format(
            "glTF (.gltf, .glb)",
            true,
            true,
            vec![
                exported(dir, "gltf"),
                exported(dir, "glb"),
                repo_file("samples/pillow.glb"),
            ],
            vec![
                ("gltf::parse", |p, b| ok(importers::gltf::parse(p, b))),
                ("gltf::read_streamed_bytes", |p, b| {
                    ok(importers::gltf::read_streamed_bytes(p, b))
                }),
                ("gltf::parse_triangles", |p, b| {
                    ok(importers::gltf::parse_triangles(p, b))
                }),
            ],
        ),
        format(
            "USD text (.usda)",
            true,
            false,
            vec![
                exported(dir, "usda"),
                repo_file("importers/tests/data/reference.usda"),
            ],
            vec![("usd::read_bytes", |p, b| {
                ok(importers::usd::read_bytes(p, b))
            })],
        ),
        format(
            "USD crate (.usdc)",
            false,
            false,
            vec![
                exported(dir, "usdc"),
                repo_file("importers/tests/data/reference.usdc"),
                repo_file("importers/tests/data/blender501_hair_by_usd_core.usdc"),
                repo_file("importers/tests/data/streaming_edges.usdc"),
            ],
            vec![
                ("usd::read_bytes", |p, b| {
                    ok(importers::usd::read_bytes(p, b))
                }),
                ("usd::read_streamed_bytes", |p, b| {
                    ok(importers::usd::read_streamed_bytes(p, b))
                }),
            ],
        ),
        format(
            "Alembic (.abc)",
            false,
            false,
            vec![
                exported(dir, "abc"),
                repo_file("importers/tests/data/xform_cubic_indexed.abc"),
            ],
            vec![("abc::parse", |p, b| ok(importers::abc::parse(p, b)))],
        ),
        format(
            "Cem Yuksel .hair",
            false,
            false,
            vec![exported(dir, "hair")],
            vec![("hair::parse", |p, b| ok(importers::hair::parse(p, b)))],
        ),
        format(
            "USC-HairSalon .data",
            false,
            false,
            vec![exported(dir, "data")],
            vec![("data::parse", |p, b| ok(importers::data::parse(p, b)))],
        ),
        format(
            "Wavefront .obj",
            true,
            false,
            vec![exported(dir, "obj"), repo_file("samples/head.obj")],
            vec![
                ("obj::parse", |p, b| ok(importers::obj::parse(p, b))),
                ("mesh::parse_obj", |p, b| {
                    ok(importers::mesh::parse_obj(p, b))
                }),
            ],
        ),
    ]
}

#[derive(Default)]
struct Tally {
    mutants: usize,
    errors: usize,
    panics: Vec<String>,
    slowest: Duration,
    slowest_mutant: String,
    peak: usize,
    peak_mutant: String,
}

#[test]
fn mutants_of_every_format_give_a_groom_or_an_error_within_bounds() {
    let count: usize = std::env::var("GROOMBAKE_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000);
    let seed: u64 = std::env::var("GROOMBAKE_MUTANT_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(12);
    let dir = std::env::temp_dir().join(format!("importers-mutants-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let formats = formats(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    // Panics are expected to be caught and counted, not printed.
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    for format in &formats {
        let mut rng = Rng(seed ^ format.name.len() as u64);
        let mut tally = Tally::default();
        let started = Instant::now();
        for n in 0..count {
            let seed_bytes = &format.seeds[n % format.seeds.len()];
            let kinds = Kinds {
                text: format.text,
                json: format.json,
            };
            let (what, bytes) = mutate(&mut rng, seed_bytes, kinds);
            for &(reader, read) in &format.readers {
                let ext = if bytes.starts_with(b"glTF") {
                    "glb"
                } else {
                    "gltf"
                };
                let path = PathBuf::from(format!("mutant.{ext}"));
                let live = LIVE.load(Ordering::Relaxed);
                PEAK.store(live, Ordering::Relaxed);
                let start = Instant::now();
                let outcome = catch_unwind(AssertUnwindSafe(|| read(&path, &bytes)));
                let took = start.elapsed();
                let peak = PEAK.load(Ordering::Relaxed).saturating_sub(live);
                tally.mutants += 1;
                let label = format!(
                    "mutant {n} of seed {} ({what}), {reader}",
                    n % format.seeds.len()
                );
                match outcome {
                    Ok(Ok(())) => {}
                    Ok(Err(_)) => tally.errors += 1,
                    Err(panic) => {
                        let message = panic
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_default();
                        tally.panics.push(format!("{label}: {message}"));
                    }
                }
                if took > tally.slowest {
                    tally.slowest = took;
                    tally.slowest_mutant = label.clone();
                }
                if peak > tally.peak {
                    tally.peak = peak;
                    tally.peak_mutant = label;
                }
            }
        }
        println!(
            "{}: {} readings of {count} mutants in {:.1} s, {} errors, {} panics; slowest {:.3} s ({}); peak {:.1} MB ({})",
            format.name,
            tally.mutants,
            started.elapsed().as_secs_f64(),
            tally.errors,
            tally.panics.len(),
            tally.slowest.as_secs_f64(),
            tally.slowest_mutant,
            tally.peak as f64 / 1e6,
            tally.peak_mutant,
        );
        for panic in tally.panics.iter().take(5) {
            println!("  PANIC {panic}");
        }
        if !tally.panics.is_empty() {
            failures.push(format!("{}: {} panics", format.name, tally.panics.len()));
        }
        if tally.slowest.as_secs_f64() > MAX_SECONDS {
            failures.push(format!("{}: {}", format.name, tally.slowest_mutant));
        }
        if tally.peak > MAX_PEAK_BYTES {
            failures.push(format!(
                "{}: peak {} bytes: {}",
                format.name, tally.peak, tally.peak_mutant
            ));
        }
    }
    let _ = std::panic::take_hook();
    assert!(failures.is_empty(), "{failures:#?}");
}
