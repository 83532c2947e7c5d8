//! `rt-view`: two programs in one binary, as a library so they can be tested
//! directly.
//!
//! - [`commands`]: the headless commands — `render` (a scene to PNG or EXR),
//!   `cast` (ray queries as CSV), `bench` and `accuracy` (what speed and
//!   accuracy cost) — with [`image_out`] writing images atomically and
//!   [`timing`] the medians they report.
//! - [`denoise`]: Open Image Denoise, loaded at run time when present.
//! - [`viewer`]: the interactive window, whose image streams in row by row.
//!
//! [`cli`] parses the command line and hands it to one or the other.

pub mod cli;
pub mod commands;
pub mod content_hash;
pub mod denoise;
pub mod exact_sum;
pub mod image_out;
pub mod part_file;
pub mod scene_cache;
pub mod sum_render;
pub mod timing;
pub mod viewer;
