//! No per-step allocation in hair-hair and the mesh collider: a counting
//! allocator compares the allocations of a solver step with hair-hair and
//! the mesh head against the same step of free hair, after warm-up.
//! (The rod solver's own step allocates a fixed number of times, for its
//! per-strand views, active flags and rayon's chunks; that count is
//! printed and must not grow with hair-hair or a mesh.)

// A test harness: a failure to set up is a bug to see at once.
#![allow(clippy::unwrap_used)]

use groombake::bench::{HeadCollider, Workload};
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

/// Allocations of each of 5 steps after 20 warm-up steps, on one thread
/// (rayon's splitting, and so its own allocations, is then fixed).
fn allocations_per_step(workload: &Workload) -> Vec<usize> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut scene = workload.scene().unwrap();
    pool.install(|| {
        for _ in 0..20 {
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

#[test]
fn hair_hair_and_a_mesh_collider_allocate_nothing_per_step() {
    let free = Workload {
        strands: 400,
        vertices: 32,
        model: groombake::sim::Model::Physical,
        iterations: 5,
        hair_hair: None,
        collider: HeadCollider::None,
    };
    let full = Workload {
        hair_hair: Some(5.0),
        collider: HeadCollider::Mesh(
            concat!(env!("CARGO_MANIFEST_DIR"), "/samples/head.obj").into(),
        ),
        ..free.clone()
    };
    let baseline = allocations_per_step(&free);
    let with = allocations_per_step(&full);
    eprintln!(
        "allocations per step: free hair {baseline:?}, with hair-hair and the mesh head {with:?}"
    );
    assert_eq!(with, baseline);
}
