//! What a ray found at a surface: the one place a hit becomes shading data.
//!
//! A [`crate::geometry::hit::Hit`] says which object and primitive a ray met and at
//! what `t`. A [`SurfaceInteraction`] made from it holds what every
//! integrator needs next (pbrt-v4's `SurfaceInteraction`, Mitsuba 3's
//! `SurfaceInteraction3f`): the point moved onto the surface with its error
//! bound and geometric normal ([`crate::geometry::surface`]), the direction back along
//! the ray, the shading normal, the material there (textured), and from
//! these the BSDF, the emitted radiance and the spawning of the next ray.
//! Texture coordinates and the tangent frame `∂p/∂u`, `∂p/∂v` are computed
//! when asked for, so a hit that needs neither pays nothing for them. A
//! material with a normal map bends the shading normal here
//! ([`crate::materials::normal_map`]), once per hit; every integrator then
//! shades with it and keeps the geometric normal for the sides of the
//! surface and for spawning rays.

use std::mem::MaybeUninit;

use crate::geometry::hit::Hit;
use crate::geometry::object::Object;
use crate::geometry::primitive::Primitive;
use crate::geometry::surface::SurfacePoint;
use crate::materials::bsdf::Bsdf;
use crate::materials::hit_bsdf::HitBsdf;
use crate::materials::material::Material;
use crate::materials::normal_map;
use crate::materials::texture_lod::Footprint;
use crate::math::color::Color;
use crate::math::ray::Ray;
use crate::math::real::{Real, Vec3, normalize_robust};
use crate::scene::Scene;

/// A ray's hit, ready to shade.
#[derive(Clone, Debug)]
pub struct SurfaceInteraction<'s> {
    /// Index of the object hit in [`Scene::objects`].
    pub object: usize,
    /// The primitive within it (a mesh's triangle; else 0).
    pub primitive: usize,
    /// The point on the surface, its error bound, and the unit geometric
    /// normal in the primitive's own orientation.
    pub point: SurfacePoint,
    /// Unit direction from the point back along the ray (ω_o).
    pub wo: Vec3,
    /// The unit shading normal (a mesh's interpolated vertex normals, bent
    /// by the material's normal map), or `None` where it is the geometric
    /// normal.
    pub shading_normal: Option<Vec3>,
    /// Where the material's normal map bent the shading normal: the normal
    /// it bent (the interpolated one, or `None` for the geometric one), for
    /// the normal-map rules of [`Bsdf::mapped`].
    pub unmapped_normal: Option<Option<Vec3>>,
    /// The object's material at the point, its textures applied: the
    /// scene's own where no texture changes it, else the copy written into
    /// the caller's scratch slot (so the interaction stays small: a
    /// material is 380 bytes, and moving it with every interaction cost a
    /// `memcpy` per hit).
    pub material: &'s Material,
    /// The object hit.
    shape: &'s Object,
}

impl<'s> SurfaceInteraction<'s> {
    /// The interaction where `ray` met the scene at `hit`; `None` for a ray
    /// with no direction. `scratch` holds the material where a texture
    /// changes it ([`Scene::textured_material`]); the interaction borrows
    /// it, so the caller keeps it for as long as the interaction.
    #[inline]
    pub fn new(
        scene: &'s Scene,
        ray: &Ray,
        hit: &Hit,
        scratch: &'s mut MaybeUninit<Material>,
    ) -> Option<Self> {
        Some(Self::along(scene, ray, normalize_robust(ray.dir)?, hit, scratch))
    }

    /// [`SurfaceInteraction::new`] for a ray whose unit direction `d` is
    /// known already (an integrator's loop has it).
    #[inline]
    pub fn along(
        scene: &'s Scene,
        ray: &Ray,
        d: Vec3,
        hit: &Hit,
        scratch: &'s mut MaybeUninit<Material>,
    ) -> Self {
        Self::along_cone(scene, ray, d, hit, 0.0, scratch)
    }

    /// [`SurfaceInteraction::along`] for a ray whose cone is `cone_width`
    /// wide at the hit ([`crate::materials::texture_lod`]): its textures are
    /// read at the mip-map level the footprint asks for.
    #[inline]
    pub fn along_cone(
        scene: &'s Scene,
        ray: &Ray,
        d: Vec3,
        hit: &Hit,
        cone_width: f32,
        scratch: &'s mut MaybeUninit<Material>,
    ) -> Self {
        let shape = &scene.objects()[hit.object];
        let point = shape.primitive.surface_point(hit.primitive, hit.normal, ray.at(hit.t));
        let footprint = Footprint::new(cone_width, d.dot(point.normal));
        let material = match scene.textured_material(hit.object, hit.primitive, point.p, footprint) {
            Some(textured) => &*scratch.write(textured),
            None => scene.object_material(hit.object),
        };
        let mut shading_normal = shape.primitive.shading_normal(hit.primitive, point.p);
        let mut unmapped_normal = None;
        if let Some((texel, scale)) = scene.normal_texel_at(hit.object, hit.primitive, point.p, footprint)
            && let Some(mapped) = normal_mapped(shape, hit.primitive, &point, shading_normal, texel, scale)
        {
            unmapped_normal = Some(shading_normal);
            shading_normal = Some(mapped);
        }
        Self {
            object: hit.object,
            primitive: hit.primitive,
            point,
            wo: -d,
            shading_normal,
            unmapped_normal,
            material,
            shape,
        }
    }

    /// Whether the ray arrived on the side the geometric normal points to
    /// (the outside of a closed object, the front of a flat one).
    #[inline]
    pub fn front(&self) -> bool {
        self.wo.dot(self.point.normal) > 0.0
    }

    /// The geometric normal turned to the side the ray arrived on.
    #[inline]
    pub fn facing_normal(&self) -> Vec3 {
        if self.front() { self.point.normal } else { -self.point.normal }
    }

    /// The radiance the surface gives off towards ω_o: the material's
    /// emission on the front side, nothing from the back.
    #[inline]
    pub fn emitted(&self) -> Color {
        if self.front() { self.material.emission } else { Color::ZERO }
    }

    /// The BSDF of the material here, about the shading normal where there
    /// is one ([`Bsdf::shaded`]).
    #[inline]
    pub fn bsdf(&self) -> Bsdf {
        self.bsdf_of(self.material, self.shading_normal)
    }

    /// The BSDF of `material` here, about `shading` (or the geometric
    /// normal): the boundary of a translucent object is flat and clear.
    /// About the normal map's normal, the rules of [`Bsdf::mapped`] apply.
    #[inline]
    pub fn bsdf_of(&self, material: &Material, shading: Option<Vec3>) -> Bsdf {
        let n = self.point.normal;
        match (shading, self.unmapped_normal) {
            (Some(mapped), Some(smooth)) => Bsdf::mapped(material, n, smooth.unwrap_or(n), mapped, self.wo),
            _ => Bsdf::shaded(material, n, shading.unwrap_or(n), self.wo),
        }
    }

    /// [`SurfaceInteraction::bsdf_of`] as the path tracer takes it: the
    /// Lambert lobe alone where that is all `material` has ([`HitBsdf`]).
    #[inline]
    pub fn hit_bsdf_of(&self, material: &Material, shading: Option<Vec3>) -> HitBsdf {
        let n = self.point.normal;
        match (shading, self.unmapped_normal) {
            // A normal map's rules are the whole model's.
            (Some(_), Some(_)) => HitBsdf::Full(self.bsdf_of(material, shading)),
            _ => HitBsdf::shaded(material, n, shading.unwrap_or(n), self.wo),
        }
    }

    /// A ray leaving the surface along `dir`, from the point pushed off the
    /// surface to the side `dir` points to ([`SurfacePoint::spawn_origin`]).
    #[inline]
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        Ray::new(self.point.spawn_origin(dir), dir)
    }

    /// The texture coordinates here ([`crate::geometry::primitive::Primitive::uv`]);
    /// `None` for primitives without them.
    pub fn uv(&self) -> Option<(Real, Real)> {
        self.shape.primitive.uv(self.primitive, self.point.p)
    }

    /// The tangent frame `(∂p/∂u, ∂p/∂v)`
    /// ([`crate::geometry::primitive::Primitive::tangents`]): along the texture
    /// coordinates where the surface has them, else any two unit vectors
    /// completing the geometric normal to an orthonormal frame.
    pub fn tangents(&self) -> (Vec3, Vec3) {
        self.shape.primitive.tangents(self.primitive, self.point.normal)
    }
}

/// The shading normal at `point` on `primitive` of `shape` bent by the
/// normal-map texel `texel` (read at the ray's level of detail,
/// [`Scene::normal_texel_at`]) of scale `scale`
/// ([`crate::materials::normal_map`]): about the shading normal `shading`
/// (or the geometric one), in the frame of the mesh's tangents, or where it
/// has none of `∂p/∂u` and the direction up the image, `−∂p/∂v`. `None`
/// where the texel makes no normal.
fn normal_mapped(
    shape: &Object,
    primitive: usize,
    point: &SurfacePoint,
    shading: Option<Vec3>,
    texel: Color,
    scale: f32,
) -> Option<Vec3> {
    let n = shading.unwrap_or(point.normal);
    let (t, w) = match &shape.primitive {
        Primitive::Mesh(mesh) => mesh.tangent(primitive, point.p),
        _ => None,
    }
    .unwrap_or_else(|| {
        let (dpdu, dpdv) = shape.primitive.tangents(primitive, point.normal);
        (dpdu, if n.cross(dpdu).dot(dpdv) > 0.0 { -1.0 } else { 1.0 })
    });
    let n_ts = normal_map::tangent_space_normal(texel, scale)?;
    Some(normal_map::mapped_normal(n, t, w, n_ts))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::texture_slot::TextureSlot;
    use crate::math::ray::Interval;
    use crate::scene::Scene;

    /// A glowing, textured quad mesh at z = 0 facing −z, u along +x and the
    /// file's v along +y, in front of a sphere.
    fn scene() -> crate::LoadedScene {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("quad.obj"),
            "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
             vn 0 0 -1\nvn 0 0 -1\nvn 0 0 -1\nvn 0 0 -1\nf 1/1/1 4/4/4 3/3/3\nf 1/1/1 3/3/3 2/2/2\n",
        )
        .unwrap();
        let text = r#"(
            camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
            image: (width: 8, height: 8),
            materials: { "glow": (color: (0.5, 0.5, 0.5), emission: (1, 2, 3)), "grey": (color: (0.5, 0.5, 0.5)) },
            objects: [
                Mesh(file: "quad.obj", material: "glow"),
                Sphere(center: (0, 0, 3), radius: 1, material: "grey"),
            ],
        )"#;
        crate::parse_scene(text, "quad.ron", dir.path()).unwrap()
    }

    #[test]
    fn a_hit_gives_its_point_direction_normals_emission_coordinates_and_frame() {
        let loaded = scene();
        let s = &loaded.scene;
        let ray = Ray::new(Vec3::new(0.5, -0.25, -4.0), Vec3::new(0.0, 0.0, 2.0));
        let hit = s.closest_hit(&ray, Interval::new(0.0, Real::INFINITY)).unwrap();
        let mut scratch = MaybeUninit::uninit();
        let si = SurfaceInteraction::new(s, &ray, &hit, &mut scratch).unwrap();
        assert_eq!((si.object, si.point.p), (0, Vec3::new(0.5, -0.25, 0.0)));
        // An untextured material is the scene's own, not a copy.
        assert!(std::ptr::eq(si.material, s.object_material(0)));
        assert_eq!(si.wo, -Vec3::Z);
        assert!(si.front() && si.facing_normal() == si.point.normal && si.point.normal == -Vec3::Z);
        assert_eq!(si.emitted(), Color::new(1.0, 2.0, 3.0));
        // The OBJ file's `vt` has v up; a mesh keeps it flipped, v down like
        // an image's rows (`crate::geometry::mesh`): v runs along −y.
        let (u, v) = si.uv().unwrap();
        assert!((u - 0.75).abs() < 1e-6 && (v - 0.625).abs() < 1e-6, "({u}, {v})");
        let (dpdu, dpdv) = si.tangents();
        assert!((dpdu - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5, "{dpdu}");
        assert!((dpdv - Vec3::new(0.0, -2.0, 0.0)).length() < 1e-5, "{dpdv}");
        // The next ray leaves towards the side it is spawned to.
        let back = si.spawn_ray(-Vec3::Z);
        assert!(back.origin.z < 0.0 && s.closest_hit(&back, Interval::new(0.0, Real::INFINITY)).is_none());

        // From behind: no emission, the normal turned towards the ray; a
        // sphere has no coordinates and an orthonormal frame about its normal.
        let ray = Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z);
        let hit = s.closest_hit(&ray, Interval::new(0.0, Real::INFINITY)).unwrap();
        let si = SurfaceInteraction::new(s, &ray, &hit, &mut scratch).unwrap();
        assert!(!si.front() && si.emitted() == Color::ZERO && si.facing_normal() == Vec3::Z);
        let ray = Ray::new(Vec3::new(0.3, 0.2, 0.0), Vec3::Z);
        let hit = s.closest_hit(&ray, Interval::new(0.0, Real::INFINITY)).unwrap();
        let si = SurfaceInteraction::new(s, &ray, &hit, &mut scratch).unwrap();
        assert_eq!((si.object, si.uv()), (1, None));
        let (t, b) = si.tangents();
        let n = si.point.normal;
        assert!(t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t.dot(b).abs() < 1e-6);
        assert!((t.length() - 1.0).abs() < 1e-6 && (t.cross(b) - n).length() < 1e-5);
    }

    #[test]
    fn the_path_tracer_gets_the_lambert_lobe_alone_except_under_a_normal_map() {
        use crate::materials::hit_bsdf::HitBsdf;
        let loaded = scene();
        let s = &loaded.scene;
        let mut scratch = MaybeUninit::uninit();
        // The plain grey sphere, and the glowing quad (emission is not a lobe).
        for ray in
            [Ray::new(Vec3::new(0.3, 0.2, 0.0), Vec3::Z), Ray::new(Vec3::new(0.5, -0.25, -4.0), Vec3::Z)]
        {
            let hit = s.closest_hit(&ray, Interval::new(0.0, Real::INFINITY)).unwrap();
            let si = SurfaceInteraction::new(s, &ray, &hit, &mut scratch).unwrap();
            let lean = si.hit_bsdf_of(si.material, si.shading_normal);
            assert!(matches!(lean, HitBsdf::Lambert(_)), "object {}", si.object);
            let wi = Vec3::new(0.3, -0.2, -1.0).normalize();
            assert_eq!(lean.eval(si.wo, wi), si.bsdf().eval(si.wo, wi));
        }
        // A normal map keeps the whole model, whose rules for it the lone
        // lobe does not have.
        let scene = normal_mapped_square(Material::flat(Color::ONE), [1.0, 0.5, 0.55]);
        let ray = Ray::new(Vec3::new(0.1, -0.2, -3.0), Vec3::Z);
        let hit = scene.cast(&ray).unwrap();
        let si = SurfaceInteraction::new(&scene, &ray, &hit, &mut scratch).unwrap();
        assert!(matches!(si.hit_bsdf_of(si.material, si.shading_normal), HitBsdf::Full(_)));
    }

    #[test]
    fn a_textured_hit_shades_with_the_textured_material_in_the_scratch_slot() {
        use crate::geometry::primitive::Primitive;
        use crate::materials::texture::Texture;
        use crate::testing::test_support::textured_square;
        use std::sync::Arc;
        let textured =
            Material { base_color_texture: Some(TextureSlot::new(0)), ..Material::flat(Color::ONE) };
        let scene = crate::scene::SceneBuilder::new()
            .texture(Arc::new(Texture::new(1, 1, vec![Color::new(1.0, 0.5, 0.25)]).unwrap()))
            .material("t", textured)
            .object(Primitive::Mesh(textured_square(0.0)), "t")
            .build()
            .unwrap();
        let ray = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        let hit = scene.cast(&ray).unwrap();
        let mut scratch = MaybeUninit::uninit();
        let si = SurfaceInteraction::new(&scene, &ray, &hit, &mut scratch).unwrap();
        assert_eq!(si.material.color, Color::new(1.0, 0.5, 0.25));
        assert_eq!(*si.material, *scene.material_at(0, 0, si.point.p));
        assert!(!std::ptr::eq(si.material, scene.object_material(0)));
    }

    /// A square in z = 0 facing −z, u along +x, with a one-texel normal
    /// map of texel `texel` (linear) on `material`.
    fn normal_mapped_square(material: Material, texel: [f32; 3]) -> Scene {
        use crate::geometry::primitive::Primitive;
        let mesh = crate::testing::test_support::textured_square(0.0);
        let map = crate::materials::texture::Texture::from_linear(1, 1, 3, &texel).unwrap();
        crate::SceneBuilder::new()
            .texture(std::sync::Arc::new(map))
            .material("m", Material { normal_texture: Some(TextureSlot::new(0)), ..material })
            .object(Primitive::Mesh(mesh), "m")
            .build()
            .unwrap()
    }

    #[test]
    fn normal_mapping_never_sends_light_through_the_geometric_surface_nor_makes_energy() {
        // A map tilting the normal 84° towards +x (n_ts ∝ (1, 0, 0.1)).
        // From 200 directions over the front hemisphere, 2000 BSDF samples
        // each: no reflected sample goes below the facet, the BSDF is zero
        // for every direction below it, and the mean weight (the albedo a
        // white furnace would show) is at most 1 within noise, for a white
        // Lambert surface, a white rough metal and a rough dielectric.
        use crate::materials::principled::Principled;
        let materials = [
            Material::flat(Color::ONE),
            Material::principled(
                Color::ONE,
                Principled { metallic: 1.0, roughness: 0.3, ..Principled::DIELECTRIC },
            ),
            Material::principled(Color::ONE, Principled { roughness: 0.2, ..Principled::DIELECTRIC }),
        ];
        for (k, material) in materials.into_iter().enumerate() {
            let scene = normal_mapped_square(material, [1.0, 0.5, 0.55]);
            let ng = -Vec3::Z;
            let mut worst: f64 = 0.0;
            for d in 0..200u32 {
                let rng = &mut crate::sampling::sampler::SampleRng::new(d, k as u32, 5);
                let (a, b) = rng.next_pair();
                // Towards the square from the front, any slope down to grazing.
                let wo = crate::sampling::sampler::uniform_sphere((a, b * 0.5));
                let wo = Vec3::new(wo.x, wo.y, -wo.z.abs().max(1e-3)).normalize();
                let ray = Ray::new(Vec3::new(0.1, -0.2, 0.0) + wo * 3.0, -wo);
                let hit = scene.cast(&ray).unwrap();
                let mut scratch = MaybeUninit::uninit();
                let si = SurfaceInteraction::new(&scene, &ray, &hit, &mut scratch).unwrap();
                let ns = si.shading_normal.unwrap();
                assert!(ns.dot(ng) < 0.2 && ns.x > 0.9, "the map tilts the normal: {ns}");
                let bsdf = si.bsdf();
                let (mut sum, mut sum2, n) = (0.0f64, 0.0f64, 2000);
                for _ in 0..n {
                    let (u, _) = rng.next_pair();
                    let Some(s) = bsdf.sample(si.wo, u, rng.next_pair()) else { continue };
                    assert!(s.wi.dot(ng) > 0.0, "material {k}: a sample along {} crossed the surface", s.wi);
                    let w = f64::from(s.weight.max_element());
                    (sum, sum2) = (sum + w, sum2 + w * w);
                    let below = Vec3::new(s.wi.x, s.wi.y, -s.wi.z);
                    assert_eq!(bsdf.eval(si.wo, below), Color::ZERO, "material {k}: light from below");
                }
                let mean = sum / n as f64;
                let error = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                worst = worst.max(mean - 4.0 * error);
            }
            assert!(worst <= 1.0 + 1e-6, "material {k} gains energy: {worst}");
        }
    }
}
