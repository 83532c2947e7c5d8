//! Helpers shared by the crate's tests: random primitives and small scenes.

use crate::camera::{Camera, Projection};
use crate::files::scene_file::LoadedScene;
use crate::geometry::aabb::Aabb;
use crate::geometry::mesh::Mesh;
use crate::geometry::plane::Plane;
use crate::geometry::polygon::Polygon;
use crate::geometry::primitive::Primitive;
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::materials::material::Material;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3, to_f32};
use crate::render::Renderer;
use crate::render::settings::{ImageSize, RenderSettings, SamplesPerPixel};
use crate::scene::effects::Effects;
use crate::scene::{Scene, SceneBuilder};
use proptest::prelude::*;

/// An f32 triple as a [`Vec3`].
pub fn v(a: [f32; 3]) -> Vec3 {
    Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real)
}

/// A primitive of kind `kind % 6` built from three points; `None` where they
/// make an invalid one. Kind 5 is a mesh of ten triangles over twelve shared
/// vertices spread across the triangle (p, q, r), so some triangles touch.
pub fn random_primitive(kind: u8, p: [f32; 3], q: [f32; 3], r: [f32; 3]) -> Option<Primitive> {
    match kind % 6 {
        0 => Sphere::new(v(p), q[0].abs() as Real).ok().map(Primitive::Sphere),
        1 => Plane::new(v(q), p[0] as Real).ok().map(Primitive::Plane),
        2 => Some(Primitive::Aabb(Aabb::from_corners(v(p), v(q)))),
        3 => Triangle::new(v(p), v(q), v(r)).ok().map(Primitive::Triangle),
        4 => Polygon::new(vec![v(p), v(q), v(q) + v(r) - v(p), v(r)]).ok().map(Primitive::Polygon),
        _ => {
            let (positions, triangles) = spread_mesh(p, q, r);
            Mesh::new(positions, triangles).map(Primitive::Mesh)
        }
    }
}

/// The vertices and triangles of [`random_primitive`]'s mesh: ten
/// triangles over twelve vertices spread across the triangle (p, q, r).
fn spread_mesh(p: [f32; 3], q: [f32; 3], r: [f32; 3]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (a, b, c) = (v(p), v(q), v(r));
    let spread = |k: usize, m: usize| (k * m % 12) as Real / 11.0;
    let positions = (0..12).map(|k| a + (b - a) * spread(k, 7) + (c - a) * spread(k, 5)).collect();
    let triangles = (0..10u32).map(|k| [k, k + 1, (k + 2) % 12]).collect();
    (positions, triangles)
}

/// [`random_primitive`], with shading normals and texture coordinates at
/// every vertex where it is a mesh (other primitives have neither): vertex
/// k's normal is the normal of (p, q, r) plus `tilt` scaled by k/11 (so
/// normals vary across the mesh, tilted up to about 60° for a tilt of
/// length 2, and may point either way), and its (u, v) its x and z times
/// `uv_scale`, so that a texture repeats across it and coordinates run
/// outside [0, 1].
pub fn random_primitive_with_attributes(
    kind: u8,
    p: [f32; 3],
    q: [f32; 3],
    r: [f32; 3],
    tilt: [f32; 3],
    uv_scale: f32,
) -> Option<Primitive> {
    if kind % 6 != 5 {
        return random_primitive(kind, p, q, r);
    }
    let (positions, triangles) = spread_mesh(p, q, r);
    let n = (v(q) - v(p)).cross(v(r) - v(p)).normalize_or_zero();
    let normals = (0..12).map(|k| n + v(tilt) * (k as Real / 11.0)).collect();
    let uvs = positions.iter().map(|x| [to_f32(x.x) * uv_scale, to_f32(x.z) * uv_scale]).collect();
    Mesh::new(positions, triangles)?.with_vertex_attributes(normals, uvs).map(Primitive::Mesh)
}

/// An icosahedron of circumradius `radius` about `center`, wound outward:
/// a closed mesh, which a translucent material may fill.
pub fn icosahedron_mesh(center: Vec3, radius: Real) -> Mesh {
    let (corners, faces) = crate::geometry::mesh::icosahedron();
    let scale = radius / corners[0].iter().map(|x| x * x).sum::<f64>().sqrt() as Real;
    let positions = corners
        .iter()
        .map(|c| center + Vec3::new(c[0] as Real, c[1] as Real, c[2] as Real) * scale)
        .collect();
    Mesh::new(positions, faces.to_vec()).unwrap()
}

/// A scene of `primitives`, one white material.
pub fn scene_of(primitives: Vec<Primitive>) -> Scene {
    let builder = SceneBuilder::new().material("white", Material::flat(Color::ONE));
    primitives.into_iter().fold(builder, |b, p| b.object(p, "white")).build().unwrap()
}

/// A camera at `position` looking at `center_of_interest`, up +y, with a
/// vertical field of view of `fov_y` degrees, `near` 1, perspective.
pub fn camera_at(position: Vec3, center_of_interest: Vec3, fov_y: Real) -> Camera {
    Camera::new(position, center_of_interest, Vec3::Y, fov_y, 1.0, Projection::Perspective).unwrap()
}

/// A renderer of a loaded scene through its own camera with its own
/// settings, at `width`×`height` and `spp` samples per pixel.
pub fn renderer(loaded: &LoadedScene, width: u32, height: u32, spp: u32) -> Renderer<'_> {
    let settings = RenderSettings {
        image: ImageSize::new(width, height).unwrap(),
        samples: SamplesPerPixel::new(spp).unwrap(),
        ..loaded.settings
    };
    Renderer::new(&loaded.scene, loaded.camera, &settings).unwrap()
}

/// A renderer of `scene` through `camera` with `effects`, at
/// `width`×`height` and `spp` samples per pixel.
pub fn renderer_of<'s>(
    scene: &'s Scene,
    camera: Camera,
    effects: Effects,
    (width, height, spp): (u32, u32, u32),
) -> Renderer<'s> {
    let settings = RenderSettings {
        image: ImageSize::new(width, height).unwrap(),
        samples: SamplesPerPixel::new(spp).unwrap(),
        effects,
        ..RenderSettings::default()
    };
    Renderer::new(scene, camera, &settings).unwrap()
}

/// `renderer`'s image, rendered on a rayon pool of `threads` threads.
pub fn render_on_threads(renderer: &crate::render::Renderer, threads: usize) -> crate::render::Frame {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| renderer.render(|_| {}))
}

/// The parameters of one random primitive: kind and three points.
pub type Parts = (u8, [f32; 3], [f32; 3], [f32; 3]);

/// 1 to `max` random primitives' parameters, points within ±`extent`.
pub fn random_parts(extent: f32, max: usize) -> impl Strategy<Value = Vec<Parts>> {
    let point = move || prop::array::uniform3(-extent..extent);
    prop::collection::vec((any::<u8>(), point(), point(), point()), 1..max)
}

/// The valid primitives among `parts`.
pub fn primitives_of(parts: Vec<Parts>) -> Vec<Primitive> {
    parts.into_iter().filter_map(|(k, p, q, r)| random_primitive(k, p, q, r)).collect()
}

/// A grid of `n`×`n` squares, two triangles each, with the vertex of column
/// `i` and row `j` at `vertex(i, j)` (`i`, `j` in `0..=n`).
pub fn grid_mesh(n: u32, vertex: impl Fn(u32, u32) -> Vec3) -> Mesh {
    let positions = (0..=n).flat_map(|j| (0..=n).map(move |i| (i, j))).map(|(i, j)| vertex(i, j)).collect();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let triangles = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
            })
        })
        .collect();
    Mesh::new(positions, triangles).unwrap()
}

/// A square of side 2 in the plane z = `z`, centred on the z axis, facing
/// −z, its two triangles carrying texture coordinates that span [0, 1]²:
/// u along +x, v down the image (v = 0 at y = 1), as glTF lays them out.
pub fn textured_square(z: Real) -> Mesh {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let positions = corners.iter().map(|&(x, y)| Vec3::new(x, y, z)).collect();
    let uvs = corners.iter().map(|&(x, y)| [(to_f32(x) + 1.0) / 2.0, (1.0 - to_f32(y)) / 2.0]).collect();
    let mesh = Mesh::new(positions, vec![[0, 2, 1], [0, 3, 2]]).unwrap();
    mesh.with_vertex_attributes(Vec::new(), uvs).unwrap()
}
