//! The `materials` map's entries.

use serde::Deserialize;

use super::values::{ColorDesc, Finite, unit_scale};
use crate::material::{Color, Material};
use crate::real::{Real, to_f32};

/// A material as written: only `color` is required; the defaults make a
/// plain diffuse surface ([`Material::flat`]). Every weight is checked to
/// keep the material energy conserving ([`crate::bsdf`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Material")]
pub(super) struct MaterialFields {
    color: ColorDesc,
    #[serde(default = "unit_scale")]
    diffuse: Finite,
    #[serde(default)]
    specular: Finite,
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
            shininess: number(f.shininess, "shininess", |v| (0.0..=1e4).contains(&v), "0 to 10000")?,
            reflectivity: number(f.reflectivity, "reflectivity", unit, "0 to 1")?,
            transparency: number(f.transparency, "transparency", unit, "0 to 1")?,
            ior: number(f.ior, "ior", |v| v > 0.0 && v <= 100.0, "above 0 and at most 100")?,
            emission: f.emission.0,
        };
        if m.color.max_element() > 1.0 {
            return Err(format!(
                "material color is a reflectance: each component must be 0 to 1, got {}",
                m.color
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
