//! The viewer drawn offscreen by the same code as the window: one egui pass of
//! [`Viewer::frame`] painted by [`Gfx`] into a texture and read back. Used by the golden-image
//! tests and for screenshots.

use std::time::{Duration, Instant};

use anyhow::Context;
use egui::{Event, RawInput, Rect, pos2, vec2};

use super::app::Viewer;
use super::gfx::{Gfx, Tessellated};

/// Where an offscreen pass's time went.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassTimes {
    /// The viewer's egui pass and its tessellation: the CPU's share of a frame.
    pub ui: Duration,
    /// Texture uploads, drawing, and waiting for the device to finish (on lavapipe, the CPU
    /// again; on a GPU, mostly the device's own time).
    pub paint: Duration,
}

/// Offscreen target format: 8-bit sRGB-encoded values, read back as they are.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// An offscreen UI target and the egui context that draws into it.
pub struct Offscreen {
    gfx: Gfx,
    pub ctx: egui::Context,
    texture: wgpu::Texture,
    size: [u32; 2],
    time: f64,
}

impl std::fmt::Debug for Offscreen {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Offscreen")
            .field("size", &self.size)
            .finish_non_exhaustive()
    }
}

/// Opens a device on any adapter (a software one included) for drawing the UI.
pub fn ui_device(
    instance: &wgpu::Instance,
    surface: Option<&wgpu::Surface<'_>>,
) -> anyhow::Result<(wgpu::Adapter, wgpu::Device, wgpu::Queue)> {
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: surface,
        apply_limit_buckets: false,
    }))
    .context(
        "no graphics adapter for the window: install a Vulkan driver (Debian: \
         mesa-vulkan-drivers libvulkan1; lavapipe is enough), or Metal/DX12 on macOS/Windows",
    )?;
    let limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("flarebench viewer"),
        required_features: wgpu::Features::empty(),
        required_limits: limits,
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }))
    .context("the graphics adapter refused a device for the window")?;
    Ok((adapter, device, queue))
}

impl Offscreen {
    /// A `width × height` target (physical pixels at one pixel per point).
    pub fn new(width: u32, height: u32) -> anyhow::Result<Offscreen> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
        let (_, device, queue) = ui_device(&instance, None)?;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("viewer offscreen"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let ctx = egui::Context::default();
        ctx.set_visuals(egui::Visuals::dark());
        Ok(Offscreen {
            gfx: Gfx::new(device, queue, FORMAT, true),
            ctx,
            texture,
            size: [width, height],
            time: 0.0,
        })
    }

    /// One pass of `viewer` with `events` (mouse, keys), painted; it returns when the device
    /// has finished drawing. Time advances 1/60 s.
    pub fn pass(&mut self, viewer: &mut Viewer, events: Vec<Event>) -> PassTimes {
        let t = Instant::now();
        let mut frame = self.ui(viewer, events);
        let ui = t.elapsed();
        let t = Instant::now();
        self.gfx.upload_textures(&mut frame);
        let view = self.texture.create_view(&Default::default());
        self.gfx.draw(&self.ctx, frame, &view, self.size);
        // Wait for the device, so the time is the drawing's and not only its submission's.
        let _ = self.gfx.device.poll(wgpu::PollType::wait_indefinitely());
        PassTimes {
            ui,
            paint: t.elapsed(),
        }
    }

    /// One pass laid out, tessellated and its textures uploaded (a new flare image included),
    /// but not drawn: what a pass costs the CPU when a GPU draws it. The target keeps its last
    /// painted image. Returns the layout and tessellation time.
    pub fn pass_unpainted(&mut self, viewer: &mut Viewer, events: Vec<Event>) -> Duration {
        let t = Instant::now();
        let mut frame = self.ui(viewer, events);
        let ui = t.elapsed();
        self.gfx.upload_textures(&mut frame);
        self.gfx.free_textures(&mut frame);
        ui
    }

    /// Lays out one pass of the viewer and tessellates it.
    fn ui(&mut self, viewer: &mut Viewer, events: Vec<Event>) -> Tessellated {
        self.time += 1.0 / 60.0;
        let input = RawInput {
            screen_rect: Some(Rect::from_min_size(
                pos2(0.0, 0.0),
                vec2(self.size[0] as f32, self.size[1] as f32),
            )),
            time: Some(self.time),
            predicted_dt: 1.0 / 60.0,
            events,
            focused: true,
            ..RawInput::default()
        };
        let output = self.ctx.run_ui(input, |ui| viewer.frame(ui));
        Tessellated::new(&self.ctx, output)
    }

    /// Runs passes until the viewer's newest render has arrived and is shown, or failed (then
    /// the status line shows why), or `timeout` passed; then one more pass so the frame is
    /// painted. True when it settled.
    pub fn settle(&mut self, viewer: &mut Viewer, timeout: Duration) -> bool {
        let end = Instant::now() + timeout;
        self.pass(viewer, Vec::new());
        while !viewer.settled() {
            if viewer.render_failure().is_some() {
                self.pass(viewer, Vec::new());
                return false;
            }
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return false;
            }
            viewer.wait_for_render(left.min(Duration::from_millis(200)));
            self.pass(viewer, Vec::new());
        }
        self.pass(viewer, Vec::new());
        true
    }

    /// The target's pixels, RGBA8 rows top to bottom.
    pub fn read(&self) -> anyhow::Result<image::RgbaImage> {
        let [w, h] = self.size;
        let row = (w * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let device = &self.gfx.device;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewer readback"),
            size: (row * h) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.gfx.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .context("waiting for the readback")?;
        rx.recv()
            .context("the readback was dropped")?
            .context("mapping the readback")?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| anyhow::anyhow!("reading the readback: {e}"))?;
        let mut pixels = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h as usize {
            let start = y * row as usize;
            pixels.extend_from_slice(&data[start..start + (w * 4) as usize]);
        }
        drop(data);
        buffer.unmap();
        image::RgbaImage::from_raw(w, h, pixels).context("readback size")
    }
}
