//! The `objects` list: each primitive as written, validated where it stands.

use std::path::PathBuf;

use serde::Deserialize;

use super::values::{Finite, V3, unit_scale};
use crate::geometry::aabb::Aabb;
use crate::geometry::geometry_error::GeometryError;
use crate::geometry::plane::Plane;
use crate::geometry::polygon::Polygon;
use crate::geometry::primitive::Primitive;
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::math::real::{Real, Vec3};

/// The object variants exactly as written in a scene file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Object")]
pub(super) enum ObjectDesc {
    Sphere {
        center: V3,
        radius: Finite,
        material: String,
    },
    Plane {
        normal: V3,
        d: Finite,
        material: String,
    },
    Aabb {
        min: V3,
        max: V3,
        material: String,
    },
    Triangle {
        a: V3,
        b: V3,
        c: V3,
        material: String,
    },
    Polygon {
        points: Vec<V3>,
        material: String,
    },
    Mesh {
        file: PathBuf,
        // Written as a plain string, like every other object's material.
        #[serde(default, deserialize_with = "some_name")]
        material: Option<String>,
        #[serde(default = "unit_scale")]
        scale: Finite,
        #[serde(default)]
        translate: V3,
        // A glTF file's KHR_lights_punctual lights, added to the scene's.
        #[serde(default)]
        lights: bool,
    },
}

fn some_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    String::deserialize(d).map(Some)
}

/// An object whose geometry is validated, except a mesh's file, which is read later.
#[derive(Deserialize)]
#[serde(try_from = "ObjectDesc")]
pub(super) struct ObjectEntry(pub(super) Shape);

/// An object's geometry and material name: ready, or an OBJ file still to
/// be read, whose own materials are used when it names none.
pub(super) enum Shape {
    Ready { primitive: Primitive, material: String },
    Mesh { file: PathBuf, scale: Real, translate: Vec3, material: Option<String>, lights: bool },
}

impl TryFrom<ObjectDesc> for ObjectEntry {
    type Error = String;
    fn try_from(o: ObjectDesc) -> Result<Self, String> {
        let ready = |p: Result<Primitive, GeometryError>, material| {
            p.map(|primitive| Self(Shape::Ready { primitive, material })).map_err(|e| e.to_string())
        };
        match o {
            ObjectDesc::Sphere { center, radius, material } => {
                ready(Sphere::new(center.into(), radius.0).map(Primitive::Sphere), material)
            }
            ObjectDesc::Plane { normal, d, material } => {
                ready(Plane::new(normal.into(), d.0).map(Primitive::Plane), material)
            }
            ObjectDesc::Aabb { min, max, material } => {
                ready(Aabb::new(min.into(), max.into()).map(Primitive::Aabb), material)
            }
            ObjectDesc::Triangle { a, b, c, material } => {
                ready(Triangle::new(a.into(), b.into(), c.into()).map(Primitive::Triangle), material)
            }
            ObjectDesc::Polygon { points, material } => {
                let points = points.into_iter().map(Vec3::from).collect();
                ready(Polygon::new(points).map(Primitive::Polygon), material)
            }
            ObjectDesc::Mesh { file, material, scale, translate, lights } => {
                if scale.0 <= 0.0 {
                    return Err(format!("mesh scale must be positive, got {}", scale.0));
                }
                Ok(Self(Shape::Mesh { file, scale: scale.0, translate: translate.into(), material, lights }))
            }
        }
    }
}
