//! Alembic (Ogawa) export: the container ([`ogawa`]), Alembic's layout of
//! properties and objects on it ([`archive`]), the hashes it needs
//! ([`hashes`]) and the curves scene of a groom ([`curves`]).

pub mod archive;
pub mod curves;
pub mod hashes;
pub mod ogawa;

pub use curves::{animated, guide_cache, write};
#[cfg(test)]
pub(crate) mod test_support {
    /// The bytes of a file of the workspace's `tests/data/`.
    pub fn test_data(name: &str) -> Vec<u8> {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/");
        std::fs::read(format!("{path}{name}")).unwrap()
    }
}
