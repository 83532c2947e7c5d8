//! OBJ files with their MTL materials as a [`Model`]: the faces split by
//! material ([`Mesh::load_obj_parts`]), the MTL materials mapped onto
//! rt-view's ([`crate::files::mtl`], which has the field-by-field table) and their
//! textures (`map_Kd`, the PBR maps, the normal map) read ([`crate::materials::texture`]). An MTL file or a texture that
//! cannot be read is a warning with a fallback; a bad MTL value an error.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::files::model::{Model, ModelError};
use crate::files::mtl::from_mtl;
use crate::geometry::mesh::Mesh;
use crate::materials::texture::Texture;
use crate::materials::texture_slot::{Encoding, TextureSlot};
use crate::math::real::{Real, Vec3};

/// Reads an OBJ file split by material ([`Mesh::load_obj_parts`]) with its
/// MTL materials ([`crate::files::mtl`]) and their `map_Kd` textures, every vertex
/// then scaled by `scale` and moved by `translate`.
pub fn load(path: &Path, scale: Real, translate: Vec3) -> Result<Model, ModelError> {
    let obj = Mesh::load_obj_parts(path, scale, translate)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut warnings = Vec::new();
    let mut files = obj.mtl_files;
    let mtl = match obj.materials {
        Ok(m) if m.is_empty() => {
            warnings.push(
                "it has no materials (no mtllib): its faces are diffuse grey; give the Mesh a material to choose one"
                    .to_owned(),
            );
            Vec::new()
        }
        Ok(m) => m,
        Err(reason) => {
            warnings.push(format!("its materials cannot be read ({reason}): its faces are diffuse grey"));
            Vec::new()
        }
    };
    // Only the materials that faces use, numbered in order of first use.
    let mut index_of: HashMap<usize, usize> = HashMap::new();
    let mut materials = Vec::new();
    let mut textures = Vec::new();
    let mut texture_of: HashMap<(PathBuf, Encoding), Option<u32>> = HashMap::new();
    let mut parts = Vec::new();
    let mut faces_without = false;
    for (mesh, material) in obj.parts {
        let Some(i) = material.filter(|&i| i < mtl.len()) else {
            faces_without = true;
            parts.push((mesh, None));
            continue;
        };
        if let Some(&k) = index_of.get(&i) {
            parts.push((mesh, Some(k)));
            continue;
        }
        let name = mtl[i].name.clone();
        let mapped = from_mtl(&mtl[i], dir).map_err(|reason| ModelError::Material {
            path: path.to_owned(),
            material: name.clone(),
            reason,
        })?;
        if !mapped.ignored.is_empty() {
            warnings.push(format!("material \"{name}\": not used: {}", mapped.ignored.join(", ")));
        }
        let mut m = mapped.material;
        // The PBR extension's maps: each image decoded once per encoding.
        let pbr_maps = [&mapped.roughness_texture, &mapped.metallic_texture, &mapped.emissive_texture];
        if pbr_maps.iter().any(|t| t.is_some()) && !mesh.has_uvs() {
            warnings.push(format!(
                "material \"{name}\": its map_Pr/map_Pm/map_Ke are not used: its faces have no texture coordinates"
            ));
        }
        if let Some(file) = mapped.normal_texture.as_ref().filter(|_| !mesh.has_uvs()) {
            warnings.push(format!(
                "material \"{name}\": its normal map {} is not used: its faces have no texture coordinates",
                file.display()
            ));
        }
        let mut decode = |file: &PathBuf, encoding: Encoding, field: &str| {
            if !files.contains(file) {
                files.push(file.clone());
            }
            match Texture::load_as(file, encoding) {
                Ok(t) => Some(t),
                Err(e) => {
                    warnings.push(format!("{e}: material \"{name}\" shows {field} instead"));
                    None
                }
            }
        };
        let has_uvs = mesh.has_uvs();
        let slot_of = |texture: Option<Texture>, textures: &mut Vec<Texture>| {
            let texture = texture.filter(|_| has_uvs)?;
            textures.push(texture);
            Some(TextureSlot::new(textures.len() as u32 - 1))
        };
        if mapped.roughness_texture.is_some() || mapped.metallic_texture.is_some() {
            let roughness =
                mapped.roughness_texture.as_ref().and_then(|f| decode(f, Encoding::Linear, "its Pr factor"));
            let metallic =
                mapped.metallic_texture.as_ref().and_then(|f| decode(f, Encoding::Linear, "its Pm factor"));
            let combined = Texture::metallic_roughness(roughness.as_ref(), metallic.as_ref());
            m.metallic_roughness_texture = slot_of(combined, &mut textures);
        }
        if let Some(file) = &mapped.emissive_texture {
            let key = (file.clone(), Encoding::Srgb);
            m.emissive_texture = match texture_of.get(&key) {
                Some(index) => index.map(TextureSlot::new),
                None => {
                    let slot = slot_of(decode(file, Encoding::Srgb, "its Ke factor"), &mut textures);
                    texture_of.insert(key, slot.map(|s| s.texture));
                    slot
                }
            };
        }
        if let Some(file) = &mapped.normal_texture {
            let key = (file.clone(), Encoding::Linear);
            let slot = match texture_of.get(&key) {
                Some(index) => index.map(TextureSlot::new),
                None => {
                    let slot = slot_of(decode(file, Encoding::Linear, "its unmapped normals"), &mut textures);
                    texture_of.insert(key, slot.map(|s| s.texture));
                    slot
                }
            };
            m.normal_texture =
                slot.filter(|_| has_uvs).map(|s| TextureSlot { scale: mapped.normal_scale, ..s });
        }
        if let Some(file) = mapped.texture {
            if !files.contains(&file) {
                files.push(file.clone());
            }
            let texture = *texture_of.entry((file.clone(), Encoding::Srgb)).or_insert_with(|| {
                match Texture::load(&file) {
                    Ok(t) => {
                        textures.push(t);
                        Some(textures.len() as u32 - 1)
                    }
                    Err(e) => {
                        warnings.push(format!("{e}: its materials show their Kd colour instead"));
                        None
                    }
                }
            });
            if texture.is_some() && !mesh.has_uvs() {
                warnings.push(format!(
                    "material \"{name}\": its texture {} is not used: its faces have no texture coordinates",
                    file.display()
                ));
            }
            m.base_color_texture = texture.map(TextureSlot::new);
        }
        index_of.insert(i, materials.len());
        parts.push((mesh, Some(materials.len())));
        materials.push((name, m));
    }
    if faces_without && !mtl.is_empty() {
        warnings.push(
            "some faces have no material (no usemtl, or a name no MTL file defines): they are diffuse grey"
                .to_owned(),
        );
    }
    Ok(Model { parts, materials, textures, warnings, files, cameras: 0 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::color::Color;

    /// Writes `files` (name, contents) into a new folder.
    fn folder(files: &[(&str, &[u8])]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).unwrap();
        }
        dir
    }

    const TWO_MATERIALS: &[u8] =
        b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
        usemtl red\nf 1/1 2/2 3/3\nusemtl tex\nf 2/2 4/1 3/3\nusemtl red\nf 1 3 4\n";

    fn png(dir: &Path, name: &str) {
        image::RgbImage::from_pixel(2, 2, image::Rgb([255, 128, 0])).save(dir.join(name)).unwrap();
    }

    #[test]
    fn an_obj_file_is_split_by_material_with_its_mtl_materials_and_textures() {
        let dir = folder(&[
            ("m.obj", TWO_MATERIALS),
            (
                "m.mtl",
                b"newmtl red\nKd 1 0 0\nKe 0 0 2\nnewmtl tex\nKd 1 1 1\nmap_Kd t.png\nmap_Bump n.png\n",
            ),
        ]);
        png(dir.path(), "t.png");
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        // Parts in order of first use: red (two faces), then tex.
        let names: Vec<&str> = model.materials.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["red", "tex"]);
        let parts: Vec<(usize, Option<usize>)> =
            model.parts.iter().map(|(m, i)| (m.triangle_count(), *i)).collect();
        assert_eq!(parts, [(2, Some(0)), (1, Some(1))]);
        assert_eq!(model.materials[0].1.emission, Color::new(0.0, 0.0, 2.0));
        assert_eq!(model.materials[1].1.base_color_texture, Some(TextureSlot::new(0)));
        assert_eq!(model.textures.len(), 1);
        let orange = model.textures[0].sample(0.5, 0.5);
        assert!(
            (orange - Color::new(1.0, crate::materials::texture::srgb_decode(128.0 / 255.0), 0.0)).length()
                < 1e-6
        );
        // Its normal map (map_Bump) is missing: named, with the fallback.
        assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
        let w = &model.warnings[0];
        assert!(
            w.contains("n.png") && w.ends_with("material \"tex\" shows its unmapped normals instead"),
            "{w}"
        );
    }

    #[test]
    fn mtl_roughness_and_metallic_maps_become_one_linear_texture_and_emission_an_srgb_one() {
        let dir = folder(&[
            ("m.obj", TWO_MATERIALS),
            (
                "m.mtl",
                b"newmtl red\nKd 1 0 0\nnewmtl tex\nKd 1 1 1\nmap_Pr r.png\nmap_Pm m.png\nmap_Ke e.png\n",
            ),
        ]);
        image::GrayImage::from_pixel(2, 2, image::Luma([64])).save(dir.path().join("r.png")).unwrap();
        image::GrayImage::from_pixel(4, 1, image::Luma([255])).save(dir.path().join("m.png")).unwrap();
        png(dir.path(), "e.png");
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        let m = model.materials[1].1;
        let (mr, e) = (m.metallic_roughness_texture.unwrap(), m.emissive_texture.unwrap());
        let combined = &model.textures[mr.texture as usize];
        assert_eq!(combined.size(), (4, 2));
        assert_eq!(combined.sample(0.5, 0.5), Color::new(1.0, 64.0 / 255.0, 1.0));
        let glow = model.textures[e.texture as usize].sample(0.5, 0.5);
        assert!((glow.y - crate::materials::texture::srgb_decode(128.0 / 255.0)).abs() < 1e-6);
        assert!(model.warnings.is_empty(), "{:?}", model.warnings);
        // A missing map is a warning naming it and the material.
        std::fs::remove_file(dir.path().join("r.png")).unwrap();
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        assert!(
            model
                .warnings
                .iter()
                .any(|w| w.contains("r.png") && w.contains("material \"tex\" shows its Pr factor")),
            "{:?}",
            model.warnings
        );
    }

    #[test]
    fn an_mtl_normal_map_becomes_a_linear_normal_slot_with_its_bump_multiplier() {
        let dir = folder(&[
            ("m.obj", TWO_MATERIALS),
            ("m.mtl", b"newmtl red\nKd 1 0 0\nnewmtl tex\nKd 1 1 1\nmap_Bump -bm 0.5 n.png\n"),
        ]);
        png(dir.path(), "n.png");
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        let slot = model.materials[1].1.normal_texture.unwrap();
        assert_eq!((slot.texture, slot.scale, slot.tex_coord), (0, 0.5, 0));
        // Linear: 128/255 as it is, not sRGB-decoded.
        assert_eq!(model.textures[0].sample(0.5, 0.5), Color::new(1.0, 128.0 / 255.0, 0.0));
        assert!(model.warnings.is_empty(), "{:?}", model.warnings);
        assert_eq!(model.materials[0].1.normal_texture, None);
    }

    #[test]
    fn an_mtl_colour_of_one_number_is_a_grey_and_of_none_or_two_a_warning_naming_the_line() {
        // The MTL specification's `Kd r` is `Kd r r r`. tobj 4.0.5 panicked
        // on colours of fewer than three numbers.
        let dir = folder(&[("m.obj", TWO_MATERIALS), ("m.mtl", b"newmtl red\nKd 0.25\nKe 2\nnewmtl tex\n")]);
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        let red = &model.materials[0].1;
        assert_eq!((red.color, red.emission), (Color::splat(0.25), Color::splat(2.0)));
        for (statement, line) in [("Ks 0.5 0.5", 3), ("Ka", 3), ("Ke 1 0", 3)] {
            let mtl = format!("newmtl red\nKd 1 0 0\n{statement}\nnewmtl tex\n");
            let dir = folder(&[("m.obj", TWO_MATERIALS), ("m.mtl", mtl.as_bytes())]);
            let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
            assert!(model.materials.is_empty(), "{statement}");
            let key = statement.split(' ').next().unwrap();
            assert!(
                model.warnings[0].starts_with("its materials cannot be read (")
                    && model.warnings[0].contains(&format!("m.mtl line {line}: {key} gives")),
                "{:?}",
                model.warnings
            );
        }
        // Not UTF-8: unreadable, said, as tobj says of a line it cannot read.
        let dir = folder(&[("m.obj", TWO_MATERIALS), ("m.mtl", b"newmtl red\nKd 1\n\xff\n")]);
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        assert!(model.warnings[0].contains("m.mtl: not UTF-8 text"), "{:?}", model.warnings);
    }

    #[test]
    fn missing_materials_and_textures_are_warnings_with_a_fallback() {
        // No MTL file at all: every face grey, said once.
        let dir = folder(&[("m.obj", TWO_MATERIALS)]);
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        assert!(model.materials.is_empty() && model.parts.iter().all(|(_, m)| m.is_none()));
        assert_eq!(model.warnings.len(), 1);
        assert!(model.warnings[0].starts_with("its materials cannot be read"), "{:?}", model.warnings);

        // A texture that is not there: the material keeps its Kd, said.
        let dir = folder(&[
            ("m.obj", TWO_MATERIALS),
            ("m.mtl", b"newmtl red\nnewmtl tex\nKd 0.5 0.5 0.5\nmap_Kd gone.png\n"),
        ]);
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        assert_eq!(model.materials[1].1.base_color_texture, None);
        assert_eq!(model.materials[1].1.color, Color::splat(0.5));
        assert!(
            model.warnings.iter().any(|w| w.contains("gone.png") && w.contains("Kd colour")),
            "{:?}",
            model.warnings
        );

        // Faces before any usemtl get the default, said.
        let dir = folder(&[
            ("m.obj", b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl a\nf 3 2 1\n"),
            ("m.mtl", b"newmtl a\n"),
        ]);
        let model = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap();
        assert_eq!(model.parts.iter().map(|(_, m)| *m).collect::<Vec<_>>(), [None, Some(0)]);
        assert!(
            model.warnings.iter().any(|w| w.starts_with("some faces have no material")),
            "{:?}",
            model.warnings
        );
    }

    #[test]
    fn a_bad_mtl_value_is_an_error_naming_the_file_the_material_and_the_field() {
        let dir = folder(&[("m.obj", TWO_MATERIALS), ("m.mtl", b"newmtl red\nNi -2\nnewmtl tex\n")]);
        let e = load(&dir.path().join("m.obj"), 1.0, Vec3::ZERO).unwrap_err().to_string();
        assert!(e.starts_with("OBJ file ") && e.contains("m.obj: material \"red\": Ni"), "{e}");
    }
}
