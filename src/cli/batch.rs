//! `groombake batch MANIFEST.toml [--jobs N] [--shard I/N] [--resume] [--merge]
//! [--emit slurm [--time T] [--mem M] [--partition P] [--account A]]`.

use super::BadInput;
use clap::{Args, ValueEnum};
use groombake::batch::slurm::{self, SlurmSettings};
use groombake::batch::{self, BatchOptions, JobStatus, Manifest};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Emit {
    /// A Slurm job-array script (`sbatch` it).
    Slurm,
}

#[derive(Debug, Args)]
pub struct BatchArgs {
    /// The manifest (TOML): `[[job]]` and `[[glob]]` entries.
    manifest: PathBuf,
    /// Jobs run at once.
    #[arg(short = 'j', long, default_value_t = 1)]
    jobs: usize,
    /// Run only shard I of N (jobs I, I+N, ...), as a farm's array task does.
    #[arg(long, value_parser = batch::parse_shard, value_name = "I/N")]
    shard: Option<(usize, usize)>,
    /// Skip jobs whose outputs match the hashes in their job report and
    /// whose inputs did not change (timeline, grooms, meshes, seed, version).
    #[arg(long)]
    resume: bool,
    /// Worker threads of each bake (default: the cores shared by the jobs).
    #[arg(long)]
    threads: Option<usize>,
    /// Bake nothing: merge the job reports on disk into the batch report.
    #[arg(long, conflicts_with_all = ["shard", "resume"])]
    merge: bool,
    /// Print a farm script that runs the manifest as a job array, and bake nothing.
    #[arg(long, value_enum, conflicts_with_all = ["shard", "resume", "merge"])]
    emit: Option<Emit>,
    /// Wall-time limit of each farm task (e.g. 02:00:00; overrides the manifest's [slurm]).
    #[arg(long, requires = "emit", value_parser = slurm_value("time"))]
    time: Option<String>,
    /// Memory of each farm task (e.g. 8G; overrides the manifest's [slurm]).
    #[arg(long, requires = "emit", value_parser = slurm_value("mem"))]
    mem: Option<String>,
    /// Partition of the farm tasks (overrides the manifest's [slurm]).
    #[arg(long, requires = "emit", value_parser = slurm_value("partition"))]
    partition: Option<String>,
    /// Account charged for the farm tasks (overrides the manifest's [slurm]).
    #[arg(long, requires = "emit", value_parser = slurm_value("account"))]
    account: Option<String>,
    /// No line per finished job.
    #[arg(short, long)]
    quiet: bool,
}

/// A value parser checking a Slurm request as the manifest's are checked.
fn slurm_value(key: &'static str) -> impl Fn(&str) -> Result<String, String> + Clone {
    move |text| slurm::check(key, text).map(|()| text.to_string())
}

/// Some jobs failed: exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{failed} of {total} job(s) failed or missing; see {report}")]
pub struct JobsFailed {
    failed: usize,
    total: usize,
    report: String,
}

pub fn run(args: BatchArgs) -> anyhow::Result<()> {
    if args.jobs == 0 || args.threads == Some(0) {
        return Err(BadInput("--jobs and --threads must be at least 1".into()).into());
    }
    let started = Instant::now();
    let manifest = Manifest::load(&args.manifest).map_err(|e| BadInput(e.to_string()))?;
    if let Some(Emit::Slurm) = args.emit {
        let exe = std::env::current_exe()?;
        // Slurm opens the task logs before a task runs: the folder must exist.
        let logs = manifest.out.join("slurm");
        std::fs::create_dir_all(&logs).map_err(|e| anyhow::anyhow!("{}: {e}", logs.display()))?;
        let flags = SlurmSettings {
            time: args.time,
            mem: args.mem,
            partition: args.partition,
            account: args.account,
        };
        let threads = args.threads.or(manifest.threads).unwrap_or(1);
        let settings = manifest.slurm.overridden_by(&flags);
        print!(
            "{}",
            batch::slurm_script(&manifest, &exe, threads, &settings)
        );
        return Ok(());
    }
    let mut reports = Vec::new();
    let mut interrupted = None;
    if !args.merge {
        // A signal stops the running bakes (their temporaries removed) and
        // the batch still writes its report, each job's state in it.
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        super::bake::stop_on_signals(&stop)?;
        let options = BatchOptions {
            parallel: args.jobs,
            shard: args.shard,
            resume: args.resume,
            threads: args.threads,
            stop: Some(stop),
        };
        let total = manifest.shard(args.shard).len();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let quiet = args.quiet;
        let finished = |report: &batch::JobReport| {
            let n = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
            if !quiet {
                let status = format!("{:?}", report.status).to_lowercase();
                let error = report
                    .error
                    .as_deref()
                    .map(|e| format!(": {}", super::shortened(&super::printable(e))))
                    .unwrap_or_default();
                let why = report
                    .rebaked_because
                    .as_deref()
                    .map(|w| format!("; baked again: {w}"))
                    .unwrap_or_default();
                eprintln!(
                    "[{n}/{total}] {status} {} ({:.1} s{why}){error}",
                    report.name, report.wall_seconds
                );
            }
        };
        reports = batch::run(&manifest, &options, &finished);
        interrupted = options.stopped_by();
        if let (Some(signal), Some(_)) = (interrupted, args.shard) {
            return Err(super::Interrupted(signal).into());
        }
        if args.shard.is_some() {
            // The other shards may still run: the merge comes later.
            let failed = reports
                .iter()
                .filter(|r| r.status == JobStatus::Failed)
                .count();
            if failed > 0 {
                return Err(JobsFailed {
                    failed,
                    total: reports.len(),
                    report: "the job reports".into(),
                }
                .into());
            }
            return Ok(());
        }
    }
    let merged = batch::merge(&manifest, &reports, started.elapsed().as_secs_f64());
    let path = batch::write_merged(&manifest, &merged)
        .map_err(|e| anyhow::anyhow!("{}: {e}", manifest.out.display()))?;
    if let Some(signal) = interrupted {
        return Err(super::Interrupted(signal).into());
    }
    if !args.quiet {
        eprintln!(
            "{} of {} job(s) succeeded; report {}",
            merged.succeeded,
            merged.jobs.len(),
            path.display()
        );
    }
    if merged.all_succeeded() {
        Ok(())
    } else {
        Err(JobsFailed {
            failed: merged.failed + merged.missing,
            total: merged.jobs.len(),
            report: path.display().to_string(),
        }
        .into())
    }
}
