//! A pixel's light path drawn in the scene view: the pixel's 3D point on
//! the view plane, its primary ray to the closest hit and the hit's normal,
//! each segment coloured by its kind; hovering a segment shows its numbers.
//!
//! Without a record, the path is the primary ray the pixel inspection
//! casts and `rt-view cast --pixels` prints for the pixel
//! ([`ViewPlane::center_ray`], cast with [`rt_core::Scene::cast`]). With the
//! record of one of the pixel's samples ([`PathRecord`], the renderer's own
//! computation, `rt-view explain`), it is every ray of that sample: shadow
//! rays (blocked or not), reflections and refractions, bounces with their
//! next-event rays, walk steps; hovering one shows its origin, direction,
//! t, what it hit, the radiance and weights it carries, the contributions
//! found at its hit, the decisions made there (MIS weights, Russian
//! roulette) and the course's tests on the hit.

use egui::{Color32, FontId, Painter, Pos2, Stroke, vec2};
use rt_core::explain::record::{PathRecord, Segment, SegmentKind as RecordKind};
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
    /// An ambient-occlusion ray.
    Occlusion,
    /// The ray a random walk leaves its object along.
    WalkExit,
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
            Self::Occlusion => Color32::from_rgb(160, 160, 200),
            Self::WalkExit => Color32::from_rgb(255, 160, 200),
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
            Self::Occlusion => "ambient-occlusion ray",
            Self::WalkExit => "walk exit",
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

    /// The path of a recorded sample: every segment of `record`, each
    /// ending at its hit, at `t_max` (a ray towards a light), or `miss`
    /// units away (a ray that left the scene), and the normal (`unit` long)
    /// at each hit.
    pub fn from_record(record: &PathRecord, unit: Real, miss: Real) -> Self {
        let mut segments = Vec::new();
        for (i, s) in record.segments.iter().enumerate() {
            let kind = match (&s.kind, &s.hit) {
                (RecordKind::Primary, Some(_)) => SegmentKind::Primary,
                (RecordKind::Shadow { blocked: true, .. } | RecordKind::NextEvent { blocked: true }, _) => {
                    SegmentKind::ShadowBlocked
                }
                (RecordKind::Shadow { .. }, _) => SegmentKind::ShadowUnblocked,
                (RecordKind::NextEvent { .. }, _) => SegmentKind::NextEvent,
                (RecordKind::AmbientOcclusion { .. }, _) => SegmentKind::Occlusion,
                (RecordKind::Reflection, _) => SegmentKind::Reflection,
                (RecordKind::Refraction, _) => SegmentKind::Refraction,
                (RecordKind::Bounce, _) => SegmentKind::Bounce,
                (RecordKind::WalkStep, _) => SegmentKind::WalkStep,
                (RecordKind::WalkExit, _) => SegmentKind::WalkExit,
                (RecordKind::Primary, None) => SegmentKind::Miss,
            };
            let to = match (&s.hit, s.t_max) {
                (Some(hit), _) => hit.point,
                (None, Some(t)) if t.is_finite() => s.origin + s.direction * t,
                (None, _) => s.origin + s.direction.normalize_or_zero() * miss,
            };
            let info = segment_info(record, i, s);
            segments.push(PathSegment { kind, from: s.origin, to, info });
            // Normals where a path meets a surface (a walk's steps end inside).
            if let Some(hit) = s.hit.as_ref().filter(|_| kind != SegmentKind::WalkStep) {
                segments.push(PathSegment {
                    kind: SegmentKind::Normal,
                    from: hit.point,
                    to: hit.point + hit.normal * unit * 0.6,
                    info: format!("normal {}\nat {}", vector(hit.normal), vector(hit.point)),
                });
            }
        }
        Self { pixel: record.pixel, point: record.pixel_point, segments }
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

/// The numbers hovering segment `i` of `record` shows, one per line.
fn segment_info(record: &PathRecord, i: usize, s: &Segment) -> String {
    let mut lines = vec![
        format!("segment {i}, depth {}", s.depth),
        format!("origin {}", vector(s.origin)),
        format!("direction {}", vector(s.direction)),
    ];
    if let Some(t) = s.t_max {
        lines.push(format!("t_max {}", short(t)));
    }
    match &s.hit {
        Some(hit) => {
            lines.push(format!("t {}, hit {}", short(hit.t), vector(hit.point)));
            let side = if hit.front { "front" } else { "back" };
            lines.push(format!(
                "object {} ({}), primitive {}, {side} side",
                hit.object, hit.shape, hit.primitive
            ));
            lines.push(format!("normal {}", vector(hit.normal)));
        }
        None => lines.push("no hit".into()),
    }
    if let Some(r) = s.radiance {
        lines.push(format!("radiance {}", color(r)));
    }
    if let Some(w) = s.weight {
        lines.push(format!("weight {}", color(w)));
    }
    for c in record.contributions.iter().filter(|c| c.segment == i) {
        lines.push(format!(
            "adds {} ({})",
            color(c.value),
            flat(&serde_json::to_value(&c.kind).unwrap_or_default())
        ));
    }
    for e in &s.events {
        lines.push(flat(&serde_json::to_value(e).unwrap_or_default()));
    }
    if let Some(test) = s.hit.as_ref().and_then(|h| h.test.as_ref()) {
        lines.push(format!("test: {}", flat(&serde_json::to_value(test).unwrap_or_default())));
    }
    lines.join("\n")
}

/// `c` as "(r, g, b)" with four significant digits.
fn color(c: rt_core::Color) -> String {
    let [r, g, b] = c.to_array();
    format!("({}, {}, {})", short(r as Real), short(g as Real), short(b as Real))
}

/// A JSON value on one line, numbers short: `type` first, then "key value"
/// pairs; arrays of numbers as "(a, b, c)".
fn flat(value: &serde_json::Value) -> String {
    use serde_json::Value;
    match value {
        Value::Number(n) => n.as_f64().map_or_else(|| n.to_string(), |v| short(v as Real)),
        Value::Array(items) => format!("({})", items.iter().map(flat).collect::<Vec<_>>().join(", ")),
        Value::Object(map) => {
            let head = map.get("type").or(map.get("shape")).and_then(Value::as_str).map(str::to_owned);
            let rest = map
                .iter()
                .filter(|(k, _)| *k != "type" && *k != "shape")
                .map(|(k, v)| format!("{k} {}", flat(v)))
                .collect::<Vec<_>>()
                .join(", ");
            match head {
                Some(h) if rest.is_empty() => h,
                Some(h) => format!("{h}: {rest}"),
                None => rest,
            }
        }
        Value::String(s) => s.clone(),
        other => other.to_string(),
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

    #[test]
    fn a_recorded_path_draws_every_segment_to_its_hit_or_its_light_with_its_numbers() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/shadows.ron");
        let loaded = rt_core::load_scene(&file).unwrap();
        let settings = loaded.settings.overridden(Some(64), Some(48), Some(1)).unwrap();
        let renderer = rt_core::Renderer::new(&loaded.scene, loaded.camera, &settings).unwrap();
        let record = (0..48)
            .flat_map(|y| (0..64).map(move |x| (x, y)))
            .filter_map(|(x, y)| renderer.record_sample(x, y, 0))
            .find(|r| r.segments.iter().any(|s| matches!(s.kind, RecordKind::Shadow { .. })))
            .expect("a pixel with a shadow ray");
        let path = PixelPath::from_record(&record, 0.5, 100.0);
        assert_eq!(path.point, record.pixel_point);
        let drawn: Vec<&PathSegment> =
            path.segments.iter().filter(|s| s.kind != SegmentKind::Normal).collect();
        assert_eq!(drawn.len(), record.segments.len());
        for (i, (d, s)) in drawn.iter().zip(&record.segments).enumerate() {
            assert_eq!(d.from, s.origin);
            match (&s.hit, s.t_max) {
                (Some(hit), _) => assert_eq!(d.to, hit.point),
                (None, Some(t)) => assert_eq!(d.to, s.origin + s.direction * t),
                (None, None) => {}
            }
            assert!(d.info.starts_with(&format!("segment {i}, depth {}", s.depth)), "{}", d.info);
            if let RecordKind::Shadow { blocked, .. } = s.kind {
                let want = if blocked { SegmentKind::ShadowBlocked } else { SegmentKind::ShadowUnblocked };
                assert_eq!(d.kind, want);
            }
        }
        // The primary hit's course test and the contributions are in the hover text.
        assert!(drawn[0].info.contains("test: "), "{}", drawn[0].info);
        assert!(drawn.iter().any(|d| d.info.contains("adds (")), "no contribution shown");
    }
}
