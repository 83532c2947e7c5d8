//! The part of OIDN's C API that denoising one image needs, declared by
//! hand and resolved from the library at run time.
//!
//! Declarations after OIDN 2.x's public header
//! `include/OpenImageDenoise/oidn.h` (RenderKit/oidn, checked against the
//! symbols that `libOpenImageDenoise.so.2` 2.5.1 exports):
//!
//! ```c
//! OIDNDevice oidnNewDevice(OIDNDeviceType type);          // OIDN_DEVICE_TYPE_CPU = 1
//! void       oidnCommitDevice(OIDNDevice device);
//! OIDNError  oidnGetDeviceError(OIDNDevice device, const char** outMessage); // OIDN_ERROR_NONE = 0
//! void       oidnReleaseDevice(OIDNDevice device);
//! OIDNFilter oidnNewFilter(OIDNDevice device, const char* type);            // "RT"
//! void       oidnSetSharedFilterImage(OIDNFilter filter, const char* name, void* devPtr,
//!                                     OIDNFormat format,                     // OIDN_FORMAT_FLOAT3 = 3
//!                                     size_t width, size_t height, size_t byteOffset,
//!                                     size_t bytePixelStride, size_t byteRowStride);
//! void       oidnSetFilterBool(OIDNFilter filter, const char* name, bool value);
//! void       oidnCommitFilter(OIDNFilter filter);
//! void       oidnExecuteFilter(OIDNFilter filter);
//! void       oidnReleaseFilter(OIDNFilter filter);
//! ```
//!
//! The enums are C `int`s. Images are shared, not copied: OIDN reads and
//! writes the caller's `[f32; 3]` pixels (a [`Color`] is three `f32`s,
//! `#[repr(C)]`) while `oidnExecuteFilter` runs, which returns when done.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use libloading::Library;
use rt_core::Color;

/// `OIDN_DEVICE_TYPE_CPU`.
const DEVICE_TYPE_CPU: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;
/// `OIDN_ERROR_NONE`.
const ERROR_NONE: c_int = 0;

type Handle = *mut c_void;

/// The library's entry points (function pointers resolved at load time;
/// valid while the [`Library`] they came from is loaded).
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    get_device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> c_int,
    release_device: unsafe extern "C" fn(Handle),
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    set_shared_filter_image:
        unsafe extern "C" fn(Handle, *const c_char, *mut c_void, c_int, usize, usize, usize, usize, usize),
    set_filter_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// A CPU device, made once and kept: making one starts OIDN's thread pool,
/// which costs more than denoising a small image.
struct Device(Handle);

// SAFETY: an OIDN device may be used from any thread (OIDN's API
// documentation: devices and filters are thread-safe objects, calls on one
// filter must not overlap); every use goes through `Oidn::device`'s mutex.
unsafe impl Send for Device {}

/// OIDN, loaded.
pub struct Oidn {
    api: Api,
    device: Mutex<Option<Device>>,
    path: PathBuf,
    // Last: dropped after everything that calls into it.
    _library: Library,
}

impl std::fmt::Debug for Oidn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Oidn").field("path", &self.path).finish_non_exhaustive()
    }
}

/// Why denoising failed: OIDN's own message.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum DenoiseError {
    /// OIDN reported an error (its code and message).
    #[error("OIDN: {message} (error {code})")]
    Oidn {
        /// `OIDNError`.
        code: i32,
        /// What OIDN said.
        message: String,
    },
    /// The images do not have `width × height` pixels each.
    #[error("denoise: {0}")]
    Size(String),
}

/// The images that go into the "RT" filter besides the colour: the
/// auxiliary features, each `width × height` pixels, row-major.
#[derive(Clone, Copy, Debug, Default)]
pub struct AuxImages<'a> {
    /// The albedo, in [0, 1].
    pub albedo: Option<&'a [Color]>,
    /// The normal, components in [−1, 1] (needs the albedo too: OIDN
    /// takes a normal only beside an albedo).
    pub normal: Option<&'a [Color]>,
}

impl Oidn {
    /// Loads the library at `path` (a path, or a bare name for the system's
    /// search path) and resolves the entry points; the loader's message
    /// when it cannot.
    pub fn load(path: &Path) -> Result<Self, String> {
        // SAFETY: loading runs the library's initialisers; OIDN's are its
        // C++ static constructors, which do not depend on the caller.
        let library = unsafe { Library::new(path) }.map_err(|e| e.to_string())?;
        // SAFETY: each symbol is declared with the signature of OIDN 2.x's
        // header (module docs); the pointers stay valid while `library`
        // does, and `Oidn` keeps it.
        let api = unsafe {
            macro_rules! get {
                ($name:literal) => {
                    *library.get(concat!($name, "\0").as_bytes()).map_err(|e| e.to_string())?
                };
            }
            Api {
                new_device: get!("oidnNewDevice"),
                commit_device: get!("oidnCommitDevice"),
                get_device_error: get!("oidnGetDeviceError"),
                release_device: get!("oidnReleaseDevice"),
                new_filter: get!("oidnNewFilter"),
                set_shared_filter_image: get!("oidnSetSharedFilterImage"),
                set_filter_bool: get!("oidnSetFilterBool"),
                commit_filter: get!("oidnCommitFilter"),
                execute_filter: get!("oidnExecuteFilter"),
                release_filter: get!("oidnReleaseFilter"),
            }
        };
        Ok(Self { api, device: Mutex::new(None), path: path.to_owned(), _library: library })
    }

    /// Where the library was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The first error OIDN holds for `device` (null: the last device
    /// creation's), cleared by asking.
    fn error(&self, device: Handle) -> Result<(), DenoiseError> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: `device` is null or a live device; OIDN writes a pointer
        // to a NUL-terminated string it owns (or leaves it null).
        let code = unsafe { (self.api.get_device_error)(device, &mut message) };
        if code == ERROR_NONE {
            return Ok(());
        }
        let message = if message.is_null() {
            "no message".to_owned()
        } else {
            // SAFETY: as above; copied before any other OIDN call.
            unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
        };
        Err(DenoiseError::Oidn { code, message })
    }

    /// The denoised `color` (linear HDR radiance, `width × height` pixels,
    /// row-major), by the "RT" filter with `hdr` on and `aux` as its
    /// auxiliary images. Blocks while OIDN runs (on all cores).
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[Color],
        aux: AuxImages,
    ) -> Result<Vec<Color>, DenoiseError> {
        let pixels = width as usize * height as usize;
        for (name, image) in [("colour", Some(color)), ("albedo", aux.albedo), ("normal", aux.normal)] {
            if let Some(image) = image
                && image.len() != pixels
            {
                return Err(DenoiseError::Size(format!(
                    "{name} has {} pixels, not {width}×{height}",
                    image.len()
                )));
            }
        }
        if aux.normal.is_some() && aux.albedo.is_none() {
            return Err(DenoiseError::Size("a normal needs an albedo beside it".into()));
        }
        if pixels == 0 {
            return Ok(Vec::new());
        }
        let mut output = vec![Color::ZERO; pixels];
        let mut device = self.device.lock().unwrap_or_else(|e| e.into_inner());
        if device.is_none() {
            // SAFETY: plain constructor calls; errors are read back.
            let d = unsafe { (self.api.new_device)(DEVICE_TYPE_CPU) };
            if d.is_null() {
                self.error(std::ptr::null_mut())?;
                return Err(DenoiseError::Oidn { code: -1, message: "no CPU device".into() });
            }
            // SAFETY: `d` is a live device.
            unsafe { (self.api.commit_device)(d) };
            if let Err(e) = self.error(d) {
                // SAFETY: released once, not used again.
                unsafe { (self.api.release_device)(d) };
                return Err(e);
            }
            *device = Some(Device(d));
        }
        let d = device.as_ref().expect("made above").0;
        let name = |s: &str| CString::new(s).expect("no NUL");
        // SAFETY: `d` is a live, committed device; the filter is released
        // before returning; each shared image points at `pixels` `[f32; 3]`s
        // that outlive the call (`color` and the aux images are only read:
        // OIDN does not write its inputs), and `output` is the only one
        // written.
        unsafe {
            let filter = (self.api.new_filter)(d, name("RT").as_ptr());
            if filter.is_null() {
                self.error(d)?;
                return Err(DenoiseError::Oidn { code: -1, message: "no RT filter".into() });
            }
            let set = |n: &str, image: *const Color| {
                (self.api.set_shared_filter_image)(
                    filter,
                    name(n).as_ptr(),
                    image as *mut c_void,
                    FORMAT_FLOAT3,
                    width as usize,
                    height as usize,
                    0,
                    0,
                    0,
                )
            };
            set("color", color.as_ptr());
            if let Some(albedo) = aux.albedo {
                set("albedo", albedo.as_ptr());
            }
            if let Some(normal) = aux.normal {
                set("normal", normal.as_ptr());
            }
            set("output", output.as_mut_ptr());
            (self.api.set_filter_bool)(filter, name("hdr").as_ptr(), true);
            (self.api.commit_filter)(filter);
            let committed = self.error(d);
            if committed.is_ok() {
                (self.api.execute_filter)(filter);
            }
            let executed = committed.and_then(|()| self.error(d));
            (self.api.release_filter)(filter);
            executed?;
        }
        Ok(output)
    }
}

impl Drop for Oidn {
    fn drop(&mut self) {
        if let Some(Device(d)) = self.device.get_mut().unwrap_or_else(|e| e.into_inner()).take() {
            // SAFETY: the device is live and no filter of it is.
            unsafe { (self.api.release_device)(d) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::denoise::library::find_and_load;

    /// A grey image with noise of ±`amount` from a fixed hash.
    fn noisy(width: u32, height: u32, amount: f32) -> Vec<Color> {
        (0..width * height)
            .map(|i| {
                let h = (i.wrapping_mul(0x9E37_79B9) ^ (i >> 3)).wrapping_mul(0x85EB_CA6B);
                Color::splat(0.5 + amount * ((h >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0))
            })
            .collect()
    }

    #[test]
    fn denoising_a_noisy_flat_image_flattens_it_or_the_library_is_clearly_absent() {
        match find_and_load() {
            Err(e) => {
                // Not installed: the message names the places and the fix.
                let text = e.to_string();
                assert!(
                    text.starts_with("OIDN not found (looked in ") && text.ends_with("scripts/get_oidn.sh")
                );
                eprintln!("OIDN absent, checked its message: {text}");
            }
            Ok(oidn) => {
                let (w, h) = (48, 32);
                let color = noisy(w, h, 0.3);
                let albedo = vec![Color::splat(0.8); color.len()];
                let normal = vec![Color::new(0.0, 0.0, -1.0); color.len()];
                // Root-mean-square distance from the flat grey.
                let spread = |img: &[Color]| {
                    (img.iter().map(|c| (c.x - 0.5).powi(2)).sum::<f32>() / img.len() as f32).sqrt()
                };
                for aux in [AuxImages::default(), AuxImages { albedo: Some(&albedo), normal: Some(&normal) }]
                {
                    let out = oidn.denoise(w, h, &color, aux).unwrap();
                    assert!(spread(&out) < spread(&color) / 3.0, "{} → {}", spread(&color), spread(&out));
                }
                // Wrong sizes are refused before OIDN sees them.
                assert!(matches!(
                    oidn.denoise(w, h, &color[1..], AuxImages::default()),
                    Err(DenoiseError::Size(_))
                ));
                let only_normal = AuxImages { albedo: None, normal: Some(&normal) };
                assert!(matches!(oidn.denoise(w, h, &color, only_normal), Err(DenoiseError::Size(_))));
            }
        }
    }
}
