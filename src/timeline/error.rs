//! Why a bake fails: its own file so that every part of the bake (render
//! hair, surfaces, outputs) can name the error without importing the bake.

use super::TimelineError;
use crate::sim;
use std::path::PathBuf;

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Timeline(#[from] TimelineError),
    #[error(transparent)]
    Import(#[from] importers::ImportError),
    #[error(transparent)]
    Export(#[from] exporters::ExportError),
    #[error("{}: {message}", file.display())]
    Input { file: PathBuf, message: String },
    #[error("simulation: {0}")]
    Simulation(#[from] sim::SimError),
    #[error("{}: {source}", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("thread pool: {0}")]
    Threads(String),
    /// An output or report path that cannot be written or names the same
    /// file as another.
    #[error("{}: {message}", file.display())]
    Output { file: PathBuf, message: String },
    /// The report path cannot be written or names an output: no report
    /// can be written, not even of the failure.
    #[error("--report {}: {message}", file.display())]
    Report { file: PathBuf, message: String },
    #[error("stopped by signal {signal}; temporaries removed, no output replaced")]
    Interrupted { signal: usize },
    #[error(transparent)]
    Preview(#[from] crate::preview::PreviewError),
    #[error("the bake was interrupted")]
    Cancelled,
    /// A failure writing an output, naming its final path.
    #[error("{0}")]
    Write(String),
}

impl BakeError {
    /// Bad input (exit 2) rather than a failure during the work (exit 1).
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            BakeError::Timeline(_)
                | BakeError::Import(_)
                | BakeError::Input { .. }
                | BakeError::Output { .. }
                | BakeError::Report { .. }
        )
    }
}
