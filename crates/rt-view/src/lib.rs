//! The `rt-view` binary's commands, as a library so they can be tested
//! directly: [`cli`] parses the command line, [`render_cmd`] renders a scene
//! to PNG, [`cast_cmd`] answers ray queries, and [`png_out`] writes images
//! atomically.

pub mod cast_cmd;
pub mod cli;
pub mod png_out;
pub mod render_cmd;
