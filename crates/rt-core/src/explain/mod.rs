//! A pixel's light path, explained: the record of everything the renderer
//! computed for one sample of one pixel (the camera, the view plane, the
//! pixel's 3D point, every ray, hit and contribution, and the course's tests
//! on each hit), for `rt-view explain` and the viewer's scene view.
//!
//! - [`record`]: the data ([`record::PathRecord`]), serialisable as JSON;
//! - [`recorder`]: the hook the integrators call as they compute a sample
//!   ([`recorder::Recorder`]; [`recorder::NoRecorder`] for renders);
//! - [`path_recorder`]: the recorder that writes a record.
//!
//! [`crate::Renderer::record_sample`] runs one sample with a
//! [`path_recorder::PathRecorder`].

pub mod path_recorder;
pub mod record;
pub mod recorder;
