//! No per-step allocation in the solver: a counting allocator counts the
//! allocations of whole `Solver::step`s after warm-up, with hair-hair and
//! the mesh head and a pillow on, for both elastic models (the physical model's direct
//! solve and the paper model's SIMD groups), on one and two threads.

// A test harness: a failure to set up is a bug to see at once.
#![allow(clippy::unwrap_used)]

use groombake::bench::{HeadCollider, Treatment, Workload};
use groombake::sim::{Material, Model, StrandSet};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: forwards the caller's layout to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as `alloc` and `dealloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations of each of 5 steps after 5 warm-up steps on `threads`
/// threads (the steps run inside the pool, as a bake's do). The counter
/// is global, so the tests of this file run one at a time (see `LOCK`).
fn allocations_per_step(workload: &Workload, model: Model, threads: usize) -> Vec<usize> {
    let _one_at_a_time = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut scene = workload.scene().unwrap();
        let groom = groombake::sim::bench_groom(workload.strands, workload.vertices).unwrap();
        let material = Material {
            model,
            ..Material::default()
        };
        scene.strands = StrandSet::from_groom(&groom, &material).unwrap();
        for _ in 0..5 {
            scene.step().unwrap();
        }
        (0..5)
            .map(|_| {
                let before = ALLOCATIONS.load(Ordering::Relaxed);
                scene.step().unwrap();
                ALLOCATIONS.load(Ordering::Relaxed) - before
            })
            .collect()
    })
}

static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn full() -> Workload {
    Workload {
        // At the default tolerance strands stop iterating at different
        // counts: the lanes' bookkeeping allocates nothing either.
        iterations: 5,
        hair_hair: Some(5.0),
        collider: HeadCollider::Mesh(
            concat!(env!("CARGO_MANIFEST_DIR"), "/samples/head.obj").into(),
        ),
        pillow: true,
        ..Workload::free_hair(403, 32)
    }
}

#[test]
fn a_solver_step_with_hair_hair_and_a_mesh_head_allocates_nothing_once_warm() {
    for model in [Model::Physical, Model::Paper] {
        for threads in [1, 2] {
            let counts = allocations_per_step(&full(), model, threads);
            assert_eq!(counts, [0; 5], "{model:?} on {threads} thread(s)");
        }
    }
    let volumetric = Workload {
        hair_hair: None,
        volumetric: Some(groombake::sim::Volumetric::default()),
        ..full()
    };
    assert_eq!(
        allocations_per_step(&volumetric, Model::Physical, 2),
        [0; 5]
    );
}

#[test]
fn free_hair_allocates_nothing_per_step_either() {
    let free = Workload {
        hair_hair: None,
        collider: HeadCollider::None,
        ..full()
    };
    assert_eq!(allocations_per_step(&free, Model::Physical, 1), [0; 5]);
    // Nor a driven step (bond drive, blower).
    for treatment in [Treatment::Wet, Treatment::BlowDry] {
        let driven = Workload {
            treatment,
            ..free.clone()
        };
        assert_eq!(
            allocations_per_step(&driven, Model::Physical, 1),
            [0; 5],
            "{treatment:?}"
        );
    }
}
