//! `groombake bench`: the solver benchmark's command line and JSON.

use crate::util::TestDir;

#[test]
fn bench_reports_ns_per_vertex_iteration_as_json() {
    let dir = TestDir::new();
    let output = dir.run_ok(&[
        "bench",
        "--strands",
        "50",
        "--vertices",
        "16",
        "--threads",
        "2",
        "--iterations",
        "3",
        "--steps",
        "4",
        "--json",
    ]);
    let report: serde_json::Value =
        serde_json::from_slice(&output.stdout).expect("bench prints one JSON object");
    let ns = report["ns_per_vertex_iteration"]
        .as_f64()
        .expect("ns_per_vertex_iteration is a number");
    assert!(ns > 0.0 && ns.is_finite(), "{report}");
    assert_eq!(report["steps"], 4);
    assert_eq!(report["threads"], 2);
    assert_eq!(report["strands"], 50);
    assert_eq!(report["vertices"], 16);
    assert_eq!(report["iterations"], 3);
    // CPU time beside wall time (issue 38): the per-simulated-second cost
    // that load does not stretch, with the CPU and load it was measured on.
    let cpu = report["cpu_seconds_per_simulated_second"]
        .as_f64()
        .expect("CPU seconds per simulated second");
    assert!(cpu > 0.0 && cpu.is_finite(), "{report}");
    assert!(report["cpu"].is_string(), "{report}");
    assert!(report["load_average"].as_f64().is_some(), "{report}");
    // The solver's share split by its phase clock: each phase took some
    // time, and together they are the solver's share (here all of it).
    let shares = &report["shares"];
    let share = |key: &str| shares[key].as_f64().unwrap_or(f64::NAN);
    for phase in ["forces", "constraints", "bonds"] {
        assert!(share(phase) > 0.0, "{phase}: {shares}");
    }
    let split = share("forces") + share("constraints") + share("bonds");
    assert!((split - share("solver")).abs() < 1e-9, "{shares}");
    assert_eq!(share("solver"), 1.0, "{shares}");
    // The CPU, as /proc/cpuinfo names it (x86-64 Linux has the field).
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    if cpuinfo.contains("model name") {
        let cpu = report["cpu"].as_str().expect("cpu is named");
        assert!(
            cpuinfo.lines().any(|l| l.starts_with("model name")
                && cpu.starts_with(l.split_once(':').unwrap().1.trim())),
            "{cpu}"
        );
    }
}

#[test]
fn bench_refuses_bad_sizes() {
    let dir = TestDir::new();
    dir.run_fail(&["bench", "--vertices", "1"], 2);
    dir.run_fail(&["bench", "--strands", "0", "--vertices", "8"], 2);
    dir.run_fail(&["bench", "--threads", "0"], 2);
    // A mode that would run without hair-hair is refused, not ignored.
    dir.run_fail(
        &["bench", "--hair-hair-mode", "volumetric", "--strands", "10"],
        2,
    );
    dir.run_fail(&["bench", "--preset", "full-head", "--strands", "10"], 2);
    dir.run_fail(
        &["bench", "--strands", "10000000", "--vertices", "10000"],
        2,
    );
}

#[test]
fn bench_steps_the_physical_model_by_default_and_the_paper_model_on_request() {
    let dir = TestDir::new();
    let run = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["bench", "--strands", "8", "--vertices", "8", "--steps", "2"];
        args.extend_from_slice(extra);
        args.push("--json");
        serde_json::from_slice(&dir.run_ok(&args).stdout).expect("one JSON object")
    };
    let physical = run(&[]);
    assert_eq!(physical["model"], "physical", "{physical}");
    // The physical model's default iteration count.
    assert_eq!(physical["iterations"], 2, "{physical}");
    let ns = physical["ns_per_vertex_step"].as_f64().expect("a number");
    assert!(ns > 0.0 && ns.is_finite(), "{physical}");
    let paper = run(&["--model", "paper"]);
    assert_eq!(paper["model"], "paper", "{paper}");
    assert_eq!(paper["iterations"], 5, "{paper}");
    dir.run_fail(&["bench", "--model", "stiff"], 2);
    // The treatment of the steps, still by default.
    assert_eq!(physical["treatment"], "still", "{physical}");
    for treatment in ["wet", "blow-dry"] {
        let driven = run(&["--treatment", treatment]);
        assert_eq!(driven["treatment"], treatment, "{driven}");
    }
    dir.run_fail(&["bench", "--treatment", "soak"], 2);
}
