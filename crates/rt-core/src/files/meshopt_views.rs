//! glTF buffer views compressed with `EXT_meshopt_compression`, decoded
//! with meshoptimizer (the `meshopt` crate) so the loader reads them as any
//! other buffer view.
//!
//! **The extension** (Khronos' `EXT_meshopt_compression` specification): a
//! buffer view's data is replaced by a compressed stream elsewhere (its
//! extension object's `buffer`, `byteOffset`, `byteLength`) that decodes to
//! `count` elements of `byteStride` bytes, by `mode` — `ATTRIBUTES`
//! (vertex data, `meshopt_decodeVertexBuffer`), `TRIANGLES` (an index
//! buffer, `meshopt_decodeIndexBuffer`) or `INDICES` (any index sequence,
//! `meshopt_decodeIndexSequence`) — then undone by `filter`: `NONE`,
//! `OCTAHEDRAL` (unit vectors), `QUATERNION`, `EXPONENTIAL` or `COLOR`. The
//! view's own buffer is usually a *fallback* buffer (extension object
//! `fallback: true`) with no data at all.
//!
//! **How.** Before the document is validated, [`redirect`] points each
//! compressed view at a new, empty buffer of its own (offset 0) and empties
//! the fallback buffers, so the `gltf` crate neither looks for their data
//! nor refuses them; once the buffers are read, [`decode`] fills each new
//! buffer with its view's decoded bytes. Everything after reads decoded
//! data through the ordinary checks (accessor bounds, index ranges).
//!
//! **Bad input.** meshoptimizer's decoders are written to be safe on
//! untrusted input (they return an error, or garbage that the loader's
//! checks catch), but they *assert* their size arguments, which would abort
//! the process: every stride, count and filter combination the
//! specification forbids is refused first, with the view named, and the
//! decoded sizes are bounded by [`MAX_DECODED_BYTES`].

use std::ffi::c_void;

use ::gltf::json::{Index, Root, Value, buffer::Buffer, validation::USize64};

/// Most bytes all of a file's compressed views may decode to together:
/// 2 GiB, the limit on a glTF file itself.
pub const MAX_DECODED_BYTES: u64 = 1 << 31;

/// The extension's name, as it appears in `extensionsUsed` and in buffers'
/// and buffer views' extension objects.
pub const EXTENSION: &str = "EXT_meshopt_compression";

/// An empty buffer, as a data URI the `gltf` crate reads without a file.
const EMPTY: &str = "data:application/octet-stream;base64,";

/// How a view's stream decodes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

/// What is undone after decoding.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

/// One compressed buffer view, checked: where its stream is, what it
/// decodes to, and the buffer [`redirect`] made for the decoded bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedView {
    view: usize,
    source: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
    target: usize,
}

/// Points every compressed buffer view of `json` at a new empty buffer and
/// empties the fallback buffers; returns the views to [`decode`] once the
/// buffers are read. An extension object that breaks the specification's
/// rules is an error naming the buffer view.
pub fn redirect(json: &mut Root) -> Result<Vec<CompressedView>, String> {
    let buffers = json.buffers.len();
    let mut views = Vec::new();
    let mut total = 0u64;
    for (k, view) in json.buffer_views.iter().enumerate() {
        let Some(ext) = view.extensions.as_ref().and_then(|e| e.others.get(EXTENSION)) else { continue };
        let at = |reason: String| format!("buffer view {k} ({EXTENSION}): {reason}");
        let number = |key: &str, default: Option<u64>| {
            ext.get(key)
                .map_or(default, Value::as_u64)
                .ok_or_else(|| at(format!("its {key} is missing or not a count")))
        };
        let text = |key: &str, default: &'static str| ext.get(key).map_or(Some(default), Value::as_str);
        let source = number("buffer", None)?;
        let (offset, length) = (number("byteOffset", Some(0))?, number("byteLength", None)?);
        let (stride, count) = (number("byteStride", None)?, number("count", None)?);
        if source >= buffers as u64 {
            return Err(at(format!("its buffer {source} does not exist")));
        }
        let mode = match text("mode", "") {
            Some("ATTRIBUTES") => Mode::Attributes,
            Some("TRIANGLES") => Mode::Triangles,
            Some("INDICES") => Mode::Indices,
            other => return Err(at(format!("its mode {other:?} is not ATTRIBUTES, TRIANGLES or INDICES"))),
        };
        let filter = match text("filter", "NONE") {
            Some("NONE") => Filter::None,
            Some("OCTAHEDRAL") => Filter::Octahedral,
            Some("QUATERNION") => Filter::Quaternion,
            Some("EXPONENTIAL") => Filter::Exponential,
            Some("COLOR") => Filter::Color,
            other => return Err(at(format!("its filter {other:?} is not one the extension defines"))),
        };
        // The specification's rules, which meshoptimizer asserts.
        let stride_ok = match mode {
            Mode::Attributes => stride % 4 == 0 && (4..=256).contains(&stride),
            Mode::Triangles | Mode::Indices => stride == 2 || stride == 4,
        };
        if !stride_ok {
            return Err(at(format!("byteStride {stride} is not allowed in mode {mode:?}")));
        }
        if mode == Mode::Triangles && count % 3 != 0 {
            return Err(at(format!("count {count} of a TRIANGLES view is not a multiple of 3")));
        }
        let filter_ok = match filter {
            Filter::None => true,
            Filter::Octahedral | Filter::Color => mode == Mode::Attributes && (stride == 4 || stride == 8),
            Filter::Quaternion => mode == Mode::Attributes && stride == 8,
            Filter::Exponential => mode == Mode::Attributes,
        };
        if !filter_ok {
            return Err(at(format!(
                "filter {filter:?} does not apply to byteStride {stride} in mode {mode:?}"
            )));
        }
        let size = stride.checked_mul(count).filter(|&s| s == view.byte_length.0);
        let Some(size) = size else {
            return Err(at(format!(
                "{count} elements of {stride} bytes do not fill the view's byteLength {}",
                view.byte_length.0
            )));
        };
        total = total.saturating_add(size);
        if total > MAX_DECODED_BYTES {
            return Err(at(format!("the compressed views decode to more than {MAX_DECODED_BYTES} bytes")));
        }
        let as_usize = |v: u64| usize::try_from(v).map_err(|_| at(format!("{v} is too large")));
        views.push(CompressedView {
            view: k,
            source: as_usize(source)?,
            offset: as_usize(offset)?,
            length: as_usize(length)?,
            stride: as_usize(stride)?,
            count: as_usize(count)?,
            mode,
            filter,
            target: buffers + views.len(),
        });
    }
    for buffer in &mut json.buffers {
        let fallback = buffer
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXTENSION))
            .and_then(|e| e.get("fallback"))
            .and_then(Value::as_bool)
            .unwrap_or(false);
        if fallback {
            buffer.uri = Some(EMPTY.into());
            buffer.byte_length = USize64(0);
        }
    }
    for v in &views {
        json.buffers.push(Buffer {
            byte_length: USize64(0),
            name: None,
            uri: Some(EMPTY.into()),
            extensions: None,
            extras: Default::default(),
        });
        let view = &mut json.buffer_views[v.view];
        view.buffer = Index::new(v.target as u32);
        view.byte_offset = None;
    }
    Ok(views)
}

/// Decodes each of `views` from `buffers` (the file's buffers as read, with
/// the empty ones [`redirect`] added) into the buffer made for it. A stream
/// outside its buffer, or one meshoptimizer cannot decode, is an error
/// naming the buffer view.
pub fn decode(views: &[CompressedView], buffers: &mut [::gltf::buffer::Data]) -> Result<(), String> {
    for v in views {
        let at = |reason: &str| format!("buffer view {} ({EXTENSION}): {reason}", v.view);
        let source = buffers
            .get(v.source)
            .and_then(|b| b.0.get(v.offset..v.offset.checked_add(v.length)?))
            .ok_or_else(|| {
            at("its compressed data runs past the end of its buffer (a truncated file?)")
        })?;
        let size = v.count * v.stride; // Checked against the view's byteLength by `redirect`.
        // u32 words: the decoders and filters write 16- and 32-bit values.
        let mut words = vec![0u32; size.div_ceil(4)];
        let out = words.as_mut_ptr().cast::<c_void>();
        // SAFETY: `out` holds `count·stride` bytes, aligned for every
        // component type; `source` is a live slice read for its length; the
        // sizes meet each function's asserted preconditions (checked in
        // `redirect`). The decoders are specified safe on untrusted data.
        let code = unsafe {
            match v.mode {
                Mode::Attributes => meshopt::ffi::meshopt_decodeVertexBuffer(
                    out,
                    v.count,
                    v.stride,
                    source.as_ptr(),
                    source.len(),
                ),
                Mode::Triangles => meshopt::ffi::meshopt_decodeIndexBuffer(
                    out,
                    v.count,
                    v.stride,
                    source.as_ptr(),
                    source.len(),
                ),
                Mode::Indices => meshopt::ffi::meshopt_decodeIndexSequence(
                    out,
                    v.count,
                    v.stride,
                    source.as_ptr(),
                    source.len(),
                ),
            }
        };
        if code != 0 {
            return Err(at(&format!("meshoptimizer cannot decode it (error {code}): a damaged file?")));
        }
        // SAFETY: as above; each filter's stride was checked in `redirect`.
        unsafe {
            match v.filter {
                Filter::None => {}
                Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct(out, v.count, v.stride),
                Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat(out, v.count, v.stride),
                Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp(out, v.count, v.stride),
                Filter::Color => meshopt::ffi::meshopt_decodeFilterColor(out, v.count, v.stride),
            }
        }
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_ne_bytes()).take(size).collect();
        let target = buffers.get_mut(v.target).ok_or_else(|| at("its decoded buffer is missing"))?;
        target.0 = bytes;
    }
    Ok(())
}
