//! The host side of the boundary: loading a plugin library, checking its header, and calling
//! its instances with host-allocated inputs and outputs.
//!
//! Loading reads the header in two steps: the 20-byte prefix common to every ABI version
//! (magic, major, minor, `struct_size`) first, the rest only once the magic and major match and
//! `struct_size` covers the whole 1.0 header — so a foreign or truncated header is refused
//! before any field past the prefix is read. Plugins built with `panic = "abort"` are refused
//! (a panic in them would end the host; with `unwind` the export thunks catch it). Libraries are
//! never unloaded: a plugin's code and static data stay valid for the life of the process.
//!
//! Minor versions: the host always sends the scene of its own minor (a plugin reads the fields
//! its `struct_size` check says it knows), but a scene that needs a newer minor than the
//! plugin's header states — an aperture mask or a light spectrum other than D65 and blackbody
//! need 1.1 — is refused here with [`PluginCallError::Unsupported`], naming the plugin and its
//! minor, instead of being sent to a plugin that would misread it.
//!
//! What this cannot protect against: a plugin is native code in the host's process, so one that
//! writes through wild pointers or calls `abort` can still take the host down. Everything a
//! well-formed plugin can do wrong — report an error, panic, return NaN or an ill-formed mesh,
//! describe itself badly — is turned into a typed error here.

use std::ffi::c_void;
use std::path::{Path, PathBuf};

use crate::LensSystem;
use crate::aperture::Aperture;
use crate::color::LightSpectrum;
use crate::ghost::mesh::GhostMesh;
use crate::ghost::render::rasterize_ghost_mesh_with;
use crate::ghost::sink::{FrameLevels, GhostSink};
use crate::image::{CoarseGrid, HdrImage};
use crate::io::write_xml;
use crate::raster::Coverage;
use rayon::prelude::*;

use super::author::{PluginKind, Scene};
use super::export::read_str;
use super::params::{ParamInfo, ParamKind};
use super::v1::{
    self, ABI_MAJOR, AbiStr, ENTRY_SYMBOL, EntryFn, ErrorBuf, ImageBuffer, KELVIN_SEE_EXT,
    LensInput, LightExt, LightInput, MAGIC, MeshBuffer, MeshVertex, PluginHeader, RenderOutput,
    SceneInput, light_spectrum, status,
};

/// Capacity of the error message buffer handed to every call (bytes).
pub const ERROR_CAPACITY: usize = 4096;
/// Most parameters a plugin may describe.
pub const MAX_PARAMS: u32 = 256;

/// Why a plugin library could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum PluginLoadError {
    /// dlopen failed; `detail` is libloading's error with its source (the loader's own text).
    #[error("{}: could not load the library: {detail}", path.display())]
    Open { path: PathBuf, detail: String },
    /// The library has no entry symbol.
    #[error("{}: no `{ENTRY_SYMBOL}` symbol, so not a flarebench plugin of ABI {ABI_MAJOR}: {detail}", path.display())]
    NoEntry { path: PathBuf, detail: String },
    /// The entry returned null.
    #[error("{}: the plugin could not describe itself (its entry returned no header)", path.display())]
    NullHeader { path: PathBuf },
    /// The header does not start with [`MAGIC`].
    #[error("{}: bad magic {found:02x?} (expected {MAGIC:02x?}): not a flarebench plugin header", path.display())]
    BadMagic { path: PathBuf, found: [u8; 8] },
    /// Another ABI major version.
    #[error("{}: built for plugin ABI {major}.{minor}, but this workbench speaks ABI {ABI_MAJOR}.x; rebuild the plugin against this sdk", path.display())]
    AbiMajor {
        path: PathBuf,
        major: u32,
        minor: u32,
    },
    /// `struct_size` is below the ABI 1.0 header.
    #[error("{}: header of {size} bytes is shorter than the {needed} bytes of ABI {ABI_MAJOR}.0", path.display())]
    ShortHeader {
        path: PathBuf,
        size: u32,
        needed: usize,
    },
    /// Built with `panic = "abort"`.
    #[error("{}: built with panic = \"abort\", so a panic in it would end the workbench; rebuild it with panic = \"unwind\"", path.display())]
    PanicAbort { path: PathBuf },
    /// A header field is invalid.
    #[error("{}: header field `{field}`: {reason}", path.display())]
    BadHeader {
        path: PathBuf,
        field: String,
        reason: String,
    },
    /// The library could not be copied for a fresh load ([`load_fresh_copy`]).
    #[error("{}: could not copy the library to load a fresh copy: {detail}", path.display())]
    Copy { path: PathBuf, detail: String },
}

impl PluginLoadError {
    /// The library the error is about.
    pub fn path(&self) -> &Path {
        match self {
            PluginLoadError::Open { path, .. }
            | PluginLoadError::NoEntry { path, .. }
            | PluginLoadError::NullHeader { path }
            | PluginLoadError::BadMagic { path, .. }
            | PluginLoadError::AbiMajor { path, .. }
            | PluginLoadError::ShortHeader { path, .. }
            | PluginLoadError::PanicAbort { path }
            | PluginLoadError::BadHeader { path, .. }
            | PluginLoadError::Copy { path, .. } => path,
        }
    }

    /// The same error about the library at `to` (a fresh copy's error told of its original).
    fn with_path(mut self, to: &Path) -> Self {
        match &mut self {
            PluginLoadError::Open { path, .. }
            | PluginLoadError::NoEntry { path, .. }
            | PluginLoadError::NullHeader { path }
            | PluginLoadError::BadMagic { path, .. }
            | PluginLoadError::AbiMajor { path, .. }
            | PluginLoadError::ShortHeader { path, .. }
            | PluginLoadError::PanicAbort { path }
            | PluginLoadError::BadHeader { path, .. }
            | PluginLoadError::Copy { path, .. } => *path = to.to_path_buf(),
        }
        self
    }
}

/// What went wrong calling a plugin.
#[derive(Debug, thiserror::Error)]
pub enum PluginCallError {
    /// The plugin reported an error.
    #[error("plugin `{plugin}` failed in {call}: {message}")]
    Failed {
        plugin: String,
        call: &'static str,
        message: String,
    },
    /// The plugin panicked (caught at the boundary).
    #[error("plugin `{plugin}` panicked in {call} (caught; the instance is discarded): {message}")]
    Panicked {
        plugin: String,
        call: &'static str,
        message: String,
    },
    /// The plugin refused the host's input.
    #[error("plugin `{plugin}` rejected the input of {call}: {message}")]
    InvalidArgument {
        plugin: String,
        call: &'static str,
        message: String,
    },
    /// A status code ABI v1 does not define.
    #[error("plugin `{plugin}` returned unknown status {status} from {call}: {message}")]
    UnknownStatus {
        plugin: String,
        call: &'static str,
        status: u32,
        message: String,
    },
    /// The image has NaN or infinite values.
    #[error(
        "plugin `{plugin}` returned {count} non-finite pixel values (the first at x {x}, y {y}); its image is discarded"
    )]
    NonFinite {
        plugin: String,
        count: usize,
        x: usize,
        y: usize,
    },
    /// The mesh is ill-formed.
    #[error("plugin `{plugin}` returned a bad mesh: {reason}")]
    BadMesh { plugin: String, reason: String },
    /// The instance panicked before.
    #[error("plugin `{plugin}`: this instance panicked earlier and cannot be used again")]
    Poisoned { plugin: String },
    /// The scene cannot be expressed in ABI v1, or not in the minor version the plugin was
    /// built for (an aperture mask or an RGB light for a 1.0 plugin).
    #[error("plugin `{plugin}`: {reason}")]
    Unsupported { plugin: String, reason: String },
}

/// The functions of a loaded plugin (all present: checked at load).
#[derive(Clone, Copy, Debug)]
struct Functions {
    create: unsafe extern "C" fn(*mut *mut c_void, *mut ErrorBuf) -> u32,
    destroy: unsafe extern "C" fn(*mut c_void),
    prepare: unsafe extern "C" fn(*mut c_void, *const LensInput, *mut ErrorBuf) -> u32,
    render: unsafe extern "C" fn(
        *mut c_void,
        *const SceneInput,
        *const f64,
        u32,
        *mut RenderOutput,
        *mut ErrorBuf,
    ) -> u32,
}

/// A loaded, checked plugin library. Its code stays loaded for the life of the process.
#[derive(Clone, Debug)]
pub struct LoadedPlugin {
    pub path: PathBuf,
    pub name: String,
    pub version: String,
    pub description: String,
    pub kind: PluginKind,
    pub abi_major: u32,
    pub abi_minor: u32,
    /// Sdk version and `rustc --version` the plugin was built with.
    pub sdk_version: String,
    pub rustc_version: String,
    pub params: Vec<ParamInfo>,
    functions: Functions,
}

/// The header prefix shared by every ABI version.
#[repr(C)]
struct HeaderPrefix {
    magic: [u8; 8],
    abi_major: u32,
    abi_minor: u32,
    struct_size: u32,
}

/// The text of a libloading error and its sources (its own text alone is only
/// "dlopen failed").
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(c) = source {
        s.push_str(": ");
        s.push_str(&c.to_string());
        source = c.source();
    }
    s
}

/// Loads and checks the plugin library at `path`. The library is never unloaded, even when it
/// is refused (its initialisers may have run; unloading is never safe after that).
pub fn load(path: &Path) -> Result<LoadedPlugin, PluginLoadError> {
    let p = || path.to_path_buf();
    // SAFETY: loading a library runs its initialisers. A plugin is native code the user chose
    // to load; that is the trust the plugin model rests on (module documentation).
    let lib = unsafe { libloading::Library::new(path) }.map_err(|e| PluginLoadError::Open {
        path: p(),
        detail: error_chain(&e),
    })?;
    // Never unloaded: every pointer the plugin hands out stays valid.
    let lib: &'static libloading::Library = Box::leak(Box::new(lib));
    // SAFETY: the entry symbol of ABI v1 has type `EntryFn` (the ABI's definition); a library
    // exporting the name with another type is outside the contract.
    let entry: EntryFn = *unsafe { lib.get::<EntryFn>(ENTRY_SYMBOL.as_bytes()) }.map_err(|e| {
        PluginLoadError::NoEntry {
            path: p(),
            detail: error_chain(&e),
        }
    })?;
    // SAFETY: calling the entry as the ABI defines it; it takes no arguments.
    let ptr = unsafe { entry() };
    if ptr.is_null() {
        return Err(PluginLoadError::NullHeader { path: p() });
    }
    if !(ptr as usize).is_multiple_of(align_of::<PluginHeader>()) {
        return Err(PluginLoadError::BadHeader {
            path: p(),
            field: "header".into(),
            reason: "pointer is misaligned".into(),
        });
    }
    // SAFETY: every ABI version's header starts with this 20-byte prefix; a non-null, aligned
    // header pointer is valid for at least it (ABI contract).
    let prefix = unsafe { ptr.cast::<HeaderPrefix>().read() };
    if prefix.magic != MAGIC {
        return Err(PluginLoadError::BadMagic {
            path: p(),
            found: prefix.magic,
        });
    }
    if prefix.abi_major != ABI_MAJOR {
        return Err(PluginLoadError::AbiMajor {
            path: p(),
            major: prefix.abi_major,
            minor: prefix.abi_minor,
        });
    }
    if (prefix.struct_size as usize) < size_of::<PluginHeader>() {
        return Err(PluginLoadError::ShortHeader {
            path: p(),
            size: prefix.struct_size,
            needed: size_of::<PluginHeader>(),
        });
    }
    // SAFETY: the plugin declares at least a whole ABI 1.0 header (checked above), valid for
    // the life of the library, which is never unloaded.
    let h: &'static PluginHeader = unsafe { &*ptr };
    read_header(path, h)
}

/// A directory of this process's own for fresh copies ([`load_fresh_copy`]).
fn copies_dir() -> PathBuf {
    std::env::temp_dir().join(format!("flarebench-plugin-copies-{}", std::process::id()))
}

/// Loads a fresh copy of the plugin library at `path`, beside any copy of it already loaded:
/// the file is copied to a path of its own (this process's directory in the system's
/// temporary directory, a new number each time) and the copy is loaded, so the dynamic loader
/// maps the new code instead of handing back the image it already has for `path` (it knows a
/// library by its path and its file's identity). The returned plugin's `path` and any error
/// name `path`, not the copy.
///
/// Every copy stays loaded for the life of the process, like every library ([`load`]): code
/// from an earlier copy may still be running or referenced (an instance, a pointer into its
/// static data). On Unix the copy's file is removed as soon as it is loaded (the mapping keeps
/// it alive), so nothing is left behind; on Windows a loaded DLL cannot be removed, and the
/// copies stay in the temporary directory.
pub fn load_fresh_copy(path: &Path) -> Result<LoadedPlugin, PluginLoadError> {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let copy_error = |detail: String| PluginLoadError::Copy {
        path: path.to_path_buf(),
        detail,
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| copy_error("the path names no file".into()))?;
    let dir = copies_dir();
    std::fs::create_dir_all(&dir)
        .map_err(|e| copy_error(format!("creating {}: {e}", dir.display())))?;
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mut name = std::ffi::OsString::from(format!("{n}-"));
    name.push(file_name);
    let copy = dir.join(name);
    // A file left by an earlier process of the same id (only possible where copies are kept).
    let _ = std::fs::remove_file(&copy);
    std::fs::copy(path, &copy).map_err(|e| copy_error(format!("to {}: {e}", copy.display())))?;
    let loaded = load(&copy);
    if cfg!(unix) {
        // The loaded image does not need its file any more (a failed load has nothing to keep).
        let _ = std::fs::remove_file(&copy);
    }
    match loaded {
        Ok(mut p) => {
            p.path = path.to_path_buf();
            Ok(p)
        }
        Err(e) => Err(e.with_path(path)),
    }
}

fn read_header(path: &Path, h: &'static PluginHeader) -> Result<LoadedPlugin, PluginLoadError> {
    let bad = |field: &str, reason: String| PluginLoadError::BadHeader {
        path: path.to_path_buf(),
        field: field.to_string(),
        reason,
    };
    match h.panic_unwind {
        1 => {}
        0 => {
            return Err(PluginLoadError::PanicAbort {
                path: path.to_path_buf(),
            });
        }
        v => return Err(bad("panic_unwind", format!("{v} is neither 0 nor 1"))),
    }
    // SAFETY: header strings point into the plugin's static data (ABI contract), valid while
    // the library is loaded, which is forever.
    let text = |field: &str, s: AbiStr| {
        unsafe { read_str(s) }
            .map(str::to_string)
            .map_err(|e| bad(field, e))
    };
    let name = text("name", h.name)?;
    if name.is_empty()
        || name.len() > 64
        || !name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
    {
        return Err(bad(
            "name",
            format!("`{name}` must be 1–64 ASCII letters, digits, `-` or `_`"),
        ));
    }
    let kind = PluginKind::from_code(h.kind)
        .ok_or_else(|| bad("kind", format!("unknown kind {}", h.kind)))?;
    if h.param_count > MAX_PARAMS {
        return Err(bad(
            "param_count",
            format!("{} is over {MAX_PARAMS}", h.param_count),
        ));
    }
    let descs: &[v1::ParamDesc] = if h.param_count == 0 {
        &[]
    } else if h.params.is_null() || !(h.params as usize).is_multiple_of(align_of::<v1::ParamDesc>())
    {
        return Err(bad("params", "null or misaligned".into()));
    } else {
        // SAFETY: non-null, aligned, `param_count` descriptors in the plugin's static data.
        unsafe { std::slice::from_raw_parts(h.params, h.param_count as usize) }
    };
    let mut params = Vec::with_capacity(descs.len());
    for (i, d) in descs.iter().enumerate() {
        let field = format!("params[{i}]");
        let pname = text(&field, d.name)?;
        let help = text(&field, d.help)?;
        let choices = text(&field, d.choices)?;
        let kind = match d.kind {
            v1::param_kind::FLOAT => ParamKind::Float,
            v1::param_kind::INT => ParamKind::Int,
            v1::param_kind::BOOL => ParamKind::Bool,
            v1::param_kind::CHOICE => {
                ParamKind::Choice(choices.split('|').map(str::to_string).collect())
            }
            k => return Err(bad(&field, format!("unknown type {k}"))),
        };
        let range_ok = d.min.is_finite()
            && d.max.is_finite()
            && d.min <= d.max
            && d.default >= d.min
            && d.default <= d.max;
        let whole = !matches!(kind, ParamKind::Float);
        let whole_ok =
            !whole || (d.min.fract() == 0.0 && d.max.fract() == 0.0 && d.default.fract() == 0.0);
        let choice_ok = match &kind {
            ParamKind::Choice(c) => {
                d.min == 0.0 && d.max == (c.len() - 1) as f64 && c.iter().all(|s| !s.is_empty())
            }
            ParamKind::Bool => d.min == 0.0 && d.max == 1.0,
            _ => true,
        };
        if pname.is_empty()
            || pname.contains([',', '=', ':'])
            || !range_ok
            || !whole_ok
            || !choice_ok
        {
            return Err(bad(
                &field,
                format!(
                    "`{pname}`: name, range {}..={} or default {} is invalid for its type",
                    d.min, d.max, d.default
                ),
            ));
        }
        if params.iter().any(|q: &ParamInfo| q.name == pname) {
            return Err(bad(&field, format!("`{pname}` is described twice")));
        }
        params.push(ParamInfo {
            name: pname,
            help,
            kind,
            min: d.min,
            max: d.max,
            default: d.default,
        });
    }
    let missing = |f: &str| bad(f, "function pointer is null".into());
    let functions = Functions {
        create: h.create.ok_or_else(|| missing("create"))?,
        destroy: h.destroy.ok_or_else(|| missing("destroy"))?,
        prepare: h.prepare.ok_or_else(|| missing("prepare"))?,
        render: h.render.ok_or_else(|| missing("render"))?,
    };
    Ok(LoadedPlugin {
        path: path.to_path_buf(),
        name,
        version: text("version", h.version)?,
        description: text("description", h.description)?,
        kind,
        abi_major: h.abi_major,
        abi_minor: h.abi_minor,
        sdk_version: text("sdk_version", h.sdk_version)?,
        rustc_version: text("rustc_version", h.rustc_version)?,
        params,
        functions,
    })
}

/// The host's error message buffer for one call.
struct ErrorMessage {
    bytes: Vec<u8>,
    buf: ErrorBuf,
}

impl ErrorMessage {
    fn new() -> Box<ErrorMessage> {
        let mut m = Box::new(ErrorMessage {
            bytes: vec![0; ERROR_CAPACITY],
            buf: ErrorBuf {
                ptr: std::ptr::null_mut(),
                capacity: ERROR_CAPACITY,
                len: 0,
            },
        });
        m.buf.ptr = m.bytes.as_mut_ptr();
        m
    }

    fn text(&self) -> String {
        let n = self.buf.len.min(self.bytes.len());
        String::from_utf8_lossy(&self.bytes[..n]).into_owned()
    }
}

/// What a render returned, checked.
#[derive(Clone, Debug)]
pub struct RenderResult {
    /// The image with the plugin's mesh (if any) rasterized into it.
    pub image: HdrImage,
    /// Items the plugin reports drawn (ghosts, sprites, spikes).
    pub items_drawn: u32,
    /// Triangles of the plugin's mesh.
    pub mesh_triangles: usize,
}

/// What a render reported besides its image (see [`PluginInstance::render_into`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderStats {
    /// Items the plugin reports drawn (ghosts, sprites, spikes).
    pub items_drawn: u32,
    /// Triangles of the plugin's mesh.
    pub mesh_triangles: usize,
}

/// A live plugin instance, destroyed (by the plugin) when dropped.
#[derive(Debug)]
pub struct PluginInstance<'p> {
    plugin: &'p LoadedPlugin,
    ptr: *mut c_void,
    poisoned: bool,
    /// Mesh capacities the last render asked for (vertices, triangles).
    mesh_capacity: (u32, u32),
    /// The last render's checked mesh, as the sinks take it (kept between frames).
    mesh: GhostMesh,
}

impl LoadedPlugin {
    /// A new instance.
    pub fn instantiate(&self) -> Result<PluginInstance<'_>, PluginCallError> {
        let mut err = ErrorMessage::new();
        let mut ptr: *mut c_void = std::ptr::null_mut();
        // SAFETY: `create` comes from a checked header; both pointers are valid for the call.
        let code = unsafe { (self.functions.create)(&mut ptr, &mut err.buf) };
        self.check("create", code, &err)?;
        if ptr.is_null() {
            return Err(PluginCallError::Failed {
                plugin: self.name.clone(),
                call: "create",
                message: "returned success but no instance".into(),
            });
        }
        Ok(PluginInstance {
            plugin: self,
            ptr,
            poisoned: false,
            mesh_capacity: (0, 0),
            mesh: GhostMesh::default(),
        })
    }

    fn check(
        &self,
        call: &'static str,
        code: u32,
        err: &ErrorMessage,
    ) -> Result<(), PluginCallError> {
        let plugin = self.name.clone();
        let message = err.text();
        match code {
            status::OK => Ok(()),
            status::ERROR => Err(PluginCallError::Failed {
                plugin,
                call,
                message,
            }),
            status::PANIC => Err(PluginCallError::Panicked {
                plugin,
                call,
                message,
            }),
            status::INVALID_ARGUMENT => Err(PluginCallError::InvalidArgument {
                plugin,
                call,
                message,
            }),
            status => Err(PluginCallError::UnknownStatus {
                plugin,
                call,
                status,
                message,
            }),
        }
    }
}

impl PluginInstance<'_> {
    /// The plugin this is an instance of.
    pub fn plugin(&self) -> &LoadedPlugin {
        self.plugin
    }

    fn usable(&self) -> Result<(), PluginCallError> {
        if self.poisoned {
            return Err(PluginCallError::Poisoned {
                plugin: self.plugin.name.clone(),
            });
        }
        Ok(())
    }

    fn after(&mut self, r: Result<(), PluginCallError>) -> Result<(), PluginCallError> {
        if matches!(r, Err(PluginCallError::Panicked { .. })) {
            self.poisoned = true;
        }
        r
    }

    /// Hands the plugin the lens (as our XML).
    pub fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginCallError> {
        self.usable()?;
        let xml = write_xml(lens);
        let input = LensInput {
            xml: AbiStr::new(&xml),
        };
        let mut err = ErrorMessage::new();
        // SAFETY: `prepare` comes from a checked header; the instance is live, the inputs and
        // the error buffer outlive the call.
        let code = unsafe { (self.plugin.functions.prepare)(self.ptr, &input, &mut err.buf) };
        let r = self.plugin.check("prepare", code, &err);
        self.after(r)
    }

    /// Renders `scene` with parameter `values` (one per [`LoadedPlugin::params`], e.g. from
    /// [`super::params::parse_values`]); checks the image for NaN and infinity and
    /// rasterizes the mesh, if any, into it. A scene with an aperture mask or a light
    /// spectrum other than D65 and blackbody needs a plugin of ABI 1.1 or later: a 1.0 plugin
    /// gets [`PluginCallError::Unsupported`] instead (module docs).
    pub fn render(
        &mut self,
        scene: &Scene,
        values: &[f64],
    ) -> Result<RenderResult, PluginCallError> {
        let mut image = HdrImage::new(0, 0);
        let RenderStats {
            items_drawn,
            mesh_triangles,
        } = self.render_into(scene, values, &mut image)?;
        Ok(RenderResult {
            image,
            items_drawn,
            mesh_triangles,
        })
    }

    /// [`PluginInstance::render`] into `image`, which is resized to the scene's frame and
    /// cleared first: a caller rendering frame after frame keeps one buffer (no fresh pages
    /// to fault in). On an error `image` holds no meaningful picture.
    ///
    /// The plugin's mesh is rasterized into `image` on the CPU with exact coverage: this is
    /// [`PluginInstance::render_into_sink`] with a sink that rasterizes into `image`.
    pub fn render_into(
        &mut self,
        scene: &Scene,
        values: &[f64],
        image: &mut HdrImage,
    ) -> Result<RenderStats, PluginCallError> {
        let stats = self.render_checked(scene, values, image)?;
        let width = image.width;
        let mut cpu = ExactRaster {
            pixels: &mut image.pixels,
            width,
            aperture: &scene.aperture,
        };
        self.send_mesh(scene, &mut cpu);
        Ok(stats)
    }

    /// Renders `scene` as [`PluginInstance::render_into`] does, except that the plugin's mesh
    /// goes to `sink` instead of being rasterized into `image`: the plugin's own pixels (checked
    /// finite) are left in `image`, and the caller adds what the sink draws (the CPU
    /// rasterizer, the GPU backend, a recording).
    ///
    /// The sink gets one frame of one full-resolution level,
    /// `FrameLevels { frame: scene.frame, grids: &[CoarseGrid::for_frame(w, h, 1)], aperture:
    /// &scene.aperture, coverage: Coverage::Exact }` — exact coverage, as the plugin ABI
    /// promises for plugin meshes — and, when the plugin returned a mesh, one
    /// [`GhostMesh`] in level 0 whose `open` mesh holds the plugin's checked triangles
    /// (vertex positions in pixels, attributes its RGB irradiance); `edge` and `fringe` are
    /// empty. `begin` and `finish` are called even without a mesh, so that the sink's frame is
    /// black then. On an error the sink is not called at all and `image` holds no meaningful
    /// picture.
    pub fn render_into_sink(
        &mut self,
        scene: &Scene,
        values: &[f64],
        image: &mut HdrImage,
        sink: &mut dyn GhostSink,
    ) -> Result<RenderStats, PluginCallError> {
        let stats = self.render_checked(scene, values, image)?;
        self.send_mesh(scene, sink);
        Ok(stats)
    }

    /// Hands the last render's checked mesh to `sink` as one frame (see
    /// [`PluginInstance::render_into_sink`]).
    fn send_mesh(&self, scene: &Scene, sink: &mut dyn GhostSink) {
        let f = scene.frame;
        let grids = [CoarseGrid::for_frame(f.width, f.height, 1)];
        sink.begin(FrameLevels {
            frame: f,
            grids: &grids,
            aperture: &scene.aperture,
            coverage: Coverage::Exact,
        });
        if !self.mesh.open.is_empty() {
            sink.draw(0, &self.mesh);
        }
        sink.finish();
    }

    /// Calls the plugin's render into `image` (resized and cleared first), growing the mesh
    /// buffers as it asks, and checks its output: the image into `image`, the mesh into
    /// `self.mesh` (not drawn).
    fn render_checked(
        &mut self,
        scene: &Scene,
        values: &[f64],
        image: &mut HdrImage,
    ) -> Result<RenderStats, PluginCallError> {
        self.mesh.clear();
        self.usable()?;
        let (aperture, mask) = self.aperture_input(&scene.aperture)?;
        let (lights, exts) = self.light_inputs(scene)?;
        let input = self.scene_input(scene, aperture, mask, (&lights, &exts))?;
        let f = scene.frame;
        loop {
            clear_frame(image, f.width, f.height);
            let (vcap, tcap) = self.mesh_capacity;
            let mut vertices = vec![
                MeshVertex {
                    x: 0.0,
                    y: 0.0,
                    rgb: [0.0; 3]
                };
                vcap as usize
            ];
            let mut triangles = vec![[0u32; 3]; tcap as usize];
            let mut output = RenderOutput {
                image: ImageBuffer {
                    pixels: image.pixels.as_mut_ptr().cast::<f32>(),
                    width: input.width,
                    height: input.height,
                },
                mesh: MeshBuffer {
                    vertices: vertices.as_mut_ptr(),
                    vertex_capacity: vcap,
                    vertex_count: 0,
                    triangles: triangles.as_mut_ptr(),
                    triangle_capacity: tcap,
                    triangle_count: 0,
                },
                items_drawn: 0,
                reserved: 0,
            };
            let mut err = ErrorMessage::new();
            let Ok(count) = u32::try_from(values.len()) else {
                return Err(self.unsupported("too many parameter values".into()));
            };
            // SAFETY: `render` comes from a checked header; the instance is live; the scene,
            // lights, light extensions, mask (borrowed from `scene`), values, image, mesh
            // buffers (with the capacities stated) and the error buffer are valid and outlive
            // the call; nothing else accesses them meanwhile.
            let code = unsafe {
                (self.plugin.functions.render)(
                    self.ptr,
                    &input,
                    values.as_ptr(),
                    count,
                    &mut output,
                    &mut err.buf,
                )
            };
            if code == status::MESH_CAPACITY {
                self.grow_mesh((output.mesh.vertex_count, output.mesh.triangle_count))?;
                continue;
            }
            let r = self.plugin.check("render", code, &err);
            self.after(r)?;
            let counts = (
                output.mesh.vertex_count as usize,
                output.mesh.triangle_count as usize,
            );
            let nt = self.check_output(image, counts, &vertices, &triangles)?;
            return Ok(RenderStats {
                items_drawn: output.items_drawn,
                mesh_triangles: nt,
            });
        }
    }

    /// [`PluginCallError::Unsupported`] from this plugin.
    fn unsupported(&self, reason: String) -> PluginCallError {
        PluginCallError::Unsupported {
            plugin: self.plugin.name.clone(),
            reason,
        }
    }

    /// What only ABI 1.1 can say (`what`): refused for a 1.0 plugin, which would misread it.
    fn needs_1_1(&self, what: String) -> Result<(), PluginCallError> {
        let minor = self.plugin.abi_minor;
        if minor >= 1 {
            return Ok(());
        }
        Err(self.unsupported(format!(
            "{what} needs plugin ABI {ABI_MAJOR}.1, but the plugin was built for ABI \
             {ABI_MAJOR}.{minor} (sdk {}); rebuild it against this sdk",
            self.plugin.sdk_version
        )))
    }

    /// The aperture as the ABI describes it, and a mask's width, height and pixels.
    fn aperture_input(
        &self,
        aperture: &Aperture,
    ) -> Result<(v1::ApertureInput, Option<MaskInput>), PluginCallError> {
        Ok(match aperture {
            Aperture::Circular => (
                v1::ApertureInput {
                    kind: v1::aperture_kind::CIRCULAR,
                    blades: 0,
                    rotation_rad: 0.0,
                    roundness: 0.0,
                },
                None,
            ),
            &Aperture::Iris {
                blades,
                rotation_rad,
                roundness,
            } => (
                v1::ApertureInput {
                    kind: v1::aperture_kind::IRIS,
                    blades,
                    rotation_rad,
                    roundness,
                },
                None,
            ),
            Aperture::Mask(m) => {
                self.needs_1_1("an aperture mask image".into())?;
                let (Ok(w), Ok(h)) = (u32::try_from(m.width()), u32::try_from(m.height())) else {
                    return Err(self.unsupported("aperture mask too large".into()));
                };
                let input = v1::ApertureInput {
                    kind: v1::aperture_kind::MASK,
                    blades: 0,
                    rotation_rad: 0.0,
                    roundness: 0.0,
                };
                (input, Some((w, h, m.data().as_ptr())))
            }
        })
    }

    /// The scene's lights as the ABI describes them, with their spectrum extensions (1.1).
    fn light_inputs(
        &self,
        scene: &Scene,
    ) -> Result<(Vec<LightInput>, Vec<LightExt>), PluginCallError> {
        let mut lights = Vec::with_capacity(scene.lights.len());
        let mut exts = Vec::with_capacity(scene.lights.len());
        for (i, l) in scene.lights.iter().enumerate() {
            let (kelvin, ext) = match l.spectrum {
                LightSpectrum::D65 => (0.0, None),
                LightSpectrum::Blackbody { kelvin } => (kelvin, None),
                LightSpectrum::Rgb(rgb) => (KELVIN_SEE_EXT, Some((light_spectrum::RGB, rgb))),
                LightSpectrum::Flat => (KELVIN_SEE_EXT, Some((light_spectrum::FLAT, [0.0; 3]))),
            };
            if ext.is_some() {
                self.needs_1_1(format!("light {i}'s spectrum {:?}", l.spectrum))?;
            }
            let (spectrum, rgb) = ext.unwrap_or((light_spectrum::KELVIN, [0.0; 3]));
            exts.push(LightExt { spectrum, rgb });
            lights.push(LightInput {
                theta_deg: l.theta_deg,
                phi_deg: l.phi_deg,
                intensity: l.intensity,
                kelvin,
            });
        }
        Ok((lights, exts))
    }

    /// The scene input, in the host's minor; it points into `lights`, `exts` and the mask.
    fn scene_input(
        &self,
        scene: &Scene,
        aperture: v1::ApertureInput,
        mask: Option<MaskInput>,
        (lights, exts): (&[LightInput], &[LightExt]),
    ) -> Result<SceneInput, PluginCallError> {
        // Only when some light needs it: a scene 1.0 could say stays as 1.0 said it.
        let light_ext = if exts.iter().any(|e| e.spectrum != light_spectrum::KELVIN) {
            exts.as_ptr()
        } else {
            std::ptr::null()
        };
        let f = scene.frame;
        let (Ok(width), Ok(height), Ok(light_count)) = (
            u32::try_from(f.width),
            u32::try_from(f.height),
            u32::try_from(lights.len()),
        ) else {
            return Err(self.unsupported("frame or light count too large".into()));
        };
        let (mask_width, mask_height, mask) = mask.unwrap_or((0, 0, std::ptr::null()));
        Ok(SceneInput {
            struct_size: size_of::<SceneInput>() as u32,
            light_count,
            lights: lights.as_ptr(),
            width,
            height,
            film_width_mm: f.film_width_mm,
            film_height_mm: f.film_height_mm,
            aperture,
            mask_width,
            mask_height,
            mask,
            light_ext,
        })
    }

    /// After [`status::MESH_CAPACITY`]: the capacities the plugin asked for, which must exceed
    /// the ones it had.
    fn grow_mesh(&mut self, need: (u32, u32)) -> Result<(), PluginCallError> {
        let (vcap, tcap) = self.mesh_capacity;
        if need.0 <= vcap && need.1 <= tcap {
            return Err(PluginCallError::BadMesh {
                plugin: self.plugin.name.clone(),
                reason: format!("asked for capacity {need:?} but already had ({vcap}, {tcap})"),
            });
        }
        self.mesh_capacity = (need.0.max(vcap), need.1.max(tcap));
        Ok(())
    }

    /// Checks a successful render's output — mesh counts within the capacities, a finite image,
    /// a well-formed mesh — and keeps the mesh in `self.mesh` (its `open` triangles, attributes
    /// the vertices' RGB). Returns the triangle count.
    fn check_output(
        &mut self,
        image: &HdrImage,
        (nv, nt): (usize, usize),
        vertices: &[MeshVertex],
        triangles: &[[u32; 3]],
    ) -> Result<usize, PluginCallError> {
        let name = || self.plugin.name.clone();
        let (vcap, tcap) = self.mesh_capacity;
        if nv > vcap as usize || nt > tcap as usize {
            return Err(PluginCallError::BadMesh {
                plugin: name(),
                reason: format!("counts {nv}/{nt} exceed the capacities {vcap}/{tcap}"),
            });
        }
        check_finite(image).map_err(|(count, x, y)| PluginCallError::NonFinite {
            plugin: name(),
            count,
            x,
            y,
        })?;
        if nt > 0 {
            let vs = &vertices[..nv];
            let ts = &triangles[..nt];
            if let Some(t) = ts.iter().find(|t| t.iter().any(|&i| i as usize >= nv)) {
                return Err(PluginCallError::BadMesh {
                    plugin: name(),
                    reason: format!("triangle {t:?} indexes past {nv} vertices"),
                });
            }
            if let Some(v) = vs.iter().find(|v| {
                ![v.x, v.y, v.rgb[0], v.rgb[1], v.rgb[2]]
                    .iter()
                    .all(|c| c.is_finite())
            }) {
                return Err(PluginCallError::BadMesh {
                    plugin: name(),
                    reason: format!("vertex {v:?} is not finite"),
                });
            }
            let open = &mut self.mesh.open;
            open.positions.extend(vs.iter().map(|v| [v.x, v.y]));
            open.attrs.extend(vs.iter().map(|v| v.rgb));
            open.triangles.extend_from_slice(ts);
        }
        Ok(nt)
    }
}

/// The CPU sink of [`PluginInstance::render_into`]: rasterizes a plugin's meshes, with the
/// frame's (exact) coverage, into the full-resolution image the plugin drew into.
struct ExactRaster<'a> {
    pixels: &'a mut [[f32; 3]],
    width: usize,
    aperture: &'a Aperture,
}

impl GhostSink for ExactRaster<'_> {
    fn begin(&mut self, levels: FrameLevels<'_>) {
        debug_assert!(levels.coverage == Coverage::Exact && levels.grids.len() == 1);
    }

    fn draw(&mut self, _level: usize, mesh: &GhostMesh) {
        rasterize_ghost_mesh_with(
            self.pixels,
            self.width,
            mesh,
            self.aperture,
            Coverage::Exact,
        );
    }

    fn finish(&mut self) {}
}

/// An aperture mask for the ABI: width, height and its row-major pixels (borrowed).
type MaskInput = (u32, u32, *const f32);

/// Sizes `image` to `width × height` and clears it: on every core when it already has that
/// size (the last frame's buffer), else by refilling.
fn clear_frame(image: &mut HdrImage, width: usize, height: usize) {
    image.width = width;
    image.height = height;
    if image.pixels.len() == width * height {
        // The same buffer as the last frame's: cleared on every core.
        image.fill_black();
    } else {
        image.pixels.clear();
        image.pixels.resize(width * height, [0.0; 3]);
    }
}

/// Count of non-finite values and the first offending pixel.
fn check_finite(img: &HdrImage) -> Result<(), (usize, usize, usize)> {
    // Fast pass: `x · 0` is 0 for finite x and NaN otherwise, so a chunk's sum of them is
    // NaN exactly when the chunk holds a non-finite value. It vectorises, and chunks run on
    // all cores; only an image that fails it is scanned value by value.
    fn chunk_finite(chunk: &[f32]) -> bool {
        // Sixteen independent sums, so that the loop vectorises.
        let mut acc = [0.0_f32; 16];
        let mut lanes = chunk.chunks_exact(16);
        for l in &mut lanes {
            for (a, &x) in acc.iter_mut().zip(l) {
                *a += x * 0.0;
            }
        }
        let rest = lanes.remainder().iter().fold(0.0, |a, &x| a + x * 0.0);
        acc.iter().sum::<f32>() + rest == 0.0
    }
    let all_finite = img
        .pixels
        .as_flattened()
        .par_chunks(1 << 15)
        .all(chunk_finite);
    if all_finite {
        return Ok(());
    }
    let mut count = 0;
    let mut first = None;
    for (i, p) in img.pixels.iter().enumerate() {
        let bad = p.iter().filter(|c| !c.is_finite()).count();
        if bad > 0 {
            count += bad;
            first.get_or_insert(i);
        }
    }
    match first {
        None => Ok(()),
        Some(i) => Err((count, i % img.width.max(1), i / img.width.max(1))),
    }
}

impl Drop for PluginInstance<'_> {
    fn drop(&mut self) {
        // SAFETY: `ptr` came from this plugin's `create` and is destroyed once, here; the
        // plugin's destroy catches panics in its drop.
        unsafe { (self.plugin.functions.destroy)(self.ptr) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_finite_check_finds_every_kind_of_bad_value_anywhere() {
        // Big enough for several parallel chunks and a remainder past the 16-lane loop.
        let (w, h) = (301, 257);
        let mut img = HdrImage::new(w, h);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = [f32::MAX, -f32::MAX, k as f32 * 1e-3];
        }
        assert_eq!(check_finite(&img), Ok(()));
        for (k, bad) in [
            (0, f32::NAN),
            (w * h - 1, f32::INFINITY),
            (w * 100 + 7, f32::NEG_INFINITY),
        ] {
            let mut img = img.clone();
            img.pixels[k][2] = bad;
            assert_eq!(
                check_finite(&img),
                Err((1, k % w, k / w)),
                "value {bad} at {k}"
            );
        }
        let mut img = img.clone();
        img.pixels[5][0] = f32::NAN;
        img.pixels[9][1] = f32::NAN;
        assert_eq!(check_finite(&img), Err((2, 5, 0)));
    }
}
