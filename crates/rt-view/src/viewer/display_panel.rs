//! The display and reference sections of the side panel: exposure, the
//! view transform (Standard or AgX), the channel view and false colour (with its legend), the histogram, and the
//! reference image with the comparison views and their metrics.
//!
//! The panel holds these settings and what is computed from the image; the
//! transform itself is [`Display`], applied by the canvas. Per frame it
//! does little: it polls a reference being read, sums again the rows that
//! arrived for the metrics ([`Metrics`]), and makes a histogram at most
//! every [`histogram::REFRESH`], only of an image that changed.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use egui::{Color32, ColorImage, Pos2, Rect, Sense, Stroke, TextureHandle, TextureOptions, Vec2, pos2};
use rt_core::math::color::ColorSpace;
use rt_core::render::view_transform::{self, ViewTransform};

use super::canvas::{Canvas, MAX_DISPLAY_SIDE};
use super::display::{Channel, Display, ErrorKind, ErrorView, turbo};
use super::error_metrics::{ErrorMetrics, Metrics};
use super::histogram::{self, BINS, Histogram};
use super::reference::{Loading, Reference};

/// The exposure slider's range, in stops.
const EXPOSURE_RANGE: std::ops::RangeInclusive<f32> = -10.0..=10.0;

/// How the render is shown against the reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Compare {
    /// The render alone.
    Off,
    /// The render left of a draggable line, the reference right of it.
    Split,
    /// `|a − b|` per channel.
    Absolute,
    /// `|a − b| / (b + ε)` per channel.
    Relative,
}

/// The panel's state.
pub(super) struct DisplayPanel {
    exposure: f32,
    view_transform: ViewTransform,
    channel: Channel,
    false_colour_range: [f32; 2],
    compare: Compare,
    /// The reference path field.
    path: String,
    reference: Option<Arc<Reference>>,
    loading: Option<Loading>,
    /// Why the last reference did not load (or the render was not taken).
    message: Option<String>,
    /// Why the reference cannot be compared with the render, if it cannot.
    mismatch: Option<String>,
    histogram: Option<Histogram>,
    /// The canvas (generation, changes) the histogram is of, and when made.
    histogram_of: Option<((u64, u64), Instant)>,
    metrics: Metrics,
    last_metrics: Option<ErrorMetrics>,
    /// The reference through the display transform, for the split view,
    /// and the transform and filter it was made with.
    reference_texture: Option<(TextureHandle, Display, TextureOptions)>,
    /// How the split view's reference is filtered: as the render is.
    filter: TextureOptions,
}

impl Default for DisplayPanel {
    fn default() -> Self {
        Self {
            exposure: 0.0,
            view_transform: ViewTransform::Standard,
            channel: Channel::Rgb,
            false_colour_range: Display::default().false_colour_range,
            compare: Compare::Off,
            path: "reference.exr".to_owned(),
            reference: None,
            loading: None,
            message: None,
            mismatch: None,
            histogram: None,
            histogram_of: None,
            metrics: Metrics::default(),
            last_metrics: None,
            reference_texture: None,
            filter: TextureOptions::LINEAR,
        }
    }
}

impl DisplayPanel {
    /// The display transform chosen, encoding in `color_space`.
    pub fn display(&self, color_space: ColorSpace) -> Display {
        let kind = match self.compare {
            Compare::Absolute => Some(ErrorKind::Absolute),
            Compare::Relative => Some(ErrorKind::Relative),
            Compare::Off | Compare::Split => None,
        };
        let error = kind.zip(self.reference.clone()).map(|(kind, reference)| ErrorView { kind, reference });
        Display {
            exposure: self.exposure,
            view_transform: self.view_transform,
            channel: self.channel,
            false_colour_range: self.false_colour_range,
            color_space,
            error,
        }
    }

    /// The reference to show right of the split line, if the split view is
    /// on: through the display transform (encoding in `color_space`), made
    /// again only when the reference or the transform changed.
    pub fn split_texture(&mut self, ctx: &egui::Context, color_space: ColorSpace) -> Option<TextureHandle> {
        self.update_reference_texture(ctx, color_space);
        self.reference_texture.as_ref().map(|(t, _, _)| t.clone())
    }

    /// Filters the split view's reference with `options` from now on (the
    /// render's: nearest-neighbour when magnified).
    pub fn set_filter(&mut self, options: TextureOptions) {
        self.filter = options;
    }

    /// A scene was loaded: its file's exposure and view transform become
    /// the display's when it was opened (`reset`) or when the file changed
    /// them; otherwise what the panel was set to stays.
    pub fn scene_loaded(
        &mut self,
        file: view_transform::Display,
        previous: view_transform::Display,
        reset: bool,
    ) {
        if reset || file != previous {
            self.exposure = file.exposure.clamp(*EXPOSURE_RANGE.start(), *EXPOSURE_RANGE.end());
            self.view_transform = file.view_transform;
        }
    }

    /// The view transform chosen.
    #[cfg(test)]
    pub fn view_transform(&self) -> ViewTransform {
        self.view_transform
    }

    /// Sets the exposure, in stops.
    #[cfg(test)]
    pub fn set_exposure(&mut self, stops: f32) {
        self.exposure = stops;
    }

    /// Sets the comparison view.
    #[cfg(test)]
    pub fn set_compare(&mut self, compare: Compare) {
        self.compare = compare;
    }

    /// The metrics of the render against the reference, as last updated.
    #[cfg(test)]
    pub fn metrics(&self) -> Option<ErrorMetrics> {
        self.last_metrics
    }

    /// Why the reference did not load or cannot be compared, if so.
    #[cfg(test)]
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref().or(self.mismatch.as_deref())
    }

    /// Starts reading the reference at `path`.
    pub fn load(&mut self, ctx: &egui::Context, path: PathBuf) {
        self.path = path.display().to_string();
        let repaint = ctx.clone();
        self.loading = Some(Loading::start(path, move || repaint.request_repaint()));
        self.message = None;
    }

    /// The rendered image on `canvas` becomes the reference (if complete).
    pub fn use_render(&mut self, canvas: Option<&Canvas>) {
        let [w, h] = canvas.map_or([0, 0], Canvas::size);
        let name = format!("the render ({w} × {h})");
        let complete = canvas.filter(|c| c.is_complete());
        match complete.and_then(|c| Reference::new(w, h, c.linear(), name)) {
            Some(r) => self.set_reference(r),
            None => self.message = Some("the render is not finished yet: no reference taken".into()),
        }
    }

    fn set_reference(&mut self, reference: Reference) {
        self.reference = Some(Arc::new(reference));
        self.reference_texture = None;
        self.last_metrics = None;
        self.message = None;
        if self.compare == Compare::Off {
            self.compare = Compare::Split;
        }
    }

    /// Per frame: takes a reference that finished loading, brings the
    /// metrics up to date with `canvas` (the image on screen; `full_size`
    /// the full render's), and makes a histogram if one is due.
    pub fn update(&mut self, ctx: &egui::Context, canvas: Option<&Canvas>, full_size: [usize; 2]) {
        if let Some(result) = self.loading.as_ref().and_then(Loading::poll) {
            self.loading = None;
            match result {
                Ok(r) => self.set_reference(r),
                Err(e) => self.message = Some(e),
            }
        }
        self.mismatch = self.reference.as_ref().and_then(|r| r.mismatch(full_size));
        if self.mismatch.is_some() {
            self.last_metrics = None;
        } else if let Some(reference) = &self.reference
            && let Some(c) = canvas.filter(|c| c.size() == full_size)
        {
            self.last_metrics = self.metrics.update(c, reference);
        }
        if let Some(c) = canvas {
            let key = (c.generation(), c.changes());
            let due =
                self.histogram_of.is_none_or(|(of, at)| of != key && at.elapsed() >= histogram::REFRESH);
            if due && c.rows_done() > 0 {
                self.histogram = Some(Histogram::of_canvas(c));
                self.histogram_of = Some((key, Instant::now()));
            } else if !due && self.histogram_of.is_some_and(|(of, _)| of != key) {
                ctx.request_repaint_after(histogram::REFRESH);
            }
        }
    }

    /// Makes the split view's texture again if the reference or the
    /// display transform changed (once per change, never per frame).
    fn update_reference_texture(&mut self, ctx: &egui::Context, color_space: ColorSpace) {
        let Some(reference) = self.reference.as_ref().filter(|_| self.compare == Compare::Split) else {
            self.reference_texture = None;
            return;
        };
        let display = Display { error: None, ..self.display(color_space) };
        if self.reference_texture.as_ref().is_some_and(|(_, d, f)| *d == display && *f == self.filter) {
            return;
        }
        let [w, h] = reference.size();
        let max_side = ctx.input(|i| i.max_texture_side).clamp(1, MAX_DISPLAY_SIDE as usize);
        let k = w.max(h).div_ceil(max_side).max(1);
        let (dw, dh) = (w.div_ceil(k), h.div_ceil(k));
        let mut texels = vec![Color32::BLACK; dw * dh];
        for (dy, out) in texels.chunks_exact_mut(dw).enumerate() {
            display.row(reference.row(dy * k), k, None, out);
        }
        let texture = ctx.load_texture("reference", ColorImage::new([dw, dh], texels), self.filter);
        self.reference_texture = Some((texture, display, self.filter));
    }

    /// The display section, then the reference section. `canvas` is the
    /// image on screen.
    pub fn ui(&mut self, ui: &mut egui::Ui, canvas: Option<&Canvas>) {
        ui.heading("Display");
        ui.horizontal(|ui| {
            ui.add(egui::Slider::new(&mut self.exposure, EXPOSURE_RANGE).step_by(0.1).text("exposure"))
                .on_hover_text("in stops: the linear colours are multiplied by 2^exposure");
            if ui.small_button("0").on_hover_text("exposure 0").clicked() {
                self.exposure = 0.0;
            }
        });
        ui.horizontal(|ui| {
            ui.label("view");
            for (transform, label, hover) in [
                (
                    ViewTransform::Standard,
                    "Standard",
                    "clamped to [0, 1], encoded in the scene's colour space",
                ),
                (
                    ViewTransform::AgX,
                    "AgX",
                    "AgX's curve: bright colours roll off to white instead of clipping",
                ),
            ] {
                ui.selectable_value(&mut self.view_transform, transform, label).on_hover_text(hover);
            }
        });
        ui.horizontal_wrapped(|ui| {
            for (channel, label) in Channel::ALL {
                ui.selectable_value(&mut self.channel, channel, label);
            }
        });
        if self.channel == Channel::FalseColour {
            self.false_colour_ui(ui);
        }
        match &self.histogram {
            Some(h) => histogram_ui(ui, h),
            None => {
                ui.small("histogram: no rows yet");
            }
        }
        ui.separator();
        self.reference_ui(ui, canvas);
    }

    /// The false colour range and its legend: Turbo from the low end's
    /// luminance to the high end's.
    fn false_colour_ui(&mut self, ui: &mut egui::Ui) {
        let [lo, hi] = &mut self.false_colour_range;
        ui.horizontal(|ui| {
            ui.label("log2 luminance");
            ui.add(egui::DragValue::new(lo).speed(0.1).range(-40.0..=*hi - 0.1));
            ui.label("to");
            ui.add(egui::DragValue::new(hi).speed(0.1).range(*lo + 0.1..=40.0));
        });
        let (rect, _) =
            ui.allocate_exact_size(Vec2::new(ui.available_width().min(280.0), 14.0), Sense::hover());
        let painter = ui.painter_at(rect);
        let steps = 64;
        for i in 0..steps {
            let t0 = i as f32 / steps as f32;
            let t1 = (i + 1) as f32 / steps as f32;
            let x = |t: f32| rect.left() + t * rect.width();
            painter.rect_filled(
                Rect::from_x_y_ranges(x(t0)..=x(t1), rect.y_range()),
                0.0,
                turbo((t0 + t1) / 2.0),
            );
        }
        ui.horizontal(|ui| {
            ui.small(format!("Y = {}", short(lo.exp2())));
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                ui.small(format!("Y = {}", short(hi.exp2())));
            });
        });
    }

    /// The reference: path, Load, Use the render, the comparison views and
    /// the metrics.
    fn reference_ui(&mut self, ui: &mut egui::Ui, canvas: Option<&Canvas>) {
        ui.heading("Reference");
        ui.horizontal(|ui| {
            let field = ui.add(egui::TextEdit::singleline(&mut self.path).desired_width(180.0));
            let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            let load = ui.button("Load").on_hover_text("an OpenEXR (linear) or PNG (sRGB) image");
            if load.clicked() || enter {
                self.load(ui.ctx(), PathBuf::from(self.path.trim()));
            }
        });
        let finished = canvas.is_some_and(Canvas::is_complete);
        if ui
            .add_enabled(finished, egui::Button::new("Use the current render as reference"))
            .on_hover_text("compare the next renders with this one")
            .clicked()
        {
            self.use_render(canvas);
        }
        if let Some(l) = &self.loading {
            ui.small(format!("loading {} …", l.path().display()));
        }
        if let Some(r) = &self.reference {
            let [w, h] = r.size();
            ui.small(format!("reference: {} ({w} × {h})", r.name()));
            ui.horizontal(|ui| {
                ui.selectable_value(&mut self.compare, Compare::Off, "render");
                ui.selectable_value(&mut self.compare, Compare::Split, "A | B")
                    .on_hover_text("render left, reference right: drag the line");
                ui.selectable_value(&mut self.compare, Compare::Absolute, "|a−b|")
                    .on_hover_text("absolute error, per channel");
                ui.selectable_value(&mut self.compare, Compare::Relative, "|a−b|/(b+ε)")
                    .on_hover_text("relative error per channel, ε = 0.01");
            });
            match self.last_metrics {
                Some(m) => {
                    ui.monospace(format!(
                        "RMSE {}  relMSE {}",
                        short(m.rmse as f32),
                        short(m.relative_mse as f32)
                    ));
                    ui.small(format!("over {} pixels rendered so far", m.pixels));
                }
                None => {
                    ui.small("RMSE: once the full-size render has rows");
                }
            }
        }
        for m in [&self.message, &self.mismatch].into_iter().flatten() {
            ui.colored_label(Color32::from_rgb(220, 60, 50), m);
        }
    }
}

/// `v` with four significant digits, never "-0".
fn short(v: f32) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if (1e-3..1e4).contains(&v.abs()) {
        let decimals = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// Draws `h`: the luminance as grey bars, each channel as a line in its
/// colour, over log2 from the range's low end to its high end.
fn histogram_ui(ui: &mut egui::Ui, h: &Histogram) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(280.0), 70.0), Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(20));
    let max = h.counts.iter().flatten().copied().max().unwrap_or(0).max(1) as f32;
    let bin_width = rect.width() / BINS as f32;
    let y = |count: u32| rect.bottom() - (count as f32 / max).sqrt() * (rect.height() - 2.0);
    for (i, &count) in h.counts[0].iter().enumerate() {
        if count > 0 {
            let x = rect.left() + i as f32 * bin_width;
            let bar = Rect::from_min_max(pos2(x, y(count)), pos2(x + bin_width, rect.bottom()));
            painter.rect_filled(bar, 0.0, Color32::from_gray(150));
        }
    }
    let colours =
        [Color32::from_rgb(230, 80, 70), Color32::from_rgb(90, 200, 90), Color32::from_rgb(90, 130, 240)];
    for (counts, colour) in h.counts[1..].iter().zip(colours) {
        let points: Vec<Pos2> = counts
            .iter()
            .enumerate()
            .map(|(i, &c)| pos2(rect.left() + (i as f32 + 0.5) * bin_width, y(c)))
            .collect();
        painter.add(egui::Shape::line(points, Stroke::new(1.0, colour)));
    }
    let black = h.not_positive[0];
    ui.small(format!(
        "log2 Y {} to {} (√ count) · {} px{}",
        short(h.range[0]),
        short(h.range[1]),
        h.pixels,
        if black > 0 { format!(", {black} black") } else { String::new() }
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers_keep_four_digits_and_never_read_minus_zero() {
        assert_eq!(short(-0.0), "0");
        assert_eq!(short(0.0123456), "0.01235");
        assert_eq!(short(1234.4), "1234");
        assert_eq!(short(-3.25), "-3.250");
        assert_eq!(short(2.5e-5), "2.500e-5");
    }
}
