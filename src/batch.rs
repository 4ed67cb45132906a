//! Batches of bakes (`groombake batch MANIFEST.toml`): a manifest lists
//! jobs, each a timeline with optionally another groom and output folder.
//! Every job bakes into its own folder and leaves a job report there
//! ([`JOB_REPORT`]); the batch merges them into one report ([`MERGED_REPORT`]).
//!
//! A job report is written last and atomically, so a job whose report is
//! present with the hashes of the files on disk is complete: `resume`
//! skips it, unless anything its outputs depend on changed since
//! ([`inputs`]: the timeline, the files it reads, the seed, groombake's
//! version); then it bakes the job again and says why. A failing job (bad input, a failed bake, a panic) is recorded
//! as failed and the others go on. Shards (`I/N`: jobs `I, I+N, ...`) let
//! a farm's array tasks split the jobs ([`slurm`]); a final `merge` gathers them.

pub mod inputs;
pub mod report;
pub mod slurm;

use crate::timeline::bake::{bake, BakeOptions};
use crate::timeline::report::size_and_sha256;
use crate::timeline::{Timeline, TimelineError};
use inputs::JobInputs;
pub use report::{BatchReport, JobOutput, JobReport, JobStatus};
use serde::{Deserialize, Serialize};
use serde_spanned::Spanned;
use slurm::SlurmSettings;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// The report every job leaves in its folder.
pub const JOB_REPORT: &str = "groombake_job.json";
/// The merged report in the batch's output folder.
pub const MERGED_REPORT: &str = "batch_report.json";

/// The manifest as written (TOML); paths are relative to its folder.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    /// Folder the jobs' folders go under (default `batch_out`).
    out: Option<String>,
    /// Worker threads of each bake (default: the cores shared by the jobs).
    threads: Option<usize>,
    #[serde(default, rename = "job")]
    jobs: Vec<Spanned<JobSpec>>,
    #[serde(default, rename = "glob")]
    globs: Vec<Spanned<GlobSpec>>,
    /// Scheduler requests of the emitted farm script.
    slurm: Option<Spanned<SlurmSettings>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JobSpec {
    /// Name of the job and of its folder (default: from the file names).
    name: Option<String>,
    timeline: String,
    /// A groom file baked instead of the timeline's `[groom]` source.
    groom: Option<String>,
    /// The job's folder, instead of `<out>/<name>`.
    out: Option<String>,
    /// Overrides the timeline's seed.
    seed: Option<u64>,
}

/// One job per groom file matching `grooms`, each with `timeline`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GlobSpec {
    timeline: String,
    grooms: String,
    /// Overrides the timeline's seed.
    seed: Option<u64>,
}

/// One job of a manifest, its paths resolved.
#[derive(Debug, Clone)]
pub struct Job {
    pub name: String,
    pub timeline: PathBuf,
    pub groom: Option<PathBuf>,
    pub folder: PathBuf,
    /// Overrides the timeline's seed.
    pub seed: Option<u64>,
}

/// A read manifest: its jobs in order.
#[derive(Debug)]
pub struct Manifest {
    pub path: PathBuf,
    /// The folder the merged report goes to.
    pub out: PathBuf,
    pub threads: Option<usize>,
    pub jobs: Vec<Job>,
    /// The `[slurm]` table (checked).
    pub slurm: SlurmSettings,
}

/// What went wrong with a manifest (bad input: exit code 2).
pub type ManifestError = TimelineError;

/// How to run a batch.
#[derive(Debug, Clone, Default)]
pub struct BatchOptions {
    /// Jobs run at once (at least 1).
    pub parallel: usize,
    /// `(index, count)`: run only jobs `index, index + count, ...`.
    pub shard: Option<(usize, usize)>,
    /// Skip jobs whose outputs match their report.
    pub resume: bool,
    /// Worker threads of each bake (overrides the manifest's).
    pub threads: Option<usize>,
    /// A request to stop, shared with the CLI's signal handlers: 0 while
    /// the batch may run, else the signal's number. Running bakes stop at
    /// their next step (removing their temporaries), no further job
    /// starts, and every job not finished is reported `interrupted`.
    pub stop: Option<Arc<AtomicUsize>>,
}

impl BatchOptions {
    /// The signal that asked the batch to stop, if one did.
    pub fn stopped_by(&self) -> Option<usize> {
        self.stop
            .as_ref()
            .map(|s| s.load(Ordering::Relaxed))
            .filter(|&s| s != 0)
    }
}

fn manifest_error(
    path: &Path,
    text: &str,
    span: std::ops::Range<usize>,
    message: String,
) -> ManifestError {
    crate::timeline::error_at(path, text, span, message)
}

/// The file name part of a path, for job names.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// A job name is a folder name: letters, digits, `-`, `_` and `.`.
fn check_name(name: &str) -> Result<(), String> {
    let ok = !name.is_empty()
        && name != "."
        && name != ".."
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "job name '{name}': use letters, digits, '-', '_' and '.' only"
        ))
    }
}

impl Manifest {
    /// Reads a manifest and expands its globs; every job's timeline and
    /// groom must exist and names must be unique.
    pub fn load(path: &Path) -> Result<Manifest, ManifestError> {
        let read = |message: String| {
            manifest_error(
                path,
                "",
                0..0,
                format!("cannot read the manifest: {message}"),
            )
        };
        let bytes = importers::read_limited(path, crate::budget::MAX_TIMELINE_BYTES)
            .map_err(|e| read(e.to_string()))?;
        let text = String::from_utf8(bytes).map_err(|e| read(format!("not UTF-8 text ({e})")))?;
        let file: ManifestFile = toml::from_str(&text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            manifest_error(path, &text, span, e.message().trim().to_string())
        })?;
        let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
        let out = base.join(file.out.as_deref().unwrap_or("batch_out"));
        let fail = |span: std::ops::Range<usize>, message: String| {
            manifest_error(path, &text, span, message)
        };
        if file.threads == Some(0) {
            return Err(fail(0..0, "threads must be at least 1".into()));
        }
        let slurm = match &file.slurm {
            Some(table) => {
                table.get_ref().check().map_err(|m| fail(table.span(), m))?;
                table.get_ref().clone()
            }
            None => SlurmSettings::default(),
        };
        let mut jobs: Vec<(Job, std::ops::Range<usize>)> = Vec::new();
        for spec in &file.jobs {
            let span = spec.span();
            let spec = spec.get_ref();
            let timeline = base.join(&spec.timeline);
            let groom = spec.groom.as_ref().map(|g| base.join(g));
            let name = spec.name.clone().unwrap_or_else(|| match &groom {
                Some(g) => format!("{}-{}", stem(&timeline), stem(g)),
                None => stem(&timeline),
            });
            let folder = match &spec.out {
                Some(o) => base.join(o),
                None => out.join(&name),
            };
            jobs.push((
                Job {
                    name,
                    timeline,
                    groom,
                    folder,
                    seed: spec.seed,
                },
                span,
            ));
        }
        for spec in &file.globs {
            let span = spec.span();
            let spec = spec.get_ref();
            let timeline = base.join(&spec.timeline);
            let pattern = base.join(&spec.grooms);
            let matches = glob::glob(&pattern.to_string_lossy())
                .map_err(|e| fail(span.clone(), format!("grooms: {e}")))?;
            let mut grooms: Vec<PathBuf> = matches.filter_map(Result::ok).collect();
            grooms.sort();
            if grooms.is_empty() {
                return Err(fail(
                    span,
                    format!("grooms: no file matches '{}'", pattern.display()),
                ));
            }
            for g in grooms {
                let name = format!("{}-{}", stem(&timeline), stem(&g));
                let folder = out.join(&name);
                jobs.push((
                    Job {
                        name,
                        timeline: timeline.clone(),
                        groom: Some(g),
                        folder,
                        seed: spec.seed,
                    },
                    span.clone(),
                ));
            }
        }
        if jobs.is_empty() {
            return Err(fail(
                0..0,
                "the manifest lists no [[job]] or [[glob]]".into(),
            ));
        }
        let mut seen = std::collections::BTreeSet::new();
        for (job, span) in &jobs {
            check_name(&job.name).map_err(|m| fail(span.clone(), m))?;
            if !seen.insert(job.folder.clone()) {
                return Err(fail(
                    span.clone(),
                    format!("two jobs write to the folder '{}'", job.folder.display()),
                ));
            }
            if !job.timeline.is_file() {
                return Err(fail(
                    span.clone(),
                    format!("timeline '{}' not found", job.timeline.display()),
                ));
            }
            if let Some(g) = job.groom.as_ref().filter(|g| !g.is_file()) {
                return Err(fail(
                    span.clone(),
                    format!("groom '{}' not found", g.display()),
                ));
            }
        }
        Ok(Manifest {
            path: path.to_path_buf(),
            out,
            threads: file.threads,
            jobs: jobs.into_iter().map(|(job, _)| job).collect(),
            slurm,
        })
    }

    /// Indices of the jobs of a shard `(index, count)` (all without one).
    pub fn shard(&self, shard: Option<(usize, usize)>) -> Vec<usize> {
        let (index, count) = shard.unwrap_or((0, 1));
        (0..self.jobs.len())
            .filter(|i| i % count.max(1) == index)
            .collect()
    }
}

/// Parses `I/N` (0 <= I < N).
pub fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let parsed = text
        .split_once('/')
        .and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)));
    match parsed {
        Some((i, n)) if n > 0 && i < n => Ok((i, n)),
        _ => Err(format!("shard '{text}': expected I/N with 0 <= I < N")),
    }
}

fn job_report_path(job: &Job) -> PathBuf {
    job.folder.join(JOB_REPORT)
}

/// The job's report on disk, if readable.
fn read_job_report(job: &Job) -> Option<JobReport> {
    let text = std::fs::read(job_report_path(job)).ok()?;
    serde_json::from_slice(&text).ok()
}

/// The path of an output, relative to the job's folder where it lies inside.
fn output_path(job: &Job, relative: &str) -> PathBuf {
    let p = Path::new(relative);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        job.folder.join(p)
    }
}

/// The report of a complete earlier run whose outputs are all on disk
/// with the same hashes and whose inputs are `current`; else why the job
/// must bake (`None`: it has no complete earlier run).
fn completed_earlier(job: &Job, current: Option<&JobInputs>) -> Result<JobReport, Option<String>> {
    let report = read_job_report(job).ok_or(None)?;
    if !matches!(report.status, JobStatus::Ok | JobStatus::Skipped) {
        return Err(None);
    }
    if let Some(o) = report.outputs.iter().find(|o| {
        !size_and_sha256(&output_path(job, &o.path))
            .is_ok_and(|(bytes, sha)| bytes == o.bytes && sha == o.sha256)
    }) {
        return Err(Some(format!("the output '{}' changed", o.path)));
    }
    // Without the current inputs the bake reports why it cannot run.
    let current = current.ok_or(None)?;
    let recorded = report
        .inputs
        .as_ref()
        .ok_or_else(|| Some("its report records no inputs".to_string()))?;
    match inputs::change(recorded, current) {
        Some(reason) => Err(Some(reason)),
        None => Ok(report),
    }
}

fn write_json(path: &Path, value: &impl Serialize) -> std::io::Result<()> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)?;
    }
    let mut file = groom::AtomicFile::create(path)?;
    serde_json::to_writer_pretty(&mut file, value)?;
    std::io::Write::write_all(&mut file, b"\n")?;
    file.commit()
}

/// Loads the job's timeline with the manifest's groom in place of its own.
fn load_timeline(job: &Job) -> Result<Timeline, String> {
    let mut timeline = Timeline::load(&job.timeline).map_err(|e| e.to_string())?;
    if let Some(groom) = &job.groom {
        let absolute =
            std::path::absolute(groom).map_err(|e| format!("{}: {e}", groom.display()))?;
        timeline.file.groom.source = Some(Spanned::new(0..0, absolute.display().to_string()));
        timeline.file.groom.generate = None;
    }
    Ok(timeline)
}

/// Bakes the job's timeline into the job's folder; returns the bake's
/// report as JSON and the outputs.
fn bake_job(
    job: &Job,
    timeline: &Timeline,
    threads: Option<usize>,
    stop: Option<&Arc<AtomicUsize>>,
) -> Result<(serde_json::Value, Vec<JobOutput>), String> {
    let options = BakeOptions {
        out_dir: job.folder.clone(),
        threads,
        seed: job.seed,
        monitor: stop.map(|stop| {
            Arc::new(crate::timeline::bake::BakeMonitor {
                stop: stop.clone(),
                ..Default::default()
            })
        }),
        ..BakeOptions::default()
    };
    let mut report = bake(timeline, &options).map_err(|e| e.to_string())?.report;
    report.finish_ok(timeline);
    let outputs = report
        .outputs
        .iter()
        .map(|o| {
            let path = Path::new(&o.path);
            let shown = path.strip_prefix(&job.folder).unwrap_or(path);
            JobOutput {
                path: shown.display().to_string(),
                bytes: o.bytes,
                sha256: o.sha256.clone(),
            }
        })
        .collect();
    let value = serde_json::to_value(&report).map_err(|e| e.to_string())?;
    Ok((value, outputs))
}

/// Removes the temporary files (`.NAME.PID.tmp`, see [`groom::AtomicFile`])
/// that a killed run of the job left in its folder: nothing else writes
/// there while the job runs.
fn remove_leftovers(folder: &Path) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            remove_leftovers(&path);
        } else if name.starts_with('.') && name.ends_with(".tmp") {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// Runs one job (or finds it complete) and writes its report.
pub fn run_job(job: &Job, options: &BatchOptions, threads: Option<usize>) -> JobReport {
    let started = Instant::now();
    // Read before baking: a file changed during the bake then differs from
    // what the report records, and the next resume bakes again.
    let timeline = load_timeline(job);
    let current = timeline
        .as_ref()
        .ok()
        .and_then(|t| inputs::current(job, t).ok());
    let mut rebaked_because = None;
    if options.resume {
        match completed_earlier(job, current.as_ref()) {
            Ok(mut report) => {
                report.status = JobStatus::Skipped;
                report.rebaked_because = None;
                return report;
            }
            Err(reason) => rebaked_because = reason,
        }
    }
    // An old report must not vouch for outputs this run may leave half done.
    let _ = std::fs::remove_file(job_report_path(job));
    remove_leftovers(&job.folder);
    let outcome = timeline.and_then(|timeline| {
        std::fs::create_dir_all(&job.folder)
            .map_err(|e| format!("{}: {e}", job.folder.display()))?;
        // A panic in one bake must not end the others.
        std::panic::catch_unwind(|| bake_job(job, &timeline, threads, options.stop.as_ref()))
            .unwrap_or_else(|_| Err("the bake panicked".into()))
    });
    let (status, error, bake, outputs) = match outcome {
        Ok((bake, outputs)) => (JobStatus::Ok, None, Some(bake), outputs),
        Err(message) if options.stopped_by().is_some() => {
            (JobStatus::Interrupted, Some(message), None, Vec::new())
        }
        Err(message) => (JobStatus::Failed, Some(message), None, Vec::new()),
    };
    let mut report = JobReport {
        name: job.name.clone(),
        timeline: job.timeline.display().to_string(),
        groom: job.groom.as_ref().map(|g| g.display().to_string()),
        folder: job.folder.display().to_string(),
        status,
        error,
        wall_seconds: started.elapsed().as_secs_f64(),
        outputs,
        bake,
        inputs: current,
        rebaked_because,
    };
    if let Err(e) = write_json(&job_report_path(job), &report) {
        report.status = JobStatus::Failed;
        report.error = Some(format!("{}: {e}", job_report_path(job).display()));
    }
    report
}

/// Runs the jobs of the options' shard, `parallel` at a time, calling
/// `finished` as each ends. Returns their reports in manifest order.
pub fn run(
    manifest: &Manifest,
    options: &BatchOptions,
    finished: &(dyn Fn(&JobReport) + Sync),
) -> Vec<JobReport> {
    let selected = manifest.shard(options.shard);
    let parallel = options.parallel.clamp(1, selected.len().max(1));
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    // Outputs are identical for any thread count; this only shares cores.
    let threads = options
        .threads
        .or(manifest.threads)
        .unwrap_or((cores / parallel).max(1));
    let next = AtomicUsize::new(0);
    let reports: Mutex<Vec<Option<JobReport>>> = Mutex::new(vec![None; selected.len()]);
    std::thread::scope(|scope| {
        for _ in 0..parallel {
            scope.spawn(|| loop {
                if options.stopped_by().is_some() {
                    break;
                }
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&index) = selected.get(k) else { break };
                let report = run_job(&manifest.jobs[index], options, Some(threads));
                finished(&report);
                if let Ok(mut slots) = reports.lock() {
                    slots[k] = Some(report);
                }
            });
        }
    });
    let slots = reports.into_inner().unwrap_or_default();
    match options.stopped_by() {
        // Every selected job is in the report: those a signal kept from
        // starting too.
        Some(signal) => slots
            .into_iter()
            .zip(&selected)
            .map(|(slot, &index)| {
                slot.unwrap_or_else(|| not_started(&manifest.jobs[index], signal))
            })
            .collect(),
        None => slots.into_iter().flatten().collect(),
    }
}

/// The report of a job a signal kept from starting.
fn not_started(job: &Job, signal: usize) -> JobReport {
    JobReport {
        name: job.name.clone(),
        timeline: job.timeline.display().to_string(),
        groom: job.groom.as_ref().map(|g| g.display().to_string()),
        folder: job.folder.display().to_string(),
        status: JobStatus::Interrupted,
        error: Some(format!(
            "not started: the batch was stopped by signal {signal}"
        )),
        wall_seconds: 0.0,
        outputs: Vec::new(),
        bake: None,
        inputs: None,
        rebaked_because: None,
    }
}

/// The merged report of every job of the manifest: the reports of this
/// run (`fresh`), else those on disk (a job without one is `missing`).
pub fn merge(manifest: &Manifest, fresh: &[JobReport], wall_seconds: f64) -> BatchReport {
    let jobs: Vec<JobReport> = manifest
        .jobs
        .iter()
        .map(|job| {
            let folder = job.folder.display().to_string();
            let this_run = fresh.iter().find(|r| r.folder == folder).cloned();
            this_run
                .or_else(|| read_job_report(job))
                .unwrap_or_else(|| JobReport {
                    name: job.name.clone(),
                    timeline: job.timeline.display().to_string(),
                    groom: job.groom.as_ref().map(|g| g.display().to_string()),
                    folder: job.folder.display().to_string(),
                    status: JobStatus::Missing,
                    error: Some("no job report".into()),
                    wall_seconds: 0.0,
                    outputs: Vec::new(),
                    bake: None,
                    inputs: None,
                    rebaked_because: None,
                })
        })
        .collect();
    let count = |s: JobStatus| jobs.iter().filter(|j| j.status == s).count();
    BatchReport {
        manifest: manifest.path.display().to_string(),
        groombake_version: env!("CARGO_PKG_VERSION").to_string(),
        succeeded: count(JobStatus::Ok) + count(JobStatus::Skipped),
        failed: count(JobStatus::Failed) + count(JobStatus::Interrupted),
        missing: count(JobStatus::Missing),
        jobs,
        wall_seconds,
    }
}

/// Writes the merged report into the manifest's output folder: JSON, and
/// beside it the same as an HTML page ([`MERGED_REPORT`] with `.html`).
pub fn write_merged(manifest: &Manifest, report: &BatchReport) -> std::io::Result<PathBuf> {
    let path = manifest.out.join(MERGED_REPORT);
    // Temporaries of killed batches writing these reports go first.
    crate::timeline::outputs::remove_stale_temporaries(&[
        path.clone(),
        path.with_extension("html"),
    ]);
    write_json(&path, report)?;
    let mut html = groom::AtomicFile::create(&path.with_extension("html"))?;
    let page = crate::report_html::batch_page(report, &manifest.out);
    std::io::Write::write_all(&mut html, page.as_bytes())?;
    html.commit()?;
    Ok(path)
}

/// The Slurm job-array script of the manifest ([`slurm::script`]).
pub fn slurm_script(
    manifest: &Manifest,
    executable: &Path,
    threads: usize,
    settings: &SlurmSettings,
) -> String {
    slurm::script(manifest, executable, threads, settings)
}
