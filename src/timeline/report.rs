//! The machine-readable summary of a bake (`--report R.json`), written on
//! success and on failure; the README documents its schema.

use serde::{Serialize, Serializer};
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::Path;

#[derive(Debug, Clone, Serialize, Default)]
pub struct StageReport {
    pub index: usize,
    pub kind: String,
    pub name: String,
    /// The hold toward the groomed shape in this stage, when on: `strength`
    /// (1/s^2) and `ramp` (its shares at the root and the tip).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hold: Option<crate::sim::Hold>,
    /// Simulated seconds (to the microsecond).
    #[serde(serialize_with = "micros")]
    pub simulated_seconds: f64,
    /// Wall-clock seconds spent simulating it (to the millisecond).
    #[serde(serialize_with = "millis")]
    pub wall_seconds: f64,
    pub steps: u64,
    /// Strands frozen in this stage: their state turned non-finite, or
    /// the watchdog found them blown up (then also in `watchdog`).
    pub contained_strands: Vec<usize>,
    /// Strands the physical sanity watchdog contained, with why.
    pub watchdog: Vec<WatchdogReport>,
    /// After this stage, the share of the largest shape change so far
    /// (the pose against the groom at the start) that the rest shape
    /// keeps: 0 the hair would spring back to its groomed shape if released
    /// now, 1 it keeps the whole change; `null` while the pose has not
    /// changed (see `timeline::plots`).
    pub set_kept: Option<f64>,
    pub warnings: Vec<String>,
}

#[derive(Debug, Clone, Serialize)]
pub struct OutputReport {
    pub path: String,
    pub what: String,
    pub bytes: u64,
    pub sha256: String,
    /// Frames written (animated exports).
    pub frames: Option<usize>,
    /// The units and up axis of an Alembic or `.obj` export, which the file
    /// cannot record for other programs (`"m, Y up"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub written_in: Option<String>,
}

/// A strand the watchdog contained: at which step of the stage, and why.
#[derive(Debug, Clone, Serialize)]
pub struct WatchdogReport {
    pub strand: usize,
    pub step: u64,
    pub reason: String,
}

/// An input file of the bake and its SHA-256.
#[derive(Debug, Clone, Serialize)]
pub struct SourceReport {
    pub path: String,
    /// `groom`, `collider mesh` or `scalp mesh`.
    pub role: String,
    pub sha256: String,
}

/// The version of the report's layout; raised when a field changes meaning
/// or goes away.
pub const SCHEMA_VERSION: u32 = 2;

#[derive(Debug, Clone, Serialize, Default)]
pub struct BakeReport {
    pub schema_version: u32,
    /// `ok`, `invalid` (bad input, exit 2), `failed` (exit 1) or
    /// `interrupted` (a signal; exit 128 + its number).
    pub status: String,
    pub exit_code: u8,
    /// The error, when the status is not `ok`.
    pub error: Option<String>,
    pub timeline: String,
    /// SHA-256 of the timeline file (absent when it could not be read).
    pub timeline_sha256: Option<String>,
    pub sources: Vec<SourceReport>,
    /// Start and end of the run, RFC 3339 UTC.
    pub started: String,
    pub finished: String,
    /// Peak resident memory of the process, bytes (getrusage).
    pub peak_memory_bytes: u64,
    pub groombake_version: String,
    pub seed: u64,
    pub threads: usize,
    pub strands: usize,
    pub vertices: usize,
    /// The fibre radii used (metres) and where they came from.
    pub fibre_radius: Option<super::fibre::FibreRadius>,
    /// Strands the solver does not move (fewer than two points, or two
    /// identical consecutive points).
    pub unsimulated_strands: Vec<usize>,
    #[serde(serialize_with = "micros")]
    pub simulated_seconds: f64,
    #[serde(serialize_with = "millis")]
    pub wall_seconds: f64,
    pub stages: Vec<StageReport>,
    pub outputs: Vec<OutputReport>,
    pub warnings: Vec<String>,
}

/// Seconds to the microsecond: simulated time is a whole number of steps,
/// and the sum of steps should not read `2.3000000000000003`.
fn micros<S: Serializer>(seconds: &f64, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_f64((seconds * 1e6).round() / 1e6)
}

/// Seconds to the millisecond: wall-clock time is not more exact.
fn millis<S: Serializer>(seconds: &f64, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_f64((seconds * 1e3).round() / 1e3)
}

/// Now, RFC 3339 UTC to the millisecond.
pub fn now_rfc3339() -> String {
    humantime::format_rfc3339_millis(std::time::SystemTime::now()).to_string()
}

/// The peak resident memory of this process so far, bytes.
pub fn peak_memory_bytes() -> u64 {
    // SAFETY: getrusage fills the zeroed struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return 0;
    }
    // Linux gives kilobytes.
    u64::try_from(usage.ru_maxrss).unwrap_or(0) * 1024
}

impl BakeReport {
    /// A report of a run of `timeline` starting now.
    pub fn start(timeline: &Path) -> BakeReport {
        BakeReport {
            schema_version: SCHEMA_VERSION,
            status: "running".into(),
            timeline: timeline.display().to_string(),
            timeline_sha256: size_and_sha256(timeline).ok().map(|(_, h)| h),
            started: now_rfc3339(),
            groombake_version: env!("CARGO_PKG_VERSION").to_string(),
            ..BakeReport::default()
        }
    }

    /// Records the input files of the timeline and their hashes.
    pub fn record_sources(&mut self, timeline: &super::Timeline) {
        self.sources = input_files(timeline)
            .into_iter()
            .filter_map(|(role, path)| {
                let (_, sha256) = size_and_sha256(&path).ok()?;
                Some(SourceReport {
                    path: path.display().to_string(),
                    role: role.into(),
                    sha256,
                })
            })
            .collect();
    }

    /// Ends the report of a bake of `timeline` that succeeded as `groombake
    /// bake --report` writes it: the input files, the timeline's warnings
    /// first, status `ok`, the time it finished.
    pub fn finish_ok(&mut self, timeline: &super::Timeline) {
        self.record_sources(timeline);
        self.warnings.splice(0..0, timeline.warnings());
        self.finish("ok", 0, None);
    }

    /// Ends the report with the outcome.
    pub fn finish(&mut self, status: &str, exit_code: u8, error: Option<String>) {
        self.status = status.into();
        self.exit_code = exit_code;
        self.error = error;
        self.finished = now_rfc3339();
        self.peak_memory_bytes = peak_memory_bytes();
    }

    /// Writes the report as JSON, whole or not at all.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let mut file = groom::AtomicFile::create(path)?;
        serde_json::to_writer_pretty(&mut file, self)?;
        std::io::Write::write_all(&mut file, b"\n")?;
        file.commit()
    }
}

/// Every file a timeline reads besides itself, with its role: the groom,
/// collider meshes and the render scalp. A bake's outputs depend on these
/// bytes (a batch's `--resume` compares their hashes).
pub fn input_files(timeline: &super::Timeline) -> Vec<(&'static str, std::path::PathBuf)> {
    let mut files = Vec::new();
    let groom = &timeline.file.groom;
    if let Some(source) = &groom.source {
        files.push(("groom", timeline.resolve(source.get_ref())));
    }
    for c in &timeline.file.colliders {
        if let super::schema::ShapeSpec::Mesh { path, .. } = c.shape.get_ref() {
            files.push(("collider mesh", timeline.resolve(path)));
        }
    }
    if let Some(scalp) = groom
        .render
        .as_ref()
        .and_then(|r| r.get_ref().scalp.as_ref())
    {
        files.push(("scalp mesh", timeline.resolve(scalp)));
    }
    files
}

/// Size and SHA-256 (lower-case hex) of a file.
pub fn size_and_sha256(path: &Path) -> std::io::Result<(u64, String)> {
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 16];
    let mut total = 0u64;
    loop {
        let n = file.read(&mut buffer)?;
        if n == 0 {
            break;
        }
        total += n as u64;
        hasher.update(&buffer[..n]);
    }
    let digest = hasher.finalize();
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    Ok((total, hex))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_of_known_text() {
        let path = std::env::temp_dir().join(format!("groombake-sha-{}", std::process::id()));
        std::fs::write(&path, b"abc").unwrap();
        let (size, hex) = size_and_sha256(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(size, 3);
        assert_eq!(
            hex,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
