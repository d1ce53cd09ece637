//! What the ghost renderer works from and what it reports: the lens data fixed for a frame
//! ([`GhostContext`]), the light ([`GhostLight`]), one ghost's grid to trace ([`GhostGrid`]),
//! the wavelength bands ([`Band`], [`BandRef`]) and the counts of a render ([`GhostStats`]).

use crate::aperture::Aperture;
use crate::frame::Frame;
use crate::system::LensSystem;
use crate::trace::InterfaceTableSet;
use std::sync::Arc;

use super::bounds::GhostBounds;
use super::enumerate::GhostPath;

/// One wavelength band of a spectral render: where to trace and what colour it adds.
#[derive(Clone, Debug)]
pub struct Band {
    pub lambda_nm: f64,
    /// Linear-sRGB weight of the band (for a light of unit irradiance).
    pub rgb: [f32; 3],
    /// The lens's interface tables at `lambda_nm` (shared: a lens's tables at a wavelength
    /// serve every frame's plan).
    pub tables: Arc<InterfaceTableSet>,
}

impl Band {
    /// A band at `lambda_nm` with colour `rgb` for `system`.
    pub fn new(system: &LensSystem, lambda_nm: f64, rgb: [f32; 3]) -> Self {
        Band {
            lambda_nm,
            rgb,
            tables: Arc::new(InterfaceTableSet::for_system(system, lambda_nm)),
        }
    }

    /// The band as the renderer takes it.
    pub fn as_ref(&self) -> BandRef<'_> {
        BandRef {
            lambda_nm: self.lambda_nm,
            rgb: self.rgb,
            tables: &self.tables,
        }
    }
}

/// A band to trace: wavelength, colour, and the lens's interface tables at that wavelength
/// (shared between ghosts; the colour may be a ghost's own).
#[derive(Clone, Copy, Debug)]
pub struct BandRef<'a> {
    pub lambda_nm: f64,
    pub rgb: [f32; 3],
    pub tables: &'a InterfaceTableSet,
}

/// A collimated light as the ghost renderer sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GhostLight {
    /// Angle to the axis and azimuth (radians).
    pub theta: f64,
    pub phi: f64,
    /// Irradiance perpendicular to the beam (image units per mm²).
    pub irradiance: f64,
}

/// What rendering a ghost did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GhostStats {
    /// Rays traced (grid vertices × bands).
    pub rays: usize,
    /// Triangles rasterised.
    pub triangles: usize,
    /// Flux carried by the rasterised triangles (before the frame crops it), summed over the
    /// bands' luminance weights.
    pub flux: f64,
}

/// Everything fixed for a frame: lens data the renderer needs per ghost.
#[derive(Clone, Copy, Debug)]
pub struct GhostContext<'a> {
    pub system: &'a LensSystem,
    pub aperture: &'a Aperture,
    pub frame: Frame,
    /// The stop's working radius (mm) and the working f-number.
    pub stop_radius: f64,
    pub f_number: f64,
    /// Trace the grids in f64 instead of f32. The f32 images agree with the f64 ones to a
    /// relative RMSE of 6e-6 (Heliar), 4.5e-4 (Nikon zoom), 1.6e-5 (fisheye at 60°)
    /// (`algorithms/ghost-raytrace/tests/precision.rs`).
    pub trace_f64: bool,
}

/// One ghost to trace: its path, lit by `light`, with an `n × n` grid over `bounds.entrance`.
#[derive(Clone, Copy, Debug)]
pub struct GhostGrid<'a> {
    pub path: GhostPath,
    pub bounds: &'a GhostBounds,
    /// Grid vertices per side.
    pub n: usize,
    pub light: GhostLight,
}
