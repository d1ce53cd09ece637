//! The plugin side of the boundary: the `extern "C"` thunks that [`export_plugin!`] points the
//! header at. Every thunk checks its pointers and sizes, converts the C inputs into the safe
//! types of [`super::author`] (checking every value), and runs the plugin inside
//! `catch_unwind`, so a panic becomes [`status::PANIC`] with its message instead of unwinding
//! into the host (which would abort it). Errors travel as a status and a message written into
//! the host's [`ErrorBuf`].

use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::OnceLock;

use crate::LensSystem;
use crate::aperture::{Aperture, ApertureMask, check_mask_size};
use crate::color::LightSpectrum;
use crate::frame::Frame;
use crate::io::parse_olf_xml;

use super::author::{FlarePlugin, Mesh, Output, ParamSpec, ParamType, Params, Scene, SceneLight};
use super::v1::{
    self, ABI_MAJOR, ABI_MINOR, AbiStr, ErrorBuf, KELVIN_SEE_EXT, LensInput, LightExt, MAGIC,
    ParamDesc, PluginHeader, RenderOutput, SceneInput, light_spectrum, status,
};

/// Exports `$ty` (a [`FlarePlugin`](crate::abi::author::FlarePlugin)) as a plugin: defines the
/// entry symbol `flarebench_plugin_v1` ([`v1::ENTRY_SYMBOL`]) returning its header. Call it
/// once per library, at the crate root of a `cdylib`.
#[macro_export]
macro_rules! export_plugin {
    ($ty:ty) => {
        /// The flarebench plugin entry point (ABI v1): returns this library's header.
        #[unsafe(no_mangle)]
        pub extern "C" fn flarebench_plugin_v1() -> *const $crate::abi::v1::PluginHeader {
            static HEADER: ::std::sync::OnceLock<$crate::abi::export::ExportedHeader> =
                ::std::sync::OnceLock::new();
            // `cfg!` is evaluated here, in the plugin's crate: its own panic strategy.
            $crate::abi::export::entry::<$ty>(&HEADER, cfg!(panic = "unwind"))
        }
    };
}

/// A plugin's header together with the descriptors and strings it points into.
#[derive(Debug)]
pub struct ExportedHeader {
    header: PluginHeader,
    _params: Vec<ParamDesc>,
    _choices: Vec<String>,
}

// SAFETY: the header and descriptors are never mutated after `build`, and their pointers
// point into `'static` strings or into the heap buffers owned by this same value (which do not
// move when the value moves); sharing read-only access across threads is sound.
unsafe impl Sync for ExportedHeader {}
// SAFETY: as above; the raw pointers carry no thread affinity.
unsafe impl Send for ExportedHeader {}

impl ExportedHeader {
    /// The header of plugin `P`, with `panic_unwind` as the plugin crate was built.
    pub fn build<P: FlarePlugin>(panic_unwind: bool) -> ExportedHeader {
        let info = P::info();
        let choices: Vec<String> = info
            .params
            .iter()
            .map(|p| match p.ty {
                ParamType::Choice(names) => names.join("|"),
                _ => String::new(),
            })
            .collect();
        let params: Vec<ParamDesc> = info
            .params
            .iter()
            .zip(&choices)
            .map(|(p, c)| ParamDesc {
                name: AbiStr::new(p.name),
                help: AbiStr::new(p.help),
                kind: match p.ty {
                    ParamType::Float => v1::param_kind::FLOAT,
                    ParamType::Int => v1::param_kind::INT,
                    ParamType::Bool => v1::param_kind::BOOL,
                    ParamType::Choice(_) => v1::param_kind::CHOICE,
                },
                reserved: 0,
                min: p.min,
                max: p.max,
                default: p.default,
                choices: AbiStr::new(c),
            })
            .collect();
        let header = PluginHeader {
            magic: MAGIC,
            abi_major: ABI_MAJOR,
            abi_minor: ABI_MINOR,
            struct_size: size_of::<PluginHeader>() as u32,
            panic_unwind: u8::from(panic_unwind),
            reserved: [0; 3],
            sdk_version: AbiStr::new(v1::SDK_VERSION),
            rustc_version: AbiStr::new(v1::RUSTC_VERSION),
            name: AbiStr::new(info.name),
            version: AbiStr::new(info.version),
            description: AbiStr::new(info.description),
            kind: info.kind.code(),
            param_count: params.len() as u32,
            params: params.as_ptr(),
            create: Some(create::<P>),
            destroy: Some(destroy::<P>),
            prepare: Some(prepare::<P>),
            render: Some(render::<P>),
        };
        ExportedHeader {
            header,
            _params: params,
            _choices: choices,
        }
    }
}

/// The body of the entry symbol: builds the header once; null if describing the plugin
/// panicked.
pub fn entry<P: FlarePlugin>(
    cell: &'static OnceLock<ExportedHeader>,
    panic_unwind: bool,
) -> *const PluginHeader {
    match catch_unwind(|| {
        &cell
            .get_or_init(|| ExportedHeader::build::<P>(panic_unwind))
            .header
    }) {
        Ok(h) => h,
        Err(_) => std::ptr::null(),
    }
}

/// The instance behind the opaque pointer: the plugin and its parameter specifications.
struct Instance<P> {
    plugin: P,
    specs: Vec<ParamSpec>,
    lens: Option<LensSystem>,
}

/// Writes `msg` into the host's buffer (truncated at a character boundary to its capacity).
///
/// # Safety
/// `error` is null or points to a valid `ErrorBuf` whose `ptr` is valid for `capacity` bytes.
unsafe fn write_error(error: *mut ErrorBuf, msg: &str) {
    // SAFETY: the caller guarantees `error` is null or valid.
    let Some(buf) = (unsafe { error.as_mut() }) else {
        return;
    };
    if buf.ptr.is_null() {
        buf.len = 0;
        return;
    }
    let mut n = msg.len().min(buf.capacity);
    while !msg.is_char_boundary(n) {
        n -= 1;
    }
    // SAFETY: `buf.ptr` is valid for `capacity` bytes (caller) and `n <= capacity`; the host's
    // buffer cannot overlap the message, which the plugin owns.
    unsafe { std::ptr::copy_nonoverlapping(msg.as_ptr(), buf.ptr, n) };
    buf.len = n;
}

/// The text of a panic payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic with a non-text payload".to_string()
    }
}

/// Runs `f` with panics caught: the status and, unless OK, the message.
fn guarded(f: impl FnOnce() -> Result<(), (u32, String)>) -> (u32, String) {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => (status::OK, String::new()),
        Ok(Err(e)) => e,
        Err(payload) => (
            status::PANIC,
            format!("panicked: {}", panic_message(&*payload)),
        ),
    }
}

/// Writes the message of a failed call into the host's buffer; returns the status.
///
/// # Safety
/// As [`write_error`].
unsafe fn report(error: *mut ErrorBuf, (code, msg): (u32, String)) -> u32 {
    if code != status::OK {
        // SAFETY: forwarded from the caller.
        unsafe { write_error(error, &msg) };
    }
    code
}

fn invalid(msg: impl Into<String>) -> (u32, String) {
    (status::INVALID_ARGUMENT, msg.into())
}

/// # Safety
/// `instance` is valid for writes; `error` as [`write_error`].
unsafe extern "C" fn create<P: FlarePlugin>(
    instance: *mut *mut c_void,
    error: *mut ErrorBuf,
) -> u32 {
    let result = guarded(|| {
        if instance.is_null() {
            return Err(invalid("create: instance pointer is null"));
        }
        let plugin = P::create().map_err(|e| (status::ERROR, e.message))?;
        let boxed = Box::new(Instance {
            plugin,
            specs: P::info().params,
            lens: None,
        });
        // SAFETY: `instance` is non-null and valid for writes (host contract).
        unsafe { *instance = Box::into_raw(boxed).cast() };
        Ok(())
    });
    // SAFETY: `error` is null or valid (host contract).
    unsafe { report(error, result) }
}

/// # Safety
/// `instance` is null or came from `create::<P>` and is not used afterwards.
unsafe extern "C" fn destroy<P: FlarePlugin>(instance: *mut c_void) {
    if instance.is_null() {
        return;
    }
    // A panic in the plugin's Drop is caught and dropped: there is no one left to tell.
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: `instance` came from `Box::into_raw` in `create::<P>` and is destroyed once.
        drop(unsafe { Box::from_raw(instance.cast::<Instance<P>>()) });
    }));
}

/// # Safety
/// `instance` came from `create::<P>`; `lens` is null or valid; `error` as [`write_error`].
unsafe extern "C" fn prepare<P: FlarePlugin>(
    instance: *mut c_void,
    lens: *const LensInput,
    error: *mut ErrorBuf,
) -> u32 {
    let result = guarded(|| {
        // SAFETY: non-null instances come from `create::<P>` (host contract).
        let inst = unsafe { instance.cast::<Instance<P>>().as_mut() }
            .ok_or_else(|| invalid("prepare: instance pointer is null"))?;
        // SAFETY: the host passes a valid `LensInput` or null.
        let lens =
            unsafe { lens.as_ref() }.ok_or_else(|| invalid("prepare: lens pointer is null"))?;
        // SAFETY: the string is valid for the duration of the call (host contract).
        let xml = unsafe { read_str(lens.xml) }.map_err(|e| invalid(format!("lens: {e}")))?;
        let loaded =
            parse_olf_xml(xml, "<lens from host>").map_err(|e| invalid(format!("lens: {e}")))?;
        inst.lens = None;
        inst.plugin
            .prepare(&loaded.system)
            .map_err(|e| (status::ERROR, e.message))?;
        inst.lens = Some(loaded.system);
        Ok(())
    });
    // SAFETY: `error` is null or valid (host contract).
    unsafe { report(error, result) }
}

/// # Safety
/// `instance` came from `create::<P>`; `scene`, `params` (`param_count` values) and `output`
/// are valid for the call; `error` as [`write_error`].
unsafe extern "C" fn render<P: FlarePlugin>(
    instance: *mut c_void,
    scene: *const SceneInput,
    params: *const f64,
    param_count: u32,
    output: *mut RenderOutput,
    error: *mut ErrorBuf,
) -> u32 {
    let result = guarded(|| {
        // SAFETY: non-null instances come from `create::<P>` (host contract).
        let inst = unsafe { instance.cast::<Instance<P>>().as_mut() }
            .ok_or_else(|| invalid("render: instance pointer is null"))?;
        if inst.lens.is_none() {
            return Err(invalid("render: prepare was not called (or failed)"));
        }
        // SAFETY: the host passes null or a `SceneInput` of at least the `struct_size` it
        // states, whose pointers are valid for the call.
        let scene = unsafe { read_scene_input(scene) }.map_err(invalid)?;
        // SAFETY: as above.
        let scene = unsafe { scene_from_input(&scene) }.map_err(invalid)?;
        let values = param_values(&inst.specs, params, param_count).map_err(invalid)?;
        // SAFETY: the host passes a valid `RenderOutput` or null.
        let output =
            unsafe { output.as_mut() }.ok_or_else(|| invalid("render: output pointer is null"))?;
        let img = &output.image;
        if img.pixels.is_null()
            || img.width as usize != scene.frame.width
            || img.height as usize != scene.frame.height
            || !(img.pixels as usize).is_multiple_of(align_of::<f32>())
        {
            return Err(invalid(format!(
                "render: the output image ({}x{}) is null, misaligned or not the scene's {}x{}",
                img.width, img.height, scene.frame.width, scene.frame.height
            )));
        }
        let n = scene.frame.width * scene.frame.height;
        // SAFETY: the host allocated `width × height` RGB f32 pixels at `pixels` (checked
        // non-null and aligned above), exclusively for this call; `[f32; 3]` has the
        // layout of three consecutive `f32`.
        let pixels = unsafe { std::slice::from_raw_parts_mut(img.pixels.cast::<[f32; 3]>(), n) };
        let mut out = Output {
            width: scene.frame.width,
            height: scene.frame.height,
            pixels,
            mesh: Mesh::default(),
            items_drawn: 0,
        };
        let p = Params::new(&inst.specs, &values);
        inst.plugin
            .render(&scene, &p, &mut out)
            .map_err(|e| (status::ERROR, e.message))?;
        output.items_drawn = out.items_drawn;
        // SAFETY: the mesh buffers are valid for their capacities (host contract).
        unsafe { write_mesh(&out.mesh, &mut output.mesh) }
    });
    // SAFETY: `error` is null or valid (host contract).
    unsafe { report(error, result) }
}

/// Copies the plugin's mesh into the host's buffers, or asks for larger ones.
///
/// # Safety
/// `buf.vertices` and `buf.triangles` are valid for their capacities (or the capacities are 0).
unsafe fn write_mesh(mesh: &Mesh, buf: &mut v1::MeshBuffer) -> Result<(), (u32, String)> {
    let (nv, nt) = (mesh.vertices.len(), mesh.triangles.len());
    let (Ok(nv32), Ok(nt32)) = (u32::try_from(nv), u32::try_from(nt)) else {
        return Err((
            status::ERROR,
            format!("mesh too large: {nv} vertices, {nt} triangles"),
        ));
    };
    buf.vertex_count = nv32;
    buf.triangle_count = nt32;
    if nt == 0 {
        buf.vertex_count = 0;
        return Ok(());
    }
    if nv32 > buf.vertex_capacity
        || nt32 > buf.triangle_capacity
        || buf.vertices.is_null()
        || buf.triangles.is_null()
    {
        return Err((
            status::MESH_CAPACITY,
            format!("the mesh needs {nv} vertices and {nt} triangles"),
        ));
    }
    // SAFETY: both host buffers hold at least `nv` / `nt` elements (checked above) and do not
    // overlap the plugin's vectors.
    unsafe {
        std::ptr::copy_nonoverlapping(mesh.vertices.as_ptr(), buf.vertices, nv);
        std::ptr::copy_nonoverlapping(mesh.triangles.as_ptr(), buf.triangles, nt);
    }
    Ok(())
}

/// Borrows an [`AbiStr`] as `&str`.
///
/// # Safety
/// `s.ptr` is valid for `s.len` bytes for the lifetime `'a` (or `s.len` is 0).
pub unsafe fn read_str<'a>(s: AbiStr) -> Result<&'a str, String> {
    if s.len == 0 {
        return Ok("");
    }
    if s.ptr.is_null() {
        return Err(format!("null string of {} bytes", s.len));
    }
    // SAFETY: `ptr` is non-null and valid for `len` bytes (caller).
    let bytes = unsafe { std::slice::from_raw_parts(s.ptr, s.len) };
    std::str::from_utf8(bytes).map_err(|e| format!("not UTF-8: {e}"))
}

/// A scene with every field zero or null: the 1.1 fields of a scene from a 1.0 host.
const EMPTY_SCENE: SceneInput = SceneInput {
    struct_size: 0,
    light_count: 0,
    lights: std::ptr::null(),
    width: 0,
    height: 0,
    film_width_mm: 0.0,
    film_height_mm: 0.0,
    aperture: v1::ApertureInput {
        kind: v1::aperture_kind::CIRCULAR,
        blades: 0,
        rotation_rad: 0.0,
        roundness: 0.0,
    },
    mask_width: 0,
    mask_height: 0,
    mask: std::ptr::null(),
    light_ext: std::ptr::null(),
};

/// Copies the host's scene, reading only the `struct_size` bytes the host says it wrote: a
/// 1.0 host's scene is [`SceneInput::SIZE_1_0`] bytes, and the fields past them stay as in
/// [`EMPTY_SCENE`] (no mask, no light extensions); a newer host's longer scene is read up to
/// the fields this sdk knows.
///
/// # Safety
/// `p` is null or points to `struct_size` readable bytes (its first field), at least
/// [`SceneInput::SIZE_1_0`].
unsafe fn read_scene_input(p: *const SceneInput) -> Result<SceneInput, String> {
    if p.is_null() {
        return Err("render: scene pointer is null".into());
    }
    if !(p as usize).is_multiple_of(align_of::<SceneInput>()) {
        return Err("render: scene pointer is misaligned".into());
    }
    // SAFETY: every ABI 1.x scene starts with its `u32` size; `p` is non-null and aligned.
    let size = unsafe { p.cast::<u32>().read() } as usize;
    if size < SceneInput::SIZE_1_0 {
        return Err(format!(
            "scene: struct_size {size} is below the {} bytes of ABI {ABI_MAJOR}.0",
            SceneInput::SIZE_1_0
        ));
    }
    let mut scene = EMPTY_SCENE;
    // SAFETY: the host's scene has `size` readable bytes (caller) and `scene` has
    // `size_of::<SceneInput>()`; the copy takes the smaller, a prefix of whole fields of the
    // same layout (minor versions only append), and the two cannot overlap.
    unsafe {
        std::ptr::copy_nonoverlapping(
            p.cast::<u8>(),
            (&raw mut scene).cast::<u8>(),
            size.min(size_of::<SceneInput>()),
        );
    }
    Ok(scene)
}

/// A light's spectrum from its `kelvin` and, since ABI 1.1, its [`LightExt`].
fn light_spectrum_of(
    i: usize,
    kelvin: f64,
    ext: Option<&LightExt>,
) -> Result<LightSpectrum, String> {
    let code = ext.map_or(light_spectrum::KELVIN, |e| e.spectrum);
    let spectrum = match code {
        light_spectrum::KELVIN if kelvin == 0.0 => LightSpectrum::D65,
        light_spectrum::KELVIN if kelvin > 0.0 => LightSpectrum::Blackbody { kelvin },
        light_spectrum::KELVIN => {
            return Err(format!(
                "scene: light {i} has kelvin {kelvin} and no spectrum in light_ext (a 1.1 \
                 host gives RGB and flat lights in light_ext)"
            ));
        }
        light_spectrum::RGB | light_spectrum::FLAT if kelvin >= 0.0 => {
            return Err(format!(
                "scene: light {i} has its spectrum in light_ext, so its kelvin must be \
                 negative ({KELVIN_SEE_EXT}), got {kelvin}"
            ));
        }
        light_spectrum::RGB => LightSpectrum::Rgb(ext.map_or([0.0; 3], |e| e.rgb)),
        light_spectrum::FLAT => LightSpectrum::Flat,
        k => return Err(format!("scene: light {i} has unknown spectrum kind {k}")),
    };
    spectrum
        .validate()
        .map_err(|e| format!("scene: light {i}: {e}"))?;
    Ok(spectrum)
}

/// The aperture mask of a 1.1 scene, checked: sizes, pointer, every value in 0..=1.
///
/// # Safety
/// `s.mask` is valid for `s.mask_width × s.mask_height` values (or null).
unsafe fn mask_from_input(s: &SceneInput) -> Result<ApertureMask, String> {
    let (w, h) = (s.mask_width as usize, s.mask_height as usize);
    let n = check_mask_size(w, h).map_err(|e| format!("scene: aperture: {e}"))?;
    if s.mask.is_null() || !(s.mask as usize).is_multiple_of(align_of::<f32>()) {
        return Err(format!(
            "scene: aperture: the mask pointer of a {w}x{h} mask is null or misaligned"
        ));
    }
    // SAFETY: non-null, aligned, and valid for `w × h` values (caller); `n` is that product.
    let values = unsafe { std::slice::from_raw_parts(s.mask, n) };
    ApertureMask::from_luma_f32(w, h, values).map_err(|e| format!("scene: aperture: {e}"))
}

/// Checks and converts the host's scene (copied by [`read_scene_input`]).
///
/// # Safety
/// `s.lights` and `s.light_ext` (unless null) are valid for `s.light_count` elements (or the
/// count is 0); `s.mask` as [`mask_from_input`].
unsafe fn scene_from_input(s: &SceneInput) -> Result<Scene, String> {
    let lights: &[v1::LightInput] = if s.light_count == 0 {
        &[]
    } else if s.lights.is_null() {
        return Err("scene: lights pointer is null".into());
    } else {
        // SAFETY: non-null and valid for `light_count` elements (caller).
        unsafe { std::slice::from_raw_parts(s.lights, s.light_count as usize) }
    };
    let exts: Option<&[LightExt]> = if s.light_ext.is_null() || s.light_count == 0 {
        None
    } else if !(s.light_ext as usize).is_multiple_of(align_of::<LightExt>()) {
        return Err("scene: light_ext pointer is misaligned".into());
    } else {
        // SAFETY: non-null, aligned and valid for `light_count` elements (caller).
        Some(unsafe { std::slice::from_raw_parts(s.light_ext, s.light_count as usize) })
    };
    let lights = lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let ok = [l.theta_deg, l.phi_deg, l.intensity, l.kelvin]
                .iter()
                .all(|v| v.is_finite())
                && (0.0..90.0).contains(&l.theta_deg)
                && l.intensity > 0.0;
            if !ok {
                return Err(format!("scene: light {i} is invalid: {l:?}"));
            }
            let spectrum = light_spectrum_of(i, l.kelvin, exts.map(|e| &e[i]))?;
            Ok(SceneLight {
                theta_deg: l.theta_deg,
                phi_deg: l.phi_deg,
                intensity: l.intensity,
                spectrum,
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    let sizes_ok = s.width > 0
        && s.height > 0
        && (s.width as u64) * (s.height as u64) <= 1 << 28
        && s.film_width_mm.is_finite()
        && s.film_width_mm > 0.0
        && s.film_height_mm.is_finite()
        && s.film_height_mm > 0.0;
    if !sizes_ok {
        return Err(format!(
            "scene: frame {}x{} px over {} x {} mm is invalid",
            s.width, s.height, s.film_width_mm, s.film_height_mm
        ));
    }
    let a = &s.aperture;
    let has_mask = s.mask_width != 0 || s.mask_height != 0 || !s.mask.is_null();
    if has_mask && a.kind != v1::aperture_kind::MASK {
        return Err(format!(
            "scene: a {}x{} mask is given but the aperture kind is {}, not a mask",
            s.mask_width, s.mask_height, a.kind
        ));
    }
    let aperture = match a.kind {
        v1::aperture_kind::CIRCULAR => Aperture::Circular,
        v1::aperture_kind::IRIS => Aperture::Iris {
            blades: a.blades,
            rotation_rad: a.rotation_rad,
            roundness: a.roundness,
        },
        // SAFETY: the mask pointer is valid for its sizes (caller).
        v1::aperture_kind::MASK => Aperture::Mask(unsafe { mask_from_input(s) }?),
        k => return Err(format!("scene: unknown aperture kind {k}")),
    };
    aperture
        .validate()
        .map_err(|e| format!("scene: aperture: {e}"))?;
    Ok(Scene {
        lights,
        frame: Frame {
            width: s.width as usize,
            height: s.height as usize,
            film_width_mm: s.film_width_mm,
            film_height_mm: s.film_height_mm,
        },
        aperture,
    })
}

/// Checks the host's parameter values against the specifications.
fn param_values(specs: &[ParamSpec], params: *const f64, count: u32) -> Result<Vec<f64>, String> {
    if count as usize != specs.len() {
        return Err(format!(
            "render: {count} parameter values for {} parameters",
            specs.len()
        ));
    }
    if count == 0 {
        return Ok(Vec::new());
    }
    if params.is_null() {
        return Err("render: parameter pointer is null".into());
    }
    // SAFETY: the host passes `count` values at `params` (host contract), checked non-null.
    let values = unsafe { std::slice::from_raw_parts(params, count as usize) }.to_vec();
    for (s, &v) in specs.iter().zip(&values) {
        let whole = !matches!(s.ty, ParamType::Float);
        if !(v >= s.min && v <= s.max) || (whole && v.fract() != 0.0) {
            return Err(format!(
                "parameter `{}` = {v} is outside {}..={}{}",
                s.name,
                s.min,
                s.max,
                if whole { " or not whole" } else { "" }
            ));
        }
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    //! The render thunk called as a host calls it, with hand-made scenes: what ABI 1.1 added
    //! (mask, light spectra) arrives as the host's values, bad values are
    //! [`status::INVALID_ARGUMENT`] with a message, and a 1.0 host's shorter scene is read.

    use super::*;
    use crate::abi::author::{PluginError, PluginInfo, PluginKind};
    use crate::abi::v1::{ApertureInput, ImageBuffer, LightInput, MeshBuffer, aperture_kind};

    /// A plugin that keeps the scene it was given.
    #[derive(Debug, Default)]
    struct Recorder {
        last: Option<Scene>,
    }

    impl FlarePlugin for Recorder {
        fn info() -> PluginInfo {
            PluginInfo {
                name: "recorder",
                version: "0",
                description: "keeps the last scene",
                kind: PluginKind::Other,
                params: Vec::new(),
            }
        }
        fn create() -> Result<Self, PluginError> {
            Ok(Recorder::default())
        }
        fn prepare(&mut self, _lens: &LensSystem) -> Result<(), PluginError> {
            Ok(())
        }
        fn render(
            &mut self,
            scene: &Scene,
            _params: &Params<'_>,
            _out: &mut Output<'_>,
        ) -> Result<(), PluginError> {
            self.last = Some(scene.clone());
            Ok(())
        }
    }

    const W: u32 = 4;
    const H: u32 = 2;

    /// An instance of [`Recorder`], created and prepared through the thunks.
    struct Harness {
        instance: *mut c_void,
    }

    impl Harness {
        fn new() -> Harness {
            let mut instance = std::ptr::null_mut();
            // SAFETY: valid pointers; a null error buffer is allowed.
            let code = unsafe { create::<Recorder>(&mut instance, std::ptr::null_mut()) };
            assert_eq!(code, status::OK);
            let xml = crate::io::olf_xml::tests::SMALL;
            let lens = LensInput {
                xml: AbiStr::new(xml),
            };
            // SAFETY: a live instance and a valid lens.
            let code = unsafe { prepare::<Recorder>(instance, &lens, std::ptr::null_mut()) };
            assert_eq!(code, status::OK);
            Harness { instance }
        }

        /// Renders `scene` (any layout starting with a `SceneInput` prefix) into a `W × H`
        /// image; the status and the message.
        fn render<T>(&mut self, scene: &T) -> (u32, String) {
            let mut pixels = vec![0.0_f32; (W * H * 3) as usize];
            let mut output = RenderOutput {
                image: ImageBuffer {
                    pixels: pixels.as_mut_ptr(),
                    width: W,
                    height: H,
                },
                mesh: MeshBuffer {
                    vertices: std::ptr::null_mut(),
                    vertex_capacity: 0,
                    vertex_count: 0,
                    triangles: std::ptr::null_mut(),
                    triangle_capacity: 0,
                    triangle_count: 0,
                },
                items_drawn: 0,
                reserved: 0,
            };
            let mut bytes = vec![0_u8; 1024];
            let mut error = ErrorBuf {
                ptr: bytes.as_mut_ptr(),
                capacity: bytes.len(),
                len: 0,
            };
            let scene = std::ptr::from_ref(scene).cast::<SceneInput>();
            // SAFETY: a live, prepared instance; the scene is valid for its `struct_size`;
            // no parameters; output and error buffers valid for the call.
            let code = unsafe {
                render::<Recorder>(
                    self.instance,
                    scene,
                    std::ptr::null(),
                    0,
                    &mut output,
                    &mut error,
                )
            };
            let message = String::from_utf8_lossy(&bytes[..error.len]).into_owned();
            (code, message)
        }

        /// The scene the plugin last received.
        fn last(&self) -> Scene {
            // SAFETY: the instance came from `create::<Recorder>` and is live.
            let inst = unsafe { &*self.instance.cast::<Instance<Recorder>>() };
            inst.plugin.last.clone().expect("a scene was rendered")
        }

        /// Renders `scene` and expects INVALID_ARGUMENT with a message containing `needle`;
        /// then checks the instance still renders a good scene.
        fn refuses(&mut self, scene: &SceneInput, needle: &str) {
            let (code, message) = self.render(scene);
            assert_eq!(code, status::INVALID_ARGUMENT, "{message}");
            assert!(message.contains(needle), "`{needle}` not in: {message}");
            let lights = [light(0.0)];
            let (code, message) = self.render(&scene_1_1(&lights));
            assert_eq!(code, status::OK, "{message}");
        }
    }

    impl Drop for Harness {
        fn drop(&mut self) {
            // SAFETY: created by `create::<Recorder>`, destroyed once.
            unsafe { destroy::<Recorder>(self.instance) };
        }
    }

    fn light(kelvin: f64) -> LightInput {
        LightInput {
            theta_deg: 5.0,
            phi_deg: 30.0,
            intensity: 2.0,
            kelvin,
        }
    }

    /// A 1.1 scene of these lights: circular, no mask, no light extensions.
    fn scene_1_1(lights: &[LightInput]) -> SceneInput {
        SceneInput {
            struct_size: size_of::<SceneInput>() as u32,
            light_count: lights.len() as u32,
            lights: lights.as_ptr(),
            width: W,
            height: H,
            film_width_mm: 36.0,
            film_height_mm: 18.0,
            ..EMPTY_SCENE
        }
    }

    /// The scene of ABI 1.0 as an older host lays it out: nothing past `aperture`.
    #[repr(C)]
    #[derive(Clone, Copy)]
    struct SceneInput1_0 {
        struct_size: u32,
        light_count: u32,
        lights: *const LightInput,
        width: u32,
        height: u32,
        film_width_mm: f64,
        film_height_mm: f64,
        aperture: ApertureInput,
    }

    #[test]
    fn a_scene_from_a_1_0_host_is_read_without_the_fields_it_does_not_have() {
        assert_eq!(size_of::<SceneInput1_0>(), SceneInput::SIZE_1_0);
        let lights = [light(3200.0), light(0.0)];
        // A separate allocation of exactly the 1.0 size: nothing past it is read.
        let old = Box::new(SceneInput1_0 {
            struct_size: SceneInput::SIZE_1_0 as u32,
            light_count: 2,
            lights: lights.as_ptr(),
            width: W,
            height: H,
            film_width_mm: 36.0,
            film_height_mm: 18.0,
            aperture: ApertureInput {
                kind: aperture_kind::IRIS,
                blades: 6,
                rotation_rad: 0.25,
                roundness: 0.5,
            },
        });
        let mut h = Harness::new();
        let (code, message) = h.render(&*old);
        assert_eq!(code, status::OK, "{message}");
        let s = h.last();
        assert_eq!(
            s.aperture,
            Aperture::Iris {
                blades: 6,
                rotation_rad: 0.25,
                roundness: 0.5
            }
        );
        let spectra: Vec<_> = s.lights.iter().map(|l| l.spectrum).collect();
        assert_eq!(
            spectra,
            [
                LightSpectrum::Blackbody { kelvin: 3200.0 },
                LightSpectrum::D65
            ]
        );
        assert_eq!((s.frame.width, s.frame.height), (W as usize, H as usize));

        // A scene shorter than 1.0's is refused before anything past its size is read.
        let mut short = Box::new(*old);
        short.struct_size = SceneInput::SIZE_1_0 as u32 - 8;
        let (code, message) = h.render(&*short);
        assert_eq!(code, status::INVALID_ARGUMENT, "{message}");
        assert!(message.contains("struct_size 56 is below the 64 bytes of ABI 1.0"));
    }

    #[test]
    fn a_mask_and_rgb_and_flat_lights_arrive_as_the_host_sent_them() {
        let (mw, mh) = (5_u32, 3_u32);
        let values: Vec<f32> = (0..mw * mh).map(|k| (k % 4) as f32 / 3.0).collect();
        let expected_mask = ApertureMask::from_luma_f32(5, 3, &values).unwrap();
        let lights = [light(-1.0), light(4500.0), light(-1.0), light(0.0)];
        let exts = [
            LightExt {
                spectrum: light_spectrum::RGB,
                rgb: [1.0, 0.5, 0.2],
            },
            LightExt {
                spectrum: light_spectrum::KELVIN,
                rgb: [0.0; 3],
            },
            LightExt {
                spectrum: light_spectrum::FLAT,
                rgb: [0.0; 3],
            },
            LightExt {
                spectrum: light_spectrum::KELVIN,
                rgb: [0.0; 3],
            },
        ];
        let scene = SceneInput {
            aperture: ApertureInput {
                kind: aperture_kind::MASK,
                blades: 0,
                rotation_rad: 0.0,
                roundness: 0.0,
            },
            mask_width: mw,
            mask_height: mh,
            mask: values.as_ptr(),
            light_ext: exts.as_ptr(),
            ..scene_1_1(&lights)
        };
        let mut h = Harness::new();
        let (code, message) = h.render(&scene);
        assert_eq!(code, status::OK, "{message}");
        let s = h.last();
        assert_eq!(s.aperture, Aperture::Mask(expected_mask));
        let spectra: Vec<_> = s.lights.iter().map(|l| l.spectrum).collect();
        assert_eq!(
            spectra,
            [
                LightSpectrum::Rgb([1.0, 0.5, 0.2]),
                LightSpectrum::Blackbody { kelvin: 4500.0 },
                LightSpectrum::Flat,
                LightSpectrum::D65,
            ]
        );
    }

    #[test]
    fn a_bad_mask_is_an_invalid_argument_and_the_instance_keeps_working() {
        let lights = [light(0.0)];
        let mut values = vec![1.0_f32; 12];
        let mask_scene = |values: &[f32], w: u32, h: u32| SceneInput {
            aperture: ApertureInput {
                kind: aperture_kind::MASK,
                blades: 0,
                rotation_rad: 0.0,
                roundness: 0.0,
            },
            mask_width: w,
            mask_height: h,
            mask: values.as_ptr(),
            ..scene_1_1(&lights)
        };
        let mut h = Harness::new();
        let (code, message) = h.render(&mask_scene(&values, 4, 3));
        assert_eq!(code, status::OK, "{message}");

        let null = SceneInput {
            mask: std::ptr::null(),
            ..mask_scene(&values, 4, 3)
        };
        h.refuses(&null, "mask pointer of a 4x3 mask is null");
        h.refuses(&mask_scene(&values, 0, 3), "positive width and height");
        // Far past the sdk's limit: refused from the sizes, the pointer is never read.
        h.refuses(&mask_scene(&values, 1 << 16, 1 << 16), "too large");
        h.refuses(&mask_scene(&values, u32::MAX, u32::MAX), "too large");
        values[5] = f32::NAN;
        h.refuses(&mask_scene(&values, 4, 3), "row 1, column 1 is NaN");
        values[5] = 1.5;
        h.refuses(&mask_scene(&values, 4, 3), "row 1, column 1 is 1.5");
        values[5] = -0.0;
        let (code, message) = h.render(&mask_scene(&values, 4, 3));
        assert_eq!(code, status::OK, "{message}");
        // Mask fields set for another kind of aperture: a host bug, not silently ignored.
        let circle_with_mask = SceneInput {
            aperture: EMPTY_SCENE.aperture,
            ..mask_scene(&values, 4, 3)
        };
        h.refuses(&circle_with_mask, "aperture kind is 0, not a mask");
        let unknown = SceneInput {
            aperture: ApertureInput {
                kind: 9,
                ..EMPTY_SCENE.aperture
            },
            ..scene_1_1(&lights)
        };
        h.refuses(&unknown, "unknown aperture kind 9");
    }

    #[test]
    fn a_bad_light_spectrum_is_an_invalid_argument_and_the_instance_keeps_working() {
        let mut h = Harness::new();
        let rgb = |rgb: [f32; 3]| LightExt {
            spectrum: light_spectrum::RGB,
            rgb,
        };
        let cases: [(f64, LightExt, &str); 7] = [
            (-1.0, rgb([f32::NAN, 0.5, 0.5]), "light 0: light colour"),
            (-1.0, rgb([1.0, f32::INFINITY, 0.5]), "light colour"),
            (-1.0, rgb([1.0, -0.1, 0.5]), "light colour"),
            (-1.0, rgb([0.0; 3]), "positive luminance"),
            // An RGB light whose kelvin a 1.0 reader would take for D65.
            (0.0, rgb([1.0, 0.5, 0.2]), "kelvin must be negative"),
            (
                -1.0,
                LightExt {
                    spectrum: 7,
                    rgb: [0.0; 3],
                },
                "unknown spectrum kind 7",
            ),
            (
                -1.0,
                LightExt {
                    spectrum: light_spectrum::KELVIN,
                    rgb: [0.0; 3],
                },
                "has kelvin -1 and no spectrum in light_ext",
            ),
        ];
        for (kelvin, ext, needle) in cases {
            let lights = [light(kelvin)];
            let exts = [ext];
            let scene = SceneInput {
                light_ext: exts.as_ptr(),
                ..scene_1_1(&lights)
            };
            h.refuses(&scene, needle);
        }
        // Without light_ext a negative kelvin is refused as 1.0 refused it.
        let lights = [light(-1.0)];
        h.refuses(&scene_1_1(&lights), "no spectrum in light_ext");
        let lights = [light(f64::NAN)];
        h.refuses(&scene_1_1(&lights), "light 0 is invalid");
    }
}
