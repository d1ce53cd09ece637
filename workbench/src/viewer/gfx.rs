//! Painting a UI frame with wgpu: egui's shapes (the lens view's lines and fills, the flare
//! image, panels and text) tessellated and drawn into any texture view — the window's surface
//! or an offscreen texture, by the same code.

use egui_wgpu::{Renderer, RendererOptions, ScreenDescriptor};

/// egui's wgpu renderer and the device it draws with.
pub struct Gfx {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    renderer: Renderer,
    pub format: wgpu::TextureFormat,
}

impl std::fmt::Debug for Gfx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gfx")
            .field("format", &self.format)
            .finish_non_exhaustive()
    }
}

impl Gfx {
    /// A painter for targets of `format`. `predictable` turns dithering off (golden images).
    pub fn new(
        device: wgpu::Device,
        queue: wgpu::Queue,
        format: wgpu::TextureFormat,
        predictable: bool,
    ) -> Gfx {
        let options = if predictable {
            RendererOptions::PREDICTABLE
        } else {
            RendererOptions::default()
        };
        let renderer = Renderer::new(&device, format, options);
        Gfx {
            device,
            queue,
            renderer,
            format,
        }
    }

    /// Draws `output` (one egui pass of `ctx`) into `target`, `size` physical pixels, cleared to
    /// the panel background first.
    pub fn paint(
        &mut self,
        ctx: &egui::Context,
        mut output: egui::FullOutput,
        target: &wgpu::TextureView,
        size: [u32; 2],
    ) {
        let ppp = output.pixels_per_point;
        let shapes = std::mem::take(&mut output.shapes);
        let jobs = ctx.tessellate(shapes, ppp);
        let mut textures = std::mem::take(&mut output.textures_delta);
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                self.renderer
                    .update_texture(&self.device, &self.queue, id, delta);
            }
        }
        let screen = ScreenDescriptor {
            size_in_pixels: size,
            pixels_per_point: ppp,
        };
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("viewer frame"),
            });
        let extra =
            self.renderer
                .update_buffers(&self.device, &self.queue, &mut encoder, &jobs, &screen);
        {
            let bg = ctx.global_style().visuals.panel_fill;
            let [r, g, b, _] = egui::Rgba::from(bg).to_array();
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("viewer ui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        resolve_target: None,
                        depth_slice: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: r as f64,
                                g: g as f64,
                                b: b as f64,
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.renderer.render(&mut pass, &jobs, &screen);
        }
        self.queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        for id in textures.free.drain() {
            self.renderer.free_texture(&id);
        }
    }
}
