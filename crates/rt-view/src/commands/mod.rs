//! The headless commands, each in its own module with its own arguments.

pub mod accuracy;
pub mod accuracy_labels;
pub mod bench;
pub mod cast;
pub mod explain;
pub mod export;
pub mod merge;
pub mod prepare;
pub mod render;
pub mod render_outputs;
pub mod render_part;
