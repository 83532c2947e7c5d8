//! The recorder that writes a [`PathRecord`]'s segments, contributions and
//! events as the integrator calls it, with what it hit and the course's
//! tests on each hit ([`crate::geometry::primitive::Primitive::explain`]).

use crate::camera::Projection;
use crate::camera::view_plane::ViewPlane;
use crate::explain::record::{
    CameraRecord, Contribution, ContributionKind, Event, Segment, SegmentHit, SegmentKind, ViewPlaneRecord,
};
use crate::explain::recorder::Recorder;
use crate::geometry::hit::Hit;
use crate::math::color::Color;
use crate::math::ray::{Interval, Ray};
use crate::math::real::Real;
use crate::scene::Scene;

#[cfg(doc)]
use crate::explain::record::PathRecord;

/// Writes the rays, contributions and events of one sample.
#[derive(Clone, Debug)]
pub struct PathRecorder<'s> {
    scene: &'s Scene,
    /// The rays so far, in the order cast.
    pub segments: Vec<Segment>,
    /// The terms so far, in the order added.
    pub contributions: Vec<Contribution>,
    current: Option<usize>,
}

impl<'s> PathRecorder<'s> {
    /// An empty record of a sample in `scene`.
    pub fn new(scene: &'s Scene) -> Self {
        Self { scene, segments: Vec::new(), contributions: Vec::new(), current: None }
    }

    /// What `ray` hit at `hit`, with the course's tests on it.
    fn segment_hit(&self, ray: &Ray, hit: &Hit) -> SegmentHit {
        let primitive = &self.scene.objects()[hit.object].primitive;
        SegmentHit {
            t: hit.t,
            object: hit.object,
            primitive: hit.primitive,
            shape: primitive.kind(),
            point: ray.at(hit.t),
            normal: hit.normal,
            front: ray.dir.dot(hit.normal) < 0.0,
            test: primitive.explain(hit.primitive, ray, hit.t),
        }
    }

    fn push(&mut self, kind: SegmentKind, ray: &Ray, t_max: Option<Real>, hit: Option<SegmentHit>) -> usize {
        let parent = self.current;
        let depth = match (parent, &kind) {
            (None, _) => 0,
            (Some(p), SegmentKind::Reflection | SegmentKind::Refraction | SegmentKind::Bounce) => {
                self.segments[p].depth + 1
            }
            (Some(p), _) => self.segments[p].depth,
        };
        self.segments.push(Segment {
            parent,
            depth,
            kind,
            origin: ray.origin,
            direction: ray.dir,
            t_max,
            hit,
            radiance: None,
            weight: None,
            events: Vec::new(),
        });
        self.segments.len() - 1
    }
}

impl Recorder for PathRecorder<'_> {
    const ACTIVE: bool = true;

    fn ray(&mut self, kind: SegmentKind, ray: &Ray, hit: Option<&Hit>, weight: Option<Color>) -> usize {
        let hit = hit.map(|h| self.segment_hit(ray, h));
        let i = self.push(kind, ray, None, hit);
        self.segments[i].weight = weight;
        self.current = Some(i);
        i
    }

    fn found(&mut self, hit: Option<&Hit>) {
        if let Some(i) = self.current {
            let s = &self.segments[i];
            let ray = Ray::new(s.origin, s.direction);
            self.segments[i].hit = hit.map(|h| self.segment_hit(&ray, h));
        }
    }

    fn returned(&mut self, radiance: Color) {
        if let Some(i) = self.current {
            self.segments[i].radiance = Some(radiance);
            self.current = self.segments[i].parent;
        }
    }

    fn probe(&mut self, kind: SegmentKind, ray: &Ray, t_max: Real) {
        // The renderer asks only whether anything is in the way; the record
        // names what is, the closest blocker within the same reach.
        let blocked = matches!(
            kind,
            SegmentKind::Shadow { blocked: true, .. }
                | SegmentKind::AmbientOcclusion { blocked: true }
                | SegmentKind::NextEvent { blocked: true }
        );
        let hit = if blocked {
            self.scene.closest_hit(ray, Interval::new(0.0, t_max)).map(|h| self.segment_hit(ray, &h))
        } else {
            None
        };
        let next_event = matches!(kind, SegmentKind::NextEvent { .. });
        let i = self.push(kind, ray, Some(t_max).filter(|t| t.is_finite()), hit);
        if next_event
            && let Some(Event::NextEvent { segment, .. }) =
                self.current.and_then(|c| self.segments[c].events.last_mut())
        {
            *segment = Some(i);
        }
    }

    fn contribution(&mut self, kind: ContributionKind, value: Color) {
        let segment = self.current.unwrap_or(0);
        self.contributions.push(Contribution { segment, kind, value });
    }

    fn event(&mut self, make: impl FnOnce() -> Event) {
        if let Some(i) = self.current {
            self.segments[i].events.push(make());
        }
    }
}

impl CameraRecord {
    /// The record of `view`'s camera.
    pub fn of(view: &ViewPlane) -> Self {
        let c = view.camera();
        let b = c.basis();
        let lens = c.lens();
        Self {
            position: c.position(),
            center_of_interest: c.center_of_interest(),
            up: c.up(),
            x: b.x,
            y: b.y,
            z: b.z,
            fov_y: c.fov_y(),
            near: c.near(),
            projection: match c.projection() {
                Projection::Perspective => "perspective",
                Projection::Orthographic => "orthographic",
            },
            lens_radius: lens.radius,
            focus_distance: lens.focus_distance,
        }
    }
}

impl ViewPlaneRecord {
    /// The record of `view`: its corners are [`ViewPlane::point`] at the
    /// image's corners, as the renderer computes pixel points.
    pub fn of(view: &ViewPlane) -> Self {
        let (w, h) = (view.width(), view.height());
        let (plane_w, plane_h) = view.size();
        let (pixel_w, pixel_h) = view.pixel_size();
        let c = view.camera();
        Self {
            image: [w, h],
            size: [plane_w, plane_h],
            pixel_size: [pixel_w, pixel_h],
            upper_left: view.upper_left(),
            upper_right: view.point(w, 0, 0.0, 0.0),
            lower_left: view.point(0, h, 0.0, 0.0),
            lower_right: view.point(w, h, 0.0, 0.0),
            center: c.position() + c.near() * c.basis().z,
        }
    }
}
