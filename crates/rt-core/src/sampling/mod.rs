//! Where samples go: the [`sampler::Sampler`] that hands out a pixel
//! sample's film position and random numbers, and the warps from the unit
//! square to disks, hemispheres and spheres.

pub mod sampler;
