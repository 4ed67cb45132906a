//! Alembic (Ogawa) export: the container ([`ogawa`]), Alembic's layout of
//! properties and objects on it ([`archive`]), the hashes it needs
//! ([`hashes`]) and the curves scene of a groom ([`curves`]).

pub mod archive;
pub mod curves;
pub mod hashes;
pub mod ogawa;

pub use curves::{animated, write};
#[cfg(test)]
pub(crate) mod test_support {
    /// A file of the shared sample data: `shared/data/` beside the repository
    /// (or beside one of its parent directories, as in a worktree).
    pub fn shared_data(name: &str) -> Vec<u8> {
        let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        for dir in manifest.ancestors() {
            let candidate = dir.join("shared/data").join(name);
            if candidate.exists() {
                return std::fs::read(&candidate).unwrap();
            }
        }
        panic!("missing shared data file {name}");
    }
}
