//! Output files that appear whole or not at all.

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// A file written under a temporary name beside its destination and renamed
/// into place by [`AtomicFile::commit`]. Dropped without a commit, the
/// temporary file is removed, so a failed run never leaves a partial output.
pub struct AtomicFile {
    writer: Option<BufWriter<File>>,
    temporary: PathBuf,
    destination: PathBuf,
}

impl AtomicFile {
    pub fn create(destination: &Path) -> io::Result<AtomicFile> {
        let directory = match destination.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = destination.file_name().ok_or_else(|| {
            io::Error::new(io::ErrorKind::InvalidInput, "output path has no file name")
        })?;
        let mut temporary_name = std::ffi::OsString::from(".");
        temporary_name.push(name);
        temporary_name.push(format!(".{}.tmp", std::process::id()));
        let temporary = directory.join(temporary_name);
        let file = File::create(&temporary)?;
        Ok(AtomicFile {
            writer: Some(BufWriter::with_capacity(1 << 20, file)),
            temporary,
            destination: destination.to_path_buf(),
        })
    }

    pub fn destination(&self) -> &Path {
        &self.destination
    }

    fn writer(&mut self) -> io::Result<&mut BufWriter<File>> {
        self.writer
            .as_mut()
            .ok_or_else(|| io::Error::other("atomic file already committed"))
    }

    /// Flushes, syncs and renames the file into place. If any of that
    /// fails (a full disk shows here, when the buffer is flushed), the
    /// temporary file is removed.
    pub fn commit(mut self) -> io::Result<()> {
        let writer = self
            .writer
            .take()
            .ok_or_else(|| io::Error::other("atomic file already committed"))?;
        let result = writer
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|file| {
                file.sync_all()?;
                drop(file);
                std::fs::rename(&self.temporary, &self.destination)
            });
        if result.is_err() {
            let _ = std::fs::remove_file(&self.temporary);
        }
        result
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer()?.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer()?.write_all(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer()?.flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.writer()?.seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.temporary);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commit_renames_and_drop_cleans_up() {
        let dir = std::env::temp_dir().join(format!("groom-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let done = dir.join("done.bin");
        let mut file = AtomicFile::create(&done).unwrap();
        file.write_all(b"abc").unwrap();
        file.commit().unwrap();
        assert_eq!(std::fs::read(&done).unwrap(), b"abc");

        let failed = dir.join("failed.bin");
        let mut file = AtomicFile::create(&failed).unwrap();
        file.write_all(b"partial").unwrap();
        drop(file);
        assert!(!failed.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Regression: a commit that failed (at the flush, as on a full disk,
    /// or at the rename, here onto a folder that is not empty) left its
    /// temporary file behind.
    #[test]
    fn regression_a_failed_commit_removes_the_temporary() {
        let dir = std::env::temp_dir().join(format!("groom-atomic-fail-{}", std::process::id()));
        let folder = dir.join("taken");
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join("inside"), b"x").unwrap();
        let mut file = AtomicFile::create(&folder).unwrap();
        file.write_all(b"data").unwrap();
        assert!(file.commit().is_err());
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("taken")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
