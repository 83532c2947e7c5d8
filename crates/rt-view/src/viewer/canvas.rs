//! The image on screen: rows of the current job applied to a pixel buffer and
//! uploaded to an egui texture as partial updates.
//!
//! A canvas belongs to one job generation and refuses rows of any other, so a
//! row of a cancelled job can never be drawn over the new view. It starts
//! from a placeholder (the previous image, resampled) that rows replace as
//! they arrive. The UI thread only copies rows: colours are built by workers.

use egui::{Color32, ColorImage, TextureHandle, TextureOptions};

use super::render_job::Row;

/// The image being assembled for one job generation.
#[derive(Clone, Debug)]
pub struct Canvas {
    generation: u64,
    width: u32,
    height: u32,
    pixels: Vec<Color32>,
    row_done: Vec<bool>,
    rows_done: u32,
    /// Rows applied since the last upload, in arrival order.
    pending: Vec<u32>,
}

impl Canvas {
    /// A canvas for job `generation`, `width`×`height`, showing `placeholder`
    /// (exactly `width·height` pixels) until rows arrive.
    pub fn new(generation: u64, width: u32, height: u32, placeholder: Vec<Color32>) -> Self {
        assert_eq!(placeholder.len(), width as usize * height as usize);
        Self {
            generation,
            width,
            height,
            pixels: placeholder,
            row_done: vec![false; height as usize],
            rows_done: 0,
            pending: Vec::new(),
        }
    }

    /// A canvas for `generation` whose placeholder is `previous` resampled to
    /// the new size (nearest neighbour), or black without one.
    pub fn replacing(previous: Option<&Canvas>, generation: u64, width: u32, height: u32) -> Self {
        let placeholder = match previous {
            Some(p) => p.resampled(width, height),
            None => vec![Color32::BLACK; width as usize * height as usize],
        };
        Self::new(generation, width, height, placeholder)
    }

    /// `[width, height]` in pixels.
    pub fn size(&self) -> [usize; 2] {
        [self.width as usize, self.height as usize]
    }
    /// Row-major pixels, top row first.
    pub fn pixels(&self) -> &[Color32] {
        &self.pixels
    }
    /// How many distinct rows have arrived.
    pub fn rows_done(&self) -> u32 {
        self.rows_done
    }
    /// Whether every row has arrived.
    pub fn is_complete(&self) -> bool {
        self.rows_done == self.height
    }

    /// Applies `row` if it belongs to this canvas's generation and size;
    /// returns whether it was applied.
    pub fn apply(&mut self, row: &Row) -> bool {
        if row.generation != self.generation
            || row.y >= self.height
            || row.pixels.len() != self.width as usize
        {
            return false;
        }
        let start = row.y as usize * self.width as usize;
        self.pixels[start..start + row.pixels.len()].copy_from_slice(&row.pixels);
        if !std::mem::replace(&mut self.row_done[row.y as usize], true) {
            self.rows_done += 1;
        }
        self.pending.push(row.y);
        true
    }

    /// A new texture holding the whole canvas.
    pub fn to_texture(&mut self, ctx: &egui::Context, options: TextureOptions) -> TextureHandle {
        self.pending.clear();
        ctx.load_texture("render", ColorImage::new(self.size(), self.pixels.clone()), options)
    }

    /// Uploads the rows applied since the last upload to `texture` (which
    /// must have this canvas's size): one partial update per run of
    /// consecutive rows. Returns the number of updates queued.
    pub fn upload_pending(&mut self, texture: &mut TextureHandle, options: TextureOptions) -> usize {
        let mut ys = std::mem::take(&mut self.pending);
        ys.sort_unstable();
        ys.dedup();
        let width = self.width as usize;
        let mut updates = 0;
        let mut i = 0;
        while i < ys.len() {
            let mut j = i + 1;
            while j < ys.len() && ys[j] == ys[j - 1] + 1 {
                j += 1;
            }
            let (first, count) = (ys[i] as usize, j - i);
            let block = self.pixels[first * width..(first + count) * width].to_vec();
            texture.set_partial([0, first], ColorImage::new([width, count], block), options);
            updates += 1;
            i = j;
        }
        updates
    }

    /// The canvas resampled to `width`×`height` by nearest neighbour.
    fn resampled(&self, width: u32, height: u32) -> Vec<Color32> {
        let mut out = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height as u64 {
            let sy = (y * self.height as u64 / height as u64) as usize;
            let row = &self.pixels[sy * self.width as usize..][..self.width as usize];
            out.extend((0..width as u64).map(|x| row[(x * self.width as u64 / width as u64) as usize]));
        }
        out
    }

    /// The image as 8-bit RGB rows, for saving.
    pub fn rgb8(&self) -> Vec<rt_core::render::Rgb8> {
        self.pixels.iter().map(|c| [c.r(), c.g(), c.b()]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(generation: u64, y: u32, width: usize, c: Color32) -> Row {
        Row { generation, y, samples: 1, pixels: vec![c; width] }
    }

    #[test]
    fn rows_of_another_generation_are_never_applied() {
        let mut c = Canvas::replacing(None, 2, 4, 3);
        assert!(!c.apply(&row(1, 0, 4, Color32::RED)));
        assert!(!c.apply(&row(3, 0, 4, Color32::RED)));
        assert!(c.pixels().iter().all(|&p| p == Color32::BLACK));
        assert!(c.apply(&row(2, 0, 4, Color32::RED)));
        assert_eq!(c.rows_done(), 1);
    }

    #[test]
    fn misshapen_rows_are_refused() {
        let mut c = Canvas::replacing(None, 1, 4, 3);
        assert!(!c.apply(&row(1, 3, 4, Color32::RED)));
        assert!(!c.apply(&row(1, 0, 5, Color32::RED)));
    }

    #[test]
    fn completion_counts_distinct_rows() {
        let mut c = Canvas::replacing(None, 1, 2, 2);
        c.apply(&row(1, 0, 2, Color32::RED));
        c.apply(&row(1, 0, 2, Color32::RED));
        assert!(!c.is_complete());
        c.apply(&row(1, 1, 2, Color32::RED));
        assert!(c.is_complete());
    }

    #[test]
    fn a_new_canvas_starts_from_the_previous_image_resampled() {
        let mut small = Canvas::replacing(None, 1, 2, 1);
        small.apply(&Row { generation: 1, y: 0, samples: 1, pixels: vec![Color32::RED, Color32::BLUE] });
        let big = Canvas::replacing(Some(&small), 2, 4, 2);
        let r = Color32::RED;
        let b = Color32::BLUE;
        assert_eq!(big.pixels(), &[r, r, b, b, r, r, b, b]);
    }

    #[test]
    fn pending_rows_upload_as_one_update_per_run_of_consecutive_rows() {
        let ctx = egui::Context::default();
        let mut c = Canvas::replacing(None, 1, 3, 6);
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
