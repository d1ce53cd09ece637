//! ABI version 1: every type and constant that crosses the plugin library boundary.
//!
//! Rules (docs/plugins.md §4): only `#[repr(C)]` plain data and `extern "C"` function pointers; enums
//! travel as `u32` and are checked by the receiver, booleans as `u8`; strings are UTF-8 byte
//! ranges ([`AbiStr`]), never NUL-terminated and never owned across the boundary. A minor
//! version only appends fields at the end of a struct that carries its own `struct_size`
//! ([`PluginHeader`], [`SceneInput`]); anything else is a new major version. The layout of every
//! type here is snapshot-tested (`sdk/tests/abi_layout.rs`), so an accidental change fails.
//!
//! Minor versions, both ways: a receiver reads an appended field only when the sender's
//! `struct_size` covers it (a shorter struct from an older sender means the older meaning),
//! and accepts a longer struct from a newer sender, ignoring what it does not know. The host
//! knows the plugin's minor from its header and refuses — with
//! `PluginCallError::Unsupported`, naming the plugin and its minor — to send a scene the
//! plugin's minor cannot express, rather than send one it would misread.
//!
//! - **1.0**: lights (D65 or blackbody), frame, circular or iris aperture.
//! - **1.1** appends to [`SceneInput`] an aperture mask image (`mask_width`, `mask_height`,
//!   `mask`, with [`aperture_kind::MASK`]) and `light_ext`, a parallel array of
//!   [`LightExt`] giving a light a spectrum that `kelvin` cannot say ([`light_spectrum`]:
//!   linear sRGB or equal energy). [`LightInput`] itself is unchanged — it is an array element,
//!   whose size no minor version may change; such a light's `kelvin` is
//!   [`KELVIN_SEE_EXT`] (negative), which a 1.0 reader refuses instead of rendering the light
//!   as daylight. [`LightExt`] has no `struct_size` either: a later minor that needs more per
//!   light appends another parallel array to [`SceneInput`].
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
/// ABI minor version: fields appended to [`PluginHeader`] or [`SceneInput`] since 1.0 (module
/// docs: 1.1 added the aperture mask and the light spectrum extension).
pub const ABI_MINOR: u32 = 1;
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
    /// Since 1.1: a transmission image over [-1, 1]² (`crate::aperture::ApertureMask`), in
    /// [`super::SceneInput::mask`]. A 1.0 plugin refuses the kind as unknown.
    pub const MASK: u32 = 2;
}

/// Since 1.1: a light's spectrum (`u32` in [`LightExt::spectrum`]).
pub mod light_spectrum {
    /// As [`super::LightInput::kelvin`] says: D65 daylight for 0, else a blackbody (the only
    /// spectra of 1.0; what a light without an extension has).
    pub const KELVIN: u32 = 0;
    /// A linear sRGB colour, [`super::LightExt::rgb`]: finite, non-negative components with a
    /// positive luminance, made a smooth spectrum by the sdk
    /// (`crate::color::LightSpectrum::Rgb`).
    pub const RGB: u32 = 1;
    /// Equal energy at every wavelength (CIE illuminant E, `crate::color::LightSpectrum::Flat`).
    pub const FLAT: u32 = 2;
}

/// Since 1.1: [`LightInput::kelvin`] of a light whose spectrum its [`LightExt`] gives
/// ([`light_spectrum::RGB`], [`light_spectrum::FLAT`]; a reader requires it negative for
/// those, and zero or positive otherwise). Negative, so that a reader that does not know
/// `light_ext` (a 1.0 plugin) refuses the light rather than renders it as D65.
pub const KELVIN_SEE_EXT: f64 = -1.0;

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
    /// Blackbody temperature (K); 0 for daylight D65; since 1.1, [`KELVIN_SEE_EXT`] when the
    /// light's [`LightExt`] gives its spectrum.
    pub kelvin: f64,
}

/// Since 1.1: what a light carries beyond [`LightInput`], in an array parallel to
/// [`SceneInput::lights`] ([`SceneInput::light_ext`]). Its size is fixed for ABI 1.x.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightExt {
    /// A [`light_spectrum`] constant.
    pub spectrum: u32,
    /// Linear sRGB colour for [`light_spectrum::RGB`]; ignored otherwise (zero).
    pub rgb: [f32; 3],
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

/// What to render: lights, frame and aperture; since 1.1 also an aperture mask and light
/// spectra. A receiver reads the 1.1 fields only when `struct_size` covers them
/// ([`SceneInput::SIZE_1_0`] is the size of a 1.0 scene, which has none of them).
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
    // ABI 1.1 (the 1.0 struct ended here).
    /// The mask of an [`aperture_kind::MASK`] aperture: `mask_width × mask_height`
    /// transmissions in 0..=1, row-major, row 0 at v = +1 (`crate::aperture::ApertureMask`),
    /// at most [`crate::aperture::MAX_MASK_TEXELS`]. 0, 0 and null for any other kind.
    pub mask_width: u32,
    pub mask_height: u32,
    pub mask: *const f32,
    /// `light_count` [`LightExt`]s, one per light, in order; null when every light's spectrum
    /// is what its `kelvin` says (D65 or a blackbody).
    pub light_ext: *const LightExt,
}

impl SceneInput {
    /// `struct_size` of an ABI 1.0 scene: everything up to and including `aperture`.
    pub const SIZE_1_0: usize = std::mem::offset_of!(SceneInput, mask_width);
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
