//! UI-thread cost of streaming rows into the viewer's texture.
//!
//! `cargo bench -p rt-view --bench apply_rows`
//!
//! For a 1280×960 image, one frame's worth of rows (1, 16 or 64 rows) is
//! applied to the canvas and uploaded as partial texture updates, the way the
//! viewer does it each frame; "full re-upload" instead sends the whole image,
//! as a viewer without partial updates would. egui's queued texture deltas
//! are taken and cleared each iteration, as the integration does every frame.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use egui::{Color32, ColorImage, TextureOptions};
use rt_view::viewer::canvas::Canvas;
use rt_view::viewer::render_job::Row;

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 960;

fn apply_rows(c: &mut Criterion) {
    let ctx = egui::Context::default();
    let options = TextureOptions::LINEAR;
    let mut group = c.benchmark_group("apply_rows_1280x960");
    for rows_per_frame in [1u32, 16, 64] {
        let rows: Vec<Row> = (0..rows_per_frame)
            .map(|y| Row {
                generation: 1,
                y: y * 7 % HEIGHT,
                samples: 1,
                pixels: vec![Color32::from_rgb(200, 40, 30); WIDTH as usize],
            })
            .collect();
        let mut canvas = Canvas::new(1, WIDTH, HEIGHT, 4096);
        let mut texture = canvas.to_texture(&ctx, options);
        group.throughput(Throughput::Elements(rows_per_frame as u64));
        group.bench_with_input(BenchmarkId::new("partial", rows_per_frame), &rows, |b, rows| {
            b.iter(|| {
                for row in rows {
                    canvas.apply(row);
                }
                canvas.upload_pending(&mut texture, options);
                ctx.tex_manager().write().take_delta().clear();
            })
        });
        group.bench_with_input(BenchmarkId::new("full_reupload", rows_per_frame), &rows, |b, rows| {
            b.iter(|| {
                for row in rows {
                    canvas.apply(row);
                }
                let size = canvas.size();
                texture.set(ColorImage::new(size, canvas.pixels().to_vec()), options);
                ctx.tex_manager().write().take_delta().clear();
            })
        });
        drop(texture);
        ctx.tex_manager().write().take_delta().clear();
    }
    group.finish();
}

criterion_group!(benches, apply_rows);
criterion_main!(benches);
