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
        let desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
        let backends = std::env::var("WGPU_BACKEND")
            .map(|b| format!(" (WGPU_BACKEND={b})"))
            .unwrap_or_default();
        let instance = wgpu::Instance::new(desc);
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

fn driver_text(info: &wgpu::AdapterInfo) -> String {
    match (info.driver.is_empty(), info.driver_info.is_empty()) {
        (false, false) => format!("{} {}", info.driver, info.driver_info),
        (false, true) => info.driver.clone(),
        (true, false) => info.driver_info.clone(),
        (true, true) => "unknown driver".to_string(),
    }
}
