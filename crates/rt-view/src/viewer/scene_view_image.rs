//! The scene view as an image, without a window: the flat render of the
//! scene seen by the observer the view starts with, and the same overlays
//! the window draws (render camera, view plane, frustum, lights, the
//! pixel's path), painted on the CPU (`soft_paint`). Used by
//! `--scene-view OUT.png` and for the pictures in the docs.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use egui::{Color32, Rect, TextureOptions, pos2, vec2};
use rt_core::explain::record::PathRecord;
use rt_core::{Camera, LoadedScene, Real};

use super::observer::Observer;
use super::observer_render::flat_render;
use super::projection::Projection;
use super::scene_view::{SceneExtent, ViewInput, draw_overlays};
use super::soft_paint::SoftPainter;
use crate::image_out::PendingImage;

/// What to picture: the scene, its render camera and image size, the
/// pixel whose path is drawn, and the observer (`None`: the one the scene
/// view starts with, framing the camera and the scene).
pub struct SceneViewShot<'a> {
    /// The scene.
    pub scene: &'a Arc<LoadedScene>,
    /// The render camera.
    pub camera: Camera,
    /// The rendered image's size, pixels (the view plane's resolution).
    pub image_size: (u32, u32),
    /// The pixel whose path is drawn, if any.
    pub pixel: Option<[u32; 2]>,
    /// The observer; `None` frames the camera and the scene.
    pub observer: Option<Observer>,
    /// The record of one of the pixel's samples: its whole path is drawn
    /// (`None`: the pixel's primary ray).
    pub record: Option<&'a PathRecord>,
}

/// The scene view `size` pixels large as 8-bit RGB, row after row.
pub fn scene_view_image(shot: &SceneViewShot<'_>, size: [u32; 2]) -> Vec<[u8; 3]> {
    let extent = SceneExtent::of(&shot.scene.scene);
    let aspect = size[0] as Real / size[1].max(1) as Real;
    let observer = shot.observer.unwrap_or_else(|| Observer::framing(&shot.camera, extent.bounds, aspect));
    let flat =
        observer.camera().and_then(|c| flat_render(&shot.scene.scene, c, size, &AtomicBool::new(false)));
    let input = ViewInput {
        scene: shot.scene,
        camera: Some(shot.camera),
        image_size: shot.image_size,
        pinned: shot.pixel,
        spec: None,
    };
    let ctx = egui::Context::default();
    ctx.set_pixels_per_point(1.0);
    let screen = Rect::from_min_size(pos2(0.0, 0.0), vec2(size[0] as f32, size[1] as f32));
    let mut painter = SoftPainter::new(size.map(|s| s as usize), Color32::from_rgb(40, 42, 46));
    let texture = flat.map(|image| ctx.load_texture("scene view", image, TextureOptions::LINEAR));
    // The first pass builds the fonts; the second draws with them laid out.
    for pass in 0..2 {
        let raw = egui::RawInput { screen_rect: Some(screen), ..Default::default() };
        let mut output = ctx.run_ui(raw, |ui| {
            let p = ui.painter_at(screen);
            if let Some(t) = &texture {
                p.image(t.id(), screen, Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)), Color32::WHITE);
            }
            if let Some(projection) = observer.camera().and_then(|c| Projection::new(c, size, screen)) {
                draw_overlays(&p, &projection, &input, &extent, shot.record, None);
            }
        });
        if pass == 0 {
            painter.update_textures(&mut output.textures_delta);
        } else {
            painter.paint_output(&ctx, output);
        }
    }
    drop(texture);
    ctx.tex_manager().write().take_delta().clear();
    painter.rgb8()
}

/// Writes the scene view `size` pixels large to `out` (a `.png`), atomically.
pub fn write_scene_view(shot: &SceneViewShot<'_>, size: [u32; 2], out: &Path) -> anyhow::Result<()> {
    let pending = PendingImage::png(out)?;
    pending.write_rgb8(size[0], size[1], &scene_view_image(shot, size))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_image_shows_the_flat_render_and_the_overlays_over_it() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/box.ron");
        let scene = Arc::new(rt_core::load_scene(&path).unwrap());
        let shot = SceneViewShot {
            scene: &scene,
            camera: scene.camera,
            image_size: (32, 24),
            pixel: Some([16, 12]),
            observer: None,
            record: None,
        };
        let size = [320, 240];
        let image = scene_view_image(&shot, size);
        assert_eq!(image.len(), 320 * 240);
        // Where the camera's eye C is drawn, the image is white (its dot).
        let extent = SceneExtent::of(&scene.scene);
        let observer = Observer::framing(&scene.camera, extent.bounds, 320.0 / 240.0);
        let screen = Rect::from_min_size(pos2(0.0, 0.0), vec2(320.0, 240.0));
        let projection = Projection::new(observer.camera().unwrap(), size, screen).unwrap();
        let c = projection.point(scene.camera.position()).unwrap();
        assert_eq!(image[c.y as usize * 320 + c.x as usize], [255, 255, 255], "no eye at {c:?}");
        // Somewhere the flat render shows the blue box, and the view plane's yellow is drawn.
        assert!(image.iter().any(|p| p[2] > 150 && p[0] < 120), "no box");
        assert!(image.iter().any(|p| p[0] > 200 && p[1] > 160 && p[2] < 120), "no view plane");
    }
}
/// The pictures of `docs/course-in-3d.md`, made with the function the
/// docs describe: `cargo test -p rt-view --lib -- --ignored course_pictures`
/// writes them into `docs/course-in-3d/`.
#[cfg(test)]
mod course_pictures {
    use super::*;
    use rt_core::Renderer;
    use rt_core::explain::record::{PathRecord, SegmentKind};

    /// Where the observer stands for a picture.
    enum Look {
        /// As the scene view starts: the camera and the whole scene.
        Framing,
        /// `distance` from the point `fraction` of the way from the eye to
        /// the primary hit.
        Along { fraction: Real, distance: Real },
    }

    /// The first pixel (scanning every `step`th) whose sample 0 `wanted` accepts.
    fn find(
        renderer: &Renderer<'_>,
        (w, h): (u32, u32),
        step: u32,
        wanted: &dyn Fn(&PathRecord) -> bool,
    ) -> PathRecord {
        (0..h)
            .step_by(step as usize)
            .flat_map(|y| (0..w).step_by(step as usize).map(move |x| (x, y)))
            .filter_map(|(x, y)| renderer.record_sample(x, y, 0))
            .find(|r| wanted(r))
            .expect("a pixel with such a path")
    }

    fn picture(
        name: &str,
        file: &str,
        size: Option<(u32, u32)>,
        look: Look,
        wanted: &dyn Fn(&PathRecord) -> bool,
    ) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let scene = Arc::new(rt_core::load_scene(&root.join("scenes").join(file)).unwrap());
        let settings = scene.settings.overridden(size.map(|s| s.0), size.map(|s| s.1), Some(1)).unwrap();
        let (w, h) = (settings.image.width(), settings.image.height());
        let renderer = Renderer::new(&scene.scene, scene.camera, &settings).unwrap();
        let record = find(&renderer, (w, h), (w / 40).max(1), wanted);
        let out = [640, 400];
        let observer = match look {
            Look::Framing => None,
            Look::Along { fraction, distance } => {
                let c = scene.camera.position();
                let hit =
                    record.segments[0].hit.as_ref().map_or(scene.camera.center_of_interest(), |h| h.point);
                Some(Observer::looking_at(&scene.camera, c + (hit - c) * fraction, distance))
            }
        };
        let shot = SceneViewShot {
            scene: &scene,
            camera: scene.camera,
            image_size: (w, h),
            pixel: Some(record.pixel),
            observer,
            record: Some(&record),
        };
        let dir = root.join("docs/course-in-3d");
        std::fs::create_dir_all(&dir).unwrap();
        write_scene_view(&shot, out, &dir.join(name)).unwrap();
        eprintln!("{name}: {file} pixel {:?} of {w}x{h}", record.pixel);
    }

    fn has(r: &PathRecord, kind: impl Fn(&SegmentKind) -> bool) -> bool {
        r.segments.iter().any(|s| kind(&s.kind))
    }

    #[test]
    #[ignore]
    fn course_pictures() {
        let hits = |r: &PathRecord| r.segments[0].hit.is_some();
        // Camera space and the view plane up close: a 16x12 image, so its pixel grid shows.
        picture(
            "camera.png",
            "box.ron",
            Some((16, 12)),
            Look::Along { fraction: 0.0, distance: 3.2 },
            &|r| r.pixel == [5, 4],
        );
        picture("primary.png", "box.ron", None, Look::Framing, &hits);
        picture("orthographic.png", "orthographic.ron", None, Look::Framing, &hits);
        picture("shadows.png", "shadows.ron", None, Look::Framing, &|r| {
            has(r, |k| matches!(k, SegmentKind::Shadow { blocked: true, .. }))
                && has(r, |k| matches!(k, SegmentKind::Shadow { blocked: false, .. }))
        });
        picture("mirrors.png", "mirrors.ron", None, Look::Framing, &|r| {
            r.segments.iter().filter(|s| matches!(s.kind, SegmentKind::Reflection)).count() >= 2
        });
        picture("glass.png", "glass.ron", None, Look::Along { fraction: 1.0, distance: 3.0 }, &|r| {
            r.segments.iter().filter(|s| matches!(s.kind, SegmentKind::Refraction)).count() >= 2
        });
        picture(
            "path-tracing.png",
            "cornell_box.ron",
            None,
            Look::Along { fraction: 0.8, distance: 9.0 },
            &|r| r.segments.iter().filter(|s| matches!(s.kind, SegmentKind::Bounce)).count() >= 3,
        );
        picture(
            "subsurface.png",
            "subsurface.ron",
            None,
            Look::Along { fraction: 1.0, distance: 1.6 },
            // A walk that starts where the primary ray enters the translucent object.
            &|r| {
                let walk = r.segments.iter().filter(|s| matches!(s.kind, SegmentKind::WalkStep));
                r.segments.iter().any(|s| s.parent == Some(0) && matches!(s.kind, SegmentKind::WalkStep))
                    && walk.count() >= 5
            },
        );
    }
}
