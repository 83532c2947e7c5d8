//! Where samples go: the [`sampler::Sampler`] that hands out a pixel
//! sample's film position and random numbers (stratified, or
//! Owen-scrambled Sobol points: [`sobol`]), and the warps from the unit
//! square to disks, hemispheres and spheres.

pub mod sampler;
pub mod sobol;
