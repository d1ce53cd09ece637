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
use crate::aperture::Aperture;
use crate::color::LightSpectrum;
use crate::ghost::render::Frame;
use crate::io::parse_olf_xml;

use super::author::{FlarePlugin, Mesh, Output, ParamSpec, ParamType, Params, Scene, SceneLight};
use super::v1::{
    self, ABI_MAJOR, ABI_MINOR, AbiStr, ErrorBuf, LensInput, MAGIC, ParamDesc, PluginHeader,
    RenderOutput, SceneInput, status,
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
        // SAFETY: the host passes a valid `SceneInput` or null.
        let scene =
            unsafe { scene.as_ref() }.ok_or_else(|| invalid("render: scene pointer is null"))?;
        // SAFETY: as above.
        let scene = unsafe { scene_from_input(scene) }.map_err(invalid)?;
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

/// Checks and converts the host's scene.
///
/// # Safety
/// `s.lights` is valid for `s.light_count` elements (or the count is 0).
unsafe fn scene_from_input(s: &SceneInput) -> Result<Scene, String> {
    if (s.struct_size as usize) < size_of::<SceneInput>() {
        return Err(format!(
            "scene: struct_size {} is below the {} bytes of ABI {ABI_MAJOR}.{ABI_MINOR}",
            s.struct_size,
            size_of::<SceneInput>()
        ));
    }
    let lights: &[v1::LightInput] = if s.light_count == 0 {
        &[]
    } else if s.lights.is_null() {
        return Err("scene: lights pointer is null".into());
    } else {
        // SAFETY: non-null and valid for `light_count` elements (caller).
        unsafe { std::slice::from_raw_parts(s.lights, s.light_count as usize) }
    };
    let lights = lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let ok = [l.theta_deg, l.phi_deg, l.intensity, l.kelvin]
                .iter()
                .all(|v| v.is_finite())
                && (0.0..90.0).contains(&l.theta_deg)
                && l.intensity > 0.0
                && l.kelvin >= 0.0;
            if !ok {
                return Err(format!("scene: light {i} is invalid: {l:?}"));
            }
            let spectrum = if l.kelvin == 0.0 {
                LightSpectrum::D65
            } else {
                LightSpectrum::Blackbody { kelvin: l.kelvin }
            };
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
    let aperture = match a.kind {
        v1::aperture_kind::CIRCULAR => Aperture::Circular,
        v1::aperture_kind::IRIS => Aperture::Iris {
            blades: a.blades,
            rotation_rad: a.rotation_rad,
            roundness: a.roundness,
        },
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
