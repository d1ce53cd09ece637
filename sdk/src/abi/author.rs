//! The plugin author's side: the safe [`FlarePlugin`] trait, parameter specifications, the scene
//! a render receives and the output it writes. Nothing here is `#[repr(C)]`; the thunks in
//! [`super::export`] translate to and from [`super::v1`].

use std::fmt;

use crate::LensSystem;
use crate::aperture::Aperture;
use crate::color::LightSpectrum;
use crate::frame::Frame;
use crate::image::HdrImage;

use super::v1;

/// What a plugin draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PluginKind {
    /// Ghosts (internal reflections).
    Ghosts,
    /// A diffraction starburst.
    Starburst,
    /// Anything else.
    Other,
}

impl PluginKind {
    /// The [`v1::kind`] code.
    pub fn code(self) -> u32 {
        match self {
            PluginKind::Ghosts => v1::kind::GHOSTS,
            PluginKind::Starburst => v1::kind::STARBURST,
            PluginKind::Other => v1::kind::OTHER,
        }
    }

    /// The kind of a [`v1::kind`] code; `None` for an unknown code.
    pub fn from_code(code: u32) -> Option<PluginKind> {
        match code {
            v1::kind::GHOSTS => Some(PluginKind::Ghosts),
            v1::kind::STARBURST => Some(PluginKind::Starburst),
            v1::kind::OTHER => Some(PluginKind::Other),
            _ => None,
        }
    }

    /// `ghosts`, `starburst` or `other`.
    pub fn name(self) -> &'static str {
        match self {
            PluginKind::Ghosts => "ghosts",
            PluginKind::Starburst => "starburst",
            PluginKind::Other => "other",
        }
    }
}

/// The type of a parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamType {
    /// A real number.
    Float,
    /// A whole number.
    Int,
    /// On or off (0 or 1).
    Bool,
    /// One of these names; the value is its index.
    Choice(&'static [&'static str]),
}

/// One parameter of a plugin: shown by `flarebench plugins list` and set with
/// `--algo NAME:key=value`. Every value travels as `f64` (an index for a choice, 0/1 for a bool).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    pub name: &'static str,
    /// One line, with the unit.
    pub help: &'static str,
    pub ty: ParamType,
    /// Inclusive range and default.
    pub min: f64,
    pub max: f64,
    pub default: f64,
}

impl ParamSpec {
    /// A real number in `[min, max]`.
    pub const fn float(
        name: &'static str,
        help: &'static str,
        min: f64,
        max: f64,
        default: f64,
    ) -> ParamSpec {
        ParamSpec {
            name,
            help,
            ty: ParamType::Float,
            min,
            max,
            default,
        }
    }

    /// A whole number in `[min, max]`.
    pub const fn int(
        name: &'static str,
        help: &'static str,
        min: i64,
        max: i64,
        default: i64,
    ) -> ParamSpec {
        ParamSpec {
            name,
            help,
            ty: ParamType::Int,
            min: min as f64,
            max: max as f64,
            default: default as f64,
        }
    }

    /// On or off.
    pub const fn bool(name: &'static str, help: &'static str, default: bool) -> ParamSpec {
        ParamSpec {
            name,
            help,
            ty: ParamType::Bool,
            min: 0.0,
            max: 1.0,
            default: if default { 1.0 } else { 0.0 },
        }
    }

    /// One of `choices`, `default` being an index into them.
    pub const fn choice(
        name: &'static str,
        help: &'static str,
        choices: &'static [&'static str],
        default: usize,
    ) -> ParamSpec {
        ParamSpec {
            name,
            help,
            ty: ParamType::Choice(choices),
            min: 0.0,
            max: (choices.len() as f64) - 1.0,
            default: default as f64,
        }
    }
}

/// A plugin's description of itself.
#[derive(Clone, Debug)]
pub struct PluginInfo {
    /// Short unique name: ASCII letters, digits, `-` and `_`.
    pub name: &'static str,
    pub version: &'static str,
    /// One line.
    pub description: &'static str,
    pub kind: PluginKind,
    pub params: Vec<ParamSpec>,
}

/// An error a plugin reports; it reaches the host as its message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PluginError {
    pub message: String,
}

impl PluginError {
    /// An error with this message.
    pub fn new(message: impl Into<String>) -> PluginError {
        PluginError {
            message: message.into(),
        }
    }
}

impl fmt::Display for PluginError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// Any error converts, with its chain of causes joined by `: `.
impl<E: std::error::Error> From<E> for PluginError {
    fn from(e: E) -> Self {
        let mut message = e.to_string();
        let mut source = e.source();
        while let Some(s) = source {
            message.push_str(": ");
            message.push_str(&s.to_string());
            source = s.source();
        }
        PluginError { message }
    }
}

/// A light at infinity, as a render receives it (checked: finite, θ in `[0, 90)`, intensity
/// > 0, a valid spectrum).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneLight {
    /// Angle to the optical axis and azimuth about it (degrees).
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Irradiance perpendicular to the beam (image units per mm² of entrance pupil).
    pub intensity: f64,
    /// Any [`LightSpectrum`]: D65 or a blackbody (ABI 1.0), linear sRGB or flat (since 1.1).
    pub spectrum: LightSpectrum,
}

/// What to render.
#[derive(Clone, Debug)]
pub struct Scene {
    pub lights: Vec<SceneLight>,
    /// Output size and the part of the sensor it shows.
    pub frame: Frame,
    /// The stop's shape: circle or iris (ABI 1.0), or a mask image (since 1.1).
    pub aperture: Aperture,
}

/// Parameter values, in the order of the plugin's [`PluginInfo::params`], checked against
/// their ranges before the plugin sees them.
#[derive(Clone, Copy, Debug)]
pub struct Params<'a> {
    specs: &'a [ParamSpec],
    values: &'a [f64],
}

impl<'a> Params<'a> {
    /// Pairs specifications with values (same length; the thunks check it).
    pub fn new(specs: &'a [ParamSpec], values: &'a [f64]) -> Params<'a> {
        Params { specs, values }
    }

    /// The value of parameter `name`, or an error naming it when the plugin has no such
    /// parameter (a bug in the plugin).
    pub fn get(&self, name: &str) -> Result<f64, PluginError> {
        self.specs
            .iter()
            .position(|s| s.name == name)
            .and_then(|i| self.values.get(i).copied())
            .ok_or_else(|| PluginError::new(format!("no parameter `{name}`")))
    }

    /// A whole-number parameter.
    pub fn get_int(&self, name: &str) -> Result<i64, PluginError> {
        Ok(self.get(name)?.round() as i64)
    }

    /// A boolean parameter.
    pub fn get_bool(&self, name: &str) -> Result<bool, PluginError> {
        Ok(self.get(name)? != 0.0)
    }

    /// A choice parameter's index.
    pub fn get_choice(&self, name: &str) -> Result<usize, PluginError> {
        Ok(self.get(name)?.round().max(0.0) as usize)
    }
}

/// A triangle mesh for the host to rasterize: vertices in pixels with linear RGB radiance per
/// pixel², interpolated linearly across each triangle.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<v1::MeshVertex>,
    pub triangles: Vec<[u32; 3]>,
}

/// Where a render writes: the host's image (zeroed, `width × height` linear RGB pixels, row 0
/// at the top) and, optionally, a mesh the host rasterizes and adds.
#[derive(Debug)]
pub struct Output<'a> {
    pub width: usize,
    pub height: usize,
    /// Row-major pixels, owned by the host.
    pub pixels: &'a mut [[f32; 3]],
    /// Triangles to rasterize (left empty by most plugins).
    pub mesh: Mesh,
    /// Ghosts, sprites or spikes drawn (for the host's report).
    pub items_drawn: u32,
}

impl Output<'_> {
    /// Adds an image of the output's size into it.
    pub fn add_image(&mut self, img: &HdrImage) -> Result<(), PluginError> {
        if img.width != self.width || img.height != self.height {
            return Err(PluginError::new(format!(
                "image of {}x{} does not match the output's {}x{}",
                img.width, img.height, self.width, self.height
            )));
        }
        for (o, p) in self.pixels.iter_mut().zip(&img.pixels) {
            for c in 0..3 {
                o[c] += p[c];
            }
        }
        Ok(())
    }
}

/// A flare algorithm as a plugin. Implement it and call [`export_plugin!`](crate::export_plugin)
/// once with the type; every call then reaches the plugin through the checked, panic-catching
/// thunks of [`super::export`]. The host calls `prepare` before the first `render` and whenever
/// the lens changes, from one thread at a time.
pub trait FlarePlugin: Sized {
    /// Name, version, kind and parameters. Called once, when the library is first asked for
    /// its header.
    fn info() -> PluginInfo;
    /// A new instance (no lens yet).
    fn create() -> Result<Self, PluginError>;
    /// Takes the lens (validated by the sdk's reader) and precomputes what renders need.
    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError>;
    /// Renders the scene with these parameter values into `out`.
    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError>;
}
