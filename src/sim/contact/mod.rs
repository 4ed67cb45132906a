//! Contact: what a strand touches. Colliders, analytic shapes or meshes
//! through a distance grid ([`colliders`]); other strands, either pairwise
//! (the penalty of [`hair_pairs`], and the physical model's contacts with
//! Coulomb friction of [`hair_friction`], both finding their pairs through
//! the cells of [`grid`]) or, for dense grooms, through the hair's volume
//! ([`volume`]). Each search runs once at the start of a step from the
//! positions then; the step's constraint solve reads what it found.

pub(crate) mod colliders;
pub(crate) mod grid;
pub(crate) mod hair_friction;
#[cfg(test)]
mod hair_friction_tests;
pub(crate) mod hair_pairs;
pub(crate) mod solve;
#[cfg(test)]
pub(crate) mod tests;
pub(crate) mod volume;
