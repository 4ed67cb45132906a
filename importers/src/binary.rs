//! A little-endian cursor over a file's bytes that names the byte offset of
//! every problem, shared by the binary readers.

use crate::{ImportError, Place};
use std::path::Path;

pub(crate) struct Cursor<'a> {
    file: &'a Path,
    bytes: &'a [u8],
    position: usize,
}

impl<'a> Cursor<'a> {
    pub fn new(file: &'a Path, bytes: &'a [u8]) -> Cursor<'a> {
        Cursor {
            file,
            bytes,
            position: 0,
        }
    }

    pub fn position(&self) -> usize {
        self.position
    }

    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.position
    }

    pub fn error_at(&self, offset: usize, message: impl Into<String>) -> ImportError {
        ImportError::malformed(self.file, Place::Offset(offset as u64), message)
    }

    /// Takes `count` bytes, or says what was being read when the file ended.
    pub fn take(&mut self, count: usize, what: &str) -> Result<&'a [u8], ImportError> {
        if count > self.remaining() {
            return Err(self.error_at(
                self.bytes.len(),
                format!(
                    "file ends inside {what} ({count} bytes needed from offset {}, {} left)",
                    self.position,
                    self.remaining()
                ),
            ));
        }
        let start = self.position;
        self.position += count;
        Ok(&self.bytes[start..start + count])
    }

    pub fn u16(&mut self, what: &str) -> Result<u16, ImportError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, ImportError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn i32(&mut self, what: &str) -> Result<i32, ImportError> {
        let b = self.take(4, what)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn f32(&mut self, what: &str) -> Result<f32, ImportError> {
        let b = self.take(4, what)?;
        Ok(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A finite f32; NaN and infinities are named with their offset.
    pub fn finite_f32(&mut self, what: &str) -> Result<f32, ImportError> {
        let offset = self.position;
        let value = self.f32(what)?;
        if !value.is_finite() {
            return Err(self.error_at(offset, format!("{what} is not finite ({value})")));
        }
        Ok(value)
    }

    pub fn finite_vec3(&mut self, what: &str) -> Result<[f32; 3], ImportError> {
        Ok([
            self.finite_f32(what)?,
            self.finite_f32(what)?,
            self.finite_f32(what)?,
        ])
    }

    /// Checks that `count` elements of `element_size` bytes fit in what is
    /// left, before anything is allocated for them.
    pub fn expect_elements(
        &self,
        count: u64,
        element_size: u64,
        what: &str,
    ) -> Result<(), ImportError> {
        let needed = count.saturating_mul(element_size);
        if needed > self.remaining() as u64 {
            return Err(self.error_at(
                self.position,
                format!(
                    "{what}: {count} elements of {element_size} bytes need {needed} bytes but only {} are left in the file",
                    self.remaining()
                ),
            ));
        }
        Ok(())
    }
}
