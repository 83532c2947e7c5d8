//! The `rt-view` binary's commands, as a library so they can be tested
//! directly: [`cli`] parses the command line, [`render_cmd`] renders a scene
//! to PNG, [`cast_cmd`] answers ray queries, [`bench_cmd`] and [`accuracy_cmd`]
//! measure speed and what accuracy costs, [`image_out`] writes images
//! atomically, and [`viewer`] is the interactive window, built from
//! [`render_job`] (background rows), [`canvas`] (rows → texture),
//! [`camera_controls`] (sliders, orbit, pan, zoom) and [`scene_watch`].

pub mod accuracy_cmd;
pub mod bench_cmd;
pub mod camera_controls;
pub mod canvas;
pub mod cast_cmd;
pub mod cli;
pub mod image_out;
pub mod render_cmd;
pub mod render_job;
pub mod scene_watch;
pub mod viewer;
