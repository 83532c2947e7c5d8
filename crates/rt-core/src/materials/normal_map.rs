//! Normal maps: a shading normal that varies over a surface, read from a
//! texture in tangent space (glTF 2.0 §3.9.3, `normalTexture`).
//!
//! **Texel → tangent space.** A texel `c` (linear RGB in [0, 1]) holds the
//! normal `n_ts = normalize((2c − 1)·(s, s, 1))`, `s` the map's `scale`:
//! red along the tangent `T`, green along the bitangent `B`, blue along the
//! normal (glTF's convention, OpenGL's: green points *up the image*, to
//! decreasing `v`).
//!
//! **Tangent space → world.** The frame is the interpolated tangent
//! `(T, w)` of the mesh's vertices (the file's, or MikkTSpace's,
//! [`crate::geometry::mesh::Mesh::tangent`]) made orthonormal to the
//! shading normal `N` by Gram–Schmidt, `T' = normalize(T − (T·N)·N)`, and
//! `B = w·(N × T')`, the sign `w` saying whether the texture is mirrored
//! on the surface. This is how MikkTSpace's own reference shader and the
//! glTF sample viewer rebuild the frame (they leave `B` unnormalised; with
//! unit `T'` and `N` it is unit anyway). The world normal is
//! `normalize(n_ts.x·T' + n_ts.y·B + n_ts.z·N)`.
//!
//! **Degenerate input** gives a finite frame: a tangent that is zero, not
//! finite, or parallel to `N` (zero-area texture coordinates) is replaced
//! by any unit vector perpendicular to `N`; a texel that decodes to the
//! zero vector leaves `N` as it is.
//!
//! **Light never goes through the geometric surface.** The mapped normal
//! only shapes the BSDF's lobes; the geometric normal still decides which
//! side of the surface a direction is on, for the BSDF's value and its
//! samples (pbrt-v3's rule, [`crate::materials::bsdf`] "Shading normals"),
//! and where secondary rays start.

use crate::math::color::Color;
use crate::math::real::{Vec3, narrow, normalize_robust};

/// The tangent-space normal that texel `c` holds, its x and y scaled by
/// `scale`: `normalize((2c − 1)·(s, s, 1))`; `None` if that is zero.
pub fn tangent_space_normal(c: Color, scale: f32) -> Option<Vec3> {
    let v = (c * 2.0 - Color::ONE) * Color::new(scale, scale, 1.0);
    normalize_robust(narrow(v.as_dvec3()))
}

/// The orthonormal tangent and bitangent `(T', B)` about the unit normal
/// `n` from the tangent `t` and handedness `w` (see the module
/// documentation); any perpendicular pair for a degenerate `t`.
pub fn frame(n: Vec3, t: Vec3, w: f32) -> (Vec3, Vec3) {
    let sign = if w < 0.0 { -1.0 } else { 1.0 };
    match normalize_robust(t - n * t.dot(n)) {
        Some(t) => (t, n.cross(t) * sign),
        None => {
            let (t, _) = n.any_orthonormal_pair();
            (t, n.cross(t) * sign)
        }
    }
}

/// The world-space normal the map gives: `n_ts` (a unit tangent-space
/// normal) in the frame of the unit normal `n` and tangent `(t, w)`.
pub fn mapped_normal(n: Vec3, t: Vec3, w: f32, n_ts: Vec3) -> Vec3 {
    let (t, b) = frame(n, t, w);
    normalize_robust(t * n_ts.x + b * n_ts.y + n * n_ts.z).unwrap_or(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::real::Real;

    #[test]
    fn the_flat_texel_is_the_normal_itself_and_scale_tilts_x_and_y() {
        let flat = tangent_space_normal(Color::new(0.5, 0.5, 1.0), 1.0).unwrap();
        assert!((flat - Vec3::Z).length() < 1e-6, "{flat}");
        // (1, 0.5, 0.5) → (1, 0, 0) scaled by s, then z 0: along the tangent.
        let right = tangent_space_normal(Color::new(1.0, 0.5, 0.5), 2.0).unwrap();
        assert!((right - Vec3::X).length() < 1e-6, "{right}");
        // (0.75, 0.5, 1) → (0.5, 0, 1); scale 2 makes it (1, 0, 1).
        let tilted = tangent_space_normal(Color::new(0.75, 0.5, 1.0), 2.0).unwrap();
        assert!((tilted - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6, "{tilted}");
        assert_eq!(tangent_space_normal(Color::splat(0.5), 1.0), None);
    }

    #[test]
    fn tangent_space_goes_to_the_frame_of_the_tangent_and_its_handedness() {
        let n = Vec3::Z;
        // A tangent not perpendicular to n is made so (Gram–Schmidt).
        let t = Vec3::new(2.0, 0.0, 1.0);
        let (t1, b) = frame(n, t, 1.0);
        assert!((t1 - Vec3::X).length() < 1e-6 && (b - Vec3::Y).length() < 1e-6, "{t1} {b}");
        // w = −1 mirrors the bitangent only.
        let (t2, b2) = frame(n, t, -1.0);
        assert!((t2 - Vec3::X).length() < 1e-6 && (b2 + Vec3::Y).length() < 1e-6);
        let n_ts = Vec3::new(0.6, 0.0, 0.8);
        assert!((mapped_normal(n, t, 1.0, n_ts) - n_ts).length() < 1e-6);
        let up = Vec3::new(0.0, 0.6, 0.8);
        assert!((mapped_normal(n, t, -1.0, up) - Vec3::new(0.0, -0.6, 0.8)).length() < 1e-6);
    }

    #[test]
    fn degenerate_tangents_give_a_finite_orthonormal_frame() {
        let n = Vec3::new(0.0, 0.6, 0.8);
        for t in [Vec3::ZERO, n * 3.0, Vec3::splat(Real::NAN), Vec3::new(Real::INFINITY, 0.0, 0.0)] {
            let (t1, b) = frame(n, t, 1.0);
            assert!(t1.is_finite() && b.is_finite(), "{t}: {t1} {b}");
            assert!((t1.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
            assert!(t1.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t1.dot(b).abs() < 1e-6);
            let m = mapped_normal(n, t, 1.0, Vec3::new(0.6, 0.0, 0.8));
            assert!(m.is_finite() && (m.length() - 1.0).abs() < 1e-6 && (m.dot(n) - 0.8).abs() < 1e-6);
        }
    }
}
