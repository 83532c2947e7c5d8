//! Rendering some rows and some sample indices of an image into exact
//! per-pixel sums ([`ExactColorSum`]): what a part of a split render holds,
//! and what `rt-view render` turns into its image, so that the two agree
//! bit for bit.
//!
//! Sample `k` of a pixel depends on the pixel, `k` and the seed alone (and
//! on the render's samples per pixel, which lays out the strata), so any
//! set of rows and sample indices can be rendered anywhere and added later.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use rt_core::Renderer;
use rt_core::bvh::PACKET_RAYS;
use rt_core::math::color::Color;
use rt_core::render::BAND_ROWS;
use rt_core::scene::effects::RayCounts;

use crate::exact_sum::ExactColorSum;

/// The exact sums of samples `samples` of every pixel of rows `rows`, the
/// rows one after the other (row-major), and the rays cast; `None` if
/// `stop` was set before the end (Ctrl-C).
///
/// Rows go in parallel bands, as [`Renderer::render`] makes them (up to
/// [`BAND_ROWS`], fewer the more samples: a band's rays fill a packet), cast
/// in the same packets ([`Renderer::accumulate_region_with`]), each
/// sample's colour added to its pixel's exact sum. `row_done` is called once
/// per finished row, from a worker thread; `stop` is looked at before each
/// band.
///
/// # Panics
/// If `rows` reach past the image or `samples` past its samples per pixel.
pub fn render_sums(
    renderer: &Renderer,
    rows: Range<u32>,
    samples: Range<u32>,
    row_done: impl Fn(u32) + Sync,
    stop: &AtomicBool,
) -> Option<(Vec<ExactColorSum>, RayCounts)> {
    let view = renderer.view_plane();
    let (width, height) = (view.width() as usize, view.height());
    assert!(rows.end <= height, "rows {rows:?} past the image's {height}");
    assert!(samples.end <= renderer.samples_per_pixel(), "samples {samples:?} past the samples per pixel");
    let mut sums = vec![ExactColorSum::default(); width * rows.len()];
    // Bands as tall as a packet's worth of samples per pixel fills, as
    // `Renderer::render`'s: with 64 samples or more a pixel fills packets
    // on its own (its rays are the most alike: on a million-triangle mesh,
    // 2.5 times faster than 8 × 8 pixels at one sample each).
    let band_rows = (PACKET_RAYS as u32 / samples.len().max(1) as u32).clamp(1, BAND_ROWS);
    let rays = sums
        .par_chunks_mut(width * band_rows as usize)
        .enumerate()
        .map(|(band, sums)| {
            if stop.load(Ordering::Relaxed) {
                return RayCounts::default();
            }
            let first = rows.start + band as u32 * band_rows;
            let rows = first..first + (sums.len() / width) as u32;
            let counts =
                renderer.accumulate_region_with(rows.clone(), 0..width as u32, samples.clone(), |at, c| {
                    sums[at].add(c)
                });
            rows.for_each(&row_done);
            counts
        })
        .sum();
    (!stop.load(Ordering::Relaxed)).then_some((sums, rays))
}

/// The image of exact sums `sums` of `count` samples each: each pixel's mean
/// ([`ExactColorSum::mean`]).
pub fn means(sums: &[ExactColorSum], count: u32) -> Vec<Color> {
    sums.iter().map(|s| s.mean(count)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene() -> rt_core::LoadedScene {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        rt_core::load_scene(&scenes.join("cornell_box.ron")).unwrap()
    }

    fn renderer(loaded: &rt_core::LoadedScene, spp: u32) -> Renderer<'_> {
        let settings = loaded.settings.overridden(Some(20), Some(19), Some(spp)).unwrap();
        Renderer::new(&loaded.scene, loaded.camera, &settings).unwrap()
    }

    #[test]
    fn sample_ranges_and_row_ranges_add_up_to_the_whole_render_exactly() {
        let loaded = scene();
        let r = renderer(&loaded, 9);
        let go = AtomicBool::new(false);
        let (whole, rays) = render_sums(&r, 0..19, 0..9, |_| {}, &go).unwrap();
        // Sample ranges, added in another order.
        let mut parts = vec![ExactColorSum::default(); whole.len()];
        let mut part_rays = RayCounts::default();
        for samples in [5..9, 0..2, 2..5] {
            let (part, rays) = render_sums(&r, 0..19, samples, |_| {}, &go).unwrap();
            parts.iter_mut().zip(&part).for_each(|(a, b)| a.merge(b));
            part_rays += rays;
        }
        assert_eq!(parts, whole);
        assert_eq!(part_rays.total(), rays.total());
        // Row ranges (more than a band, less than one, at the bottom edge).
        let mut tiled = Vec::new();
        for rows in [0..11, 11..12, 12..19] {
            tiled.extend(render_sums(&r, rows, 0..9, |_| {}, &go).unwrap().0);
        }
        assert_eq!(tiled, whole);
    }

    #[test]
    fn the_means_are_the_renderers_pixels_up_to_the_rounding_of_their_f32_sums() {
        let loaded = scene();
        let r = renderer(&loaded, 4);
        let (sums, _) = render_sums(&r, 0..19, 0..4, |_| {}, &AtomicBool::new(false)).unwrap();
        let frame = r.render(|_| {});
        for (got, want) in means(&sums, 4).iter().zip(&frame.pixels) {
            let tolerance = 4.0 * f32::EPSILON * want.max_element().max(1e-30);
            assert!((*got - *want).abs().max_element() <= tolerance, "{got} against {want}");
        }
    }

    #[test]
    fn every_row_is_reported_once_and_a_stopped_render_returns_nothing() {
        let loaded = scene();
        let r = renderer(&loaded, 2);
        let seen = std::sync::Mutex::new(vec![0; 19]);
        render_sums(&r, 3..19, 0..2, |y| seen.lock().unwrap()[y as usize] += 1, &AtomicBool::new(false));
        let seen = seen.into_inner().unwrap();
        assert_eq!(seen[..3], [0; 3]);
        assert_eq!(seen[3..], [1; 16]);
        assert!(render_sums(&r, 0..19, 0..2, |_| {}, &AtomicBool::new(true)).is_none());
    }
}
