//! The viewer window (`flarebench view`, `flarebench edit --window`): the lens's meridional
//! section with ray fans and the selected ghost's path beside a live flare preview, with a
//! status line. winit + wgpu, panels and painting by egui.
//!
//! - `app`: the viewer's state and its UI pass (`Viewer::frame`), the link with the editor
//! - `lens_picker`: the bundled library in a searchable list (`O`), to open another lens
//! - `lens_view`: the lens section painted from [`crate::lens_drawing`], pan, zoom, hover
//! - `flare_view`: the flare image, light drag, exposure, ghost picking and labels
//! - `flare_worker`: the render thread (newest job wins; fast, settled, reference stages)
//! - `ghost_debug`: the selected ghost traced alone for the debug views (on the render thread)
//! - `debug_view`: the debug views drawn over the flare (grid, stop, relative radius,
//!   irradiance) and their false-colour ramp
//! - `bounds_table`: the lens's ghost bounds tabulated over the light's angles while the render
//!   thread is idle, for fast frames planned by lookup
//! - `plugins`: the ghost plugins (`--algo`) and the thread that reloads their rebuilt libraries
//! - `status`: the status line
//! - `gfx`: egui's shapes drawn with wgpu into any texture view
//! - `offscreen`: the viewer drawn into a texture and read back (tests, screenshots)
//! - `window`: winit's event loop, the surface, input
//!
//! docs/window.md describes the views, the controls and the threads.

pub mod app;
pub mod bounds_table;
pub mod debug_view;
pub mod flare_view;
pub mod flare_worker;
pub mod gfx;
pub mod ghost_debug;
pub mod lens_picker;
pub mod lens_view;
pub mod offscreen;
pub mod plugins;
pub mod status;
pub mod window;

/// The starburst mode of [`ViewerOptions`] (`render --starburst`).
pub use crate::flare::StarburstMode;
pub use app::{EditorLink, Viewer, ViewerOptions};
