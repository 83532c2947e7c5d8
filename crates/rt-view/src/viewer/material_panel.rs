//! The material panel: the material of the object under the pinned pixel,
//! every value it holds, and live edits of its base colour, metallic,
//! roughness and index of refraction.
//!
//! An edit makes a new scene with that one material replaced
//! ([`rt_core::Scene::with_material`]: the objects, BVH and emitters are
//! shared, nothing is loaded or rebuilt), which the window renders as after
//! a camera move: a preview while a slider is dragged, the full image once
//! it rests. The scene as loaded is kept, for Revert. Edits live in the
//! viewer only: the scene file is never written, and loading the file
//! again (F5, a save seen by the watcher, Open) drops them.

use std::collections::BTreeSet;
use std::sync::Arc;

use egui::Color32;
use rt_core::materials::texture_slot::TextureSlot;
use rt_core::{LoadedScene, Material};

use super::interaction::Interaction;

/// Why metallic and roughness cannot be edited on a classic material.
const CLASSIC_HOVER: &str = "Physically based materials only: this material uses the classic weights \
     (diffuse, specular, reflectivity, transparency), which have no metallic or roughness parameter.";

/// The panel's state: the scene before the first edit, and which materials
/// were edited since.
#[derive(Default)]
pub(super) struct MaterialPanel {
    /// The scene as loaded from its file (`None`: nothing edited).
    original: Option<Arc<LoadedScene>>,
    /// The indices of the materials edited.
    edited: BTreeSet<usize>,
    /// Why the last edit was refused, if it was.
    error: Option<String>,
    /// Where the roughness slider and Revert were drawn (tests drive them).
    #[cfg(test)]
    pub drawn: Drawn,
}

/// Where the panel's controls were last drawn.
#[cfg(test)]
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Drawn {
    pub roughness: Option<egui::Rect>,
    pub revert: Option<egui::Rect>,
}

/// What the panel did this frame: the scene to render from now on, if an
/// edit or Revert changed it, and how (a drag previews).
pub(super) struct Edit {
    pub scene: Arc<LoadedScene>,
    pub interaction: Interaction,
}

impl MaterialPanel {
    /// A scene came from the file: edits of the one before are gone.
    /// Returns whether there were any (the window says so).
    pub fn scene_loaded(&mut self) -> bool {
        self.error = None;
        self.edited.clear();
        self.original.take().is_some()
    }

    /// Whether material `index` was edited since the scene was loaded.
    pub fn is_edited(&self, index: usize) -> bool {
        self.edited.contains(&index)
    }

    /// The panel for the material of `object` of `scene` (`None`: no pixel
    /// pinned on an object): its name and values, the editors and Revert.
    pub fn ui(&mut self, ui: &mut egui::Ui, scene: &Arc<LoadedScene>, object: Option<usize>) -> Option<Edit> {
        #[cfg(test)]
        {
            self.drawn = Drawn::default();
        }
        ui.heading("Material");
        let Some(object) = object else {
            ui.weak("Click an object in the image to see its material.");
            return None;
        };
        let index = scene.scene.objects()[object].material;
        let material = *scene.scene.material(index);
        let name = &scene.scene.material_names()[index];
        ui.horizontal(|ui| {
            ui.label(egui::RichText::new(format!("\"{name}\"")).monospace());
            if self.is_edited(index) {
                ui.colored_label(Color32::from_rgb(200, 150, 40), "edited")
                    .on_hover_text("Changed in the viewer only: the scene file is not written.");
            }
        });
        egui::Grid::new("material values").num_columns(2).striped(true).show(ui, |ui| {
            for (what, value) in describe(&material) {
                ui.label(what);
                ui.monospace(value);
                ui.end_row();
            }
        });
        let (edited, dragging) = self.editors(ui, material);
        let reverted = self.revert_ui(ui, index);
        if let Some(e) = &self.error {
            ui.colored_label(Color32::from_rgb(220, 60, 50), e);
        }
        if reverted {
            return self.revert(scene, index);
        }
        let edited = edited?;
        match scene.scene.with_material(index, edited) {
            Ok(new) => {
                self.error = None;
                self.original.get_or_insert_with(|| scene.clone());
                self.edited.insert(index);
                let scene =
                    Arc::new(LoadedScene { scene: new, camera: scene.camera, settings: scene.settings });
                Some(Edit { scene, interaction: Interaction { changed: true, dragging } })
            }
            Err(e) => {
                self.error = Some(format!("not applied: {e}"));
                None
            }
        }
    }

    /// The colour picker and the sliders; returns the material edited (if
    /// a control changed it) and whether a slider is being dragged.
    fn editors(&mut self, ui: &mut egui::Ui, mut m: Material) -> (Option<Material>, bool) {
        let (mut changed, mut dragging) = (false, false);
        ui.horizontal(|ui| {
            let mut rgb = m.color.to_array();
            let picker = ui.color_edit_button_rgb(&mut rgb).on_hover_text("Base colour (linear)");
            ui.label("base colour");
            if picker.changed() {
                m.color = rt_core::math::color::Color::from_array(rgb);
                changed = true;
            }
        });
        let mut slider = |ui: &mut egui::Ui, value: &mut f32, range, text| {
            let response = ui.add(egui::Slider::new(value, range).text(text));
            changed |= response.changed();
            dragging |= response.dragged();
            response
        };
        match &mut m.physical {
            Some(p) => {
                slider(ui, &mut p.metallic, 0.0..=1.0, "metallic");
                let _rough = slider(ui, &mut p.roughness, 0.0..=1.0, "roughness");
                #[cfg(test)]
                {
                    self.drawn.roughness = Some(_rough.rect);
                }
            }
            None => {
                let (mut metallic, mut roughness) = (0.0, m.roughness());
                for (value, text) in [(&mut metallic, "metallic"), (&mut roughness, "roughness")] {
                    ui.add_enabled(false, egui::Slider::new(value, 0.0..=1.0).text(text))
                        .on_disabled_hover_text(CLASSIC_HOVER);
                }
            }
        }
        slider(ui, &mut m.ior, 1.0..=3.0, "ior");
        (changed.then_some(m), dragging)
    }

    /// Revert, enabled once material `index` is edited; returns whether it was clicked.
    fn revert_ui(&mut self, ui: &mut egui::Ui, index: usize) -> bool {
        let button = ui
            .add_enabled(self.is_edited(index), egui::Button::new("Revert"))
            .on_hover_text("Back to this material as the scene file has it")
            .on_disabled_hover_text("Not edited: the material is as the scene file has it");
        #[cfg(test)]
        {
            self.drawn.revert = Some(button.rect);
        }
        button.clicked()
    }

    /// Material `index` of `scene` as it was loaded: the loaded scene
    /// itself once no material is edited any more.
    fn revert(&mut self, scene: &Arc<LoadedScene>, index: usize) -> Option<Edit> {
        let original = self.original.clone()?;
        self.edited.remove(&index);
        self.error = None;
        let interaction = Interaction { changed: true, dragging: false };
        if self.edited.is_empty() {
            self.original = None;
            return Some(Edit { scene: original, interaction });
        }
        let restored = scene.scene.with_material(index, *original.scene.material(index)).ok()?;
        let scene = Arc::new(LoadedScene { scene: restored, camera: scene.camera, settings: scene.settings });
        Some(Edit { scene, interaction })
    }
}

/// Every value of `m`, as (what, value) rows: the model, the base colour,
/// the physically based parameters or the classic weights, the ior, the
/// emission, the subsurface medium and the textures used.
pub(super) fn describe(m: &Material) -> Vec<(&'static str, String)> {
    let rgb = |c: rt_core::math::color::Color| format!("({:.2}, {:.2}, {:.2})", c.x, c.y, c.z);
    let mut rows = vec![];
    match &m.physical {
        Some(p) => {
            rows.push(("model", "physically based (glTF 2.0)".to_owned()));
            rows.push(("base colour", rgb(m.color)));
            rows.push(("metallic", format!("{:.3}", p.metallic)));
            rows.push(("roughness", format!("{:.3}", p.roughness)));
            rows.push(("ior", format!("{:.3}", m.ior)));
            rows.push(("specular", format!("{:.2} × {}", p.specular, rgb(p.specular_color))));
            rows.push(("transmission", format!("{:.3}", p.transmission)));
            if p.transmission > 0.0 {
                let distance = p.attenuation_distance;
                rows.push(("attenuation", format!("{} after {distance}", rgb(p.attenuation_color))));
            }
            rows.push(("clearcoat", format!("{:.2}, roughness {:.2}", p.clearcoat, p.clearcoat_roughness)));
        }
        None => {
            rows.push(("model", "classic weights".to_owned()));
            rows.push(("colour", rgb(m.color)));
            rows.push(("diffuse", format!("{:.3}", m.diffuse)));
            rows.push(("specular", format!("{:.2} × {}", m.specular, rgb(m.specular_color))));
            rows.push(("shininess", format!("{:.1} (roughness {:.3})", m.shininess, m.roughness())));
            rows.push(("reflectivity", format!("{:.3}", m.reflectivity)));
            rows.push(("transparency", format!("{:.3}", m.transparency)));
            rows.push(("ior", format!("{:.3}", m.ior)));
        }
    }
    rows.push(("emission", rgb(m.emission)));
    if m.subsurface.is_some() {
        rows.push(("subsurface", "a scattering inside".to_owned()));
    }
    let slots = [
        ("base colour map", &m.base_color_texture),
        ("metal-rough map", &m.metallic_roughness_texture),
        ("emissive map", &m.emissive_texture),
        ("occlusion map", &m.occlusion_texture),
    ];
    for (what, slot) in slots {
        if let Some(TextureSlot { texture, tex_coord, .. }) = slot {
            rows.push((what, format!("texture {texture}, uv set {tex_coord}")));
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use rt_core::materials::principled::Principled;
    use rt_core::math::color::Color;

    use super::*;

    #[test]
    fn describe_lists_the_models_own_values_and_the_textures_used() {
        let physical = Material {
            base_color_texture: Some(TextureSlot::new(3)),
            ..Material::principled(
                Color::splat(0.5),
                Principled { roughness: 0.25, ..Principled::DIELECTRIC },
            )
        };
        let rows = describe(&physical);
        let get = |rows: &[(&str, String)], what| rows.iter().find(|r| r.0 == what).map(|r| r.1.clone());
        assert_eq!(get(&rows, "model").unwrap(), "physically based (glTF 2.0)");
        assert_eq!(get(&rows, "roughness").unwrap(), "0.250");
        assert_eq!(get(&rows, "base colour map").unwrap(), "texture 3, uv set 0");
        assert_eq!(get(&rows, "shininess"), None);
        let classic = describe(&Material::flat(Color::ONE));
        assert_eq!(get(&classic, "model").unwrap(), "classic weights");
        assert!(get(&classic, "shininess").is_some() && get(&classic, "metallic").is_none());
        assert_eq!(get(&classic, "base colour map"), None);
    }

    /// The panel drawn for `object` of the scene file `name`, one frame.
    fn drawn_for(name: &str, object: usize) -> (MaterialPanel, Option<Edit>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name);
        let scene = Arc::new(rt_core::load_scene(&path).unwrap());
        let (ctx, mut panel) = (egui::Context::default(), MaterialPanel::default());
        let mut edit = None;
        let mut output =
            ctx.run_ui(egui::RawInput::default(), |ui| edit = panel.ui(ui, &scene, Some(object)));
        output.textures_delta.clear();
        ctx.tex_manager().write().take_delta().clear();
        (panel, edit)
    }

    #[test]
    fn only_a_physically_based_material_gets_a_roughness_slider_and_drawing_edits_nothing() {
        let (physical, edit) = drawn_for("metal_rough.ron", 0);
        assert!(physical.drawn.roughness.is_some() && edit.is_none());
        let (classic, edit) = drawn_for("sphere.ron", 0);
        assert!(classic.drawn.roughness.is_none() && classic.drawn.revert.is_some() && edit.is_none());
    }
}
