//! Reference answers for the accuracy measurements (`rt-view accuracy`)
//! and the hard-case tests: fixed ray sets with known answers
//! ([`hard_cases`]), computed in double-double arithmetic
//! ([`double_double`]). Built for the crate's tests and with the
//! `accuracy` feature (which rt-view turns on); a renderer needs neither.

pub mod double_double;
pub mod hard_cases;
