//! The headless commands, each in its own module with its own arguments.

pub mod accuracy;
pub mod bench;
pub mod cast;
pub mod export;
pub mod render;
pub mod render_outputs;
