//! How a material uses a texture: which image, read through which
//! coordinates and which sampler — glTF 2.0's `textureInfo` (§5.29, and
//! its `normalTextureInfo` / `occlusionTextureInfo` variants) with the
//! `KHR_texture_transform` extension.
//!
//! One decoded image ([`crate::materials::texture::Texture`], shared
//! between materials) may be used by several slots, each with its own
//! texture-coordinate set, transform and sampler: only the slot differs,
//! the texels are stored once.
//!
//! **Transform.** `KHR_texture_transform` maps a surface's coordinates
//! before the lookup by `uv' = T·R·S·uv` in homogeneous coordinates
//! (the extension's specification, "Overview"):
//!
//! ```text
//! T = | 1 0 ox |   R = |  cos r  sin r  0 |   S = | sx 0  0 |
//!     | 0 1 oy |       | −sin r  cos r  0 |       | 0  sy 0 |
//!     | 0 0 1  |       |  0      0      1 |       | 0  0  1 |
//! ```
//!
//! so `u' = sx·cos r·u + sy·sin r·v + ox` and `v' = −sx·sin r·u + sy·cos r·v + oy`:
//! the reading under which the extension's example (offset (0, 1),
//! rotation π/2, scale ½: "only the lower left quadrant of the source
//! image, rotated clockwise 90°") does what it says, and three.js's
//! (`Matrix3::setUvTransform`). The extension's own `texCoord` replaces the
//! slot's set when given.

use crate::math::real::Real;

/// How the texels of one image are decoded to the numbers a slot uses.
///
/// glTF fixes it per use (§3.9.2 and §5.19): colours (base colour,
/// emissive) are sRGB-encoded and decoded by the IEC 61966-2-1 curve;
/// data (metallic-roughness, occlusion, normals) are linear and used as
/// stored. One image used both ways is decoded both ways.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Encoding {
    /// sRGB-encoded colour, decoded to linear at load.
    #[default]
    Srgb,
    /// Linear data, each 8-bit value `b` read as `b/255`.
    Linear,
}

/// One of glTF's texture filters (§5.26, `magFilter` / `minFilter`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Filter {
    /// The texel the point falls in.
    Nearest,
    /// Bilinear between the four texel centres around the point.
    #[default]
    Linear,
}

/// How a lookup filters: within a level (`mag`, `min`) and between mip-map
/// levels (`mip`), and how coordinates outside `[0, 1]` wrap.
///
/// glTF's `minFilter` codes combine `min` and `mip`: `NEAREST` (9728) and
/// `LINEAR` (9729) use the full-size image only (`mip = None`);
/// `X_MIPMAP_NEAREST` the nearest level, `X_MIPMAP_LINEAR` both levels
/// around the footprint blended (trilinear when `X` is `LINEAR`). A sampler
/// the file leaves undefined is [`Sampler::DEFAULT`]: linear, trilinear,
/// repeating (glTF leaves the filters to the implementation, §5.26).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Sampler {
    /// Filter when a texel covers more than a pixel's footprint (magnifying).
    pub mag: Filter,
    /// Filter within a level when the footprint covers more than a texel.
    pub min: Filter,
    /// Filter between mip-map levels; `None` reads the full-size image.
    pub mip: Option<Filter>,
    /// Wrap modes along `u` and `v`.
    pub wrap: [Wrap; 2],
}

impl Sampler {
    /// Linear filtering, trilinear between mip-map levels, repeating.
    pub const DEFAULT: Self =
        Self { mag: Filter::Linear, min: Filter::Linear, mip: Some(Filter::Linear), wrap: [Wrap::Repeat; 2] };

    /// The sampler glTF's numeric codes describe (`magFilter`, `minFilter`;
    /// OpenGL's enums, §5.26): an absent or unknown code keeps the default.
    pub fn from_gl(mag: Option<u32>, min: Option<u32>, wrap: [Wrap; 2]) -> Self {
        let mag = match mag {
            Some(9728) => Filter::Nearest,
            _ => Filter::Linear,
        };
        let (min, mip) = match min {
            Some(9728) => (Filter::Nearest, None),
            Some(9729) => (Filter::Linear, None),
            Some(9984) => (Filter::Nearest, Some(Filter::Nearest)),
            Some(9985) => (Filter::Linear, Some(Filter::Nearest)),
            Some(9986) => (Filter::Nearest, Some(Filter::Linear)),
            _ => (Filter::Linear, Some(Filter::Linear)),
        };
        Self { mag, min, mip, wrap }
    }
}

impl Default for Sampler {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// `KHR_texture_transform` as the 2×3 affine matrix `T·R·S` (see the module
/// documentation), rows `[a, b, c]` giving `u' = a·u + b·v + c`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UvTransform {
    rows: [[f32; 3]; 2],
}

impl UvTransform {
    /// No change.
    pub const IDENTITY: Self = Self { rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] };

    /// The transform of the extension's `offset`, `rotation` (radians) and
    /// `scale`; `None` if any is not finite.
    pub fn new(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Option<Self> {
        if !(offset.iter().chain(&scale).all(|x| x.is_finite()) && rotation.is_finite()) {
            return None;
        }
        let (s, c) = rotation.sin_cos();
        let [ox, oy] = offset;
        let [sx, sy] = scale;
        Some(Self { rows: [[sx * c, sy * s, ox], [-sx * s, sy * c, oy]] })
    }

    /// Whether this is the identity (an untransformed slot skips the arithmetic).
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// `T·R·S·(u, v, 1)`.
    pub fn apply(&self, (u, v): (Real, Real)) -> (Real, Real) {
        let [r0, r1] = self.rows.map(|r| r.map(Real::from));
        (r0[0] * u + r0[1] * v + r0[2], r1[0] * u + r1[1] * v + r1[2])
    }

    /// How much the transform scales areas, `|det|` of its linear part
    /// (`sx·sy`): a footprint's area in texture space grows by it, used when
    /// choosing a mip-map level.
    pub fn area_scale(&self) -> f32 {
        let [r0, r1] = self.rows;
        (r0[0] * r1[1] - r0[1] * r1[0]).abs()
    }
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// A material's use of one texture: glTF's `textureInfo`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TextureSlot {
    /// Index into the scene's decoded textures ([`crate::scene::Scene::texture`]),
    /// each an image decoded with the [`Encoding`] this use needs.
    pub texture: u32,
    /// Which texture-coordinate set of the mesh (`TEXCOORD_n`) is read:
    /// meshes keep sets 0 and 1. The transform's own `texCoord`, when the
    /// file gives one, is already here.
    pub tex_coord: u32,
    /// `KHR_texture_transform`, the identity when absent.
    pub transform: UvTransform,
    /// The sampler: filters and wrap modes of this use.
    pub sampler: Sampler,
    /// A slot's scalar: `normalTexture.scale` (the normal's x and y are
    /// multiplied by it) and `occlusionTexture.strength` (the occlusion is
    /// `1 + strength·(texel − 1)`); 1 for the other slots, where it is unused.
    pub scale: f32,
}

impl TextureSlot {
    /// Texture `texture` read with coordinate set 0, untransformed, with the
    /// default sampler and a scale of 1.
    pub const fn new(texture: u32) -> Self {
        Self {
            texture,
            tex_coord: 0,
            transform: UvTransform::IDENTITY,
            sampler: Sampler::DEFAULT,
            scale: 1.0,
        }
    }

    /// The coordinates this slot looks up, given the surface's coordinates
    /// `uv` in its set ([`TextureSlot::tex_coord`]): transformed.
    pub fn transformed(&self, uv: (Real, Real)) -> (Real, Real) {
        if self.transform.is_identity() { uv } else { self.transform.apply(uv) }
    }
}

/// How texel indices outside the image are brought back into it: glTF's
/// sampler wrap modes (glTF 2.0 §3.8.4.3), for one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Wrap {
    /// Index `i` is `i mod n`: the image tiles the plane.
    #[default]
    Repeat,
    /// Index `i` is clamped to `[0, n − 1]`: the border texels extend.
    ClampToEdge,
    /// The image tiles the plane mirrored every other time: index `i` is
    /// `i mod 2n` folded back into `[0, n − 1]`.
    MirroredRepeat,
}

impl Wrap {
    /// Texel index `i` on an axis of `n` texels.
    pub(crate) fn index(self, i: i64, n: i64) -> i64 {
        match self {
            Self::Repeat => i.rem_euclid(n),
            Self::ClampToEdge => i.clamp(0, n - 1),
            Self::MirroredRepeat => {
                let j = i.rem_euclid(2 * n);
                if j < n { j } else { 2 * n - 1 - j }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: (Real, Real), b: (Real, Real)) -> bool {
        (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6
    }

    #[test]
    fn the_transform_is_translation_times_rotation_times_scale() {
        // The extension's example: offset (0, 1), rotation π/2, scale ½ —
        // u' = ½·v, v' = 1 − ½·u.
        let t = UvTransform::new([0.0, 1.0], std::f32::consts::FRAC_PI_2, [0.5, 0.5]).unwrap();
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.7)] {
            let got = t.apply((u, v));
            assert!(close(got, (0.5 * v, 1.0 - 0.5 * u)), "({u}, {v}) → {got:?}");
        }
        assert!((t.area_scale() - 0.25).abs() < 1e-6);
        // Offset alone translates; scale alone scales, about the origin.
        let offset = UvTransform::new([0.25, -0.5], 0.0, [1.0, 1.0]).unwrap();
        assert!(close(offset.apply((0.5, 0.5)), (0.75, 0.0)));
        let scale = UvTransform::new([0.0, 0.0], 0.0, [2.0, 3.0]).unwrap();
        assert!(close(scale.apply((0.5, 0.5)), (1.0, 1.5)));
        assert!(UvTransform::new([0.0, 0.0], 0.0, [1.0, 1.0]).unwrap().is_identity());
        assert_eq!(UvTransform::new([f32::NAN, 0.0], 0.0, [1.0, 1.0]), None);
        assert_eq!(UvTransform::new([0.0, 0.0], f32::INFINITY, [1.0, 1.0]), None);
    }

    #[test]
    fn an_untransformed_slot_reads_its_coordinates_as_they_are() {
        let mut slot = TextureSlot::new(0);
        assert_eq!(slot.transformed((0.1, 0.2)), (0.1, 0.2));
        slot.transform = UvTransform::new([1.0, 0.0], 0.0, [2.0, 2.0]).unwrap();
        assert!(close(slot.transformed((0.1, 0.2)), (1.2, 0.4)));
    }

    #[test]
    fn gl_filter_codes_map_onto_filter_and_mip_mode() {
        let s = |mag, min| Sampler::from_gl(mag, min, [Wrap::Repeat; 2]);
        assert_eq!(s(None, None), Sampler::DEFAULT);
        let nearest = s(Some(9728), Some(9728));
        assert_eq!((nearest.mag, nearest.min, nearest.mip), (Filter::Nearest, Filter::Nearest, None));
        assert_eq!(s(None, Some(9729)).mip, None);
        assert_eq!(s(None, Some(9984)).mip, Some(Filter::Nearest));
        let trilinear = s(Some(9729), Some(9987));
        assert_eq!(
            (trilinear.mag, trilinear.min, trilinear.mip),
            (Filter::Linear, Filter::Linear, Some(Filter::Linear))
        );
        let nearest_linear = s(None, Some(9986));
        assert_eq!((nearest_linear.min, nearest_linear.mip), (Filter::Nearest, Some(Filter::Linear)));
    }
}
