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
use std::path::Path;

/// A whole regular file mapped read-only.
pub struct Mapped {
    pointer: *mut libc::c_void,
    len: usize,
}

// SAFETY: the mapping is read-only and owned by this value alone; it is
// only unmapped by `drop`.
unsafe impl Send for Mapped {}
unsafe impl Sync for Mapped {}

impl Mapped {
    /// Maps the regular file at `path` (an empty file maps to no bytes).
    pub fn open(path: &Path) -> Result<Mapped, ImportError> {
        use std::os::unix::fs::OpenOptionsExt;
        use std::os::unix::io::AsRawFd;
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
        let len = usize::try_from(metadata.len()).map_err(|_| {
            ImportError::malformed(path, Place::File, "too large to map into memory")
        })?;
        if len == 0 {
            return Ok(Mapped {
                pointer: std::ptr::null_mut(),
                len: 0,
            });
        }
        // SAFETY: a fresh private read-only mapping of an open file of
        // `len` bytes; the descriptor may close after the call.
        let pointer = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ,
                libc::MAP_PRIVATE,
                file.as_raw_fd(),
                0,
            )
        };
        if pointer == libc::MAP_FAILED {
            return Err(ImportError::io(path, std::io::Error::last_os_error()));
        }
        Ok(Mapped { pointer, len })
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: `pointer` maps `len` readable bytes until `drop`.
        unsafe { std::slice::from_raw_parts(self.pointer.cast::<u8>(), self.len) }
    }

    /// Drops the pages read so far from this process's resident memory;
    /// the bytes stay readable (read again from the page cache or the
    /// file). Needs `&mut self`, so no slice of the old pages is held.
    pub fn release(&mut self) {
        if self.len > 0 {
            // SAFETY: advice on our own read-only private mapping; a file
            // mapping reads its pages back on the next access.
            unsafe {
                libc::madvise(self.pointer, self.len, libc::MADV_DONTNEED);
            }
        }
    }
}

impl Drop for Mapped {
    fn drop(&mut self) {
        if self.len > 0 {
            // SAFETY: unmaps the mapping `open` made, once.
            unsafe {
                libc::munmap(self.pointer, self.len);
            }
        }
    }
}
