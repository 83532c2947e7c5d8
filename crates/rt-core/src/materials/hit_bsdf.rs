//! The BSDF the path tracer builds at each hit: the Lambert lobe on its own
//! where a material has nothing else, else the whole model of [`Bsdf`].
//!
//! Most surfaces of a room are plain diffuse: no glossy, mirror or glass
//! lobe, no physically based model. For them the whole [`Bsdf`] (its lobe
//! weights and choice probabilities, the physically based model's slot, a
//! struct of some 250 bytes written at every hit) is set-up that nothing
//! reads. [`LambertBsdf`] keeps only what the Lambert lobe needs — its
//! albedo, the two normals and the shading frame — and does the very
//! operations [`Bsdf`] does for such a material, in the same order, so
//! that every value, sample and density has the same bits (tested): the
//! images do not change, the path tracer only does less.
//!
//! For a material with `reflectivity = transparency = specular = 0` and no
//! physically based model, [`Bsdf`]'s lobe weights are `(ρ̄, 0, 0, 0)`
//! (ρ̄ the albedo's mean), so its choice probabilities are exactly
//! `(1, 0, 0, 0)` when `0 < ρ̄ < ∞` (`ρ̄/ρ̄` rounds to 1): it always samples
//! the Lambert lobe, its density is `1·cos θ_i/π`, and `f = ρ/π` (times
//! Chiang et al.'s term about a shading normal). A black or non-finite
//! albedo keeps the whole model.

use crate::materials::bsdf::{Bsdf, BsdfSample, Lobe, facing_normals, reflected_cosine, terminator};
use crate::materials::material::Material;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3, to_f32};
use crate::sampling::sampler::cosine_hemisphere_in;

/// The Lambert lobe `ρ/π` alone, about the shading normal `n` (or the
/// geometric one), with [`Bsdf`]'s rules for shading normals.
#[derive(Clone, Copy, Debug)]
pub struct LambertBsdf {
    /// The shading normal turned to the side `ω_o` is on.
    n: Vec3,
    /// The geometric normal turned to the side `ω_o` is on.
    ng: Vec3,
    /// Whether `n` differs from `ng` (the shading-normal rules apply).
    shaded: bool,
    /// Tangents completing `n` to an orthonormal frame.
    frame: (Vec3, Vec3),
    /// The albedo ρ = kd·color.
    diffuse: Color,
}

impl LambertBsdf {
    /// The Lambert BSDF of `m` at a hit with unit geometric normal
    /// `geometric` and unit shading normal `shading`, seen from `wo`, as
    /// [`Bsdf::shaded`] makes it; `None` where `m` has more than the Lambert
    /// lobe (or a black or non-finite albedo).
    #[inline]
    pub fn shaded(m: &Material, geometric: Vec3, shading: Vec3, wo: Vec3) -> Option<Self> {
        if m.physical.is_some() || m.reflectivity != 0.0 || m.transparency != 0.0 || m.specular != 0.0 {
            return None;
        }
        // `Bsdf::with_normals`' albedo with `rest = 1`: the same product.
        let rest: f32 = 1.0;
        let diffuse = m.color * (rest * (1.0 - m.specular) * m.diffuse);
        let mean = diffuse.element_sum() / 3.0;
        // 0 < ρ̄ < ∞, and not NaN (a comparison, cheaper than `is_finite`).
        if !(mean > 0.0 && mean < f32::INFINITY) {
            return None;
        }
        let (n, ng, _) = facing_normals(geometric, shading, wo);
        Some(Self { n, ng, shaded: n != ng, frame: n.any_orthonormal_pair(), diffuse })
    }

    /// `f(ω_o, ω_i)`: [`Bsdf::eval`].
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Color {
        if reflected_cosine(self.n, self.ng, self.shaded, wo, wi).is_none() {
            return Color::ZERO;
        }
        let f = Color::from(glam::Vec3A::from(self.diffuse) * std::f32::consts::FRAC_1_PI);
        if self.shaded { f * terminator(self.n, self.ng, wi) } else { f }
    }

    /// The density of [`LambertBsdf::sample`]'s directions: [`Bsdf::pdf`].
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> Real {
        let Some(cos_i) = reflected_cosine(self.n, self.ng, self.shaded, wo, wi) else { return 0.0 };
        // `Bsdf::pdf` multiplies by the lobe's choice probability, 1 here.
        1.0 * cos_i * std::f64::consts::FRAC_1_PI as Real
    }

    /// A cosine-distributed direction about `n`: [`Bsdf::sample`].
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Real, u2: (Real, Real)) -> Option<BsdfSample> {
        // `Bsdf` chooses the Lambert lobe for every `u < 1` (and no lobe
        // for a NaN).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if self.n.dot(wo) <= 0.0 || !(u < 1.0) {
            return None;
        }
        let wi = cosine_hemisphere_in(self.n, self.frame, u2);
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        let weight = self.eval(wo, wi) * to_f32(self.n.dot(wi) / pdf);
        // Reflections stay on ω_o's side of the facet.
        if self.shaded && self.ng.dot(wi) <= 0.0 {
            return None;
        }
        Some(BsdfSample { wi, weight, pdf, lobe: Lobe::Diffuse, eta: 1.0 })
    }
}

/// The BSDF at one hit as the path tracer uses it: [`LambertBsdf`] where
/// the material is plain diffuse, else the whole [`Bsdf`]; the same bits
/// either way.
///
/// The enum is as large as [`Bsdf`], but making the Lambert variant writes
/// only its own fields and the tag: the set-up it saves is that writing
/// (boxing the large variant would cost an allocation a hit instead).
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
pub enum HitBsdf {
    /// The Lambert lobe alone.
    Lambert(LambertBsdf),
    /// Any material.
    Full(Bsdf),
}

impl HitBsdf {
    /// [`Bsdf::shaded`], or its Lambert lobe alone where that is all `m` has.
    #[inline]
    pub fn shaded(m: &Material, geometric: Vec3, shading: Vec3, wo: Vec3) -> Self {
        match LambertBsdf::shaded(m, geometric, shading, wo) {
            Some(lambert) => Self::Lambert(lambert),
            None => Self::Full(Bsdf::shaded(m, geometric, shading, wo)),
        }
    }

    /// Whether the BSDF has a smooth (non-δ) part: [`Bsdf::has_smooth_lobes`].
    #[inline]
    pub fn has_smooth_lobes(&self) -> bool {
        match self {
            Self::Lambert(_) => true,
            Self::Full(b) => b.has_smooth_lobes(),
        }
    }

    /// [`Bsdf::eval`].
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Color {
        match self {
            Self::Lambert(l) => l.eval(wo, wi),
            Self::Full(b) => b.eval(wo, wi),
        }
    }

    /// [`Bsdf::pdf`].
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> Real {
        match self {
            Self::Lambert(l) => l.pdf(wo, wi),
            Self::Full(b) => b.pdf(wo, wi),
        }
    }

    /// [`Bsdf::sample`].
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Real, u2: (Real, Real)) -> Option<BsdfSample> {
        match self {
            Self::Lambert(l) => l.sample(wo, u, u2),
            Self::Full(b) => b.sample(wo, u, u2),
        }
    }

    /// `|n_s·ω_i|`: [`Bsdf::cosine`].
    #[inline]
    pub fn cosine(&self, wi: Vec3) -> Real {
        match self {
            Self::Lambert(l) => l.n.dot(wi).abs(),
            Self::Full(b) => b.cosine(wi),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::principled::Principled;
    use proptest::prelude::*;

    fn bits(c: Color) -> [u32; 3] {
        c.to_array().map(f32::to_bits)
    }

    fn unit(a: [f32; 3]) -> Vec3 {
        Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real).normalize_or(Vec3::Y)
    }

    /// Bits of a real number, whatever `Real` is.
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
    fn real_bits(x: Real) -> u64 {
        (x as f64).to_bits()
    }

    /// A sample's direction, weight, density, lobe and η, as bits.
    type SampleBits = ([u64; 3], [u32; 3], u64, Lobe, u64);

    /// The parts of a sample that the path tracer reads, as bits.
    fn sample_bits(s: Option<BsdfSample>) -> Option<SampleBits> {
        s.map(|s| {
            (s.wi.to_array().map(real_bits), bits(s.weight), real_bits(s.pdf), s.lobe, real_bits(s.eta))
        })
    }

    #[test]
    fn only_plain_diffuse_materials_take_the_lambert_lobe_alone() {
        let plain = Material::flat(Color::new(0.8, 0.5, 0.2));
        let lambert =
            |m: &Material| matches!(HitBsdf::shaded(m, Vec3::Y, Vec3::Y, Vec3::Y), HitBsdf::Lambert(_));
        assert!(lambert(&plain));
        assert!(lambert(&Material { diffuse: 0.3, emission: Color::ONE, ..plain }));
        for (name, m) in [
            ("glossy", Material { specular: 0.1, ..plain }),
            ("mirror", Material { reflectivity: 0.1, ..plain }),
            ("glass", Material { transparency: 0.1, ..plain }),
            ("physically based", Material { physical: Some(Principled::DIELECTRIC), ..plain }),
            ("black", Material::flat(Color::ZERO)),
            ("no diffuse part", Material { diffuse: 0.0, ..plain }),
            ("infinite albedo", Material::flat(Color::new(f32::INFINITY, 0.5, 0.5))),
            ("NaN albedo", Material::flat(Color::new(f32::NAN, 0.5, 0.5))),
        ] {
            assert!(!lambert(&m), "{name}");
        }
    }

    #[test]
    fn a_lobe_choice_of_one_or_more_samples_nothing_as_the_whole_model() {
        let m = Material::flat(Color::new(0.8, 0.5, 0.2));
        let (lambert, full) =
            (HitBsdf::shaded(&m, Vec3::Y, Vec3::Y, Vec3::Y), Bsdf::shaded(&m, Vec3::Y, Vec3::Y, Vec3::Y));
        for u in [1.0, 1.5, Real::NAN] {
            assert!(lambert.sample(Vec3::Y, u, (0.3, 0.6)).is_none(), "{u}");
            assert!(full.sample(Vec3::Y, u, (0.3, 0.6)).is_none(), "{u}");
        }
    }

    proptest! {
        /// For any plain diffuse material, normals (a shading normal or
        /// none), and directions on either side, the Lambert lobe alone gives
        /// the whole model's values, densities and samples bit for bit: the
        /// path tracer's images do not change with it.
        #[test]
        fn the_lambert_lobe_alone_has_the_bits_of_the_whole_model(
            color in prop::array::uniform3(0f32..1.0),
            kd in 0f32..1.0,
            geometric in prop::array::uniform3(-1f32..1.0),
            lean in prop::array::uniform3(-0.6f32..0.6),
            shaded in any::<bool>(),
            wo in prop::array::uniform3(-1f32..1.0),
            wi in prop::array::uniform3(-1f32..1.0),
            u in 0f32..1.0,
            u2 in prop::array::uniform2(0f32..1.0),
        ) {
            let m = Material { diffuse: kd, ..Material::flat(Color::from_array(color)) };
            let ng = unit(geometric);
            let ns = if shaded { (ng + unit(lean) * 0.5).normalize_or(ng) } else { ng };
            let (wo, wi) = (unit(wo), unit(wi));
            let (u, u2) = (u as Real, (u2[0] as Real, u2[1] as Real));
            let full = Bsdf::shaded(&m, ng, ns, wo);
            let lean_one = HitBsdf::shaded(&m, ng, ns, wo);
            let mean = (Color::from_array(color) * kd).element_sum() / 3.0;
            prop_assert_eq!(matches!(lean_one, HitBsdf::Lambert(_)), mean > 0.0);
            prop_assert_eq!(lean_one.has_smooth_lobes(), full.has_smooth_lobes());
            prop_assert_eq!(bits(lean_one.eval(wo, wi)), bits(full.eval(wo, wi)));
            prop_assert_eq!((lean_one.pdf(wo, wi) as f64).to_bits(), (full.pdf(wo, wi) as f64).to_bits());
            prop_assert_eq!((lean_one.cosine(wi) as f64).to_bits(), (full.cosine(wi) as f64).to_bits());
            prop_assert_eq!(sample_bits(lean_one.sample(wo, u, u2)), sample_bits(full.sample(wo, u, u2)));
        }
    }
}
