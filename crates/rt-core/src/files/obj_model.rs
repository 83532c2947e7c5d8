//! OBJ files with their MTL materials as a [`Model`]: the faces split by
//! material ([`Mesh::load_obj_parts`]), the MTL materials mapped onto
//! rt-view's ([`crate::files::mtl`], which has the field-by-field table) and their
//! `map_Kd` textures read ([`crate::materials::texture`]). An MTL file or a texture that
//! cannot be read is a warning with a fallback; a bad MTL value an error.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::files::model::{Model, ModelError};
use crate::files::mtl::from_mtl;
use crate::geometry::mesh::Mesh;
use crate::materials::texture::Texture;
use crate::materials::texture_slot::TextureSlot;
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
    let mut texture_of: HashMap<PathBuf, Option<u32>> = HashMap::new();
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
        if let Some(file) = mapped.texture {
            if !files.contains(&file) {
                files.push(file.clone());
            }
            let texture = *texture_of.entry(file.clone()).or_insert_with(|| match Texture::load(&file) {
                Ok(t) => {
                    textures.push(t);
                    Some(textures.len() as u32 - 1)
                }
                Err(e) => {
                    warnings.push(format!("{e}: its materials show their Kd colour instead"));
                    None
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
    Ok(Model { parts, materials, textures, warnings, files })
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
        assert_eq!(model.warnings, ["material \"tex\": not used: map_Bump/norm"]);
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
