//! ABI version 1: every type and constant that crosses the plugin library boundary.
//!
//! Rules (DESIGN §5): only `#[repr(C)]` plain data and `extern "C"` function pointers; enums
//! travel as `u32` and are checked by the receiver, booleans as `u8`; strings are UTF-8 byte
//! ranges ([`AbiStr`]), never NUL-terminated and never owned across the boundary. A minor
//! version only appends fields at the end of a struct that carries its own `struct_size`
//! ([`PluginHeader`], [`SceneInput`]); anything else is a new major version. The layout of every
//! type here is snapshot-tested (`sdk/tests/abi_layout.rs`), so an accidental change fails.
//!
//! Ownership: the plugin owns its header, descriptors and instance (freed only by its
//! `destroy`); the host owns every input and every output buffer (the image, the mesh buffers
//! and the error message buffer) and the plugin only writes into them during a call.
//!
//! The lens travels as our XML text (`docs/formats.md`; written by
//! [`crate::io::write_xml`], read back losslessly by [`crate::io::parse_olf_xml`]): the format is
//! already versioned and documented, carries every field of the model (aspheres, coatings,
//! catalogue glasses), and a C plugin can parse it with any XML reader.

pub mod layout;

use std::ffi::c_void;

/// The first eight bytes of every header.
pub const MAGIC: [u8; 8] = *b"FLAREPLG";
/// ABI major version: a plugin with another major is refused.
pub const ABI_MAJOR: u32 = 1;
/// ABI minor version: fields appended to [`PluginHeader`] or [`SceneInput`] since 1.0.
pub const ABI_MINOR: u32 = 0;
/// Name of the one exported entry symbol, of type [`EntryFn`].
pub const ENTRY_SYMBOL: &str = "flarebench_plugin_v1";
/// The sdk version a plugin was built against (diagnostics only).
pub const SDK_VERSION: &str = env!("CARGO_PKG_VERSION");
/// `rustc --version` of the compiler that built the sdk (diagnostics only).
pub const RUSTC_VERSION: &str = env!("FLAREBENCH_RUSTC_VERSION");

/// The entry symbol: returns the plugin's header, which must stay valid and unchanged for as
/// long as the library is loaded (the host never unloads it). Null means the plugin could not
/// describe itself.
pub type EntryFn = unsafe extern "C" fn() -> *const PluginHeader;

/// Status codes returned by every call (`u32`).
pub mod status {
    /// Success.
    pub const OK: u32 = 0;
    /// The plugin reported an error; the message buffer says why.
    pub const ERROR: u32 = 1;
    /// The plugin panicked; the panic was caught at the boundary and the message says where.
    /// The instance must not be used again (only destroyed).
    pub const PANIC: u32 = 2;
    /// A pointer or value passed to the plugin was invalid (null, wrong size, out of range).
    pub const INVALID_ARGUMENT: u32 = 3;
    /// The host's mesh buffers are too small: `vertex_count` and `triangle_count` of
    /// [`super::MeshBuffer`] hold the sizes needed; the host may call again with larger ones.
    pub const MESH_CAPACITY: u32 = 4;
}

/// What a plugin draws (`u32` in [`PluginHeader::kind`]).
pub mod kind {
    /// Ghosts (internal reflections).
    pub const GHOSTS: u32 = 0;
    /// A diffraction starburst.
    pub const STARBURST: u32 = 1;
    /// Anything else (a whole flare, an example).
    pub const OTHER: u32 = 2;
}

/// The type of a parameter (`u32` in [`ParamDesc::kind`]); every value travels as `f64`.
pub mod param_kind {
    /// A real number in `[min, max]`.
    pub const FLOAT: u32 = 0;
    /// A whole number in `[min, max]`.
    pub const INT: u32 = 1;
    /// 0 or 1.
    pub const BOOL: u32 = 2;
    /// An index into the `|`-separated [`super::ParamDesc::choices`].
    pub const CHOICE: u32 = 3;
}

/// The shape of the stop (`u32` in [`ApertureInput::kind`]).
pub mod aperture_kind {
    /// The unit circle.
    pub const CIRCULAR: u32 = 0;
    /// An iris of `blades` blades (`crate::aperture::Aperture::Iris`).
    pub const IRIS: u32 = 1;
}

/// A borrowed UTF-8 string: `len` bytes at `ptr` (null only when `len` is 0). Not
/// NUL-terminated.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbiStr {
    pub ptr: *const u8,
    pub len: usize,
}

impl AbiStr {
    /// An empty string.
    pub const EMPTY: AbiStr = AbiStr {
        ptr: std::ptr::null(),
        len: 0,
    };

    /// Borrows `s` (the caller keeps `s` alive for as long as the `AbiStr` is used).
    pub fn new(s: &str) -> AbiStr {
        AbiStr {
            ptr: s.as_ptr(),
            len: s.len(),
        }
    }
}

/// The plugin's description of itself, returned by the entry symbol.
///
/// The first four fields (`magic`, `abi_major`, `abi_minor`, `struct_size`: 20 bytes) are the
/// same in every ABI version; the host reads them first and reads the rest only when the major
/// matches and `struct_size` covers it.
#[repr(C)]
#[derive(Debug)]
pub struct PluginHeader {
    /// [`MAGIC`].
    pub magic: [u8; 8],
    /// [`ABI_MAJOR`] of the sdk the plugin was built with.
    pub abi_major: u32,
    /// [`ABI_MINOR`] of the sdk the plugin was built with.
    pub abi_minor: u32,
    /// `size_of::<PluginHeader>()` as the plugin was built (bytes); at least the 1.0 size.
    pub struct_size: u32,
    /// 1 when the plugin was built with `panic = "unwind"` (its panics can be caught), 0 for
    /// `panic = "abort"` (a panic would end the host: the host refuses such a plugin).
    pub panic_unwind: u8,
    /// Zero.
    pub reserved: [u8; 3],
    /// Sdk version and `rustc --version` (diagnostics only).
    pub sdk_version: AbiStr,
    pub rustc_version: AbiStr,
    /// Short unique name (`ghost-raytrace`): letters, digits, `-`, `_`.
    pub name: AbiStr,
    /// The plugin's own version.
    pub version: AbiStr,
    /// One line saying what it does.
    pub description: AbiStr,
    /// A [`kind`] constant.
    pub kind: u32,
    /// Number of parameter descriptors at `params`.
    pub param_count: u32,
    pub params: *const ParamDesc,
    /// Creates an instance into `*instance`.
    pub create:
        Option<unsafe extern "C" fn(instance: *mut *mut c_void, error: *mut ErrorBuf) -> u32>,
    /// Frees an instance made by `create` (null is ignored).
    pub destroy: Option<unsafe extern "C" fn(instance: *mut c_void)>,
    /// Prepares an instance for a lens (called before the first render and when the lens
    /// changes).
    pub prepare: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            lens: *const LensInput,
            error: *mut ErrorBuf,
        ) -> u32,
    >,
    /// Renders a scene with parameter values (one `f64` per descriptor, in order) into the
    /// host's output buffers.
    pub render: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            scene: *const SceneInput,
            params: *const f64,
            param_count: u32,
            output: *mut RenderOutput,
            error: *mut ErrorBuf,
        ) -> u32,
    >,
}

/// One parameter a plugin takes.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ParamDesc {
    /// `key` in `--algo NAME:key=value`.
    pub name: AbiStr,
    /// One line for `--help`-like listings, with the unit.
    pub help: AbiStr,
    /// A [`param_kind`] constant.
    pub kind: u32,
    /// Zero.
    pub reserved: u32,
    /// Range (inclusive) and default; for a choice, `0..=count-1`.
    pub min: f64,
    pub max: f64,
    pub default: f64,
    /// For [`param_kind::CHOICE`], the names separated by `|`; else empty.
    pub choices: AbiStr,
}

/// A host-owned buffer for an error message: the plugin writes up to `capacity` bytes of UTF-8
/// at `ptr` and sets `len`.
#[repr(C)]
#[derive(Debug)]
pub struct ErrorBuf {
    pub ptr: *mut u8,
    pub capacity: usize,
    pub len: usize,
}

/// The lens: our XML text.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LensInput {
    pub xml: AbiStr,
}

/// A light at infinity.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightInput {
    /// Angle to the optical axis and azimuth about it (degrees).
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Irradiance perpendicular to the beam (image units per mm² of entrance pupil).
    pub intensity: f64,
    /// Blackbody temperature (K); 0 for daylight D65.
    pub kelvin: f64,
}

/// The stop's shape.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ApertureInput {
    /// An [`aperture_kind`] constant.
    pub kind: u32,
    /// Iris blades (≥ 3 for an iris).
    pub blades: u32,
    /// Iris rotation (radians) and blade roundness (0 straight … 1 circle).
    pub rotation_rad: f64,
    pub roundness: f64,
}

/// What to render: lights, frame and aperture.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct SceneInput {
    /// `size_of::<SceneInput>()` as the host was built (bytes).
    pub struct_size: u32,
    pub light_count: u32,
    pub lights: *const LightInput,
    /// Output size (pixels) and the part of the sensor it shows (mm, centred on the axis).
    pub width: u32,
    pub height: u32,
    pub film_width_mm: f64,
    pub film_height_mm: f64,
    pub aperture: ApertureInput,
}

/// A host-allocated linear HDR image: `width × height` pixels of 3 `f32` (linear sRGB),
/// row-major, row 0 at the top, zeroed before the call. The plugin adds its flare into it.
#[repr(C)]
#[derive(Debug)]
pub struct ImageBuffer {
    pub pixels: *mut f32,
    pub width: u32,
    pub height: u32,
}

/// A mesh vertex: position in pixels (x right, y down) and linear RGB radiance per pixel².
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshVertex {
    pub x: f32,
    pub y: f32,
    pub rgb: [f32; 3],
}

/// Host-allocated buffers for an optional triangle mesh the host rasterizes (exactly, with the
/// colour interpolated linearly) and adds to the image. Capacities 0 mean the host wants no
/// mesh. The plugin sets the counts.
#[repr(C)]
#[derive(Debug)]
pub struct MeshBuffer {
    pub vertices: *mut MeshVertex,
    pub vertex_capacity: u32,
    pub vertex_count: u32,
    /// Three vertex indices per triangle.
    pub triangles: *mut [u32; 3],
    pub triangle_capacity: u32,
    pub triangle_count: u32,
}

/// Everything a render writes.
#[repr(C)]
#[derive(Debug)]
pub struct RenderOutput {
    pub image: ImageBuffer,
    pub mesh: MeshBuffer,
    /// Ghosts (or sprites, spikes …) the plugin drew, for reports.
    pub items_drawn: u32,
    /// Zero.
    pub reserved: u32,
}
