//! What a job's outputs depend on, recorded in its report so that
//! `batch --resume` skips a job only when nothing of it changed: the
//! groombake version, the timeline's bytes, the bytes of every file it
//! reads (the groom, or the manifest's groom in its place, collider and
//! scalp meshes) and the job's options (the seed). Outputs are identical
//! for any thread count, so threads are not part of it. Files are compared
//! by content: the same bytes under another path bake the same outputs.

use super::Job;
use crate::timeline::report::{input_files, size_and_sha256};
use crate::timeline::Timeline;
use serde::{Deserialize, Serialize};

/// A file a job reads, with its SHA-256.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct InputFile {
    /// `groom`, `collider mesh` or `scalp mesh`.
    pub role: String,
    pub path: String,
    pub sha256: String,
}

/// Everything a job's outputs depend on.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct JobInputs {
    pub groombake_version: String,
    pub timeline_sha256: String,
    pub sources: Vec<InputFile>,
    /// The manifest's seed for the job (overrides the timeline's).
    pub seed: Option<u64>,
}

/// The current version of this program.
pub fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The inputs of a job as they are on disk now, read from its timeline
/// (loaded with the manifest's groom in place).
pub fn current(job: &Job, timeline: &Timeline) -> Result<JobInputs, String> {
    let hash = |path: &std::path::Path| {
        size_and_sha256(path)
            .map(|(_, sha)| sha)
            .map_err(|e| format!("{}: {e}", path.display()))
    };
    let sources = input_files(timeline)
        .into_iter()
        .map(|(role, path)| {
            Ok(InputFile {
                role: role.to_string(),
                sha256: hash(&path)?,
                path: path.display().to_string(),
            })
        })
        .collect::<Result<_, String>>()?;
    Ok(JobInputs {
        groombake_version: version().to_string(),
        timeline_sha256: hash(&job.timeline)?,
        sources,
        seed: job.seed,
    })
}

/// Why outputs baked from `old` inputs are stale for `new` ones; `None`
/// when they are the same.
pub fn change(old: &JobInputs, new: &JobInputs) -> Option<String> {
    if old.groombake_version != new.groombake_version {
        return Some(format!(
            "groombake {} -> {}",
            old.groombake_version, new.groombake_version
        ));
    }
    if old.timeline_sha256 != new.timeline_sha256 {
        return Some("the timeline changed".into());
    }
    let same = |a: &InputFile, b: &InputFile| a.role == b.role && a.sha256 == b.sha256;
    if old.sources.len() != new.sources.len() {
        return Some("the timeline reads other files".into());
    }
    if let Some(file) = old
        .sources
        .iter()
        .zip(&new.sources)
        .find_map(|(a, b)| (!same(a, b)).then_some(b))
    {
        return Some(format!("the {} '{}' changed", file.role, file.path));
    }
    if old.seed != new.seed {
        let show = |s: Option<u64>| s.map_or("the timeline's".to_string(), |s| s.to_string());
        return Some(format!(
            "the seed changed ({} -> {})",
            show(old.seed),
            show(new.seed)
        ));
    }
    None
}
