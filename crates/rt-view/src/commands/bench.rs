//! `rt-view bench`: BVH build, primary-ray throughput and memory on generated
//! meshes of about 10k, 100k and 1M triangles, and a full render of the
//! showcase scene. Every figure is the median of `--runs` timed runs.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use rt_core::mesh::Mesh;
use rt_core::{Camera, Color, Material, Primitive, Projection, Real, Renderer, Scene, SceneBuilder, Vec3};

use crate::timing::median;

/// `rt-view bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Folder for the generated OBJ files, cameras and bench.csv.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Timed runs per measurement; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Thread counts to measure throughput with, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2])]
    pub threads: Vec<usize>,
    /// Only the 10k and 100k meshes (a quick run).
    #[arg(long)]
    pub quick: bool,
    /// Scene whose full render is timed too.
    #[arg(long, default_value = "scenes/showcase.ron")]
    pub showcase: PathBuf,
}

/// Image size of the throughput measurement.
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 960;

/// One generated mesh's results.
struct MeshResult {
    label: &'static str,
    triangles: usize,
    build: Duration,
    bytes_per_triangle: f64,
    /// (threads, Mrays/s) pairs.
    mrays: Vec<(usize, f64)>,
    hits: usize,
    peak_rss_mib: Option<f64>,
    /// Median time of the full render pipeline over median time of bare
    /// `Scene::cast` calls for the same pixels, one thread each.
    render_over_cast: f64,
}

/// Runs the benchmark and prints a table; writes meshes and bench.csv to `--out`.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let runs = args.runs.max(1);
    let sizes: &[(&str, u32)] =
        if args.quick { &[("10k", 71), ("100k", 224)] } else { &[("10k", 71), ("100k", 224), ("1m", 708)] };
    let camera =
        Camera::new(Vec3::new(0.0, 6.0, -9.0), Vec3::ZERO, Vec3::Y, 50.0, 1.0, Projection::Perspective)?;
    let mut results = Vec::new();
    for &(label, n) in sizes {
        eprintln!("terrain {label}: generating {}x{n} quads ...", n);
        let (positions, triangles) = terrain(n);
        write_obj(&args.out.join(format!("terrain_{label}.obj")), &positions, &triangles)?;
        write_camera(&args.out.join(format!("terrain_{label}.json")), &camera)?;
        let mesh = Mesh::new(positions, triangles).context("generated mesh")?;
        let mesh_bytes = mesh.memory_bytes();
        let scene_of = |mesh: Mesh| {
            SceneBuilder::new(camera)
                .image_size(WIDTH, HEIGHT)
                .background(Color::ONE)
                .material("ground", Material::flat(Color::new(0.4, 0.6, 0.3)))
                .object(Primitive::Mesh(mesh), "ground")
                .build()
        };
        let mut builds = Vec::new();
        for _ in 0..runs {
            builds.push(scene_of(mesh.clone())?.bvh_stats().build_time);
        }
        let scene = scene_of(mesh)?;
        let stats = scene.bvh_stats();
        let renderer = Renderer::new(&scene, WIDTH, HEIGHT, 1)?;
        let rays = WIDTH as f64 * HEIGHT as f64;
        let mut mrays = Vec::new();
        for &threads in &args.threads {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
            let times: Vec<Duration> = (0..runs)
                .map(|_| {
                    let start = Instant::now();
                    pool.install(|| renderer.render(|_| {}));
                    start.elapsed()
                })
                .collect();
            mrays.push((threads, rays / median(times).as_secs_f64() / 1e6));
        }
        let render_over_cast = render_over_cast(&scene, &renderer, runs)?;
        let hits = (0..HEIGHT)
            .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
            .filter(|&(x, y)| scene.cast(&renderer.view_plane().center_ray(x, y)).is_some())
            .count();
        results.push(MeshResult {
            label,
            triangles: stats.primitives,
            build: median(builds),
            bytes_per_triangle: (stats.bytes + mesh_bytes) as f64 / stats.primitives as f64,
            mrays,
            hits,
            peak_rss_mib: peak_rss_mib(),
            render_over_cast,
        });
    }
    let showcase = time_scene(&args.showcase, runs)?;
    report(args, &results, showcase)
}

/// How much the renderer (effect plan, samples, ray counts, colours) costs
/// over pure ray casting for a scene without lights: the median time of
/// `Renderer::render` over the median time of a loop of `Scene::cast` calls
/// through the same pixel centres that stores the same flat colours. Runs
/// alternate, on one thread, so drift on a shared machine hits both alike.
fn render_over_cast(scene: &Scene, renderer: &Renderer, runs: usize) -> anyhow::Result<f64> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let view = renderer.view_plane();
    let cast_all = || {
        let mut pixels = Vec::with_capacity((WIDTH * HEIGHT) as usize);
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                pixels.push(match scene.cast(&view.center_ray(x, y)) {
                    Some(hit) => scene.hit_color(&hit),
                    None => scene.background,
                });
            }
        }
        pixels
    };
    let (mut rendered, mut cast) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let start = Instant::now();
        let frame = pool.install(|| renderer.render(|_| {}));
        rendered.push(start.elapsed());
        let start = Instant::now();
        let pixels = cast_all();
        cast.push(start.elapsed());
        anyhow::ensure!(frame.pixels == pixels, "the renderer and pure casting disagree");
    }
    Ok(median(rendered).as_secs_f64() / median(cast).as_secs_f64())
}

/// Median of the showcase's full render time (its own size and spp), if it exists.
fn time_scene(path: &Path, runs: usize) -> anyhow::Result<Option<(Duration, u32, u32)>> {
    if !path.exists() {
        return Ok(None);
    }
    let scene = rt_core::load_scene(path)?;
    let renderer = Renderer::new(&scene, scene.width, scene.height, scene.samples_per_pixel)?;
    let times = (0..runs)
        .map(|_| {
            let start = Instant::now();
            renderer.render(|_| {});
            start.elapsed()
        })
        .collect();
    Ok(Some((median(times), scene.width, scene.height)))
}

fn report(
    args: &BenchArgs,
    results: &[MeshResult],
    showcase: Option<(Duration, u32, u32)>,
) -> anyhow::Result<()> {
    const COLUMNS: [(&str, &str, usize); 8] = [
        ("mesh", "mesh", 6),
        ("triangles", "triangles", 10),
        ("build s", "bvh_build_s", 10),
        ("B/tri", "bytes_per_triangle", 10),
        ("threads", "threads", 8),
        ("Mrays/s", "mrays_per_s", 11),
        ("hits", "hits", 9),
        ("peak MiB", "peak_rss_mib", 9),
    ];
    let row = |fields: &[String]| {
        fields.iter().zip(COLUMNS).map(|(f, (_, _, w))| format!("{f:>w$}")).collect::<Vec<_>>().join(" ")
    };
    let mut csv = COLUMNS.map(|c| c.1).join(",") + "\n";
    println!("primary rays {WIDTH}x{HEIGHT}, medians of {} runs", args.runs.max(1));
    println!("{}", row(&COLUMNS.map(|c| c.0.to_owned())));
    for r in results {
        for &(threads, m) in &r.mrays {
            let fields = [
                r.label.to_owned(),
                r.triangles.to_string(),
                format!("{:.4}", r.build.as_secs_f64()),
                format!("{:.1}", r.bytes_per_triangle),
                threads.to_string(),
                format!("{m:.3}"),
                r.hits.to_string(),
                r.peak_rss_mib.map_or(String::from("-"), |v| format!("{v:.0}")),
            ];
            println!("{}", row(&fields));
            csv += &(fields.join(",") + "\n");
        }
    }
    if let (Some(first), Some(last)) = (results.first(), results.last())
        && let (Some(&(t, a)), Some(&(_, b))) = (first.mrays.first(), last.mrays.first())
    {
        println!(
            "time per ray, {} vs {} triangles ({t} thread(s)): {:.2}x",
            last.triangles,
            first.triangles,
            a / b
        );
    }
    let ratios: Vec<String> =
        results.iter().map(|r| format!("{:.3}x ({})", r.render_over_cast, r.label)).collect();
    println!("no-effects render / pure ray casting, 1 thread: {}", ratios.join(", "));
    if let Some((time, w, h)) = showcase {
        println!("{}: {w}x{h} full render {:.4} s", args.showcase.display(), time.as_secs_f64());
    }
    let path = args.out.join("bench.csv");
    std::fs::write(&path, csv).with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("wrote {} and the meshes to {}", path.display(), args.out.display());
    Ok(())
}

/// A noisy terrain over [−5, 5]² of n×n quads (2n² triangles): two sine
/// waves plus a small hashed jitter, so the BVH sees an uneven surface.
/// Triangles are wound so that their normals point up (+y).
pub fn terrain(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (-5.0 + 10.0 * i as f64 / n as f64, -5.0 + 10.0 * j as f64 / n as f64);
            let jitter = (hash(i, j) >> 40) as f64 / (1u64 << 24) as f64;
            let y =
                0.6 * (1.3 * x).sin() * (0.9 * z).cos() + 0.25 * (4.1 * x + 2.3 * z).sin() + 0.02 * jitter;
            positions.push(Vec3::new(x as Real, y as Real, z as Real));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let triangles = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                [[at(i, j), at(i + 1, j + 1), at(i + 1, j)], [at(i, j), at(i, j + 1), at(i + 1, j + 1)]]
            })
        })
        .collect();
    (positions, triangles)
}

fn hash(i: u32, j: u32) -> u64 {
    let mut z = ((i as u64) << 32 | j as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn write_obj(path: &Path, positions: &[Vec3], triangles: &[[u32; 3]]) -> anyhow::Result<()> {
    let mut text = String::with_capacity(positions.len() * 32 + triangles.len() * 24);
    for p in positions {
        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
    }
    for [a, b, c] in triangles {
        let _ = writeln!(text, "f {} {} {}", a + 1, b + 1, c + 1);
    }
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// The camera and image size as JSON, for `bench/embree_primary.py`.
fn write_camera(path: &Path, c: &Camera) -> anyhow::Result<()> {
    let v = |v: Vec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
    let json = format!(
        "{{\"position\": {}, \"center_of_interest\": {}, \"up\": {}, \"fov_y\": {}, \"near\": {}, \"width\": {WIDTH}, \"height\": {HEIGHT}}}\n",
        v(c.position()),
        v(c.center_of_interest()),
        v(c.up()),
        c.fov_y(),
        c.near()
    );
    std::fs::write(path, json).with_context(|| format!("cannot write {}", path.display()))
}

/// The process's peak resident memory (Linux `VmHWM`), in MiB.
fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terrain_has_two_triangles_per_quad_all_valid_and_is_reproducible() {
        let (positions, triangles) = terrain(10);
        assert_eq!((positions.len(), triangles.len()), (121, 200));
        let mesh = Mesh::new(positions.clone(), triangles.clone()).unwrap();
        assert!((0..200).all(|i| mesh.normal(i) != Vec3::ZERO), "degenerate triangle");
        // Wound so that normals face up (+y), towards the bench camera.
        assert!((0..200).all(|i| mesh.normal(i).y > 0.0));
        assert_eq!(terrain(10), (positions, triangles));
    }

    #[test]
    fn written_obj_files_load_back_to_the_same_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.obj");
        let (positions, triangles) = terrain(6);
        write_obj(&path, &positions, &triangles).unwrap();
        let loaded = Mesh::load_obj(&path, 1.0, Vec3::ZERO).unwrap();
        let original = Mesh::new(positions, triangles).unwrap();
        // tobj numbers vertices by first use: compare the triangles' corners.
        assert_eq!(loaded.triangle_count(), original.triangle_count());
        for i in 0..original.triangle_count() {
            assert_eq!(loaded.triangle(i), original.triangle(i), "triangle {i}");
        }
    }
}
