//! Issue 38: `inspect` and `preview` read an animated cache a frame at a
//! time, so their memory is one frame plus the topology, not the file.
//! Measured as the child's peak resident memory (`wait4`'s `ru_maxrss`) on
//! two caches of the same groom, one with four times the frames of the
//! other: the peak may not grow by more than a small part of the
//! difference in file size. Alembic, USD crate files and GLB stream.

use crate::util::TestDir;
use groom::{Frame, Groom};
use std::path::Path;

const STRANDS: usize = 2_000;
const VERTICES: usize = 16;
/// Each frame is STRANDS x VERTICES x 12 bytes = 384 kB of points.
const FEW_FRAMES: usize = 30;

/// An animated Alembic cache of `frames` frames; frame `i` is the groom
/// raised by `i` cm, so the last frame holds the highest point.
fn write_cache(path: &Path, frames: usize) {
    let strands: Vec<Vec<[f32; 3]>> = (0..STRANDS)
        .map(|s| {
            let x = (s % 50) as f32;
            let z = (s / 50) as f32;
            (0..VERTICES).map(|v| [x, -(v as f32), z]).collect()
        })
        .collect();
    let groom = Groom::from_strands(strands);
    let options = exporters::AnimationOptions {
        fps: 24.0,
        frame_count: frames,
    };
    let mut writer = exporters::animated(path, &groom, options).unwrap();
    for i in 0..frames {
        let frame = Frame {
            time: i as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0], p[1] + i as f32, p[2]])
                .collect(),
            attributes: Vec::new(),
        };
        writer.write_frame(&frame).unwrap();
    }
    writer.finish().unwrap();
}

/// Runs groombake with `args` to success; its peak resident memory, bytes.
// The child is reaped by `wait4` (which gives its rusage), not `wait`.
#[allow(clippy::zombie_processes)]
fn peak_rss(dir: &TestDir, args: &[&str]) -> u64 {
    let child = dir
        .command()
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value for wait4 to fill.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: waits for our own child, writing into the two locals.
    let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(reaped, pid, "wait4");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "groombake {args:?} failed: status {status}"
    );
    // Linux reports kilobytes.
    usage.ru_maxrss as u64 * 1024
}

#[test]
fn inspect_and_preview_memory_does_not_grow_with_the_frames() {
    memory_does_not_grow_with_the_frames("abc");
}

#[test]
fn usd_crate_inspect_and_preview_memory_does_not_grow_with_the_frames() {
    memory_does_not_grow_with_the_frames("usdc");
}

#[test]
fn glb_inspect_and_preview_memory_does_not_grow_with_the_frames() {
    memory_does_not_grow_with_the_frames("glb");
}

fn memory_does_not_grow_with_the_frames(extension: &str) {
    let dir = TestDir::new();
    let (few_name, many_name) = (format!("few.{extension}"), format!("many.{extension}"));
    write_cache(&dir.path(&few_name), FEW_FRAMES);
    write_cache(&dir.path(&many_name), 4 * FEW_FRAMES);
    let size = |name: &str| std::fs::metadata(dir.path(name)).unwrap().len();
    let added = size(&many_name) - size(&few_name);
    assert!(added > 30 << 20, "{added} bytes");

    // The summary still covers every frame: the last one is the highest.
    let summary = dir.inspect(&many_name);
    assert_eq!(summary["frames"], 4 * FEW_FRAMES);
    assert_eq!(
        summary["frame_times"].as_array().unwrap().len(),
        4 * FEW_FRAMES
    );
    // glTF is metres: the exporter scales the groom's centimetres.
    let unit = if extension == "glb" { 0.01 } else { 1.0 };
    let bound = |which: &str| summary["bounds"][which][1].as_f64().unwrap() / unit;
    let top = bound("max");
    assert!(
        (top - (4 * FEW_FRAMES - 1) as f64).abs() < 1e-4,
        "{}",
        summary["bounds"]
    );
    assert!((bound("min") + 15.0).abs() < 1e-4, "{}", summary["bounds"]);

    for args in [
        &["inspect", "FILE", "--json"][..],
        &["inspect", "FILE"],
        &[
            "preview", "FILE", "-o", "out.png", "--frame", "1", "--size", "64x64",
        ],
    ] {
        let run = |file: &str| {
            let args: Vec<&str> = args
                .iter()
                .map(|&a| if a == "FILE" { file } else { a })
                .collect();
            peak_rss(&dir, &args)
        };
        let (few, many) = (run(&few_name), run(&many_name));
        let grown = many.saturating_sub(few);
        println!("{extension} {args:?}: peak {few} / {many} bytes, file +{added} bytes");
        // Reading the file whole grows by at least its size (the bytes)
        // and again by the frames decoded; one frame at a time, by about
        // nothing. A tenth of the added size leaves room for noise.
        assert!(
            grown < added / 10,
            "{extension} {args:?}: peak memory {few} bytes with {FEW_FRAMES} frames, {many} with {}: \
             grew by {grown} bytes for {added} more bytes of file",
            4 * FEW_FRAMES
        );
    }
}
