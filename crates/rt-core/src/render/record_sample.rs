//! One pixel sample computed with a recorder: the renderer's own sample
//! ([`Renderer::sample`]), and the record of everything it computed
//! ([`crate::explain`]).

use crate::explain::path_recorder::PathRecorder;
use crate::explain::record::{CameraRecord, IntegratorKind, PathRecord, ViewPlaneRecord};
use crate::integrators::Integrator;
use crate::render::Renderer;
use crate::scene::effects::RayCounts;

impl Renderer<'_> {
    /// Sample `k` of pixel (x, y), computed as [`Renderer::sample`] computes
    /// it (the same primary ray, hit, random numbers and integrator: its
    /// [`PathRecord::value`] is that sample's colour bit for bit), with the
    /// record of its light path. `None` if the pixel is outside the image
    /// or `k` is not below the samples per pixel.
    pub fn record_sample(&self, x: u32, y: u32, k: u32) -> Option<PathRecord> {
        if x >= self.view.width() || y >= self.view.height() || k >= self.spp {
            return None;
        }
        let film = self.sampler.film_position(x, y, k);
        let lens = if self.view.has_lens() { self.sampler.lens_position(x, y, k) } else { (0.5, 0.5) };
        let mut sampler = self.sampler;
        let ray = self.primary_ray(&mut sampler, x, y, k);
        let hit = self.scene.cast(&ray);
        sampler.start_pixel_sample(x, y, k);
        let mut rec = PathRecorder::new(self.scene);
        let value =
            self.integrator.radiance_recorded(&ray, hit, &mut sampler, &mut RayCounts::default(), &mut rec);
        let integrator = match &self.integrator {
            Integrator::Direct(tracer) if !tracer.plan().shading => IntegratorKind::Flat,
            Integrator::Direct(_) => IntegratorKind::Direct,
            Integrator::Path(_) => IntegratorKind::Path,
        };
        Some(PathRecord {
            pixel: [x, y],
            sample: k,
            samples_per_pixel: self.spp,
            seed: self.sampler.seed(),
            integrator,
            camera: CameraRecord::of(&self.view),
            view_plane: ViewPlaneRecord::of(&self.view),
            film: [film.0, film.1],
            lens: [lens.0, lens.1],
            pixel_point: self.view.point(x, y, film.0, film.1),
            segments: rec.segments,
            contributions: rec.contributions,
            value,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::explain::record::{ContributionKind, IntegratorKind, PathRecord, SegmentKind};
    use crate::math::color::Color;
    use crate::math::real::{Real, Vec3};
    use crate::render::Renderer;
    use crate::scene::effects::RayCounts;

    /// A scene of the repository's `scenes/` folder, rendered `w`×`h` at
    /// `spp` samples per pixel.
    fn scene(name: &str, w: u32, h: u32, spp: u32) -> crate::LoadedScene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name);
        let mut loaded = crate::load_scene(&path).unwrap();
        loaded.settings = loaded.settings.overridden(Some(w), Some(h), Some(spp)).unwrap();
        loaded
    }

    /// The sample's value rebuilt from its record alone, by the rule of its
    /// integrator (`explain::record`): the same f32 additions in the same
    /// order as the renderer's.
    fn rebuilt(r: &PathRecord) -> Color {
        match r.integrator {
            IntegratorKind::Path => r.contributions.iter().fold(Color::ZERO, |sum, c| sum + c.value),
            IntegratorKind::Direct | IntegratorKind::Flat => {
                for (i, s) in r.segments.iter().enumerate() {
                    let sum = r
                        .contributions
                        .iter()
                        .filter(|c| c.segment == i)
                        .fold(Color::ZERO, |sum, c| sum + c.value);
                    match s.radiance {
                        Some(radiance) => assert_eq!(sum, radiance, "segment {i} of {:?}", r.pixel),
                        None => assert_eq!(sum, Color::ZERO, "segment {i} of {:?}", r.pixel),
                    }
                }
                for c in &r.contributions {
                    if let ContributionKind::Reflection { child } | ContributionKind::Refraction { child } =
                        c.kind
                    {
                        let s = &r.segments[child];
                        assert_eq!(c.value, s.weight.unwrap() * s.radiance.unwrap());
                        assert_eq!(s.parent, Some(c.segment));
                    }
                }
                r.segments[0].radiance.unwrap()
            }
        }
    }

    /// Every pixel's recorded sample against the same sample of a whole
    /// render at 1 spp (and `k` of `spp` against [`Renderer::sample`]):
    /// value and rebuilt value bit for bit. Returns the records.
    fn check_scene(name: &str, w: u32, h: u32, spp: u32) -> Vec<PathRecord> {
        let s = scene(name, w, h, spp);
        let r = Renderer::new(&s.scene, s.camera, &s.settings).unwrap();
        let frame = (spp == 1).then(|| r.render(|_| {}));
        let mut records = Vec::new();
        for y in 0..h {
            for x in 0..w {
                for k in 0..spp {
                    let rec = r.record_sample(x, y, k).unwrap();
                    let sample = r.sample(x, y, k, &mut RayCounts::default());
                    assert_eq!(rec.value.to_array().map(f32::to_bits), sample.to_array().map(f32::to_bits));
                    if let Some(f) = &frame {
                        assert_eq!(rec.value, f.pixels[(y * w + x) as usize], "{name} ({x}, {y})");
                    }
                    let again = rebuilt(&rec);
                    assert_eq!(
                        again.to_array().map(f32::to_bits),
                        rec.value.to_array().map(f32::to_bits),
                        "{name} ({x}, {y}) #{k}"
                    );
                    records.push(rec);
                }
            }
        }
        records
    }

    fn count(records: &[PathRecord], pick: impl Fn(&SegmentKind) -> bool) -> usize {
        records.iter().flat_map(|r| &r.segments).filter(|s| pick(&s.kind)).count()
    }

    #[test]
    fn a_recorded_whitted_sample_adds_up_to_the_rendered_one_bit_for_bit() {
        let records = check_scene("effects.ron", 24, 18, 1);
        assert!(records.iter().all(|r| r.integrator == IntegratorKind::Direct));
        assert!(count(&records, |k| matches!(k, SegmentKind::Shadow { blocked: true, .. })) > 0);
        assert!(count(&records, |k| matches!(k, SegmentKind::Reflection)) > 0);
        assert!(count(&records, |k| matches!(k, SegmentKind::Refraction)) > 0);
        check_scene("ao.ron", 12, 9, 1);
        check_scene("glass.ron", 16, 12, 2);
        let flat = check_scene("box.ron", 8, 6, 1);
        assert!(flat.iter().all(|r| r.integrator == IntegratorKind::Flat));
    }

    #[test]
    fn a_recorded_path_traced_sample_adds_up_to_the_rendered_one_bit_for_bit() {
        let records = check_scene("cornell_box.ron", 12, 12, 1);
        assert!(records.iter().all(|r| r.integrator == IntegratorKind::Path));
        assert!(count(&records, |k| matches!(k, SegmentKind::Bounce)) > 0);
        assert!(count(&records, |k| matches!(k, SegmentKind::NextEvent { .. })) > 0);
        check_scene("caustic.ron", 8, 8, 2);
        check_scene("depth_of_field.ron", 8, 6, 1);
    }

    #[test]
    fn a_recorded_subsurface_sample_adds_up_to_the_rendered_one_bit_for_bit() {
        let records = check_scene("subsurface.ron", 12, 9, 1);
        assert!(count(&records, |k| matches!(k, SegmentKind::WalkStep)) > 0);
        assert!(count(&records, |k| matches!(k, SegmentKind::WalkExit)) > 0);
    }

    /// `docs/conventions.md`'s camera math, written out independently.
    fn conventions_point(r: &PathRecord, px: Real, py: Real) -> Vec3 {
        let c = &r.camera;
        let [w, h] = r.view_plane.image.map(|v| v as Real);
        let plane_h = 2.0 * c.near * (0.5 * c.fov_y).to_radians().tan();
        let plane_w = plane_h * w / h;
        let o = c.position + c.near * c.z + (plane_h / 2.0) * c.y - (plane_w / 2.0) * c.x;
        o + px * (plane_w / w) * c.x - py * (plane_h / h) * c.y
    }

    #[test]
    fn the_view_plane_and_the_pixel_point_follow_the_conventions_and_the_primary_ray_goes_through_it() {
        for name in ["effects.ron", "orthographic.ron", "depth_of_field.ron"] {
            let s = scene(name, 20, 10, 4);
            let r = Renderer::new(&s.scene, s.camera, &s.settings).unwrap();
            for (x, y, k) in [(0, 0, 0), (19, 9, 3), (7, 4, 1)] {
                let rec = r.record_sample(x, y, k).unwrap();
                let c = &rec.camera;
                let scale = c.position.abs().max_element().max(1.0) * c.near.max(1.0);
                let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-5 * scale;
                let v = &rec.view_plane;
                assert!(
                    (v.size[1] - 2.0 * c.near * (0.5 * c.fov_y).to_radians().tan()).abs() <= 1e-6 * v.size[1]
                );
                assert!(close(v.upper_left, conventions_point(&rec, 0.0, 0.0)), "{name}");
                assert!(close(v.lower_right, conventions_point(&rec, 20.0, 10.0)), "{name}");
                assert!(close(v.center, conventions_point(&rec, 10.0, 5.0)), "{name}");
                let p = conventions_point(&rec, x as Real + rec.film[0], y as Real + rec.film[1]);
                assert!(close(rec.pixel_point, p), "{name}: {} vs {p}", rec.pixel_point);
                let primary = &rec.segments[0];
                assert_eq!(primary.kind, SegmentKind::Primary);
                if rec.camera.lens_radius == 0.0 {
                    let expected = r.view_plane().primary_ray(x, y, rec.film[0], rec.film[1]);
                    assert_eq!((primary.origin, primary.direction), (expected.origin, expected.dir));
                    if rec.camera.projection == "orthographic" {
                        assert!(close(primary.origin, p) && primary.direction == c.z);
                    } else {
                        assert!(primary.origin == c.position && close(primary.origin + primary.direction, p));
                    }
                }
                let ray = crate::Ray::new(primary.origin, primary.direction);
                let hit = s.scene.cast(&ray);
                assert_eq!(
                    primary.hit.as_ref().map(|h| (h.t, h.object, h.primitive, h.normal)),
                    hit.map(|h| (h.t, h.object, h.primitive, h.normal))
                );
            }
            assert!(
                r.record_sample(20, 0, 0).is_none()
                    && r.record_sample(0, 10, 0).is_none()
                    && r.record_sample(0, 0, 4).is_none()
            );
        }
    }
}
