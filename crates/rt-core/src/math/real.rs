//! The geometry's floating-point type, and the numerical policies that depend on it.
//!
//! All geometry (points, directions, ray parameters) uses [`Real`] and [`Vec3`]:
//! `f32`/`glam::Vec3` by default, `f64`/`glam::DVec3` with the `f64` cargo feature.
//! Colours are always `f32` (see [`crate::math::color::Color`]).
//!
//! Every numerical tolerance of the crate is defined here, once, with the
//! reasoning that fixes its value.

#[cfg(not(feature = "f64"))]
mod precision {
    /// The scalar type of all geometry.
    pub type Real = f32;
    /// A 3-vector of [`Real`]: points, directions and normals in world units.
    pub type Vec3 = glam::Vec3;
}

#[cfg(feature = "f64")]
mod precision {
    /// The scalar type of all geometry.
    pub type Real = f64;
    /// A 3-vector of [`Real`]: points, directions and normals in world units.
    pub type Vec3 = glam::DVec3;
}

pub use precision::{Real, Vec3};

/// Unit roundoff of [`Real`]: half the distance from 1 to the next number (2⁻²⁴ for f32).
pub const UNIT_ROUNDOFF: Real = Real::EPSILON * 0.5;

/// pbrt's γₙ = n·u / (1 − n·u): a bound on the relative error of n chained
/// floating-point operations (Pharr, Jakob, Humphreys, *PBR* 4th ed., §6.8.1).
pub const fn gamma(n: u32) -> Real {
    let nu = n as Real * UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// Largest absolute coordinate of `p`, but at least 1: the length scale that
/// the `cast` self-intersection rule and geometric tolerances are relative to.
pub fn magnitude_scale(p: Vec3) -> Real {
    p.abs().max_element().max(1.0)
}

/// Self-intersection rule for rays whose history is unknown (`cast`, primary rays).
///
/// A hit counts only if its distance from the origin, `t·|d|`, is greater than
/// `2⁻¹⁶ · s` with `s = max(1, largest |coordinate| of the origin)`.
///
/// The `cast` contract (`docs/conventions.md`) requires hits at distance
/// ≤ 2⁻²⁰·s never to count and hits at distance ≥ 2⁻¹⁰·s always to count. 2⁻¹⁶ is 16× above the lower bound and
/// 64× below the upper one, leaning towards keeping near hits. In f32 a point
/// on a surface at magnitude s is off the surface by a few ulps, about 2⁻²³·s
/// each, so 2⁻¹⁶·s leaves a margin of 2⁷ = 128 ulps.
///
/// For primary rays this acts like a near clipping distance of 2⁻¹⁶·s: for a
/// camera 10⁵ units from the origin, 1.5 units (where f32 resolves 0.008).
pub const CAST_MIN_DISTANCE_FACTOR: Real = 1.0 / 65536.0;

/// The smallest ray parameter `t` that counts as a hit for a ray from `origin`
/// along `dir`, by the rule of [`CAST_MIN_DISTANCE_FACTOR`]. Returns +∞ (nothing
/// counts) for a zero or non-finite direction. `dir` should have been rescaled
/// ([`crate::math::ray::Ray::rescaled`]) so that `|dir|` cannot overflow or underflow.
pub fn cast_min_t(origin: Vec3, dir: Vec3) -> Real {
    let len = dir.length();
    if len > 0.0 && len.is_finite() {
        CAST_MIN_DISTANCE_FACTOR * magnitude_scale(origin) / len
    } else {
        Real::INFINITY
    }
}

/// The fraction of its length by which a shadow ray towards a sampled point
/// on an emitter stops short, so that it does not find the emitter itself.
///
/// The sampled point lies on the emitter's surface only to rounding (a few
/// ulps of its coordinates, relative 2⁻²² in f32), and the shadow ray's
/// origin is pushed off the shading point's surface; an emitter hit within
/// the last 10⁻⁴ of the way would be the emitter itself. 10⁻⁴ is about 800
/// f32 ulps of relative distance, so rounding never reaches it, and 10⁻⁴ of
/// the distance to a light is far below what an occluder between them can
/// be noticed at. A principled alternative (pbrt-v4's `SpawnRayTo`, offsetting
/// both ends by their error bounds) would change which rays are blocked and
/// so the images' bits.
pub const SHADOW_SHORTEN: Real = 1e-4;

/// The narrowest `cos θᵢ − cos θₒ` a spot light's falloff divides by
/// ([`crate::lights::light::spot_falloff`]): the `KHR_lights_punctual`
/// specification's own floor of 0.001 in its implementation note, so equal
/// inner and outer cones make a hard edge instead of a division by zero, and
/// rt-view's spot lights fall off as a glTF viewer's do.
pub const SPOT_CONE_MIN_WIDTH: Real = 0.001;

/// How much wider (relative, in sin²θ) the sun's disc counts for what a ray
/// finds and the density than for where samples go
/// ([`crate::lights::sun::Sun`]): a sample on the rim of a 0.27° disc,
/// normalised in f32, lands a relative 10⁻⁵ or so outside it (the
/// direction's components are off by an ulp each, 6·10⁻⁸, against
/// sin α ≈ 4.7·10⁻³). 10⁻³ of sin²α covers that with room; it adds 0.1 %
/// to the sun's found radiance integral only in a ring a ray finds once in
/// a thousand sun hits, far below the noise of any render.
pub const SUN_RIM_SLACK: Real = 1e-3;

/// The least cos θ the Perez sky formula is evaluated at
/// ([`crate::lights::sky`]): `e^(B/cos θ)`, with B < 0 at every accepted
/// turbidity, vanishes at the horizon, and this keeps the division finite
/// there (e^(−0.11/10⁻³) ≈ 10⁻⁴⁹ at the mildest B, nothing next to 1).
pub const PEREZ_MIN_COS: f64 = 1e-3;

/// The GGX roughness α below which a microfacet lobe is a perfectly smooth
/// surface: δ reflection and refraction instead of a distribution of normals
/// (pbrt-v4's `TrowbridgeReitzDistribution::EffectivelySmooth`, §9.6.1).
///
/// At α = 10⁻³ the lobe is under 0.1° wide, far below a pixel's footprint
/// at any reasonable field of view, so treating it as δ changes no image;
/// below it, `D(h)` peaks above 3·10⁵ and its density is concentrated in a
/// cone narrower than f32 directions resolve near the normal (a unit
/// vector's z differs from 1 by α²/2 = 5·10⁻⁷ there, ~8 ulps), so a
/// sampled GGX would be numerically degenerate.
pub const SMOOTH_ALPHA: Real = 1e-3;

/// The least `|cos θ|` a ray cone's footprint is divided by
/// ([`crate::materials::texture_lod::Footprint`]): a ray grazing a surface
/// has a footprint `w/|cos θ|` that grows without bound; held here it is at
/// most 1000 cone widths, ten mip-map levels above the head-on one — the
/// texture's mean, or close, which is what a grazing view of it averages to.
pub const FOOTPRINT_MIN_COS: Real = 1e-3;

/// How far above the geometric surface the mirror reflection of `ω_o`
/// about a normal-mapped normal must stay, as a cosine with the geometric
/// normal: `min(VALID_REFLECTION_SHARE·cos θ_o, VALID_REFLECTION_MARGIN)`
/// ([`crate::materials::bsdf`], "Normal maps"). A map can tilt the normal
/// so far from the viewer that its mirror direction points into the
/// surface (or `ω_o` lies below it); the normal is then bent back until
/// the reflection clears the surface by this margin — the values Blender
/// Cycles uses (`ensure_valid_specular_reflection`), so both renderers bend
/// the same normals by the same amount. The share keeps the margin below
/// `cos θ_o` itself, so a viewer grazing the surface still has a solution.
pub const VALID_REFLECTION_MARGIN: Real = 0.01;

/// See [`VALID_REFLECTION_MARGIN`].
pub const VALID_REFLECTION_SHARE: Real = 0.9;

/// The area-ratio triangle test's tolerance
/// ([`crate::geometry::triangle::intersect_area_ratio`], the course's test):
/// a point counts as inside when the three sub-triangle areas sum to at
/// most `(1 + ε)` times the triangle's area. The sum is exactly 1 inside,
/// but it is computed with rounding (cross products and lengths, relative
/// errors of a few 10⁻⁷ in f32), so without slack the test would lose
/// points inside; 10⁻⁴ is some 800 f32 ulps of the sum, far above that
/// rounding. Just outside an edge the excess is about twice the point's
/// distance from the edge over the triangle's height there, so points up
/// to `ε/2` heights outside are (wrongly) hit: the price of this test,
/// which `rt-view accuracy` shows beside the watertight one.
pub const AREA_RATIO_EPSILON: Real = 1e-4;

/// How planar a polygon must be ([`crate::geometry::polygon::Polygon::new`]):
/// a corner may be off the best-fit plane by this fraction of the
/// polygon's diagonal, plus 16 ulps of the corners' magnitude for
/// rounding. The plane the polygon is then drawn in lies within 10⁻⁴ of
/// its size of every corner, far below what a pixel resolves of it; a
/// polygon bent by more is refused rather than drawn as if it were flat.
pub const PLANARITY_TOLERANCE: Real = 1e-4;

/// The least `|normalize(up) × cam_z|` a camera accepts
/// ([`crate::camera::Camera`]): below it `up` is parallel to the view
/// direction (sin 0.0057°) and the camera's roll undefined. Above it the
/// cross product's direction is well defined in f32 (its components are
/// at least 10⁻⁴ against a rounding of 10⁻⁷).
pub const MIN_UP_SINE: Real = 1e-4;

/// A pixel must be at least this many ulps of the magnitudes its ray is
/// built from (`near` for perspective directions, also `|C|∞` for
/// orthographic origins) ([`crate::camera::view_plane::ViewPlane`]), so
/// that neighbouring pixels get different rays: a pixel's point on the
/// view plane is computed to within a few ulps, well inside 16.
pub const MIN_PIXEL_ULPS: Real = 16.0;

/// The smallest weight a secondary ray of the direct-lighting tracer may
/// have in its pixel ([`crate::integrators::tracer`], adaptive depth
/// control): under half an 8-bit step of a full-intensity colour, so what
/// it would add cannot change the pixel's 8-bit value.
pub const MIN_WEIGHT: f32 = 1.0 / 512.0;

/// Added to the square root of the intensity in adaptive sampling's
/// relative error ([`crate::render::adaptive`]), so a black pixel's error is
/// finite (0 if its halves agree): Blender Cycles' value.
pub const ADAPTIVE_DARK: f32 = 1e-4;

/// The margin of a packet's cone test on slopes ([`crate::bvh`]'s packets),
/// times `1 + max|slope|`. The slopes are computed from the rays' inverse
/// directions with three roundings (a relative error under 2·10⁻⁷), and a
/// ray's own rounded slab or watertight test can accept a box or triangle
/// the exact ray misses by a relative 5γ₃ ≈ 10⁻⁶ of the distance: the cone
/// must never cull what a ray would enter. 10⁻⁶ on the slopes and
/// [`CONE_PAD`] on the boxes are a hundred times the rounding they cover,
/// and still far below a pixel's footprint (10⁻³ of the distance at
/// 640×480).
pub const CONE_SLOPE_MARGIN: Real = 1e-6;

/// How much a box is widened on every side, relative to its reach from
/// the packet's origin, before a packet's cone test culls it (see
/// [`CONE_SLOPE_MARGIN`]).
pub const CONE_PAD: Real = 1e-4;

/// Below this `|g|` a Henyey–Greenstein direction is drawn as an isotropic
/// one ([`crate::materials::medium::sample_henyey_greenstein`], pbrt-v4's
/// switch, §11.3.1): the inverted distribution divides by `2g` and loses
/// all precision as `g → 0`, while the phase function differs from the
/// isotropic one by under `3|g|` = 0.3 % there.
pub const HG_ISOTROPIC_G: Real = 1e-3;

/// Below this `sin²θ_max` (sin² 1.5°) the cone of a sphere light is
/// computed from the series `1 − cos θ_max = s/2 + s²/8`
/// ([`crate::lights::light`]), pbrt-v4's switch: `1 − √(1 − s)` loses `s`
/// to cancellation when it is small, and the series' next term, `s³/16`,
/// is under an f32 ulp of the sum there.
pub const SMALL_CONE_SIN2: Real = 0.00068523;

/// A random walk's spectral densities are divided by their largest once
/// it leaves `[WALK_RESCALE_BELOW, WALK_RESCALE_ABOVE]`
/// ([`crate::materials::medium`]): they multiply at every step and would
/// overflow or underflow an f64 after some thousands of steps; the
/// contribution is divided by the same number, so its ratio to the density
/// does not change. 10¹⁰⁰ leaves two hundred orders of magnitude to the
/// ends of the f64 range.
pub const WALK_RESCALE_ABOVE: f64 = 1e100;

/// See [`WALK_RESCALE_ABOVE`].
pub const WALK_RESCALE_BELOW: f64 = 1e-100;

/// The shortest mean free path a translucent material may have
/// ([`crate::files`]' subsurface settings): `σt = 1/ℓ` stays a normal f32
/// (at most 10³⁰, below f32's 3.4·10³⁸) however small the file's ℓ is.
pub const MIN_MEAN_FREE_PATH: f32 = 1e-30;

/// `v / |v|`, or `None` for a zero or non-finite `v`, for any finite `v`:
/// `v` is first divided by its largest absolute component, so `|v|²` can
/// neither overflow (components near 10³⁸ in f32) nor underflow (near 10⁻²⁰).
#[inline]
pub fn normalize_robust(v: Vec3) -> Option<Vec3> {
    let m = v.abs().max_element();
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    // The three quotients as one SIMD division (the same bits).
    divide(v, Vec3::splat(m)).try_normalize()
}

/// A geometric scalar as the `f32` that colours are computed in.
#[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
#[inline]
pub fn to_f32(x: Real) -> f32 {
    x as f32
}

/// A geometric scalar widened to f64 (exactly).
#[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
#[inline]
pub fn to_f64(x: Real) -> f64 {
    x as f64
}

/// `n / d` component by component, each quotient correctly rounded (IEEE
/// 754 division), exactly what three scalar divisions give; with `f32`
/// geometry as one 4-lane SIMD division instead of three in a row.
#[inline(always)]
pub fn divide(n: Vec3, d: Vec3) -> Vec3 {
    #[cfg(not(feature = "f64"))]
    {
        (glam::Vec3A::from(n) / glam::Vec3A::from(d)).into()
    }
    #[cfg(feature = "f64")]
    {
        n / d
    }
}

/// A geometric vector widened to f64 (exactly).
pub fn widen(v: Vec3) -> glam::DVec3 {
    glam::DVec3::new(to_f64(v.x), to_f64(v.y), to_f64(v.z))
}

/// An f64 vector rounded to the nearest [`Vec3`].
#[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
pub fn narrow(v: glam::DVec3) -> Vec3 {
    Vec3::new(v.x as Real, v.y as Real, v.z as Real)
}

/// `2ⁿ` for a normal power of two (−126 ≤ n ≤ 127 for f32, −1022 ≤ n ≤
/// 1023 for f64), exactly: built from its exponent bits.
#[inline]
fn pow2_small(n: i32) -> Real {
    let biased = n + Real::MAX_EXP - 1;
    debug_assert!(biased > 0 && biased < 2 * Real::MAX_EXP - 1, "2^{n} is not a normal number");
    #[cfg(not(feature = "f64"))]
    {
        f32::from_bits((biased as u32) << (f32::MANTISSA_DIGITS - 1))
    }
    #[cfg(feature = "f64")]
    {
        f64::from_bits((biased as u64) << (f64::MANTISSA_DIGITS - 1))
    }
}

/// `x · 2ⁿ`, exact unless the result overflows or underflows; `n` may be
/// as large as a subnormal's exponent (applied in two exact halves).
#[inline]
pub fn scale_pow2(x: Real, n: i32) -> Real {
    // Where 2ⁿ is normal and n ≥ −1, one multiplication gives the halves'
    // bits: scaling up is exact (or overflows alike), and for n = −1 the
    // first half is 2⁰. Rays and hits nearly always take this way.
    if (-1..Real::MAX_EXP).contains(&n) {
        return x * pow2_small(n);
    }
    let half = n / 2;
    x * pow2_small(half) * pow2_small(n - half)
}

/// The exponent `n` with `2ⁿ ≤ m < 2ⁿ⁺¹`: read from the bits of a normal
/// `m`; for a subnormal one, from its logarithm (possibly one off, which is
/// harmless: callers only need some nearby power of two). `m` > 0, finite.
pub fn exponent_of(m: Real) -> i32 {
    if m < Real::MIN_POSITIVE {
        return m.log2().floor() as i32;
    }
    #[cfg(not(feature = "f64"))]
    let biased = (m.to_bits() >> (f32::MANTISSA_DIGITS - 1)) as i32;
    #[cfg(feature = "f64")]
    let biased = (m.to_bits() >> (f64::MANTISSA_DIGITS - 1)) as i32;
    biased - (Real::MAX_EXP - 1)
}
/// The sign-exact 2D edge function `a·b − c·d`, as used by the watertight
/// ray/triangle test.
///
/// With f32 geometry the products are formed in f64, where they are exact
/// (24 + 24 bits < 53), so the sign of the result is always right. With f64
/// geometry it is Kahan's difference of products with a fused multiply-add,
/// whose error is within 1.5 ulp of the result, so again the sign is right.
#[inline]
pub fn difference_of_products(a: Real, b: Real, c: Real, d: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        (a as f64 * b as f64 - c as f64 * d as f64) as Real
    }
    #[cfg(feature = "f64")]
    {
        let cd = c * d;
        let err = (-c).mul_add(d, cd);
        a.mul_add(b, -cd) + err
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cast_rule_sits_inside_the_window_spec_requires() {
        for origin in [Vec3::ZERO, Vec3::new(1e4, -3.0, 2.0), Vec3::splat(-7e6)] {
            for dir_len in [1e-3 as Real, 1.0, 250.0] {
                let dir = Vec3::new(0.0, 0.0, dir_len);
                let s = magnitude_scale(origin);
                let distance = cast_min_t(origin, dir) * dir_len;
                assert!(distance > s / (1 << 20) as Real);
                assert!(distance < s / (1 << 10) as Real);
            }
        }
    }

    #[test]
    fn cast_rule_refuses_everything_for_a_zero_direction() {
        assert_eq!(cast_min_t(Vec3::ONE, Vec3::ZERO), Real::INFINITY);
    }

    #[test]
    fn difference_of_products_has_the_exact_sign_when_products_nearly_cancel() {
        // a·b and c·d differ in the last bit only: the naive f32 form gives 0.
        let a: Real = 1.0 + Real::EPSILON;
        let b: Real = 1.0 - Real::EPSILON / 2.0;
        let (c, d): (Real, Real) = (1.0, 1.0);
        assert!(difference_of_products(a, b, c, d) > 0.0);
        assert!(difference_of_products(c, d, a, b) < 0.0);
    }

    #[test]
    fn normalize_robust_works_across_the_whole_exponent_range() {
        for scale in [1e-30 as Real, 1e-20, 1.0, 1e20, 1e30, Real::MAX / 4.0] {
            let n = normalize_robust(Vec3::new(3.0, 0.0, 4.0) * scale).unwrap();
            assert!((n - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6, "{scale}: {n}");
        }
        assert_eq!(normalize_robust(Vec3::ZERO), None);
        assert_eq!(normalize_robust(Vec3::new(Real::NAN, 0.0, 1.0)), None);
    }

    #[test]
    fn scaling_by_powers_of_two_is_exact_even_for_extreme_exponents() {
        let x: Real = 1.2345678;
        for n in [-140, -75, -1, 0, 1, 75, 120] {
            let y = scale_pow2(x, n);
            if y != 0.0 && y.is_finite() && y.is_normal() {
                assert_eq!(scale_pow2(y, -n), x, "n = {n}");
            }
        }
        assert_eq!(exponent_of(Real::MAX), Real::MAX_EXP - 1);
        assert_eq!(exponent_of(Real::MIN_POSITIVE), Real::MIN_EXP - 1);
        assert_eq!(exponent_of(Real::MIN_POSITIVE / 2.0), Real::MIN_EXP - 2);
        for m in [1e-30 as Real, 3e-7, 0.999, 1.5, 7.0, 8.0, 3e12] {
            let n = exponent_of(m);
            assert!(scale_pow2(1.0, n) <= m && m < scale_pow2(2.0, n), "{m}: {n}");
        }
        assert_eq!(exponent_of(1.0), 0);
        assert_eq!(exponent_of(0.75), -1);
        assert_eq!(exponent_of(1024.5), 10);
    }

    #[test]
    fn one_multiplication_scales_by_the_bits_of_two_halves_wherever_it_is_taken() {
        // The two exact halves, as `scale_pow2` applies every other n.
        let halves = |x: Real, n: i32| x * pow2_small(n / 2) * pow2_small(n - n / 2);
        let mut xs = vec![0.0, -0.0, Real::MIN_POSITIVE, Real::MAX, -Real::MAX, 1.0, -3.75];
        // Subnormals, whose scaling up must stay exact too.
        xs.extend([Real::MIN_POSITIVE / 3.0, -Real::MIN_POSITIVE / 1024.0, Real::from_bits(1)]);
        let mut bits: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..2000 {
            bits = crate::sampling::sampler::mix(bits.wrapping_add(0x9E37_79B9_7F4A_7C15));
            #[cfg(not(feature = "f64"))]
            let x = f32::from_bits(bits as u32);
            #[cfg(feature = "f64")]
            let x = f64::from_bits(bits);
            if x.is_finite() {
                xs.push(x);
            }
        }
        for &x in &xs {
            for n in -1..Real::MAX_EXP {
                let (fast, slow) = (scale_pow2(x, n), halves(x, n));
                assert_eq!(fast.to_bits(), slow.to_bits(), "{x:e} · 2^{n}: {fast:e} against {slow:e}");
            }
        }
    }

    #[test]
    fn gamma_bounds_grow_with_the_operation_count() {
        assert!(gamma(1) > UNIT_ROUNDOFF && gamma(3) > gamma(2));
    }
}
