//! A read-only memory map of an input file, for the frame-at-a-time
//! readers ([`crate::stream`]): the parsers keep working on a byte slice,
//! but only the pages a frame touches are read, and
//! [`Mapped::release`] drops them from the process's resident memory once
//! the frame is decoded, so memory stays one frame plus the topology
//! however large the file (the pages stay in the page cache for the next
//! read).
//!
//! Caveat: a file truncated by another process while it is mapped makes a
//! read of the lost pages fault (SIGBUS), as with any memory-mapped reader.

use crate::{special_kind, ImportError, Place};
use memmap2::{Mmap, UncheckedAdvice};
use std::path::Path;

/// A whole regular file mapped read-only (`memmap2`).
pub struct Mapped {
    /// `None` for an empty file, which cannot be mapped.
    map: Option<Mmap>,
}

impl Mapped {
    /// Maps the regular file at `path` (an empty file maps to no bytes).
    pub fn open(path: &Path) -> Result<Mapped, ImportError> {
        use std::os::unix::fs::OpenOptionsExt;
        // Non-blocking open: a FIFO with no writer would block.
        let file = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(path)
            .map_err(|e| ImportError::io(path, e))?;
        let metadata = file.metadata().map_err(|e| ImportError::io(path, e))?;
        if let Some(kind) = special_kind(&metadata) {
            return Err(ImportError::malformed(
                path,
                Place::File,
                format!("{kind}, not a regular file: inputs are read from regular files"),
            ));
        }
        usize::try_from(metadata.len()).map_err(|_| {
            ImportError::malformed(path, Place::File, "too large to map into memory")
        })?;
        if metadata.len() == 0 {
            return Ok(Mapped { map: None });
        }
        // SAFETY: a read-only mapping of a regular file; another process
        // truncating it while mapped makes a read fault (the module's caveat).
        let map = unsafe { Mmap::map(&file) }.map_err(|e| ImportError::io(path, e))?;
        Ok(Mapped { map: Some(map) })
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        self.map.as_deref().unwrap_or(&[])
    }

    /// Drops the pages read so far from this process's resident memory;
    /// the bytes stay readable (read again from the page cache or the
    /// file). Needs `&mut self`, so no slice of the old pages is held.
    pub fn release(&mut self) {
        if let Some(map) = &self.map {
            // SAFETY: DONTNEED on a read-only file mapping only drops
            // resident pages: the next access reads them back from the
            // file, and `&mut self` means no slice into them is alive.
            // Advice is a hint: a failure leaves the pages resident.
            let _ = unsafe { map.unchecked_advise(UncheckedAdvice::DontNeed) };
        }
    }
}
