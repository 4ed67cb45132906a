//! Solver cost per vertex-iteration (the figure of issue 3): one step of
//! 1,000 strands x 32 vertices, 5 iterations, hair-hair off, on 1 and 2
//! threads. `groombake bench` measures the full 10,000-strand case.

// A benchmark harness: a failure to set up is a bug to see at once.
#![allow(clippy::expect_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use groombake::sim::{
    bench_groom, ColliderSet, Environment, Material, Solver, SolverParameters, StrandSet,
};

fn step(c: &mut Criterion) {
    let groom = bench_groom(1_000, 32).expect("bench groom");
    let parameters = SolverParameters::default();
    let mut group = c.benchmark_group("solver_step");
    group.throughput(Throughput::Elements(
        (groom.points.len() * parameters.iterations as usize) as u64,
    ));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        let mut strands = StrandSet::from_groom(&groom, &Material::default()).expect("strands");
        let mut solver = Solver::new(parameters).expect("solver");
        let colliders = ColliderSet::new();
        let environment = Environment::default();
        group.bench_function(format!("1000x32_5it_{threads}threads"), |b| {
            b.iter(|| {
                pool.install(|| {
                    solver
                        .step(&mut strands, &colliders, &environment)
                        .expect("step")
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
