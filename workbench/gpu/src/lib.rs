//! flarebench's GPU backend on wgpu: a frame's ghost meshes (the backend-neutral description
//! the CPU rasterizer also draws from, `flarebench_sdk::ghost::sink`) shaded and rasterized
//! into linear HDR float targets, coarse levels upsampled, starbursts composited, tone mapped;
//! headless, with readback for files. See `docs/gpu.md`.
//!
//! - [`device`]: finding an adapter, opening the device, its errors kept per frame.
//! - [`renderer`]: [`GhostRenderer`], the ghost meshes drawn level by level.
//! - `pipelines`, `targets`, `buffers`, `uniforms`, `timing`: what the renderer is made of.
//! - [`compose`]: starbursts composited from their patterns, and the tone-mapping pass.
//! - `shaders/`: the WGSL (aperture, rasterizer, upsampling, starburst, tone mapping).

mod buffers;
pub mod compose;
pub mod device;
mod error;
pub mod fringe;
mod pipelines;
pub mod renderer;
mod targets;
mod timing;
mod uniforms;

pub use compose::ToneCurve;
pub use device::{AdapterChoice, AdapterReport, GpuContext};
pub use error::GpuError;
pub use renderer::{FrameReport, GhostRenderer};
pub use targets::AccumFormat;
pub use timing::PassTiming;
