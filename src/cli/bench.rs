//! `groombake bench`: times the solver on a generated groom, optionally
//! with hair-hair and a head collider, and shows each phase's share.

use super::BadInput;
use clap::Args;
use groombake::bench::{self, HeadCollider, Treatment, Workload};
use groombake::sim::Model;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Strands on a scalp cap (default 10,000).
    #[arg(long, conflicts_with = "guides")]
    strands: Option<usize>,
    /// Simulated guides on a scalp cap (as --strands), which drive the
    /// render hairs of --render.
    #[arg(long, requires = "render")]
    guides: Option<usize>,
    /// Render hairs grown between the guides, interpolated from them and
    /// written to an animated Alembic file (removed after) 24 times per
    /// simulated second, as a bake delivers them.
    #[arg(long, value_name = "R")]
    render: Option<usize>,
    /// A named workload: `full-head` is 5,000 guides x 32 vertices driving
    /// 100,000 render hairs, the mesh head samples/head.obj (or the mesh of
    /// --collider), a pillow and hair-hair (alpha 5); it also prints the
    /// projected cost of 5 simulated seconds (from wall and from CPU time).
    /// `--hair-hair-mode volumetric` replaces its pairwise hair-hair with
    /// the volumetric grid, `--hair-hair ALPHA` sets its pairwise alpha;
    /// --strands, --guides, --render, --vertices and --pillow are the
    /// preset's own and refused with it.
    #[arg(long, value_parser = ["full-head"])]
    preset: Option<String>,
    /// A pillow: a slab that moves in from outside the hair at 18 cm/s and presses against the left side of the head (from 1.5 s).
    #[arg(long)]
    pillow: bool,
    /// Vertices per strand (default 32).
    #[arg(long)]
    vertices: Option<usize>,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(short = 'j', long, value_parser = super::bake::parse_threads)]
    threads: Option<usize>,
    /// Elastic model: `physical` (real hair, direct solve) or `paper`.
    #[arg(long, default_value = "physical", value_parser = ["physical", "paper"])]
    model: String,
    /// Constraint iterations per step (default: the model's, at most 2
    /// physical, 5 paper). Given alone, every strand gets exactly this many.
    #[arg(long)]
    iterations: Option<u32>,
    /// Physical model: a strand stops iterating once its edges are within
    /// this fraction of their length, 0-0.01 (default 0.001 without
    /// --iterations, 0 with it: all iterations).
    #[arg(long, value_name = "FRACTION")]
    tolerance: Option<f32>,
    /// Steps timed (after 10 untimed ones); by default enough for about 2 s.
    #[arg(long)]
    steps: Option<usize>,
    /// Hair-hair penalty strength alpha of (20), 0-10 (off by default).
    #[arg(long, value_name = "ALPHA")]
    hair_hair: Option<f32>,
    /// Coulomb friction coefficient between hairs, 0-1, with pairwise
    /// --hair-hair and the physical model (off by default).
    #[arg(long, value_name = "MU")]
    hair_friction: Option<f32>,
    /// Hair-hair mode: `pairwise` (the penalty of (20), strength from
    /// --hair-hair) or `volumetric` (a grid of hair density and velocity,
    /// default settings: 5 mm cells, smoothing 20 /s, repulsion 10 m^2/s^2).
    #[arg(long, value_parser = ["pairwise", "volumetric"], default_value = "pairwise")]
    hair_hair_mode: String,
    /// Head collider: `ball` (radius 0.08 m) or `mesh FILE` (metres, Y up,
    /// centred on the head, e.g. samples/head.obj).
    #[arg(long, num_args = 1..=2, value_names = ["KIND", "FILE"])]
    collider: Vec<String>,
    /// The bond treatment of every step: `still` (no drive: a press or
    /// settle stage), `wet` (hydrogen bonds driven to 0 over 0.2 s) or
    /// `blow-dry` (a blower across the crown re-forms them, as in
    /// samples/blow_dry.toml).
    #[arg(long, default_value = "still", value_parser = treatment_parser())]
    treatment: Treatment,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// `--treatment`: one of [`Treatment::name`] (clap lists them in `--help`
/// and refuses any other).
fn treatment_parser() -> impl clap::builder::TypedValueParser<Value = Treatment> {
    use clap::builder::{PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Treatment::ALL.map(Treatment::name))
        .map(|name| Treatment::from_name(&name).unwrap_or_default())
}

fn collider_of(values: &[String]) -> Result<HeadCollider, BadInput> {
    match values {
        [] => Ok(HeadCollider::None),
        [kind] if kind == "ball" => Ok(HeadCollider::Ball),
        [kind, file] if kind == "mesh" => Ok(HeadCollider::Mesh(PathBuf::from(file))),
        [kind] if kind == "mesh" => Err(BadInput("--collider mesh needs a FILE".into())),
        _ => Err(BadInput(
            "--collider must be `ball` or `mesh FILE`".to_string(),
        )),
    }
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    if args.threads == Some(0) {
        return Err(BadInput("--threads must be at least 1".into()).into());
    }
    if let Some(alpha) = args.hair_hair {
        if !(alpha.is_finite() && (0.0..=10.0).contains(&alpha)) {
            return Err(BadInput("--hair-hair must be in [0, 10]".into()).into());
        }
    }
    if let Some(mu) = args.hair_friction {
        if !(mu.is_finite() && (0.0..=1.0).contains(&mu)) {
            return Err(BadInput("--hair-friction must be in [0, 1]".into()).into());
        }
        let pairwise_on = args.hair_hair.is_some() || args.preset.is_some();
        if !pairwise_on || args.hair_hair_mode != "pairwise" || args.model == "paper" {
            return Err(BadInput(
                "--hair-friction needs pairwise --hair-hair and the physical model".into(),
            )
            .into());
        }
    }
    let model = if args.model == "paper" {
        Model::Paper
    } else {
        Model::Physical
    };
    let iterations = args.iterations.unwrap_or(model.default_iterations());
    // A count given alone is the count every strand gets.
    let tolerance = args.tolerance.unwrap_or(match args.iterations {
        Some(_) => 0.0,
        None => model.default_tolerance(),
    });
    let collider = collider_of(&args.collider)?;
    if args.hair_hair_mode == "volumetric" && args.preset.is_none() && args.hair_hair.is_none() {
        return Err(BadInput(
            "--hair-hair-mode volumetric needs --hair-hair (it turns hair-hair on)".into(),
        )
        .into());
    }
    let workload = match args.preset.as_deref() {
        Some(preset) => preset_workload(preset, &args, collider)?,
        None => Workload {
            model,
            iterations,
            tolerance,
            hair_hair: args.hair_hair.filter(|_| args.hair_hair_mode == "pairwise"),
            hair_friction: args.hair_friction,
            volumetric: (args.hair_hair_mode == "volumetric" && args.hair_hair.is_some())
                .then(groombake::sim::Volumetric::default),
            collider,
            render: args.render,
            pillow: args.pillow,
            ..Workload::free_hair(
                args.guides.or(args.strands).unwrap_or(10_000),
                args.vertices.unwrap_or(32),
            )
        },
    };
    let workload = Workload {
        model,
        iterations,
        tolerance,
        ..workload
    };
    let workload = Workload {
        treatment: args.treatment,
        ..workload
    };
    workload.check().map_err(|e| BadInput(e.to_string()))?;
    if let HeadCollider::Mesh(path) = &workload.collider {
        // Read before any stepping, so a bad file fails at once.
        importers::mesh::read_triangles(path)?;
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(threads) = args.threads {
        builder = builder.num_threads(threads);
    }
    let pool = builder.build()?;
    let threads = pool.current_num_threads();
    let report = pool.install(|| bench::run(&workload, args.steps, 2.0, threads))?;
    let shares = report.shares;
    let load = load_average();
    let cpu = cpu_model();
    let dt = bench::step_dt();
    let per_simulated_second = report.seconds_per_simulated_second(dt);
    let cpu_per_simulated_second = report.cpu_seconds_per_simulated_second(dt);
    // The wall projection holds only on a machine as loaded as this one
    // was; the CPU one (all threads' user + system time) does not stretch
    // with other processes' load: divided by the threads it is the wall
    // time on as many idle cores (if the work spreads over them).
    let projected_5s = args.preset.is_some().then_some(5.0 * per_simulated_second);
    let projected_5s_cpu = args
        .preset
        .is_some()
        .then_some(cpu_per_simulated_second.map(|c| 5.0 * c))
        .flatten();
    if args.json {
        let json = serde_json::json!({
            "strands": workload.strands,
            "vertices": workload.vertices,
            "model": args.model,
            "threads": threads,
            "iterations": workload.iterations,
            "tolerance": workload.tolerance,
            "solves_per_strand_step": report.solves_per_strand_step(),
            "hair_hair": workload.hair_hair,
            "hair_friction": workload.hair_friction,
            "hair_hair_mode": if workload.volumetric.is_some() { "volumetric" } else { "pairwise" },
            "render": workload.render,
            "pillow": workload.pillow,
            "treatment": workload.treatment.name(),
            "dt": dt,
            "collider": match &workload.collider {
                HeadCollider::None => None,
                HeadCollider::Ball => Some("ball".to_string()),
                HeadCollider::Mesh(p) => Some(format!("mesh {}", p.display())),
            },
            "steps": report.timing.steps,
            "seconds": report.timing.seconds,
            "ms_per_step": report.timing.seconds * 1e3 / report.timing.steps as f64,
            "ns_per_vertex_step": report.ns_per_vertex_step(),
            "ns_per_vertex_iteration": report.ns_per_vertex_iteration(),
            "cpu_ns_per_vertex_step": report.cpu_ns_per_vertex_step(),
            "cpu_ns_per_vertex_iteration": report
                .cpu_ns_per_vertex_step()
                .map(|c| c / report.solves_per_strand_step().max(1.0)),
            "shares": {
                "solver": shares.solver,
                "forces": shares.forces,
                "constraints": shares.constraints,
                "bonds": shares.bonds,
                "collisions": shares.collisions,
                "hair_hair": shares.hair_hair,
                "interpolation": shares.interpolation,
                "export": shares.export,
            },
            "seconds_per_simulated_second": per_simulated_second,
            "cpu_seconds_per_simulated_second": cpu_per_simulated_second,
            "projected_5s_seconds": projected_5s,
            "projected_5s_cpu_seconds": projected_5s_cpu,
            "projected_5s_cpu_seconds_per_thread": projected_5s_cpu.map(|c| c / threads as f64),
            "peak_memory_bytes": report.peak_memory,
            "load_average": load,
            "cpu": cpu,
        });
        println!("{json}");
    } else {
        println!(
            "{} strands x {} vertices, {} model, {} iterations ({:.2} per strand-step), {} threads, \
             treatment {}: {} steps in {:.3} s, {:.2} ms per step, {:.2} ns per vertex-step, {:.2} ns per \
             vertex-iteration ({} ns of CPU time per vertex-step)",
            workload.strands,
            workload.vertices,
            args.model,
            workload.iterations,
            report.solves_per_strand_step(),
            threads,
            workload.treatment.name(),
            report.timing.steps,
            report.timing.seconds,
            report.timing.seconds * 1e3 / report.timing.steps as f64,
            report.ns_per_vertex_step(),
            report.ns_per_vertex_iteration(),
            report
                .cpu_ns_per_vertex_step()
                .map_or("?".to_string(), |c| format!("{c:.2}"))
        );
        if let Some(render) = workload.render {
            println!(
                "{} guides drive {render} render hairs, interpolated and exported {} times \
                 per simulated second; pillow {}",
                workload.strands,
                bench::EXPORT_FPS,
                if workload.pillow { "on" } else { "off" }
            );
        }
        println!(
            "{per_simulated_second:.1} s of wall time and {} s of CPU time (user + system, \
             all threads) per simulated second (dt {dt:.6} s)",
            cpu_per_simulated_second.map_or("?".to_string(), |c| format!("{c:.1}"))
        );
        if let Some(wall) = projected_5s {
            println!(
                "5 simulated seconds projected: {wall:.0} s ({:.1} min) of wall time at load \
                 average {}; {} of CPU time, {} per thread on {threads} idle cores; CPU {}",
                wall / 60.0,
                load.map_or("?".to_string(), |l| format!("{l:.2}")),
                projected_5s_cpu.map_or("?".to_string(), |c| format!("{c:.0} s")),
                projected_5s_cpu.map_or("?".to_string(), |c| format!(
                    "{:.0} s ({:.1} min)",
                    c / threads as f64,
                    c / threads as f64 / 60.0
                )),
                cpu.as_deref().unwrap_or("?")
            );
        }
        let share = |s: Option<f64>| s.map_or("-".to_string(), |s| format!("{:.1} %", s * 100.0));
        println!(
            "shares of CPU time (by ablation and the solver's phase clock): solver {} \
             (forces {}, constraints {}, bonds {}), collisions {}, hair-hair {}, \
             interpolation {}, export {}",
            share(Some(shares.solver)),
            share(Some(shares.forces)),
            share(Some(shares.constraints)),
            share(Some(shares.bonds)),
            share(shares.collisions),
            share(shares.hair_hair),
            share(shares.interpolation),
            share(shares.export)
        );
        println!(
            "peak memory {}, load average {}, CPU {}",
            report
                .peak_memory
                .map_or("?".to_string(), |b| format!("{:.0} MB", b as f64 / 1e6)),
            load.map_or("?".to_string(), |l| format!("{l:.2}")),
            cpu.as_deref().unwrap_or("?")
        );
    }
    Ok(())
}

/// The workload of `--preset`, with the options that apply to it: the
/// hair-hair mode and alpha, the collider mesh. An option the preset fixes
/// itself is refused rather than ignored.
fn preset_workload(
    preset: &str,
    args: &BenchArgs,
    collider: HeadCollider,
) -> Result<Workload, BadInput> {
    let fixed = [
        ("--strands", args.strands.is_some()),
        ("--guides", args.guides.is_some()),
        ("--render", args.render.is_some()),
        ("--vertices", args.vertices.is_some()),
        ("--pillow", args.pillow),
    ];
    if let Some((name, _)) = fixed.iter().find(|(_, given)| *given) {
        return Err(BadInput(format!(
            "{name} does not apply with --preset {preset}: the preset fixes it \
             (5,000 guides x 32 vertices, 100,000 render hairs, a pillow)"
        )));
    }
    let head = match collider {
        HeadCollider::Mesh(path) => path,
        HeadCollider::None => PathBuf::from("samples/head.obj"),
        HeadCollider::Ball => {
            return Err(BadInput(format!(
                "--preset {preset} takes a mesh head: --collider mesh FILE"
            )))
        }
    };
    if !head.is_file() {
        return Err(BadInput(format!(
            "--preset {preset}: head mesh '{}' not found (run from the repository \
             or give --collider mesh FILE)",
            head.display()
        )));
    }
    let mut workload = Workload::full_head(head);
    if args.hair_hair_mode == "volumetric" {
        if args.hair_hair.is_some() || args.hair_friction.is_some() {
            return Err(BadInput(
                "--hair-hair ALPHA and --hair-friction are of pairwise hair-hair: they do not \
                 apply with --hair-hair-mode volumetric"
                    .into(),
            ));
        }
        workload.hair_hair = None;
        workload.volumetric = Some(groombake::sim::Volumetric::default());
    } else if let Some(alpha) = args.hair_hair {
        workload.hair_hair = Some(alpha);
    }
    workload.hair_friction = args.hair_friction;
    Ok(workload)
}

/// The CPU's model name and the instructions the solver dispatches to
/// (Linux): a figure is only comparable with one from the same CPU (the
/// same bench ran 1.6x slower on one virtual machine than on another).
fn cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let name = text
        .lines()
        .find_map(|l| l.strip_prefix("model name")?.split_once(':'))?
        .1
        .trim();
    Some(format!(
        "{name} ({})",
        groombake::sim::Instructions::of_this_cpu().name()
    ))
}

/// The one-minute load average (Linux), to judge the timing by.
fn load_average() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: BenchArgs,
    }

    fn preset(extra: &[&str]) -> Result<Workload, BadInput> {
        let mut argv = vec!["bench", "--preset", "full-head"];
        argv.extend_from_slice(extra);
        let args = Cli::parse_from(argv).args;
        // Tests run in the package root, where samples/head.obj is.
        preset_workload("full-head", &args, collider_of(&args.collider)?)
    }

    /// Issue 38: `--preset full-head --hair-hair-mode volumetric` ran
    /// pairwise; the mode now replaces the preset's pairwise hair-hair.
    #[test]
    fn preset_takes_the_volumetric_mode() {
        let pairwise = preset(&[]).unwrap();
        assert_eq!(pairwise.hair_hair, Some(5.0));
        assert!(pairwise.volumetric.is_none());
        let volumetric = preset(&["--hair-hair-mode", "volumetric"]).unwrap();
        assert_eq!(volumetric.hair_hair, None);
        assert!(volumetric.volumetric.is_some());
        assert_eq!(volumetric.render, Some(100_000));
        assert_eq!(preset(&["--hair-hair", "2"]).unwrap().hair_hair, Some(2.0));
    }

    #[test]
    fn preset_refuses_what_it_fixes_or_what_does_not_apply() {
        for extra in [
            &["--strands", "50"][..],
            &["--vertices", "8"],
            &["--pillow"],
            &["--hair-hair-mode", "volumetric", "--hair-hair", "5"],
        ] {
            let error = preset(extra).err().map(|e| e.0).unwrap_or_default();
            assert!(error.contains("not apply"), "{extra:?}: {error}");
        }
    }
}
