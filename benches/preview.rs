//! The budget: 100,000 strands of 32 vertices drawn at 1024x1024 in
//! under 2 s on 2 cores. The groom is generated in-process.

use criterion::{criterion_group, criterion_main, Criterion};
use groombake::generate::{generate, GeneratorParameters, StrandShape};
use groombake::preview::{render, PreviewOptions, View};
use std::hint::black_box;

fn big_groom(shape: StrandShape) -> groom::Groom {
    let parameters = GeneratorParameters {
        strands: 100_000,
        shape,
        // 31 edges: 32 vertices per strand.
        segment_length: 0.24 / 31.0,
        ..GeneratorParameters::default()
    };
    match generate(&parameters) {
        Ok(groom) => groom,
        Err(error) => panic!("generate: {error}"),
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("preview");
    group.sample_size(10);
    for (name, shape) in [
        ("straight", StrandShape::Straight),
        ("wavy", StrandShape::Wavy),
    ] {
        let groom = big_groom(shape);
        assert_eq!(groom.vertex_count(), 100_000 * 32);
        for view in [View::Front, View::Persp] {
            let options = PreviewOptions {
                width: 1024,
                height: 1024,
                view,
                ..PreviewOptions::default()
            };
            group.bench_function(format!("100k_x32_1024_{name}_{view:?}"), |b| {
                b.iter(|| render(black_box(&groom), black_box(&options)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
