//! flarebench-sdk: the optics core shared by every flare algorithm and the workbench.
//!
//! - [`system`]: the lens prescription model ([`LensSystem`], [`Surface`]) and its validation,
//!   with the optional sensor stack (plates in front of the sensor, its spectral reflectance).
//! - [`glass`]: dispersion — the exact two-term Cauchy fit from nd/Vd and the refractiveindex.info
//!   catalogue formulas for 1613 named glasses.
//! - [`io`]: reading and writing lens files (OpenLensFlare XML and our superset of it, Zemax
//!   `.zmx`, PBRT `.dat`, FlareSim `.lens`) and OpenLensFlare's ghost bounds.
//! - [`trace`]: the sequential ray tracer (scalar f64, batched structure-of-arrays f32/f64).
//! - [`fresnel`] and [`coating`]: interface reflectance, bare and with thin-film coatings.
//! - [`paraxial`]: first-order analysis (focal lengths, pupils, f-number, Petzval sum).
//! - [`aperture`]: the stop's opening (circle, iris of straight or rounded blades, mask image),
//!   shared by ghosts and the starburst.
//! - [`color`]: spectral → colour (CIE 1931 observer, linear sRGB, light spectra, the
//!   wavelengths a render samples and their RGB weights).
//! - [`image`] and [`raster`]: linear HDR images and the exact-coverage CPU triangle rasterizer.
//! - [`frame`]: the output image's pixels ↔ the part of the sensor it shows ([`Frame`]).
//! - [`spectrum`]: the d, F and C line wavelengths.
//! - [`lens_kind`]: what kind of lens a prescription is (prime, zoom, fisheye, …), for finding it.
//! - [`rect`], [`ghost_path`] and [`fingerprint`]: the rectangle, the ghost path and the lens
//!   fingerprint, shared by `trace`, `io` and `ghost` so that neither of the first two depends on
//!   `ghost` (the layers are in `tests/layering.rs`).
//! - [`ghost`]: ghost paths, their traced grids and bounds, bounds tables, the four-reflection
//!   energy bound, and meshing a ghost for the rasterizer.
//! - [`starburst`]: the Fraunhofer diffraction starburst of the aperture.
//! - [`abi`]: the plugin interface (the versioned C ABI, the author's trait and export macro,
//!   the host's loader).
//!
//! Conventions (docs/ARCHITECTURE.md §4; the formulas are in docs/physics.md): millimetres,
//! nanometres for wavelengths, radians inside; surfaces are listed object side first;
//! curvature `c = 1/R` with `R > 0` meaning the centre of curvature lies toward the sensor; the
//! optical axis is +z toward the sensor.

pub mod abi;
pub mod aperture;
pub mod coating;
pub mod color;
pub mod fingerprint;
pub mod frame;
pub mod fresnel;
pub mod ghost;
pub mod ghost_path;
pub mod glass;
pub mod hash;
pub mod image;
pub mod io;
pub mod lens_kind;
pub mod paraxial;
pub mod raster;
pub mod rect;
pub mod spectrum;
pub mod starburst;
pub mod system;
pub mod trace;

pub use frame::Frame;
pub use glass::{Dispersion, GlassCatalog};
pub use lens_kind::LensKind;
pub use system::{Coating, LensSystem, Medium, Surface, SurfaceKind};
