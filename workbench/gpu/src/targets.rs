//! The render targets of a frame's levels and the output, kept from frame to frame, and the
//! readback of the output into an [`HdrImage`].

use flarebench_sdk::image::{CoarseGrid, HdrImage};

use crate::buffers::GrowBuffer;
use crate::{GpuContext, GpuError};

/// Linear RGBA, 32-bit float: blended additively (the device asks for FLOAT32_BLENDABLE).
/// Rgba16Float would halve the bandwidth but rounds every addition to 11 bits (docs/gpu.md).
pub const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Bytes per texel of [`TARGET_FORMAT`].
const TEXEL_BYTES: u32 = 16;

#[derive(Debug)]
struct Target {
    width: u32,
    height: u32,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

impl Target {
    fn new(device: &wgpu::Device, width: u32, height: u32, label: &str) -> Target {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TARGET_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Target {
            width,
            height,
            texture,
            view,
        }
    }
}

/// The targets of the coarse levels and the output.
#[derive(Debug, Default)]
pub struct LevelTargets {
    /// The coarse levels' targets, in level order.
    levels: Vec<Target>,
    /// Coarse targets of earlier frames not used by this one, kept for the next.
    spare: Vec<Target>,
    output: Option<Target>,
    readback: Option<GrowBuffer>,
}

impl LevelTargets {
    /// Targets for a `width × height` output and the coarse levels `grids`, reusing those of
    /// earlier frames whose size matches.
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        width: usize,
        height: usize,
        grids: &[CoarseGrid],
    ) {
        self.spare.append(&mut self.levels);
        for g in grids {
            let (w, h) = (g.width.max(1) as u32, g.height.max(1) as u32);
            let target = match self
                .spare
                .iter()
                .position(|t| (t.width, t.height) == (w, h))
            {
                Some(k) => self.spare.swap_remove(k),
                None => Target::new(device, w, h, "coarse level"),
            };
            self.levels.push(target);
        }
        // Spares of another frame size are let go.
        self.spare.truncate(8);
        let (w, h) = (width.max(1) as u32, height.max(1) as u32);
        if self
            .output
            .as_ref()
            .is_none_or(|t| (t.width, t.height) != (w, h))
        {
            self.output = Some(Target::new(device, w, h, "output"));
        }
    }

    /// The view of coarse level `level`.
    pub fn level_view(&self, level: usize) -> &wgpu::TextureView {
        &self.levels[level].view
    }

    /// The output's view.
    pub fn output_view(&self) -> Option<&wgpu::TextureView> {
        self.output.as_ref().map(|t| &t.view)
    }

    /// The output texture.
    pub fn output(&self) -> Option<&wgpu::Texture> {
        self.output.as_ref().map(|t| &t.texture)
    }

    /// Copies the output into host memory (rows padded to 256 bytes on the way) and returns it
    /// as RGB.
    pub fn read_back(
        &mut self,
        ctx: &GpuContext,
        width: usize,
        height: usize,
    ) -> Result<HdrImage, GpuError> {
        let Some(output) = &self.output else {
            return Ok(HdrImage::new(width, height));
        };
        let (w, h) = (output.width, output.height);
        let row = (w * TEXEL_BYTES).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let size = u64::from(row) * u64::from(h);
        let buffer = self.readback.get_or_insert_with(|| {
            GrowBuffer::new(&ctx.device, "readback", wgpu::BufferUsages::MAP_READ)
        });
        buffer.reserve(&ctx.device, size);
        let buffer = buffer.buffer();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        copy_rows(&mut encoder, &output.texture, buffer, (w, h), row);
        ctx.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..size);
        ctx.map_read(&slice)?;
        let mut img = HdrImage::new(width, height);
        {
            let data = slice.get_mapped_range().map_err(|e| GpuError::Readback {
                what: e.to_string(),
            })?;
            for (y, out) in img.pixels.chunks_exact_mut(width).enumerate() {
                let start = y * row as usize;
                let texels: &[[f32; 4]] =
                    bytemuck::cast_slice(&data[start..start + width * TEXEL_BYTES as usize]);
                for (o, t) in out.iter_mut().zip(texels) {
                    *o = [t[0], t[1], t[2]];
                }
            }
        }
        buffer.unmap();
        Ok(img)
    }
}

/// Copies a `width × height` texture into `buffer`, each row padded to `row` bytes (a multiple
/// of `COPY_BYTES_PER_ROW_ALIGNMENT`).
pub fn copy_rows(
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    buffer: &wgpu::Buffer,
    (width, height): (u32, u32),
    row: u32,
) {
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
}
