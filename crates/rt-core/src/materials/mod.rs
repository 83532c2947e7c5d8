//! How surfaces and insides scatter light: a scene file's [`material`],
//! the BSDF it makes ([`bsdf`], with the optics of [`shading`] and the
//! physically based model of [`principled`]), the
//! medium of a translucent inside ([`medium`]), image [`texture`]s, the
//! [`normal_map`]s that bend the shading normal and the [`alpha`] that cuts
//! surfaces out.

pub mod alpha;
pub mod bsdf;
pub mod material;
pub mod medium;
pub mod normal_map;
pub mod principled;
pub mod shading;
pub mod texture;
