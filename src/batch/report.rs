//! What a batch reports: each job's report and the merged one. Their own
//! module so that the HTML page of a batch can read them without
//! importing the batch runner that writes the page.

use super::inputs::JobInputs;
use serde::{Deserialize, Serialize};

/// An output of a job: its path (relative to the job's folder where it
/// lies inside it), size and SHA-256.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct JobOutput {
    pub path: String,
    pub bytes: u64,
    pub sha256: String,
}

/// How a job ended.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum JobStatus {
    /// Baked now.
    Ok,
    /// Complete from an earlier run (`resume`): outputs match the report.
    Skipped,
    Failed,
    /// No report found (a merge of shards that did not all run).
    Missing,
    /// Stopped by a signal while it ran, or never started because of one.
    Interrupted,
}

/// The report of one job (also the entry of the merged report).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct JobReport {
    pub name: String,
    pub timeline: String,
    pub groom: Option<String>,
    pub folder: String,
    pub status: JobStatus,
    pub error: Option<String>,
    pub wall_seconds: f64,
    pub outputs: Vec<JobOutput>,
    /// The bake's own report (`bake --report`), when it ran.
    pub bake: Option<serde_json::Value>,
    /// What the outputs depend on (absent in reports of older versions,
    /// and when the timeline could not be read).
    #[serde(default)]
    pub inputs: Option<JobInputs>,
    /// Why `resume` baked a job again that had a complete report.
    #[serde(default)]
    pub rebaked_because: Option<String>,
}

/// The merged report of a batch.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BatchReport {
    pub manifest: String,
    pub groombake_version: String,
    pub jobs: Vec<JobReport>,
    pub succeeded: usize,
    pub failed: usize,
    pub missing: usize,
    pub wall_seconds: f64,
}

impl BatchReport {
    pub fn all_succeeded(&self) -> bool {
        self.failed == 0 && self.missing == 0
    }
}
