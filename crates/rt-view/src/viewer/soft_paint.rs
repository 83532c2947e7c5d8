//! egui's output painted on the CPU, for images made without a window
//! (`--scene-view OUT.png`, the pictures in the docs): the same shapes the
//! window draws, tessellated by egui into triangles, filled here.
//!
//! Each triangle is filled at pixel centres by its barycentric
//! coordinates (inside when all three are ≥ 0, so shared edges leave no
//! gaps), its vertex colours and texture coordinates interpolated; the
//! texture is sampled bilinearly and multiplied by the colour, and the
//! result blended "over" the image with premultiplied alpha
//! (`dst = src + (1 − src.a)·dst`), in gamma space as egui's own painters
//! blend. egui's feathering (a 1-pixel alpha ramp along edges) gives the
//! anti-aliasing.

use std::collections::HashMap;

use egui::epaint::{ClippedPrimitive, Primitive};
use egui::{Color32, ColorImage, FullOutput, TextureId, TexturesDelta};

/// An RGBA image egui's meshes are painted into, and the textures they use.
pub struct SoftPainter {
    size: [usize; 2],
    pixels: Vec<[f32; 4]>,
    textures: HashMap<TextureId, ColorImage>,
}

impl SoftPainter {
    /// A painter for an image `size` pixels large, filled with `background`.
    pub fn new(size: [usize; 2], background: Color32) -> Self {
        let b = background.to_array().map(|c| c as f32 / 255.0);
        Self { size, pixels: vec![b; size[0] * size[1]], textures: HashMap::new() }
    }

    /// Applies texture uploads (whole images and patches) and frees,
    /// emptying `delta` (egui insists every delta is handled).
    pub fn update_textures(&mut self, delta: &mut TexturesDelta) {
        for (id, deltas) in &delta.set {
            for d in deltas {
                let egui::ImageData::Color(image) = &d.image;
                match d.pos {
                    None => {
                        self.textures.insert(*id, (**image).clone());
                    }
                    Some([x0, y0]) => {
                        let Some(texture) = self.textures.get_mut(id) else { continue };
                        let [w, h] = image.size;
                        for y in 0..h {
                            for x in 0..w {
                                let (tx, ty) = (x0 + x, y0 + y);
                                if tx < texture.size[0] && ty < texture.size[1] {
                                    texture.pixels[ty * texture.size[0] + tx] = image.pixels[y * w + x];
                                }
                            }
                        }
                    }
                }
            }
        }
        for id in &delta.free {
            self.textures.remove(id);
        }
        delta.clear();
    }

    /// Paints a whole egui output (its textures, then its shapes) at
    /// `pixels_per_point`.
    pub fn paint_output(&mut self, ctx: &egui::Context, mut output: FullOutput) {
        self.update_textures(&mut output.textures_delta);
        let ppp = output.pixels_per_point;
        let primitives = ctx.tessellate(output.shapes, ppp);
        self.paint(&primitives, ppp);
    }

    /// Paints tessellated primitives (positions in points, `ppp` pixels each).
    pub fn paint(&mut self, primitives: &[ClippedPrimitive], ppp: f32) {
        for p in primitives {
            let Primitive::Mesh(mesh) = &p.primitive else { continue };
            let clip = p.clip_rect * ppp;
            let texture = self.textures.get(&mesh.texture_id);
            for tri in mesh.indices.chunks_exact(3) {
                let v = [0, 1, 2].map(|k| mesh.vertices[tri[k] as usize]);
                fill_triangle(&mut self.pixels, self.size, clip, v, ppp, texture);
            }
        }
    }

    /// The image as 8-bit RGB, row after row.
    pub fn rgb8(&self) -> Vec<[u8; 3]> {
        let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        self.pixels.iter().map(|p| [byte(p[0]), byte(p[1]), byte(p[2])]).collect()
    }
}

/// Fills one triangle of vertices `v` (points; `ppp` pixels each) into
/// `pixels`, inside `clip` (pixels).
fn fill_triangle(
    pixels: &mut [[f32; 4]],
    [w, h]: [usize; 2],
    clip: egui::Rect,
    v: [egui::epaint::Vertex; 3],
    ppp: f32,
    texture: Option<&ColorImage>,
) {
    let p = v.map(|v| v.pos * ppp);
    let area = cross(p[1] - p[0], p[2] - p[0]);
    if area.abs() < 1e-9 {
        return;
    }
    let lo = |a: f32, b: f32, c: f32, min: f32| a.min(b).min(c).max(min).floor().max(0.0) as usize;
    let hi = |a: f32, b: f32, c: f32, max: f32| a.max(b).max(c).min(max).ceil().max(0.0) as usize;
    let (x0, x1) = (lo(p[0].x, p[1].x, p[2].x, clip.left()), hi(p[0].x, p[1].x, p[2].x, clip.right()).min(w));
    let (y0, y1) = (lo(p[0].y, p[1].y, p[2].y, clip.top()), hi(p[0].y, p[1].y, p[2].y, clip.bottom()).min(h));
    let colors = v.map(|v| v.color.to_array().map(|c| c as f32 / 255.0));
    for y in y0..y1 {
        for x in x0..x1 {
            let c = egui::pos2(x as f32 + 0.5, y as f32 + 0.5);
            let b0 = cross(p[1] - c, p[2] - c) / area;
            let b1 = cross(p[2] - c, p[0] - c) / area;
            let b2 = 1.0 - b0 - b1;
            if b0 < 0.0 || b1 < 0.0 || b2 < 0.0 {
                continue;
            }
            let mut src = [0.0; 4];
            for (k, s) in src.iter_mut().enumerate() {
                *s = b0 * colors[0][k] + b1 * colors[1][k] + b2 * colors[2][k];
            }
            if let Some(t) = texture {
                let uv = v[0].uv.to_vec2() * b0 + v[1].uv.to_vec2() * b1 + v[2].uv.to_vec2() * b2;
                let texel = bilinear(t, uv.x, uv.y);
                for k in 0..4 {
                    src[k] *= texel[k];
                }
            }
            let dst = &mut pixels[y * w + x];
            for k in 0..4 {
                dst[k] = src[k] + (1.0 - src[3]) * dst[k];
            }
        }
    }
}

/// The z of the 2D cross product: twice the signed area of `a`, `b`.
fn cross(a: egui::Vec2, b: egui::Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

/// `texture` at normalized coordinates (u, v), bilinearly, premultiplied RGBA in 0..1.
fn bilinear(texture: &ColorImage, u: f32, v: f32) -> [f32; 4] {
    let [w, h] = texture.size;
    let (x, y) = (u * w as f32 - 0.5, v * h as f32 - 0.5);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let at = |x: f32, y: f32| {
        let (x, y) = ((x.max(0.0) as usize).min(w - 1), (y.max(0.0) as usize).min(h - 1));
        texture.pixels[y * w + x].to_array().map(|c| c as f32 / 255.0)
    };
    let (a, b, c, d) = (
        at(x.floor(), y.floor()),
        at(x.floor() + 1.0, y.floor()),
        at(x.floor(), y.floor() + 1.0),
        at(x.floor() + 1.0, y.floor() + 1.0),
    );
    let mut out = [0.0; 4];
    for k in 0..4 {
        out[k] = (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_filled_rectangle_covers_its_pixels_and_nothing_else() {
        let ctx = egui::Context::default();
        let mut painter = SoftPainter::new([40, 30], Color32::BLACK);
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(40.0, 30.0))),
            ..Default::default()
        };
        let output = ctx.run_ui(input, |ui| {
            let r = egui::Rect::from_min_max(egui::pos2(10.0, 5.0), egui::pos2(30.0, 25.0));
            ui.painter().rect_filled(r, 0.0, Color32::from_rgb(255, 0, 0));
        });
        painter.paint_output(&ctx, output);
        let image = painter.rgb8();
        assert_eq!(image[15 * 40 + 20], [255, 0, 0]);
        assert_eq!(image[2 * 40 + 2], [0, 0, 0]);
        assert_eq!(image[15 * 40 + 35], [0, 0, 0]);
    }
}
