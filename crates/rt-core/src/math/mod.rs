//! The numbers everything else is made of: the geometry's floating-point
//! type and its tolerances ([`real`]), rays and ranges of their parameter
//! ([`ray`]), and linear RGB colours ([`color`]).

pub mod color;
pub mod ray;
pub mod real;
