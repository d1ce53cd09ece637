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
        output: egui::FullOutput,
        target: &wgpu::TextureView,
        size: [u32; 2],
    ) {
        let mut frame = Tessellated::new(ctx, output);
        self.upload_textures(&mut frame);
        self.draw(ctx, frame, target, size);
    }

    /// Applies the pass's texture changes (the flare image, font atlas) to the renderer.
    pub fn upload_textures(&mut self, frame: &mut Tessellated) {
        for (id, deltas) in frame.textures.set.drain() {
            for delta in &deltas {
                self.renderer
                    .update_texture(&self.device, &self.queue, id, delta);
            }
        }
    }

    /// Draws a tessellated pass (its textures uploaded) into `target` and frees the textures it
    /// let go of.
    pub fn draw(
        &mut self,
        ctx: &egui::Context,
        mut frame: Tessellated,
        target: &wgpu::TextureView,
        size: [u32; 2],
    ) {
        let screen = ScreenDescriptor {
            size_in_pixels: size,
            pixels_per_point: frame.pixels_per_point,
        };
        let jobs = &frame.jobs;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("viewer frame"),
            });
        let extra =
            self.renderer
                .update_buffers(&self.device, &self.queue, &mut encoder, jobs, &screen);
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
            self.renderer.render(&mut pass, jobs, &screen);
        }
        self.queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        self.free_textures(&mut frame);
    }

    /// Frees the textures a pass let go of (a pass that is not drawn must still do this).
    pub fn free_textures(&mut self, frame: &mut Tessellated) {
        for id in std::mem::take(&mut frame.textures.free) {
            self.renderer.free_texture(&id);
        }
    }
}

/// One egui pass tessellated: its triangles, clip rectangles and texture changes, ready to
/// draw. Tessellation is the last CPU step of a pass before the device's work.
#[derive(Debug)]
pub struct Tessellated {
    jobs: Vec<egui::ClippedPrimitive>,
    textures: egui::TexturesDelta,
    pixels_per_point: f32,
}

impl Tessellated {
    /// Tessellates `output`'s shapes (egui's own tessellator, on the calling thread).
    pub fn new(ctx: &egui::Context, mut output: egui::FullOutput) -> Tessellated {
        let ppp = output.pixels_per_point;
        let shapes = std::mem::take(&mut output.shapes);
        Tessellated {
            jobs: ctx.tessellate(shapes, ppp),
            textures: std::mem::take(&mut output.textures_delta),
            pixels_per_point: ppp,
        }
    }
}
