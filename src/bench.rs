//! The workload `groombake bench` and the criterion benches time: a
//! generated scalp groom (the default head's cap, ellipsoid 0.08 x 0.10 x
//! 0.09 m), optionally with hair-hair on and a head collider, stepped on a
//! given thread pool.
//!
//! Phase shares come from ablation, not from clocks inside the solver (so
//! timing cannot touch the results): the same workload is also run
//! without hair-hair and without the collider, and each phase's share is
//! the difference in CPU time per step. The rod solver's own phases
//! (forces, constraints, bonds) are one share; interpolation and export
//! are not part of this workload (reported as absent).

use crate::sim::parry3d::math::Vector;
use crate::sim::parry3d::shape::SharedShape;
use crate::sim::{
    self, Collider, ColliderSet, Environment, Material, Model, Pose, SimError, Solver,
    SolverParameters, StrandSet,
};
use std::path::PathBuf;
use std::time::Instant;

/// The head collider of the workload.
#[derive(Debug, Clone, PartialEq)]
pub enum HeadCollider {
    None,
    /// A ball of the head's smallest semi-axis (0.08 m) at its centre.
    Ball,
    /// A triangle mesh in metres, Y up, centred on the head (the sample
    /// `samples/head.obj` fits the scalp).
    Mesh(PathBuf),
}

/// What to time.
#[derive(Debug, Clone, PartialEq)]
pub struct Workload {
    pub strands: usize,
    pub vertices: usize,
    /// The elastic model (real hair's defaults for the physical one).
    pub model: Model,
    pub iterations: u32,
    /// `alpha` of the hair-hair penalty (20); `None` leaves it off.
    pub hair_hair: Option<f32>,
    pub collider: HeadCollider,
}

/// Why the workload cannot run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Generator(#[from] crate::generate::GeneratorError),
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error(transparent)]
    Import(#[from] importers::ImportError),
    #[error("{0} strands turned non-finite")]
    NonFinite(usize),
}

/// Everything one run steps: state, solver and colliders.
pub struct Scene {
    pub strands: StrandSet,
    pub solver: Solver,
    pub colliders: ColliderSet,
}

impl Workload {
    pub fn check(&self) -> Result<(), BenchError> {
        if self.vertices < 2 || self.vertices > 10_001 {
            return Err(BenchError::Input(
                "--vertices must be between 2 and 10001".into(),
            ));
        }
        if self.strands == 0 || self.strands.saturating_mul(self.vertices) > 50_000_000 {
            return Err(BenchError::Input(
                "--strands must be at least 1 and --strands x --vertices at most 50,000,000".into(),
            ));
        }
        Ok(())
    }

    /// The strands, solver and collider of this workload.
    pub fn scene(&self) -> Result<Scene, BenchError> {
        self.check()?;
        let groom = sim::bench_groom(self.strands, self.vertices)?;
        let solver = Solver::new(SolverParameters {
            iterations: self.iterations,
            hair_hair_strength: self.hair_hair,
            ..SolverParameters::default()
        })?;
        let material = Material {
            model: self.model,
            ..Material::default()
        };
        let strands = StrandSet::from_groom(&groom, &material)?;
        let mut colliders = ColliderSet::new();
        let shape = match &self.collider {
            HeadCollider::None => None,
            HeadCollider::Ball => Some(SharedShape::ball(0.08)),
            HeadCollider::Mesh(path) => {
                let (vertices, triangles) = importers::mesh::read_triangles(path)?;
                let vertices = vertices
                    .iter()
                    .map(|v| Vector::new(v[0], v[1], v[2]))
                    .collect();
                Some(SharedShape::trimesh(vertices, triangles).map_err(|e| {
                    BenchError::Input(format!(
                        "{}: not a usable collider mesh: {e}",
                        path.display()
                    ))
                })?)
            }
        };
        if let Some(shape) = shape {
            colliders.insert(Collider::new("head", shape, Pose::IDENTITY, 0.3));
        }
        Ok(Scene {
            strands,
            solver,
            colliders,
        })
    }
}

impl Scene {
    /// One step of the workload.
    pub fn step(&mut self) -> Result<(), BenchError> {
        let report =
            self.solver
                .step(&mut self.strands, &self.colliders, &Environment::default())?;
        if report.contained.is_empty() {
            Ok(())
        } else {
            Err(BenchError::NonFinite(report.contained.len()))
        }
    }
}

/// Timing of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    pub steps: usize,
    pub seconds: f64,
    /// CPU time of all threads of the process, when the platform says.
    pub cpu_seconds: Option<f64>,
}

impl Timing {
    /// CPU seconds per step (wall seconds where CPU time is unknown).
    pub fn cpu_per_step(&self) -> f64 {
        self.cpu_seconds.unwrap_or(self.seconds) / self.steps as f64
    }
}

/// Steps `scene` 10 times untimed, then `steps` times (by default as many
/// as fit in about `budget` seconds) on the current thread pool.
pub fn time(scene: &mut Scene, steps: Option<usize>, budget: f64) -> Result<Timing, BenchError> {
    for _ in 0..10 {
        scene.step()?;
    }
    let steps = match steps {
        Some(steps) => steps.max(1),
        None => {
            let start = Instant::now();
            scene.step()?;
            let one = start.elapsed().as_secs_f64().max(1e-6);
            ((budget / one) as usize).clamp(3, 10_000)
        }
    };
    let cpu_start = process_cpu_ns();
    let start = Instant::now();
    for _ in 0..steps {
        scene.step()?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let cpu_seconds = match (cpu_start, process_cpu_ns()) {
        (Some(a), Some(b)) => Some(b.saturating_sub(a) as f64 * 1e-9),
        _ => None,
    };
    Ok(Timing {
        steps,
        seconds,
        cpu_seconds,
    })
}

/// Shares of the step's CPU time, by ablation (fractions summing to 1;
/// `None` for phases not in the workload).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Shares {
    /// The rod solver: forces, constraints, bonds, velocities.
    pub solver: f64,
    pub collisions: Option<f64>,
    pub hair_hair: Option<f64>,
    pub interpolation: Option<f64>,
    pub export: Option<f64>,
}

/// The full report of `groombake bench`.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub workload: Workload,
    pub threads: usize,
    pub timing: Timing,
    pub shares: Shares,
    /// Peak resident memory of the process, bytes (Linux).
    pub peak_memory: Option<u64>,
}

impl Report {
    fn vertex_count(&self) -> f64 {
        (self.workload.strands * self.workload.vertices) as f64
    }

    /// Wall nanoseconds per vertex per step.
    pub fn ns_per_vertex_step(&self) -> f64 {
        self.timing.seconds * 1e9 / (self.timing.steps as f64 * self.vertex_count())
    }

    /// Wall nanoseconds per vertex per constraint iteration.
    pub fn ns_per_vertex_iteration(&self) -> f64 {
        self.ns_per_vertex_step() / f64::from(self.workload.iterations)
    }

    /// CPU nanoseconds (all threads) per vertex per step.
    pub fn cpu_ns_per_vertex_step(&self) -> Option<f64> {
        self.timing
            .cpu_seconds
            .map(|cpu| cpu * 1e9 / (self.timing.steps as f64 * self.vertex_count()))
    }
}

/// Times `workload` on the current thread pool; with hair-hair or a
/// collider, also the runs without them for the phase shares.
pub fn run(
    workload: &Workload,
    steps: Option<usize>,
    budget: f64,
    threads: usize,
) -> Result<Report, BenchError> {
    let timing = time(&mut workload.scene()?, steps, budget)?;
    let mut shares = Shares {
        solver: 1.0,
        ..Shares::default()
    };
    let with_collider = workload.collider != HeadCollider::None;
    if workload.hair_hair.is_some() || with_collider {
        let cost = |w: Workload| -> Result<f64, BenchError> {
            Ok(time(&mut w.scene()?, Some(timing.steps), budget)?.cpu_per_step())
        };
        let total = timing.cpu_per_step();
        let base = cost(Workload {
            hair_hair: None,
            collider: HeadCollider::None,
            ..workload.clone()
        })?;
        let collisions = if with_collider {
            let with = cost(Workload {
                hair_hair: None,
                ..workload.clone()
            })?;
            Some((with - base).max(0.0))
        } else {
            None
        };
        let hair_hair = workload
            .hair_hair
            .map(|_| (total - base - collisions.unwrap_or(0.0)).max(0.0));
        let sum = base + collisions.unwrap_or(0.0) + hair_hair.unwrap_or(0.0);
        shares = Shares {
            solver: base / sum,
            collisions: collisions.map(|c| c / sum),
            hair_hair: hair_hair.map(|h| h / sum),
            interpolation: None,
            export: None,
        };
    }
    Ok(Report {
        workload: workload.clone(),
        threads,
        timing,
        shares,
        peak_memory: peak_memory(),
    })
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

/// Peak resident set size (`VmHWM` of `/proc/self/status`), bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Positions after 30 steps on the mesh head on `threads` threads.
    fn positions_bits(threads: usize, hair_hair: Option<f32>) -> Vec<u32> {
        let workload = Workload {
            strands: 300,
            vertices: 24,
            model: Model::Physical,
            iterations: 5,
            hair_hair,
            collider: HeadCollider::Mesh(
                concat!(env!("CARGO_MANIFEST_DIR"), "/samples/head.obj").into(),
            ),
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut scene = workload.scene().unwrap();
        pool.install(|| (0..30).try_for_each(|_| scene.step()))
            .unwrap();
        scene
            .strands
            .positions()
            .iter()
            .flat_map(|p| p.map(f32::to_bits))
            .collect()
    }

    #[test]
    fn hair_hair_on_a_mesh_head_is_bit_identical_for_any_thread_count() {
        let one = positions_bits(1, Some(5.0));
        assert_eq!(one, positions_bits(2, Some(5.0)));
        assert_eq!(one, positions_bits(3, Some(5.0)));
        // Hair touched hair: the penalty changed the result.
        assert_ne!(one, positions_bits(1, None));
    }
}
