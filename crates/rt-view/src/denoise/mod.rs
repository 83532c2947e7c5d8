//! Denoising with Intel Open Image Denoise (OIDN), loaded at run time.
//!
//! OIDN is not in Debian's packages and the `oidn` crate links the library
//! at build time, which would make every build need it. Instead
//! [`library`] finds `libOpenImageDenoise.so.2` where
//! `scripts/get_oidn.sh` puts it (or on the system's search path) and
//! [`oidn`] calls its small C API through hand-written declarations: a
//! build, the tests and the README's commands work without it, and
//! `--denoise` says clearly when it is absent.
//!
//! What is denoised: the linear HDR colour, with the albedo and normal of
//! the first non-specular hit ([`rt_core::render::passes`]) as auxiliary
//! images, by OIDN's "RT" filter with `hdr` on. The auxiliary images are
//! averaged over the same samples as the colour and carry some noise
//! (antialiased edges, glossy albedo estimates, the choice at glass), so
//! `cleanAux` stays off: OIDN prefilters them itself.

pub mod library;
pub mod oidn;

pub use library::{NotFound, find_and_load};
pub use oidn::{AuxImages, DenoiseError, Oidn};
