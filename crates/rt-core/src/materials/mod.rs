//! How surfaces and insides scatter light: a scene file's [`material`],
//! the BSDF it makes ([`bsdf`], with the optics of [`shading`] and the
//! physically based model of [`principled`]), the
//! medium of a translucent inside ([`medium`]), image [`texture`]s and how a
//! material uses one ([`texture_slot`]) at the level of detail a ray's
//! footprint asks for ([`texture_lod`]), the [`normal_map`]s that bend the
//! shading normal and the [`alpha`] that cuts surfaces out.

pub mod alpha;
pub mod bsdf;
pub mod hit_bsdf;
pub mod material;
pub mod medium;
pub mod normal_map;
pub mod principled;
pub mod shading;
pub mod texture;
pub mod texture_lod;
pub mod texture_slot;
