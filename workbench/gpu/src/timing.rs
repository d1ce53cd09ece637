//! GPU time per render pass, from timestamp queries (where the adapter has them).

use crate::{GpuContext, GpuError};

/// Passes measured per frame at most (every coarse level, the output, and room to spare).
const MAX_PASSES: u32 = 16;

/// One pass's GPU time.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    pub name: String,
    pub ms: f64,
}

/// Timestamp queries for a frame's passes.
#[derive(Debug)]
pub struct PassTimer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    names: Vec<String>,
    period_ns: f32,
}

impl PassTimer {
    pub fn new(ctx: &GpuContext) -> PassTimer {
        let count = 2 * MAX_PASSES;
        let bytes = u64::from(count) * 8;
        PassTimer {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass times"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass times"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            read: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass times read"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            names: Vec::new(),
            period_ns: ctx.queue.get_timestamp_period(),
        }
    }

    /// Forgets the last frame's passes.
    pub fn clear(&mut self) {
        self.names.clear();
    }

    /// The timestamp writes of a next pass named `name` (none beyond the set's room).
    pub fn pass(&mut self, name: String) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let k = self.names.len() as u32;
        if k >= MAX_PASSES {
            return None;
        }
        self.names.push(name);
        Some(wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        })
    }

    /// Resolves the frame's queries (at the end of its command buffer).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let n = 2 * self.names.len() as u32;
        if n == 0 {
            return;
        }
        encoder.resolve_query_set(&self.set, 0..n, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, u64::from(n) * 8);
    }

    /// The frame's pass times (after it has finished).
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<PassTiming>, GpuError> {
        let n = 2 * self.names.len();
        if n == 0 {
            return Ok(Vec::new());
        }
        let slice = self.read.slice(..n as u64 * 8);
        ctx.map_read(&slice)?;
        let times: Vec<PassTiming> = {
            let data = slice.get_mapped_range().map_err(|e| GpuError::Readback {
                what: e.to_string(),
            })?;
            let ticks: &[u64] = bytemuck::cast_slice(&data);
            self.names
                .iter()
                .enumerate()
                .map(|(k, name)| PassTiming {
                    name: name.clone(),
                    ms: ticks[2 * k + 1].saturating_sub(ticks[2 * k]) as f64
                        * f64::from(self.period_ns)
                        * 1e-6,
                })
                .collect()
        };
        self.read.unmap();
        Ok(times)
    }
}
