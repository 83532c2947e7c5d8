//! Materials: how a surface answers light. Its colours are linear RGB
//! ([`crate::math::color`]).

use crate::materials::alpha::AlphaMode;
use crate::materials::medium::Subsurface;
use crate::materials::principled::Principled;
use crate::materials::texture_slot::TextureSlot;
use crate::math::color::Color;
use crate::math::real::{Real, SMOOTH_ALPHA};

/// A surface's appearance.
///
/// Two models: the physically based one (glTF 2.0's metallic-roughness
/// BSDF, [`crate::materials::principled`]) when `physical` is set — then
/// `color` is its base colour, `ior` its index of refraction, `emission`
/// its emission, and the weights `diffuse` … `transparency` and
/// `specular_color` are unused — or else the weights of the older model
/// below.
///
/// Without lights (pure ray casting) a hit shows `color` flat and every other
/// field is unused. With lights it is shaded by its BSDF ([`crate::materials::bsdf`]),
/// the mixture
///
/// `f = (1 − kr − kt)·[(1 − ks)·kd·color/π + ks·s·f_ggx(shininess)] + kr·s·mirror + kt·glass(ior, color)`
///
/// with `kr = reflectivity`, `kt = transparency`, `ks = specular`,
/// `kd = diffuse`, `s = specular_color`, and it gives off radiance `emission` from the side its
/// geometric normal points to. Every weight is in [0, 1] and kr + kt ≤ 1,
/// so no material reflects more light than arrives.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Material {
    /// Base colour, each component in [0, 1]: the flat colour, the diffuse
    /// albedo and the glass tint.
    pub color: Color,
    /// Diffuse (Lambert) weight kd in [0, 1].
    pub diffuse: f32,
    /// Glossy (GGX) weight ks in [0, 1]; the Lambert lobe gets the rest.
    pub specular: f32,
    /// Tint s of the glossy and mirror lobes, each component in [0, 1]
    /// (white by default: a dielectric's highlight; a metal's is its colour).
    pub specular_color: Color,
    /// Blinn–Phong exponent giving the glossy lobe's roughness
    /// ([`Material::roughness`]); larger is a smaller, sharper highlight.
    pub shininess: f32,
    /// Mirror reflection weight kr in [0, 1].
    pub reflectivity: f32,
    /// Transmission weight kt in [0, 1], kr + kt ≤ 1.
    pub transparency: f32,
    /// Index of refraction of the inside (the side the normal points away from), > 0.
    pub ior: f32,
    /// Radiance the surface gives off (W·m⁻²·sr⁻¹) from the side its
    /// geometric normal points to. It is seen directly; under global
    /// illumination it also lights the scene.
    pub emission: Color,
    /// A translucent inside ([`crate::materials::medium`]): under global illumination
    /// the surface is then a smooth dielectric boundary of index `ior`
    /// (index-matched, letting light straight through, when `ior` is 1)
    /// around a homogeneous scattering medium, and the BSDF lobes above are
    /// not used. Only closed objects may have one.
    pub subsurface: Option<Subsurface>,
    /// A base-colour texture (sRGB-decoded): where the surface has the
    /// slot's texture coordinates, its colour multiplies `color` (as
    /// `map_Kd` multiplies `Kd`, and glTF's `baseColorTexture` its factor).
    pub base_color_texture: Option<TextureSlot>,
    /// glTF's `metallicRoughnessTexture` (linear data): its blue channel
    /// multiplies the physically based `metallic`, its green one
    /// `roughness`; unused by the weights model.
    pub metallic_roughness_texture: Option<TextureSlot>,
    /// An emissive texture (sRGB-decoded): its colour multiplies `emission`.
    pub emissive_texture: Option<TextureSlot>,
    /// glTF's `occlusionTexture` (linear data, red channel), kept but not
    /// applied: global illumination computes the occlusion it bakes, so
    /// applying it would count it twice, and the direct-lighting tracer's
    /// ambient term has ray-traced ambient occlusion of its own.
    pub occlusion_texture: Option<TextureSlot>,
    /// The physically based parameters ([`Principled`]): when set, the
    /// surface is shaded by the glTF 2.0 BSDF instead of the weights.
    pub physical: Option<Principled>,
    /// A normal map (glTF's `normalTexture`, linear data) holding
    /// tangent-space normals ([`crate::materials::normal_map`]): where the
    /// surface has the slot's texture coordinates it replaces the shading
    /// normal. The slot's `scale` is how far its normals tilt, multiplying
    /// their x and y (glTF's `normalTexture.scale`, 1 by default).
    pub normal_texture: Option<TextureSlot>,
    /// The base colour's alpha factor in [0, 1] (glTF's
    /// `baseColorFactor[3]`), multiplied by the texture's alpha where it has
    /// one; used as `alpha_mode` says.
    pub alpha: f32,
    /// How alpha decides where the surface is ([`crate::materials::alpha`]).
    pub alpha_mode: AlphaMode,
}

impl Material {
    /// A plain diffuse material of `color`, as old (flat-colour) scene files get.
    pub const fn flat(color: Color) -> Self {
        Self {
            color,
            diffuse: 1.0,
            specular: 0.0,
            specular_color: Color::ONE,
            shininess: 32.0,
            reflectivity: 0.0,
            transparency: 0.0,
            ior: 1.5,
            emission: Color::ZERO,
            subsurface: None,
            base_color_texture: None,
            metallic_roughness_texture: None,
            emissive_texture: None,
            occlusion_texture: None,
            physical: None,
            normal_texture: None,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
        }
    }

    /// A physically based material of base colour `color` and parameters `p`.
    pub const fn principled(color: Color, p: Principled) -> Self {
        Self { physical: Some(p), ..Self::flat(color) }
    }

    /// The GGX roughness α of the glossy lobe, from the Blinn–Phong exponent
    /// s by Walter et al.'s correspondence `α = √(2/(s + 2))` ("Microfacet
    /// Models for Refraction through Rough Surfaces", 2007, eq. 33): 1 for
    /// s = 0, 0.2 for s = 48, 0.014 for s = 10 000.
    pub fn roughness(&self) -> f32 {
        (2.0 / (self.shininess + 2.0)).sqrt()
    }

    /// The surface of a subsurface material: a clear, smooth dielectric of
    /// its `ior` (the medium inside does the colouring), with its emission.
    pub fn boundary(&self) -> Material {
        Material {
            color: Color::ONE,
            transparency: 1.0,
            reflectivity: 0.0,
            subsurface: None,
            physical: None,
            ..*self
        }
    }

    /// Whether the surface has a δ (mirror) reflection, which the
    /// direct-lighting tracer follows with a ray: `reflectivity` or
    /// `transparency` of the weights model; a smooth specular layer or
    /// clearcoat (α below [`SMOOTH_ALPHA`]), or a δ refraction, of the
    /// physically based one.
    pub fn reflects_sharply(&self) -> bool {
        match &self.physical {
            None => self.reflectivity > 0.0 || self.transparency > 0.0,
            Some(p) => {
                let smooth = |roughness: f32| Real::from(roughness * roughness) < SMOOTH_ALPHA;
                smooth(p.roughness)
                    || (p.clearcoat > 0.0 && smooth(p.clearcoat_roughness))
                    || self.refracts_sharply()
            }
        }
    }

    /// Whether the surface has a δ refraction, which the direct-lighting
    /// tracer follows with a ray: `transparency` of the weights model; a
    /// smooth (or index-matched) transmission of the physically based one.
    pub fn refracts_sharply(&self) -> bool {
        match &self.physical {
            None => self.transparency > 0.0,
            Some(p) => {
                p.transmission > 0.0
                    && p.metallic < 1.0
                    && (Real::from(p.roughness * p.roughness) < SMOOTH_ALPHA || self.ior == 1.0)
            }
        }
    }

    /// The texture slots that change what the surface looks like (base
    /// colour, metallic-roughness, emissive), those present.
    pub fn applied_textures(&self) -> impl Iterator<Item = &TextureSlot> {
        [&self.base_color_texture, &self.metallic_roughness_texture, &self.emissive_texture]
            .into_iter()
            .flatten()
    }

    /// Every texture slot the material has, the normal map and occlusion
    /// included.
    pub fn texture_slots(&self) -> impl Iterator<Item = &TextureSlot> {
        self.applied_textures().chain(&self.normal_texture).chain(&self.occlusion_texture)
    }

    /// Moves every texture slot's index up by `by`: a model's materials
    /// number its own textures from 0, a scene's follow the textures
    /// already there.
    pub fn offset_textures(&mut self, by: u32) {
        for slot in [
            &mut self.base_color_texture,
            &mut self.metallic_roughness_texture,
            &mut self.emissive_texture,
            &mut self.normal_texture,
            &mut self.occlusion_texture,
        ]
        .into_iter()
        .flatten()
        {
            slot.texture += by;
        }
    }

    /// Whether any texture changes the surface (an untextured material is
    /// used as it is, [`crate::scene::Scene::material_at`]).
    pub fn is_textured(&self) -> bool {
        self.base_color_texture.is_some()
            || self.metallic_roughness_texture.is_some()
            || self.emissive_texture.is_some()
    }

    /// Whether the surface gives off light.
    pub fn is_emissive(&self) -> bool {
        self.emission != Color::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_physically_based_surfaces_ask_for_reflection_and_refraction_rays() {
        let p = |f: fn(&mut Principled)| {
            let mut p = Principled::DIELECTRIC;
            f(&mut p);
            Material::principled(Color::ONE, p)
        };
        let rough = p(|p| p.roughness = 0.5);
        assert!(!rough.reflects_sharply() && !rough.refracts_sharply());
        let mirror = p(|p| (p.roughness, p.metallic) = (0.0, 1.0));
        assert!(mirror.reflects_sharply() && !mirror.refracts_sharply());
        let glass = p(|p| (p.roughness, p.transmission) = (0.0, 1.0));
        assert!(glass.reflects_sharply() && glass.refracts_sharply());
        let coated = p(|p| (p.roughness, p.clearcoat) = (0.5, 1.0));
        assert!(coated.reflects_sharply() && !coated.refracts_sharply());
        let weights = Material { reflectivity: 0.5, ..Material::flat(Color::ONE) };
        assert!(weights.reflects_sharply() && !weights.refracts_sharply());
    }
}
