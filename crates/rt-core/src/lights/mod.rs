//! Where light comes from, all through one interface
//! ([`light_source::LightSource`]): the scene file's point, spot, directional and
//! sphere [`light`]s, emissive objects ([`emitter`]), the [`environment`];
//! and the choice of one to sample ([`light_sampler`]).

pub mod distribution;
pub mod emitter;
pub mod environment;
pub mod environment_map;
pub mod light;
pub mod light_sampler;
pub mod light_source;
pub mod sky;
pub mod sun;
