//! The passes after the ghosts: starbursts composited from their computed patterns
//! (`shaders/starburst.wgsl`) and the tone mapping of 8-bit output (`shaders/tonemap.wgsl`).

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::starburst::{SplatGeometry, StarburstPattern, StarburstSplat};

use crate::buffers::GrowBuffer;
use crate::pipelines::{additive_target, pipeline};
use crate::targets::AccumFormat;
use crate::uniforms::{BLOCK_STRIDE, strided};
use crate::{GpuContext, GpuError};

/// `starburst.wgsl`'s `Splat`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatBlock {
    first: [f32; 2],
    step: [f32; 2],
    rect: [f32; 4],
    frame: [f32; 2],
    size: u32,
    offset: u32,
    flux: f32,
    _pad: [f32; 3],
}

/// `tonemap.wgsl`'s `Tone`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ToneBlock {
    scale: f32,
    curve: u32,
    _pad: [u32; 2],
}

/// The tone curve of 8-bit output (the PNG writer's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToneCurve {
    /// The ACES filmic fit.
    Aces,
    /// Clamp to [0, 1].
    Clamp,
}

/// Pipelines and buffers of the starburst and tone passes.
#[derive(Debug)]
pub struct Compositor {
    splat_layout: wgpu::BindGroupLayout,
    splat: wgpu::RenderPipeline,
    tone_layout: wgpu::BindGroupLayout,
    tone: wgpu::RenderPipeline,
    blocks: GrowBuffer,
    tone_block: wgpu::Buffer,
    patterns: GrowBuffer,
    /// The patterns `patterns` holds, in order.
    resident: Vec<Arc<StarburstPattern>>,
    tone_target: Option<(u32, u32, wgpu::Texture, wgpu::TextureView)>,
    readback: Option<GrowBuffer>,
}

fn layout_entries(second: wgpu::BindingType) -> [wgpu::BindGroupLayoutEntry; 2] {
    [
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: None,
            },
            count: None,
        },
        wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: second,
            count: None,
        },
    ]
}

impl Compositor {
    /// The passes, the starburst pass adding into linear targets of `format`.
    pub fn new(device: &wgpu::Device, format: AccumFormat) -> Compositor {
        let splat_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("starburst"),
            entries: &layout_entries(wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            }),
        });
        let tone_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tone"),
            entries: &layout_entries(wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            }),
        });
        let splat = pipeline(
            device,
            &splat_layout,
            include_str!("shaders/starburst.wgsl"),
            ("vs_splat", "fs_splat"),
            additive_target(format),
        );
        let tone = pipeline(
            device,
            &tone_layout,
            include_str!("shaders/tonemap.wgsl"),
            ("vs_full", "fs_tone"),
            wgpu::ColorTargetState {
                format: wgpu::TextureFormat::Rgba8Unorm,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            },
        );
        Compositor {
            splat_layout,
            splat,
            tone_layout,
            tone,
            blocks: GrowBuffer::new(device, "starburst blocks", wgpu::BufferUsages::UNIFORM),
            tone_block: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tone"),
                size: size_of::<ToneBlock>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            patterns: GrowBuffer::new(device, "starburst patterns", wgpu::BufferUsages::STORAGE),
            resident: Vec::new(),
            tone_target: None,
            readback: None,
        }
    }

    /// Adds `splats` to `output` (the frame's linear target, its values times `scale`, a power
    /// of two); returns the bytes uploaded. Patterns already on the GPU from an earlier frame
    /// are not uploaded again.
    pub fn add_starbursts(
        &mut self,
        ctx: &GpuContext,
        output: &wgpu::TextureView,
        scale: f32,
        frame: &Frame,
        splats: &[StarburstSplat],
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> Result<u64, GpuError> {
        let mut uploaded = 0;
        // The frame's distinct patterns, in first-use order.
        let mut wanted: Vec<Arc<StarburstPattern>> = Vec::new();
        for s in splats {
            if !wanted.iter().any(|p| Arc::ptr_eq(p, &s.pattern)) {
                wanted.push(Arc::clone(&s.pattern));
            }
        }
        let same = wanted.len() == self.resident.len()
            && wanted
                .iter()
                .zip(&self.resident)
                .all(|(a, b)| Arc::ptr_eq(a, b));
        if !same {
            let floats: Vec<f32> = wanted
                .iter()
                .flat_map(|p| p.rgb().iter().flatten().copied())
                .collect();
            let bytes: &[u8] = bytemuck::cast_slice(&floats);
            self.patterns.write(&ctx.device, &ctx.queue, bytes);
            uploaded += bytes.len() as u64;
            self.resident = wanted;
        }
        let mut blocks = Vec::with_capacity(splats.len());
        for s in splats {
            let g =
                SplatGeometry::new(frame, &s.pattern, s.centre_mm, s.f_number).map_err(|e| {
                    GpuError::Device {
                        what: format!("starburst: {e}"),
                    }
                })?;
            let n = g.size as f64;
            let (x_a, x_b) = (g.first[0], g.first[0] + n * g.step[0]);
            let (y_a, y_b) = (g.first[1], g.first[1] + n * g.step[1]);
            let (w, h) = (frame.width as f64, frame.height as f64);
            let rect = [
                x_a.min(x_b).max(0.0).floor(),
                y_a.min(y_b).max(0.0).floor(),
                x_a.max(x_b).min(w).ceil(),
                y_a.max(y_b).min(h).ceil(),
            ];
            if !(rect[0] < rect[2] && rect[1] < rect[3]) {
                continue;
            }
            let offset: usize = self
                .resident
                .iter()
                .take_while(|p| !Arc::ptr_eq(p, &s.pattern))
                .map(|p| p.size() * p.size())
                .sum();
            blocks.push(SplatBlock {
                first: g.first.map(|v| v as f32),
                step: g.step.map(|v| v as f32),
                rect: rect.map(|v| v as f32),
                frame: [w as f32, h as f32],
                size: g.size as u32,
                offset: offset as u32,
                flux: s.flux as f32 * scale,
                _pad: [0.0; 3],
            });
        }
        if blocks.is_empty() {
            return Ok(uploaded);
        }
        let block_bytes = strided(&blocks);
        self.blocks.write(&ctx.device, &ctx.queue, &block_bytes);
        uploaded += block_bytes.len() as u64;
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("starburst"),
            layout: &self.splat_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: self.blocks.buffer(),
                        offset: 0,
                        size: wgpu::BufferSize::new(size_of::<SplatBlock>() as u64),
                    }),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.patterns.buffer().as_entire_binding(),
                },
            ],
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("starbursts"),
            });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("starbursts"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: output,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timestamps,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.splat);
            for k in 0..blocks.len() {
                pass.set_bind_group(0, &group, &[(k as u64 * BLOCK_STRIDE) as u32]);
                pass.draw(0..6, 0..1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
        Ok(uploaded)
    }

    /// Tone maps `hdr` (a `width × height` linear target, its values times `1 / unscale`, a
    /// power of two) to 8-bit sRGB and reads it back as RGB bytes, row-major.
    pub fn tone_map(
        &mut self,
        ctx: &GpuContext,
        hdr: &wgpu::TextureView,
        unscale: f32,
        (width, height): (u32, u32),
        exposure_ev: f32,
        curve: ToneCurve,
    ) -> Result<Vec<u8>, GpuError> {
        let block = ToneBlock {
            scale: exposure_ev.exp2() * unscale,
            curve: match curve {
                ToneCurve::Aces => 0,
                ToneCurve::Clamp => 1,
            },
            _pad: [0; 2],
        };
        ctx.queue
            .write_buffer(&self.tone_block, 0, bytemuck::bytes_of(&block));
        if self
            .tone_target
            .as_ref()
            .is_none_or(|t| (t.0, t.1) != (width, height))
        {
            let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("tone mapped"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            self.tone_target = Some((width, height, texture, view));
        }
        let (_, _, texture, view) = self.tone_target.as_ref().expect("made above");
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tone"),
            layout: &self.tone_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.tone_block,
                        offset: 0,
                        size: None,
                    }),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(hdr),
                },
            ],
        });
        let row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let size = u64::from(row) * u64::from(height);
        let buffer = self.readback.get_or_insert_with(|| {
            GrowBuffer::new(&ctx.device, "tone readback", wgpu::BufferUsages::MAP_READ)
        });
        buffer.reserve(&ctx.device, size);
        let buffer = buffer.buffer();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("tone"),
            });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("tone"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.tone);
            pass.set_bind_group(0, &group, &[0]);
            pass.draw(0..3, 0..1);
        }
        crate::targets::copy_rows(&mut encoder, texture, buffer, (width, height), row);
        ctx.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..size);
        ctx.map_read(&slice)?;
        let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
        {
            let data = slice.get_mapped_range().map_err(|e| GpuError::Readback {
                what: e.to_string(),
            })?;
            for y in 0..height as usize {
                let line = &data[y * row as usize..][..width as usize * 4];
                for px in line.chunks_exact(4) {
                    rgb.extend_from_slice(&px[..3]);
                }
            }
        }
        buffer.unmap();
        Ok(rgb)
    }
}
