//! The image section of the side panel: resolution scale, samples per pixel
//! and the effects the user has switched off.

use std::ops::RangeInclusive;

use rt_core::LoadedScene;
use rt_core::camera::view_plane::MAX_IMAGE_SIDE;
use rt_core::scene::effects::{EffectPlan, EffectToggles};

use super::interaction::Interaction;

/// The range of the resolution scale.
pub const RESOLUTION_SCALE: RangeInclusive<f32> = 0.25..=2.0;

/// What the full-resolution render is made of, besides the camera.
pub(super) struct ImageSettings {
    /// The image size is the scene's times this, in [`RESOLUTION_SCALE`].
    resolution_scale: f32,
    /// Samples per pixel of full renders (the scene's until the user changes it).
    spp: u32,
    /// Effects the user has switched off.
    toggles: EffectToggles,
}

impl ImageSettings {
    /// The settings for `scene`: its size and samples, every effect on.
    pub fn new(scene: &LoadedScene) -> Self {
        Self { resolution_scale: 1.0, spp: scene.settings.samples.get(), toggles: EffectToggles::default() }
    }

    /// A new scene was loaded: its sample count is taken if `reset` or if the
    /// file's count changed (otherwise the user's choice stays).
    pub fn scene_loaded(&mut self, scene: &LoadedScene, previous: &LoadedScene, reset: bool) {
        if reset || scene.settings.samples != previous.settings.samples {
            self.spp = scene.settings.samples.get();
        }
    }

    /// The image size as a multiple of the scene's.
    pub fn resolution_scale(&self) -> f32 {
        self.resolution_scale
    }

    /// Sets the resolution scale (brought into [`RESOLUTION_SCALE`]).
    pub fn set_resolution_scale(&mut self, scale: f32) {
        self.resolution_scale = scale.clamp(*RESOLUTION_SCALE.start(), *RESOLUTION_SCALE.end());
    }

    /// Samples per pixel of full renders.
    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Full-resolution image size: the scene's, times the resolution scale.
    pub fn full_size(&self, scene: &LoadedScene) -> (u32, u32) {
        let scale = |n: u32| ((n as f32 * self.resolution_scale).round() as u32).clamp(1, MAX_IMAGE_SIDE);
        let image = scene.settings.image;
        (scale(image.width()), scale(image.height()))
    }

    /// The effects the user has switched off.
    pub fn toggles(&self) -> EffectToggles {
        self.toggles
    }

    /// The resolution, sample and effect controls.
    pub fn ui(&mut self, ui: &mut egui::Ui, scene: &LoadedScene) -> Interaction {
        ui.heading("Image");
        let r =
            ui.add(egui::Slider::new(&mut self.resolution_scale, RESOLUTION_SCALE).text("resolution scale"));
        let mut interaction = Interaction { changed: r.changed(), dragging: r.dragged() };
        let (w, h) = self.full_size(scene);
        ui.label(format!("{w} × {h} pixels"));
        let r = ui
            .add(egui::Slider::new(&mut self.spp, 1..=1024).logarithmic(true).text("samples per pixel"))
            .on_hover_text("Anti-aliasing and soft-shadow quality: shows 1 sample first, then refines");
        interaction = interaction | Interaction { changed: r.changed(), dragging: r.dragged() };
        interaction.changed |= self.effects_ui(ui, &scene.scene.effect_plan(&scene.settings.effects));
        interaction
    }

    /// Checkboxes for the effects the scene asks for (the others are shown
    /// disabled). Returns whether one changed.
    fn effects_ui(&mut self, ui: &mut egui::Ui, asked: &EffectPlan) -> bool {
        let before = self.toggles;
        let t = &mut self.toggles;
        // Path tracing does all of the direct tracer's effects its own way:
        // their boxes only matter with global illumination off.
        let direct = asked.global_illumination.is_none() || !t.global_illumination;
        ui.horizontal_wrapped(|ui| {
            ui.add_enabled(
                asked.global_illumination.is_some(),
                egui::Checkbox::new(&mut t.global_illumination, "global illumination"),
            )
            .on_hover_text("Path tracing: light bounces between surfaces, glass lets light through, emissive objects and the background light the scene");
            ui.add_enabled(
                asked.subsurface && t.global_illumination,
                egui::Checkbox::new(&mut t.subsurface, "subsurface"),
            )
            .on_hover_text("Random walks through translucent objects; off, their materials act as plain surfaces");
            ui.add_enabled(direct && asked.shadows, egui::Checkbox::new(&mut t.shadows, "shadows"));
            ui.add_enabled(direct && asked.reflection, egui::Checkbox::new(&mut t.reflection, "reflection"));
            ui.add_enabled(direct && asked.refraction, egui::Checkbox::new(&mut t.refraction, "refraction"));
            ui.add_enabled(
                direct && asked.ambient_occlusion.is_some(),
                egui::Checkbox::new(&mut t.ambient_occlusion, "ambient occlusion"),
            );
        });
        if !asked.shading {
            ui.small("No lights: flat colours (pure ray casting).");
        }
        self.toggles != before
    }
}
