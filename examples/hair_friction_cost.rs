//! The cost of hair-hair friction (issue 33) per step, for instruction
//! counts under valgrind (docs/performance.md): hair resting on hair on a
//! head-size ball (`groombake::bench::resting_hair`), settled, then
//! `steps` steps with hair-hair friction `mu` (0: frictionless).
//!
//! `cargo run --release --example hair_friction_cost -- STRANDS MU SETTLE STEPS`
//! (defaults 300 0.3 360 20). Under `valgrind --tool=callgrind` with
//! `RAYON_NUM_THREADS=1`, the STEPS steps' instructions are the difference
//! from a run of 0 steps (toggling collection on `measured` counts only
//! this thread, not rayon's worker that runs the steps).

// A measuring tool: bad arguments or a failed step end it at once.
#![allow(clippy::expect_used)]

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: f64| -> f64 {
        args.get(i)
            .map(|a| a.parse().expect("a number"))
            .unwrap_or(default)
    };
    let strands = arg(0, 300.0) as usize;
    let mu = arg(1, 0.3) as f32;
    let settle = arg(2, 360.0) as usize;
    let steps = arg(3, 20.0) as usize;
    let friction = (mu > 0.0).then_some(mu);
    let mut scene = groombake::bench::resting_hair(strands, 32, friction, settle).expect("scene");
    let start = std::time::Instant::now();
    let contacts = measured(&mut scene, steps);
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{strands} strands x 32, mu {mu}: {steps} steps after {settle}, {:.3} ms per step, {:.0} contacts per step",
        seconds * 1e3 / steps.max(1) as f64,
        contacts as f64 / steps.max(1) as f64
    );
}

/// The measured steps; returns the contacts found in them.
#[inline(never)]
fn measured(scene: &mut groombake::bench::Scene, steps: usize) -> usize {
    let mut contacts = 0;
    for _ in 0..steps {
        scene.step().expect("step");
        contacts += scene.solver.hair_contact_count();
        if std::env::var_os("VERBOSE").is_some() {
            let fastest = scene
                .strands
                .velocities()
                .iter()
                .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
                .fold(0.0f32, f32::max);
            eprintln!(
                "contacts {} fastest {fastest:.4} m/s",
                scene.solver.hair_contact_count()
            );
        }
    }
    contacts
}
