//! The uniform blocks the shaders read, laid out as WGSL lays them out.

use bytemuck::{Pod, Zeroable};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::aperture::iris::IrisGeometry;

/// Dynamic offsets into a buffer of per-level blocks must be multiples of this.
pub const BLOCK_STRIDE: u64 = 256;

/// `raster.wgsl`'s `Level`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LevelBlock {
    pub size: [f32; 2],
    pub min_area: f32,
    /// A power of two every shade is multiplied by (`GhostRenderer::set_scale_log2`).
    pub scale: f32,
}

/// `upsample.wgsl`'s `Upsample`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct UpsampleBlock {
    pub factor: f32,
    pub norm: f32,
    pub offset: [f32; 2],
}

/// `aperture.wgsl`'s `ApertureParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct ApertureBlock {
    pub kind: u32,
    pub by_normals: u32,
    pub blades: u32,
    pub mask_width: u32,
    pub mask_height: u32,
    pub mask_binary: u32,
    pub mask_slope: f32,
    pub _pad: u32,
    pub rotation: f32,
    pub sector: f32,
    pub half_sector: f32,
    pub a: f32,
    pub c: f32,
    pub kappa: f32,
    pub w: f32,
    pub s: f32,
    pub first_normal: [f32; 2],
    pub step: [f32; 2],
}

impl ApertureBlock {
    /// The block for `aperture` (a mask's fields are uploaded separately).
    pub fn new(aperture: &Aperture) -> ApertureBlock {
        let mut block = ApertureBlock::zeroed();
        match aperture {
            Aperture::Circular => block.kind = 0,
            Aperture::Iris {
                blades,
                rotation_rad,
                roundness,
            } => {
                let g = IrisGeometry::new(*blades, *rotation_rad, *roundness);
                block.kind = 1;
                block.by_normals = u32::from(g.by_normals);
                block.blades = g.n as u32;
                block.rotation = g.rotation as f32;
                block.sector = g.sector as f32;
                block.half_sector = g.half as f32;
                block.a = g.a as f32;
                block.c = g.c as f32;
                block.kappa = g.kappa as f32;
                block.w = g.w as f32;
                block.s = g.s as f32;
                block.first_normal = g.first_normal.map(|v| v as f32);
                block.step = g.step.map(|v| v as f32);
            }
            Aperture::Mask(mask) => {
                block.kind = 2;
                block.mask_width = mask.width() as u32;
                block.mask_height = mask.height() as u32;
                block.mask_binary = u32::from(mask.is_binary());
                block.mask_slope = mask.field_slope();
            }
        }
        block
    }
}

/// The bytes of `blocks`, each at a multiple of [`BLOCK_STRIDE`].
pub fn strided<T: Pod>(blocks: &[T]) -> Vec<u8> {
    let stride = BLOCK_STRIDE as usize;
    let mut bytes = vec![0_u8; blocks.len().max(1) * stride];
    for (k, b) in blocks.iter().enumerate() {
        let src = bytemuck::bytes_of(b);
        bytes[k * stride..k * stride + src.len()].copy_from_slice(src);
    }
    bytes
}
