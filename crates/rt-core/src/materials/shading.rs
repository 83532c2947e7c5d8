//! The optics of smooth surfaces: mirror reflection, Snell's law and the
//! Fresnel equations. Pure functions of unit vectors, used by the BSDFs
//! ([`crate::materials::bsdf`]) and the direct-lighting tracer.
//!
//! Conventions: `n` is a unit normal on the side the light or viewer is on
//! (face-forwarded), `l` points from the surface to the light, `v` from the
//! surface to the viewer, `d` is a direction of travel (towards the surface).

use crate::math::real::{Real, Vec3};

/// `d` mirrored about the plane with normal `n`: `d − 2(d·n)n`. Either side
/// of `n` gives the same result.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// The refracted direction for unit `d` arriving at a surface with unit
/// normal `n` facing against it (`d·n < 0`), from a medium of index `eta_i`
/// into one of index `eta_t`, by Snell's law `ηᵢ sin θᵢ = ηₜ sin θₜ`:
/// `t = η·d + (η·cos θᵢ − cos θₜ)·n` with `η = ηᵢ/ηₜ`. `None` on total
/// internal reflection (`sin θₜ > 1`).
pub fn refract(d: Vec3, n: Vec3, eta_i: Real, eta_t: Real) -> Option<Vec3> {
    let eta = eta_i / eta_t;
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize_or(d))
}

/// The Fresnel reflectance of unpolarised light at a smooth dielectric
/// boundary, exact: the mean of the s- and p-polarised reflectances
/// `r_s = (ηᵢcos θᵢ − ηₜcos θₜ)/(ηᵢcos θᵢ + ηₜcos θₜ)`,
/// `r_p = (ηₜcos θᵢ − ηᵢcos θₜ)/(ηₜcos θᵢ + ηᵢcos θₜ)`, squared
/// (Hecht, *Optics*, §4.6; pbrt-v4 §9.3 `FrDielectric`). `cos_i` ∈ [0, 1] is
/// the cosine of the angle of incidence; 1 on total internal reflection.
pub fn fresnel_dielectric(cos_i: Real, eta_i: Real, eta_t: Real) -> Real {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t = eta_i / eta_t * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let r_s = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let r_p = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Real, b: Real, tolerance: Real) -> bool {
        (a - b).abs() <= tolerance
    }

    #[test]
    fn reflection_mirrors_about_the_normal() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        assert!((reflect(d, Vec3::Y) - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        assert_eq!(reflect(d, Vec3::Y), reflect(d, -Vec3::Y));
    }

    #[test]
    fn fresnel_at_normal_incidence_is_the_textbook_value_and_grazing_reflects_all() {
        // ((1 − 1.5)/(1 + 1.5))² = 0.04 for glass in air.
        assert!(close(fresnel_dielectric(1.0, 1.0, 1.5), 0.04, 1e-6));
        assert!(close(fresnel_dielectric(1.0, 1.5, 1.0), 0.04, 1e-6), "the same from inside");
        assert!(fresnel_dielectric(1e-4, 1.0, 1.5) > 0.999);
        assert_eq!(fresnel_dielectric(0.0, 1.0, 1.5), 1.0);
        // Brewster's angle, tan θ = 1.5: only s-polarised light reflects, so F = r_s²/2.
        let brewster = (1.5 as Real).atan();
        let f = fresnel_dielectric(brewster.cos(), 1.0, 1.5);
        let cos_t = (1.0 - (brewster.sin() / 1.5).powi(2)).sqrt();
        let r_s = (brewster.cos() - 1.5 * cos_t) / (brewster.cos() + 1.5 * cos_t);
        assert!(close(f, 0.5 * r_s * r_s, 1e-6));
    }

    #[test]
    fn refraction_obeys_snells_law() {
        let n = Vec3::Y;
        for degrees in [0.0 as Real, 20.0, 45.0, 80.0] {
            let a = degrees.to_radians();
            let d = Vec3::new(a.sin(), -a.cos(), 0.0);
            let t = refract(d, n, 1.0, 1.5).unwrap();
            assert!(close(t.length(), 1.0, 1e-6));
            assert!(close(a.sin(), 1.5 * t.x, 1e-6), "{degrees}°: sin θᵢ = 1.5 sin θₜ");
            assert!(t.y < 0.0 && t.z == 0.0, "goes on through, in the plane of incidence");
        }
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let n = Vec3::Y;
        let critical = (1.0 as Real / 1.5).asin();
        let ray = |a: Real| Vec3::new(a.sin(), -a.cos(), 0.0);
        assert!(refract(ray(critical - 0.01), n, 1.5, 1.0).is_some());
        assert_eq!(refract(ray(critical + 0.01), n, 1.5, 1.0), None);
        assert_eq!(fresnel_dielectric((critical + 0.01).cos(), 1.5, 1.0), 1.0);
    }
}
