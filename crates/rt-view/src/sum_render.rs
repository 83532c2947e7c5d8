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
use rt_core::math::color::Color;
use rt_core::render::passes::{FeatureFrame, FeatureSums};
use rt_core::scene::effects::RayCounts;

use crate::exact_sum::ExactColorSum;

/// The exact sums of samples `samples` of every pixel of rows `rows`, the
/// rows one after the other (row-major), and the rays cast; `None` if
/// `stop` was set before the end (Ctrl-C).
///
/// Rows go in parallel bands, as [`Renderer::render`] makes them (up to
/// [`rt_core::render::BAND_ROWS`], fewer the more samples: a band's rays fill a packet), cast
/// in the same packets ([`Renderer::accumulate_region_packets`]), each
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
    let width = renderer.view_plane().width() as usize;
    let mut sums = vec![ExactColorSum::default(); width * rows.len()];
    let rays = render_bands(
        renderer,
        rows,
        samples,
        (&mut sums, None),
        |band, out| out.copy_from_slice(band),
        row_done,
        stop,
    )?;
    Some((sums, rays))
}

/// The image of samples `0..spp` of every pixel of every row, as
/// [`means`] of [`render_sums`] gives it, bit for bit, and the rays cast;
/// `None` if `stop` was set before the end (Ctrl-C).
///
/// Each band's exact sums are turned into its pixels' means as soon as the
/// band is done, in a buffer each worker reuses: the image's sums (48 bytes
/// a pixel, four times its colours) are never held at once, written and
/// read back.
pub fn render_means(
    renderer: &Renderer,
    row_done: impl Fn(u32) + Sync,
    stop: &AtomicBool,
) -> Option<(Vec<Color>, RayCounts)> {
    let view = renderer.view_plane();
    let (spp, height) = (renderer.samples_per_pixel(), view.height());
    let mut pixels = vec![Color::ZERO; view.width() as usize * height as usize];
    let rays = render_bands(renderer, 0..height, 0..spp, (&mut pixels, None), means_of(spp), row_done, stop)?;
    Some((pixels, rays))
}

/// What [`render_bands`] does with a finished band's sums for
/// [`render_means`]: each pixel's mean of its `spp` samples.
fn means_of(spp: u32) -> impl Fn(&[ExactColorSum], &mut [Color]) + Sync {
    move |band, out| out.iter_mut().zip(band).for_each(|(out, sum)| *out = sum.mean(spp))
}

/// [`render_means`] that also records the feature passes of every sample
/// ([`Renderer::accumulate_region_packets_with_features`]): the image is
/// the same, bit for bit (its sums are exact), and the passes are those of
/// [`Renderer::render_with_features_until`].
pub fn render_means_with_features(
    renderer: &Renderer,
    row_done: impl Fn(u32) + Sync,
    stop: &AtomicBool,
) -> Option<(Vec<Color>, FeatureFrame, RayCounts)> {
    let view = renderer.view_plane();
    let (spp, width, height) = (renderer.samples_per_pixel(), view.width(), view.height());
    let mut pixels = vec![Color::ZERO; width as usize * height as usize];
    let mut features = vec![FeatureSums::default(); pixels.len()];
    let out = (&mut pixels[..], Some(&mut features[..]));
    let rays = render_bands(renderer, 0..height, 0..spp, out, means_of(spp), row_done, stop)?;
    Some((pixels, FeatureFrame { width, height, samples: spp, pixels: features }, rays))
}

/// Renders rows `rows` (samples `samples`) into `out.0` (one `T` per pixel,
/// row-major), band by band: each band's exact sums are made in a buffer
/// the worker reuses, then handed to `finish` with the band's part of
/// `out.0`; with `out.1`, each sample's features are added to it (laid out
/// as `out.0`). The rays cast; `None` if `stop` was set before the end.
///
/// # Panics
/// If `rows` reach past the image, `samples` past its samples per pixel,
/// or `out.0` (or `out.1`) is not one per pixel of the rows.
fn render_bands<T: Send>(
    renderer: &Renderer,
    rows: Range<u32>,
    samples: Range<u32>,
    out: (&mut [T], Option<&mut [FeatureSums]>),
    finish: impl Fn(&[ExactColorSum], &mut [T]) + Sync,
    row_done: impl Fn(u32) + Sync,
    stop: &AtomicBool,
) -> Option<RayCounts> {
    let view = renderer.view_plane();
    let (width, height) = (view.width() as usize, view.height());
    assert!(rows.end <= height, "rows {rows:?} past the image's {height}");
    assert!(samples.end <= renderer.samples_per_pixel(), "samples {samples:?} past the samples per pixel");
    let (out, features) = out;
    assert_eq!(out.len(), width * rows.len(), "one output per pixel of the rows");
    // Bands as tall as a packet's worth of samples per pixel fills, as
    // `Renderer::render`'s (`band_rows`): with 64 samples or more a pixel fills packets
    // on its own (its rays are the most alike: on a million-triangle mesh,
    // 2.5 times faster than 8 × 8 pixels at one sample each).
    let band_rows = rt_core::render::band_rows(samples.len() as u32);
    let band_len = width * band_rows as usize;
    // Each band's part of the features, or none.
    let feature_bands: Vec<Option<&mut [FeatureSums]>> = match features {
        Some(f) => {
            assert_eq!(f.len(), out.len(), "one feature sum per pixel of the rows");
            f.chunks_mut(band_len).map(Some).collect()
        }
        None => out.chunks(band_len).map(|_| None).collect(),
    };
    let rays = out
        .par_chunks_mut(band_len)
        .zip(feature_bands)
        .enumerate()
        .map_init(Vec::new, |sums, (band, (out, features))| {
            if stop.load(Ordering::Relaxed) {
                return RayCounts::default();
            }
            sums.clear();
            sums.resize(out.len(), ExactColorSum::default());
            let first = rows.start + band as u32 * band_rows;
            let rows = first..first + (out.len() / width) as u32;
            let add = &mut |colours: &[(usize, Color)]| add_packet(sums, colours);
            let (columns, samples) = (0..width as u32, samples.clone());
            let counts = match features {
                Some(f) => {
                    renderer.accumulate_region_packets_with_features(rows.clone(), columns, samples, add, f)
                }
                None => renderer.accumulate_region_packets(rows.clone(), columns, samples, add),
            };
            finish(sums, out);
            rows.for_each(&row_done);
            counts
        })
        .sum();
    (!stop.load(Ordering::Relaxed)).then_some(rays)
}

/// Adds each sample colour of a packet (its pixel's index, its colour) to
/// its pixel's sum, a run of equal colours of one pixel at once
/// ([`ExactColorSum::add_times`]): the sums are those of adding one by one,
/// and a flat render, whose pixels mostly see one colour in all their
/// samples, converts each colour to fixed point once, not once per sample.
fn add_packet(sums: &mut [ExactColorSum], colours: &[(usize, Color)]) {
    let mut rest = colours;
    while let Some(&(at, c)) = rest.first() {
        // At least the first: a NaN colour equals nothing, itself included.
        let run = 1 + rest[1..].iter().take_while(|&&(a, b)| a == at && b == c).count();
        sums[at].add_times(c, run as u32);
        rest = &rest[run..];
    }
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
    fn recording_the_feature_passes_leaves_the_image_as_it_is_bit_for_bit() {
        // The passes are those of rt-core's one-loop render, the colours
        // those of the exact sums, not its f32 ones.
        let loaded = scene();
        let r = renderer(&loaded, 5);
        let go = AtomicBool::new(false);
        let (plain, rays) = render_means(&r, |_| {}, &go).unwrap();
        let (pixels, features, feature_rays) = render_means_with_features(&r, |_| {}, &go).unwrap();
        let bits = |p: &[Color]| p.iter().map(|c| c.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&pixels), bits(&plain));
        assert_eq!(feature_rays, rays);
        let (_, expected) = r.render_with_features_until(|_| {}, &go).unwrap();
        assert_eq!(features.pixels, expected.pixels);
        assert_eq!((features.width, features.height, features.samples), (20, 19, 5));
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
    fn the_means_render_is_the_means_of_the_sums_render_bit_for_bit() {
        let loaded = scene();
        for spp in [1, 9, 70] {
            let r = renderer(&loaded, spp);
            let go = AtomicBool::new(false);
            let (sums, rays) = render_sums(&r, 0..19, 0..spp, |_| {}, &go).unwrap();
            let (pixels, means_rays) = render_means(&r, |_| {}, &go).unwrap();
            assert_eq!(pixels, means(&sums, spp), "spp {spp}");
            assert_eq!(means_rays, rays);
        }
        assert!(render_means(&renderer(&loaded, 2), |_| {}, &AtomicBool::new(true)).is_none());
    }

    #[test]
    fn a_packet_of_runs_adds_what_its_samples_add_one_by_one() {
        let (a, b) = (Color::new(0.1, 0.2, 0.3), Color::new(0.1, 0.2, 0.30001));
        let packet = [(0, a), (0, a), (0, b), (0, a), (1, a), (1, a), (2, f32::NAN * a), (2, b)];
        let mut runs = vec![ExactColorSum::default(); 3];
        add_packet(&mut runs, &packet);
        let mut one_by_one = vec![ExactColorSum::default(); 3];
        packet.iter().for_each(|&(at, c)| one_by_one[at].add(c));
        assert_eq!(runs, one_by_one);
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
