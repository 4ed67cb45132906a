//! The files a bake writes, checked before the first step and made
//! crash-consistent:
//!
//! - every output and the report are checked for a usable folder and for
//!   collisions by canonical path (`./a.usda`, `/abs/a.usda` and
//!   `sub/../a.usda` are one file) before anything is simulated;
//! - each output is written to a staging file beside its final path,
//!   `.groombake-<PID>.<NAME>` (beside, not in one staging folder, so the
//!   final rename never crosses file systems and stays atomic), and all are
//!   renamed into place only after the last one is written: the old report
//!   is removed first and the new report is written last, so a set with a
//!   report is complete and a set without one is not to be trusted;
//! - a staged file of a failed or interrupted bake is removed when the bake
//!   unwinds ([`Staging`]'s `Drop`); one a killed bake left behind carries a
//!   dead process's id and the next bake into that folder removes it
//!   ([`remove_stale_temporaries`]).

use std::collections::BTreeSet;
use std::ffi::OsStr;
use std::path::{Component, Path, PathBuf};

/// The prefix of staged outputs; the process id follows.
const STAGED_PREFIX: &str = ".groombake-";

/// `path` made absolute and free of `.`/`..`, with symbolic links of its
/// existing part resolved: two paths name one file exactly when their
/// canonical forms are equal.
pub fn canonical(path: &Path) -> std::io::Result<PathBuf> {
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()?.join(path)
    };
    // Lexically first (`sub/../x` must not need `sub` to exist), then the
    // longest existing ancestor through the file system (links).
    let mut lexical = PathBuf::new();
    for component in absolute.components() {
        match component {
            Component::ParentDir => {
                lexical.pop();
            }
            Component::CurDir => {}
            other => lexical.push(other),
        }
    }
    let mut existing = lexical.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(resolved) = existing.canonicalize() {
            let mut out = resolved;
            for part in rest.iter().rev() {
                out.push(part);
            }
            return Ok(out);
        }
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                existing = parent;
            }
            _ => return Ok(lexical),
        }
    }
}

/// Why `path` cannot be written, found without writing it: it cannot name
/// a file ([`super::check_output_name`]), it is a folder, a part of its
/// folder is a file, or the folder that exists is not
/// writable (see `may_write_in`).
pub fn check_writable(path: &Path) -> Result<(), String> {
    super::check_output_name(path)?;
    if path.is_dir() {
        return Err("is a folder, not a file".into());
    }
    let mut ancestor = path.parent();
    while let Some(dir) = ancestor {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => return may_write_in(dir),
            Ok(_) => {
                return Err(format!(
                    "'{}' is a file, not a folder",
                    dir.display().to_string().escape_debug()
                ))
            }
            Err(_) => ancestor = dir.parent(),
        }
    }
    Ok(())
}

/// Whether a file can be created in `dir`, tried with an unnamed
/// temporary file (`O_TMPFILE`): nothing is left behind, even by a bake
/// killed during the check. Where the file system has no unnamed files
/// (network and special ones), a named probe file is created and removed.
fn may_write_in(dir: &Path) -> Result<(), String> {
    use std::os::unix::fs::OpenOptionsExt;
    let cannot = |e: std::io::Error| {
        format!(
            "cannot write in '{}': {e}",
            dir.display().to_string().escape_debug()
        )
    };
    let unnamed = std::fs::OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_TMPFILE)
        .mode(0o600)
        .open(dir);
    match unnamed {
        Ok(_) => Ok(()),
        // Kernels and file systems without O_TMPFILE answer one of these.
        Err(e) if matches!(e.raw_os_error(), Some(libc::EOPNOTSUPP | libc::EISDIR)) => {
            let probe = dir.join(format!("{STAGED_PREFIX}{}.probe", std::process::id()));
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&probe)
                .map_err(cannot)?;
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(cannot(e)),
    }
}

/// `text` with this process's staged file names replaced by their final
/// names (for messages about an output).
pub fn final_names(text: &str) -> String {
    text.replace(&format!("{STAGED_PREFIX}{}.", std::process::id()), "")
}

/// Outputs staged beside their final paths, renamed into place by
/// [`Staging::commit`]; dropped before that, the staged files are removed.
#[derive(Debug, Default)]
pub struct Staging {
    /// (staged, final) paths.
    files: Vec<(PathBuf, PathBuf)>,
    committed: bool,
}

impl Staging {
    /// The staged path of the output at `final_path`; its extension is the
    /// final one, so the exporters choose the same format.
    pub fn stage(&mut self, final_path: &Path) -> PathBuf {
        let name = final_path.file_name().unwrap_or(OsStr::new("output"));
        let mut staged_name =
            std::ffi::OsString::from(format!("{STAGED_PREFIX}{}.", std::process::id()));
        staged_name.push(name);
        let staged = final_path.with_file_name(staged_name);
        self.files.push((staged.clone(), final_path.to_path_buf()));
        staged
    }

    /// Removes the old report (so a half-renamed set has none), then renames
    /// every staged file into place. The caller writes the new report after.
    pub fn commit(mut self, report: Option<&Path>) -> std::io::Result<()> {
        if let Some(report) = report {
            match std::fs::remove_file(report) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e),
                _ => {}
            }
        }
        for (staged, final_path) in &self.files {
            std::fs::rename(staged, final_path)?;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            for (staged, _) in &self.files {
                let _ = std::fs::remove_file(staged);
            }
        }
    }
}

/// Whether a process with this id runs (or cannot be told apart from one
/// that does: a process of another user).
fn is_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    // SAFETY: kill with signal 0 only checks that the process exists.
    let result = unsafe { libc::kill(pid, 0) };
    result == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

/// The process id in the name of a bake's temporary: a staged output
/// `.groombake-<PID>.<NAME>`, or an atomic file `.<NAME>.<PID>.tmp` whose
/// NAME is one of `names` or itself staged.
fn temporary_pid(file_name: &str, names: &BTreeSet<String>) -> Option<u32> {
    if let Some(rest) = file_name.strip_prefix(STAGED_PREFIX) {
        let (pid, _) = rest.split_once('.')?;
        return pid.parse().ok();
    }
    let inner = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (name, pid) = inner.rsplit_once('.')?;
    (names.contains(name) || name.starts_with(STAGED_PREFIX))
        .then(|| pid.parse().ok())
        .flatten()
}

/// Removes, in the folders of `outputs`, the temporaries of bakes whose
/// process no longer runs; returns the paths removed.
pub fn remove_stale_temporaries(outputs: &[PathBuf]) -> Vec<PathBuf> {
    let names: BTreeSet<String> = outputs
        .iter()
        .filter_map(|p| p.file_name()?.to_str().map(str::to_string))
        .collect();
    let folders: BTreeSet<PathBuf> = outputs
        .iter()
        .map(|p| match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        })
        .collect();
    let me = std::process::id();
    let mut removed = Vec::new();
    for folder in folders {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let Some(pid) = name.to_str().and_then(|n| temporary_pid(n, &names)) else {
                continue;
            };
            if pid != me && !is_alive(pid) && std::fs::remove_file(entry.path()).is_ok() {
                removed.push(entry.path());
            }
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dotted_paths_are_one_file() {
        let here = std::env::current_dir().unwrap();
        let a = canonical(Path::new("final.usda")).unwrap();
        assert_eq!(a, canonical(Path::new("./final.usda")).unwrap());
        assert_eq!(a, canonical(Path::new("sub/../final.usda")).unwrap());
        assert_eq!(a, canonical(&here.join("final.usda")).unwrap());
        assert_ne!(a, canonical(Path::new("sub/final.usda")).unwrap());
    }

    #[test]
    fn temporaries_are_recognised_by_name() {
        let names: BTreeSet<String> = ["final.usda".to_string()].into();
        assert_eq!(temporary_pid(".groombake-42.final.usda", &names), Some(42));
        assert_eq!(temporary_pid(".final.usda.42.tmp", &names), Some(42));
        assert_eq!(
            temporary_pid("..groombake-42.final.usda.42.tmp", &names),
            Some(42)
        );
        assert_eq!(temporary_pid(".other.abc.42.tmp", &names), None);
        assert_eq!(temporary_pid("final.usda", &names), None);
    }
}
