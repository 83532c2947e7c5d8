//! OBJ materials (MTL files) as rt-view materials.
//!
//! An MTL material describes a Phong-era surface: a diffuse colour `Kd`, a
//! specular colour `Ks` with exponent `Ns`, an index of refraction `Ni`, a
//! dissolve `d` (or its complement `Tr`), an emission `Ke`, an illumination
//! model `illum`, and texture maps. [`from_mtl`] maps them onto the one
//! radiometric model of [`crate::materials::bsdf`], field by field:
//!
//! | MTL | rt-view | rule |
//! |---|---|---|
//! | `Kd` | `color` | each component clamped to [0, 1] (default 0.8, Blender's) |
//! | `map_Kd` | `base_color_texture` | sRGB image, multiplies `Kd` ([`crate::materials::texture`]) |
//! | `Ks` | `specular` (or `reflectivity` with `illum` 3, 5, 7) and `specular_color` | its largest component, clamped to [0, 1], is the weight; `Ks` over it the tint |
//! | `Ns` | `shininess` | clamped to [0, 10 000] (default 32) |
//! | `Ni` | `ior` | must be above 0 and at most 100 (default 1.5) |
//! | `d`, `Tr` | `transparency` | `1 − d` (or `Tr`), clamped to [0, 1]: a dissolved surface becomes clear glass of index `Ni` |
//! | `Ke` | `emission` | components must be ≥ 0 |
//! | `illum` 3, 5, 7 | mirror | `Ks` becomes the mirror weight instead of the glossy one |
//!
//! Weights are then scaled so that `reflectivity + transparency ≤ 1`, which
//! keeps every material energy conserving.
//!
//! With the PBR extension of MTL (`Pr` roughness or `Pm` metallic present,
//! as Blender writes them) the material is physically based instead
//! ([`crate::materials::principled`]): base colour `Kd`, `metallic` `Pm`,
//! `roughness` `Pr`, `clearcoat` `Pc`, `clearcoat_roughness` `Pcr`, `ior`
//! `Ni`, `transmission` `1 − d` (or `Tr`), `emission` `Ke` (each of
//! `Pr`, `Pm`, `Pc`, `Pcr` from 0 to 1); `Ks`, `Ns` and `illum` are then
//! not used (and named). Its textures: `map_Pr` and `map_Pm` (linear
//! grey images, their first channel) replace `Pr` and `Pm`, as Blender's
//! importer reads them (they become one metallic-roughness texture,
//! glTF's layout); `map_Ke` (sRGB) multiplies `Ke`, or white when the file
//! gives no `Ke`. `Ps` (sheen) and `aniso`/`anisor` (anisotropy) have no
//! counterpart in the material (its GGX lobe is isotropic and has no sheen)
//! and are named, as is everything else (`Ka`, `map_Ks`, `map_d`, …):
//! named in the part's warnings, never dropped silently.
//!
//! A normal map, in either model: the PBR extension's `norm`, else
//! `map_Bump` or `bump` (as Blender writes and reads a normal map in MTL:
//! a linear tangent-space image, glTF's convention), its `-bm` option the
//! normal scale (default 1). A classic grey height map named by `map_Bump`
//! is read as a normal map too, and tilts the surface wrongly: MTL does not
//! say which of the two an image is.

use std::path::{Path, PathBuf};

use crate::materials::material::Material;
use crate::materials::principled::Principled;
use crate::math::color::Color;

/// An MTL material mapped onto a [`Material`].
#[derive(Clone, Debug, PartialEq)]
pub struct MtlMaterial {
    /// The material (its `texture` is left `None`: the scene numbers textures).
    pub material: Material,
    /// The `map_Kd` image, resolved against the OBJ file's folder.
    pub texture: Option<PathBuf>,
    /// The PBR extension's `map_Pr` (roughness) and `map_Pm` (metallic)
    /// images, resolved the same way: linear grey.
    pub roughness_texture: Option<PathBuf>,
    /// See `roughness_texture`.
    pub metallic_texture: Option<PathBuf>,
    /// The `map_Ke` image (sRGB), resolved the same way.
    pub emissive_texture: Option<PathBuf>,
    /// The normal map (`norm`, else `map_Bump`/`bump`), resolved the same
    /// way: linear tangent-space normals.
    pub normal_texture: Option<PathBuf>,
    /// The normal map's `-bm` option: how far its normals tilt (1 by default).
    pub normal_scale: f32,
    /// MTL statements read but not used, in a sentence each.
    pub ignored: Vec<String>,
}

/// Maps tobj's reading of an MTL material, from an OBJ file in `dir`.
/// Errors name the field and its value.
pub fn from_mtl(m: &tobj::Material, dir: &Path) -> Result<MtlMaterial, String> {
    let rgb = |v: [f32; 3], name: &str| -> Result<Color, String> {
        if v.iter().all(|c| c.is_finite() && *c >= 0.0) {
            Ok(Color::from_array(v))
        } else {
            Err(format!("{name} must be finite and not negative, got {} {} {}", v[0], v[1], v[2]))
        }
    };
    let number = |v: f32, name: &str| -> Result<f32, String> {
        if v.is_finite() { Ok(v) } else { Err(format!("{name} must be a finite number, got {v}")) }
    };
    let mut material = Material::flat(Color::splat(0.8));
    if let Some(kd) = m.diffuse {
        material.color = rgb(kd, "Kd")?.min(Color::ONE);
    }
    let ks = match m.specular {
        Some(ks) => {
            let ks = rgb(ks, "Ks")?;
            let weight = ks.max_element();
            if weight > 0.0 {
                material.specular_color = ks / weight;
            }
            weight.min(1.0)
        }
        None => 0.0,
    };
    let mirror = matches!(m.illumination_model, Some(3 | 5 | 7));
    if mirror {
        material.reflectivity = ks;
    } else {
        material.specular = ks;
    }
    if let Some(ns) = m.shininess {
        material.shininess = number(ns, "Ns")?.clamp(0.0, 1e4);
    }
    if let Some(ni) = m.optical_density {
        let ni = number(ni, "Ni")?;
        if !(ni > 0.0 && ni <= 100.0) {
            return Err(format!("Ni (index of refraction) must be above 0 and at most 100, got {ni}"));
        }
        material.ior = ni;
    }
    let tr = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => Some(1.0 - number(d, "d")?),
        (None, Some(tr)) => {
            Some(number(tr.trim().parse().map_err(|_| format!("Tr must be a number, got {tr}"))?, "Tr")?)
        }
        (None, None) => None,
    };
    if let Some(tr) = tr {
        material.transparency = tr.clamp(0.0, 1.0);
    }
    let sum = material.reflectivity + material.transparency;
    if sum > 1.0 {
        material.reflectivity /= sum;
        material.transparency /= sum;
    }
    if let Some(ke) = m.emissive {
        material.emission = rgb(ke, "Ke")?;
    }
    let texture = m.diffuse_texture.as_ref().map(|t| dir.join(texture_file(t)));
    let mut ignored = Vec::new();
    // The PBR extension: a physically based material instead of the weights.
    let pbr_value = |key: &str| -> Result<Option<f32>, String> {
        match m.unknown_param.get(key) {
            None => Ok(None),
            Some(v) => match v.trim().parse::<f32>() {
                Ok(x) if (0.0..=1.0).contains(&x) => Ok(Some(x)),
                _ => Err(format!("{key} must be a number from 0 to 1, got {v}")),
            },
        }
    };
    let (pr, pm, pc, pcr) = (pbr_value("Pr")?, pbr_value("Pm")?, pbr_value("Pc")?, pbr_value("Pcr")?);
    let map = |key: &str| -> Result<Option<PathBuf>, String> {
        match m.unknown_param.get(key).map(|v| texture_file(v)) {
            None => Ok(None),
            Some("") => Err(format!("{key} names no file")),
            Some(file) => Ok(Some(dir.join(file))),
        }
    };
    let (roughness_texture, metallic_texture) = (map("map_Pr")?, map("map_Pm")?);
    let emissive_texture = map("map_Ke")?;
    let normal_statement = match m.unknown_param.get("norm") {
        Some(v) => Some(("norm", v.as_str())),
        None => m.normal_texture.as_deref().map(|v| ("map_Bump", v)),
    };
    let (normal_texture, normal_scale) = match normal_statement {
        None => (None, 1.0),
        Some((key, value)) => match texture_file(value) {
            "" => return Err(format!("{key} names no file")),
            file => (Some(dir.join(file)), bump_multiplier(value).map_err(|e| format!("{key} {e}"))?),
        },
    };
    if emissive_texture.is_some() && m.emissive.is_none() {
        material.emission = Color::ONE;
    }
    // A texture replaces its factor (as Blender's importer reads it).
    let (pr, pm) = (
        if roughness_texture.is_some() { Some(1.0) } else { pr },
        if metallic_texture.is_some() { Some(1.0) } else { pm },
    );
    if pr.is_some() || pm.is_some() {
        let d = Principled::DIELECTRIC;
        let p = Principled {
            metallic: pm.unwrap_or(d.metallic),
            roughness: pr.unwrap_or(d.roughness),
            transmission: tr.unwrap_or(0.0).clamp(0.0, 1.0),
            clearcoat: pc.unwrap_or(0.0),
            clearcoat_roughness: pcr.unwrap_or(0.0),
            ..d
        };
        material = Material {
            ior: material.ior,
            emission: material.emission,
            ..Material::principled(material.color, p)
        };
        for (name, present) in [
            ("Ks", m.specular.is_some()),
            ("Ns", m.shininess.is_some()),
            ("illum", m.illumination_model.is_some()),
        ] {
            if present {
                ignored.push(format!("{name} (the PBR fields Pr/Pm define the material)"));
            }
        }
    }
    for (name, value) in [
        ("Ka", m.ambient.is_some()),
        ("map_Ka", m.ambient_texture.is_some()),
        ("map_Ks", m.specular_texture.is_some()),
        ("map_Ns", m.shininess_texture.is_some()),
        (
            "map_Bump (norm gives the normal map)",
            m.normal_texture.is_some() && normal_statement.is_some_and(|(k, _)| k == "norm"),
        ),
        ("map_d", m.dissolve_texture.is_some()),
    ] {
        if value {
            ignored.push(name.to_owned());
        }
    }
    for (key, why) in [
        ("Ps", "sheen: the material has no sheen lobe"),
        ("aniso", "anisotropy: the material's GGX lobe is isotropic"),
        ("anisor", "anisotropy: the material's GGX lobe is isotropic"),
    ] {
        if m.unknown_param.contains_key(key) {
            ignored.push(format!("{key} ({why})"));
        }
    }
    let read = ["Tr", "Pr", "Pm", "Pc", "Pcr", "map_Pr", "map_Pm", "map_Ke", "Ps", "aniso", "anisor", "norm"];
    let mut unknown: Vec<&String> = m.unknown_param.keys().filter(|k| !read.contains(&k.as_str())).collect();
    unknown.sort();
    ignored.extend(unknown.into_iter().cloned());
    Ok(MtlMaterial {
        material,
        texture,
        roughness_texture,
        metallic_texture,
        emissive_texture,
        normal_texture,
        normal_scale,
        ignored,
    })
}

/// A texture statement's `-bm` (bump multiplier) option, 1 when absent;
/// what is wrong with it otherwise.
fn bump_multiplier(value: &str) -> Result<f32, String> {
    let mut words = value.split_whitespace();
    while let Some(word) = words.next() {
        if word == "-bm" {
            let v = words.next().unwrap_or("");
            return match v.parse::<f32>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(format!("-bm must be a number, got {v:?}")),
            };
        }
    }
    Ok(1.0)
}

/// The file name of a texture statement's value: MTL allows options before
/// it (`map_Kd -s 1 1 1 wood.png`); the name is the last word.
fn texture_file(value: &str) -> &str {
    value.split_whitespace().last().unwrap_or(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> tobj::Material {
        let (mut materials, _) = tobj::load_mtl_buf(&mut text.as_bytes()).unwrap();
        materials.remove(0)
    }

    #[test]
    fn pbr_maps_replace_their_factors_and_what_has_no_counterpart_is_named() {
        let m = parse(
            "newmtl a\nKd 1 1 1\nPr 0.3\nmap_Pr r.png\nmap_Pm -bm 1 m.png\nmap_Ke e.png\nPs 0.2\naniso 0.5\nnorm n.png\n",
        );
        let got = from_mtl(&m, Path::new("models")).unwrap();
        let p = got.material.physical.unwrap();
        assert_eq!((p.roughness, p.metallic), (1.0, 1.0));
        assert_eq!(got.material.emission, Color::ONE);
        assert_eq!(got.roughness_texture, Some(PathBuf::from("models/r.png")));
        assert_eq!(got.metallic_texture, Some(PathBuf::from("models/m.png")));
        assert_eq!(got.emissive_texture, Some(PathBuf::from("models/e.png")));
        let ignored = got.ignored.join("; ");
        for name in ["Ps (sheen", "aniso (anisotropy"] {
            assert!(ignored.contains(name), "{name}: {ignored}");
        }
        assert!(
            !ignored.contains("map_P") && !ignored.contains("map_Ke") && !ignored.contains("norm"),
            "{ignored}"
        );
        assert_eq!((got.normal_texture, got.normal_scale), (Some(PathBuf::from("models/n.png")), 1.0));
        // Ke is kept and multiplied by its map.
        let got = from_mtl(&parse("newmtl a\nKe 2 2 2\nmap_Ke e.png\n"), Path::new(".")).unwrap();
        assert_eq!(got.material.emission, Color::splat(2.0));
    }

    #[test]
    fn every_mapped_field_lands_where_the_table_says() {
        let m = parse(
            "newmtl a\nKd 0.5 0.25 2\nKs 0.3 0.3 0.3\nNs 100\nNi 1.33\nd 0.4\nKe 1 2 3\nmap_Kd -s 1 1 1 tex/wood.png\n",
        );
        let got = from_mtl(&m, Path::new("models")).unwrap();
        let mat = got.material;
        assert_eq!(mat.color, Color::new(0.5, 0.25, 1.0));
        assert!((mat.specular - 0.3).abs() < 1e-6 && mat.reflectivity == 0.0);
        assert_eq!((mat.shininess, mat.ior), (100.0, 1.33));
        assert!((mat.transparency - 0.6).abs() < 1e-6);
        assert_eq!(mat.emission, Color::new(1.0, 2.0, 3.0));
        assert_eq!(got.texture, Some(PathBuf::from("models/tex/wood.png")));
        assert!(got.ignored.is_empty(), "{:?}", got.ignored);
    }

    #[test]
    fn the_pbr_extension_makes_a_physically_based_material_from_its_fields() {
        let text = "newmtl a\nKd 0.9 0.5 0.1\nKs 0.5 0.5 0.5\nNs 250\nPr 0.3\nPm 1\nPc 0.5\nPcr 0.1\nNi 1.6\nd 0.75\nKe 1 0 0\n";
        let mapped = from_mtl(&parse(text), Path::new(".")).unwrap();
        let m = mapped.material;
        let p = m.physical.unwrap();
        assert_eq!((m.color, m.ior, m.emission), (Color::new(0.9, 0.5, 0.1), 1.6, Color::new(1.0, 0.0, 0.0)));
        assert_eq!((p.metallic, p.roughness, p.clearcoat, p.clearcoat_roughness), (1.0, 0.3, 0.5, 0.1));
        assert!((p.transmission - 0.25).abs() < 1e-6);
        assert!(
            mapped.ignored.iter().any(|i| i.starts_with("Ks"))
                && mapped.ignored.iter().any(|i| i.starts_with("Ns"))
        );
        assert!(!mapped.ignored.iter().any(|i| i == "Pr" || i == "Pm"), "{:?}", mapped.ignored);
        let e = from_mtl(&parse("newmtl a\nPr 2\n"), Path::new(".")).unwrap_err();
        assert_eq!(e, "Pr must be a number from 0 to 1, got 2");
    }

    #[test]
    fn norm_or_map_bump_is_the_normal_map_and_bm_its_scale() {
        let got = from_mtl(&parse("newmtl a\nmap_Bump -bm 0.5 tex/n.png\n"), Path::new("m")).unwrap();
        assert_eq!((got.normal_texture, got.normal_scale), (Some(PathBuf::from("m/tex/n.png")), 0.5));
        assert!(got.ignored.is_empty(), "{:?}", got.ignored);
        // The PBR extension's norm wins over map_Bump, which is then named.
        let got =
            from_mtl(&parse("newmtl a\nPr 0.5\nnorm -bm 2 a.png\nbump b.png\n"), Path::new(".")).unwrap();
        assert_eq!((got.normal_texture, got.normal_scale), (Some(PathBuf::from("./a.png")), 2.0));
        assert_eq!(got.ignored, ["map_Bump (norm gives the normal map)"]);
        let e = from_mtl(&parse("newmtl a\nmap_Bump -bm x n.png\n"), Path::new(".")).unwrap_err();
        assert!(e.starts_with("map_Bump -bm must be a number"), "{e}");
    }

    #[test]
    fn mirror_illumination_models_turn_ks_into_a_mirror_and_weights_stay_energy_conserving() {
        let m = parse("newmtl a\nKs 1 0.8 0.4\nillum 3\nTr 0.5\n");
        let mat = from_mtl(&m, Path::new(".")).unwrap().material;
        assert_eq!(mat.specular_color, Color::new(1.0, 0.8, 0.4));
        assert_eq!(mat.specular, 0.0);
        assert!((mat.reflectivity + mat.transparency - 1.0).abs() < 1e-6, "{mat:?}");
        assert!((mat.reflectivity - 2.0 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn defaults_without_fields_are_a_grey_diffuse_surface() {
        let mat = from_mtl(&parse("newmtl a\n"), Path::new(".")).unwrap().material;
        assert_eq!(mat, Material::flat(Color::splat(0.8)));
    }

    #[test]
    fn unused_statements_are_named_and_bad_values_are_errors_naming_the_field() {
        let m = parse("newmtl a\nKa 1 1 1\nmap_Bump n.png\naniso 0.5\n");
        let got = from_mtl(&m, Path::new(".")).unwrap();
        assert_eq!(got.ignored, ["Ka", "aniso (anisotropy: the material's GGX lobe is isotropic)"]);
        assert_eq!((got.normal_texture, got.normal_scale), (Some(PathBuf::from("./n.png")), 1.0));
        for (text, field) in
            [("Kd -1 0 0", "Kd"), ("Ke 0 -2 0", "Ke"), ("Ni 0", "Ni"), ("Ni 500", "Ni"), ("Tr x", "Tr")]
        {
            let e = from_mtl(&parse(&format!("newmtl a\n{text}\n")), Path::new(".")).unwrap_err();
            assert!(e.starts_with(field), "{text}: {e}");
        }
    }
}
