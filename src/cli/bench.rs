//! `groombake bench`: times the solver on a generated groom.

use super::BadInput;
use clap::Args;
use groombake::sim::{self, ColliderSet, Environment, Material, Solver, SolverParameters};
use std::time::Instant;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Strands on a scalp cap.
    #[arg(long, default_value_t = 10_000)]
    strands: usize,
    /// Vertices per strand.
    #[arg(long, default_value_t = 32)]
    vertices: usize,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long, value_parser = super::bake::parse_threads)]
    threads: Option<usize>,
    /// Constraint iterations per step.
    #[arg(long, default_value_t = 5)]
    iterations: u32,
    /// Steps timed (after 10 untimed ones); by default enough for about 2 s.
    #[arg(long)]
    steps: Option<usize>,
    /// Hair-hair penalty strength (off by default).
    #[arg(long)]
    hair_hair: Option<f32>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    if args.vertices < 2 || args.vertices > 10_001 {
        return Err(BadInput("--vertices must be between 2 and 10001".into()).into());
    }
    if args.strands.saturating_mul(args.vertices) > 50_000_000 {
        return Err(BadInput("--strands x --vertices must be at most 50,000,000".into()).into());
    }
    if args.threads == Some(0) {
        return Err(BadInput("--threads must be at least 1".into()).into());
    }
    let groom = sim::bench_groom(args.strands, args.vertices)?;
    let parameters = SolverParameters {
        iterations: args.iterations,
        hair_hair_strength: args.hair_hair,
        ..SolverParameters::default()
    };
    let mut solver = Solver::new(parameters).map_err(|e| BadInput(e.to_string()))?;
    let mut strands = sim::StrandSet::from_groom(&groom, &Material::default())?;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(threads) = args.threads {
        builder = builder.num_threads(threads);
    }
    let pool = builder.build()?;
    let threads = pool.current_num_threads();
    let colliders = ColliderSet::new();
    let environment = Environment::default();
    let vertex_iterations = (strands.vertex_count() as f64) * f64::from(args.iterations);
    let (steps, seconds, cpu_ns) =
        pool.install(|| -> anyhow::Result<(usize, f64, Option<u64>)> {
            let mut step = |solver: &mut Solver| -> anyhow::Result<()> {
                let report = solver.step(&mut strands, &colliders, &environment)?;
                if !report.contained.is_empty() {
                    anyhow::bail!("{} strands turned non-finite", report.contained.len());
                }
                Ok(())
            };
            for _ in 0..10 {
                step(&mut solver)?;
            }
            let steps = match args.steps {
                Some(steps) => steps.max(1),
                None => {
                    let start = Instant::now();
                    step(&mut solver)?;
                    let one = start.elapsed().as_secs_f64().max(1e-6);
                    ((2.0 / one) as usize).clamp(3, 10_000)
                }
            };
            let cpu_start = process_cpu_ns();
            let start = Instant::now();
            for _ in 0..steps {
                step(&mut solver)?;
            }
            let seconds = start.elapsed().as_secs_f64();
            let cpu = match (cpu_start, process_cpu_ns()) {
                (Some(a), Some(b)) => Some(b.saturating_sub(a)),
                _ => None,
            };
            Ok((steps, seconds, cpu))
        })?;
    let ns = seconds * 1e9 / (steps as f64 * vertex_iterations);
    // CPU time of all threads: on a busy machine the wall clock overstates
    // the cost; this does not.
    let cpu_ns = cpu_ns.map(|cpu| cpu as f64 / (steps as f64 * vertex_iterations));
    let ms_per_step = seconds * 1e3 / steps as f64;
    if args.json {
        let report = serde_json::json!({
            "strands": args.strands,
            "vertices": args.vertices,
            "threads": threads,
            "iterations": args.iterations,
            "hair_hair": args.hair_hair,
            "steps": steps,
            "seconds": seconds,
            "ms_per_step": ms_per_step,
            "ns_per_vertex_iteration": ns,
            "cpu_ns_per_vertex_iteration": cpu_ns,
        });
        println!("{report}");
    } else {
        println!(
            "{} strands x {} vertices, {} iterations, {} threads: {} steps in {:.3} s, \
             {:.2} ms per step, {:.2} ns per vertex-iteration ({} ns of CPU time)",
            args.strands,
            args.vertices,
            args.iterations,
            threads,
            steps,
            seconds,
            ms_per_step,
            ns,
            cpu_ns.map_or("?".to_string(), |c| format!("{c:.2}"))
        );
    }
    Ok(())
}

/// CPU time of every thread of this process so far, in nanoseconds (Linux
/// `/proc/self/task/*/schedstat`); `None` elsewhere.
fn process_cpu_ns() -> Option<u64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    let mut total = 0u64;
    for task in tasks.flatten() {
        let text = std::fs::read_to_string(task.path().join("schedstat")).ok()?;
        total += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total)
}
