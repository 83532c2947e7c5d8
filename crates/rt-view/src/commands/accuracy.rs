//! `rt-view accuracy`: what each step of accuracy costs in time.
//!
//! Two parts, each a table of (setting, time, error):
//! - **images**: samples per pixel (edges, soft shadows, ambient occlusion)
//!   and recursion depth (mirrors, glass), each against a converged reference
//!   render of the same scene, and the intersection methods on the showcase
//!   against the default methods' image. Error is the RMSE and the largest
//!   difference of the 8-bit pixel values (as in the PNG), scaled to [0, 1].
//!   On the Cornell box, global illumination's error against time also for
//!   the Sobol sampler, adaptive sampling (noise thresholds at up to 256
//!   spp) and OIDN denoising (where the library is found), beside the
//!   stratified sampler's, all against the same stratified reference.
//! - **geometry**: every intersection method on the fixed ray sets of
//!   [`rt_core::accuracy::hard_cases`]: nanoseconds per ray, wrong hits or misses, and
//!   the largest error of `t`.
//!
//! Times are medians of `--runs` runs. With `--with-f64 BIN` the geometry part
//! also runs in an f64 build of `rt-view` (as a child process) and its rows
//! are added. Writes `accuracy.csv`, `accuracy.md` (the README's tables) and
//! `accuracy.png` (error against time) to `--out`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use anyhow::{Context, bail};
use clap::Args;
use plotters::prelude::*;
use rt_core::accuracy::hard_cases::{CaseKind, all_cases};
use rt_core::geometry::method::{BoxMethod, Methods, SphereMethod, TriangleMethod};
use rt_core::render::adaptive::StoppingRule;
use rt_core::render::settings::AdaptiveSampling;
use rt_core::sampling::sampler::SamplerKind;
use rt_core::{Camera, RenderSettings, Renderer, SamplesPerPixel, Scene, load_scene};

use crate::commands::accuracy_labels;
use crate::commands::render_outputs::{Denoised, denoise_frame};

use crate::timing::median_time;

/// `rt-view accuracy`.
#[derive(Debug, Args)]
pub struct AccuracyArgs {
    /// Folder for accuracy.csv, accuracy.md and accuracy.png.
    #[arg(long, default_value = "accuracy-out")]
    pub out: PathBuf,
    /// Timed runs per measurement; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Smaller images and fewer samples (a quick run).
    #[arg(long)]
    pub quick: bool,
    /// An rt-view built with `--features f64`, whose geometry rows are added.
    #[arg(long, value_name = "RT_VIEW_F64")]
    pub with_f64: Option<PathBuf>,
    /// Only the geometry part, written as accuracy-f32.csv or accuracy-f64.csv
    /// (what --with-f64 runs in the other build).
    #[arg(long)]
    pub geometry_only: bool,
    /// Folder of the measured scene files.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Measure nothing: read the rows of an accuracy.csv written before and
    /// write accuracy.md and accuracy.png from them to --out.
    #[arg(long, value_name = "CSV")]
    pub replot: Option<PathBuf>,
}

/// The geometry's precision in this build.
const PRECISION: &str = if cfg!(feature = "f64") { "f64" } else { "f32" };

/// CSV header; one [`Row`] a line.
const HEADER: &str = "precision,part,experiment,setting,time_s,ns_per_ray,rmse,max_error,wrong,rays";

/// One measured setting.
#[derive(Clone, Debug, PartialEq)]
struct Row {
    precision: String,
    /// `image` or `geometry`.
    part: String,
    /// Scene or ray set.
    experiment: String,
    /// The knob's value, e.g. `spp=16` or `triangle=MollerTrumbore`.
    setting: String,
    /// Median time of one render or one pass over the ray set, seconds.
    time_s: f64,
    /// Geometry only: median time per ray, nanoseconds.
    ns_per_ray: Option<f64>,
    /// Images only: RMSE against the reference, in [0, 1].
    rmse: Option<f64>,
    /// Images: largest pixel difference; geometry: largest relative error of `t`.
    max_error: f64,
    /// Geometry only: rays with the wrong hit/miss answer.
    wrong: Option<usize>,
    /// Rays cast by one run.
    rays: u64,
}

impl Row {
    fn csv(&self) -> String {
        debug_assert!(!format!("{}{}", self.experiment, self.setting).contains(','), "{self:?}");
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
        format!(
            "{},{},{},{},{:e},{},{},{:e},{},{}",
            self.precision,
            self.part,
            self.experiment,
            self.setting,
            self.time_s,
            opt(self.ns_per_ray),
            opt(self.rmse),
            self.max_error,
            self.wrong.map_or(String::new(), |w| w.to_string()),
            self.rays
        )
    }

    fn parse(line: &str) -> anyhow::Result<Self> {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 10 {
            bail!("expected 10 fields, got {}", f.len());
        }
        let num = |s: &str| s.parse::<f64>().with_context(|| format!("bad number {s:?}"));
        let opt = |s: &str| if s.is_empty() { Ok(None) } else { num(s).map(Some) };
        Ok(Self {
            precision: f[0].into(),
            part: f[1].into(),
            experiment: f[2].into(),
            setting: f[3].into(),
            time_s: num(f[4])?,
            ns_per_ray: opt(f[5])?,
            rmse: opt(f[6])?,
            max_error: num(f[7])?,
            wrong: if f[8].is_empty() { None } else { Some(f[8].parse()?) },
            rays: f[9].parse()?,
        })
    }
}

/// Runs the measurements and writes the CSV, table and plot.
pub fn run(args: &AccuracyArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    if let Some(binary) = args.with_f64.as_ref().filter(|b| !b.is_file()) {
        bail!(
            "--with-f64 {}: no such file (build it with `cargo build --release -p rt-view --features f64 \
             --target-dir target/f64`)",
            binary.display()
        );
    }
    if let Some(csv) = &args.replot {
        let rows = read_csv(csv)?;
        std::fs::write(args.out.join("accuracy.md"), markdown(&rows)).context("cannot write accuracy.md")?;
        plot(&args.out.join("accuracy.png"), &rows)?;
        eprintln!("wrote accuracy.md and accuracy.png from {} to {}", csv.display(), args.out.display());
        return Ok(());
    }
    let runs = args.runs.max(1);
    let mut rows = geometry_rows(runs);
    if !args.geometry_only {
        rows.extend(image_rows(args, runs)?);
    }
    let own_csv = args.out.join(format!("accuracy-{PRECISION}.csv"));
    write_csv(&own_csv, &rows)?;
    if args.geometry_only {
        eprintln!("wrote {}", own_csv.display());
        return Ok(());
    }
    if let Some(binary) = &args.with_f64 {
        rows.extend(f64_rows(binary, &args.out, runs)?);
    }
    write_csv(&args.out.join("accuracy.csv"), &rows)?;
    let table = markdown(&rows);
    std::fs::write(args.out.join("accuracy.md"), &table).context("cannot write accuracy.md")?;
    plot(&args.out.join("accuracy.png"), &rows)?;
    println!("{table}");
    eprintln!("wrote accuracy.csv, accuracy.md and accuracy.png to {}", args.out.display());
    Ok(())
}

fn write_csv(path: &Path, rows: &[Row]) -> anyhow::Result<()> {
    let mut text = format!("{HEADER}\n");
    for row in rows {
        writeln!(text, "{}", row.csv())?;
    }
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// Runs `binary accuracy --geometry-only` (an f64 build) and reads its rows.
fn f64_rows(binary: &Path, out: &Path, runs: usize) -> anyhow::Result<Vec<Row>> {
    eprintln!("geometry with f64: {} ...", binary.display());
    let status = Command::new(binary)
        .args(["accuracy", "--geometry-only", "--runs", &runs.to_string(), "--out"])
        .arg(out)
        .status()
        .with_context(|| format!("cannot run {}", binary.display()))?;
    if !status.success() {
        bail!("{} accuracy --geometry-only failed ({status})", binary.display());
    }
    let path = out.join("accuracy-f64.csv");
    read_csv(&path).with_context(|| {
        format!("{} wrote no readable {} (is it an f64 build?)", binary.display(), path.display())
    })
}

/// The rows of an accuracy CSV ([`HEADER`] and one [`Row`] a line).
fn read_csv(path: &Path) -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    text.lines()
        .skip(1)
        .enumerate()
        .map(|(i, line)| Row::parse(line).with_context(|| format!("{}:{}", path.display(), i + 2)))
        .collect()
}

/// The methods worth comparing on a case: the default first, then the others
/// for the case's primitive kind.
fn methods_for(kind: CaseKind) -> Vec<(String, Methods)> {
    let d = Methods::default();
    match kind {
        CaseKind::Sphere => [SphereMethod::Careful, SphereMethod::Textbook]
            .map(|m| (format!("sphere={m:?}"), Methods { sphere: m, ..d }))
            .to_vec(),
        CaseKind::Triangle => {
            [TriangleMethod::Watertight, TriangleMethod::MollerTrumbore, TriangleMethod::AreaRatio]
                .map(|m| (format!("triangle={m:?}"), Methods { triangle: m, ..d }))
                .to_vec()
        }
        CaseKind::Box => [BoxMethod::Slab, BoxMethod::SixPlane]
            .map(|m| (format!("box={m:?}"), Methods { aabb: m, ..d }))
            .to_vec(),
    }
}

/// Each method on each hard case: time per ray, wrong answers, `t` error.
fn geometry_rows(runs: usize) -> Vec<Row> {
    /// Passes over the ray set per timed run (a pass takes about a millisecond).
    const PASSES: usize = 20;
    let mut rows = Vec::new();
    for case in all_cases() {
        eprintln!("geometry: {} ...", case.name);
        for (setting, methods) in methods_for(case.kind) {
            let score = case.score(methods);
            let time = median_time(runs, || {
                for _ in 0..PASSES {
                    std::hint::black_box(case.count_hits(std::hint::black_box(methods)));
                }
            }) / PASSES as u32;
            rows.push(Row {
                precision: PRECISION.into(),
                part: "geometry".into(),
                experiment: case.name.into(),
                setting,
                time_s: time.as_secs_f64(),
                ns_per_ray: Some(time.as_secs_f64() * 1e9 / case.rays() as f64),
                rmse: None,
                max_error: score.max_t_error,
                wrong: Some(score.wrong),
                rays: case.rays() as u64,
            });
        }
    }
    rows
}

/// One image sweep: a scene, the settings to try, and the reference setting.
struct Sweep {
    experiment: &'static str,
    scene: &'static str,
    settings: Vec<Setting>,
    reference: Setting,
    /// Samples per pixel of every render of the sweep (`None`: the scene's,
    /// or the setting's own).
    spp: Option<u32>,
    /// Whether the reference is a row of the sweep (not where it is another
    /// sweep's method: it would only repeat that sweep's last point).
    reference_row: bool,
}

#[derive(Clone, Copy, Debug)]
enum Setting {
    Spp(u32),
    Depth(u32),
    Methods(Methods),
    /// Global illumination's `max_bounces`.
    Bounces(u32),
    /// Global illumination with Russian roulette on or off, at a sample count.
    Roulette(bool, u32),
    /// Global illumination's `max_walk_steps` (subsurface random walks).
    WalkSteps(u32),
    /// The Sobol sampler at a sample count.
    Sobol(u32),
    /// Adaptive sampling to a noise threshold, at most a sample count
    /// (the default stopping rule, 16 samples at least).
    Adaptive(f32, u32),
    /// OIDN-denoised, at a sample count (the denoiser's time included).
    Denoised(u32),
}

impl Setting {
    fn label(&self) -> String {
        let d = Methods::default();
        match *self {
            Self::Spp(n) => format!("spp={n}"),
            Self::Depth(n) => format!("max_depth={n}"),
            Self::Methods(m) if m.triangle != d.triangle => format!("triangle={:?}", m.triangle),
            Self::Methods(m) if m.sphere != d.sphere => format!("sphere={:?}", m.sphere),
            Self::Methods(m) if m.aabb != d.aabb => format!("box={:?}", m.aabb),
            Self::Methods(_) => "default methods".into(),
            Self::Bounces(n) => format!("max_bounces={n}"),
            Self::Roulette(on, n) => format!("roulette={}/{n}spp", if on { "on" } else { "off" }),
            Self::WalkSteps(n) => format!("max_walk_steps={n}"),
            Self::Sobol(n) => format!("sobol spp={n}"),
            Self::Adaptive(t, n) => format!("threshold={t}/{n}spp"),
            Self::Denoised(n) => format!("denoised spp={n}"),
        }
    }
}

/// Renders every sweep's settings and references; one row per setting.
fn image_rows(args: &AccuracyArgs, runs: usize) -> anyhow::Result<Vec<Row>> {
    let (spps, reference_spp, size) =
        if args.quick { (vec![1, 4, 16], 64, (64, 36)) } else { (vec![1, 4, 16, 64, 256], 1024, (160, 90)) };
    let depths = [0, 1, 2, 3, 4, 6, 8];
    let spp_sweep = |experiment, scene| Sweep {
        experiment,
        scene,
        settings: spps.iter().map(|&n| Setting::Spp(n)).collect(),
        reference: Setting::Spp(reference_spp),
        spp: None,
        reference_row: true,
    };
    let depth_sweep = |experiment, scene| Sweep {
        experiment,
        scene,
        settings: depths.iter().map(|&n| Setting::Depth(n)).collect(),
        reference: Setting::Depth(rt_core::scene::effects::MAX_DEPTH),
        spp: None,
        reference_row: true,
    };
    // Global illumination on the Cornell box: noise against samples; bias
    // against the bounce limit (same samples, so the same random numbers for
    // the first bounces: the difference is what the later bounces add); and
    // Russian roulette, whose time saving and extra noise both show against
    // a many-sample reference without it.
    let gi_spp = if args.quick { 4 } else { 64 };
    let bounce_sweep = Sweep {
        experiment: "global illumination (bounces)",
        scene: "cornell_box.ron",
        settings: [0, 1, 2, 3, 4, 6, 8].iter().map(|&n| Setting::Bounces(n)).collect(),
        reference: Setting::Bounces(64),
        spp: Some(gi_spp),
        reference_row: true,
    };
    let roulette_sweep = Sweep {
        experiment: "global illumination (roulette)",
        scene: "cornell_box.ron",
        settings: vec![Setting::Roulette(true, gi_spp), Setting::Roulette(false, gi_spp)],
        reference: Setting::Roulette(false, reference_spp),
        spp: None,
        reference_row: true,
    };
    // Subsurface scattering (random walks through the translucent sphere and
    // box of subsurface.ron): noise against samples, and the bias of capping
    // the walks' length (same samples, as for the bounce limit).
    let walk_sweep = Sweep {
        experiment: "subsurface (walk cap)",
        scene: "subsurface.ron",
        settings: [1, 4, 16, 64, 256, 1024, 4096].iter().map(|&n| Setting::WalkSteps(n)).collect(),
        reference: Setting::WalkSteps(rt_core::scene::effects::MAX_WALK_STEPS),
        spp: Some(gi_spp),
        reference_row: true,
    };
    let d = Methods::default();
    let method_sweep = Sweep {
        experiment: "methods (showcase)",
        scene: "showcase.ron",
        settings: vec![
            Setting::Methods(Methods { triangle: TriangleMethod::MollerTrumbore, ..d }),
            Setting::Methods(Methods { triangle: TriangleMethod::AreaRatio, ..d }),
            Setting::Methods(Methods { sphere: SphereMethod::Textbook, ..d }),
            Setting::Methods(Methods { aabb: BoxMethod::SixPlane, ..d }),
        ],
        reference: Setting::Methods(d),
        spp: None,
        reference_row: true,
    };
    // The Cornell box's noise against time with each way of lowering it,
    // against the stratified sweep's reference: the Sobol sampler, adaptive
    // sampling (thresholds, at most 256 spp) and, where OIDN is found,
    // denoising (albedo and normal passes fed to it).
    let gi_sweep = |experiment, settings: Vec<Setting>| Sweep {
        experiment,
        scene: "cornell_box.ron",
        settings,
        reference: Setting::Spp(reference_spp),
        spp: None,
        reference_row: false,
    };
    let sobol_sweep =
        gi_sweep("global illumination (Sobol)", spps.iter().map(|&n| Setting::Sobol(n)).collect());
    let (adaptive_spp, thresholds) =
        if args.quick { (16, vec![0.2, 0.05]) } else { (256, vec![0.2, 0.1, 0.05, 0.02]) };
    let adaptive_sweep = gi_sweep(
        "global illumination (adaptive)",
        thresholds.into_iter().map(|t| Setting::Adaptive(t, adaptive_spp)).collect(),
    );
    let denoise_sweep = match crate::denoise::find_and_load() {
        Ok(_) => Some(gi_sweep(
            "global illumination (denoised)",
            spps.iter().filter(|&&n| n <= 64).map(|&n| Setting::Denoised(n)).collect(),
        )),
        Err(e) => {
            eprintln!("warning: no denoised rows: {e}");
            None
        }
    };
    let sweeps = [
        spp_sweep("edges (spp)", "antialiasing.ron"),
        spp_sweep("soft shadows (spp)", "soft_shadows.ron"),
        spp_sweep("ambient occlusion (spp)", "ao.ron"),
        depth_sweep("mirrors (depth)", "mirrors.ron"),
        depth_sweep("glass (depth)", "glass.ron"),
        method_sweep,
        spp_sweep("global illumination (spp)", "cornell_box.ron"),
        sobol_sweep,
        adaptive_sweep,
        bounce_sweep,
        roulette_sweep,
        spp_sweep("subsurface (spp)", "subsurface.ron"),
        walk_sweep,
    ];
    let mut rows = Vec::new();
    for sweep in sweeps.into_iter().chain(denoise_sweep) {
        let path = args.scenes.join(sweep.scene);
        let loaded = load_scene(&path).with_context(|| format!("cannot load {}", path.display()))?;
        eprintln!("images: {} ({}) ...", sweep.experiment, path.display());
        // The method sweep renders at the scene's own size: its differences are single pixels.
        let size = if sweep.experiment.starts_with("methods") && !args.quick {
            (loaded.settings.image.width(), loaded.settings.image.height())
        } else if sweep.experiment.starts_with("global") {
            if args.quick { (32, 32) } else { (128, 128) }
        } else if sweep.experiment.starts_with("subsurface") {
            if args.quick { (32, 24) } else { (160, 120) }
        } else {
            size
        };
        let settings = loaded.settings.overridden(Some(size.0), Some(size.1), sweep.spp)?;
        let mut renders = Vec::new();
        for &setting in &sweep.settings {
            renders.push((setting, render(&loaded.scene, loaded.camera, settings, setting, runs)?));
        }
        // The reference too (its error is 0 by definition), timed once: it is the slowest.
        let reference = render(&loaded.scene, loaded.camera, settings, sweep.reference, 1)?;
        if sweep.reference_row {
            renders.push((sweep.reference, reference.clone()));
        }
        for (setting, (image, time)) in renders {
            let (rmse, max_error) = image_error(&image.0, &reference.0.0);
            rows.push(Row {
                precision: PRECISION.into(),
                part: "image".into(),
                experiment: sweep.experiment.into(),
                setting: setting.label(),
                time_s: time.as_secs_f64(),
                ns_per_ray: None,
                rmse: Some(rmse),
                max_error,
                wrong: None,
                rays: image.1,
            });
        }
    }
    Ok(rows)
}

/// Pixels as 8-bit values, and the rays one render cast.
type Image = (Vec<[u8; 3]>, u64);

/// Renders `scene` through `camera` with `settings` and one setting
/// changed, `runs` times: the last image and the median time.
fn render(
    scene: &Scene,
    camera: Camera,
    mut settings: RenderSettings,
    setting: Setting,
    runs: usize,
) -> anyhow::Result<(Image, Duration)> {
    let mut other_methods = None;
    let gi = settings.effects.global_illumination.as_mut();
    match (setting, gi) {
        (Setting::Spp(n), _) => settings.samples = SamplesPerPixel::new(n)?,
        (Setting::Depth(n), _) => settings.effects.max_depth = n,
        (Setting::Methods(m), _) => other_methods = Some(scene.clone().with_methods(m)),
        (Setting::Bounces(n), Some(gi)) => gi.max_bounces = n,
        (Setting::Roulette(on, n), Some(gi)) => {
            gi.russian_roulette = on;
            settings.samples = SamplesPerPixel::new(n)?;
        }
        (Setting::WalkSteps(n), Some(gi)) => gi.max_walk_steps = n,
        (Setting::Sobol(n) | Setting::Adaptive(_, n) | Setting::Denoised(n), _) => {
            settings.samples = SamplesPerPixel::new(n)?;
            if let Setting::Sobol(_) = setting {
                settings = settings.with_sampler(SamplerKind::Sobol);
            }
        }
        (_, None) => bail!("{setting:?} needs a scene with global illumination"),
    }
    let renderer = Renderer::new(other_methods.as_ref().unwrap_or(scene), camera, &settings)?;
    let stop = AtomicBool::new(false);
    let mut frame = None;
    let mut failed = None;
    let time = median_time(runs, || {
        frame = match setting {
            Setting::Adaptive(threshold, _) => {
                AdaptiveSampling::new(threshold, AdaptiveSampling::DEFAULT_MIN_SAMPLES)
                    .ok()
                    .and_then(|a| renderer.render_adaptive_with(a, StoppingRule::LastPass, |_| {}, &stop))
                    .map(|a| a.frame)
            }
            Setting::Denoised(_) => {
                renderer.render_with_features_until(|_| {}, &stop).map(|(mut frame, features)| {
                    if let Denoised::Skipped(why) = denoise_frame(&mut frame, &features) {
                        failed = Some(why);
                    }
                    frame
                })
            }
            _ => Some(renderer.render(|_| {})),
        }
    });
    if let Some(why) = failed {
        bail!("{}: not denoised: {why}", setting.label());
    }
    let frame = frame.context("the render gave no image")?;
    Ok(((frame.to_rgb8(), frame.rays.total()), time))
}

/// RMSE and largest difference of two images' channel values, over 255.
fn image_error(image: &[[u8; 3]], reference: &[[u8; 3]]) -> (f64, f64) {
    let (mut sum, mut max) = (0.0, 0.0f64);
    for (p, q) in image.iter().zip(reference) {
        for c in 0..3 {
            let e = (f64::from(p[c]) - f64::from(q[c])).abs() / 255.0;
            sum += e * e;
            max = max.max(e);
        }
    }
    ((sum / (3 * image.len()) as f64).sqrt(), max)
}

/// The README's tables: images, then geometry (one line per case and method,
/// precisions side by side).
fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| image experiment | setting | time (s) | rays | RMSE | max error |\n|---|---|---:|---:|---:|---:|\n",
    );
    for r in rows.iter().filter(|r| r.part == "image") {
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {} | {:.4} | {:.3} |",
            r.experiment,
            r.setting,
            r.time_s,
            r.rays,
            r.rmse.unwrap_or(0.0),
            r.max_error
        );
    }
    s.push_str(
        "\n| ray set | method | precision | ns/ray | wrong (of rays) | max t error |\n|---|---|---|---:|---:|---:|\n",
    );
    let mut geometry: Vec<&Row> = rows.iter().filter(|r| r.part == "geometry").collect();
    // Case order, then method order, each method's f64 row right after its f32 row.
    let order = |r: &Row| rows.iter().position(|x| x.experiment == r.experiment).unwrap_or(0);
    let first = |r: &Row| rows.iter().position(|x| x.experiment == r.experiment && x.setting == r.setting);
    geometry.sort_by_key(|r| (order(r), first(r), r.precision.clone()));
    for r in geometry {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} | {} of {} | {:.1e} |",
            r.experiment,
            r.setting,
            r.precision,
            r.ns_per_ray.unwrap_or(0.0),
            r.wrong.unwrap_or(0),
            r.rays,
            r.max_error
        );
    }
    s
}

/// Errors this small are drawn on the plot's floor (log axes have no 0).
const FLOOR: f64 = 1e-4;

/// Two panels: image RMSE against render time (a line per sweep), and the
/// fraction of wrong geometry answers against time per ray (a point per
/// method and precision, over all ray sets of its primitive kind).
fn plot(path: &Path, rows: &[Row]) -> anyhow::Result<()> {
    rt_font()?;
    let (width, height) = (PLOT_SIZE.0, PLOT_SIZE.1);
    let mut buffer = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let (left, right) = root.split_horizontally(width * 11 / 20);
        // The images' legend has a column of its own, beside their chart,
        // so that it hides no point or label.
        let (images, legend) = left.split_horizontally(width * 11 / 20 - LEGEND_WIDTH);
        let experiments = plot_images(&images, rows)?;
        draw_legend(&legend, &experiments)?;
        plot_geometry(&right, rows)?;
        root.present()?;
    }
    let pixels: Vec<[u8; 3]> = buffer.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    crate::image_out::PendingImage::png(path)?.write_rgb8(width, height, &pixels)
}

/// The plot's size in pixels.
const PLOT_SIZE: (u32, u32) = (1600, 560);
/// The width of the images' legend column.
const LEGEND_WIDTH: u32 = 210;

/// The legend of the images' chart: each experiment's line colour and name,
/// one under the other, from the height of the chart's top.
fn draw_legend(area: &Area, experiments: &[(String, RGBAColor)]) -> anyhow::Result<()> {
    for (i, (name, color)) in experiments.iter().enumerate() {
        let y = 56 + 22 * i as i32;
        area.draw(&PathElement::new(vec![(4, y), (26, y)], color.stroke_width(2)))?;
        area.draw(&Text::new(name.as_str(), (32, y - 8), ("sans-serif", 14).into_font().color(&BLACK)))?;
    }
    Ok(())
}

/// Registers the font the plot's text uses (egui's Ubuntu Light, already
/// built into the viewer), so no system fonts are needed.
fn rt_font() -> anyhow::Result<()> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT)
        .map_err(|_| anyhow::anyhow!("the built-in plot font cannot be read"))
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi > 0.0) {
        return 1e-3..1.0;
    }
    (lo / 2.0)..(hi * 2.0)
}

/// The images' chart; returns each experiment's name and line colour, for
/// the legend.
fn plot_images(area: &Area, rows: &[Row]) -> anyhow::Result<Vec<(String, RGBAColor)>> {
    // The method sweep's differences are single pixels: they are in the table.
    let images: Vec<&Row> =
        rows.iter().filter(|r| r.part == "image" && !r.experiment.starts_with("methods")).collect();
    let mut chart = ChartBuilder::on(area)
        .caption("Images: error against render time", ("sans-serif", 24))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(
            log_range(images.iter().map(|r| r.time_s)).log_scale(),
            (FLOOR / 2.0..0.5f64).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("render time (s), median")
        .y_desc("RMSE vs reference (floor = exact)")
        .label_style(("sans-serif", 15))
        .draw()?;
    let mut experiments: Vec<&str> = images.iter().map(|r| r.experiment.as_str()).collect();
    experiments.dedup();
    let (mut labels, mut legend) = (Vec::new(), Vec::new());
    for (i, experiment) in experiments.into_iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let points: Vec<(f64, f64, &str)> = images
            .iter()
            .filter(|r| r.experiment == experiment)
            .map(|r| (r.time_s, r.rmse.unwrap_or(0.0).max(FLOOR), r.setting.as_str()))
            .collect();
        chart.draw_series(LineSeries::new(points.iter().map(|p| (p.0, p.1)), color.stroke_width(2)))?;
        legend.push((experiment.to_string(), color));
        chart.draw_series(points.iter().map(|&(x, y, _)| Circle::new((x, y), 3, color.filled())))?;
        labels.extend(
            points
                .iter()
                .map(|&(x, y, label)| ((x, y), label.split('=').nth(1).unwrap_or(label).to_string())),
        );
    }
    draw_labels(&mut chart, &labels, 12, area.get_pixel_range().0.end)?;
    Ok(legend)
}

fn plot_geometry(area: &Area, rows: &[Row]) -> anyhow::Result<()> {
    // (label, ns per ray (median over cases), wrong fraction)
    let mut points: Vec<(String, f64, f64)> = Vec::new();
    let geometry: Vec<&Row> = rows.iter().filter(|r| r.part == "geometry").collect();
    let mut keys: Vec<(String, String)> =
        geometry.iter().map(|r| (r.setting.clone(), r.precision.clone())).collect();
    keys.sort();
    keys.dedup();
    for (setting, precision) in keys {
        let mine: Vec<&&Row> =
            geometry.iter().filter(|r| r.setting == setting && r.precision == precision).collect();
        let mut ns: Vec<f64> = mine.iter().filter_map(|r| r.ns_per_ray).collect();
        ns.sort_by(f64::total_cmp);
        let wrong: usize = mine.iter().filter_map(|r| r.wrong).sum();
        let rays: u64 = mine.iter().map(|r| r.rays).sum();
        points.push((format!("{setting} {precision}"), ns[ns.len() / 2], wrong as f64 / rays.max(1) as f64));
    }
    let mut chart = ChartBuilder::on(area)
        .caption("Geometry: wrong answers against time per ray", ("sans-serif", 24))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(
            {
                // Room on the right for the labels.
                let range = log_range(points.iter().map(|p| p.1));
                range.start..range.end * 4.0
            }
            .log_scale(),
            (FLOOR / 2.0..1.0f64).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("ns per ray, median over the kind's ray sets")
        .y_desc("fraction of rays wrong (floor = none)")
        .label_style(("sans-serif", 15))
        .draw()?;
    chart.draw_series(points.iter().map(|(label, ns, wrong)| {
        let color = if label.contains("f64") { BLUE } else { RED };
        Circle::new((*ns, wrong.max(FLOOR)), 4, color.filled())
    }))?;
    let labels: Vec<((f64, f64), String)> =
        points.iter().map(|(label, ns, wrong)| ((*ns, wrong.max(FLOOR)), label.clone())).collect();
    draw_labels(&mut chart, &labels, 13, area.get_pixel_range().0.end)?;
    Ok(())
}

type LogChart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// Draws each text beside its point where [`accuracy_labels::place`] puts
/// it (right of the y axis, between the x axis and the top, left of
/// `right`, the end of the chart's own column; no label over another or
/// over a dot; each box padded so neighbours keep a gap),
/// with a grey leader line to labels pushed away from their points.
fn draw_labels(
    chart: &mut LogChart,
    labels: &[((f64, f64), String)],
    size: u32,
    right: i32,
) -> anyhow::Result<()> {
    let font = ("sans-serif", size).into_text_style(chart.plotting_area());
    let pixels: Vec<(i32, i32)> = labels.iter().map(|(p, _)| chart.backend_coord(p)).collect();
    let sizes = labels
        .iter()
        .map(|(_, text)| chart.plotting_area().estimate_text_size(text, &font).map(|(w, h)| (w + 8, h + 2)))
        .collect::<Result<Vec<_>, _>>()?;
    let (x, y) = chart.plotting_area().get_pixel_range();
    let placed = accuracy_labels::place(&pixels, &sizes, (x.start..right, y));
    let grey = RGBColor(150, 150, 150);
    chart.draw_series(labels.iter().zip(placed).map(|((p, text), l)| {
        let to = if l.leader { (l.offset.0, l.offset.1 + l.size.1 as i32 / 2) } else { (0, 0) };
        EmptyElement::at(*p)
            + PathElement::new(vec![(0, 0), to], grey)
            + Text::new(text.clone(), l.offset, font.clone())
    }))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip_through_csv() {
        let row = Row {
            precision: "f32".into(),
            part: "geometry".into(),
            experiment: "sphere from inside".into(),
            setting: "sphere=Textbook".into(),
            time_s: 1.5e-3,
            ns_per_ray: Some(12.25),
            rmse: None,
            max_error: 3e-7,
            wrong: Some(4),
            rays: 20000,
        };
        assert_eq!(Row::parse(&row.csv()).unwrap(), row);
        assert!(Row::parse("f32,geometry,x").is_err());
    }

    #[test]
    fn image_error_is_zero_for_equal_images_and_one_for_black_against_white() {
        let black = vec![[0u8; 3]; 4];
        let white = vec![[255u8; 3]; 4];
        assert_eq!(image_error(&black, &black), (0.0, 0.0));
        assert_eq!(image_error(&black, &white), (1.0, 1.0));
    }

    #[test]
    fn every_primitive_kind_compares_its_default_method_first_then_the_others() {
        for kind in [CaseKind::Sphere, CaseKind::Triangle, CaseKind::Box] {
            let methods = methods_for(kind);
            assert_eq!(methods[0].1, Methods::default());
            assert!(methods[1..].iter().all(|(_, m)| !m.is_default()));
        }
    }
}
