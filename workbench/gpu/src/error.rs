//! What can go wrong on the GPU side, each with what to do about it.

/// An error of the GPU backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all: no Vulkan, Metal or DX12 driver was found.
    #[error(
        "no GPU adapter found{backends}: install a Vulkan driver (on Debian or Ubuntu, \
         `apt-get install mesa-vulkan-drivers libvulkan1` gives the software driver lavapipe; \
         a GPU vendor's driver for real hardware), or render with `--backend cpu`"
    )]
    NoAdapter {
        /// ` (WGPU_BACKEND=…)` when the environment narrowed the search, else empty.
        backends: String,
    },
    /// Only a software adapter was found while a hardware one was asked for.
    #[error(
        "no hardware GPU adapter: only the software adapter {name} ({driver}) was found; \
         `--backend gpu` uses it (slowly), `--backend cpu` renders on the CPU"
    )]
    SoftwareOnly { name: String, driver: String },
    /// The adapter lacks something the backend needs.
    #[error("the GPU adapter {name} cannot be used: {what}")]
    Unsupported { name: String, what: String },
    /// The device could not be created.
    #[error("could not open the GPU device {name}: {source}")]
    RequestDevice {
        name: String,
        #[source]
        source: wgpu::RequestDeviceError,
    },
    /// The device was lost, or reported an error, while drawing.
    #[error(
        "the GPU device failed during the frame ({what}); the CPU path (`--backend cpu`) is unaffected"
    )]
    Device { what: String },
    /// Reading the image back failed.
    #[error("reading the frame back from the GPU failed: {what}")]
    Readback { what: String },
    /// A frame too large for the adapter's textures.
    #[error("a {width} × {height} frame exceeds the GPU's largest texture ({max} pixels a side)")]
    FrameTooLarge {
        width: usize,
        height: usize,
        max: u32,
    },
}
