//! The scene view: the scene seen by an observer camera the user orbits
//! (drag), pans (Shift-, right- or middle-drag) and zooms (wheel), with the
//! render camera, its view plane, frustum and lights drawn over it
//! ([`camera_overlay`]) and, for the pinned pixel, its light path
//! ([`PixelPath`]).
//!
//! The image under the overlays is rt-core's flat render of the scene
//! ([`observer_render`]), made by an [`ObserverJob`] on a thread of its own
//! at a modest resolution (a third of it while the observer moves); the
//! UI thread only polls the job and draws the last image it finished,
//! starting the next job once the one in flight is done, so a drag never
//! queues up renders. The overlays are drawn every frame with the
//! observer's [`Projection`]: moving the render camera's sliders moves
//! them at once.
//!
//! With a pixel pinned, the record of one of its samples (chosen in the
//! view's header) is computed off the UI thread ([`RecordJob`]) and its
//! whole path drawn; until it arrives, the primary ray is.
//!
//! Closed, the view costs nothing: no job runs, no texture or record is
//! kept, and nothing is computed in the frame ([`SceneView::renders_started`]
//! counts the jobs, for the tests and the trace).

use std::sync::Arc;

use egui::{Color32, Rect, Sense, TextureHandle, TextureOptions, Vec2};
use rt_core::{Camera, LoadedScene, Real, Vec3, ViewPlane};

use super::camera_controls::CameraSettings;
use super::camera_overlay::{self, CameraScene};
use super::observer::Observer;
use super::observer_render::ObserverJob;
use super::path_overlay::PixelPath;
use super::projection::Projection;
use super::record_job::{RecordJob, RecordKey};
use super::render_job::JobSpec;
use rt_core::explain::record::PathRecord;

/// The flat render's longer side, in pixels, when the observer is still.
const STILL_SIDE: f32 = 480.0;
/// While the observer moves, the flat render is this many times smaller.
const MOVING_DIVISOR: f32 = 3.0;
/// Radians of orbit per point of mouse movement.
const ORBIT_PER_POINT: f32 = 0.01;
/// Zoom factor per point of wheel scroll (as an exponent).
const ZOOM_PER_POINT: f32 = 0.002;
/// Background of the view before its first image arrives.
const BACKGROUND: Color32 = Color32::from_rgb(40, 42, 46);

/// What a flat render shows: the scene (by identity), the observer and
/// the image's size.
#[derive(Clone, Debug, PartialEq)]
struct RenderKey {
    scene: usize,
    observer: CameraSettings,
    size: [u32; 2],
}

/// What the scene view draws besides the scene: the render camera and
/// image size, and the pinned pixel.
pub(super) struct ViewInput<'a> {
    /// The scene on show.
    pub scene: &'a Arc<LoadedScene>,
    /// The render camera (`None` while its settings are invalid).
    pub camera: Option<Camera>,
    /// The rendered image's size in pixels.
    pub image_size: (u32, u32),
    /// The pinned pixel of the image, if any.
    pub pinned: Option<[u32; 2]>,
    /// The full-resolution render (whose samples are recorded), if any.
    pub spec: Option<JobSpec>,
}

/// Lengths that make the overlays read well in a scene: its bounded
/// objects' box, and from it a middle and a unit length.
#[derive(Clone, Copy, Debug)]
pub(super) struct SceneExtent {
    /// The bounded objects' box (min, max), if there are any.
    pub bounds: Option<(Vec3, Vec3)>,
}

impl SceneExtent {
    /// The extent of `scene`'s bounded objects.
    pub fn of(scene: &rt_core::Scene) -> Self {
        let boxes = scene.objects().iter().filter_map(|o| o.primitive.bounds());
        let bounds = boxes.map(|b| (b.min(), b.max())).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        Self { bounds: bounds.filter(|(a, b)| a.is_finite() && b.is_finite()) }
    }

    /// The camera overlay's scene for `view`: frustum out past the scene's
    /// far side, axes a fifth of the camera-to-COI distance long.
    pub fn camera_scene<'a>(&self, view: &'a ViewPlane, lights: &'a [rt_core::Light]) -> CameraScene<'a> {
        let camera = view.camera();
        let (c, z) = (camera.position(), camera.basis().z);
        let span = (camera.center_of_interest() - c).length();
        let (middle, reach) = match self.bounds {
            Some((lo, hi)) => {
                let corners = (0..8).map(|i| {
                    Vec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    )
                });
                let far = corners.map(|q| (q - c).dot(z)).fold(0.0 as Real, Real::max);
                (0.5 * (lo + hi), far.max(span) * 1.1)
            }
            None => (camera.center_of_interest(), span * 2.0),
        };
        CameraScene { view, reach, lights, middle, unit: (0.2 * span).max(camera.near()) }
    }
}

/// Draws everything the scene view shows over its image, as `projection`
/// sees it; returns the hovered path segment, if any.
pub(super) fn draw_overlays(
    painter: &egui::Painter,
    projection: &Projection,
    input: &ViewInput<'_>,
    extent: &SceneExtent,
    record: Option<&PathRecord>,
    pointer: Option<egui::Pos2>,
) -> Option<usize> {
    let camera = input.camera?;
    let (w, h) = input.image_size;
    let view = ViewPlane::new(camera, w, h).ok()?;
    let scene = &input.scene.scene;
    let overlay = extent.camera_scene(&view, scene.lights());
    camera_overlay::draw(painter, projection, &overlay);
    let pixel = input.pinned.filter(|&[x, y]| x < w && y < h)?;
    let path = match record.filter(|r| r.pixel == pixel) {
        Some(record) => PixelPath::from_record(record, overlay.unit, overlay.reach),
        None => PixelPath::primary(&view, scene, pixel, overlay.unit, overlay.reach),
    };
    path.draw(painter, projection, pointer)
}

/// The scene view's state (see the module's docs).
#[derive(Default)]
pub(super) struct SceneView {
    open: bool,
    observer: Option<Observer>,
    /// The scene (by identity) whose extent is known, and its extent.
    extent: Option<(usize, SceneExtent)>,
    job: Option<(ObserverJob, RenderKey)>,
    texture: Option<(TextureHandle, RenderKey)>,
    renders_started: u64,
    /// The pinned pixel's sample whose path is drawn.
    sample: u32,
    record_job: Option<RecordJob>,
    /// The last record (or why there is none) and what it records.
    record: Option<(RecordKey, Result<PathRecord, String>)>,
}

impl SceneView {
    /// Whether the view is shown.
    pub fn is_open(&self) -> bool {
        self.open
    }

    /// Shows the view, or hides it and drops its job and image.
    pub fn set_open(&mut self, open: bool) {
        self.open = open;
        if !open {
            self.job = None;
            self.texture = None;
            self.record_job = None;
            self.record = None;
        }
    }

    /// Shows or hides the view.
    pub fn toggle(&mut self) {
        self.set_open(!self.open);
    }

    /// How many flat renders the view has started.
    pub fn renders_started(&self) -> u64 {
        self.renders_started
    }

    /// Whether a flat render is in flight.
    #[cfg(test)]
    pub fn rendering(&self) -> bool {
        self.job.is_some() || self.record_job.is_some()
    }

    /// The pixel of the record drawn, once it has arrived.
    #[cfg(test)]
    pub fn record_pixel(&self) -> Option<[u32; 2]> {
        self.record.as_ref().and_then(|(_, r)| r.as_ref().ok()).map(|r| r.pixel)
    }

    /// The observer, once the view has been shown.
    #[cfg(test)]
    pub fn observer(&self) -> Option<&Observer> {
        self.observer.as_ref()
    }

    /// A new scene is shown: the observer frames it afresh.
    pub fn scene_changed(&mut self) {
        self.observer = None;
        self.extent = None;
        self.job = None;
        self.record_job = None;
        self.record = None;
    }

    /// The button that shows and hides the view (side panel).
    pub fn toggle_ui(&mut self, ui: &mut egui::Ui) {
        let open = self.open;
        if ui
            .selectable_label(open, "Scene view")
            .on_hover_text("3: the scene in 3D, the camera and the pinned pixel's path")
            .clicked()
        {
            self.toggle();
        }
    }

    /// The view, filling `ui`'s space: input, jobs, image and overlays.
    pub fn ui(&mut self, ui: &mut egui::Ui, input: &ViewInput<'_>) {
        let scene_id = Arc::as_ptr(input.scene) as usize;
        let extent = match self.extent {
            Some((id, extent)) if id == scene_id => extent,
            _ => {
                let extent = SceneExtent::of(&input.scene.scene);
                self.extent = Some((scene_id, extent));
                extent
            }
        };
        ui.horizontal(|ui| {
            ui.strong("Scene view");
            if ui
                .small_button("Frame")
                .on_hover_text("the observer sees the camera and the scene again")
                .clicked()
            {
                self.observer = None;
            }
            if let (Some(_), Some(spec)) = (input.pinned, &input.spec) {
                ui.separator();
                ui.label("sample");
                let last = spec.spp.saturating_sub(1);
                ui.add(egui::DragValue::new(&mut self.sample).range(0..=last))
                    .on_hover_text("which of the pinned pixel's samples to follow");
                self.sample = self.sample.min(last);
                match &self.record {
                    Some((_, Ok(r))) => {
                        let [r, g, b] = r.value.to_array();
                        ui.small(format!("value ({r:.4}, {g:.4}, {b:.4})"));
                    }
                    Some((_, Err(e))) => {
                        ui.small(e.as_str());
                    }
                    None => {}
                }
            } else {
                ui.small("drag: orbit · Shift/right drag: pan · wheel: zoom · click a pixel: its path");
            }
        });
        let wanted = input
            .pinned
            .zip(input.spec.as_ref())
            .map(|(p, spec)| (RecordKey::new(spec, p, self.sample), spec));
        self.poll_record(ui.ctx(), wanted);
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let camera = input.camera.unwrap_or(input.scene.camera);
        let aspect = (rect.width() / rect.height().max(1.0)) as Real;
        let observer = self.observer.get_or_insert_with(|| Observer::framing(&camera, extent.bounds, aspect));
        let moving = steer(ui, &response, observer);
        let observer = *observer;
        let ppp = ui.ctx().pixels_per_point();
        let size = render_size(rect.size() * ppp, moving);
        let key = RenderKey { scene: scene_id, observer: *observer.settings(), size };
        self.poll(ui.ctx());
        if self.texture.as_ref().is_none_or(|(_, k)| *k != key) && self.job.is_none() {
            self.start(ui.ctx(), input.scene, &observer, key);
        }
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, BACKGROUND);
        if let Some((texture, _)) = &self.texture {
            let uv = Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            painter.image(texture.id(), rect, uv, Color32::WHITE);
        }
        let Some(projection) = observer.camera().and_then(|c| Projection::new(c, size, rect)) else { return };
        let record = self.record.as_ref().and_then(|(_, r)| r.as_ref().ok());
        draw_overlays(&painter, &projection, input, &extent, record, response.hover_pos());
    }

    /// Takes a finished record; starts recording `wanted` (the pinned
    /// pixel's chosen sample of the render) once no other is in flight;
    /// forgets the record when no pixel is pinned.
    fn poll_record(&mut self, ctx: &egui::Context, wanted: Option<(RecordKey, &JobSpec)>) {
        if let Some(job) = &self.record_job
            && let Some(record) = job.take()
        {
            self.record = Some((job.key().clone(), record));
            self.record_job = None;
        }
        let Some((key, spec)) = wanted else {
            self.record = None;
            return;
        };
        let have = self.record.as_ref().is_some_and(|(k, _)| *k == key);
        let pending = self.record_job.as_ref().is_some_and(|j| *j.key() == key);
        if !have && !pending && self.record_job.is_none() {
            let repaint = ctx.clone();
            self.record_job = Some(RecordJob::start(spec, key.clone(), move || repaint.request_repaint()));
        }
        if self.record.as_ref().is_some_and(|(k, _)| k.pixel != key.pixel) {
            self.record = None;
        }
    }

    /// Takes a finished image into the texture; forgets a job that ended.
    fn poll(&mut self, ctx: &egui::Context) {
        let Some((job, key)) = &self.job else { return };
        if let Some(image) = job.take() {
            let key = key.clone();
            match &mut self.texture {
                Some((texture, shown)) => {
                    texture.set(image, TextureOptions::LINEAR);
                    *shown = key;
                }
                None => {
                    self.texture = Some((ctx.load_texture("scene view", image, TextureOptions::LINEAR), key))
                }
            }
            self.job = None;
        } else if job.ended() {
            self.job = None;
        }
    }

    fn start(&mut self, ctx: &egui::Context, scene: &Arc<LoadedScene>, observer: &Observer, key: RenderKey) {
        let Some(camera) = observer.camera() else { return };
        let repaint = ctx.clone();
        let job = ObserverJob::start(scene.clone(), camera, key.size, move || repaint.request_repaint());
        self.renders_started += 1;
        self.job = Some((job, key));
    }
}

/// Orbit, pan and zoom from this frame's input; returns whether the
/// observer is being moved (the flat render then goes smaller).
fn steer(ui: &egui::Ui, response: &egui::Response, observer: &mut Observer) -> bool {
    let delta = response.drag_delta();
    let dragging = response.dragged();
    if dragging && delta != Vec2::ZERO {
        let pan = ui.input(|i| i.modifiers.shift)
            || response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle);
        let height = response.rect.height().max(1.0);
        if pan {
            observer.pan((-delta.x / height) as Real, (delta.y / height) as Real);
        } else {
            observer.orbit((-delta.x * ORBIT_PER_POINT) as Real, (-delta.y * ORBIT_PER_POINT) as Real);
        }
    }
    let scroll = if response.hovered() { ui.input(|i| i.smooth_scroll_delta.y) } else { 0.0 };
    if scroll != 0.0 {
        observer.zoom((-scroll * ZOOM_PER_POINT).exp() as Real);
    }
    dragging || scroll != 0.0
}

/// The flat render's size for a view `physical` pixels large: its shape,
/// the longer side [`STILL_SIDE`] (or less, if the view is smaller), and
/// [`MOVING_DIVISOR`] times smaller while the observer moves.
fn render_size(physical: Vec2, moving: bool) -> [u32; 2] {
    let longer = physical.x.max(physical.y).max(1.0);
    let mut scale = (STILL_SIDE / longer).min(1.0);
    if moving {
        scale /= MOVING_DIVISOR;
    }
    [(physical.x * scale).round().max(1.0) as u32, (physical.y * scale).round().max(1.0) as u32]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flat_render_keeps_the_views_shape_and_shrinks_while_moving() {
        assert_eq!(render_size(egui::vec2(960.0, 720.0), false), [480, 360]);
        assert_eq!(render_size(egui::vec2(960.0, 720.0), true), [160, 120]);
        assert_eq!(render_size(egui::vec2(300.0, 200.0), false), [300, 200]);
    }

    #[test]
    fn hovering_the_primary_ray_in_the_view_picks_it_and_elsewhere_nothing() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sphere.ron");
        let scene = Arc::new(rt_core::load_scene(&path).unwrap());
        let input = ViewInput {
            scene: &scene,
            camera: Some(scene.camera),
            image_size: (320, 240),
            pinned: Some([160, 120]),
            spec: None,
        };
        let extent = SceneExtent::of(&scene.scene);
        let screen = Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(400.0, 300.0));
        let observer = Observer::framing(&scene.camera, extent.bounds, 400.0 / 300.0);
        let projection = Projection::new(observer.camera().unwrap(), [400, 300], screen).unwrap();
        let ray = ViewPlane::new(scene.camera, 320, 240).unwrap().center_ray(160, 120);
        let hit = scene.scene.cast(&ray).unwrap();
        let [a, b] = projection.segment(ray.origin, ray.at(hit.t)).unwrap();
        let ctx = egui::Context::default();
        let hovered = |pointer: egui::Pos2| {
            let mut found = None;
            let raw = egui::RawInput { screen_rect: Some(screen), ..Default::default() };
            let mut output = ctx.run_ui(raw, |ui| {
                let painter = ui.painter_at(screen);
                found = draw_overlays(&painter, &projection, &input, &extent, None, Some(pointer));
            });
            output.textures_delta.clear();
            found
        };
        assert_eq!(hovered(a + (b - a) * 0.5 + egui::vec2(0.0, 2.0)), Some(0), "the primary ray");
        assert_eq!(hovered(egui::pos2(2.0, 298.0)), None);
    }
}
