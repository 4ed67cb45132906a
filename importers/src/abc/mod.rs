//! Alembic (Ogawa) import: the container ([`ogawa`]), Alembic's objects and
//! properties on it ([`archive`]) and the curves scene ([`scene`]).
//!
//! The whole file is read into memory; every offset, size and count in it is
//! checked against the bytes there before use.

pub mod archive;
pub mod ogawa;
pub mod scene;

use crate::{read_bytes, ImportError};
use groom::Groom;
use std::path::Path;

/// Reads every Curves object of an `.abc` file into one groom.
pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = read_bytes(path)?;
    parse(path, &bytes)
}

/// Reads a groom from the bytes of an `.abc` file; `path` names it in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let fail = |fault: ogawa::Fault| ImportError::malformed(path, fault.place, fault.message);
    let archive = archive::Archive::open(bytes).map_err(fail)?;
    scene::read_groom(&archive).map_err(fail)
}
