//! `rt-view bench`: BVH build, ray throughput and memory on generated meshes
//! of about 10k, 100k and 1M triangles, and a full render of the showcase
//! scene. Every figure is the median of `--runs` timed runs.
//!
//! Three sets of rays per mesh, at 1280×960: the renderer's primary rays (cast
//! as packets, [`Scene::cast_all`]), the same rays one at a time
//! ([`Scene::cast`], what Embree's `rtcIntersect1` does), and incoherent
//! rays: from each primary hit, one cosine-distributed diffuse bounce with a
//! fixed seed, as the path tracer spawns it. The meshes, the camera and the
//! bounce rays are written out, so `bench/embree_primary.py` casts the very
//! same rays with Intel Embree.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use rayon::prelude::*;
use rt_core::bvh::BuildSteps;
use rt_core::geometry::mesh::Mesh;
use rt_core::math::real::to_f32;
use rt_core::sampling::sampler::{SampleRng, cosine_hemisphere};
use rt_core::{
    Camera, Color, ImageSize, Interval, Material, Primitive, Projection, Ray, Real, RenderSettings, Renderer,
    Scene, SceneBuilder, Vec3,
};

use crate::timing::median;

/// `rt-view bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Folder for the generated meshes, cameras, bounce rays and bench.csv.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Timed runs per measurement; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Thread counts to measure builds and throughput with, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2])]
    pub threads: Vec<usize>,
    /// Only the 10k and 100k meshes (a quick run).
    #[arg(long)]
    pub quick: bool,
    /// Only the BVH builds and their SAH cost (no rays, no showcase): for
    /// profiling and comparing builds.
    #[arg(long)]
    pub build_only: bool,
    /// Scene whose full render is timed too.
    #[arg(long, default_value = "scenes/showcase.ron")]
    pub showcase: PathBuf,
}

/// Image size of the throughput measurement.
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 960;
/// Seed of the bounce rays' random numbers.
const BOUNCE_SEED: u64 = 1;

/// One mesh's results at one thread count.
struct Row {
    label: &'static str,
    triangles: usize,
    threads: usize,
    build: Duration,
    sah_cost: f64,
    bytes_per_triangle: f64,
    /// Mrays/s of the renderer (packets), of single primary rays, of bounce rays.
    packets: f64,
    single: f64,
    bounce: f64,
    hits: usize,
    bounce_hits: usize,
    peak_rss_mib: Option<f64>,
}

/// Runs the benchmark and prints a table; writes meshes, rays and bench.csv to `--out`.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    anyhow::ensure!(args.threads.iter().all(|&t| t > 0), "--threads: thread counts must be at least 1");
    let runs = args.runs.max(1);
    let sizes: &[(&str, u32)] =
        if args.quick { &[("10k", 71), ("100k", 224)] } else { &[("10k", 71), ("100k", 224), ("1m", 708)] };
    let camera =
        Camera::new(Vec3::new(0.0, 6.0, -9.0), Vec3::ZERO, Vec3::Y, 50.0, 1.0, Projection::Perspective)?;
    let mut rows = Vec::new();
    for &(label, n) in sizes {
        eprintln!("terrain {label}: generating {n}x{n} quads ...");
        let (positions, triangles) = terrain(n);
        write_obj(&args.out.join(format!("terrain_{label}.obj")), &positions, &triangles)?;
        write_camera(&args.out.join(format!("terrain_{label}.json")), &camera)?;
        let mesh = Mesh::new(positions, triangles).context("generated mesh")?;
        let mesh_bytes = mesh.memory_bytes();
        let scene_of = |mesh: Mesh| {
            SceneBuilder::new()
                .background(Color::ONE)
                .material("ground", Material::flat(Color::new(0.4, 0.6, 0.3)))
                .object(Primitive::Mesh(mesh), "ground")
                .build()
        };
        let scene = scene_of(mesh.clone())?;
        let stats = scene.bvh_stats();
        // The builds first, while the process holds little more than the
        // mesh (as Embree's commits are timed, in a process holding only the
        // mesh's arrays). Timed after the ray sets below were made, the 1 M
        // build on one thread took 0.26 s against 0.18–0.19 s here (two
        // alternating runs each on a virtual machine, where memory handed
        // back and taken again is slow to clear: docs/performance.md).
        let builds = args
            .threads
            .iter()
            .map(|&threads| time_builds(threads, runs, &mesh, scene_of))
            .collect::<anyhow::Result<Vec<_>>>()?;
        if args.build_only {
            for (&threads, b) in args.threads.iter().zip(&builds) {
                println!(
                    "terrain {label}: {} triangles, {threads} thread(s): build {:.4} s, CPU of the scene set-up with it {:.4} s, of which the kernel's {:.4} s, {} page faults (medians of {runs}), SAH {:.2}, {} nodes, {} leaves",
                    stats.primitives,
                    b.build.as_secs_f64(),
                    b.cpu.as_secs_f64(),
                    b.system.as_secs_f64(),
                    b.page_faults,
                    stats.sah_cost,
                    stats.nodes,
                    stats.leaves
                );
                println!("  steps (medians): {}", b.steps);
            }
            continue;
        }
        let settings = RenderSettings { image: ImageSize::new(WIDTH, HEIGHT)?, ..RenderSettings::default() };
        let renderer = Renderer::new(&scene, camera, &settings)?;
        let view = renderer.view_plane();
        let primary: Vec<Ray> =
            (0..HEIGHT).flat_map(|y| (0..WIDTH).map(move |x| view.center_ray(x, y))).collect();
        let (bounce, bounce_ids) = bounce_rays(&scene, &primary);
        write_rays(&args.out.join(format!("terrain_{label}.bounce")), &bounce, &bounce_ids)?;
        let hits = primary.iter().filter(|r| scene.cast(r).is_some()).count();
        let bounce_hits = bounce_ids.iter().filter(|&&id| id != u32::MAX).count();
        for (&threads, build) in args.threads.iter().zip(builds.iter().map(|b| b.build)) {
            eprintln!("terrain {label}: {threads} thread(s) ...");
            // A pool per measurement, dropped after it: idle workers of
            // another pool would compete for the cores.
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
            let rays = |f: &(dyn Fn() + Sync)| {
                primary.len() as f64 / median_of(runs, || pool.install(f)).as_secs_f64() / 1e6
            };
            let packets = rays(&|| {
                renderer.render(|_| {});
            });
            let single = rays(&|| {
                primary.par_chunks(1024).for_each(|c| {
                    c.iter().for_each(|r| {
                        let _ = scene.cast(r);
                    })
                });
            });
            let bounce_rate = bounce.len() as f64
                / median_of(runs, || {
                    pool.install(|| {
                        bounce.par_chunks(1024).for_each(|c| {
                            c.iter().for_each(|r| {
                                let _ = bounce_hit(&scene, r);
                            })
                        })
                    })
                })
                .as_secs_f64()
                / 1e6;
            rows.push(Row {
                label,
                triangles: stats.primitives,
                threads,
                build,
                sah_cost: stats.sah_cost,
                bytes_per_triangle: (stats.bytes + mesh_bytes) as f64 / stats.primitives as f64,
                packets,
                single,
                bounce: bounce_rate,
                hits,
                bounce_hits,
                peak_rss_mib: peak_rss_mib(),
            });
        }
    }
    if args.build_only {
        return Ok(());
    }
    let showcase = time_scene(&args.showcase, runs)?;
    report(args, &rows, showcase)
}

/// The CPU time this process's threads have run so far, all together (user
/// and system: page faults count), from Linux's `/proc/self/task/*/schedstat`
/// (nanoseconds; zero where it cannot be read). `--build-only` prints it
/// beside the wall time, which on a shared machine also holds the time other
/// processes ran.
fn process_cpu_time() -> Duration {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return Duration::ZERO };
    let ns: u64 = tasks
        .flatten()
        .filter_map(|task| std::fs::read_to_string(task.path().join("schedstat")).ok())
        .filter_map(|stat| stat.split_whitespace().next()?.parse::<u64>().ok())
        .sum();
    Duration::from_nanos(ns)
}

/// Medians over the builds of [`time_builds`].
struct BuildTimes {
    /// The BVH's own build time ([`rt_core::bvh::BvhStats::build_time`]).
    build: Duration,
    /// The CPU time of the whole scene set-up, all threads ([`process_cpu_time`]).
    cpu: Duration,
    /// The kernel's share of it, and its page faults ([`KernelUsage`]).
    system: Duration,
    page_faults: u64,
    /// The medians of each of the build's steps.
    steps: BuildSteps,
}

/// Makes `runs` scenes of `mesh` with `scene_of` on a pool of `threads`
/// threads (made for these builds and dropped after them: idle workers of
/// another pool would compete for the cores) and times each; the mesh is
/// copied for each before the clocks start.
fn time_builds<E: std::error::Error + Send + Sync + 'static>(
    threads: usize,
    runs: usize,
    mesh: &Mesh,
    scene_of: impl Fn(Mesh) -> Result<Scene, E> + Sync,
) -> anyhow::Result<BuildTimes> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let (mut build, mut cpu, mut system, mut page_faults) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut steps: [Vec<Duration>; 5] = Default::default();
    for _ in 0..runs {
        let mesh = mesh.clone();
        let (before, usage) = (process_cpu_time(), KernelUsage::now());
        let made = pool.install(|| scene_of(mesh))?;
        cpu.push(process_cpu_time().saturating_sub(before));
        let spent = KernelUsage::now().since(usage);
        system.push(spent.system);
        page_faults.push(spent.page_faults);
        let stats = made.bvh_stats();
        build.push(stats.build_time);
        for (list, (_, d)) in steps.iter_mut().zip(stats.build_steps.named()) {
            list.push(d);
        }
    }
    Ok(BuildTimes {
        build: median(build),
        cpu: median(cpu),
        system: median(system),
        page_faults: median(page_faults),
        steps: {
            let [items, binary_tree, leaf_list, collapse, finish] = steps.map(median);
            BuildSteps { items, binary_tree, leaf_list, collapse, finish }
        },
    })
}

/// The kernel's share of this process's work so far (all threads): its
/// system CPU time and the page faults it served without reading a file
/// (`getrusage`'s `ru_stime` and `ru_minflt`). A build writes fresh memory
/// (its items, tree, nodes and leaves); each first touch of a page is a
/// fault the kernel serves by clearing the page, and in a virtual machine
/// the host may have to fault the memory in as well, so the same build
/// varies with how much of it it pays (docs/performance.md).
#[derive(Clone, Copy)]
struct KernelUsage {
    system: Duration,
    page_faults: u64,
}

impl KernelUsage {
    #[cfg(unix)]
    fn now() -> Self {
        // SAFETY: getrusage writes one `rusage` into memory this owns; on
        // failure (it has none for RUSAGE_SELF) the zeros stay.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
        let system = Duration::from_secs(usage.ru_stime.tv_sec.max(0) as u64)
            + Duration::from_micros(usage.ru_stime.tv_usec.max(0) as u64);
        Self { system, page_faults: usage.ru_minflt.max(0) as u64 }
    }

    #[cfg(not(unix))]
    fn now() -> Self {
        Self { system: Duration::ZERO, page_faults: 0 }
    }

    /// What was spent between `earlier` and this.
    fn since(self, earlier: Self) -> Self {
        Self {
            system: self.system.saturating_sub(earlier.system),
            page_faults: self.page_faults.saturating_sub(earlier.page_faults),
        }
    }
}

/// The median wall time of `runs` calls of `f`, after one untimed call
/// (which pages in what the first run would otherwise pay for).
fn median_of(runs: usize, f: impl Fn()) -> Duration {
    f();
    median(
        (0..runs)
            .map(|_| {
                let start = Instant::now();
                f();
                start.elapsed()
            })
            .collect(),
    )
}

/// The incoherent ray set: from each primary hit, one diffuse bounce, drawn
/// as the path tracer draws it (cosine-distributed about the normal on the
/// side the ray came from, from an origin offset off the surface), with the
/// random stream of sample 0 of the pixel under [`BOUNCE_SEED`]. Also the
/// primitive each bounce ray hits (`u32::MAX` for a miss).
fn bounce_rays(scene: &Scene, primary: &[Ray]) -> (Vec<Ray>, Vec<u32>) {
    let rays: Vec<Ray> = primary
        .par_iter()
        .enumerate()
        .filter_map(|(i, ray)| {
            let hit = scene.cast(ray)?;
            let object = &scene.objects()[hit.object];
            let sp = object.primitive.surface_point(hit.primitive, hit.normal, ray.at(hit.t));
            let n = if sp.normal.dot(ray.dir) < 0.0 { sp.normal } else { -sp.normal };
            let (x, y) = (i as u32 % WIDTH, i as u32 / WIDTH);
            let dir = cosine_hemisphere(n, SampleRng::seeded(x, y, 0, BOUNCE_SEED).next_pair());
            Some(Ray::new(sp.spawn_origin(dir), dir))
        })
        .collect();
    let ids =
        rays.par_iter().map(|r| bounce_hit(scene, r).map_or(u32::MAX, |h| h.primitive as u32)).collect();
    (rays, ids)
}

/// A bounce ray's hit: any `t > 0` counts (its origin is off the surface).
fn bounce_hit(scene: &Scene, ray: &Ray) -> Option<rt_core::Hit> {
    scene.closest_hit(ray, Interval::new(0.0, Real::INFINITY))
}

/// Writes `rays` as little-endian f32 (origin x, y, z, direction x, y, z)
/// and the primitive each hits as a u32 (`0xFFFFFFFF` for a miss), ray by
/// ray: 28 bytes each, for `bench/embree_primary.py`.
fn write_rays(path: &Path, rays: &[Ray], ids: &[u32]) -> anyhow::Result<()> {
    let mut bytes = Vec::with_capacity(rays.len() * 28);
    for (r, id) in rays.iter().zip(ids) {
        for v in [r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z] {
            bytes.extend_from_slice(&to_f32(v).to_le_bytes());
        }
        bytes.extend_from_slice(&id.to_le_bytes());
    }
    std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

/// Median of the showcase's full render time (its own size and spp), if it exists.
fn time_scene(path: &Path, runs: usize) -> anyhow::Result<Option<(Duration, u32, u32)>> {
    if !path.exists() {
        return Ok(None);
    }
    let loaded = crate::scene_cache::load_scene(path)?;
    let renderer = Renderer::new(&loaded.scene, loaded.camera, &loaded.settings)?;
    let time = median_of(runs, || {
        renderer.render(|_| {});
    });
    Ok(Some((time, loaded.settings.image.width(), loaded.settings.image.height())))
}

fn report(args: &BenchArgs, rows: &[Row], showcase: Option<(Duration, u32, u32)>) -> anyhow::Result<()> {
    const COLUMNS: [(&str, &str, usize); 12] = [
        ("mesh", "mesh", 5),
        ("triangles", "triangles", 10),
        ("threads", "threads", 7),
        ("build s", "bvh_build_s", 8),
        ("SAH", "sah_cost", 6),
        ("B/tri", "bytes_per_triangle", 6),
        ("packets", "primary_packets_mrays_per_s", 8),
        ("single", "primary_single_mrays_per_s", 8),
        ("bounce", "bounce_mrays_per_s", 8),
        ("hits", "hits", 8),
        ("b. hits", "bounce_hits", 8),
        ("peak MiB", "peak_rss_mib", 8),
    ];
    let row = |fields: &[String]| {
        fields.iter().zip(COLUMNS).map(|(f, (_, _, w))| format!("{f:>w$}")).collect::<Vec<_>>().join(" ")
    };
    let mut csv = COLUMNS.map(|c| c.1).join(",") + "\n";
    println!(
        "{WIDTH}x{HEIGHT} rays, Mrays/s: primary rays as the renderer casts them (packets) and one by one \
         (single), and one diffuse bounce per primary hit; medians of {} runs",
        args.runs.max(1)
    );
    println!("{}", row(&COLUMNS.map(|c| c.0.to_owned())));
    for r in rows {
        let fields = [
            r.label.to_owned(),
            r.triangles.to_string(),
            r.threads.to_string(),
            format!("{:.4}", r.build.as_secs_f64()),
            format!("{:.2}", r.sah_cost),
            format!("{:.1}", r.bytes_per_triangle),
            format!("{:.3}", r.packets),
            format!("{:.3}", r.single),
            format!("{:.3}", r.bounce),
            r.hits.to_string(),
            r.bounce_hits.to_string(),
            r.peak_rss_mib.map_or(String::from("-"), |v| format!("{v:.0}")),
        ];
        println!("{}", row(&fields));
        csv += &(fields.join(",") + "\n");
    }
    if let Some((time, w, h)) = showcase {
        println!("{}: {w}x{h} full render {:.4} s", args.showcase.display(), time.as_secs_f64());
    }
    let path = args.out.join("bench.csv");
    std::fs::write(&path, csv).with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("wrote {} and the meshes and rays to {}", path.display(), args.out.display());
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
