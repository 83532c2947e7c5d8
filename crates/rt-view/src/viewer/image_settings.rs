//! The image section of the side panel: resolution scale, samples per pixel
//! (or no limit, with a target to estimate the time to), and the effects
//! the user has switched off.
//!
//! Effects the scene does not use are shown unticked and disabled, whatever
//! the user chose for scenes that use them ("not used by this scene" on
//! hover). The resolution scale is the user's, kept from scene to scene and
//! from run to run; opening a scene at a scale other than 1 says so.

use std::ops::RangeInclusive;

use rt_core::LoadedScene;
use rt_core::camera::view_plane::MAX_IMAGE_SIDE;
use rt_core::sampling::sampler::MAX_OPEN_ENDED_SAMPLES;
use rt_core::scene::effects::{EffectPlan, EffectToggles};

use super::interaction::Interaction;

/// Why the direct tracer's effects are disabled while path tracing.
const DIRECT_ONLY: &str = "done by path tracing its own way while global illumination is on";

/// The target samples per pixel until the user sets one.
const DEFAULT_TARGET_SPP: u32 = 4096;

/// The range of the resolution scale.
pub const RESOLUTION_SCALE: RangeInclusive<f32> = 0.25..=2.0;

/// What the full-resolution render is made of, besides the camera.
pub(super) struct ImageSettings {
    /// The image size is the scene's times this, in [`RESOLUTION_SCALE`].
    resolution_scale: f32,
    /// Samples per pixel of full renders (the scene's until the user changes it).
    spp: u32,
    /// Render until stopped instead of to `spp`.
    no_limit: bool,
    /// Samples per pixel to estimate the time to, with no limit.
    target_spp: u32,
    /// Effects the user has switched off.
    toggles: EffectToggles,
    /// Denoise each pass of full renders with OIDN (where it is present).
    denoise: bool,
}

impl ImageSettings {
    /// The settings for `scene`: its size and samples, every effect on.
    pub fn new(scene: &LoadedScene) -> Self {
        Self {
            resolution_scale: 1.0,
            spp: scene.settings.samples.get(),
            no_limit: false,
            target_spp: DEFAULT_TARGET_SPP,
            toggles: EffectToggles::default(),
            denoise: false,
        }
    }

    /// A new scene was loaded: its sample count is taken if `reset` (a scene
    /// opened) or if the file's count changed (otherwise the user's choice
    /// stays). Returns a note for an opened scene shown at a resolution
    /// scale other than 1: the scale stays the user's (it is remembered
    /// from run to run too), so the new scene's size is not the file's.
    pub fn scene_loaded(
        &mut self,
        scene: &LoadedScene,
        previous: &LoadedScene,
        reset: bool,
    ) -> Option<String> {
        if reset || scene.settings.samples != previous.settings.samples {
            self.spp = scene.settings.samples.get();
        }
        (reset && self.resolution_scale != 1.0).then(|| {
            let (w, h) = self.full_size(scene);
            let file = scene.settings.image;
            format!(
                "resolution scale {}× kept: {w} × {h} pixels (the file's {} × {})",
                self.resolution_scale,
                file.width(),
                file.height()
            )
        })
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

    /// Whether full renders go on until stopped.
    pub fn no_limit(&self) -> bool {
        self.no_limit
    }

    /// Renders until stopped (`true`) or to the sample count.
    #[cfg(test)]
    pub fn set_no_limit(&mut self, on: bool) {
        self.no_limit = on;
    }

    /// With no limit, the samples per pixel to show the time to.
    pub fn target_spp(&self) -> Option<u32> {
        self.no_limit.then_some(self.target_spp)
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

    /// Whether full renders are denoised ([`super::render_job::JobSpec::denoise`]).
    pub fn denoise(&self) -> bool {
        self.denoise
    }

    /// The Denoise checkbox: enabled where `oidn` (whether OIDN loads, or
    /// why not) is `Ok`, else disabled and unticked with the reason on
    /// hover. Returns whether it changed.
    fn denoise_ui(&mut self, ui: &mut egui::Ui, oidn: Result<(), String>) -> bool {
        let before = self.denoise;
        match oidn {
            Ok(()) => {
                ui.checkbox(&mut self.denoise, "denoise").on_hover_text(
                    "Denoise each refinement pass with Open Image Denoise, fed the albedo and normal of \
                     what each pixel sees; Save writes the denoised image shown",
                );
            }
            Err(why) => {
                self.denoise = false;
                ui.add_enabled(false, egui::Checkbox::new(&mut false, "denoise")).on_disabled_hover_text(why);
            }
        }
        self.denoise != before
    }

    /// The resolution, sample and effect controls.
    pub fn ui(&mut self, ui: &mut egui::Ui, scene: &LoadedScene) -> Interaction {
        ui.heading("Image");
        let r =
            ui.add(egui::Slider::new(&mut self.resolution_scale, RESOLUTION_SCALE).text("resolution scale"));
        let mut interaction = Interaction { changed: r.changed(), dragging: r.dragged() };
        let (w, h) = self.full_size(scene);
        let file = scene.settings.image;
        if (w, h) == (file.width(), file.height()) {
            ui.label(format!("{w} × {h} pixels"));
        } else {
            ui.label(format!("{w} × {h} pixels (the file's {} × {})", file.width(), file.height()));
        }
        let r = ui
            .add_enabled(
                !self.no_limit,
                egui::Slider::new(&mut self.spp, 1..=1024).logarithmic(true).text("samples per pixel"),
            )
            .on_hover_text("Anti-aliasing and soft-shadow quality: shows 1 sample first, then refines");
        interaction = interaction | Interaction { changed: r.changed(), dragging: r.dragged() };
        ui.horizontal(|ui| {
            interaction.changed |= ui
                .checkbox(&mut self.no_limit, "no limit")
                .on_hover_text("Keep adding samples until Stop (Space) or a change of view")
                .changed();
            if self.no_limit {
                ui.add(
                    egui::DragValue::new(&mut self.target_spp).range(1..=MAX_OPEN_ENDED_SAMPLES).speed(16),
                )
                .on_hover_text("The status line shows the time until every pixel has this many samples");
                ui.label("spp target");
            }
        });
        interaction.changed |= self.effects_ui(ui, &scene.scene.effect_plan(&scene.settings.effects));
        let oidn = crate::denoise::find_and_load().map(|_| ()).map_err(|e| e.to_string());
        interaction.changed |= self.denoise_ui(ui, oidn);
        interaction
    }

    /// Checkboxes for the effects the scene asks for; the others are shown
    /// disabled, and unticked if the scene does not use them. Returns
    /// whether one changed.
    fn effects_ui(&mut self, ui: &mut egui::Ui, asked: &EffectPlan) -> bool {
        let before = self.toggles;
        let t = &mut self.toggles;
        // Path tracing does all of the direct tracer's effects its own way:
        // their boxes only matter with global illumination off.
        let direct = (asked.global_illumination.is_some() && t.global_illumination).then_some(DIRECT_ONLY);
        let needs_gi = (!t.global_illumination).then_some("needs global illumination");
        ui.horizontal_wrapped(|ui| {
            let gi = asked.global_illumination.is_some();
            effect_box(ui, &mut t.global_illumination, "global illumination", gi, None).on_hover_text(
                "Path tracing: light bounces between surfaces, glass lets light through, emissive objects and the background light the scene",
            );
            effect_box(ui, &mut t.subsurface, "subsurface", asked.subsurface, needs_gi)
                .on_hover_text("Random walks through translucent objects; off, their materials act as plain surfaces");
            effect_box(ui, &mut t.shadows, "shadows", asked.shadows, direct);
            effect_box(ui, &mut t.reflection, "reflection", asked.reflection, direct);
            effect_box(ui, &mut t.refraction, "refraction", asked.refraction, direct);
            let ao = asked.ambient_occlusion.is_some();
            effect_box(ui, &mut t.ambient_occlusion, "ambient occlusion", ao, direct);
        });
        if !asked.shading {
            ui.small("No lights: flat colours (pure ray casting).");
        }
        self.toggles != before
    }
}

/// An effect's checkbox: disabled and unticked where the scene does not use
/// the effect (the user's choice is kept for scenes that do), disabled as it
/// is where `blocked` says why.
fn effect_box(
    ui: &mut egui::Ui,
    value: &mut bool,
    label: &str,
    used: bool,
    blocked: Option<&str>,
) -> egui::Response {
    if !used {
        let mut unused = false;
        return ui
            .add_enabled(false, egui::Checkbox::new(&mut unused, label))
            .on_disabled_hover_text("not used by this scene");
    }
    let response = ui.add_enabled(blocked.is_none(), egui::Checkbox::new(value, label));
    match blocked {
        Some(why) => response.on_disabled_hover_text(why),
        None => response,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::accesskit::Toggled;
    use std::path::Path;

    fn scene(name: &str) -> LoadedScene {
        rt_core::load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name)).unwrap()
    }

    /// Each checkbox of the panel drawn for `scene`, by label: (ticked, enabled).
    fn checkboxes(settings: &mut ImageSettings, scene: &LoadedScene) -> Vec<(String, bool, bool)> {
        let ctx = egui::Context::default();
        ctx.enable_accesskit();
        let mut output = ctx.run_ui(egui::RawInput::default(), |ui| {
            settings.ui(ui, scene);
        });
        output.textures_delta.clear();
        ctx.tex_manager().write().take_delta().clear();
        let update = output.platform_output.accesskit_update.expect("accesskit is on");
        update
            .nodes
            .iter()
            .filter_map(|(_, node)| {
                let ticked = node.toggled()?;
                Some((node.label()?.to_owned(), ticked == Toggled::True, !node.is_disabled()))
            })
            .collect()
    }

    fn state(boxes: &[(String, bool, bool)], label: &str) -> (bool, bool) {
        let (_, ticked, enabled) =
            boxes.iter().find(|(l, ..)| l == label).unwrap_or_else(|| panic!("{label}: {boxes:?}"));
        (*ticked, *enabled)
    }

    #[test]
    fn effects_the_scene_does_not_use_are_shown_unticked_and_disabled_and_the_users_choice_stays() {
        // Before, effects.ron showed "global illumination" greyed out but ticked.
        let effects = scene("effects.ron");
        let mut settings = ImageSettings::new(&effects);
        let boxes = checkboxes(&mut settings, &effects);
        assert_eq!(state(&boxes, "global illumination"), (false, false));
        assert_eq!(state(&boxes, "subsurface"), (false, false));
        assert_eq!(state(&boxes, "shadows"), (true, true));
        // A scene that uses them: ticked and enabled, as the toggles say.
        let cornell = scene("cornell_box.ron");
        let boxes = checkboxes(&mut settings, &cornell);
        assert_eq!(state(&boxes, "global illumination"), (true, true));
        assert!(settings.toggles().global_illumination);
        assert_eq!(state(&boxes, "no limit"), (false, true));
    }

    /// The Denoise checkbox drawn with `oidn` as the library's state:
    /// (ticked, enabled, whether clicking it changed the setting).
    fn denoise_box(
        settings: &mut ImageSettings,
        oidn: Result<(), String>,
        click: bool,
    ) -> (bool, bool, bool) {
        let ctx = egui::Context::default();
        ctx.enable_accesskit();
        let mut changed = false;
        let mut run = |input: egui::RawInput, changed: &mut bool| {
            let mut output = ctx.run_ui(input, |ui| *changed |= settings.denoise_ui(ui, oidn.clone()));
            output.textures_delta.clear();
            ctx.tex_manager().write().take_delta().clear();
            output
        };
        let output = run(egui::RawInput::default(), &mut changed);
        let update = output.platform_output.accesskit_update.expect("accesskit is on");
        let (id, node) = update.nodes.iter().find(|(_, n)| n.label() == Some("denoise")).expect("the box");
        let (ticked, enabled) = (node.toggled() == Some(Toggled::True), !node.is_disabled());
        if click {
            let request = egui::accesskit::ActionRequest {
                action: egui::accesskit::Action::Click,
                target_node: *id,
                target_tree: egui::accesskit::TreeId::ROOT,
                data: None,
            };
            let input = egui::RawInput {
                events: vec![egui::Event::AccessKitActionRequest(request)],
                ..Default::default()
            };
            run(input, &mut changed);
        }
        (ticked, enabled, changed)
    }

    #[test]
    fn the_denoise_box_toggles_where_oidn_loads_and_is_disabled_and_off_where_it_does_not() {
        let cornell = scene("cornell_box.ron");
        let mut settings = ImageSettings::new(&cornell);
        assert_eq!(denoise_box(&mut settings, Ok(()), true), (false, true, true));
        assert!(settings.denoise());
        assert_eq!(denoise_box(&mut settings, Ok(()), false), (true, true, false));
        // Without the library: off, and a click does nothing.
        let absent = Err("OIDN not found (looked in …); run scripts/get_oidn.sh".to_owned());
        let (ticked, enabled, _) = denoise_box(&mut settings, absent.clone(), true);
        assert_eq!((ticked, enabled, settings.denoise()), (false, false, false));
    }

    #[test]
    fn opening_a_scene_at_another_resolution_scale_says_so_and_a_reload_does_not() {
        let (effects, cornell) = (scene("effects.ron"), scene("cornell_box.ron"));
        let mut settings = ImageSettings::new(&effects);
        assert_eq!(settings.scene_loaded(&cornell, &effects, true), None);
        settings.set_resolution_scale(2.0);
        let note = settings.scene_loaded(&cornell, &effects, true).expect("a note");
        let (w, h) = (cornell.settings.image.width(), cornell.settings.image.height());
        assert!(note.contains(&format!("{} × {} pixels (the file's {w} × {h})", 2 * w, 2 * h)), "{note}");
        assert_eq!(settings.scene_loaded(&cornell, &cornell, false), None);
        assert_eq!(settings.resolution_scale(), 2.0, "the scale stays the user's");
    }

    #[test]
    fn no_limit_gives_a_target_and_greys_out_the_sample_count() {
        let effects = scene("effects.ron");
        let mut settings = ImageSettings::new(&effects);
        assert_eq!((settings.no_limit(), settings.target_spp()), (false, None));
        settings.no_limit = true;
        assert_eq!(settings.target_spp(), Some(DEFAULT_TARGET_SPP));
        let boxes = checkboxes(&mut settings, &effects);
        assert_eq!(state(&boxes, "no limit"), (true, true));
    }
}
