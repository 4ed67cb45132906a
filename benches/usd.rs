//! USD export and import throughput: a generated groom of 10,000 strands of
//! 32 vertices (320,000 points) with widths and a per-strand attribute,
//! written and read as `.usda` and `.usdc`, and an animated `.usdc` of 10
//! frames streamed through `exporters::animated`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use groom::{Attribute, AttributeValues, Groom};
use groombake::generate::{generate, GeneratorParameters, StrandShape};
use std::hint::black_box;
use std::path::PathBuf;

fn big_groom() -> Groom {
    let parameters = GeneratorParameters {
        strands: 10_000,
        shape: StrandShape::Wavy,
        segment_length: 0.24 / 31.0,
        ..GeneratorParameters::default()
    };
    let mut groom = match generate(&parameters) {
        Ok(groom) => groom,
        Err(error) => panic!("generate: {error}"),
    };
    let vertices = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(vec![0.0001; vertices]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "hydrogen_bonds",
        AttributeValues::Float(vec![0.35; groom.strand_count()]),
    ));
    groom
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("groombake-bench-{}-{name}", std::process::id()))
}

fn bench(c: &mut Criterion) {
    let groom = big_groom();
    let vertices = groom.vertex_count() as u64;
    let mut group = c.benchmark_group("usd");
    group.sample_size(10);
    group.throughput(Throughput::Elements(vertices));
    for ext in ["usda", "usdc"] {
        let path = scratch(&format!("static.{ext}"));
        group.bench_function(format!("write_{ext}"), |b| {
            b.iter(|| exporters::write(&path, black_box(&groom)).map_err(|e| e.to_string()))
        });
        group.bench_function(format!("read_{ext}"), |b| {
            b.iter(|| importers::read(black_box(&path)).map_err(|e| e.to_string()))
        });
        let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        eprintln!("{ext}: {size} bytes for {vertices} points");
        let _ = std::fs::remove_file(&path);
    }
    let frames: Vec<groom::Frame> = (0..10)
        .map(|i| groom::Frame {
            time: i as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0] + i as f32 * 1e-3, p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    group.throughput(Throughput::Elements(vertices * frames.len() as u64));
    let path = scratch("animated.usdc");
    group.bench_function("write_animated_usdc_10_frames", |b| {
        b.iter(|| {
            let options = exporters::AnimationOptions {
                fps: 24.0,
                frame_count: frames.len(),
            };
            let mut writer =
                exporters::animated(&path, &groom, options).map_err(|e| e.to_string())?;
            for frame in &frames {
                writer.write_frame(frame).map_err(|e| e.to_string())?;
            }
            writer.finish().map_err(|e| e.to_string())
        })
    });
    let _ = std::fs::remove_file(&path);
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
