//! How much of a texture a ray sees: ray cones and the mip-map level of
//! detail they give (Akenine-Möller et al., "Texture Level of Detail
//! Strategies for Real-Time Ray Tracing", Ray Tracing Gems, 2019, ch. 20).
//!
//! A pixel's rays are thought of as a cone: of width `w₀` where it leaves
//! the camera and spread angle `γ`, so that after a distance `t` it is
//! `w = w₀ + γ·t` wide (small angles, `tan γ ≈ γ`; §20.3.4). A perspective
//! camera's cone starts as a point with the angle one pixel subtends,
//! `γ = atan(2·tan(fov_y/2)/H)` (eq. 20.30); an orthographic camera's keeps
//! the width of a pixel and does not spread. At a hit, the cone's footprint
//! on the surface is `w/|cos θ|` long (θ between the ray and the geometric
//! normal), and the level of detail of a texture of `W × H` texels is
//!
//! ```text
//! λ = ½·log₂(W·H · A_uv/A_world) + log₂(w/|cos θ|)      (eq. 20.33–20.36)
//! ```
//!
//! with `A_uv/A_world` the ratio of the triangle's area in texture
//! coordinates to its area in the world (the texture transform's `|det|`
//! included): λ = 0 is a texel per footprint, each step up halves the
//! resolution ([`crate::materials::texture::Texture::lookup`]).
//!
//! **After a bounce** the cone keeps its spread: the width keeps growing
//! with the distance travelled along the whole path, as if every surface
//! were a flat mirror. Curved surfaces and rough lobes widen a real
//! footprint further (§20.3.4 adds a curvature term); ignoring them keeps
//! secondary lookups sharper than needed, which costs at most some noise in
//! indirect light, never bias beyond the filter's. A thin lens's aperture is
//! not added to the width either (out-of-focus blur averages the texture
//! anyway).

use crate::camera::Projection;
use crate::camera::view_plane::ViewPlane;
use crate::math::real::{FOOTPRINT_MIN_COS, Real, to_f32};

/// A cone of rays: its width where it starts and its spread angle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCone {
    /// Width at the origin, world units.
    pub width: f32,
    /// Spread angle γ, radians: the width grows by `γ` per unit distance.
    pub spread: f32,
}

impl RayCone {
    /// A ray of no width: lookups read the full-size image (λ = −∞),
    /// as when nothing is known about the footprint.
    pub const POINT: Self = Self { width: 0.0, spread: 0.0 };

    /// The cone of one pixel of `view`: a point spreading by the pixel's
    /// angle for a perspective camera (eq. 20.30), a pixel's width not
    /// spreading for an orthographic one.
    pub fn of_pixel(view: &ViewPlane) -> Self {
        let (_, pixel_h) = view.pixel_size();
        match view.camera().projection() {
            Projection::Perspective => Self { width: 0.0, spread: to_f32(view.spread_angle()) },
            Projection::Orthographic => Self { width: to_f32(pixel_h), spread: 0.0 },
        }
    }

    /// The width after `distance` along the cone: `w₀ + γ·distance`.
    pub fn width_at(&self, distance: Real) -> f32 {
        self.width + self.spread * to_f32(distance)
    }
}

/// A ray's footprint on a surface: a cone `width` wide meeting it at an
/// angle θ covers a length `w/|cos θ|` there (world units), worked out
/// only when a texture is read.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// The cone's width `w` at the surface.
    pub width: f32,
    /// `cos θ` between the ray and the geometric normal, either sign.
    pub cos: Real,
}

impl Footprint {
    /// No footprint: lookups read the full-size image.
    pub const POINT: Self = Self { width: 0.0, cos: 1.0 };

    /// The footprint of a cone `width` wide meeting a surface at `cos`
    /// (the cosine between the ray and the geometric normal, either sign).
    pub fn new(width: f32, cos: Real) -> Self {
        Self { width, cos }
    }

    /// `w/|cos θ|`, with `|cos θ|` held at least [`FOOTPRINT_MIN_COS`].
    pub fn length(&self) -> f32 {
        self.width / to_f32(self.cos.abs().max(FOOTPRINT_MIN_COS))
    }

    /// The level of detail λ of a texture of `texels` (W·H) texels for this
    /// footprint on a triangle whose texture-to-world area ratio is
    /// `uv_per_world_area` (see the module documentation). −∞ for a point
    /// footprint or a triangle without texture area: the full-size image.
    pub fn level_of_detail(&self, texels: f32, uv_per_world_area: f32) -> f32 {
        let (density, length) = (texels * uv_per_world_area, self.length());
        if !(length > 0.0 && density > 0.0) {
            return f32::NEG_INFINITY;
        }
        0.5 * density.log2() + length.log2()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::math::real::Vec3;

    #[test]
    fn a_perspective_pixel_spreads_by_its_angle_and_an_orthographic_one_keeps_its_width() {
        let camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0, 1.0, Projection::Perspective).unwrap();
        let view = ViewPlane::new(camera, 200, 100).unwrap();
        let cone = RayCone::of_pixel(&view);
        // fov 90°: 2·tan 45° / 100 = 0.02, atan(0.02).
        assert!((cone.spread - 0.02f32.atan()).abs() < 1e-7 && cone.width == 0.0, "{cone:?}");
        assert!((cone.width_at(10.0) - 10.0 * 0.02f32.atan()).abs() < 1e-6);
        let ortho = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0, 1.0, Projection::Orthographic).unwrap();
        let view = ViewPlane::new(ortho, 200, 100).unwrap();
        let cone = RayCone::of_pixel(&view);
        assert_eq!((cone.width, cone.spread), (to_f32(view.pixel_size().1), 0.0));
        assert_eq!(cone.width_at(1000.0), cone.width);
    }

    #[test]
    fn the_level_of_detail_is_one_texel_per_footprint_at_zero_and_grows_with_log2() {
        // A 256×256 texture over a 1×1 square (uv area 1): a texel is 1/256
        // wide, so a footprint of 1/256 is level 0 and 4/256 level 2.
        let at = |width: f32, cos: Real| Footprint::new(width, cos).level_of_detail(65536.0, 1.0);
        assert!(at(1.0 / 256.0, 1.0).abs() < 1e-5);
        assert!((at(4.0 / 256.0, 1.0) - 2.0).abs() < 1e-5);
        // Seen at 60° the footprint doubles: one level up.
        assert!((at(1.0 / 256.0, 0.5) - 1.0).abs() < 1e-5);
        assert!((at(1.0 / 256.0, -0.5) - 1.0).abs() < 1e-5);
        // The uv area doubling per world area (a tiled texture) adds ½ level.
        assert!((Footprint::new(1.0 / 256.0, 1.0).level_of_detail(65536.0, 2.0) - 0.5).abs() < 1e-5);
        assert_eq!(Footprint::POINT.level_of_detail(65536.0, 1.0), f32::NEG_INFINITY);
        assert!(at(1.0, 1.0) > 0.0);
        assert_eq!(Footprint::new(0.01, 0.0).level_of_detail(1.0, 0.0), f32::NEG_INFINITY);
        assert!(at(1.0 / 256.0, 0.0).is_finite());
    }

    /// A checkerboard floor running to the horizon under a camera 1 unit
    /// above it, looking level: every far row sees many checks per pixel.
    /// `mip` is the texture's mip-map filter.
    fn horizon_scene(mip: Option<crate::materials::texture_slot::Filter>) -> crate::scene::Scene {
        use crate::geometry::mesh::Mesh;
        use crate::geometry::primitive::Primitive;
        use crate::materials::material::Material;
        use crate::materials::texture::Texture;
        use crate::materials::texture_slot::{Filter, Sampler, TextureSlot};
        use crate::math::color::Color;
        let (w, d) = (1000.0, 2000.0);
        let floor = Mesh::new(
            vec![
                Vec3::new(-w, 0.0, 0.0),
                Vec3::new(w, 0.0, 0.0),
                Vec3::new(w, 0.0, d),
                Vec3::new(-w, 0.0, d),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        )
        .unwrap()
        .with_vertex_attributes(vec![], vec![[0.0, 0.0], [2000.0, 0.0], [2000.0, 2000.0], [0.0, 2000.0]])
        .unwrap();
        let checker = Texture::new(2, 2, vec![Color::ZERO, Color::ONE, Color::ONE, Color::ZERO]).unwrap();
        let slot = TextureSlot {
            sampler: Sampler { mag: Filter::Nearest, mip, ..Sampler::DEFAULT },
            ..TextureSlot::new(0)
        };
        let material = Material { base_color_texture: Some(slot), ..Material::flat(Color::ONE) };
        crate::scene::SceneBuilder::new()
            .texture(std::sync::Arc::new(checker))
            .material("checker", material)
            .object(Primitive::Mesh(floor), "checker")
            .build()
            .unwrap()
    }

    #[test]
    fn a_checkerboard_to_the_horizon_at_one_sample_matches_a_supersampled_reference_without_moire() {
        use crate::materials::texture_slot::Filter;
        use crate::scene::effects::Effects;
        use crate::testing::test_support::renderer_of;
        let camera = Camera::new(
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 10.0),
            Vec3::Y,
            40.0,
            0.1,
            Projection::Perspective,
        )
        .unwrap();
        let (w, h) = (64, 48);
        let render = |mip, spp| {
            let scene = horizon_scene(mip);
            let frame = renderer_of(&scene, camera, Effects::default(), (w, h, spp)).render(|_| {});
            frame.pixels.iter().map(|c| f64::from(c.x)).collect::<Vec<_>>()
        };
        // The reference: the full-size texture, 256 samples a pixel.
        let reference = render(None, 256);
        let mipmapped = render(Some(Filter::Linear), 1);
        let aliased = render(None, 1);
        // Far rows: just below the horizon (row 24), 10 to 60 units away.
        let rows = 25..31;
        let row_mean =
            |img: &[f64], y: u32| (0..w).map(|x| img[(y * w + x) as usize]).sum::<f64>() / f64::from(w);
        let pixel_error = |img: &[f64]| {
            let n = rows.len() as f64 * f64::from(w);
            rows.clone()
                .flat_map(|y| (0..w).map(move |x| (y * w + x) as usize))
                .map(|i| (img[i] - reference[i]).abs())
                .sum::<f64>()
                / n
        };
        for y in rows.clone() {
            let (r, m) = (row_mean(&reference, y), row_mean(&mipmapped, y));
            assert!((r - m).abs() < 0.05, "row {y}: mip-mapped mean {m:.3}, reference {r:.3}");
        }
        let (with, without) = (pixel_error(&mipmapped), pixel_error(&aliased));
        assert!(with < 0.08, "mip-mapped pixels differ from the reference by {with:.3} on average");
        assert!(without > 3.0 * with, "without mip-maps {without:.3}, with {with:.3}");
    }
}
