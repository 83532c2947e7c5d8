//! The `materials` map's entries.

use serde::Deserialize;

use super::values::{ColorDesc, Finite, unit_scale};
use crate::materials::material::Material;
use crate::materials::medium::Subsurface;
use crate::math::color::Color;
use crate::math::real::{Real, to_f32};

/// A material as written: only `color` is required; the defaults make a
/// plain diffuse surface ([`Material::flat`]). Every weight is checked to
/// keep the material energy conserving ([`crate::materials::bsdf`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Material")]
pub(super) struct MaterialFields {
    color: ColorDesc,
    #[serde(default = "unit_scale")]
    diffuse: Finite,
    #[serde(default)]
    specular: Finite,
    #[serde(default = "super::values::white")]
    specular_color: ColorDesc,
    #[serde(default = "default_shininess")]
    shininess: Finite,
    #[serde(default)]
    reflectivity: Finite,
    #[serde(default)]
    transparency: Finite,
    #[serde(default = "default_ior")]
    ior: Finite,
    #[serde(default)]
    emission: ColorDesc,
    #[serde(default, deserialize_with = "super::values::present")]
    subsurface: Option<SubsurfaceDesc>,
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
        let mean_free_path = color(mfp).max(Color::splat(1e-30));
        Ok(Self(Subsurface { albedo: color(albedo), mean_free_path, anisotropy: to_f32(g) }))
    }
}

#[derive(Deserialize)]
#[serde(try_from = "MaterialFields")]
pub(super) struct MaterialDesc(pub(super) Material);

impl TryFrom<MaterialFields> for MaterialDesc {
    type Error = String;
    fn try_from(f: MaterialFields) -> Result<Self, String> {
        let number = |Finite(v): Finite, name: &str, ok: fn(Real) -> bool, rule: &str| {
            if ok(v) { Ok(to_f32(v)) } else { Err(format!("material {name} must be {rule}, got {v}")) }
        };
        let unit = |v: Real| (0.0..=1.0).contains(&v);
        let m = Material {
            color: f.color.0,
            diffuse: number(f.diffuse, "diffuse", unit, "0 to 1")?,
            specular: number(f.specular, "specular", unit, "0 to 1")?,
            specular_color: f.specular_color.0,
            shininess: number(f.shininess, "shininess", |v| (0.0..=1e4).contains(&v), "0 to 10000")?,
            reflectivity: number(f.reflectivity, "reflectivity", unit, "0 to 1")?,
            transparency: number(f.transparency, "transparency", unit, "0 to 1")?,
            ior: number(f.ior, "ior", |v| v > 0.0 && v <= 100.0, "above 0 and at most 100")?,
            emission: f.emission.0,
            subsurface: f.subsurface.map(|s| s.0),
            texture: None,
        };
        if m.color.max_element() > 1.0 {
            return Err(format!(
                "material color is a reflectance: each component must be 0 to 1, got {}",
                m.color
            ));
        }
        if m.specular_color.max_element() > 1.0 {
            return Err(format!(
                "material specular_color is a reflectance: each component must be 0 to 1, got {}",
                m.specular_color
            ));
        }
        if m.reflectivity + m.transparency > 1.0 {
            return Err(format!(
                "material reflectivity + transparency must not exceed 1, got {} + {}",
                m.reflectivity, m.transparency
            ));
        }
        Ok(Self(m))
    }
}

pub(super) fn default_shininess() -> Finite {
    Finite(Material::flat(Color::ZERO).shininess as Real)
}
pub(super) fn default_ior() -> Finite {
    Finite(Material::flat(Color::ZERO).ior as Real)
}
