//! How a material scatters light: its BSDF (bidirectional scattering
//! distribution function) at one hit, evaluated, sampled, and with the
//! density of its samples.
//!
//! # The radiometric model
//!
//! The units and lobes are those of pbrt-v4 and Mitsuba 3. Radiance L is in
//! W·m⁻²·sr⁻¹, a BSDF f in sr⁻¹, and light leaving a point towards the viewer
//! is `L_o = L_e + ∫ f(ω_o, ω_i)·L_i(ω_i)·|cos θ_i| dω_i`. A [`Material`] is a
//! mixture of four lobes, with kr = `reflectivity`, kt = `transparency`,
//! ks = `specular`, kd = `diffuse`, s = `specular_color` (the tint of the
//! glossy and mirror lobes, white by default; a metal's colour):
//!
//! ```text
//! f = (1 − kr − kt)·[(1 − ks)·kd·color/π + ks·s·f_ggx] + kr·s·f_mirror + kt·f_dielectric
//! ```
//!
//! - **Lambert**: `ρ/π` with albedo ρ = kd·color (pbrt-v4 §9.2, `DiffuseBxDF`).
//! - **Glossy**: the GGX (Trowbridge–Reitz) microfacet lobe
//!   `D(h)·G(ω_o, ω_i)/(4·cos θ_o·cos θ_i)` with
//!   `D(h) = α²/(π·(cos²θ_h·(α² − 1) + 1)²)` and Smith's separable
//!   masking-shadowing `G = G₁(ω_o)·G₁(ω_i)`, `G₁ = 2/(1 + √(1 + α²·tan²θ))`
//!   (Walter, Marschner, Li and Torrance, "Microfacet Models for Refraction
//!   through Rough Surfaces", EGSR 2007), with Fresnel 1 and tinted by s:
//!   Mitsuba 3's `roughconductor` with `material = "none"` and
//!   `specular_reflectance` s. Its roughness comes from the
//!   Blinn–Phong exponent by Walter et al.'s correspondence
//!   `α = √(2/(shininess + 2))`. Directions are sampled from the
//!   distribution of visible normals (Heitz, "Sampling the GGX Distribution
//!   of Visible Normals", JCGT 2018).
//! - **Mirror**: a perfect reflection tinted by s (a δ lobe).
//! - **Dielectric**: a smooth boundary of index `ior`, δ reflection with the
//!   exact Fresnel reflectance F ([`fresnel_dielectric`]) and δ refraction by
//!   Snell's law with `(1 − F)·color`, divided by `η²` (η the ratio of the
//!   indices across the boundary, the side the light arrives on over the
//!   side it leaves to): radiance is compressed into a narrower cone when it
//!   enters a denser medium (pbrt-v4 §9.5.2). The factors of a path that
//!   enters and leaves an object cancel.
//!
//! Every lobe reflects or transmits at most what arrives (the Lambert and δ
//! lobes exactly their weight, the GGX lobe less, by its masking), and
//! `(1 − ks)·kd·max(color) + ks ≤ 1` and `kr + kt ≤ 1` hold for every
//! material the scene loader accepts, so every material is energy
//! conserving: tested by integrating `f·cos` over the sphere.
//!
//! # Conventions
//!
//! `ω_o` points towards the viewer, `ω_i` towards the light; both are unit
//! vectors in world space. The reflection lobes are two-sided: they act on
//! the side of the surface `ω_o` is on, and are zero for `ω_i` on the other.
//! The dielectric is oriented: the side the geometric normal points to is
//! outside (index 1), the other inside (index `ior`).
//!
//! # Shading normals
//!
//! A smooth mesh gives a *shading* normal `n_s` (its interpolated vertex
//! normals) that differs from the *geometric* normal `n_g` of the flat
//! triangle ([`Bsdf::shaded`]). The lobes are then defined about `n_s`,
//! which hides the facets, while `n_g` keeps deciding which side of the
//! surface a direction is on, so no light leaks through it:
//!
//! - **No leaks.** A reflected direction must lie on `ω_o`'s side of the
//!   *geometric* surface and a refracted one on the other: directions the
//!   lobes around `n_s` give on the wrong side of `n_g` carry nothing (they
//!   are zero in [`Bsdf::eval`] and [`Bsdf::pdf`], and a sample that draws
//!   one is refused) — pbrt-v3's rule (§9.1, `BSDF::f`).
//! - **No black facets.** Where `ω_o` lies below the shading hemisphere but
//!   above the geometric one (at silhouettes of coarse meshes), every lobe
//!   about `n_s` would be zero; the BSDF falls back to `n_g` there.
//! - **No hard terminator.** Near the shadow terminator a coarse mesh's
//!   own facets shadow light that `n_s` says arrives; the smooth lobes are
//!   multiplied by Chiang, Li and Burley's shadowing term
//!   `G = min(1, (n_g·ω_i)/((n_s·ω_i)(n_g·n_s)))`, `−G³ + G² + G`
//!   ("Taming the Shadow Terminator", SIGGRAPH 2019 Talks), which fades
//!   the light smoothly to zero where the facet turns away.
//!
//! With `n_s = n_g` (every primitive but a mesh with vertex normals) all
//! three are the plain rules above, and nothing changes.
//!
//! # Normal maps
//!
//! A normal map ([`crate::materials::normal_map`]) bends the smooth normal
//! `n_s` (the interpolated one, or `n_g`) to `n_m`, far more than vertex
//! normals ever lean, and the lobes are defined about `n_m`
//! ([`Bsdf::mapped`]). The rules above still hold about `n_g` (no leaks,
//! Chiang et al.'s term between `n_g` and `n_s`), and two more apply, as
//! Blender Cycles applies them:
//!
//! - **A reflection the viewer can see.** Where `n_m` leans so far from the
//!   viewer that the mirror reflection `r` of `ω_o` about it points into the
//!   surface (`r·n_g < t`, `t = min(0.9·cos θ_o, 0.01)`,
//!   [`crate::math::real::VALID_REFLECTION_MARGIN`]), `n_m` is bent back
//!   towards `n_g` in their common plane, `n' = cos φ·n_g + sin φ·x` (`x`
//!   the unit direction of the lean along the surface), to the largest lean
//!   whose mirror reflection of `ω_o` has cosine `t` with `n_g`: as
//!   `r'·n_g = 2(n'·ω_o)(n'·n_g) − ω_o·n_g = z·cos 2φ + x_o·sin 2φ` with
//!   `z = ω_o·n_g`, `x_o = ω_o·x`, that is
//!   `2φ = atan2(x_o, z) + acos(t/√(z² + x_o²))` (Blender Cycles'
//!   `ensure_valid_specular_reflection` bends it in the same plane to the
//!   same cosine; this is its closed form, not its code). The bend is
//!   exact however far the map leans. `ω_o` is then above the lobes' normal, so no fallback to `n_g`
//!   is needed. As in Cycles, only the specular lobes turn about the bent
//!   normal: the diffuse base keeps the map's `n_m` (its value carries the
//!   ratio `max(0, n_m·ω_i)/(n·ω_i)` of its cosine to the bent normal's,
//!   which the integrators multiply by).
//! - **Bumps shadow their own diffuse light.** The diffuse base is
//!   multiplied by Conty Estevez, Lecocq and Stein's shadowing term ("A
//!   Microfacet-Based Shadowing Function to Solve the Bump Terminator
//!   Problem", Ray Tracing Gems, 2019, ch. 12): Smith's GGX masking
//!   `G₁ = 2/(1 + √(1 + α_b²·tan²θ_i))` of `ω_i` about `n_s`, for a
//!   roughness that grows with the bend, `α_b² = min(1, tan²θ_d/8)`,
//!   `cos θ_d = n_s·n_m`. Chiang et al.'s term (above) darkens a gentle
//!   bump's lit flank too much and a steep one's too little; this one is
//!   1 for an unbent normal and light from straight above, and fades the
//!   light smoothly towards the horizon of `n_s` the more the map bends.
//!   The specular lobes are not softened (Cycles softens the diffuse
//!   closures only).

use crate::materials::material::Material;
use crate::materials::principled::{Chosen, Lobes, sample_visible_normal};
use crate::materials::shading::{fresnel_dielectric, reflect, refract};
use crate::math::color::Color;
use crate::math::real::{
    Real, VALID_REFLECTION_MARGIN, VALID_REFLECTION_SHARE, Vec3, normalize_robust, to_f32,
};
use crate::sampling::sampler::cosine_hemisphere_in;

/// Which lobe a sample came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    /// The Lambert lobe.
    Diffuse,
    /// The GGX lobe.
    Glossy,
    /// The mirror (δ).
    Mirror,
    /// The dielectric's reflection (δ).
    Reflection,
    /// The dielectric's refraction (δ).
    Transmission,
    /// A rough dielectric's refraction (the physically based model's transmission).
    RoughTransmission,
}

impl Lobe {
    /// Whether the lobe is a δ distribution: one direction, no density.
    pub fn is_delta(self) -> bool {
        !matches!(self, Self::Diffuse | Self::Glossy | Self::RoughTransmission)
    }

    /// Whether the sampled direction goes through the surface.
    pub fn is_transmission(self) -> bool {
        matches!(self, Self::Transmission | Self::RoughTransmission)
    }
}

/// A direction drawn from a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Unit direction towards where light comes from.
    pub wi: Vec3,
    /// `f·|cos θ_i|/pdf`: what the sample multiplies a path's throughput by.
    pub weight: Color,
    /// The density the sample was drawn with over solid angle (smooth lobes,
    /// all of them together), or the probability of choosing its δ lobe.
    pub pdf: Real,
    /// The lobe it came from.
    pub lobe: Lobe,
    /// For a sample through the surface (a transmission lobe), the relative
    /// index `η = η_i/η_o` of the side `ω_i` is on over the side `ω_o` is on,
    /// whose `1/η²` the weight carries (radiance compressed into a narrower
    /// cone); 1 for a reflection. pbrt-v4's `BSDFSample::eta` (§9.5.2), which
    /// a path tracer multiplies up to take that factor back out of its
    /// Russian roulette (§14.1.5).
    pub eta: Real,
}

/// The BSDF of one material at one hit, seen from one direction `ω_o`.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// The shading normal turned to the side `ω_o` is on.
    n: Vec3,
    /// The geometric normal turned to the side `ω_o` is on.
    ng: Vec3,
    /// Whether `n` differs from `ng` (the shading-normal rules apply).
    shaded: bool,
    /// The smooth normal a normal map bent to `n`, turned to `ω_o`'s side
    /// (`n` itself without a map).
    ns: Vec3,
    /// Whether a normal map bent `ns` to `n` (the rules of "Normal maps").
    bumped: bool,
    /// The normal map's normal before it was bent for a visible reflection:
    /// the diffuse base's normal ("Normal maps"; `n` without a map).
    nd: Vec3,
    /// Tangents completing `n` to an orthonormal frame.
    frame: (Vec3, Vec3),
    /// `ω_o` arrives from the side the geometric normal points to (outside).
    outside: bool,
    /// Colour of the Lambert lobe: `(1 − kr − kt)·(1 − ks)·kd·color`.
    diffuse: Color,
    /// Weight of the GGX lobe: `(1 − kr − kt)·ks`.
    glossy: f32,
    /// The glossy and mirror lobes' tint s.
    specular_color: Color,
    /// GGX roughness α.
    alpha: Real,
    /// kr.
    mirror: f32,
    /// kt.
    dielectric: f32,
    /// The dielectric's tint.
    tint: Color,
    /// Index of refraction of the inside.
    ior: Real,
    /// Probabilities of choosing each lobe when sampling, in the order
    /// diffuse, glossy, mirror, dielectric; they sum to 1 (or all are 0 for a
    /// black material).
    choose: [f32; 4],
    /// The physically based model's lobes, for a material that has one
    /// (then the fields of the weights above are unused).
    principled: Option<Lobes>,
}

impl Bsdf {
    /// The BSDF of `m` at a hit with unit geometric normal `normal` (the
    /// primitive's own orientation), seen from the unit direction `wo`.
    #[inline]
    pub fn new(m: &Material, normal: Vec3, wo: Vec3) -> Self {
        let (n, outside) = facing_facet(normal, wo);
        Self::with_normals(m, n, n, outside, wo)
    }

    /// The BSDF of `m` at a hit with unit geometric normal `geometric` and
    /// unit shading normal `shading`, seen from `wo` (see "Shading normals"
    /// above). The shading normal is first turned to the side the
    /// geometric one points to.
    #[inline]
    pub fn shaded(m: &Material, geometric: Vec3, shading: Vec3, wo: Vec3) -> Self {
        let (n, ng, outside) = facing_normals(geometric, shading, wo);
        Self::with_normals(m, n, ng, outside, wo)
    }

    /// The BSDF of `m` at a hit with unit geometric normal `geometric` where
    /// a normal map bent the unit smooth normal `smooth` (a mesh's
    /// interpolated normal, or `geometric`) to the unit `mapped`, seen from
    /// `wo` (see "Normal maps" above).
    #[inline]
    pub fn mapped(m: &Material, geometric: Vec3, smooth: Vec3, mapped: Vec3, wo: Vec3) -> Self {
        let (ng, outside) = facing_facet(geometric, wo);
        let ns = if smooth.dot(ng) < 0.0 { -smooth } else { smooth };
        let n = if mapped.dot(ng) < 0.0 { -mapped } else { mapped };
        let nd = n;
        let n = visible_reflection_normal(ng, wo, n);
        let mut b = Self::with_normals(m, n, ng, outside, wo);
        b.ns = ns;
        b.nd = nd;
        b.bumped = n != ns;
        b
    }

    #[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
    #[inline]
    fn with_normals(m: &Material, n: Vec3, ng: Vec3, outside: bool, wo: Vec3) -> Self {
        let rest = (1.0 - m.reflectivity - m.transparency).max(0.0);
        let diffuse = m.color * (rest * (1.0 - m.specular) * m.diffuse);
        let glossy = rest * m.specular;
        // Choose lobes by their share of the reflected energy (the Lambert
        // lobe's by its mean albedo over the three channels).
        let weights = [diffuse.element_sum() / 3.0, glossy, m.reflectivity, m.transparency];
        let total: f32 = weights.iter().sum();
        // The four quotients as one 4-lane division: each correctly rounded,
        // the bits of four scalar divisions.
        let choose =
            if total > 0.0 { (glam::Vec4::from_array(weights) / total).to_array() } else { [0.0; 4] };
        Self {
            n,
            ng,
            shaded: n != ng,
            ns: n,
            bumped: false,
            nd: n,
            frame: n.any_orthonormal_pair(),
            outside,
            diffuse,
            glossy,
            specular_color: m.specular_color,
            alpha: m.roughness() as Real,
            mirror: m.reflectivity,
            dielectric: m.transparency,
            tint: m.color,
            ior: m.ior as Real,
            choose,
            principled: m
                .physical
                .map(|p| Lobes::new(&p, m.color, m.ior as Real, outside, n.dot(wo).max(0.0))),
        }
    }

    /// The normal the lobes are defined about (the shading normal, or the
    /// geometric one where it falls back), turned to `ω_o`'s side.
    pub fn normal(&self) -> Vec3 {
        self.n
    }

    /// The Lambert lobe's albedo ρ (its value is ρ/π): what it reflects of
    /// light arriving equally from every direction (the direct-lighting
    /// tracer's ambient term).
    #[inline]
    pub fn diffuse_albedo(&self) -> Color {
        if let Some(p) = &self.principled {
            return p.diffuse_albedo();
        }
        self.diffuse
    }

    /// For the physically based model, the weights of its δ lobes
    /// `(reflection, transmission)` as seen from `wo` (the transmission
    /// without its 1/η²); `None` for the weights model, whose δ lobes are
    /// its `reflectivity` and `transparency`.
    pub fn delta_weights(&self, wo: Vec3) -> Option<(Color, Color)> {
        self.principled.map(|p| p.delta_weights(self.n.dot(wo).max(0.0)))
    }

    /// Whether the BSDF has a smooth (non-δ) part, which light sampling can reach.
    #[inline]
    pub fn has_smooth_lobes(&self) -> bool {
        if let Some(p) = &self.principled {
            return p.has_smooth_lobes();
        }
        self.choose[0] > 0.0 || self.choose[1] > 0.0
    }

    /// The smooth lobes' `f(ω_o, ω_i)` (δ lobes have no value to evaluate).
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Color {
        if let Some(p) = &self.principled {
            if !self.on_the_right_side(wo, wi) {
                return Color::ZERO;
            }
            let f = p.eval(self.local(wo), self.local(wi));
            if self.bumped && self.n.dot(wi) > 0.0 {
                let diffuse = p.eval_diffuse(self.local(wo), self.local(wi));
                return self.bump_shadowed(f, diffuse, wi);
            }
            return if self.shaded && self.n.dot(wi) > 0.0 { f * self.terminator(wi) } else { f };
        }
        if reflected_cosine(self.n, self.ng, self.shaded, wo, wi).is_none() {
            return Color::ZERO;
        }
        // On four lanes, so that the three products are made, and kept, as
        // one vector (the same bits): as `Color` they were made as one and
        // two lanes, stored apart and read back with one 8-byte load, a
        // store-to-load forwarding stall.
        let mut f = Color::from(glam::Vec3A::from(self.diffuse) * std::f32::consts::FRAC_1_PI);
        let diffuse = f;
        if self.glossy > 0.0 {
            f += self.specular_color * (self.glossy * to_f32(self.ggx(self.local(wo), self.local(wi))));
        }
        if self.bumped {
            return self.bump_shadowed(f, diffuse, wi);
        }
        if self.shaded { f * self.terminator(wi) } else { f }
    }

    /// `|n_s·ω_i|`: the cosine that weighs light arriving along `wi` (the
    /// shading normal's, as the lobes are defined about it).
    #[inline]
    pub fn cosine(&self, wi: Vec3) -> Real {
        self.n.dot(wi).abs()
    }

    /// Chiang, Li and Burley's shadowing term for `ω_i` above the surface
    /// (see "Shading normals"): 1 where the facet does not turn away.
    fn terminator(&self, wi: Vec3) -> f32 {
        terminator(self.n, self.ng, wi)
    }

    /// `f` (all smooth lobes, of which `diffuse` is the diffuse base) for
    /// light from `wi` above a normal-mapped surface: the diffuse base times
    /// the bump's shadowing term, all of it times Chiang et al.'s term
    /// between the facet and the smooth normal (see "Normal maps").
    fn bump_shadowed(&self, f: Color, diffuse: Color, wi: Vec3) -> Color {
        let rest = (f - diffuse).max(Color::ZERO);
        // The diffuse base lies about the unbent normal: its cosine, not
        // the bent normal's, which the caller multiplies by.
        let cosines = if self.nd == self.n {
            1.0
        } else {
            to_f32((self.nd.dot(wi).max(0.0) / self.n.dot(wi)).max(0.0))
        };
        let f = diffuse * (cosines * self.bump_shadowing(wi)) + rest;
        if self.ns == self.ng {
            return f;
        }
        f * terminator(self.ns, self.ng, wi)
    }

    /// Conty Estevez, Lecocq and Stein's shadowing term for a normal map
    /// (see "Normal maps"): Smith's GGX `G₁` of `ω_i` about the smooth
    /// normal for `α² = min(1, tan²θ_d/8)`, `θ_d` the map's bend.
    fn bump_shadowing(&self, wi: Vec3) -> f32 {
        let (cos_d, cos_i) = (self.ns.dot(self.nd), self.ns.dot(wi));
        if cos_i <= 0.0 {
            return 0.0;
        }
        if cos_d >= 1.0 || cos_i >= 1.0 {
            return 1.0;
        }
        let alpha2 = (0.125 * (1.0 / (cos_d * cos_d) - 1.0)).clamp(0.0, 1.0);
        let tan2_i = 1.0 / (cos_i * cos_i) - 1.0;
        to_f32(2.0 / (1.0 + (1.0 + alpha2 * tan2_i).sqrt()))
    }

    /// The density over solid angle with which [`Bsdf::sample`] draws `ω_i`
    /// from the smooth lobes (their selection probabilities included).
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> Real {
        if let Some(p) = &self.principled {
            if !self.on_the_right_side(wo, wi) {
                return 0.0;
            }
            return p.pdf(self.local(wo), self.local(wi));
        }
        let Some(cos_i) = reflected_cosine(self.n, self.ng, self.shaded, wo, wi) else { return 0.0 };
        let mut pdf = self.choose[0] as Real * cos_i * std::f64::consts::FRAC_1_PI as Real;
        if self.choose[1] > 0.0 {
            pdf += self.choose[1] as Real * self.ggx_pdf(self.local(wo), self.local(wi));
        }
        pdf
    }

    /// Draws `ω_i` for `wo`: `u` chooses the lobe, `u2` the direction in it.
    /// `None` when the material reflects nothing or the drawn direction
    /// carries nothing (a microfacet reflection below the surface).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Real, u2: (Real, Real)) -> Option<BsdfSample> {
        let s = self.sample_lobes(wo, u, u2)?;
        if self.shaded {
            // Reflections stay on ω_o's side of the facet, refractions cross it.
            let through = s.lobe.is_transmission();
            if (self.ng.dot(s.wi) < 0.0) != through || self.ng.dot(s.wi) == 0.0 {
                return None;
            }
        }
        Some(s)
    }

    /// For the physically based model: `ω_o` above the lobes' normal, and
    /// `ω_i` on the same side of both normals (reflection) or on the other
    /// side of both (transmission): see "Shading normals".
    fn on_the_right_side(&self, wo: Vec3, wi: Vec3) -> bool {
        let (cos_o, cos_i, cos_g) = (self.n.dot(wo), self.n.dot(wi), self.ng.dot(wi));
        cos_o > 0.0 && cos_i != 0.0 && (!self.shaded || (cos_g != 0.0 && (cos_g > 0.0) == (cos_i > 0.0)))
    }

    /// [`Bsdf::sample_lobes`] for the physically based model.
    fn sample_principled(&self, p: &Lobes, wo: Vec3, u: Real, u2: (Real, Real)) -> Option<BsdfSample> {
        if self.n.dot(wo) <= 0.0 {
            return None;
        }
        let s = p.sample(self.local(wo), u, u2)?;
        let lobe = match s.chosen {
            Chosen::Diffuse => Lobe::Diffuse,
            Chosen::Reflection | Chosen::Coat => Lobe::Glossy,
            Chosen::Mirror => Lobe::Mirror,
            Chosen::CoatMirror => Lobe::Reflection,
            Chosen::RoughTransmission => Lobe::RoughTransmission,
            Chosen::Transmission => Lobe::Transmission,
        };
        let wi = self.world(s.wi);
        let eta = if lobe.is_transmission() { p.eta() } else { 1.0 };
        if self.shaded && !lobe.is_delta() {
            // The terminator term and the facet's sides: as `eval` and `pdf` say.
            let pdf = self.pdf(wo, wi);
            if pdf.is_nan() || pdf <= 0.0 {
                return None;
            }
            let weight = self.eval(wo, wi) * to_f32(self.cosine(wi) / pdf);
            return Some(BsdfSample { wi, weight, pdf, lobe, eta });
        }
        Some(BsdfSample { wi, weight: s.weight, pdf: s.pdf, lobe, eta })
    }

    fn sample_lobes(&self, wo: Vec3, u: Real, u2: (Real, Real)) -> Option<BsdfSample> {
        if let Some(p) = &self.principled {
            return self.sample_principled(p, wo, u, u2);
        }
        let [p_diffuse, p_glossy, p_mirror, p_dielectric] = self.choose.map(|p| p as Real);
        if self.n.dot(wo) <= 0.0 && p_dielectric == 0.0 {
            return None;
        }
        let mut u = u;
        if u < p_diffuse + p_glossy {
            let wi = if u < p_diffuse {
                // `frame` is `n`'s own tangent pair: the bits of `cosine_hemisphere(n, u2)`.
                cosine_hemisphere_in(self.n, self.frame, u2)
            } else {
                let h = self.world(self.ggx_sample_normal(self.local(wo), u2));
                reflect(-wo, h)
            };
            let pdf = self.pdf(wo, wi);
            if pdf <= 0.0 {
                return None;
            }
            let lobe = if u < p_diffuse { Lobe::Diffuse } else { Lobe::Glossy };
            let weight = self.eval(wo, wi) * to_f32(self.n.dot(wi) / pdf);
            return Some(BsdfSample { wi, weight, pdf, lobe, eta: 1.0 });
        }
        u -= p_diffuse + p_glossy;
        // δ lobes: weight = lobe weight / probability of choosing it.
        let total = self.diffuse.element_sum() / 3.0 + self.glossy + self.mirror + self.dielectric;
        if u < p_mirror {
            let wi = reflect(-wo, self.n);
            let weight = self.specular_color * total;
            return Some(BsdfSample { wi, weight, pdf: p_mirror, lobe: Lobe::Mirror, eta: 1.0 });
        }
        u -= p_mirror;
        if p_dielectric <= 0.0 {
            return None;
        }
        let u = (u / p_dielectric).clamp(0.0, 1.0);
        let (eta_i, eta_t) = if self.outside { (1.0, self.ior) } else { (self.ior, 1.0) };
        let cos_o = self.n.dot(wo);
        let fresnel = fresnel_dielectric(cos_o, eta_i, eta_t);
        if u < fresnel {
            let wi = reflect(-wo, self.n);
            let pdf = p_dielectric * fresnel;
            return Some(BsdfSample {
                wi,
                weight: Color::splat(total),
                pdf,
                lobe: Lobe::Reflection,
                eta: 1.0,
            });
        }
        let wi = refract(-wo, self.n, eta_i, eta_t)?;
        // Radiance arriving from the far side (index eta_t) towards the viewer
        // (index eta_i) is scaled by (eta_i/eta_t)².
        let scale = eta_i / eta_t;
        let weight = self.tint * (total * to_f32(scale * scale));
        let pdf = p_dielectric * (1.0 - fresnel);
        Some(BsdfSample { wi, weight, pdf, lobe: Lobe::Transmission, eta: eta_t / eta_i })
    }

    /// `w` in the local frame: (tangent, bitangent, normal) coordinates.
    fn local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.frame.0), w.dot(self.frame.1), w.dot(self.n))
    }

    /// A local-frame vector back in world space.
    fn world(&self, v: Vec3) -> Vec3 {
        v.x * self.frame.0 + v.y * self.frame.1 + v.z * self.n
    }

    /// The GGX distribution of normals `D(h)`, `h` local and unit.
    fn ggx_d(&self, h: Vec3) -> Real {
        let a2 = self.alpha * self.alpha;
        let c2 = h.z * h.z;
        let denom = c2 * (a2 - 1.0) + 1.0;
        a2 / (std::f64::consts::PI as Real * denom * denom)
    }

    /// Smith's masking `G₁(w) = 2/(1 + √(1 + α²·tan²θ))`, `w` local.
    fn ggx_g1(&self, w: Vec3) -> Real {
        let c2 = w.z * w.z;
        if c2 <= 0.0 {
            return 0.0;
        }
        let tan2 = ((1.0 - c2) / c2).max(0.0);
        2.0 / (1.0 + (1.0 + self.alpha * self.alpha * tan2).sqrt())
    }

    /// The GGX lobe `D·G/(4·cos θ_o·cos θ_i)` for local `wo`, `wi` above the surface.
    fn ggx(&self, wo: Vec3, wi: Vec3) -> Real {
        let Some(h) = (wo + wi).try_normalize() else { return 0.0 };
        self.ggx_d(h) * self.ggx_g1(wo) * self.ggx_g1(wi) / (4.0 * wo.z * wi.z)
    }

    /// The density of `wi` under visible-normal sampling:
    /// `G₁(ω_o)·(ω_o·h)·D(h)/cos θ_o`, over `4·(ω_o·h)` for the reflection.
    fn ggx_pdf(&self, wo: Vec3, wi: Vec3) -> Real {
        let Some(h) = (wo + wi).try_normalize() else { return 0.0 };
        let d_visible = self.ggx_g1(wo) * self.ggx_d(h) / wo.z;
        d_visible / 4.0
    }

    /// A microfacet normal drawn from the normals visible from local `wo`
    /// (Heitz 2018, listing 1).
    fn ggx_sample_normal(&self, wo: Vec3, u: (Real, Real)) -> Vec3 {
        sample_visible_normal(wo, self.alpha, u)
    }
}

/// The lobes' normal, the geometric normal (both turned to `ω_o`'s side of
/// the geometric one) and whether `ω_o` is outside, for unit `geometric`
/// and `shading` normals seen from `wo` (see "Shading normals"): the
/// shading normal falls back to the facet's where `ω_o` lies below it.
#[inline(always)]
pub(crate) fn facing_normals(geometric: Vec3, shading: Vec3, wo: Vec3) -> (Vec3, Vec3, bool) {
    let (ng, outside) = facing_facet(geometric, wo);
    if shading == geometric {
        return (ng, ng, outside);
    }
    let ns = if shading.dot(ng) < 0.0 { -shading } else { shading };
    // ω_o below the shading hemisphere: fall back to the facet.
    let n = if ns.dot(wo) > 0.0 { ns } else { ng };
    (n, ng, outside)
}

/// The unit geometric normal `geometric` turned to `ω_o`'s side, and
/// whether `ω_o` is outside (on the side it points to, or in its plane).
#[inline(always)]
fn facing_facet(geometric: Vec3, wo: Vec3) -> (Vec3, bool) {
    let outside = wo.dot(geometric) >= 0.0;
    (if outside { geometric } else { -geometric }, outside)
}

/// `n·ω_i` where the reflection lobes about `n` carry light from `wi` to
/// `wo` — both above `n`, and with a shading normal (`shaded`) `wi` on
/// `ω_o`'s side of the facet `ng` too (see "Shading normals", no leaks) —
/// else `None`.
#[inline(always)]
pub(crate) fn reflected_cosine(n: Vec3, ng: Vec3, shaded: bool, wo: Vec3, wi: Vec3) -> Option<Real> {
    let (cos_o, cos_i) = (n.dot(wo), n.dot(wi));
    if cos_i <= 0.0 || cos_o <= 0.0 || (shaded && ng.dot(wi) <= 0.0) {
        return None;
    }
    Some(cos_i)
}

/// Chiang, Li and Burley's shadowing term for `ω_i` above a surface whose
/// lobes lie about the shading normal `n`, with geometric normal `ng` (see
/// "Shading normals"): `G = min(1, (n_g·ω_i)/((n·ω_i)(n_g·n)))`,
/// `−G³ + G² + G`; 1 where `G` is not finite.
#[inline]
pub(crate) fn terminator(n: Vec3, ng: Vec3, wi: Vec3) -> f32 {
    let g = to_f32(ng.dot(wi) / (n.dot(wi) * ng.dot(n)));
    let g = if g.is_finite() { g.clamp(0.0, 1.0) } else { 1.0 };
    -g * g * g + g * g + g
}

/// The normal `n` (a normal map's, turned to `ω_o`'s side of the geometric
/// normal `ng`) bent towards `wo` just enough that the mirror reflection of
/// `wo` about it clears the surface (see "Normal maps"); `n` itself where
/// it does already.
fn visible_reflection_normal(ng: Vec3, wo: Vec3, n: Vec3) -> Vec3 {
    let wz = ng.dot(wo);
    let t = (VALID_REFLECTION_SHARE * wz).min(VALID_REFLECTION_MARGIN);
    if (n * (2.0 * n.dot(wo)) - wo).dot(ng) >= t {
        return n;
    }
    // The lean's direction along the surface; n = ng always passes above.
    let Some(x) = normalize_robust(n - ng * n.dot(ng)) else { return ng };
    let wx = x.dot(wo);
    let a = (wz * wz + wx * wx).sqrt();
    if a.is_nan() || a <= 0.0 {
        return ng;
    }
    let phi = (0.5 * (wx.atan2(wz) + (t / a).clamp(-1.0, 1.0).acos())).max(0.0);
    ng * phi.cos() + x * phi.sin()
}

/// The power heuristic with β = 2 for a sample drawn with density `pdf_a`
/// that another strategy could have drawn with density `pdf_b`:
/// `pdf_a²/(pdf_a² + pdf_b²)` (Veach and Guibas, "Optimally Combining
/// Sampling Techniques for Monte Carlo Rendering", 1995). The weights of the
/// two strategies for the same direction sum to 1.
#[inline]
pub fn power_heuristic(pdf_a: Real, pdf_b: Real) -> Real {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 && (a + b).is_finite() {
        a / (a + b)
    } else if pdf_a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::math::real::{narrow, to_f64, widen};
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, SphereGrid};

    fn material(f: impl FnOnce(&mut Material)) -> Material {
        let mut m = Material::flat(Color::new(0.8, 0.5, 0.2));
        f(&mut m);
        m
    }

    /// Materials covering every lobe and mixture.
    fn materials() -> Vec<(&'static str, Material)> {
        vec![
            ("lambert", material(|_| {})),
            ("white lambert", Material::flat(Color::ONE)),
            ("glossy rough", material(|m| m.specular = 0.5)),
            ("glossy sharp", material(|m| (m.specular, m.shininess) = (1.0, 500.0))),
            ("glossy very rough", material(|m| (m.specular, m.shininess) = (1.0, 0.0))),
            ("mirror", material(|m| m.reflectivity = 1.0)),
            ("half mirror", material(|m| (m.reflectivity, m.specular) = (0.5, 0.3))),
            ("glass", material(|m| (m.transparency, m.diffuse) = (1.0, 0.0))),
            ("mixed", material(|m| (m.reflectivity, m.transparency, m.specular) = (0.2, 0.3, 0.4))),
        ]
    }

    /// `∫ f dω` over the unit sphere, by the midpoint rule on a `side × side`
    /// grid in (cos θ, φ) about +y (equal solid angle per cell).
    fn integrate(mut f: impl FnMut(Vec3) -> f64, side: usize) -> f64 {
        let mut sum = 0.0;
        for i in 0..side {
            for j in 0..side {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / side as f64;
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / side as f64;
                let r = (1.0 - y * y).max(0.0).sqrt();
                sum += f(Vec3::new((r * phi.cos()) as Real, y as Real, (r * phi.sin()) as Real));
            }
        }
        sum * 4.0 * std::f64::consts::PI / (side * side) as f64
    }

    #[test]
    fn lambert_is_albedo_over_pi_on_the_viewers_side_only() {
        let m = Material::flat(Color::new(0.5, 0.25, 1.0));
        let b = Bsdf::new(&m, Vec3::Y, Vec3::new(0.0, 1.0, 0.0));
        let f = b.eval(Vec3::Y, Vec3::new(0.6, 0.8, 0.0));
        assert!((f - Color::new(0.5, 0.25, 1.0) / std::f32::consts::PI).abs().max_element() < 1e-7);
        assert_eq!(b.eval(Vec3::Y, Vec3::new(0.6, -0.8, 0.0)), Color::ZERO);
        // Seen from below, it is the lower side that reflects.
        let below = Bsdf::new(&m, Vec3::Y, -Vec3::Y);
        assert_eq!(below.eval(-Vec3::Y, Vec3::new(0.6, -0.8, 0.0)), f);
    }

    /// `∫ f·|cos θ_i| dω_i` over the sphere: the smooth lobes' albedo for
    /// `wo`, by the midpoint rule on `n` cells (all three channels at once).
    fn albedo(b: &Bsdf, wo: Vec3, n: usize) -> Color {
        albedo_f64(b, wo, (n as f64).sqrt() as usize).as_vec3()
    }

    /// [`albedo`] in f64 on a `side × side` grid.
    fn albedo_f64(b: &Bsdf, wo: Vec3, side: usize) -> DVec3 {
        let mut sum = DVec3::ZERO;
        integrate(
            |wi| {
                sum += b.eval(wo, wi).as_dvec3() * to_f64(wi.y.abs());
                0.0
            },
            side,
        );
        sum * 4.0 * std::f64::consts::PI / (side * side) as f64
    }

    #[test]
    fn a_diffuse_and_glossy_mixture_evaluates_to_the_weighted_sum_of_its_lobes() {
        // f = (1 − ks)·kd·color/π + ks·s·D·G₁(ω_o)·G₁(ω_i)/(4·cos θ_o·cos θ_i),
        // worked out here in f64 from the formulas of the module's header
        // (α = √(2/(n + 2)) for the exponent n), at four pairs of directions.
        let m = material(|m| {
            (m.diffuse, m.specular, m.shininess) = (0.7, 0.3, 50.0);
            m.specular_color = Color::new(1.0, 0.9, 0.5);
        });
        let n = Vec3::new(0.2, 1.0, -0.1).normalize();
        let b = Bsdf::new(&m, n, n);
        let alpha = (2.0f64 / 52.0).sqrt();
        let (nn, pi) = (widen(n), std::f64::consts::PI);
        let g1 = |w: DVec3| {
            let c = w.dot(nn);
            let tan2 = (1.0 - c * c) / (c * c);
            2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
        };
        for (wo, wi) in [
            (Vec3::new(0.3, 1.0, 0.2), Vec3::new(-0.3, 1.0, -0.2)),
            (Vec3::new(0.5, 0.6, 0.0), Vec3::new(-0.4, 0.7, 0.1)),
            (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.6, 0.3, -0.5)),
            (Vec3::new(-0.9, 0.4, 0.2), Vec3::new(0.8, 0.5, -0.1)),
        ] {
            let (wo, wi) = (wo.normalize(), wi.normalize());
            let (o, i) = (widen(wo), widen(wi));
            let h = (o + i).normalize();
            let c2 = h.dot(nn).powi(2);
            let d = alpha * alpha / (pi * (c2 * (alpha * alpha - 1.0) + 1.0).powi(2));
            let ggx = d * g1(o) * g1(i) / (4.0 * o.dot(nn) * i.dot(nn));
            let got = b.eval(wo, wi);
            for c in 0..3 {
                let diffuse = 0.7 * 0.7 * to_f64(m.color[c] as Real) / pi;
                let expected = diffuse + 0.3 * to_f64(m.specular_color[c] as Real) * ggx;
                let got = got[c] as f64;
                assert!(
                    (got - expected).abs() <= 1e-5 * expected,
                    "{wo} → {wi}, channel {c}: {got} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn a_glossy_lobe_seen_straight_down_its_normal_samples_finite_directions() {
        // ω_o = n exactly: the visible-normal frame has no azimuth to start
        // from and takes a fixed one; every sample is a finite unit vector.
        let m = material(|m| (m.specular, m.shininess) = (1.0, 30.0));
        let b = Bsdf::new(&m, Vec3::Y, Vec3::Y);
        let mut drawn = 0;
        for k in 0..256u32 {
            let rng = &mut SampleRng::new(k, 2, 8);
            // A microfacet reflection below the surface gives no sample.
            let Some(s) = b.sample(Vec3::Y, rng.next_pair().0, rng.next_pair()) else { continue };
            assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-5 && s.weight.is_finite(), "{s:?}");
            drawn += 1;
        }
        assert!(drawn > 200, "{drawn} of 256");
    }

    #[test]
    fn only_materials_with_a_diffuse_or_glossy_part_have_smooth_lobes() {
        // Light sampling is spent only where a smooth lobe can use it.
        for (name, m) in materials() {
            let smooth = m.diffuse > 0.0 && m.reflectivity + m.transparency < 1.0 || m.specular > 0.0;
            assert_eq!(Bsdf::new(&m, Vec3::Y, Vec3::Y).has_smooth_lobes(), smooth, "{name}");
        }
    }

    #[test]
    fn a_viewer_in_the_tangent_plane_sees_nothing_reflected() {
        // cos θ_o = 0 exactly: no smooth lobe reflects towards it, and no
        // direction has a density, whatever the light's side.
        for (name, m) in materials() {
            let b = Bsdf::new(&m, Vec3::Y, Vec3::X);
            for wi in [Vec3::Y, Vec3::new(0.3, 0.8, 0.1).normalize()] {
                assert_eq!((b.eval(Vec3::X, wi), b.pdf(Vec3::X, wi)), (Color::ZERO, 0.0), "{name}");
            }
        }
    }

    #[test]
    fn a_shading_normal_given_back_to_front_acts_as_the_same_normal() {
        // The shading normal is turned to the geometric normal's side first:
        // −n_s and n_s give the same BSDF.
        let m = material(|m| m.specular = 0.4);
        let (ng, ns) = (Vec3::Y, Vec3::new(0.3, 1.0, 0.0).normalize());
        let wo = Vec3::new(-0.2, 1.0, 0.4).normalize();
        let (a, b) = (Bsdf::shaded(&m, ng, ns, wo), Bsdf::shaded(&m, ng, -ns, wo));
        for wi in [Vec3::new(0.5, 0.7, 0.1), Vec3::new(-0.1, 0.9, -0.6), Vec3::new(0.9, 0.2, 0.0)] {
            let wi = wi.normalize();
            assert_eq!((a.eval(wo, wi), a.pdf(wo, wi)), (b.eval(wo, wi), b.pdf(wo, wi)), "{wi}");
            assert!(a.eval(wo, wi).max_element() > 0.0);
            // Seen from behind the facet, the surface reflects as if both
            // normals had been given facing the viewer.
            let (back, front) = (Bsdf::shaded(&m, ng, ns, -wo), Bsdf::shaded(&m, -ng, -ns, -wo));
            assert_eq!(back.eval(-wo, -wi), front.eval(-wo, -wi), "{wi}");
            assert!(back.eval(-wo, -wi).max_element() > 0.0, "{wi}");
        }
    }

    #[test]
    fn every_lobe_reflects_at_most_what_arrives() {
        for (name, m) in materials() {
            for degrees in [0.0 as Real, 30.0, 60.0, 85.0] {
                let a = degrees.to_radians();
                let wo = Vec3::new(a.sin(), a.cos(), 0.0);
                let b = Bsdf::new(&m, Vec3::Y, wo);
                let smooth = albedo(&b, wo, 1000 * 1000);
                // The δ lobes reflect their weight exactly (the glass's
                // reflection and refraction together at most kt).
                let delta = m.reflectivity + m.transparency;
                let total = smooth.max_element() + delta;
                assert!(total <= 1.0 + 2e-3, "{name} at {degrees}°: albedo {smooth} + {delta}");
            }
        }
    }

    #[test]
    fn with_shading_normals_no_lobe_reflects_more_than_arrives_or_leaks_below_the_facet() {
        // The facet faces +y; shading normals lean up to 60° away from it.
        let mut rng = SampleRng::new(1, 2, 3);
        for (name, m) in materials() {
            for (lean, degrees) in [(20.0 as Real, 30.0 as Real), (60.0, 10.0), (45.0, 70.0)] {
                let l = lean.to_radians();
                let ns = Vec3::new(l.sin(), l.cos(), 0.0);
                let a = degrees.to_radians();
                let wo = Vec3::new(-a.sin(), a.cos(), 0.0);
                let b = Bsdf::shaded(&m, Vec3::Y, ns, wo);
                let side = 600;
                let channel = |k: usize| {
                    integrate(
                        |wi| {
                            let f = b.eval(wo, wi)[k];
                            if wi.y <= 0.0 {
                                assert_eq!(f, 0.0, "{name}: light from below the facet leaks through");
                            }
                            (f * to_f32(b.cosine(wi))) as f64
                        },
                        side,
                    ) as f32
                };
                let smooth = Color::new(channel(0), channel(1), channel(2));
                let total = smooth.max_element() + m.reflectivity + m.transparency;
                assert!(total <= 1.0 + 2e-3, "{name}, lean {lean}°, view {degrees}°: albedo {smooth}");
                // Sampled directions reflect on the viewer's side of the
                // facet and refract to the other.
                for _ in 0..2000 {
                    let (u, _) = rng.next_pair();
                    if let Some(s) = b.sample(wo, u, rng.next_pair()) {
                        let through = s.lobe == Lobe::Transmission;
                        assert!(
                            (s.wi.y < 0.0) == through && s.wi.y != 0.0,
                            "{name}: {:?} to {}",
                            s.lobe,
                            s.wi
                        );
                        assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
                    }
                }
            }
        }
    }

    #[test]
    fn where_the_viewer_is_below_the_shading_normal_the_facet_shades_instead_of_black() {
        let m = Material::flat(Color::ONE);
        // Shading normal leaning 60° to +x, viewer 70° to −x: below it.
        let a = (70.0 as Real).to_radians();
        let wo = Vec3::new(-a.sin(), a.cos(), 0.0);
        let lean = (60.0 as Real).to_radians();
        let ns = Vec3::new(lean.sin(), lean.cos(), 0.0);
        assert!(ns.dot(wo) < 0.0);
        let b = Bsdf::shaded(&m, Vec3::Y, ns, wo);
        assert_eq!(b.normal(), Vec3::Y);
        assert_eq!(b.eval(wo, Vec3::Y), Color::splat(std::f32::consts::FRAC_1_PI));
        // A viewer exactly in the shading normal's tangent plane is not above
        // it either: the facet shades.
        let ns = Vec3::new(1.0, 1.0, 0.0).normalize();
        let wo = Vec3::new(-1.0, 1.0, 0.0).normalize();
        assert_eq!(ns.dot(wo), 0.0);
        assert_eq!(Bsdf::shaded(&m, Vec3::Y, ns, wo).normal(), Vec3::Y);
        // With the normals equal, shaded is the plain BSDF, bit for bit.
        let plain = Bsdf::new(&m, Vec3::Y, wo);
        let same = Bsdf::shaded(&m, Vec3::Y, Vec3::Y, wo);
        let wi = Vec3::new(0.3, 0.9, 0.1).normalize();
        assert_eq!(plain.eval(wo, wi), same.eval(wo, wi));
        assert_eq!(plain.pdf(wo, wi), same.pdf(wo, wi));
    }

    #[test]
    fn the_terminator_term_fades_light_smoothly_where_the_facet_turns_away() {
        // A facet facing +y whose shading normal leans 30° to +x: light
        // grazing the facet from +x is still well above the shading horizon.
        let m = Material::flat(Color::ONE);
        let lean = (30.0 as Real).to_radians();
        let b = Bsdf::shaded(&m, Vec3::Y, Vec3::new(lean.sin(), lean.cos(), 0.0), Vec3::Y);
        let at = |deg: Real| {
            let a = deg.to_radians();
            b.eval(Vec3::Y, Vec3::new(a.cos(), a.sin(), 0.0)).x * std::f32::consts::PI
        };
        // High light: no shadowing. Towards the facet's horizon: falls to 0,
        // monotonically.
        assert_eq!(at(80.0), 1.0);
        let fading: Vec<f32> = [20.0, 10.0, 5.0, 1.0, 0.0].iter().map(|&d| at(d)).collect();
        assert!(fading.windows(2).all(|w| w[1] <= w[0]) && fading[4] == 0.0 && fading[0] > 0.5, "{fading:?}");
    }

    #[test]
    fn a_normal_maps_diffuse_light_fades_by_the_microfacet_bump_shadowing_term() {
        // A flat facet (+y) whose map leans the normal 30° to +x, lit from
        // 75° off +y on that side (15° above the horizon), seen from above:
        // the Lambert value is 1/π times Conty Estevez et al.'s G₁ for
        // α² = tan²30°/8 at θ_i = 75° (0.886), not Chiang et al.'s
        // −g³ + g² + g for g = cos 75°/(cos 45°·cos 30°) (0.578), which
        // darkened the lit flanks of bumps.
        let m = Material::flat(Color::ONE);
        let (n, wi, wo) = (at(30.0), at(75.0), Vec3::Y);
        let b = Bsdf::mapped(&m, Vec3::Y, Vec3::Y, n, wo);
        assert_eq!(b.normal(), n, "the viewer sees the reflection: no bend");
        let alpha2 = to_f64(0.125 * (1.0 / (n.y * n.y) - 1.0));
        let tan2 = to_f64(1.0 / (wi.y * wi.y) - 1.0);
        let g1 = 2.0 / (1.0 + (1.0 + alpha2 * tan2).sqrt());
        let got = f64::from(b.eval(wo, wi).x) * std::f64::consts::PI;
        assert!((got - g1).abs() < 1e-5 && (g1 - 0.886).abs() < 1e-3, "{got} {g1}");
        // Without a map nothing fades; below the facet nothing arrives.
        let flat = Bsdf::mapped(&m, Vec3::Y, Vec3::Y, Vec3::Y, wo).eval(wo, wi).x * std::f32::consts::PI;
        assert!((flat - 1.0).abs() < 1e-6, "{flat}");
        assert_eq!(b.eval(wo, at(95.0)), Color::ZERO);
    }

    #[test]
    fn a_mapped_normal_leaning_away_from_the_viewer_is_bent_for_a_visible_reflection() {
        // The map leans the normal 60° to +x; the viewer is 60° off +y on
        // the other side, behind the mapped normal (ω_o·n = cos 120°).
        let m = Material::flat(Color::ONE);
        let (n, wo) = (at(60.0), at(-60.0));
        let b = Bsdf::mapped(&m, Vec3::Y, Vec3::Y, n, wo);
        let bent = b.normal();
        let r = bent * (2.0 * bent.dot(wo)) - wo;
        let margin = (VALID_REFLECTION_SHARE * wo.y).min(VALID_REFLECTION_MARGIN);
        assert!(bent.dot(wo) > 0.0 && (r.y - margin).abs() < 1e-5, "{bent}: reflection {r}");
        // The diffuse base still lies about the map's normal: light along
        // it arrives with its full cosine, one from the far side of it
        // (above the facet) with none.
        let along = at(60.0);
        let value = b.eval(wo, along) * to_f32(b.cosine(along));
        let term = 2.0 / (1.0 + (1.0 + 0.125 * 3.0 * 3.0_f32).sqrt());
        assert!((value.x * std::f32::consts::PI - term).abs() < 1e-4, "{value} vs {term}");
        assert_eq!(b.eval(wo, at(-40.0)), Color::ZERO);
        // The shading-normal rules without a map keep the facet fallback.
        assert_eq!(Bsdf::shaded(&m, Vec3::Y, n, wo).normal(), Vec3::Y);
    }

    #[test]
    fn a_white_lambert_surface_reflects_everything() {
        let m = Material::flat(Color::ONE);
        let wo = Vec3::new(0.3, 0.9, 0.1).normalize();
        let a = albedo(&Bsdf::new(&m, Vec3::Y, wo), wo, 400 * 400);
        assert!((a - Color::ONE).abs().max_element() < 1e-3, "{a}");
    }

    #[test]
    fn sampled_weights_are_value_times_cosine_over_density_and_average_to_the_albedo() {
        for (name, m) in materials() {
            for degrees in [10.0 as Real, 45.0, 80.0] {
                let a = degrees.to_radians();
                let wo = Vec3::new(a.sin(), a.cos(), 0.0);
                let b = Bsdf::new(&m, Vec3::Y, wo);
                let mut rng = SampleRng::new(1, 2, 3);
                let n = 200_000;
                let (mut sum, mut squares) = (DVec3::ZERO, DVec3::ZERO);
                for _ in 0..n {
                    let (u, _) = rng.next_pair();
                    let Some(s) = b.sample(wo, u, rng.next_pair()) else { continue };
                    assert!((s.wi.length() - 1.0).abs() < 1e-4, "{name}: |wi| = {}", s.wi.length());
                    assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "{name}: {}", s.weight);
                    if !s.lobe.is_delta() {
                        // The weight is exactly what eval and pdf say.
                        let expected = b.eval(wo, s.wi) * to_f32(s.wi.y.abs() / b.pdf(wo, s.wi));
                        let error = (s.weight - expected).abs().max_element();
                        assert!(error <= 1e-4 * expected.max_element().max(1.0), "{name}: {s:?}");
                        assert_eq!(s.pdf, b.pdf(wo, s.wi));
                    }
                    let w = s.weight.as_dvec3();
                    sum += w;
                    squares += w * w;
                }
                // Estimator: the mean weight over n = 2·10⁵ draws (a draw
                // that gives nothing weighs 0), with standard error
                // σ = √(sample variance/n), measured per channel.
                let mean = sum / n as f64;
                let sigma = ((squares / n as f64 - mean * mean).max(DVec3::ZERO) / n as f64).powf(0.5);
                // Independent reference: ∫ f·|cos| dω over the sphere by the
                // midpoint rule on 1000² cells (never calling `sample` or
                // `pdf`); its error falls as 1/side², so the difference from
                // the 500² rule (3× the finer one's error) bounds it. Plus
                // the δ lobes' albedo by hand: kr, and kt split by Fresnel
                // into F and (1 − F)·color/η².
                let fine = albedo_f64(&b, wo, 1000);
                let quadrature_error = (fine - albedo_f64(&b, wo, 500)).abs();
                let (eta_i, eta_t) = (1.0, to_f64(m.ior as Real));
                let fresnel = to_f64(fresnel_dielectric(wo.y, eta_i as Real, eta_t as Real));
                let delta = DVec3::splat((m.reflectivity as f64) + m.transparency as f64 * fresnel)
                    + m.color.as_dvec3() * (m.transparency as f64 * (1.0 - fresnel) / (eta_t * eta_t));
                let expected = fine + delta;
                // Bound: 5σ (two-sided 6·10⁻⁷ per channel), the quadrature
                // error, and 10⁻⁵ for the f32 rounding of weights and colours.
                let bound = 5.0 * sigma + quadrature_error + DVec3::splat(1e-5);
                assert!(
                    (mean - expected).abs().cmple(bound).all(),
                    "{name} at {degrees}°: sampled {mean} ± {sigma}, integrated {expected} ± {quadrature_error}"
                );
            }
        }
    }

    /// The χ² test of [`Bsdf::sample`] for `wo` against [`Bsdf::pdf`]:
    /// `samples` draws binned on a 20 × 40 equal-area grid of the sphere
    /// about the geometric normal `ng` (so the two hemispheres meet on a bin
    /// edge), the δ lobes as discrete outcomes with the probability each
    /// sample's `pdf` field claims, and "no sample" as the rest.
    fn assert_samples_follow_the_pdf(name: &str, b: &Bsdf, wo: Vec3, samples: usize) {
        let grid = SphereGrid::sphere(widen(b.ng), 20, 40);
        let draw = |rng: &mut SampleRng| {
            let (u, _) = rng.next_pair();
            match b.sample(wo, u, rng.next_pair()) {
                None => Draw::Nothing,
                Some(s) if s.lobe.is_delta() => Draw::Delta(s.lobe as usize, to_f64(s.pdf)),
                Some(s) => Draw::At(widen(s.wi)),
            }
        };
        chi_square::directions(name, &grid, samples, draw, &|wi| to_f64(b.pdf(wo, narrow(wi))));
    }

    /// A unit direction at `degrees` from +y, towards +x.
    fn at(degrees: Real) -> Vec3 {
        let a = degrees.to_radians();
        Vec3::new(a.sin(), a.cos(), 0.0)
    }

    #[test]
    fn the_lambert_lobe_samples_directions_with_the_cosine_density_pdf_reports() {
        // 2·10⁵ draws per view, χ² at α ≈ 10⁻⁴ (see `chi_square`).
        let m = Material::flat(Color::ONE);
        // From above, and from below (where the lower side reflects).
        for (side, wo) in [("above", at(0.0)), ("below", -at(70.0))] {
            assert_samples_follow_the_pdf(
                &format!("lambert from {side}"),
                &Bsdf::new(&m, Vec3::Y, wo),
                wo,
                200_000,
            );
        }
    }

    #[test]
    fn the_glossy_lobe_samples_directions_with_the_density_pdf_reports() {
        // GGX alone at α = 1, 0.5, 0.2 and 0.05 (shininess 0, 6, 48, 798),
        // seen from near the normal, obliquely and at grazing (85°); 2·10⁵
        // draws each, χ² at α ≈ 10⁻⁴.
        for shininess in [0.0, 6.0, 48.0, 798.0] {
            let m = material(|m| (m.specular, m.shininess) = (1.0, shininess));
            for degrees in [5.0, 50.0, 85.0] {
                let wo = at(degrees);
                let b = Bsdf::new(&m, Vec3::Y, wo);
                let name = format!("GGX α = {} at {degrees}°", m.roughness());
                assert_samples_follow_the_pdf(&name, &b, wo, 200_000);
            }
        }
    }

    #[test]
    fn mixtures_sample_each_lobe_with_the_probability_and_density_they_report() {
        // Diffuse + glossy; a half mirror; every lobe at once; glass from
        // outside and inside (past the critical angle: all reflection).
        // The δ lobes' frequencies are tested against the probabilities
        // their samples report, with the smooth density and "nothing", in
        // one χ² per case (2·10⁵ draws, α ≈ 10⁻⁴).
        let cases = [
            ("diffuse + glossy", material(|m| (m.specular, m.shininess) = (0.5, 20.0)), Vec3::Y, 30.0),
            ("half mirror", material(|m| (m.reflectivity, m.specular) = (0.5, 0.3)), Vec3::Y, 60.0),
            (
                "every lobe",
                material(|m| (m.reflectivity, m.transparency, m.specular) = (0.2, 0.3, 0.4)),
                Vec3::Y,
                45.0,
            ),
            ("glass, outside", material(|m| (m.transparency, m.diffuse) = (1.0, 0.0)), Vec3::Y, 75.0),
            ("glass, inside", material(|m| (m.transparency, m.diffuse) = (1.0, 0.0)), -Vec3::Y, 40.0),
        ];
        for (name, m, normal, degrees) in cases {
            let wo = at(degrees);
            assert_samples_follow_the_pdf(name, &Bsdf::new(&m, normal, wo), wo, 200_000);
        }
    }

    #[test]
    fn with_a_shading_normal_samples_follow_the_density_pdf_reports() {
        // The facet faces +y; shading normals lean 20°–45° away from it, so
        // some of the lobes about n_s fall below the facet (refused by both
        // `sample` and `pdf`); the viewer on either side of the lean.
        // 2·10⁵ draws each, χ² at α ≈ 10⁻⁴.
        let cases = [
            ("lambert", Material::flat(Color::ONE), 20.0, -30.0),
            ("glossy", material(|m| (m.specular, m.shininess) = (1.0, 20.0)), 45.0, 60.0),
            ("diffuse + glossy", material(|m| (m.specular, m.shininess) = (0.5, 100.0)), 30.0, -70.0),
        ];
        for (name, m, lean, degrees) in cases {
            let wo = at(degrees);
            let b = Bsdf::shaded(&m, Vec3::Y, at(lean), wo);
            assert_samples_follow_the_pdf(&format!("{name}, lean {lean}°, view {degrees}°"), &b, wo, 200_000);
        }
    }

    #[test]
    fn the_smooth_density_integrates_to_how_often_sampling_gives_a_smooth_direction() {
        // If `pdf` is the density `sample` draws smooth directions with, its
        // integral is the fraction of samples that are smooth (microfacet
        // normals that would reflect below the surface give none).
        for (name, m) in materials() {
            let wo = Vec3::new(0.5, 0.8, 0.2).normalize();
            let b = Bsdf::new(&m, Vec3::Y, wo);
            let integral = integrate(|wi| to_f64(b.pdf(wo, wi)), 1000);
            let mut rng = SampleRng::new(9, 9, 9);
            let n = 200_000;
            let smooth = (0..n)
                .filter(|_| {
                    let (u, _) = rng.next_pair();
                    b.sample(wo, u, rng.next_pair()).is_some_and(|s| !s.lobe.is_delta())
                })
                .count() as f64
                / n as f64;
            assert!((integral - smooth).abs() < 0.01, "{name}: ∫pdf = {integral}, smooth fraction {smooth}");
        }
    }

    #[test]
    fn glass_reflects_fresnel_and_refracts_the_rest_scaled_by_eta_squared() {
        let m = material(|m| (m.transparency, m.diffuse, m.color) = (1.0, 0.0, Color::ONE));
        let wo = Vec3::Y;
        let b = Bsdf::new(&m, Vec3::Y, wo);
        let r = b.sample(wo, 0.01, (0.5, 0.5)).unwrap();
        assert_eq!((r.lobe, r.wi), (Lobe::Reflection, Vec3::Y));
        assert!((r.pdf - 0.04).abs() < 1e-6, "F at normal incidence: {}", r.pdf);
        let t = b.sample(wo, 0.5, (0.5, 0.5)).unwrap();
        assert_eq!(t.lobe, Lobe::Transmission);
        assert!((t.wi + Vec3::Y).length() < 1e-6);
        assert!((t.weight.x - 1.0 / 2.25).abs() < 1e-6, "1/1.5²: {}", t.weight);
        // The sample names the index it passed into, whose 1/η² its weight
        // carries; a reflection crosses nothing.
        assert_eq!((t.eta, r.eta), (1.5, 1.0));
        // From inside the factor is inverted: entering and leaving cancel.
        let inside = Bsdf::new(&m, Vec3::Y, -Vec3::Y);
        let t = inside.sample(-Vec3::Y, 0.5, (0.5, 0.5)).unwrap();
        assert!((t.weight.x - 2.25).abs() < 1e-5, "{}", t.weight);
        assert_eq!(t.eta, 1.0 / 1.5);
    }

    #[test]
    fn power_heuristic_weights_of_two_strategies_sum_to_one() {
        let mut rng = SampleRng::new(4, 5, 6);
        for _ in 0..1000 {
            let (a, b) = rng.next_pair();
            let (a, b) = (a * 10.0, b * 0.1);
            let sum = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((sum - 1.0).abs() < 1e-6 || (a == 0.0 && b == 0.0), "{a} {b}: {sum}");
        }
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(Real::INFINITY, 3.0), 1.0);
    }
}
