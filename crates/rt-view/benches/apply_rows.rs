//! UI-thread cost of streaming rows into the viewer's texture.
//!
//! `cargo bench -p rt-view --bench apply_rows`
//!
//! For a 1280×960 image, one frame's worth of rows (1, 16 or 64 rows) is
//! applied to the canvas and uploaded as partial texture updates, the way the
//! viewer does it each frame; "full re-upload" instead sends the whole image,
//! as a viewer without partial updates would. egui's queued texture deltas
//! are taken and cleared each iteration, as the integration does every frame.
//!
//! Rows arrive from the channel owned, and the canvas moves them in
//! (`Canvas::take`): each iteration gets fresh copies of the rows, made
//! outside the timing. Rows carry linear colours beside their 8-bit ones.
//! "partial" shows them
//! at exposure 0 in the RGB view (the rows' own 8-bit colours are copied);
//! "partial_exposed" through the display transform (exposure +1: every
//! texel made from the linear colour on the UI thread); "redisplay" is the
//! cost of a change of exposure, all 960 rows made again and uploaded.

use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use egui::{Color32, ColorImage, TextureOptions};
use rt_view::viewer::canvas::Canvas;
use rt_view::viewer::display::Display;
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
                linear: vec![[0.58, 0.021, 0.013]; WIDTH as usize],
            })
            .collect();
        let mut canvas = Canvas::new(1, WIDTH, HEIGHT, 4096);
        let mut texture = canvas.to_texture(&ctx, options);
        group.throughput(Throughput::Elements(rows_per_frame as u64));
        group.bench_with_input(BenchmarkId::new("partial", rows_per_frame), &rows, |b, rows| {
            b.iter_batched(
                || rows.clone(),
                |rows| {
                    for row in rows {
                        let _ = canvas.take(row);
                    }
                    canvas.upload_pending(&mut texture, options);
                    ctx.tex_manager().write().take_delta().clear();
                },
                BatchSize::PerIteration,
            )
        });
        let mut exposed = Canvas::new(1, WIDTH, HEIGHT, 4096);
        exposed.set_display(&Display { exposure: 1.0, ..Display::default() });
        let mut exposed_texture = exposed.to_texture(&ctx, options);
        group.bench_with_input(BenchmarkId::new("partial_exposed", rows_per_frame), &rows, |b, rows| {
            b.iter_batched(
                || rows.clone(),
                |rows| {
                    for row in rows {
                        let _ = exposed.take(row);
                    }
                    exposed.upload_pending(&mut exposed_texture, options);
                    ctx.tex_manager().write().take_delta().clear();
                },
                BatchSize::PerIteration,
            )
        });
        drop(exposed_texture);
        group.bench_with_input(BenchmarkId::new("full_reupload", rows_per_frame), &rows, |b, rows| {
            b.iter_batched(
                || rows.clone(),
                |rows| {
                    for row in rows {
                        let _ = canvas.take(row);
                    }
                    let size = canvas.size();
                    texture.set(ColorImage::new(size, canvas.pixels()), options);
                    ctx.tex_manager().write().take_delta().clear();
                },
                BatchSize::PerIteration,
            )
        });
        drop(texture);
        ctx.tex_manager().write().take_delta().clear();
    }
    // A change of exposure on a finished image: every row's texels again.
    let mut canvas = Canvas::new(1, WIDTH, HEIGHT, 4096);
    for y in 0..HEIGHT {
        canvas.apply(&Row {
            generation: 1,
            y,
            samples: 1,
            pixels: vec![Color32::from_rgb(200, 40, 30); WIDTH as usize],
            linear: vec![[0.58, 0.021, 0.013]; WIDTH as usize],
        });
    }
    let mut texture = canvas.to_texture(&ctx, options);
    let displays = [1.0, 2.0].map(|exposure| Display { exposure, ..Display::default() });
    let mut i = 0;
    group.throughput(Throughput::Elements(HEIGHT as u64));
    group.bench_function("redisplay", |b| {
        b.iter(|| {
            i += 1;
            canvas.set_display(&displays[i % 2]);
            canvas.upload_pending(&mut texture, options);
            ctx.tex_manager().write().take_delta().clear();
        })
    });
    drop(texture);
    ctx.tex_manager().write().take_delta().clear();
    group.finish();
}

criterion_group!(benches, apply_rows);
criterion_main!(benches);
