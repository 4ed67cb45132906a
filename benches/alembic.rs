//! Alembic export and import throughput: a 5,000-strand groom of 40 points
//! each (200,000 points, 2.4 MB of positions), static and as 24 frames.
//! Throughput counts the bytes of positions written or read.

#![allow(clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use groom::{Attribute, AttributeValues, Frame, Groom};
use std::path::PathBuf;

const STRANDS: usize = 5_000;
const POINTS: usize = 40;
const FRAMES: usize = 24;

fn groom() -> Groom {
    let strands: Vec<Vec<[f32; 3]>> = (0..STRANDS)
        .map(|s| {
            let (x, z) = ((s % 100) as f32 * 0.2, (s / 100) as f32 * 0.2);
            (0..POINTS)
                .map(|k| [x + 0.01 * (k as f32).sin(), -0.5 * k as f32, z])
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(strands);
    let n = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float((0..n).map(|i| 0.01 - (i % POINTS) as f32 * 1e-4).collect()),
    ));
    groom.set_attribute(Attribute::new(
        "wetness",
        AttributeValues::Float(vec![0.5; n]),
    ));
    groom
}

fn frames(groom: &Groom) -> Vec<Frame> {
    (0..FRAMES)
        .map(|f| Frame {
            time: f as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0] + 0.1 * (f as f32 * 0.3).sin(), p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("groombake-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write_animated(path: &std::path::Path, groom: &Groom, frames: &[Frame]) {
    let options = exporters::AnimationOptions {
        fps: 24.0,
        frame_count: frames.len(),
    };
    let mut writer = exporters::animated(path, groom, options).unwrap();
    for frame in frames {
        writer.write_frame(frame).unwrap();
    }
    writer.finish().unwrap();
}

fn alembic(c: &mut Criterion) {
    let groom = groom();
    let frames = frames(&groom);
    let pose_bytes = (groom.vertex_count() * 12) as u64;
    let static_path = scratch("static.abc");
    let animated_path = scratch("animated.abc");
    // The import benchmarks read these, whichever benchmarks run.
    exporters::write(&static_path, &groom).unwrap();
    write_animated(&animated_path, &groom, &frames);

    let mut group = c.benchmark_group("alembic");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(pose_bytes));
    group.bench_function("export_static", |b| {
        b.iter(|| exporters::write(&static_path, &groom).unwrap())
    });
    group.bench_function("import_static", |b| {
        b.iter(|| importers::read(&static_path).unwrap())
    });
    group.throughput(Throughput::Bytes(pose_bytes * FRAMES as u64));
    group.bench_function("export_24_frames", |b| {
        b.iter(|| write_animated(&animated_path, &groom, &frames))
    });
    group.bench_function("import_24_frames", |b| {
        b.iter(|| importers::read(&animated_path).unwrap())
    });
    group.finish();
    let _ = std::fs::remove_dir_all(static_path.parent().unwrap());
}

criterion_group!(benches, alembic);
criterion_main!(benches);
