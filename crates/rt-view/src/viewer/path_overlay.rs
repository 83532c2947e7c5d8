//! A pixel's light path drawn in the scene view: the pixel's 3D point on
//! the view plane, its primary ray to the closest hit and the hit's normal,
//! each segment coloured by its kind; hovering a segment shows its numbers.
//!
//! The primary ray is the one the pixel inspection casts and `rt-view cast
//! --pixels` prints for the pixel: [`ViewPlane::center_ray`], cast with
//! [`rt_core::Scene::cast`].

use egui::{Color32, FontId, Painter, Pos2, Stroke, vec2};
use rt_core::{Real, Scene, Vec3, ViewPlane};

use super::camera_overlay::{self, arrow, dot, label, short};
use super::projection::{Projection, distance_to_segment};

/// What a segment of a path is, which sets its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentKind {
    /// The ray from the eye through the pixel to the closest hit.
    Primary,
    /// A surface normal at a hit (drawn as an arrow).
    Normal,
    /// A shadow ray that reached its light.
    ShadowUnblocked,
    /// A shadow ray stopped by an object.
    ShadowBlocked,
    /// A mirror reflection.
    Reflection,
    /// A refraction through a surface.
    Refraction,
    /// A sampled bounce of a global-illumination path.
    Bounce,
    /// A next-event estimation ray towards a light.
    NextEvent,
    /// A step of a random walk inside an object.
    WalkStep,
    /// A ray that hit nothing (continues to the background).
    Miss,
}

impl SegmentKind {
    /// The colour the segment is drawn in.
    pub fn color(self) -> Color32 {
        match self {
            Self::Primary => Color32::WHITE,
            Self::Normal => Color32::from_rgb(120, 230, 230),
            Self::ShadowUnblocked => Color32::from_rgb(255, 230, 90),
            Self::ShadowBlocked => Color32::from_rgb(150, 90, 60),
            Self::Reflection => Color32::from_rgb(120, 170, 255),
            Self::Refraction => Color32::from_rgb(200, 120, 255),
            Self::Bounce => Color32::from_rgb(255, 150, 60),
            Self::NextEvent => Color32::from_rgb(255, 210, 120),
            Self::WalkStep => Color32::from_rgb(255, 100, 160),
            Self::Miss => Color32::from_gray(140),
        }
    }

    /// Its name, as the hover text says it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary ray",
            Self::Normal => "normal",
            Self::ShadowUnblocked => "shadow ray (reaches the light)",
            Self::ShadowBlocked => "shadow ray (blocked)",
            Self::Reflection => "reflection",
            Self::Refraction => "refraction",
            Self::Bounce => "bounce",
            Self::NextEvent => "next-event ray",
            Self::WalkStep => "walk step",
            Self::Miss => "ray to the background",
        }
    }
}

/// One drawn segment of a path, with what hovering it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct PathSegment {
    /// What it is.
    pub kind: SegmentKind,
    /// Where it starts.
    pub from: Vec3,
    /// Where it ends (the hit, the light, or a far point for a miss).
    pub to: Vec3,
    /// Its numbers, one per line.
    pub info: String,
}

/// The pixel's point and path: what is drawn for a pinned pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelPath {
    /// The pixel.
    pub pixel: [u32; 2],
    /// Its centre's 3D point on the view plane.
    pub point: Vec3,
    /// The segments, primary ray first.
    pub segments: Vec<PathSegment>,
}

/// `v` as "(x, y, z)" with four significant digits.
pub fn vector(v: Vec3) -> String {
    format!("({}, {}, {})", short(v.x), short(v.y), short(v.z))
}

impl PixelPath {
    /// Pixel (x, y)'s point on `view` and its primary ray cast into `scene`
    /// (to the hit, with its normal, `unit` long; or `miss` units far).
    pub fn primary(view: &ViewPlane, scene: &Scene, [x, y]: [u32; 2], unit: Real, miss: Real) -> Self {
        let point = view.point(x, y, 0.5, 0.5);
        let ray = view.center_ray(x, y);
        let dir = ray.dir;
        let mut info = format!("origin {}\ndirection {}", vector(ray.origin), vector(dir));
        let mut segments = Vec::new();
        match scene.cast(&ray) {
            Some(hit) => {
                let at = ray.at(hit.t);
                let object = &scene.objects()[hit.object];
                info += &format!(
                    "\nt {}\nhit {}\nobject {} ({}), primitive {}",
                    short(hit.t),
                    vector(at),
                    hit.object,
                    object.primitive.kind(),
                    hit.primitive
                );
                segments.push(PathSegment { kind: SegmentKind::Primary, from: ray.origin, to: at, info });
                segments.push(PathSegment {
                    kind: SegmentKind::Normal,
                    from: at,
                    to: at + hit.normal.normalize_or_zero() * unit,
                    info: format!("normal {}\nat {}", vector(hit.normal), vector(at)),
                });
            }
            None => {
                info += "\nno hit: the background";
                let far = ray.origin + dir.normalize_or_zero() * miss;
                segments.push(PathSegment { kind: SegmentKind::Miss, from: ray.origin, to: far, info });
            }
        }
        Self { pixel: [x, y], point, segments }
    }

    /// Draws the path; returns the segment under `pointer` (within a few
    /// points), whose numbers are then shown beside it.
    pub fn draw(&self, painter: &Painter, p: &Projection, pointer: Option<Pos2>) -> Option<usize> {
        let mut hovered: Option<(usize, f32)> = None;
        for (i, s) in self.segments.iter().enumerate() {
            let color = s.kind.color();
            if s.kind == SegmentKind::Normal {
                arrow(painter, p, s.from, s.to, color);
                label(painter, p, s.to, "n", color);
            } else {
                camera_overlay::line(painter, p, s.from, s.to, Stroke::new(2.0, color));
                if s.kind != SegmentKind::Miss {
                    dot(painter, p, s.to, 3.0, color);
                }
            }
            if let (Some(at), Some(screen)) = (pointer, p.segment(s.from, s.to)) {
                let d = distance_to_segment(at, screen);
                if d <= HOVER_POINTS && hovered.is_none_or(|(_, best)| d < best) {
                    hovered = Some((i, d));
                }
            }
        }
        let [x, y] = self.pixel;
        dot(painter, p, self.point, 4.0, Color32::from_rgb(255, 80, 200));
        label(painter, p, self.point, &format!("P({x},{y})"), Color32::from_rgb(255, 80, 200));
        let hovered = hovered.map(|(i, _)| i);
        if let (Some(i), Some(at)) = (hovered, pointer) {
            let s = &self.segments[i];
            info_box(painter, at, &format!("{}\n{}", s.kind.name(), s.info), s.kind.color());
        }
        hovered
    }
}

/// How near (points) the pointer must be to a segment to hover it.
pub const HOVER_POINTS: f32 = 6.0;

/// `text` in a dark box beside the pointer at `at`, kept inside the painter's clip.
fn info_box(painter: &Painter, at: Pos2, text: &str, accent: Color32) {
    let galley = painter.layout_no_wrap(text.to_owned(), FontId::monospace(11.0), Color32::from_gray(230));
    let clip = painter.clip_rect();
    let size = galley.size() + vec2(12.0, 10.0);
    let mut min = at + vec2(14.0, 14.0);
    min.x = min.x.min(clip.right() - size.x).max(clip.left());
    min.y = min.y.min(clip.bottom() - size.y).max(clip.top());
    let rect = egui::Rect::from_min_size(min, size);
    painter.rect_filled(rect, 4.0, Color32::from_black_alpha(220));
    painter.rect_stroke(rect, 4.0, Stroke::new(1.0, accent), egui::StrokeKind::Inside);
    painter.galley(rect.min + vec2(6.0, 5.0), galley, Color32::WHITE);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_primary_segment_is_the_ray_cast_prints_for_the_pixel() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sphere.ron");
        let loaded = rt_core::load_scene(&path).unwrap();
        let view = ViewPlane::new(loaded.camera, 320, 240).unwrap();
        let path = PixelPath::primary(&view, &loaded.scene, [160, 120], 0.5, 10.0);
        assert_eq!(path.point, view.point(160, 120, 0.5, 0.5));
        let ray = view.center_ray(160, 120);
        let hit = loaded.scene.cast(&ray).expect("the sphere is in the middle");
        assert_eq!(path.segments[0].kind, SegmentKind::Primary);
        assert_eq!((path.segments[0].from, path.segments[0].to), (ray.origin, ray.at(hit.t)));
        assert_eq!(path.segments[1].kind, SegmentKind::Normal);
        let missed = PixelPath::primary(&view, &loaded.scene, [0, 0], 0.5, 10.0);
        assert_eq!(missed.segments.len(), 1);
        assert_eq!(missed.segments[0].kind, SegmentKind::Miss);
    }
}
