//! Test tooling: random scenes and primitives for property tests
//! ([`test_support`]) and Pearson's χ² test of a sampling routine against
//! its density ([`chi_square`]). Compiled for the crate's tests only.

pub(crate) mod chi_square;
pub(crate) mod test_support;
