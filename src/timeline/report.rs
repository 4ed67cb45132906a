//! The machine-readable summary of a bake (`--report R.json`).

use serde::Serialize;
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::Path;

#[derive(Debug, Clone, Serialize, Default)]
pub struct StageReport {
    pub index: usize,
    pub kind: String,
    pub name: String,
    /// Simulated seconds.
    pub simulated_seconds: f64,
    /// Wall-clock seconds spent simulating it.
    pub wall_seconds: f64,
    pub steps: u64,
    /// Strands frozen after their state turned non-finite in this stage.
    pub contained_strands: Vec<usize>,
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
}

#[derive(Debug, Clone, Serialize, Default)]
pub struct BakeReport {
    pub timeline: String,
    pub groombake_version: String,
    pub seed: u64,
    pub threads: usize,
    pub strands: usize,
    pub vertices: usize,
    pub simulated_seconds: f64,
    pub wall_seconds: f64,
    pub stages: Vec<StageReport>,
    pub outputs: Vec<OutputReport>,
    pub warnings: Vec<String>,
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
