//! The curves objects a groom was read from (USD `BasisCurves` prims), kept
//! in [`Provenance::metadata`](crate::Provenance::metadata) so that a writer
//! of the same kind can write them again: each prim's path, its strands
//! (consecutive, in the groom's order) and the attributes it did not have
//! (zero-filled in the groom, left out when written back).
//!
//! A writer honours the table only while it still describes the groom
//! (its strand counts add up to the groom's); a bake or a selection that
//! changes the strands leaves a table that does not, and is written flat.

use crate::{Groom, PRIMS_KEY};

/// Per prim, in [`PRIMS_KEY`]'s order, the attributes the prim lacks: one
/// line each, names separated by spaces (an empty line: none).
pub const PRIMS_MISSING_KEY: &str = "prims.missing";

/// Set (to `synthesised`) when the reader made up `group_id` from the
/// prims (the source has none): a writer that keeps the prims leaves it out,
/// and reading the prims back gives the same ids again.
pub const GROUP_ID_KEY: &str = "prims.group_id";

/// The reader's warnings (one per line, as in
/// [`Provenance::losses`](crate::Provenance::losses)) that a prim lacked an
/// attribute other prims have, so the groom holds zeros for its strands: no
/// loss when the prims are written back as they were.
pub const ZERO_FILLED_KEY: &str = "prims.zero_filled";

/// The losses of [`ZERO_FILLED_KEY`].
pub fn zero_filled(groom: &Groom) -> Vec<&str> {
    groom
        .provenance
        .metadata
        .get(ZERO_FILLED_KEY)
        .map(|m| m.lines().collect())
        .unwrap_or_default()
}

/// One curves object of the source.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SourcePrim {
    /// Its composed path, e.g. `/World/Hair/Strands`.
    pub path: String,
    /// Its strands: this many, following the previous prim's.
    pub strands: usize,
    /// Groom attributes this prim did not have.
    pub missing: Vec<String>,
}

/// The groom's source prims, when they still describe its strands.
pub fn source_prims(groom: &Groom) -> Option<Vec<SourcePrim>> {
    let metadata = &groom.provenance.metadata;
    let table = metadata.get(PRIMS_KEY)?;
    let missing: Vec<&str> = metadata
        .get(PRIMS_MISSING_KEY)
        .map(|m| m.split('\n').collect())
        .unwrap_or_default();
    let mut prims = Vec::new();
    for (index, line) in table.lines().enumerate() {
        let (path, count) = line.rsplit_once(' ')?;
        prims.push(SourcePrim {
            path: path.to_string(),
            strands: count.parse().ok()?,
            missing: missing
                .get(index)
                .map(|m| m.split_whitespace().map(str::to_string).collect())
                .unwrap_or_default(),
        });
    }
    let total = prims
        .iter()
        .try_fold(0usize, |sum, p| sum.checked_add(p.strands))?;
    (total == groom.strand_count() && !prims.is_empty()).then_some(prims)
}

/// Records the prims a reader read (see [`source_prims`]).
pub fn set_source_prims(groom: &mut Groom, prims: &[SourcePrim]) {
    let metadata = &mut groom.provenance.metadata;
    let table: Vec<String> = prims
        .iter()
        .map(|p| format!("{} {}", p.path, p.strands))
        .collect();
    metadata.insert(PRIMS_KEY.into(), table.join("\n"));
    if prims.iter().any(|p| !p.missing.is_empty()) {
        let missing: Vec<String> = prims.iter().map(|p| p.missing.join(" ")).collect();
        metadata.insert(PRIMS_MISSING_KEY.into(), missing.join("\n"));
    } else {
        metadata.remove(PRIMS_MISSING_KEY);
    }
}

/// Whether `group_id` was made up by the reader from the prims.
pub fn group_id_is_synthesised(groom: &Groom) -> bool {
    groom
        .provenance
        .metadata
        .get(GROUP_ID_KEY)
        .map(String::as_str)
        == Some("synthesised")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_round_trips_and_is_dropped_when_strands_change() {
        let mut groom = Groom::from_strands([[[0.0f32; 3]; 2]; 3]);
        let prims = vec![
            SourcePrim {
                path: "/A/b".into(),
                strands: 1,
                missing: vec!["width".into()],
            },
            SourcePrim {
                path: "/A/c".into(),
                strands: 2,
                missing: Vec::new(),
            },
        ];
        set_source_prims(&mut groom, &prims);
        assert_eq!(source_prims(&groom), Some(prims));
        let fewer = groom.select_strands(&[0, 1]);
        assert_eq!(source_prims(&fewer), None);
    }
}
