//! flarebench's GPU backend on wgpu: a frame's ghost meshes (the backend-neutral description
//! the CPU rasterizer also draws from, `flarebench_sdk::ghost::sink`) shaded and rasterized
//! into linear HDR float targets, coarse levels upsampled, starbursts composited, tone mapped;
//! headless, with readback for files. See `docs/gpu.md`.

pub mod device;
mod error;

pub use device::{AdapterChoice, AdapterReport, GpuContext};
pub use error::GpuError;
