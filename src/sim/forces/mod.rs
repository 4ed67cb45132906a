//! Outside forces on the hair, applied in the step's prediction: gravity
//! and drag (the step's `predict`), the blower ([`blower`]) and the hold
//! toward the groomed shape ([`hold`]), an implicit spring folded into the
//! prediction and the vertices' inverse masses.

pub(crate) mod blower;
pub(crate) mod hold;
#[cfg(test)]
mod hold_tests;
pub(crate) mod predict;
#[cfg(test)]
mod tests;
