//! [`GhostRenderer`]: the GPU backend as a [`GhostSink`]. A frame's meshes are gathered as
//! they come, uploaded once when the frame ends, and drawn level by level: each coarse level
//! into its own float target ([`AccumFormat`]: Rgba32Float by default), then the output
//! target — the coarse levels added by exact bilinear upsampling, the full-resolution meshes
//! drawn on top, all additively.

use std::sync::Arc;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::mesh::{GhostMesh, Mesh, SAMPLED_MIN_AREA};
use flarebench_sdk::ghost::sink::{FrameLevels, GhostSink};
use flarebench_sdk::image::{CoarseGrid, HdrImage};
use flarebench_sdk::raster::Coverage;
use flarebench_sdk::raster::boxes::Boxes;
use flarebench_sdk::starburst::StarburstSplat;

use crate::buffers::GrowBuffer;
use crate::compose::{Compositor, ToneCurve};
use crate::pipelines::{Kind, Pipelines};
use crate::targets::{AccumFormat, LevelTargets, pow2};
use crate::timing::{PassTimer, PassTiming};
use crate::uniforms::{ApertureBlock, BLOCK_STRIDE, LevelBlock, UpsampleBlock, strided};
use crate::{GpuContext, GpuError};

/// A run of one kind's triangles drawn into one level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Draw {
    level: usize,
    kind: Kind,
    first: u32,
    count: u32,
}

/// The storage buffers of one kind of triangle.
#[derive(Debug)]
struct KindBuffers {
    positions: GrowBuffer,
    attrs: GrowBuffer,
    triangles: GrowBuffer,
}

impl KindBuffers {
    fn new(device: &wgpu::Device, kind: Kind) -> Self {
        let usage = wgpu::BufferUsages::STORAGE;
        let label = kind.label();
        KindBuffers {
            positions: GrowBuffer::new(device, label, usage),
            attrs: GrowBuffer::new(device, label, usage),
            triangles: GrowBuffer::new(device, label, usage),
        }
    }

    /// Uploads `mesh`; returns the bytes written.
    fn upload<const N: usize>(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mesh: &Mesh<N>,
    ) -> u64 {
        let p: &[u8] = bytemuck::cast_slice(&mesh.positions);
        let a: &[u8] = bytemuck::cast_slice(&mesh.attrs);
        let t: &[u8] = bytemuck::cast_slice(&mesh.triangles);
        self.positions.write(device, queue, p);
        self.attrs.write(device, queue, a);
        self.triangles.write(device, queue, t);
        (p.len() + a.len() + t.len()) as u64
    }
}

/// What the last frame drew and cost.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Triangles drawn: wholly open, on an edge, fringed.
    pub triangles: [usize; 3],
    /// Bytes uploaded (meshes, tables, uniforms).
    pub bytes_uploaded: u64,
    /// Draw calls recorded.
    pub draw_calls: usize,
    /// Fragments the frame's triangles make (pixels of their levels): the area of each
    /// point-sampled triangle, the whole-pixel bounding box of each exactly covered one —
    /// with the bytes uploaded, what a frame costs a GPU (docs/performance.md).
    pub fragments: u64,
    /// GPU time per pass, when the adapter measures it.
    pub passes: Vec<PassTiming>,
}

/// The GPU ghost renderer (module docs). Buffers and targets are kept from frame to frame.
#[derive(Debug)]
pub struct GhostRenderer {
    ctx: Arc<GpuContext>,
    accum: AccumFormat,
    /// Values are accumulated times 2^scale_log2 ([`Self::set_scale_log2`]).
    scale_log2: i32,
    pipelines: Pipelines,
    compositor: Compositor,
    kinds: [KindBuffers; 3],
    fringe_tables: GrowBuffer,
    level_blocks: GrowBuffer,
    upsample_blocks: GrowBuffer,
    aperture_block: wgpu::Buffer,
    mask_fields: GrowBuffer,
    /// The mask whose fields `mask_fields` holds.
    mask_uploaded: Option<flarebench_sdk::aperture::ApertureMask>,
    targets: LevelTargets,
    timer: Option<PassTimer>,
    // The frame being gathered.
    frame: Option<Frame>,
    grids: Vec<CoarseGrid>,
    aperture: ApertureBlock,
    /// Triangles of at least this many pixels² are point-sampled (the frame's coverage).
    min_area: f32,
    staging: GhostMesh,
    draws: Vec<Draw>,
    error: Option<GpuError>,
    report: FrameReport,
}

impl GhostRenderer {
    /// A renderer on `ctx`'s device accumulating in `accum` (`AccumFormat::default()` is
    /// f32). f32 needs a device that blends 32-bit float targets
    /// ([`crate::AdapterReport::float32_blendable`]); without it this fails with
    /// [`GpuError::Unsupported`], and f16 still renders.
    pub fn new(ctx: Arc<GpuContext>, accum: AccumFormat) -> Result<GhostRenderer, GpuError> {
        if accum == AccumFormat::F32 && !ctx.report.float32_blendable {
            return Err(GpuError::Unsupported {
                name: ctx.report.name.clone(),
                what: "it cannot blend into 32-bit float targets (FLOAT32_BLENDABLE), which \
                       the f32 accumulation needs; `--backend cpu` renders on the CPU"
                    .into(),
            });
        }
        let device = &ctx.device;
        let storage = wgpu::BufferUsages::STORAGE;
        let uniform = wgpu::BufferUsages::UNIFORM;
        Ok(GhostRenderer {
            accum,
            scale_log2: 0,
            pipelines: Pipelines::new(device, accum),
            compositor: Compositor::new(device, accum),
            kinds: [Kind::Open, Kind::Edge, Kind::Fringe].map(|k| KindBuffers::new(device, k)),
            fringe_tables: GrowBuffer::new(device, "fringe tables", storage),
            level_blocks: GrowBuffer::new(device, "level blocks", uniform),
            upsample_blocks: GrowBuffer::new(device, "upsample blocks", uniform),
            aperture_block: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("aperture"),
                size: size_of::<ApertureBlock>() as u64,
                usage: uniform | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            mask_fields: GrowBuffer::new(device, "mask fields", storage),
            mask_uploaded: None,
            targets: LevelTargets::new(accum),
            timer: ctx.report.timestamps.then(|| PassTimer::new(&ctx)),
            frame: None,
            grids: Vec::new(),
            aperture: ApertureBlock::new(&Aperture::Circular),
            min_area: SAMPLED_MIN_AREA,
            staging: GhostMesh::default(),
            draws: Vec::new(),
            error: None,
            report: FrameReport::default(),
            ctx,
        })
    }

    /// The format the levels and the output accumulate in.
    pub fn accum(&self) -> AccumFormat {
        self.accum
    }

    /// Accumulates the next frames' values times 2^`log2` (clamped to ±64), divided out again
    /// by [`Self::read_back`] and [`Self::tone_map`]; 0 by default. A power of two is exact in
    /// f32 (barring overflow), so the f32 image does not change; what it is for is f16
    /// ([`AccumFormat::F16`]), whose normal range (6.1e-5 to 65504) a frame's values must be
    /// lifted into (docs/gpu.md § Target format).
    pub fn set_scale_log2(&mut self, log2: i32) {
        self.scale_log2 = log2.clamp(-64, 64);
    }

    /// The scale's exponent ([`Self::set_scale_log2`]).
    pub fn scale_log2(&self) -> i32 {
        self.scale_log2
    }

    /// The device this renderer draws on.
    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// The output target of the last frame (linear HDR, of [`Self::accum`]'s texture format):
    /// what [`Self::read_back`] reads, and what a window samples.
    pub fn output(&self) -> Option<&wgpu::Texture> {
        self.targets.output()
    }

    /// What the last frame drew and cost (pass times once [`Self::read_back`] has run).
    pub fn report(&self) -> &FrameReport {
        &self.report
    }

    /// The first error of the last frame, if any (a sink's calls cannot return one).
    pub fn take_error(&mut self) -> Result<(), GpuError> {
        match self.error.take() {
            Some(e) => Err(e),
            None => self.ctx.check(),
        }
    }

    /// Waits for the last frame and reads its image back (linear RGB, the frame's size).
    pub fn read_back(&mut self) -> Result<HdrImage, GpuError> {
        self.take_error()?;
        let Some(frame) = self.frame else {
            return Ok(HdrImage::new(0, 0));
        };
        let image =
            self.targets
                .read_back(&self.ctx, frame.width, frame.height, pow2(-self.scale_log2))?;
        if let Some(timer) = &mut self.timer {
            self.report.passes = timer.read(&self.ctx)?;
        }
        self.ctx.check()?;
        Ok(image)
    }

    /// Adds the starbursts `splats` to the last frame's output (after its ghosts, before
    /// [`Self::read_back`]); patterns already on the GPU are not uploaded again.
    pub fn add_starbursts(&mut self, splats: &[StarburstSplat]) -> Result<(), GpuError> {
        self.take_error()?;
        let Some(frame) = self.frame else {
            return Ok(());
        };
        let Some(output) = self.targets.output_view() else {
            return Ok(());
        };
        let timestamps = self
            .timer
            .as_mut()
            .and_then(|t| t.pass("starbursts".to_string()));
        let bytes = self.compositor.add_starbursts(
            &self.ctx,
            output,
            pow2(self.scale_log2),
            &frame,
            splats,
            timestamps,
        )?;
        self.report.bytes_uploaded += bytes;
        if let Some(timer) = &self.timer {
            let mut encoder =
                self.ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("times"),
                    });
            timer.resolve(&mut encoder);
            self.ctx.queue.submit([encoder.finish()]);
        }
        self.ctx.check()
    }

    /// The last frame's output tone mapped to 8-bit sRGB (exposure `exposure_ev` stops, then
    /// `curve`), read back as RGB bytes, row-major: the PNG writer's mapping, on the GPU.
    pub fn tone_map(&mut self, exposure_ev: f32, curve: ToneCurve) -> Result<Vec<u8>, GpuError> {
        self.take_error()?;
        let Some(frame) = self.frame else {
            return Ok(Vec::new());
        };
        let Some(output) = self.targets.output_view() else {
            return Ok(Vec::new());
        };
        let size = (frame.width as u32, frame.height as u32);
        let unscale = pow2(-self.scale_log2);
        self.compositor
            .tone_map(&self.ctx, output, unscale, size, exposure_ev, curve)
    }

    fn fail(&mut self, e: GpuError) {
        self.error.get_or_insert(e);
    }

    /// Uploads the mask's fields when they changed.
    fn upload_mask(&mut self, aperture: &Aperture) {
        let Aperture::Mask(mask) = aperture else {
            return;
        };
        if self.mask_uploaded.as_ref() == Some(mask) {
            return;
        }
        let mut fields = Vec::with_capacity(2 * mask.data().len());
        fields.extend_from_slice(mask.data());
        fields.extend_from_slice(mask.distance_field());
        let bytes: &[u8] = bytemuck::cast_slice(&fields);
        self.mask_fields
            .write(&self.ctx.device, &self.ctx.queue, bytes);
        self.report.bytes_uploaded += bytes.len() as u64;
        self.mask_uploaded = Some(mask.clone());
    }

    /// Records a mesh's triangles of each kind as draws into `level`.
    fn gather(&mut self, level: usize, mesh: &GhostMesh) {
        let before = [
            self.staging.open.len(),
            self.staging.edge.len(),
            self.staging.fringe.len(),
        ];
        self.report.fragments += fragments(&mesh.open, self.min_area)
            + fragments(&mesh.edge, self.min_area)
            + fragments(&mesh.fringe, self.min_area)
            + box_fragments(&mesh.boxes);
        self.staging.append(mesh);
        // Boxes are drawn as pairs of open triangles with exact coverage.
        self.staging.boxes_into_open();
        let after = [
            self.staging.open.len(),
            self.staging.edge.len(),
            self.staging.fringe.len(),
        ];
        for (k, kind) in [Kind::Open, Kind::Edge, Kind::Fringe]
            .into_iter()
            .enumerate()
        {
            let count = after[k] - before[k];
            if count == 0 {
                continue;
            }
            match self
                .draws
                .iter_mut()
                .rev()
                .find(|d| d.kind == kind)
                .filter(|d| d.level == level && (d.first + d.count) as usize == before[k])
            {
                Some(d) => d.count += count as u32,
                None => self.draws.push(Draw {
                    level,
                    kind,
                    first: before[k] as u32,
                    count: count as u32,
                }),
            }
        }
    }

    fn submit(&mut self) -> Result<(), GpuError> {
        let frame = self.frame.expect("a frame has begun");
        let max = self.ctx.limits.max_texture_dimension_2d;
        if frame.width > max as usize || frame.height > max as usize {
            return Err(GpuError::FrameTooLarge {
                width: frame.width,
                height: frame.height,
                max,
            });
        }
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let coarse_count = self.grids.iter().take_while(|g| g.factor > 1).count();
        self.targets.prepare(
            device,
            frame.width,
            frame.height,
            &self.grids[..coarse_count],
        );
        // Uploads: meshes, fringe tables, uniforms.
        let mut bytes = 0;
        bytes += self.kinds[0].upload(device, queue, &self.staging.open);
        bytes += self.kinds[1].upload(device, queue, &self.staging.edge);
        bytes += self.kinds[2].upload(device, queue, &self.staging.fringe);
        let tables = crate::fringe::pack_tables(&self.staging.fringe_tables);
        let table_bytes: &[u8] = bytemuck::cast_slice(&tables);
        self.fringe_tables.write(device, queue, table_bytes);
        bytes += table_bytes.len() as u64;
        // Level blocks: one per level, the output frame's for the full-resolution one.
        let level_blocks: Vec<LevelBlock> = self
            .grids
            .iter()
            .map(|g| {
                let f = frame.coarse(g);
                LevelBlock {
                    size: [f.width as f32, f.height as f32],
                    min_area: self.min_area,
                    scale: pow2(self.scale_log2),
                }
            })
            .collect();
        let level_bytes = strided(&level_blocks);
        self.level_blocks.write(device, queue, &level_bytes);
        let upsample: Vec<UpsampleBlock> = self.grids[..coarse_count]
            .iter()
            .map(|g| UpsampleBlock {
                factor: g.factor as f32,
                norm: 1.0 / (g.factor * g.factor) as f32,
                offset: [g.offset[0] as f32, g.offset[1] as f32],
            })
            .collect();
        let upsample_bytes = strided(&upsample);
        self.upsample_blocks.write(device, queue, &upsample_bytes);
        queue.write_buffer(&self.aperture_block, 0, bytemuck::bytes_of(&self.aperture));
        bytes += (level_bytes.len() + upsample_bytes.len()) as u64;
        self.report.bytes_uploaded += bytes;

        let raster_groups: Vec<wgpu::BindGroup> = (0..3)
            .map(|k| {
                let b = &self.kinds[k];
                self.pipelines.raster_bind_group(
                    device,
                    [
                        self.level_blocks.buffer(),
                        b.positions.buffer(),
                        b.attrs.buffer(),
                        b.triangles.buffer(),
                        &self.aperture_block,
                        self.mask_fields.buffer(),
                    ],
                )
            })
            .collect();
        let fringe_group = self
            .pipelines
            .fringe_bind_group(device, self.fringe_tables.buffer());
        let upsample_groups: Vec<wgpu::BindGroup> = (0..coarse_count)
            .map(|l| {
                self.pipelines.upsample_bind_group(
                    device,
                    self.upsample_blocks.buffer(),
                    self.targets.level_view(l),
                )
            })
            .collect();

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("ghost frame"),
        });
        let draws = &self.draws;
        let pipelines = &self.pipelines;
        let record = |pass: &mut wgpu::RenderPass<'_>, level: usize| -> usize {
            let mut calls = 0;
            for d in draws.iter().filter(|d| d.level == level) {
                let k = d.kind as usize;
                pass.set_pipeline(pipelines.raster(d.kind));
                pass.set_bind_group(
                    0,
                    &raster_groups[k],
                    &[(level as u64 * BLOCK_STRIDE) as u32],
                );
                if d.kind == Kind::Fringe {
                    pass.set_bind_group(1, &fringe_group, &[]);
                }
                pass.draw(0..6, d.first..d.first + d.count);
                calls += 1;
            }
            calls
        };
        let mut calls = 0;
        for level in 0..coarse_count {
            let name = format!("coarse level ×{}", self.grids[level].factor);
            let timestamps = self.timer.as_mut().and_then(|t| t.pass(name));
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("coarse level"),
                color_attachments: &[Some(clear_attachment(self.targets.level_view(level)))],
                depth_stencil_attachment: None,
                timestamp_writes: timestamps,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            calls += record(&mut pass, level);
        }
        {
            let timestamps = self
                .timer
                .as_mut()
                .and_then(|t| t.pass("full resolution".to_string()));
            let output = self.targets.output_view().expect("prepared above");
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("full resolution"),
                color_attachments: &[Some(clear_attachment(output))],
                depth_stencil_attachment: None,
                timestamp_writes: timestamps,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipelines.upsample);
            for (l, group) in upsample_groups.iter().enumerate() {
                pass.set_bind_group(0, group, &[(l as u64 * BLOCK_STRIDE) as u32]);
                pass.draw(0..3, 0..1);
                calls += 1;
            }
            if self.grids.len() > coarse_count {
                calls += record(&mut pass, coarse_count);
            }
        }
        if let Some(timer) = &mut self.timer {
            timer.resolve(&mut encoder);
        }
        queue.submit([encoder.finish()]);
        self.report.draw_calls = calls;
        Ok(())
    }
}

/// The fragments `mesh`'s triangles make (see [`FrameReport::fragments`]).
fn fragments<const N: usize>(mesh: &Mesh<N>, min_area: f32) -> u64 {
    let mut total = 0.0_f64;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions.get(i as usize).copied().unwrap_or_default());
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs();
        if !area.is_finite() {
            continue;
        }
        total += if area >= min_area {
            f64::from(area)
        } else {
            let w = a[0].max(b[0]).max(c[0]).ceil() - a[0].min(b[0]).min(c[0]).floor();
            let h = a[1].max(b[1]).max(c[1]).ceil() - a[1].min(b[1]).min(c[1]).floor();
            f64::from(w * h)
        };
    }
    total as u64
}

/// The fragments `boxes` make drawn as triangles: the whole pixels each one's rectangle
/// touches.
fn box_fragments(boxes: &Boxes) -> u64 {
    boxes
        .rects
        .iter()
        .filter(|r| r.iter().all(|v| v.is_finite()))
        .map(|r| f64::from((r[2].ceil() - r[0].floor()) * (r[3].ceil() - r[1].floor())))
        .sum::<f64>() as u64
}

fn clear_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        },
    }
}

impl GhostSink for GhostRenderer {
    fn begin(&mut self, levels: FrameLevels<'_>) {
        self.frame = Some(levels.frame);
        self.grids = levels.grids.to_vec();
        self.aperture = ApertureBlock::new(levels.aperture);
        self.min_area = match levels.coverage {
            Coverage::Sampled { min_area } => min_area,
            Coverage::Exact => f32::MAX,
        };
        self.staging.clear();
        self.draws.clear();
        self.error = None;
        self.report = FrameReport::default();
        if let Some(timer) = &mut self.timer {
            timer.clear();
        }
        self.upload_mask(levels.aperture);
    }

    fn draw(&mut self, level: usize, mesh: &GhostMesh) {
        if level >= self.grids.len() {
            self.fail(GpuError::Device {
                what: format!("a mesh for level {level} of {}", self.grids.len()),
            });
            return;
        }
        self.gather(level, mesh);
    }

    fn finish(&mut self) {
        if self.frame.is_none() {
            return;
        }
        self.report.triangles = [
            self.staging.open.len(),
            self.staging.edge.len(),
            self.staging.fringe.len(),
        ];
        if let Err(e) = self.submit() {
            self.fail(e);
        }
    }
}
