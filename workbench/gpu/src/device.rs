//! Finding an adapter and opening a device: [`GpuContext`], and the report of what was found
//! ([`AdapterReport`]).

use std::sync::{Arc, Mutex};

use crate::GpuError;

/// Which adapters may be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdapterChoice {
    /// A hardware GPU only (discrete, integrated or virtual); a software adapter such as
    /// lavapipe is refused ([`GpuError::SoftwareOnly`]).
    Hardware,
    /// The best adapter there is, a software one if nothing else.
    Any,
}

/// What the backend runs on, for reports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterReport {
    /// The adapter's name (`llvmpipe (LLVM 15.0.6, 256 bits)` for lavapipe).
    pub name: String,
    /// Its driver and driver version.
    pub driver: String,
    /// The graphics API: `vulkan`, `metal`, `dx12`.
    pub backend: String,
    /// `discrete`, `integrated`, `virtual`, `cpu` or `other`.
    pub device_type: String,
    /// True when the adapter runs on the CPU (lavapipe, WARP, SwiftShader).
    pub software: bool,
    /// True when the device measures GPU time per pass (timestamp queries).
    pub timestamps: bool,
    /// True when the device blends into 32-bit float targets (`FLOAT32_BLENDABLE`), which
    /// the default accumulation format ([`crate::AccumFormat::F32`]) needs.
    pub float32_blendable: bool,
}

/// An open device with its queue, and what it runs on. Errors the device reports outside a
/// call (validation, out of memory, a lost device) are kept and returned by
/// [`GpuContext::check`].
#[derive(Debug)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub report: AdapterReport,
    pub limits: wgpu::Limits,
    errors: Arc<Mutex<Option<String>>>,
}

impl GpuContext {
    /// Opens the best adapter `choice` allows. The environment variable `WGPU_BACKEND`
    /// (`vulkan`, `metal`, `dx12`) narrows the search, as in every wgpu program.
    pub fn new(choice: AdapterChoice) -> Result<GpuContext, GpuError> {
        let backends = std::env::var("WGPU_BACKEND")
            .map(|b| format!(" (WGPU_BACKEND={b})"))
            .unwrap_or_default();
        let instance = headless_instance();
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        let best = adapters.into_iter().min_by_key(rank);
        let Some(adapter) = best else {
            return Err(GpuError::NoAdapter { backends });
        };
        let info = adapter.get_info();
        let software = matches!(info.device_type, wgpu::DeviceType::Cpu);
        if software && choice == AdapterChoice::Hardware {
            return Err(GpuError::SoftwareOnly {
                driver: driver_text(&info),
                name: info.name,
            });
        }
        let features = adapter.features();
        // Asked for where there is one: a renderer accumulating in f32 needs it
        // (`GhostRenderer::new` says so), one accumulating in f16 does not.
        let float32_blendable = features.contains(wgpu::Features::FLOAT32_BLENDABLE);
        let timestamps = features.contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required = wgpu::Features::empty();
        if float32_blendable {
            required |= wgpu::Features::FLOAT32_BLENDABLE;
        }
        if timestamps {
            required |= wgpu::Features::TIMESTAMP_QUERY;
        }
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("flarebench"),
            required_features: required,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|source| GpuError::RequestDevice {
            name: info.name.clone(),
            source,
        })?;
        let errors = Arc::new(Mutex::new(None));
        let sink = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| e.to_string());
        }));
        let lost = Arc::clone(&errors);
        device.set_device_lost_callback(move |reason, message| {
            let mut slot = lost.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| format!("device lost ({reason:?}): {message}"));
        });
        let report = AdapterReport {
            name: info.name.clone(),
            driver: driver_text(&info),
            backend: info.backend.to_str().to_string(),
            device_type: match info.device_type {
                wgpu::DeviceType::DiscreteGpu => "discrete",
                wgpu::DeviceType::IntegratedGpu => "integrated",
                wgpu::DeviceType::VirtualGpu => "virtual",
                wgpu::DeviceType::Cpu => "cpu",
                wgpu::DeviceType::Other => "other",
            }
            .to_string(),
            software,
            timestamps,
            float32_blendable,
        };
        Ok(GpuContext {
            device,
            queue,
            report,
            limits,
            errors,
        })
    }

    /// The first error the device reported since the last check, if any.
    pub fn check(&self) -> Result<(), GpuError> {
        let mut slot = self.errors.lock().unwrap_or_else(|p| p.into_inner());
        match slot.take() {
            Some(what) => Err(GpuError::Device { what }),
            None => Ok(()),
        }
    }

    /// Maps `slice` for reading once the work submitted so far has filled it, and waits for
    /// it; read it with `get_mapped_range`, then unmap its buffer.
    pub fn map_read(&self, slice: &wgpu::BufferSlice<'_>) -> Result<(), GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        let readback = |what: String| GpuError::Readback { what };
        rx.recv()
            .map_err(|e| readback(e.to_string()))?
            .map_err(|e| readback(e.to_string()))
    }

    /// Waits until the GPU has finished everything submitted.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device {
                what: e.to_string(),
            })?;
        self.check()
    }
}

/// A wgpu instance for drawing off screen: it never presents to a window, so it asks the
/// Vulkan driver for no window-system surface extension.
///
/// With the Xlib, XCB or Wayland surface extension enabled, Mesa's device-selection layer
/// (`VK_LAYER_MESA_device_select`, installed with Mesa's Vulkan drivers) connects to the Wayland
/// compositor and the X server to find their default GPU whenever the adapters are listed:
/// without `XDG_RUNTIME_DIR` libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set in
/// the environment.` on standard error, twice, and the probe takes time. Without those
/// extensions the layer only orders the devices, silently; the ranking in [`GpuContext::new`]
/// chooses among them anyway.
///
/// Elsewhere (macOS, Windows), or when `WGPU_BACKEND` leaves Vulkan out, this is wgpu's own
/// instance without a display handle.
pub fn headless_instance() -> wgpu::Instance {
    let desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    #[cfg(all(unix, not(target_os = "macos"), not(target_os = "android")))]
    if desc.backends.contains(wgpu::Backends::VULKAN) {
        // Vulkan is the only backend wgpu is built with here (`Cargo.toml`: no GL).
        if let Some(instance) = headless_vulkan(&desc) {
            return instance;
        }
    }
    wgpu::Instance::new(desc)
}

/// The window-system surface extensions [`headless_instance`] leaves out.
#[cfg(all(unix, not(target_os = "macos"), not(target_os = "android")))]
const WINDOW_SYSTEM_EXTENSIONS: [&std::ffi::CStr; 3] = [
    c"VK_KHR_xlib_surface",
    c"VK_KHR_xcb_surface",
    c"VK_KHR_wayland_surface",
];

/// A Vulkan-only wgpu instance without [`WINDOW_SYSTEM_EXTENSIONS`], or `None` when Vulkan
/// cannot be loaded (then wgpu's own instance finds no Vulkan adapter either and says so).
#[cfg(all(unix, not(target_os = "macos"), not(target_os = "android")))]
fn headless_vulkan(desc: &wgpu::InstanceDescriptor) -> Option<wgpu::Instance> {
    let hal_desc = wgpu::hal::InstanceDescriptor {
        name: "flarebench",
        flags: desc.flags,
        memory_budget_thresholds: desc.memory_budget_thresholds,
        backend_options: desc.backend_options.clone(),
        telemetry: None,
        display: None,
    };
    let drop_window_systems: Box<wgpu::hal::vulkan::CreateInstanceCallback> = Box::new(|args| {
        args.extensions
            .retain(|e| !WINDOW_SYSTEM_EXTENSIONS.contains(e));
    });
    // SAFETY: wgpu-hal asks callbacks not to remove extensions because it assumes an available
    // extension is enabled. The three window-system ones are the exception: wgpu-hal consults
    // them only to create a surface from an Xlib, XCB or Wayland window, and checks first that
    // the instance's extension list (the list after this callback) holds them, returning an
    // error otherwise. Nothing here creates a surface. `VK_KHR_surface`, which the swapchain
    // device extension depends on, stays.
    let hal = unsafe {
        wgpu::hal::vulkan::Instance::init_with_callback(&hal_desc, Some(drop_window_systems))
    }
    .ok()?;
    // SAFETY: `hal` is a Vulkan instance wgpu-hal itself made, valid and not shared; wgpu
    // takes it over.
    Some(unsafe { wgpu::Instance::from_hal::<wgpu::hal::api::Vulkan>(hal) })
}

fn driver_text(info: &wgpu::AdapterInfo) -> String {
    match (info.driver.is_empty(), info.driver_info.is_empty()) {
        (false, false) => format!("{} {}", info.driver, info.driver_info),
        (false, true) => info.driver.clone(),
        (true, false) => info.driver_info.clone(),
        (true, true) => "unknown driver".to_string(),
    }
}
