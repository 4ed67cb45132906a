//! One resource budget for everything a run may be asked to do: the groom's
//! vertices, the steps of a bake, the work of stepping every vertex, the
//! frames and bytes of each output, the worker threads. Timelines and
//! generator parameters are checked against it before anything is
//! allocated or simulated, so no input can ask for unbounded memory or time.
//!
//! The numbers leave room for a full head (150,000 strands of 64 vertices)
//! baked for hours of simulated time; past them a run would take days or
//! more memory than a workstation has.

/// Vertices of a groom (about 300 bytes of simulation state each: 6 GB).
pub const MAX_VERTICES: u64 = 20_000_000;
/// Steps of one bake over all stages (a day at the default 1/360 s is 31 M).
pub const MAX_STEPS: u64 = 50_000_000;
/// Vertices times steps: the solver's work (about 10 ns each: a day).
pub const MAX_VERTEX_STEPS: u64 = 10_000_000_000_000;
/// Frames of one animated export.
pub const MAX_FRAMES: u64 = 1_000_000;
/// Estimated bytes of one output (points of every frame, 12 bytes a point).
pub const MAX_OUTPUT_BYTES: u64 = 64 << 30;
/// Worker threads.
pub const MAX_THREADS: usize = 1024;
/// Cell-triangle entries of a collider mesh's distance grid (8 bytes each
/// while it is built: 512 MB; a mesh of small triangles lists a few
/// hundred per triangle).
pub const MAX_GRID_ENTRIES: u64 = 64_000_000;
/// The largest coordinate of a scene, metres (a collider mesh's vertex
/// after its scale, a groom's translation): past 10 km an f32 position
/// resolves 1 mm, far coarser than a hair (50 to 100 micrometres).
pub const MAX_COORDINATE: f64 = 1e4;
/// Bytes of a timeline or batch manifest (a long timeline is a few KB).
pub const MAX_TIMELINE_BYTES: u64 = 16 << 20;
/// Bytes of an input file read whole (a groom, a collider mesh).
pub const MAX_INPUT_BYTES: u64 = importers::MAX_FILE_BYTES;
/// The smallest time step, seconds.
pub const MIN_DT: f64 = 1e-6;

/// Vertices of `strands` strands of `vertices_per_strand` each, if within
/// the budget; the message says why not.
pub fn check_vertices(strands: u64, vertices_per_strand: u64) -> Result<u64, String> {
    match strands.checked_mul(vertices_per_strand) {
        Some(total) if total <= MAX_VERTICES => Ok(total),
        _ => Err(format!(
            "{strands} strands of {vertices_per_strand} vertices are more than the \
             {MAX_VERTICES} vertices a groom may have"
        )),
    }
}

/// The work of a bake of `vertices` over `steps`, if within the budget.
pub fn check_work(vertices: u64, steps: u64) -> Result<(), String> {
    if steps > MAX_STEPS {
        return Err(format!(
            "{steps} time steps in all: more than {MAX_STEPS} (raise dt or shorten the stages)"
        ));
    }
    match vertices.checked_mul(steps) {
        Some(work) if work <= MAX_VERTEX_STEPS => Ok(()),
        _ => Err(format!(
            "{vertices} vertices over {steps} steps is more than {MAX_VERTEX_STEPS} \
             vertex steps (raise dt, shorten the stages or use fewer strands)"
        )),
    }
}

/// An animated output of `frames` frames of `vertices`, if within the budget.
pub fn check_output(frames: u64, vertices: u64) -> Result<(), String> {
    if frames > MAX_FRAMES {
        return Err(format!("{frames} frames: more than {MAX_FRAMES}"));
    }
    match frames.checked_mul(vertices).and_then(|n| n.checked_mul(12)) {
        Some(bytes) if bytes <= MAX_OUTPUT_BYTES => Ok(()),
        _ => Err(format!(
            "{frames} frames of {vertices} vertices are more than {} GiB",
            MAX_OUTPUT_BYTES >> 30
        )),
    }
}

/// A collider grid of `entries` cell-triangle entries for `triangles`
/// triangles, if within the budget.
pub fn check_grid_entries(entries: u64, triangles: u64) -> Result<(), String> {
    if entries <= MAX_GRID_ENTRIES {
        Ok(())
    } else {
        Err(format!(
            "the distance grid of {triangles} triangles needs {entries} cell entries, more than \
             {MAX_GRID_ENTRIES} (a few triangles far larger than the rest?)"
        ))
    }
}

/// A `--threads` value, if within the budget.
pub fn check_threads(threads: usize) -> Result<usize, String> {
    if (1..=MAX_THREADS).contains(&threads) {
        Ok(threads)
    } else {
        Err(format!("--threads must be 1 to {MAX_THREADS}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_are_bounded_not_only_factors() {
        assert!(check_vertices(10_000_000, 10_001).is_err());
        assert!(check_vertices(u64::MAX, u64::MAX).is_err());
        assert_eq!(check_vertices(200, 25), Ok(5000));
        assert!(check_work(5000, 3600).is_ok());
        assert!(check_work(MAX_VERTICES, MAX_STEPS).is_err());
        assert!(check_output(100, 5000).is_ok());
        assert!(check_output(MAX_FRAMES, MAX_VERTICES).is_err());
        assert!(check_threads(0).is_err());
        assert!(check_threads(1_000_000).is_err());
    }
}
