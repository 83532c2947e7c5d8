//! The `materials` map's entries.

use serde::Deserialize;

use super::values::{ColorDesc, Finite};
use crate::materials::alpha::{AlphaMode, DEFAULT_ALPHA_CUTOFF};
use crate::materials::material::Material;
use crate::materials::medium::Subsurface;
use crate::materials::principled::Principled;
use crate::materials::texture_slot::Wrap;
use crate::materials::texture_slot::{Encoding, Filter, Sampler, TextureSlot, UvTransform};
use crate::math::color::Color;
use crate::math::real::{MIN_MEAN_FREE_PATH, Real, to_f32};

/// A material as written, in one of two models. With `base_color` it is
/// physically based (glTF 2.0's metallic-roughness BSDF,
/// [`crate::materials::principled`]): `metallic`, `roughness`,
/// `transmission`, `attenuation_color`, `attenuation_distance`,
/// `clearcoat`, `clearcoat_roughness`, `specular_factor`,
/// `specular_color_factor` and `emission_strength` apply. With `color` it
/// is the older mixture of weights: `diffuse`, `specular`,
/// `specular_color`, `shininess`, `reflectivity` and `transparency` apply,
/// and the defaults make a plain diffuse surface ([`Material::flat`]).
/// Mixing the two models' fields is refused, naming the field. Every value
/// is checked to keep the material energy conserving.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Material")]
pub(super) struct MaterialFields {
    #[serde(default, deserialize_with = "super::values::present")]
    color: Option<ColorDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    diffuse: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    specular: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    specular_color: Option<ColorDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    shininess: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    reflectivity: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    transparency: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    base_color: Option<ColorDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    metallic: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    roughness: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    transmission: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    attenuation_color: Option<ColorDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    attenuation_distance: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    clearcoat: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    clearcoat_roughness: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    specular_factor: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    specular_color_factor: Option<ColorDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    emission_strength: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    ior: Option<Finite>,
    #[serde(default)]
    emission: ColorDesc,
    #[serde(default, deserialize_with = "super::values::present")]
    subsurface: Option<SubsurfaceDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    base_color_texture: Option<TextureDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    metallic_roughness_texture: Option<TextureDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    emissive_texture: Option<TextureDesc>,
    // Normal map and alpha, in either model (see `SurfaceFields`).
    #[serde(default, deserialize_with = "super::values::present")]
    normal_texture: Option<TextureDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    normal_scale: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    alpha: Option<Finite>,
    #[serde(default, deserialize_with = "super::values::present")]
    alpha_mode: Option<AlphaModeDesc>,
    #[serde(default, deserialize_with = "super::values::present")]
    alpha_cutoff: Option<Finite>,
}

/// A texture a material uses: an image file's path (relative to the scene
/// file), alone — `base_color_texture: "wood.png"` — or with options:
/// `(file: "wood.png", tex_coord: 1, offset: (0, 0), rotation: 0,
/// scale: (4, 4), filter: Nearest, mipmaps: false, wrap: ClampToEdge)`,
/// each optional: texture-coordinate set 0 or 1 (default 0),
/// `KHR_texture_transform`'s offset, rotation (degrees) and scale, the
/// filter (`Linear` by default) and whether mip-maps are used against
/// aliasing (default yes, trilinear), and the wrap mode of both axes
/// (`Repeat`, `ClampToEdge`, `MirroredRepeat`; default `Repeat`).
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub(super) enum TextureDesc {
    /// Just the file.
    File(String),
    /// The file with options.
    Options(TextureFields),
}

/// [`TextureDesc`]'s options.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Texture")]
pub(super) struct TextureFields {
    file: String,
    #[serde(default)]
    tex_coord: u32,
    #[serde(default)]
    offset: Option<(f32, f32)>,
    #[serde(default)]
    rotation: Option<f32>,
    #[serde(default)]
    scale: Option<(f32, f32)>,
    #[serde(default)]
    filter: Option<FilterName>,
    #[serde(default)]
    mipmaps: Option<bool>,
    #[serde(default)]
    wrap: Option<WrapName>,
}

/// A texture filter's name in a scene file.
#[derive(Clone, Copy, Debug, Deserialize)]
pub(super) enum FilterName {
    Nearest,
    Linear,
}

/// A wrap mode's name in a scene file.
#[derive(Clone, Copy, Debug, Deserialize)]
pub(super) enum WrapName {
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

impl TextureDesc {
    /// The image file (relative to the scene file) and the slot reading it
    /// (its `texture` index left 0 for the scene to fill in); what is wrong
    /// with the options, naming `field`.
    fn slot(&self, field: &str) -> Result<(String, TextureSlot), String> {
        let f = match self {
            Self::File(file) => return Ok((file.clone(), TextureSlot::new(0))),
            Self::Options(f) => f,
        };
        if f.tex_coord > 1 {
            return Err(format!("material {field}.tex_coord must be 0 or 1, got {}", f.tex_coord));
        }
        let transform = UvTransform::new(
            f.offset.map_or([0.0; 2], |(x, y)| [x, y]),
            f.rotation.unwrap_or(0.0).to_radians(),
            f.scale.map_or([1.0; 2], |(x, y)| [x, y]),
        )
        .ok_or_else(|| format!("material {field}: offset, rotation and scale must be finite numbers"))?;
        let filter = match f.filter {
            Some(FilterName::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        };
        let wrap = match f.wrap {
            None | Some(WrapName::Repeat) => Wrap::Repeat,
            Some(WrapName::ClampToEdge) => Wrap::ClampToEdge,
            Some(WrapName::MirroredRepeat) => Wrap::MirroredRepeat,
        };
        let mip = f.mipmaps.unwrap_or(true).then_some(Filter::Linear);
        let sampler = Sampler { mag: filter, min: filter, mip, wrap: [wrap; 2] };
        Ok((
            f.file.clone(),
            TextureSlot { tex_coord: f.tex_coord, transform, sampler, ..TextureSlot::new(0) },
        ))
    }
}

/// A material's textures as the scene file gives them: which slot, the
/// image file (relative to the scene file), its decoding and the slot.
pub(super) struct TextureUses(pub(super) Vec<(TextureField, String, Encoding, TextureSlot)>);

/// Which of a material's texture slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TextureField {
    BaseColor,
    MetallicRoughness,
    Emissive,
    Normal,
}

impl TextureField {
    /// The field's name in a scene file.
    pub(super) fn name(self) -> &'static str {
        match self {
            Self::BaseColor => "base_color_texture",
            Self::MetallicRoughness => "metallic_roughness_texture",
            Self::Emissive => "emissive_texture",
            Self::Normal => "normal_texture",
        }
    }

    /// Puts `slot` into `material`'s slot of this field.
    pub(super) fn set(self, material: &mut Material, slot: TextureSlot) {
        match self {
            Self::BaseColor => material.base_color_texture = Some(slot),
            Self::MetallicRoughness => material.metallic_roughness_texture = Some(slot),
            Self::Emissive => material.emissive_texture = Some(slot),
            Self::Normal => material.normal_texture = Some(slot),
        }
    }
}

/// A material's normal map's scale and alpha: `normal_scale` (default 1:
/// how far the normals of `normal_texture`, an image of linear
/// tangent-space normals in glTF's convention,
/// [`crate::materials::normal_map`], tilt), and `alpha` (default 1) with `alpha_mode` (`Opaque`, the
/// default, `Mask` with `alpha_cutoff`, default 0.5, or `Blend`:
/// [`crate::materials::alpha`]).
struct SurfaceFields {
    has_normal_texture: bool,
    normal_scale: Option<Finite>,
    alpha: Option<Finite>,
    alpha_mode: Option<AlphaModeDesc>,
    alpha_cutoff: Option<Finite>,
}

/// `alpha_mode: Opaque | Mask | Blend`.
#[derive(Deserialize, Clone, Copy, PartialEq)]
enum AlphaModeDesc {
    Opaque,
    Mask,
    Blend,
}

impl SurfaceFields {
    /// `m` with the alpha fields set, and the normal map's scale.
    fn apply(self, m: Material) -> Result<(Material, f32), String> {
        let unit = |v: Option<Finite>, default: f32, name: &str| match v {
            None => Ok(default),
            Some(Finite(v)) if (0.0..=1.0).contains(&v) => Ok(to_f32(v)),
            Some(Finite(v)) => Err(format!("material {name} must be 0 to 1, got {v}")),
        };
        let cutoff = unit(self.alpha_cutoff, DEFAULT_ALPHA_CUTOFF, "alpha_cutoff")?;
        let alpha_mode = match self.alpha_mode.unwrap_or(AlphaModeDesc::Opaque) {
            AlphaModeDesc::Mask => AlphaMode::Mask { cutoff },
            _ if self.alpha_cutoff.is_some() => {
                return Err("material alpha_cutoff applies to alpha_mode: Mask only".into());
            }
            AlphaModeDesc::Opaque => AlphaMode::Opaque,
            AlphaModeDesc::Blend => AlphaMode::Blend,
        };
        if self.normal_scale.is_some() && !self.has_normal_texture {
            return Err("material normal_scale needs a normal_texture".into());
        }
        let normal_scale = self.normal_scale.map_or(1.0, |s| to_f32(s.0));
        let alpha = unit(self.alpha, 1.0, "alpha")?;
        Ok((Material { alpha, alpha_mode, ..m }, normal_scale))
    }
}

/// `subsurface: (albedo: (r, g, b), mean_free_path: (r, g, b), anisotropy: g)`;
/// `anisotropy` is optional (0: isotropic).
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Subsurface")]
struct SubsurfaceFields {
    albedo: (Finite, Finite, Finite),
    mean_free_path: (Finite, Finite, Finite),
    #[serde(default)]
    anisotropy: Finite,
}

#[derive(Deserialize)]
#[serde(try_from = "SubsurfaceFields")]
struct SubsurfaceDesc(Subsurface);

impl TryFrom<SubsurfaceFields> for SubsurfaceDesc {
    type Error = String;
    fn try_from(f: SubsurfaceFields) -> Result<Self, String> {
        let rgb = |(r, g, b): (Finite, Finite, Finite)| [r.0, g.0, b.0];
        let albedo = rgb(f.albedo);
        if let Some(a) = albedo.iter().find(|a| !(0.0..=1.0).contains(*a)) {
            return Err(format!("subsurface.albedo is a fraction: each component must be 0 to 1, got {a}"));
        }
        let mfp = rgb(f.mean_free_path);
        if let Some(l) = mfp.iter().find(|l| !(**l > 0.0 && **l <= 1e9)) {
            return Err(format!(
                "subsurface.mean_free_path is a length in scene units: each component must be above 0 \
                 and at most 1e9, got {l}"
            ));
        }
        let g = f.anisotropy.0;
        if g.is_nan() || g.abs() >= 1.0 {
            return Err(format!("subsurface.anisotropy must be between −1 and 1 (exclusive), got {g}"));
        }
        let color = |v: [Real; 3]| Color::new(to_f32(v[0]), to_f32(v[1]), to_f32(v[2]));
        // At most 1e9 units: σt = 1/ℓ stays a normal f32, however small ℓ is.
        let mean_free_path = color(mfp).max(Color::splat(MIN_MEAN_FREE_PATH));
        Ok(Self(Subsurface { albedo: color(albedo), mean_free_path, anisotropy: to_f32(g) }))
    }
}

/// A material, and the textures it reads.
#[derive(Deserialize)]
#[serde(try_from = "MaterialFields")]
pub(super) struct MaterialDesc(pub(super) Material, pub(super) TextureUses);

impl TryFrom<MaterialFields> for MaterialDesc {
    type Error = String;
    fn try_from(f: MaterialFields) -> Result<Self, String> {
        let mut uses = Vec::new();
        for (field, desc, encoding) in [
            (TextureField::BaseColor, &f.base_color_texture, Encoding::Srgb),
            (TextureField::MetallicRoughness, &f.metallic_roughness_texture, Encoding::Linear),
            (TextureField::Emissive, &f.emissive_texture, Encoding::Srgb),
            (TextureField::Normal, &f.normal_texture, Encoding::Linear),
        ] {
            if let Some(desc) = desc {
                let (file, slot) = desc.slot(field.name())?;
                uses.push((field, file, encoding, slot));
            }
        }
        if f.metallic_roughness_texture.is_some() && f.base_color.is_none() {
            return Err("material metallic_roughness_texture belongs to the physically based model: \
                        write base_color instead of color"
                .into());
        }
        let number = |v: Option<Finite>, default: f32, name: &str, ok: fn(Real) -> bool, rule: &str| match v {
            None => Ok(default),
            Some(Finite(v)) if ok(v) => Ok(to_f32(v)),
            Some(Finite(v)) => Err(format!("material {name} must be {rule}, got {v}")),
        };
        let unit = |v: Real| (0.0..=1.0).contains(&v);
        let reflectance = |c: Option<ColorDesc>, default: Color, name: &str| match c {
            None => Ok(default),
            Some(ColorDesc(c)) if c.max_element() <= 1.0 => Ok(c),
            Some(ColorDesc(c)) => {
                Err(format!("material {name} is a reflectance: each component must be 0 to 1, got {c}"))
            }
        };
        let ior = number(f.ior, 1.5, "ior", |v| v > 0.0 && v <= 100.0, "above 0 and at most 100")?;
        let emission = f.emission.0;
        let subsurface = f.subsurface.map(|s| s.0);
        let physical_fields = [
            ("metallic", f.metallic.is_some()),
            ("roughness", f.roughness.is_some()),
            ("transmission", f.transmission.is_some()),
            ("attenuation_color", f.attenuation_color.is_some()),
            ("attenuation_distance", f.attenuation_distance.is_some()),
            ("clearcoat", f.clearcoat.is_some()),
            ("clearcoat_roughness", f.clearcoat_roughness.is_some()),
            ("specular_factor", f.specular_factor.is_some()),
            ("specular_color_factor", f.specular_color_factor.is_some()),
            ("emission_strength", f.emission_strength.is_some()),
        ];
        let weight_fields = [
            ("diffuse", f.diffuse.is_some()),
            ("specular", f.specular.is_some()),
            ("specular_color", f.specular_color.is_some()),
            ("shininess", f.shininess.is_some()),
            ("reflectivity", f.reflectivity.is_some()),
            ("transparency", f.transparency.is_some()),
        ];
        let m = match (f.color, f.base_color) {
            (Some(_), Some(_)) => {
                return Err(
                    "material has both color (the weights model) and base_color (the physically based \
                     model): write one"
                        .into(),
                );
            }
            (None, None) => {
                return Err("material needs a color (or a base_color, for a physically based one)".into());
            }
            (None, Some(base)) => {
                if let Some((name, _)) = weight_fields.iter().find(|(_, present)| *present) {
                    return Err(format!(
                        "material {name} belongs to the weights model (with color); a material with base_color \
                         is physically based: use metallic, roughness, transmission, clearcoat, specular_factor"
                    ));
                }
                let base = reflectance(Some(base), Color::ONE, "base_color")?;
                let d = Principled::DIELECTRIC;
                let attenuation_color = reflectance(f.attenuation_color, Color::ONE, "attenuation_color")?;
                if attenuation_color.min_element() <= 0.0 {
                    return Err(format!(
                        "material attenuation_color must be above 0 in each component (0 would absorb \
                         everything at once), got {attenuation_color}"
                    ));
                }
                let p = Principled {
                    metallic: number(f.metallic, d.metallic, "metallic", unit, "0 to 1")?,
                    roughness: number(f.roughness, d.roughness, "roughness", unit, "0 to 1")?,
                    transmission: number(f.transmission, d.transmission, "transmission", unit, "0 to 1")?,
                    attenuation_color,
                    attenuation_distance: number(
                        f.attenuation_distance,
                        f32::INFINITY,
                        "attenuation_distance",
                        |v| v > 0.0,
                        "above 0 (in scene units; leave it out for a clear inside)",
                    )?,
                    clearcoat: number(f.clearcoat, d.clearcoat, "clearcoat", unit, "0 to 1")?,
                    clearcoat_roughness: number(
                        f.clearcoat_roughness,
                        d.clearcoat_roughness,
                        "clearcoat_roughness",
                        unit,
                        "0 to 1",
                    )?,
                    specular: number(f.specular_factor, d.specular, "specular_factor", unit, "0 to 1")?,
                    specular_color: reflectance(
                        f.specular_color_factor,
                        Color::ONE,
                        "specular_color_factor",
                    )?,
                };
                let strength =
                    number(f.emission_strength, 1.0, "emission_strength", |v| v >= 0.0, "0 or more")?;
                Material { ior, emission: emission * strength, subsurface, ..Material::principled(base, p) }
            }
            (Some(color), None) => {
                if let Some((name, _)) = physical_fields.iter().find(|(_, present)| *present) {
                    return Err(format!(
                        "material {name} belongs to the physically based model: write base_color instead of color"
                    ));
                }
                let flat = Material::flat(Color::ZERO);
                let m = Material {
                    color: reflectance(Some(color), Color::ONE, "color")?,
                    diffuse: number(f.diffuse, flat.diffuse, "diffuse", unit, "0 to 1")?,
                    specular: number(f.specular, flat.specular, "specular", unit, "0 to 1")?,
                    specular_color: reflectance(f.specular_color, Color::ONE, "specular_color")?,
                    shininess: number(
                        f.shininess,
                        flat.shininess,
                        "shininess",
                        |v| (0.0..=1e4).contains(&v),
                        "0 to 10000",
                    )?,
                    reflectivity: number(f.reflectivity, 0.0, "reflectivity", unit, "0 to 1")?,
                    transparency: number(f.transparency, 0.0, "transparency", unit, "0 to 1")?,
                    ior,
                    emission,
                    subsurface,
                    ..flat
                };
                if m.reflectivity + m.transparency > 1.0 {
                    return Err(format!(
                        "material reflectivity + transparency must not exceed 1, got {} + {}",
                        m.reflectivity, m.transparency
                    ));
                }
                m
            }
        };
        let surface = SurfaceFields {
            has_normal_texture: f.normal_texture.is_some(),
            normal_scale: f.normal_scale,
            alpha: f.alpha,
            alpha_mode: f.alpha_mode,
            alpha_cutoff: f.alpha_cutoff,
        };
        let (m, normal_scale) = surface.apply(m)?;
        for (field, _, _, slot) in &mut uses {
            if *field == TextureField::Normal {
                slot.scale = normal_scale;
            }
        }
        Ok(Self(m, TextureUses(uses)))
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::super::parse_scene;
    use crate::materials::principled::Principled;
    use crate::math::color::Color;

    /// The scene's first material, written as `material`, or the error as text.
    fn material(material: &str) -> Result<crate::materials::material::Material, String> {
        let text = format!(
            "Scene(camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
            image: (width: 8, height: 8), materials: {{ \"m\": {material} }},
            objects: [Sphere(center: (0, 0, 0), radius: 1, material: \"m\")])"
        );
        parse_scene(&text, "m.ron", Path::new(".")).map(|l| *l.scene.material(0)).map_err(|e| e.to_string())
    }

    #[test]
    fn a_base_color_makes_a_physically_based_material_with_every_field_read() {
        let m = material(
            "(base_color: (0.9, 0.5, 0.1), metallic: 0.3, roughness: 0.4, ior: 1.7, transmission: 0.5,
              attenuation_color: (0.5, 0.6, 0.7), attenuation_distance: 2, clearcoat: 0.6, clearcoat_roughness: 0.1,
              specular_factor: 0.8, specular_color_factor: (1, 0.9, 0.8), emission: (1, 2, 3), emission_strength: 4)",
        )
        .unwrap();
        assert_eq!(
            (m.color, m.ior, m.emission),
            (Color::new(0.9, 0.5, 0.1), 1.7, Color::new(4.0, 8.0, 12.0))
        );
        let p = m.physical.unwrap();
        assert_eq!((p.metallic, p.roughness, p.transmission), (0.3, 0.4, 0.5));
        assert_eq!((p.attenuation_color, p.attenuation_distance), (Color::new(0.5, 0.6, 0.7), 2.0));
        assert_eq!((p.clearcoat, p.clearcoat_roughness, p.specular), (0.6, 0.1, 0.8));
        assert_eq!(p.specular_color, Color::new(1.0, 0.9, 0.8));
        // Defaults: glTF's, with metallic 0 and roughness 0.5.
        let m = material("(base_color: (1, 1, 1))").unwrap();
        assert_eq!((m.physical, m.ior), (Some(Principled::DIELECTRIC), 1.5));
        // The weights model is untouched.
        assert_eq!(material("(color: (1, 1, 1))").unwrap().physical, None);
    }

    #[test]
    fn a_normal_map_and_alpha_are_read_and_bad_ones_named() {
        use crate::materials::alpha::AlphaMode;
        let dir = tempfile::tempdir().unwrap();
        image::RgbImage::from_pixel(2, 2, image::Rgb([255, 128, 255]))
            .save(dir.path().join("n.png"))
            .unwrap();
        std::fs::write(
            dir.path().join("quad.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
        )
        .unwrap();
        let scene = |material: &str, object: &str| {
            let text = format!(
                "Scene(camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
                image: (width: 8, height: 8), materials: {{ \"m\": {material} }}, objects: [{object}])"
            );
            crate::parse_scene(&text, "s.ron", dir.path())
        };
        let mesh = r#"Mesh(file: "quad.obj", material: "m")"#;
        let s = scene(
            r#"(base_color: (1, 1, 1), normal_texture: "n.png", normal_scale: 0.5, alpha: 0.8, alpha_mode: Mask, alpha_cutoff: 0.3)"#,
            mesh,
        )
        .unwrap()
        .scene;
        let m = *s.material(0);
        assert_eq!(m.normal_texture.map(|s| (s.texture, s.scale)), Some((0, 0.5)));
        assert_eq!((m.alpha, m.alpha_mode), (0.8, AlphaMode::Mask { cutoff: 0.3 }));
        // Linear: 255 reads 1, 128 reads 128/255, not sRGB-decoded.
        let texel = s.texture(0).sample(0.5, 0.5);
        assert!((texel - Color::new(1.0, 128.0 / 255.0, 1.0)).abs().max_element() < 1e-6, "{texel}");
        assert!(s.warnings().is_empty(), "{:?}", s.warnings());
        assert!(s.source_files().iter().any(|f| f.ends_with("n.png")));
        let m = *scene("(color: (1, 1, 1), alpha_mode: Blend)", mesh).unwrap().scene.material(0);
        assert_eq!((m.alpha, m.alpha_mode, m.normal_texture), (1.0, AlphaMode::Blend, None));
        // The options form, as for every texture: set, transform, sampler;
        // normal_scale is the slot's scale.
        let s = scene(
            r#"(color: (1, 1, 1), normal_texture: (file: "n.png", scale: (4, 4), filter: Nearest), normal_scale: 2)"#,
            mesh,
        )
        .unwrap()
        .scene;
        let slot = s.material(0).normal_texture.unwrap();
        assert_eq!(
            (slot.scale, slot.sampler.mag, slot.transform.is_identity()),
            (2.0, crate::materials::texture_slot::Filter::Nearest, false)
        );
        // A missing map is an error naming file, material and field, as for
        // the other textures; a sphere has no texture coordinates to map.
        let e =
            scene(r#"(base_color: (1, 1, 1), normal_texture: "gone.png")"#, mesh).map(|_| ()).unwrap_err();
        let e = e.to_string();
        assert!(
            e.starts_with("s.ron: material \"m\": normal_texture: cannot read texture")
                && e.contains("gone.png"),
            "{e}"
        );
        let sphere = r#"Sphere(center: (0, 0, 0), radius: 1, material: "m")"#;
        let s = scene(r#"(base_color: (1, 1, 1), normal_texture: "n.png")"#, sphere).unwrap().scene;
        let w = s.warnings().join("\n");
        assert!(w.contains("material \"m\": normal_texture is not used on objects[0] (Sphere)"), "{w}");
        for (text, expected) in [
            ("(base_color: (1, 1, 1), alpha: 1.5)", "material alpha must be 0 to 1, got 1.5"),
            ("(base_color: (1, 1, 1), alpha_cutoff: 0.2)", "alpha_cutoff applies to alpha_mode: Mask only"),
            ("(base_color: (1, 1, 1), alpha_mode: Mask, alpha_cutoff: -1)", "alpha_cutoff must be 0 to 1"),
            ("(base_color: (1, 1, 1), normal_scale: 2)", "normal_scale needs a normal_texture"),
            ("(base_color: (1, 1, 1), alpha_mode: Sometimes)", "s.ron:"),
        ] {
            let error = scene(text, sphere).map(|_| ()).unwrap_err().to_string();
            assert!(error.contains(expected), "{text}: {error}");
        }
    }

    #[test]
    fn mixing_the_two_models_or_bad_values_are_refused_naming_the_field() {
        let cases = [
            (
                "(base_color: (1, 1, 1), reflectivity: 0.5)",
                "material reflectivity belongs to the weights model",
            ),
            ("(color: (1, 1, 1), metallic: 1)", "material metallic belongs to the physically based model"),
            ("(color: (1, 1, 1), base_color: (1, 1, 1))", "both color"),
            ("(diffuse: 1)", "material needs a color"),
            ("(base_color: (1, 1, 1), roughness: 1.5)", "material roughness must be 0 to 1, got 1.5"),
            ("(base_color: (1, 1, 1), metallic: -0.1)", "material metallic must be 0 to 1, got -0.1"),
            ("(base_color: (1.2, 1, 1))", "material base_color is a reflectance"),
            (
                "(base_color: (1, 1, 1), attenuation_distance: 0)",
                "material attenuation_distance must be above 0",
            ),
            (
                "(base_color: (1, 1, 1), attenuation_color: (0, 1, 1))",
                "material attenuation_color must be above 0",
            ),
            (
                "(base_color: (1, 1, 1), emission_strength: -1)",
                "material emission_strength must be 0 or more",
            ),
            ("(base_color: (1, 1, 1), clearcoat: NaN)", "m.ron:"),
        ];
        for (text, expected) in cases {
            let error = material(text).unwrap_err();
            assert!(error.contains(expected), "{text}: {error}");
            assert!(error.starts_with("m.ron:2:"), "where it stands: {error}");
        }
    }

    #[test]
    fn textures_are_read_by_path_with_their_options_and_shared_between_materials() {
        use crate::materials::texture_slot::Wrap;
        use crate::materials::texture_slot::{Filter, Sampler};
        let dir = tempfile::tempdir().unwrap();
        image::RgbImage::from_pixel(2, 2, image::Rgb([128, 64, 255])).save(dir.path().join("t.png")).unwrap();
        let text = r#"Scene(camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
            image: (width: 8, height: 8),
            materials: {
                "a": (base_color: (1, 1, 1), base_color_texture: "t.png",
                      metallic_roughness_texture: (file: "t.png", tex_coord: 1, scale: (2, 2), rotation: 90,
                                                   filter: Nearest, mipmaps: false, wrap: ClampToEdge),
                      emissive_texture: "t.png", emission: (1, 1, 1)),
                "b": (color: (1, 1, 1), base_color_texture: (file: "t.png")),
            },
            objects: [Sphere(center: (0, 0, 0), radius: 1, material: "a"), Sphere(center: (3, 0, 0), radius: 1, material: "b")])"#;
        let loaded = parse_scene(text, "m.ron", dir.path()).unwrap();
        let s = &loaded.scene;
        // t.png as colour (sRGB) and as data (linear): two decodings for four uses.
        assert_eq!(s.texture_stats().0, 2);
        let (a, b) = (s.material(0), s.material(1));
        let (base, mr, e) = (
            a.base_color_texture.unwrap(),
            a.metallic_roughness_texture.unwrap(),
            a.emissive_texture.unwrap(),
        );
        assert_eq!((base.texture, e.texture, b.base_color_texture.unwrap().texture), (0, 0, 0));
        assert_eq!(mr.texture, 1);
        assert_eq!(base.sampler, Sampler::DEFAULT);
        assert_eq!(
            mr.sampler,
            Sampler { mag: Filter::Nearest, min: Filter::Nearest, mip: None, wrap: [Wrap::ClampToEdge; 2] }
        );
        let (u, v) = mr.transformed((1.0, 0.0));
        assert!(u.abs() < 1e-6 && (v + 2.0).abs() < 1e-6, "({u}, {v})");
        assert_eq!(mr.tex_coord, 1);
        assert_eq!(s.texture(1).sample(0.5, 0.5), Color::new(128.0 / 255.0, 64.0 / 255.0, 1.0));
        assert!(s.texture(0).sample(0.5, 0.5).x < 0.25);
        assert!(s.source_files().iter().any(|f| f.ends_with("t.png")));
    }

    #[test]
    fn a_texture_that_cannot_be_used_is_an_error_naming_the_material_and_field() {
        let dir = tempfile::tempdir().unwrap();
        let scene = |material: &str| {
            let text = format!(
                "Scene(camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
                image: (width: 8, height: 8), materials: {{ \"m\": {material} }},
                objects: [Sphere(center: (0, 0, 0), radius: 1, material: \"m\")])"
            );
            parse_scene(&text, "m.ron", dir.path()).map(|_| ()).unwrap_err().to_string()
        };
        let e = scene(r#"(base_color: (1, 1, 1), emissive_texture: "gone.png")"#);
        assert!(
            e.starts_with("m.ron: material \"m\": emissive_texture: cannot read texture ")
                && e.contains("gone.png"),
            "{e}"
        );
        let e = scene(r#"(base_color: (1, 1, 1), base_color_texture: (file: "t.png", tex_coord: 2))"#);
        assert!(e.contains("base_color_texture.tex_coord must be 0 or 1, got 2"), "{e}");
        let e = scene(r#"(color: (1, 1, 1), metallic_roughness_texture: "t.png")"#);
        assert!(e.contains("metallic_roughness_texture belongs to the physically based model"), "{e}");
    }
}
