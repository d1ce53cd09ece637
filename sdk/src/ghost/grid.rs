//! A square grid of parallel rays on the entrance plane (z = 0, the front vertex), traced along
//! one path at one wavelength. Nothing is dropped: every vertex keeps its landing point, its
//! largest relative radius (for feathered clipping) and its Fresnel/coating weight.

use crate::trace::{LANES, RayBatch, Sequence};

use super::bounds::Rect;

/// The traced grid, in the meridional frame (light in the y–z plane); rotate the sensor
/// positions by the light's azimuth. Vertex `(i, j)` (i along x, j along y) is at `j * n + i`.
#[derive(Clone, Debug, Default)]
pub struct GridTrace {
    /// Vertices per side.
    pub n: usize,
    /// The entrance-plane rectangle the grid spans.
    pub rect: Rect,
    /// Landing point on the sensor plane (mm).
    pub sensor: Vec<[f32; 2]>,
    /// Crossing of the aperture stop (last pass), over the stop's working radius.
    pub stop_uv: Vec<[f32; 2]>,
    /// Largest r / semi-diameter along the path (> 1: clipped somewhere).
    pub max_rel: Vec<f32>,
    /// Fresnel/coating throughput along the path.
    pub weight: Vec<f32>,
    /// False for rays that stopped (missed a surface, total internal reflection): their other
    /// values are meaningless.
    pub completed: Vec<bool>,
    batch: RayBatch<f32>,
}

impl GridTrace {
    /// Area of one grid cell on the entrance plane (mm²).
    pub fn cell_area(&self) -> f64 {
        let d = (self.n.max(2) - 1) as f64;
        (self.rect.width() / d) * (self.rect.height() / d)
    }

    /// True when vertex `k` reached the sensor inside every aperture.
    pub fn passes(&self, k: usize) -> bool {
        self.completed[k] && self.max_rel[k] <= 1.0
    }
}

/// Traces an `n × n` grid over `rect` of collimated rays at `theta` (radians, in the y–z plane)
/// through `seq` into `out` (buffers are reused). `stop_radius` normalises the stop crossing.
pub fn trace_grid(
    seq: &Sequence<f32>,
    theta: f64,
    rect: Rect,
    n: usize,
    stop_radius: f64,
    out: &mut GridTrace,
) {
    let n = n.max(2);
    let (s, c) = theta.sin_cos();
    let dir = [0.0, s as f32, c as f32];
    out.batch.clear();
    let d = (n - 1) as f64;
    for j in 0..n {
        let y = rect.y0 + rect.height() * j as f64 / d;
        for i in 0..n {
            let x = rect.x0 + rect.width() * i as f64 / d;
            out.batch.push([x as f32, y as f32, 0.0], dir);
        }
    }
    seq.trace_batch(&mut out.batch);
    let total = n * n;
    out.n = n;
    out.rect = rect;
    out.sensor.clear();
    out.stop_uv.clear();
    out.max_rel.clear();
    out.weight.clear();
    out.completed.clear();
    let inv_stop = (1.0 / stop_radius) as f32;
    for (pi, p) in out.batch.packets().iter().enumerate() {
        let lanes = LANES.min(total - pi * LANES);
        for l in 0..lanes {
            out.sensor.push([p.x[l], p.y[l]]);
            out.stop_uv
                .push([p.stop_x[l] * inv_stop, p.stop_y[l] * inv_stop]);
            out.max_rel.push(p.max_rel2[l].sqrt());
            out.weight.push(p.weight[l]);
            out.completed.push(p.completed(l));
        }
    }
}
