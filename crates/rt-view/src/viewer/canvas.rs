//! The image on screen: rows of the current job applied to a pixel buffer and
//! uploaded to an egui texture as partial updates.
//!
//! A canvas belongs to one job generation and refuses rows of any other, so a
//! row of a cancelled job can never be drawn over the new view. The UI thread
//! only moves rows in and copies their display texels: colours are built by
//! workers.
//!
//! The canvas keeps the whole image twice, as the rows it was sent (moved
//! in, not copied): linear (scene-referred, the mean of each pixel's samples
//! so far, for Save EXR, the histogram and the comparison with a reference)
//! and encoded as 8 bits (for Save PNG). The texture shows a *display* image
//! of at most [`MAX_DISPLAY_SIDE`] pixels a side: every k-th pixel of every
//! k-th row, k the smallest whole factor that fits. A 15 300 × 8 500 render
//! thus shows through a 3 825 × 2 125 texture, and starting a new job
//! touches only that: the image has no pixels (transparent, zero) until its
//! rows arrive.
//!
//! The display image's texels come from the linear image through the
//! [`Display`] transform (exposure, channel view, false colour, error
//! against a reference): a row's texels when it arrives, every finished
//! row's when the transform changes. With the plain transform (exposure
//! 0, RGB) the rows' own 8-bit colours are copied, as fast as ever.

use egui::{Color32, ColorImage, TextureHandle, TextureOptions};

use super::display::{Channel, Display};
use super::render_job::Row;

/// Largest side of the texture the image is shown through, in texels
/// (lower if the GPU's limit is lower).
pub const MAX_DISPLAY_SIDE: u32 = 4096;

/// The image being assembled for one job generation.
#[derive(Clone, Debug)]
pub struct Canvas {
    generation: u64,
    width: u32,
    height: u32,
    /// The image's rows, top row first, each the last one that arrived
    /// (empty until one does).
    rows: Vec<Stored>,
    rows_done: u32,
    /// Rows applied so far, counting a row again each time it arrives.
    changes: u64,
    /// How the display image is made from the linear one.
    transform: Display,
    /// Pixels of the image per display texel along each axis.
    factor: u32,
    /// The display image: `display_size()` texels.
    display: Vec<Color32>,
    /// Display rows changed since the last upload, in arrival order.
    pending: Vec<u32>,
    /// Per display row, the generation whose pixels it shows: this canvas's
    /// own, an older one's carried over by [`Canvas::replacing`], or 0 for a
    /// row no job has drawn yet (the window's trace reports it).
    sources: Vec<u64>,
}

/// One row of the image as it arrived: empty until then.
#[derive(Clone, Debug, Default)]
struct Stored {
    samples: u32,
    pixels: Vec<Color32>,
    linear: Vec<[f32; 3]>,
}

impl Stored {
    fn done(&self) -> bool {
        !self.pixels.is_empty()
    }
}

impl Canvas {
    /// A black canvas for job `generation`, `width`×`height`, shown through
    /// a texture of at most `max_side` texels a side (and never more than
    /// [`MAX_DISPLAY_SIDE`]; the GPU's own limit comes from egui's
    /// `InputState::max_texture_side`).
    pub fn new(generation: u64, width: u32, height: u32, max_side: usize) -> Self {
        let max_side = (max_side.max(1) as u32).min(MAX_DISPLAY_SIDE);
        let factor = width.max(height).div_ceil(max_side).max(1);
        let (dw, dh) = (width.div_ceil(factor), height.div_ceil(factor));
        Self {
            generation,
            width,
            height,
            rows: vec![Stored::default(); height as usize],
            rows_done: 0,
            changes: 0,
            transform: Display::default(),
            factor,
            display: vec![Color32::BLACK; dw as usize * dh as usize],
            pending: Vec::new(),
            sources: vec![0; dh as usize],
        }
    }

    /// A canvas for `generation` that shows `previous`'s display image,
    /// resampled (nearest neighbour), until rows arrive; black without one.
    pub fn replacing(
        previous: Option<&Canvas>,
        generation: u64,
        width: u32,
        height: u32,
        max_side: usize,
    ) -> Self {
        let mut canvas = Self::new(generation, width, height, max_side);
        if let Some(p) = previous {
            let [dw, dh] = canvas.display_size();
            let [pw, ph] = p.display_size();
            for y in 0..dh {
                let sy = y * ph / dh;
                canvas.sources[y] = p.sources[sy];
                for x in 0..dw {
                    canvas.display[y * dw + x] = p.display[sy * pw + x * pw / dw];
                }
            }
        }
        canvas
    }

    /// The job generation this canvas accepts rows of.
    pub fn generation(&self) -> u64 {
        self.generation
    }
    /// `[width, height]` of the image in pixels.
    pub fn size(&self) -> [usize; 2] {
        [self.width as usize, self.height as usize]
    }
    /// `[width, height]` of the display image (and texture) in texels.
    pub fn display_size(&self) -> [usize; 2] {
        [self.width.div_ceil(self.factor) as usize, self.height.div_ceil(self.factor) as usize]
    }
    /// Image pixels per display texel along each axis (1 unless the image
    /// is larger than [`MAX_DISPLAY_SIDE`]).
    pub fn display_factor(&self) -> u32 {
        self.factor
    }
    /// Row-major 8-bit pixels of the whole image, top row first
    /// (transparent where no row has arrived yet).
    pub fn pixels(&self) -> Vec<Color32> {
        self.gather(|r| &r.pixels, Color32::TRANSPARENT)
    }
    /// The colour at pixel (x, y), if it is inside the image (transparent
    /// until its row arrives).
    pub fn pixel(&self, x: u32, y: u32) -> Option<Color32> {
        (x < self.width && y < self.height)
            .then(|| self.rows[y as usize].pixels.get(x as usize).copied().unwrap_or(Color32::TRANSPARENT))
    }
    /// Row-major linear colours of the whole image (zero where no row has
    /// arrived yet).
    pub fn linear(&self) -> Vec<[f32; 3]> {
        self.gather(|r| &r.linear, [0.0; 3])
    }
    /// The 8-bit pixels of row `y`, once it has arrived.
    pub fn pixel_row(&self, y: u32) -> Option<&[Color32]> {
        self.rows.get(y as usize).filter(|r| r.done()).map(|r| &r.pixels[..])
    }
    /// The linear colours of row `y`, once it has arrived.
    pub fn linear_row(&self, y: u32) -> Option<&[[f32; 3]]> {
        self.rows.get(y as usize).filter(|r| r.done()).map(|r| &r.linear[..])
    }
    /// Samples per pixel of row `y` (0 until it arrives).
    pub fn row_samples(&self, y: u32) -> u32 {
        self.rows.get(y as usize).map_or(0, |r| r.samples)
    }
    /// The rows' `part` one after the other, `missing` for rows not arrived.
    fn gather<T: Copy>(&self, part: impl Fn(&Stored) -> &Vec<T>, missing: T) -> Vec<T> {
        let mut all = Vec::with_capacity(self.width as usize * self.height as usize);
        for r in &self.rows {
            match r.done() {
                true => all.extend_from_slice(part(r)),
                false => all.extend(std::iter::repeat_n(missing, self.width as usize)),
            }
        }
        all
    }
    /// How many rows have been applied in all, a row counted each time it
    /// arrives: what was computed from the image is stale when it changed.
    pub fn changes(&self) -> u64 {
        self.changes
    }
    /// Per display row, the job generation whose pixels it shows (this
    /// canvas's, or an older one's carried over from the image it replaced);
    /// 0 where no job has drawn yet.
    pub fn display_sources(&self) -> &[u64] {
        &self.sources
    }
    /// How many distinct rows have arrived.
    pub fn rows_done(&self) -> u32 {
        self.rows_done
    }
    /// Whether every row has arrived.
    pub fn is_complete(&self) -> bool {
        self.rows_done == self.height
    }

    /// Applies a copy of `row` if it belongs to this canvas's generation
    /// and size; returns whether it was applied. ([`Canvas::take`] moves a
    /// row in without copying it.)
    pub fn apply(&mut self, row: &Row) -> bool {
        self.take(row.clone()).is_ok()
    }

    /// Moves `row` in if it belongs to this canvas's generation and size;
    /// gives it back if not.
    pub fn take(&mut self, row: Row) -> Result<(), Row> {
        if row.generation != self.generation
            || row.y >= self.height
            || row.pixels.len() != self.width as usize
            || row.linear.len() != self.width as usize
        {
            return Err(row);
        }
        let stored = &mut self.rows[row.y as usize];
        if !stored.done() {
            self.rows_done += 1;
        }
        *stored = Stored { samples: row.samples, pixels: row.pixels, linear: row.linear };
        self.changes += 1;
        if row.y.is_multiple_of(self.factor) {
            let dy = row.y / self.factor;
            self.make_texels(dy);
            self.pending.push(dy);
            self.sources[dy as usize] = self.generation;
        }
        Ok(())
    }

    /// The display transform in force.
    pub fn display(&self) -> &Display {
        &self.transform
    }

    /// Shows the image through `display` from now on: every finished row's
    /// texels are made again (and uploaded with the next pending rows);
    /// rows still to come keep the placeholder until they arrive. Nothing
    /// happens if `display` is the transform in force; returns whether
    /// it changed.
    pub fn set_display(&mut self, display: &Display) -> bool {
        if self.transform == *display {
            return false;
        }
        self.transform = display.clone();
        let [_, dh] = self.display_size();
        for dy in 0..dh as u32 {
            if self.rows[(dy * self.factor) as usize].done() {
                self.make_texels(dy);
                self.pending.push(dy);
            }
        }
        true
    }

    /// Makes the texels of display row `dy` from image row `dy·factor`.
    fn make_texels(&mut self, dy: u32) {
        let [dw, _] = self.display_size();
        let (y, k) = ((dy * self.factor) as usize, self.factor as usize);
        let texels = &mut self.display[dy as usize * dw..(dy as usize + 1) * dw];
        let row = &self.rows[y];
        if self.transform.is_plain() {
            let pixels = &row.pixels;
            if k == 1 {
                texels.copy_from_slice(pixels);
            } else {
                for (texel, pixel) in texels.iter_mut().zip(pixels.iter().step_by(k)) {
                    *texel = *pixel;
                }
            }
        } else {
            let size = [self.width as usize, self.height as usize];
            let compare = self.transform.error_for(size).map(|e| (e.kind, e.reference.row(y)));
            self.transform.row(&row.linear, k, compare, texels);
        }
    }

    /// A new texture holding the whole display image.
    pub fn to_texture(&mut self, ctx: &egui::Context, options: TextureOptions) -> TextureHandle {
        let image = ColorImage::new(self.display_size(), self.to_texture_image());
        ctx.load_texture("render", image, options)
    }

    /// The display image's texels, for uploading all of it (nothing is
    /// pending afterwards).
    pub fn to_texture_image(&mut self) -> Vec<Color32> {
        self.pending.clear();
        self.display.clone()
    }

    /// The display image's texels as they are now.
    pub fn display_image(&self) -> Vec<Color32> {
        self.display.clone()
    }

    /// Uploads the display rows changed since the last upload to `texture`
    /// (which must have the display size): one partial update per run of
    /// consecutive rows. Returns the number of updates queued.
    pub fn upload_pending(&mut self, texture: &mut TextureHandle, options: TextureOptions) -> usize {
        let mut ys = std::mem::take(&mut self.pending);
        ys.sort_unstable();
        ys.dedup();
        let [width, _] = self.display_size();
        let mut updates = 0;
        let mut i = 0;
        while i < ys.len() {
            let mut j = i + 1;
            while j < ys.len() && ys[j] == ys[j - 1] + 1 {
                j += 1;
            }
            let (first, count) = (ys[i] as usize, j - i);
            let block = self.display[first * width..(first + count) * width].to_vec();
            texture.set_partial([0, first], ColorImage::new([width, count], block), options);
            updates += 1;
            i = j;
        }
        updates
    }

    /// The image as 8-bit RGB rows, for saving.
    pub fn rgb8(&self) -> Vec<rt_core::render::Rgb8> {
        self.pixels().iter().map(|c| [c.r(), c.g(), c.b()]).collect()
    }

    /// The image as 8-bit RGB rows through the exposure and view transform
    /// of the display in force, as Save PNG writes it: what the window shows
    /// at full resolution, as `rt-view render --exposure --view-transform`
    /// writes a PNG. The analysis views (one channel, false colour, the
    /// error against a reference) are not part of it: they are ways of
    /// looking at the image, not the image. With exposure 0 and the Standard
    /// transform these are the rows' own colours ([`Canvas::rgb8`]).
    pub fn rgb8_displayed(&self) -> Vec<rt_core::render::Rgb8> {
        let display = Display { channel: Channel::Rgb, error: None, ..self.transform.clone() };
        if display.is_plain() {
            return self.rgb8();
        }
        let [width, _] = self.size();
        let mut texels = vec![Color32::TRANSPARENT; width];
        let linear = self.linear();
        let mut out = Vec::with_capacity(linear.len());
        for row in linear.chunks_exact(width) {
            display.row(row, 1, None, &mut texels);
            out.extend(texels.iter().map(|c| [c.r(), c.g(), c.b()]));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(generation: u64, y: u32, width: usize, c: Color32) -> Row {
        let linear = [c.r(), c.g(), c.b()].map(|v| v as f32 / 255.0);
        Row { generation, y, samples: 1, pixels: vec![c; width], linear: vec![linear; width] }
    }

    #[test]
    fn saved_colours_follow_the_exposure_and_view_transform_but_not_the_analysis_views() {
        let mut canvas = Canvas::new(1, 3, 2, 16);
        for y in 0..2 {
            assert!(canvas.apply(&row(1, y, 3, Color32::from_rgb(40, 80, 120))));
        }
        let plain = canvas.rgb8_displayed();
        assert_eq!(plain, canvas.rgb8(), "exposure 0, Standard: the rows' own colours");
        canvas.set_display(&Display { exposure: 1.0, ..Display::default() });
        let brighter = canvas.rgb8_displayed();
        assert_eq!(brighter[0], [80, 160, 240], "one stop up doubles linear values: {:?}", brighter[0]);
        canvas.set_display(&Display { exposure: 1.0, channel: Channel::FalseColour, ..Display::default() });
        assert_eq!(canvas.rgb8_displayed(), brighter, "false colour is a view, not the saved image");
        canvas.set_display(&Display {
            view_transform: rt_core::render::view_transform::ViewTransform::AgX,
            ..Display::default()
        });
        assert_ne!(canvas.rgb8_displayed(), plain, "AgX rolls the values through its curve");
    }

    #[test]
    fn rows_of_another_generation_are_never_applied() {
        let mut c = Canvas::new(2, 4, 3, 4096);
        assert!(!c.apply(&row(1, 0, 4, Color32::RED)));
        assert!(!c.apply(&row(3, 0, 4, Color32::RED)));
        assert!(c.pixels().iter().all(|&p| p == Color32::TRANSPARENT));
        assert!(c.apply(&row(2, 0, 4, Color32::RED)));
        assert_eq!(c.rows_done(), 1);
    }

    #[test]
    fn each_display_row_tells_which_generation_it_shows() {
        let mut old = Canvas::new(1, 2, 2, 4096);
        old.apply(&row(1, 0, 2, Color32::RED));
        assert_eq!(old.display_sources(), [1, 0]);
        // Twice the height: rows carried over keep the old generation, rows
        // the old image had not drawn stay blank (0).
        let mut new = Canvas::replacing(Some(&old), 2, 2, 4, 4096);
        assert_eq!(new.display_sources(), [1, 1, 0, 0]);
        new.apply(&row(2, 3, 2, Color32::BLUE));
        new.apply(&row(2, 0, 2, Color32::BLUE));
        assert!(!new.apply(&row(1, 2, 2, Color32::RED)));
        assert_eq!(new.display_sources(), [2, 1, 0, 2]);
        // A downsampled display: only the rows shown on it count.
        let mut huge = Canvas::new(3, 8192, 4, 4096);
        huge.apply(&row(3, 1, 8192, Color32::RED));
        huge.apply(&row(3, 2, 8192, Color32::RED));
        assert_eq!(huge.display_sources(), [0, 3]);
    }

    #[test]
    fn misshapen_rows_are_refused() {
        let mut c = Canvas::new(1, 4, 3, 4096);
        assert!(!c.apply(&row(1, 3, 4, Color32::RED)));
        assert!(!c.apply(&row(1, 0, 5, Color32::RED)));
    }

    #[test]
    fn completion_counts_distinct_rows() {
        let mut c = Canvas::new(1, 2, 2, 4096);
        c.apply(&row(1, 0, 2, Color32::RED));
        c.apply(&row(1, 0, 2, Color32::RED));
        assert!(!c.is_complete());
        c.apply(&row(1, 1, 2, Color32::RED));
        assert!(c.is_complete());
    }

    #[test]
    fn a_new_canvas_shows_the_previous_image_resampled_until_rows_arrive() {
        let mut small = Canvas::new(1, 2, 1, 4096);
        small.apply(&Row {
            generation: 1,
            y: 0,
            samples: 1,
            pixels: vec![Color32::RED, Color32::BLUE],
            linear: vec![[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        });
        let big = Canvas::replacing(Some(&small), 2, 4, 2, 4096);
        let r = Color32::RED;
        let b = Color32::BLUE;
        assert_eq!(big.display, &[r, r, b, b, r, r, b, b]);
        // The image itself has no pixels yet: a saved image is never the placeholder.
        assert!(big.pixels().iter().all(|&p| p == Color32::TRANSPARENT));
    }

    #[test]
    fn a_huge_image_is_shown_through_a_texture_of_at_most_the_display_limit() {
        // 15 300 × 8 500 (a 2× resolution scale on a big scene): the texture
        // is every 4th pixel of every 4th row; with a GPU limit of 2048, every 8th.
        assert_eq!(Canvas::new(1, 15_300, 8_500, 16_384).display_size(), [3825, 2125]);
        let ctx = egui::Context::default();
        let limit = ctx.input(|i| i.max_texture_side);
        let mut c = Canvas::new(1, 15_300, 8_500, limit);
        let k = c.display_factor() as usize;
        assert!(c.display_size()[0] <= limit && c.display_size()[1] <= limit);
        let mut texture = c.to_texture(&ctx, TextureOptions::NEAREST);
        assert_eq!(texture.size(), c.display_size());
        let mut pixels = vec![Color32::BLACK; 15_300];
        pixels[2 * k] = Color32::RED;
        let linear = vec![[0.0; 3]; 15_300];
        assert!(c.apply(&Row { generation: 1, y: k as u32, samples: 1, pixels, linear }));
        let width = c.display_size()[0];
        assert_eq!(c.display[width + 2], Color32::RED, "texel (2, 1) is pixel (2k, k)");
        assert!(c.apply(&row(1, k as u32 + 1, 15_300, Color32::GREEN)), "rows between texels still count");
        assert_eq!(c.upload_pending(&mut texture, TextureOptions::NEAREST), 1);
        assert_eq!(c.pixel(2 * k as u32, k as u32), Some(Color32::RED));
        drop(texture);
        ctx.tex_manager().write().take_delta().clear();
    }

    #[test]
    fn a_new_display_transform_remakes_the_finished_rows_texels_once() {
        use crate::viewer::display::{Display, ErrorKind, ErrorView};
        use crate::viewer::reference::Reference;
        let grey = Color32::from_gray(64); // linear 64/255
        let mut c = Canvas::replacing(None, 1, 2, 3, 4096);
        c.apply(&row(1, 0, 2, grey));
        c.apply(&row(1, 2, 2, grey));
        c.pending.clear();
        assert_eq!(c.display, [grey, grey, Color32::BLACK, Color32::BLACK, grey, grey]);
        let brighter = Display { exposure: 1.0, ..Display::default() };
        assert!(c.set_display(&brighter));
        let twice = Color32::from_gray(128);
        // Rows 0 and 2 made again and pending; row 1 (not rendered) keeps its placeholder.
        assert_eq!(c.display, [twice, twice, Color32::BLACK, Color32::BLACK, twice, twice]);
        assert_eq!(c.pending, [0, 2]);
        assert!(!c.set_display(&brighter), "the same transform again does nothing");
        assert_eq!(c.pending, [0, 2]);
        // A row arriving now goes through the transform too.
        c.apply(&row(1, 1, 2, grey));
        assert_eq!(c.display[2..4], [twice, twice]);
        // Back to exposure 0: exactly the rows' own colours.
        assert!(c.set_display(&Display::default()));
        assert_eq!(c.display, [grey; 6]);
        // The absolute error against a reference equal to the render but in pixel 0.
        let mut pixels = vec![[64.0 / 255.0; 3]; 6];
        pixels[0] = [0.0; 3];
        let reference = std::sync::Arc::new(Reference::new(2, 3, pixels, "r".into()).unwrap());
        let error = ErrorView { kind: ErrorKind::Absolute, reference };
        c.set_display(&Display { error: Some(error), ..Display::default() });
        assert_eq!(
            c.display,
            [grey, Color32::BLACK, Color32::BLACK, Color32::BLACK, Color32::BLACK, Color32::BLACK]
        );
    }

    #[test]
    fn pending_rows_upload_as_one_update_per_run_of_consecutive_rows() {
        let ctx = egui::Context::default();
        let mut c = Canvas::new(1, 3, 6, 4096);
        let mut texture = c.to_texture(&ctx, TextureOptions::NEAREST);
        for y in [4, 0, 1, 5, 2] {
            c.apply(&row(1, y, 3, Color32::RED));
        }
        // Runs: 0–2 and 4–5.
        assert_eq!(c.upload_pending(&mut texture, TextureOptions::NEAREST), 2);
        assert_eq!(c.upload_pending(&mut texture, TextureOptions::NEAREST), 0);
        // No renderer consumes the queued deltas here; debug builds of egui
        // panic on dropping unapplied ones, so clear them explicitly.
        drop(texture);
        ctx.tex_manager().write().take_delta().clear();
    }
}
