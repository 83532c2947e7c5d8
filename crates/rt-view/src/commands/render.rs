//! `rt-view render SCENE -o OUT.png|OUT.exr`: a headless render with a progress bar.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rt_core::Renderer;
use rt_core::render::adaptive::{self, AdaptiveFrame, AdaptiveStats};
use rt_core::render::settings::AdaptiveSampling;
use rt_core::render::view_transform::{Display, MAX_EXPOSURE_STOPS, ViewTransform};
use rt_core::sampling::sampler::SamplerKind;
use rt_core::scene::effects::{EffectPlan, RayCounts};

use crate::commands::render_outputs::{self, Denoised, Pass};
use crate::commands::render_part::{self, PartOf};
use crate::image_out::{Format, PendingImage};
use crate::sum_render;

/// `rt-view render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// Output file: .png, or .exr for linear HDR.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: PathBuf,
    /// Image width in pixels (default: the scene's).
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,
    /// Image height in pixels (default: the scene's).
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,
    /// Samples per pixel, for anti-aliasing (default: the scene's, else 1).
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    /// Seed of the random numbers: renders with different seeds are
    /// independent estimates of the same image (0 is the default image).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Where the samples go: `stratified` (jittered strata, independent
    /// random numbers along the path) or `sobol` (Owen-scrambled Sobol
    /// points in every dimension of the path: less noise at the same
    /// samples) (default: the scene's `sampler`, else stratified).
    #[arg(long, value_name = "stratified|sobol")]
    pub sampler: Option<SamplerKind>,
    /// Adaptive sampling: a pixel stops taking samples once its relative
    /// noise estimate is below T (e.g. 0.01; --spp is then the most a pixel
    /// takes; 0 turns off the scene's `adaptive_sampling`) (default: the
    /// scene's, else off).
    #[arg(long, value_name = "T")]
    pub noise_threshold: Option<f32>,
    /// Adaptive sampling: the samples every pixel takes before its noise is
    /// first estimated, rounded up to 1, 4, 16, 64, 256, 1024 or a multiple
    /// of 1024 (default: the scene's, else 16).
    #[arg(long, value_name = "N")]
    pub min_samples: Option<u32>,
    /// Print to stderr: scene load and BVH build times, the effects
    /// simulated, the rays cast by kind (primary, shadow, reflection,
    /// refraction, ambient occlusion, and under global illumination bounce
    /// and next-event rays), tracing time and Mrays/s (all rays).
    #[arg(long)]
    pub stats: bool,
    /// Exposure of the PNG in stops, each +1 doubling the light (default:
    /// the scene's `exposure`, else 0). Not applied to EXR, which stays
    /// linear scene radiance.
    #[arg(long, value_name = "STOPS", allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// View transform of the PNG: `standard` (clamp, then the scene's
    /// colour space) or `agx` (rolls highlights off; sRGB) (default: the
    /// scene's `view_transform`, else standard). Not applied to EXR.
    #[arg(long, value_name = "standard|agx")]
    pub view_transform: Option<ViewTransform>,
    /// Render only part K of N (K from 0 to N-1) into a part file OUT.rtpart,
    /// for `rt-view merge`: sample indices [K·S/N, (K+1)·S/N) of every
    /// pixel by default, or with --tiles rows [K·H/N, (K+1)·H/N).
    #[arg(long, value_name = "K/N", value_parser = PartOf::parse)]
    pub part: Option<PartOf>,
    /// With --part: split the image into N bands of rows (tiles), each with
    /// every sample, instead of splitting the samples.
    #[arg(long, requires = "part")]
    pub tiles: bool,
    /// Feature passes to write as layers of the EXR output (comma-separated):
    /// albedo and normal of the first non-specular hit (through mirrors and
    /// clear glass), depth (distance from the camera to the first hit) and
    /// id (index of the first object hit); see docs/denoising.md. Needs
    /// `-o OUT.exr`.
    #[arg(long, value_delimiter = ',', value_name = "albedo,normal,depth,id")]
    pub passes: Vec<Pass>,
    /// Every feature pass (`--passes albedo,normal,depth,id`).
    #[arg(long)]
    pub aovs: bool,
    /// Denoise the image with Intel Open Image Denoise, fed the albedo and
    /// normal passes (`scripts/get_oidn.sh` fetches the library). Without
    /// the library: a warning saying where it was looked for, and the image
    /// as rendered. An EXR keeps the noisy colour as `noisy.R/G/B`.
    #[arg(long)]
    pub denoise: bool,
}

impl RenderArgs {
    /// The passes asked for, each once, in a fixed order.
    pub fn passes(&self) -> Vec<Pass> {
        let mut passes = if self.aovs { Pass::ALL.to_vec() } else { self.passes.clone() };
        passes.sort();
        passes.dedup();
        passes
    }
}

/// The display settings of `settings`, with the command line's `exposure`
/// and `view_transform` where given, or why the exposure is refused.
pub fn display_of(
    settings: Display,
    exposure: Option<f32>,
    view_transform: Option<ViewTransform>,
) -> anyhow::Result<Display> {
    let exposure = exposure.unwrap_or(settings.exposure);
    if exposure.is_nan() || exposure.abs() > MAX_EXPOSURE_STOPS {
        anyhow::bail!(
            "--exposure must be -{MAX_EXPOSURE_STOPS} to {MAX_EXPOSURE_STOPS} stops, got {exposure}"
        );
    }
    Ok(Display { exposure, view_transform: view_transform.unwrap_or(settings.view_transform) })
}

/// The render was stopped by Ctrl-C (SIGINT); nothing was written. `main`
/// exits with status 130, as shells expect after SIGINT.
#[derive(Debug, thiserror::Error)]
#[error("interrupted: nothing was written")]
pub struct Interrupted;

/// Loads the scene, renders it in parallel (one progress tick per finished
/// row) and writes the PNG (or linear EXR) atomically. Nothing is written on any error or on
/// Ctrl-C, which stops the workers after their current band of rows.
///
/// Each pixel is the mean of the exact sum of its samples
/// ([`crate::exact_sum`]), so that parts of the render made on other
/// machines (`--part`, [`render_part`]) merge into this very image.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    // A part file or an image, its name checked before any work.
    let (part, output) = match args.part {
        Some(part) => (Some(render_part::PendingPart::create(&args.output, part.split(args.tiles))?), None),
        None => (None, Some(PendingImage::create(&args.output)?)),
    };
    let passes = args.passes();
    // Denoising needs the library: without it the image is rendered (and
    // written) exactly as without `--denoise`, after a warning.
    let denoise = args.denoise
        && match crate::denoise::find_and_load() {
            Ok(_) => true,
            Err(e) => {
                eprintln!("warning: not denoised: {e}");
                false
            }
        };
    let with_features = !passes.is_empty() || denoise;
    if with_features && part.is_some() {
        anyhow::bail!(
            "{}: feature passes and denoising (--passes, --aovs, --denoise) are not made for parts: merge the parts, then denoise",
            args.output.display()
        );
    }
    if !passes.is_empty() && output.as_ref().is_some_and(|o| o.format() != Format::Exr) {
        anyhow::bail!(
            "{}: feature passes (--passes, --aovs) are written to an .exr output only",
            args.output.display()
        );
    }
    let load_start = Instant::now();
    let loaded = crate::scene_cache::load_scene(&args.scene)?;
    let load_time = load_start.elapsed();
    let scene = &loaded.scene;
    for warning in scene.warnings() {
        eprintln!("warning: {}: {warning}", args.scene.display());
    }
    let settings = loaded
        .settings
        .overridden(args.width, args.height, args.spp)
        .with_context(|| format!("{}: cannot render", args.scene.display()))?
        .with_seed(args.seed);
    let settings = settings
        .with_sampler(args.sampler.unwrap_or(settings.sampler))
        .with_adaptive(args.noise_threshold, args.min_samples)
        .with_context(|| format!("{}: cannot render", args.scene.display()))?;
    let display = display_of(settings.display, args.exposure, args.view_transform)?;
    let (width, height, spp) = (settings.image.width(), settings.image.height(), settings.samples.get());
    let renderer = Renderer::new(scene, loaded.camera, &settings)
        .with_context(|| format!("{}: cannot render", args.scene.display()))?;
    if let Some(part) = part {
        if settings.adaptive.is_some() {
            anyhow::bail!(
                "{}: adaptive sampling (a noise threshold) cannot be split into parts: each pixel's \
                 stopping point depends on all its samples; render the parts without it",
                args.scene.display()
            );
        }
        let written = part.render(&args.scene, scene, &renderer, &settings, display, load_start)?;
        return if written { Ok(()) } else { Err(Interrupted.into()) };
    }
    let output = output.expect("an image where there is no part");

    let stop = Arc::new(AtomicBool::new(false));
    let handler_stop = stop.clone();
    // Only fails if a handler is already set (not in this program) or the OS refuses.
    let _ = ctrlc::set_handler(move || handler_stop.store(true, Ordering::Relaxed));

    let pass_count = settings.adaptive.map_or(1, |a| adaptive::passes(a.min_samples(), spp).len() as u64);
    let bar = ProgressBar::new(height as u64 * pass_count).with_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, {elapsed} (ETA {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(format!("rendering {width}x{height}, {spp} spp"));
    let start = Instant::now();
    let (frame, adaptive, features) = match settings.adaptive {
        None if with_features => {
            let rendered = sum_render::render_means_with_features(&renderer, |_| bar.inc(1), &stop);
            let (frame, features) = rendered
                .map(|(pixels, features, rays)| {
                    let frame =
                        rt_core::Frame { width, height, pixels, color_space: settings.color_space, rays };
                    (frame, Some(features))
                })
                .unzip();
            (frame, None, features.flatten())
        }
        None => {
            let means = sum_render::render_means(&renderer, |_| bar.inc(1), &stop);
            let frame = means.map(|(pixels, rays)| rt_core::Frame {
                width,
                height,
                pixels,
                color_space: settings.color_space,
                rays,
            });
            (frame, None, None)
        }
        Some(a) => match renderer.render_adaptive(a, |_| bar.inc(1), &stop) {
            Some(AdaptiveFrame { frame, stats, .. }) => (Some(frame), Some((a, stats)), None),
            None => (None, None, None),
        },
    };
    let elapsed = start.elapsed();
    bar.finish_and_clear();
    let mut frame = frame.ok_or(Interrupted)?;

    let mut noisy = None;
    if denoise && let Some(features) = &features {
        match render_outputs::denoise_frame(&mut frame, features) {
            Denoised::Done { took, noisy: n } => {
                eprintln!("denoised with OIDN in {:.3} s", took.as_secs_f64());
                noisy = Some(n);
            }
            Denoised::Skipped(why) => eprintln!("warning: not denoised: {why}"),
        }
    }
    if output.format() == Format::Exr && (noisy.is_some() || !passes.is_empty()) {
        let channels = render_outputs::exr_channels(&frame, noisy.as_deref(), features.as_ref(), &passes);
        output.write_channels(width, height, channels)?;
    } else {
        output.write_frame(&frame, &display)?;
    }
    eprintln!(
        "wrote {} ({width}x{height}, {spp} spp) in {:.3} s",
        args.output.display(),
        elapsed.as_secs_f64()
    );
    if args.stats {
        let bvh = scene.bvh_stats();
        let build = bvh.build_time.as_secs_f64();
        eprintln!("scene load: {:.3} s (of which BVH build {build:.3} s)", load_time.as_secs_f64());
        if bvh.build_steps != rt_core::bvh::BuildSteps::default() {
            // Built here, not read back from a scene cache.
            eprintln!("BVH build steps: {}", bvh.build_steps);
        }
        eprintln!(
            "BVH: {} primitives, {} nodes ({}-wide), depth {}, {:.1} KiB ({:.1} bytes per primitive)",
            bvh.primitives,
            bvh.nodes,
            bvh.width,
            bvh.depth,
            bvh.bytes as f64 / 1024.0,
            bvh.bytes as f64 / bvh.primitives.max(1) as f64
        );
        if let Some(line) = describe_geometry(scene) {
            eprintln!("{line}");
        }
        eprintln!("effects: {}", describe_plan(renderer.plan()));
        if renderer.plan().global_illumination.is_some() && scene.light_sampler().is_empty() {
            eprintln!(
                "note: nothing gives off light (no lights, no emissive objects, black background): the image is black"
            );
        }
        if let Some((a, stats)) = adaptive {
            eprintln!("{}", describe_adaptive(a, &stats));
        }
        eprintln!("rays: {}", describe_counts(&frame.rays));
        eprintln!(
            "tracing: {:.3} s, {} rays, {:.3} Mrays/s on {} threads",
            elapsed.as_secs_f64(),
            frame.rays.total(),
            frame.rays.total() as f64 / elapsed.as_secs_f64() / 1e6,
            rayon::current_num_threads()
        );
    }
    Ok(())
}

/// The meshes' size for `--stats`: triangles, bytes (positions, indices,
/// normals and vertex attributes) per triangle, and the textures; `None`
/// when the scene has no mesh.
pub fn describe_geometry(scene: &rt_core::Scene) -> Option<String> {
    let meshes: Vec<&rt_core::geometry::mesh::Mesh> = scene
        .objects()
        .iter()
        .filter_map(|o| match &o.primitive {
            rt_core::Primitive::Mesh(m) => Some(m),
            _ => None,
        })
        .collect();
    if meshes.is_empty() {
        return None;
    }
    let triangles: usize = meshes.iter().map(|m| m.triangle_count()).sum();
    let bytes: usize = meshes.iter().map(|m| m.memory_bytes()).sum();
    let smooth = meshes.iter().filter(|m| m.has_vertex_normals()).count();
    let textured = meshes.iter().filter(|m| m.has_uvs()).count();
    let (count, texels) = scene.texture_stats();
    Some(format!(
        "meshes: {} ({smooth} with vertex normals, {textured} with texture coordinates), {triangles} triangles, \
         {:.1} MiB ({:.1} bytes per triangle); textures: {count}, {:.1} MiB",
        meshes.len(),
        bytes as f64 / (1 << 20) as f64,
        bytes as f64 / triangles.max(1) as f64,
        texels as f64 / (1 << 20) as f64,
    ))
}

/// The plan in words: "shading, shadows, …" or "none (pure ray casting)".
pub fn describe_plan(plan: &EffectPlan) -> String {
    if !plan.shading {
        return "none (no lights: pure ray casting, flat colours)".into();
    }
    if let Some(gi) = plan.global_illumination {
        let roulette = if gi.russian_roulette { ", Russian roulette" } else { "" };
        let subsurface = if plan.subsurface {
            format!(", subsurface random walks of at most {} steps", gi.max_walk_steps)
        } else {
            String::new()
        };
        return format!(
            "global illumination (path tracing, at most {} bounces{roulette}{subsurface})",
            gi.max_bounces
        );
    }
    let mut on = vec!["shading".to_owned()];
    if plan.shadows {
        on.push("shadows".into());
    }
    if plan.reflection {
        on.push("reflection".into());
    }
    if plan.refraction {
        on.push("refraction".into());
    }
    if plan.reflection || plan.refraction {
        on.push(format!("max depth {}", plan.max_depth));
    }
    if let Some(ao) = plan.ambient_occlusion {
        on.push(format!("ambient occlusion ({} samples, radius {})", ao.samples, ao.radius));
    }
    on.join(", ")
}

/// Adaptive sampling's line of `--stats`: samples taken against the full
/// count, the share saved, the pixels that stopped early.
pub fn describe_adaptive(a: AdaptiveSampling, stats: &AdaptiveStats) -> String {
    format!(
        "adaptive sampling (noise threshold {}, at least {} samples, {} passes): {} of {} samples taken \
         ({:.1} % saved), {} pixels converged early",
        a.threshold(),
        a.min_samples(),
        stats.passes,
        stats.taken,
        stats.full,
        100.0 * stats.saved(),
        stats.converged
    )
}

/// The ray counts by kind: "primary 345600, shadow 0, …".
pub fn describe_counts(c: &RayCounts) -> String {
    format!(
        "primary {}, shadow {}, reflection {}, refraction {}, ambient occlusion {}, bounce {}, next event {}, \
         subsurface {} (walk steps {})",
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction,
        c.ambient_occlusion,
        c.bounce,
        c.next_event,
        c.subsurface,
        c.walk_steps
    )
}
