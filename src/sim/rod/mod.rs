//! The rod: one strand as a Cosserat rod and what holds its shape. The
//! constraints of the paper model ([`constraints`]) and their sweep on four
//! strands in SIMD lanes ([`lanes`]); the physical model's direct solve
//! ([`direct`]) in the numbers of [`real`] and its midpoint step
//! ([`midpoint`]); the side-chain bonds that set
//! the rest shape and remember it ([`bonds`]); and the sag-free rest shape
//! solved before the first step ([`sag_free`]). Everything here acts
//! within one strand: contacts with colliders and other strands are in
//! `contact`, outside forces in `forces`.

pub(crate) mod bonds;
pub(crate) mod constraints;
pub(crate) mod direct;
pub(crate) mod lanes;
pub(crate) mod midpoint;
#[cfg(test)]
pub(crate) mod physical_tests;
pub(crate) mod real;
pub(crate) mod sag_free;
#[cfg(test)]
mod sag_free_tests;
pub(crate) mod shape_memory;
pub(crate) mod solve;
