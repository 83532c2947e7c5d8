//! Random walks through a translucent object's medium: where light that
//! enters a translucent object comes out again (the path tracer's step 6,
//! [`crate::integrators::path_tracer`]). The medium itself (free flights, the phase
//! function, the hero channel's spectral weights) is [`crate::materials::medium`]; this
//! module moves a walk through the scene's geometry.

use crate::explain::record::{Event, SegmentKind};
use crate::explain::recorder::Recorder;
use crate::geometry::hit::Hit;
use crate::geometry::surface::SurfacePoint;
use crate::materials::bsdf::Bsdf;
use crate::materials::material::Material;
use crate::materials::medium::{Subsurface, WalkWeight, sample_henyey_greenstein};
use crate::math::color::Color;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, gamma, to_f32};
use crate::sampling::sampler::Sampler;
use crate::scene::Scene;
use crate::scene::effects::{GlobalIllumination, RayCounts};

/// How a random walk through a translucent object ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum WalkEnd {
    /// Absorbed, ended by Russian roulette, or stopped at the step cap.
    Ended,
    /// Out of the object along `ray`, which hits `hit`, with the walk's
    /// throughput `weight`: through its boundary, or onto another object's
    /// surface inside it.
    Out { ray: Ray, hit: Option<Hit>, weight: Color },
    /// A walk ray that hit nothing, or met its object's surface from
    /// outside: it slipped out of the object without crossing its surface,
    /// which a closed object never lets happen (tested); the path goes on
    /// along it.
    Escaped { ray: Ray, weight: Color },
}

/// Walks through the translucent objects of one scene.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RandomWalk<'s> {
    scene: &'s Scene,
    /// The step cap and whether Russian roulette may end a walk.
    settings: GlobalIllumination,
}

impl<'s> RandomWalk<'s> {
    /// Walks in `scene` with the global-illumination `settings`.
    pub(crate) fn new(scene: &'s Scene, settings: GlobalIllumination) -> Self {
        Self { scene, settings }
    }

    /// A random walk through the medium of `object` ([`crate::materials::medium`]),
    /// from the entry point `entry` along the refracted direction `w`, for a
    /// path of throughput `beta` so far (for Russian roulette):
    ///
    /// 1. A free-flight distance t is drawn with the walk's hero channel
    ///    (spectral MIS over the whole walk, [`WalkWeight`]) and a ray cast
    ///    along the walk (a `subsurface` ray).
    /// 2. If the object's surface comes first, the walk meets its boundary
    ///    from inside: the dielectric reflects it back in (Fresnel) or lets it
    ///    out, and then the walk is over: the path goes on from there as a
    ///    *bounce* ray. Index-matched boundaries (ior 1) always let it out.
    /// 3. Else it scatters at t: the throughput takes the scattering weight,
    ///    a new direction is drawn from the phase function (weight 1), and
    ///    Russian roulette may end it as in the path loop (step 5).
    ///
    /// No light is sampled from inside: a smooth dielectric boundary lets no
    /// shadow ray through, and index-matched objects rely on the walk finding
    /// its way out, which is unbiased too (Mitsuba's `volpath` also samples
    /// lights from inside index-matched media, which lowers noise, not the
    /// mean). A surface of another object met inside ends the walk there: a
    /// translucent object's inside is not meant to hold others.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn walk<R: Recorder>(
        &self,
        object: usize,
        medium: &Subsurface,
        boundary: &Material,
        entry: &SurfacePoint,
        w: Vec3,
        beta: Color,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> WalkEnd {
        let scene = self.scene;
        let g = medium.anisotropy as Real;
        let mut spectral = WalkWeight::new(sampler.get_1d());
        let mut ray = Ray::new(entry.spawn_origin(w), w);
        let mut steps = 0;
        loop {
            counts.subsurface += 1;
            let mut hit = scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY));
            // A point of the walk right at the surface may be computed on it
            // or a rounding error outside it: a scattering point next to the
            // surface, or a reflection's origin moved off one face but left
            // on the next at an edge, far from the origin. Put it back inside
            // (at an edge or a corner, one face at a time).
            for _ in 0..3 {
                if hit.is_some_and(|h| h.object == object && ray.dir.dot(h.normal) > 0.0) {
                    break;
                }
                let Some(back) = self.back_inside(object, &ray) else { break };
                ray = back;
                hit = scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY));
            }
            if R::ACTIVE {
                rec.ray(SegmentKind::WalkStep, &ray, hit.as_ref(), Some(beta * spectral.weight()));
            }
            let t = spectral.sample_distance(medium, sampler.get_1d());
            match hit {
                None => return WalkEnd::Escaped { ray, weight: spectral.weight() },
                Some(h) if t >= h.t => {
                    spectral.pass(medium, h.t);
                    if h.object != object {
                        return WalkEnd::Out { ray, hit: Some(h), weight: spectral.weight() };
                    }
                    let o = &scene.objects()[object];
                    let sp = o.primitive.surface_point(h.primitive, h.normal, ray.at(h.t));
                    if ray.dir.dot(sp.normal) < 0.0 {
                        // The walk meets its object's surface from outside:
                        // it had slipped out.
                        return WalkEnd::Escaped { ray, weight: spectral.weight() };
                    }
                    let wo = -ray.dir;
                    let bsdf = Bsdf::new(boundary, sp.normal, wo);
                    let u = sampler.get_1d();
                    let Some(s) = bsdf.sample(wo, u, sampler.get_2d()) else { return WalkEnd::Ended };
                    spectral.scale(s.weight);
                    if s.wi.dot(sp.normal) > 0.0 {
                        counts.bounce += 1;
                        let out = Ray::new(sp.spawn_origin(s.wi), s.wi);
                        let hit = scene.closest_hit(&out, Interval::new(0.0, Real::INFINITY));
                        if R::ACTIVE {
                            rec.ray(
                                SegmentKind::WalkExit,
                                &out,
                                hit.as_ref(),
                                Some(beta * spectral.weight()),
                            );
                        }
                        return WalkEnd::Out { ray: out, hit, weight: spectral.weight() };
                    }
                    ray = Ray::new(sp.spawn_origin(s.wi), s.wi);
                }
                Some(h) => {
                    steps += 1;
                    counts.walk_steps += 1;
                    if steps > self.settings.max_walk_steps {
                        return WalkEnd::Ended;
                    }
                    spectral.scatter(medium, t);
                    let weight = spectral.weight();
                    if weight.max_element() <= 0.0 || !weight.is_finite() {
                        return WalkEnd::Ended;
                    }
                    if self.settings.russian_roulette {
                        let survive = (beta * weight).max_element();
                        if survive < 1.0 {
                            let u = sampler.get_1d();
                            let survived = to_f32(u) < survive;
                            rec.event(|| Event::Roulette { survive: survive as Real, survived });
                            if to_f32(u) >= survive {
                                return WalkEnd::Ended;
                            }
                            spectral.scale(Color::splat(1.0 / survive));
                        }
                    }
                    // The scattering point, computed, is off the exact one by
                    // up to γ₂·(|o| + t); one that close to the surface ahead
                    // might land outside it, and the next ray would miss the
                    // object. It is kept 4γ₃·(|o|∞ + t_surface) inside (a few
                    // ulps of the coordinates: no measurable bias).
                    let margin = 4.0 * gamma(3) * (ray.origin.abs().max_element() + h.t);
                    let t = if h.t - t < margin { (h.t - margin).max(0.0) } else { t };
                    let at = ray.at(t);
                    rec.event(|| Event::WalkScatter { point: at, weight: spectral.weight() });
                    ray = Ray::new(at, sample_henyey_greenstein(ray.dir, g, sampler.get_2d()));
                }
            }
        }
    }

    /// For a walk ray that did not find its object's surface from inside:
    /// if its origin lies on or outside the surface by no more than rounding,
    /// the same ray from just inside the surface there. The surface is
    /// looked for within `r` = 16γ₃ of the coordinates' magnitude, on either
    /// side of the point, along the ray and along each axis; every face found
    /// that the point is not clearly inside of (by more than `r`) moves it to
    /// just inside that face, so a point at an edge or a corner gets inside
    /// all of its faces. `None` if no face is that near (a real leak, which
    /// the walk reports as [`WalkEnd::Escaped`]).
    fn back_inside(&self, object: usize, ray: &Ray) -> Option<Ray> {
        let scene = self.scene;
        let reach = 16.0 * gamma(3) * ray.origin.abs().max_element().max(1.0);
        let o = &scene.objects()[object];
        let mut p = ray.origin;
        let mut moved = false;
        for dir in [ray.dir, Vec3::X, Vec3::Y, Vec3::Z] {
            let probe = Ray::new(p, dir);
            let Some(h) = o.primitive.intersect_with(&probe, Interval::new(-reach, reach), scene.methods())
            else {
                continue;
            };
            let sp = o.primitive.surface_point(h.primitive, h.normal, probe.at(h.t));
            if (p - sp.p).dot(sp.normal) > -reach {
                // Just inside, against the outward normal.
                p = sp.spawn_origin(-sp.normal);
                moved = true;
            }
        }
        moved.then(|| Ray::new(p, ray.dir))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_walk_never_slips_out_of_a_closed_object_between_its_faces() {
        // Walks inside a closed mesh, a box and a sphere, near the origin and
        // 10⁴ units from it: every walk ray meets the object's surface (none
        // escapes between triangles, however far from the origin).
        let (corners, faces) = crate::geometry::mesh::icosahedron();
        let dir = tempfile::tempdir().unwrap();
        let mut obj = String::new();
        for c in corners {
            obj += &format!("v {} {} {}\n", c[0], c[1], c[2]);
        }
        for f in faces {
            obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
        }
        std::fs::write(dir.path().join("ico.obj"), obj).unwrap();
        for offset in [0.0 as Real, 1e4] {
            for object in [
                format!(
                    "Mesh(file: \"ico.obj\", scale: 0.5, translate: ({offset}, 0, {offset}), material: \"m\")"
                ),
                format!(
                    "Aabb(min: ({a}, -1, {a}), max: ({b}, 1, {b}), material: \"m\")",
                    a = offset - 1.0,
                    b = offset + 1.0
                ),
                format!("Sphere(center: ({offset}, 0, {offset}), radius: 1, material: \"m\")"),
            ] {
                let text = format!(
                    r#"(
                    camera: (position: (0, 0, -4), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 30, near: 1),
                    image: (width: 4, height: 4),
                    materials: {{ "m": (color: (1, 1, 1), ior: 1.3, subsurface: (albedo: (1, 1, 1), mean_free_path: (0.05, 0.1, 0.2))) }},
                    objects: [ {object} ],
                    effects: (global_illumination: ()),
                )"#
                );
                let s = crate::parse_scene(&text, "walk.ron", dir.path()).unwrap();
                let walk = RandomWalk::new(&s.scene, s.settings.effects.global_illumination.unwrap());
                let o = &s.scene.objects()[0];
                let m = s.scene.material(o.material);
                let centre = Vec3::new(offset, 0.0, offset);
                let mut counts = RayCounts::default();
                let mut outcomes = [0u32; 3];
                for k in 0..4000u32 {
                    let sampler = &mut Sampler::new(1, 0);
                    sampler.start_pixel_sample(k, 1, 2);
                    // Enter at a random point of the surface, straight inwards.
                    let d = crate::sampling::sampler::uniform_sphere(sampler.get_2d());
                    let ray = Ray::new(centre + d * 10.0, -d);
                    let h = s.scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY)).unwrap();
                    let sp = o.primitive.surface_point(h.primitive, h.normal, ray.at(h.t));
                    let end = walk.walk(
                        0,
                        &m.subsurface.unwrap(),
                        &m.boundary(),
                        &sp,
                        -d,
                        Color::ONE,
                        sampler,
                        &mut counts,
                        &mut crate::explain::recorder::NoRecorder,
                    );
                    outcomes[match end {
                        WalkEnd::Ended => 0,
                        WalkEnd::Out { .. } => 1,
                        WalkEnd::Escaped { .. } => 2,
                    }] += 1;
                }
                assert_eq!(outcomes[2], 0, "{object}: {outcomes:?}");
                assert!(outcomes[1] > 3800, "{object}: {outcomes:?}");
            }
        }
    }
}
