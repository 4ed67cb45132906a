//! Solver cost per step (the workload of `groombake bench`): 1,000
//! strands x 32 vertices, the physical model at its default iterations, on
//! 1 and 2 threads, free, with hair-hair (alpha 5, pairwise and
//! volumetric), with a ball head, with the mesh head (samples/head.obj),
//! with the pillow, and as guides driving 5,000 render hairs interpolated
//! and exported (Alembic, 24 frames per second: every 15th step); and the
//! paper's model free at 5 iterations. `groombake bench` measures 10,000
//! strands and more.

// A benchmark harness: a failure to set up is a bug to see at once.
#![allow(clippy::expect_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use groombake::bench::{HeadCollider, Treatment, Workload};
use groombake::sim::Model;

fn step(c: &mut Criterion) {
    let head = concat!(env!("CARGO_MANIFEST_DIR"), "/samples/head.obj");
    let plain = Workload::free_hair(1_000, 32);
    let cases = [
        ("free", plain.clone()),
        (
            "paper_free",
            Workload {
                model: Model::Paper,
                iterations: 5,
                tolerance: 0.0,
                ..plain.clone()
            },
        ),
        (
            "hair_hair",
            Workload {
                hair_hair: Some(5.0),
                ..plain.clone()
            },
        ),
        (
            "ball",
            Workload {
                collider: HeadCollider::Ball,
                ..plain.clone()
            },
        ),
        (
            "mesh",
            Workload {
                collider: HeadCollider::Mesh(head.into()),
                ..plain.clone()
            },
        ),
        (
            "hair_hair_volumetric",
            Workload {
                hair_hair: Some(5.0),
                volumetric: Some(groombake::sim::Volumetric::default()),
                ..plain.clone()
            },
        ),
        (
            "mesh_pillow",
            Workload {
                collider: HeadCollider::Mesh(head.into()),
                pillow: true,
                ..plain.clone()
            },
        ),
        (
            "guides_5k_render",
            Workload {
                render: Some(5_000),
                ..plain.clone()
            },
        ),
        (
            "wet",
            Workload {
                treatment: Treatment::Wet,
                ..plain.clone()
            },
        ),
        (
            "blow_dry",
            Workload {
                treatment: Treatment::BlowDry,
                ..plain.clone()
            },
        ),
        (
            "mesh_hair_hair",
            Workload {
                hair_hair: Some(5.0),
                collider: HeadCollider::Mesh(head.into()),
                ..plain.clone()
            },
        ),
    ];
    let mut group = c.benchmark_group("solver_step");
    group.throughput(Throughput::Elements(
        (plain.strands * plain.vertices) as u64,
    ));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        for (name, workload) in &cases {
            let mut scene = workload.scene().expect("scene");
            // Past the first fall, as `groombake bench` times it.
            pool.install(|| (0..10).try_for_each(|_| scene.step()))
                .expect("warm-up");
            let iterations = workload.iterations;
            let id = format!("1000x32_{iterations}it_{name}_{threads}threads");
            group.bench_function(id, |b| {
                b.iter(|| pool.install(|| scene.step().expect("step")))
            });
        }
    }
    group.finish();
}

/// Hair-hair friction's cost (issue 33: at most 1.5x the frictionless
/// step): 300 strands x 32 of 24 cm hair combed down over a head-size
/// ball, settled 1 s, then the same step with pairwise hair-hair
/// frictionless and with friction mu 0.3, on 1 thread
/// (`examples/hair_friction_cost.rs` counts the contacts and, under
/// valgrind, the instructions).
fn hair_friction(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let mut group = c.benchmark_group("hair_friction_step");
    for (name, mu) in [("frictionless", None), ("mu_0.3", Some(0.3))] {
        let mut scene = pool
            .install(|| groombake::bench::resting_hair(300, 32, mu, 360))
            .expect("scene");
        group.bench_function(format!("resting_300x32_{name}"), |b| {
            b.iter(|| pool.install(|| scene.step().expect("step")))
        });
    }
    group.finish();
}

criterion_group!(benches, step, hair_friction);
criterion_main!(benches);
