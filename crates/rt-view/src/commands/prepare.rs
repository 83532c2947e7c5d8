//! `rt-view prepare SCENE -o SCENE.rtc`: the scene loaded and built once
//! and written as a scene cache ([`crate::scene_cache`]), which every
//! command that takes a SCENE reads in a fraction of the load time.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

/// `rt-view prepare`.
#[derive(Debug, Args)]
pub struct PrepareArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// The cache to write (conventionally SCENE.rtc), atomically.
    #[arg(short, long, value_name = "OUT.rtc")]
    pub output: PathBuf,
}

/// Runs `prepare`, saying on stderr what was written.
pub fn run(args: &PrepareArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let bytes = crate::scene_cache::prepare(&args.scene, &args.output)?;
    eprintln!(
        "{}: {:.1} MB, prepared from {} in {:.2} s",
        args.output.display(),
        bytes as f64 / 1e6,
        args.scene.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
