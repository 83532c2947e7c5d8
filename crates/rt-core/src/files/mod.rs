//! Reading what is written in files: scene files ([`scene_file`]), the
//! models they load (OBJ with its MTL materials, glTF 2.0; [`model`]
//! splits a model into meshes and materials), environment maps
//! ([`environment_image`]), and rays written as text, the `cast` command's
//! input ([`ray_text`]).

pub mod environment_image;
pub mod gltf_model;
#[cfg(test)]
mod gltf_mutation;
pub mod meshopt_views;
pub mod model;
pub mod mtl;
pub mod obj_model;
pub mod ray_text;
pub mod scene_file;
