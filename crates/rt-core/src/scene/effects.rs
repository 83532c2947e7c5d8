//! What a render asks for ([`Effects`], with the scene's lights) and what the
//! renderer will simulate ([`EffectPlan`]), decided once per render: a kind
//! of ray that no effect needs is never cast, and [`RayCounts`] proves it.

use std::ops::{Add, AddAssign};

use crate::lights::light::Light;
use crate::materials::material::Material;
use crate::math::color::Color;
use crate::math::real::Real;

/// Deepest reflection/refraction recursion a scene may ask for.
pub const MAX_DEPTH: u32 = 64;

/// Largest sample count of an area light or of ambient occlusion per shaded point.
pub const MAX_EFFECT_SAMPLES: u32 = 4096;

/// The light transport a render asks for (a scene file's `effects` block):
/// recursion depth, ambient occlusion, and global illumination, which
/// chooses the path tracer over the direct-lighting tracer. The default
/// (no recursion, neither of the others) with no lights is pure ray casting.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Effects {
    /// How many reflection/refraction bounces follow a primary ray, 0 to
    /// [`MAX_DEPTH`]; 0 turns both off.
    pub max_depth: u32,
    /// Ambient occlusion, if asked for: darkens the ambient term by how much
    /// of the hemisphere is blocked within a radius.
    pub ambient_occlusion: Option<AmbientOcclusion>,
    /// Global illumination, if asked for: path tracing replaces the
    /// direct-lighting tracer ([`crate::integrators::path_tracer`]).
    pub global_illumination: Option<GlobalIllumination>,
}

/// Most surfaces a path may scatter from under global illumination.
pub const MAX_BOUNCES: u32 = 1024;

/// The largest cap on scattering events in one walk through a translucent
/// object that a scene may set.
pub const MAX_WALK_STEPS: u32 = 1_000_000;

/// The cap on scattering events in one walk that a scene gets unless it sets
/// one: far above what the walks of the example scenes take (their mean is
/// tens to a few hundred steps), so it ends almost no walk.
pub const DEFAULT_WALK_STEPS: u32 = 4096;

/// Global-illumination settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct GlobalIllumination {
    /// How many surfaces a path may scatter from, 0 to [`MAX_BOUNCES`]: 0
    /// shows only what glows, 1 is direct lighting, each more adds one
    /// bounce of indirect light.
    pub max_bounces: u32,
    /// Whether Russian roulette may end paths early (unbiased; faster for
    /// the same noise on most scenes).
    pub russian_roulette: bool,
    /// How many scattering events one random walk through a translucent
    /// object may take, 1 to [`MAX_WALK_STEPS`]; a walk that reaches the cap
    /// ends there and its light is lost (a bias, which
    /// `rt-view accuracy` measures).
    pub max_walk_steps: u32,
}

/// Ambient-occlusion settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AmbientOcclusion {
    /// Rays per shaded point, ≥ 1.
    pub samples: u32,
    /// How far an occluder counts, world units, > 0.
    pub radius: Real,
}

/// Which kinds of rays a render casts. Each flag is on only when the scene
/// has something for that kind of ray to find.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EffectPlan {
    /// Lights exist: hits are shaded. Off: flat colours, primary rays only.
    pub shading: bool,
    /// Some light casts shadows: shadow rays.
    pub shadows: bool,
    /// Some material reflects (mirror or Fresnel reflection of glass) and
    /// `max_depth > 0`: reflection rays.
    pub reflection: bool,
    /// Some material is transparent and `max_depth > 0`: refraction rays.
    pub refraction: bool,
    /// Ambient occlusion was asked for and there is ambient light for it to
    /// darken: AO rays.
    pub ambient_occlusion: Option<AmbientOcclusion>,
    /// Recursion limit for reflection and refraction rays.
    pub max_depth: u32,
    /// Path tracing instead of the direct-lighting tracer; the flags above
    /// then say what the direct-lighting tracer would do if it were switched off.
    pub global_illumination: Option<GlobalIllumination>,
    /// Some material has a translucent inside and global illumination is
    /// on: random walks through those objects (off: their materials act as
    /// plain surfaces).
    pub subsurface: bool,
}

/// Effects a user can switch off in the viewer; a plan never turns on what
/// the scene does not ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct EffectToggles {
    /// Keep shadow rays.
    pub shadows: bool,
    /// Keep reflection rays.
    pub reflection: bool,
    /// Keep refraction rays.
    pub refraction: bool,
    /// Keep ambient-occlusion rays.
    pub ambient_occlusion: bool,
    /// Keep global illumination (off: the direct-lighting tracer).
    pub global_illumination: bool,
    /// Keep random walks through translucent objects (off: their materials
    /// act as plain surfaces).
    pub subsurface: bool,
}

impl Default for EffectToggles {
    fn default() -> Self {
        Self {
            shadows: true,
            reflection: true,
            refraction: true,
            ambient_occlusion: true,
            global_illumination: true,
            subsurface: true,
        }
    }
}

impl EffectPlan {
    /// The effects a render asks for: `effects`, in a scene with `lights`
    /// and `ambient` light whose objects use `used_materials` (a material no
    /// object uses asks for nothing).
    pub fn new<'m>(
        lights: &[Light],
        ambient: Color,
        effects: &Effects,
        used_materials: impl IntoIterator<Item = &'m Material>,
    ) -> Self {
        let global_illumination = effects.global_illumination;
        let shading = !lights.is_empty() || global_illumination.is_some();
        let (mut reflects, mut refracts, mut translucent) = (false, false, false);
        for m in used_materials {
            reflects |= m.reflects_sharply();
            refracts |= m.refracts_sharply();
            translucent |= m.subsurface.is_some();
        }
        let recursion = shading && effects.max_depth > 0;
        Self {
            shading,
            shadows: shading && lights.iter().any(|l| l.shadows),
            reflection: recursion && reflects,
            refraction: recursion && refracts,
            ambient_occlusion: effects.ambient_occlusion.filter(|_| shading && ambient != Color::ZERO),
            max_depth: if recursion { effects.max_depth } else { 0 },
            global_illumination,
            subsurface: translucent && global_illumination.is_some(),
        }
    }

    /// This plan without the effects `toggles` switches off.
    pub fn restricted(self, toggles: EffectToggles) -> Self {
        Self {
            shadows: self.shadows && toggles.shadows,
            reflection: self.reflection && toggles.reflection,
            refraction: self.refraction && toggles.refraction,
            ambient_occlusion: self.ambient_occlusion.filter(|_| toggles.ambient_occlusion),
            global_illumination: self.global_illumination.filter(|_| toggles.global_illumination),
            subsurface: self.subsurface && toggles.subsurface && toggles.global_illumination,
            ..self
        }
    }
}

/// How many rays of each kind a render cast.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays: width × height × samples per pixel.
    pub primary: u64,
    /// Rays towards light samples.
    pub shadow: u64,
    /// Mirror and Fresnel reflection rays.
    pub reflection: u64,
    /// Rays refracted into or out of transparent objects.
    pub refraction: u64,
    /// Ambient-occlusion rays.
    pub ambient_occlusion: u64,
    /// Global illumination: rays that carry a path on from a surface, in a
    /// direction its BSDF chose.
    pub bounce: u64,
    /// Global illumination: shadow rays towards sampled points on lights
    /// (next-event estimation).
    pub next_event: u64,
    /// Random walks: rays cast inside translucent objects, from one
    /// scattering event (or the point of entry) to the next event or the
    /// surface.
    pub subsurface: u64,
    /// Random walks: scattering events inside translucent objects (not
    /// rays; each is followed by one `subsurface` ray).
    pub walk_steps: u64,
}

impl RayCounts {
    /// All rays together.
    pub fn total(&self) -> u64 {
        self.primary
            + self.shadow
            + self.reflection
            + self.refraction
            + self.ambient_occlusion
            + self.bounce
            + self.next_event
            + self.subsurface
    }
}

impl Add for RayCounts {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            primary: self.primary + o.primary,
            shadow: self.shadow + o.shadow,
            reflection: self.reflection + o.reflection,
            refraction: self.refraction + o.refraction,
            ambient_occlusion: self.ambient_occlusion + o.ambient_occlusion,
            bounce: self.bounce + o.bounce,
            next_event: self.next_event + o.next_event,
            subsurface: self.subsurface + o.subsurface,
            walk_steps: self.walk_steps + o.walk_steps,
        }
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl std::iter::Sum for RayCounts {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::default(), Add::add)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn plan(lights: &str, materials: &str, extra: &str) -> EffectPlan {
        let text = format!(
            r#"(
            camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
            image: (width: 4, height: 4),
            materials: {{ "m": (color: (1, 1, 1), {materials}) }},
            objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "m") ],
            lights: [ {lights} ],
            {extra}
        )"#
        );
        let l = crate::parse_scene(&text, "t.ron", Path::new(".")).unwrap();
        l.scene.effect_plan(&l.settings.effects)
    }

    #[test]
    fn a_scene_without_lights_plans_pure_ray_casting_whatever_its_materials() {
        let p = plan(
            "",
            "reflectivity: 0.5, transparency: 0.5",
            "ambient: (1, 1, 1), effects: (ambient_occlusion: (samples: 4, radius: 1)),",
        );
        assert_eq!(
            p,
            EffectPlan {
                shading: false,
                shadows: false,
                reflection: false,
                refraction: false,
                ambient_occlusion: None,
                max_depth: 0,
                global_illumination: None,
                subsurface: false,
            }
        );
    }

    #[test]
    fn each_effect_is_planned_only_with_what_it_needs() {
        let light = "Point(position: (0, 5, 0))";
        let p = plan(light, "", "");
        assert!(p.shading && p.shadows && !p.reflection && !p.refraction && p.ambient_occlusion.is_none());
        assert!(!plan("Point(position: (0, 5, 0), shadows: false)", "", "").shadows);
        let glass = plan(light, "transparency: 0.9", "");
        assert!(
            glass.reflection && glass.refraction && glass.max_depth == 5,
            "glass also reflects (Fresnel)"
        );
        assert!(!plan(light, "reflectivity: 0.9", "effects: (max_depth: 0),").reflection);
        let ao = "effects: (ambient_occlusion: (samples: 4, radius: 1)),";
        assert!(plan(light, "", ao).ambient_occlusion.is_none(), "no ambient light to darken");
        assert!(plan(light, "", &format!("ambient: (0.1, 0.1, 0.1), {ao}")).ambient_occlusion.is_some());
    }

    #[test]
    fn toggles_switch_effects_off_but_never_on() {
        let all = plan(
            "Point(position: (0, 5, 0))",
            "transparency: 0.9",
            "ambient: (0.1, 0.1, 0.1), effects: (ambient_occlusion: (samples: 4, radius: 1)),",
        );
        let none = EffectToggles {
            shadows: false,
            reflection: false,
            refraction: false,
            ambient_occlusion: false,
            global_illumination: false,
            subsurface: false,
        };
        let off = all.restricted(none);
        assert!(
            off.shading
                && !off.shadows
                && !off.reflection
                && !off.refraction
                && off.ambient_occlusion.is_none()
        );
        assert_eq!(all.restricted(EffectToggles::default()), all);
        let flat = plan("Point(position: (0, 5, 0), shadows: false)", "", "");
        assert_eq!(flat.restricted(EffectToggles::default()), flat, "nothing is added");
    }
}
