//! The render targets of a frame's levels and the output, kept from frame to frame, and the
//! readback of the output into an [`HdrImage`].

use flarebench_sdk::image::{CoarseGrid, HdrImage};

use crate::buffers::GrowBuffer;
use crate::{GpuContext, GpuError};

/// The format every level and the output accumulate in: linear RGBA floats, blended
/// additively. Measured against the CPU image in docs/gpu.md § Target format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AccumFormat {
    /// Rgba32Float (the default): needs the device feature `FLOAT32_BLENDABLE`.
    #[default]
    F32,
    /// Rgba16Float: blendable on every device, half the memory and bandwidth, but every
    /// addition rounds the running sum to 11 significant bits and the largest value is 65504.
    F16,
}

impl AccumFormat {
    /// The texture format of the targets.
    pub fn texture_format(self) -> wgpu::TextureFormat {
        match self {
            AccumFormat::F32 => wgpu::TextureFormat::Rgba32Float,
            AccumFormat::F16 => wgpu::TextureFormat::Rgba16Float,
        }
    }

    /// Bytes per texel.
    pub fn texel_bytes(self) -> u32 {
        match self {
            AccumFormat::F32 => 16,
            AccumFormat::F16 => 8,
        }
    }
}

/// 2^`k`, exactly, for `k` in [−126, 127] (normal f32s).
pub fn pow2(k: i32) -> f32 {
    assert!((-126..=127).contains(&k), "2^{k} is not a normal f32");
    f32::from_bits(((k + 127) as u32) << 23)
}

/// Unpacks one row of RGBA texels of `format` (`bytes`, native byte order, as the GPU wrote
/// them) into `out`'s RGB times `unscale`, alpha dropped; `bytes` holds at least `out.len()`
/// texels.
pub fn unpack_row(format: AccumFormat, bytes: &[u8], unscale: f32, out: &mut [[f32; 3]]) {
    let bytes = &bytes[..out.len() * format.texel_bytes() as usize];
    match format {
        AccumFormat::F32 => {
            for (o, t) in out.iter_mut().zip(bytes.chunks_exact(16)) {
                let c = |k: usize| {
                    unscale * f32::from_ne_bytes(t[4 * k..4 * k + 4].try_into().unwrap())
                };
                *o = [c(0), c(1), c(2)];
            }
        }
        AccumFormat::F16 => {
            for (o, t) in out.iter_mut().zip(bytes.chunks_exact(8)) {
                let c = |k: usize| {
                    let h = half::f16::from_bits(u16::from_ne_bytes([t[2 * k], t[2 * k + 1]]));
                    unscale * h.to_f32()
                };
                *o = [c(0), c(1), c(2)];
            }
        }
    }
}

#[derive(Debug)]
struct Target {
    width: u32,
    height: u32,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

impl Target {
    fn new(
        device: &wgpu::Device,
        format: AccumFormat,
        width: u32,
        height: u32,
        label: &str,
    ) -> Target {
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
            format: format.texture_format(),
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
#[derive(Debug)]
pub struct LevelTargets {
    format: AccumFormat,
    /// The coarse levels' targets, in level order.
    levels: Vec<Target>,
    /// Coarse targets of earlier frames not used by this one, kept for the next.
    spare: Vec<Target>,
    output: Option<Target>,
    readback: Option<GrowBuffer>,
}

impl LevelTargets {
    /// No targets yet; they will be of `format`.
    pub fn new(format: AccumFormat) -> LevelTargets {
        LevelTargets {
            format,
            levels: Vec::new(),
            spare: Vec::new(),
            output: None,
            readback: None,
        }
    }

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
                None => Target::new(device, self.format, w, h, "coarse level"),
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
            self.output = Some(Target::new(device, self.format, w, h, "output"));
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
    /// as RGB, every value times `unscale` (a power of two: exact).
    pub fn read_back(
        &mut self,
        ctx: &GpuContext,
        width: usize,
        height: usize,
        unscale: f32,
    ) -> Result<HdrImage, GpuError> {
        let Some(output) = &self.output else {
            return Ok(HdrImage::new(width, height));
        };
        let (w, h) = (output.width, output.height);
        let texel = self.format.texel_bytes();
        let row = (w * texel).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
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
                unpack_row(self.format, &data[y * row as usize..], unscale, out);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f16_texels_unpack_to_their_f32_values() {
        // 1, 65504 (the largest f16), 2^-24 (the smallest subnormal), alpha; then
        // -2, +inf, 0.1 (0x2E66 = 819 / 8192), alpha.
        let words: [u16; 8] = [0x3C00, 0x7BFF, 0x0001, 0x3C00, 0xC000, 0x7C00, 0x2E66, 0];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_ne_bytes()).collect();
        let mut out = [[0.0; 3]; 2];
        unpack_row(AccumFormat::F16, &bytes, 1.0, &mut out);
        assert_eq!(out[0], [1.0, 65504.0, 2.0_f32.powi(-24)]);
        assert_eq!(out[1][0], -2.0);
        assert_eq!(out[1][1], f32::INFINITY);
        assert_eq!(out[1][2], 819.0 / 8192.0);
    }

    #[test]
    fn f32_texels_unpack_and_padding_is_ignored() {
        let values = [1.5_f32, -0.25, 3e-30, 9.0, 7.0, 8.0, 65536.5, 1.0];
        let mut bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
        bytes.extend_from_slice(&[0xFF; 32]);
        let mut out = [[0.0; 3]; 2];
        unpack_row(AccumFormat::F32, &bytes, 1.0, &mut out);
        assert_eq!(out, [[1.5, -0.25, 3e-30], [7.0, 8.0, 65536.5]]);
        unpack_row(AccumFormat::F32, &bytes, pow2(-20), &mut out);
        assert_eq!(out[0][0], 1.5 / 1_048_576.0);
    }

    #[test]
    fn powers_of_two_are_exact() {
        assert_eq!(pow2(0), 1.0);
        assert_eq!(pow2(-24), 1.0 / 16_777_216.0);
        assert_eq!(pow2(40), 1_099_511_627_776.0);
        assert_eq!(pow2(-126), f32::MIN_POSITIVE);
        assert_eq!(pow2(127), 2.0_f32.powi(127));
    }
}
