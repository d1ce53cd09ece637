//! A square grid of parallel rays on the entrance plane (z = 0, the front vertex), traced along
//! one path at one wavelength. Nothing is dropped: every vertex keeps its landing point, its
//! largest relative radius (for feathered clipping) and its Fresnel/coating weight.

use crate::trace::{LANES, Probe, RayBatch, Real, Sequence};

use crate::rect::Rect;

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
    batch64: RayBatch<f64>,
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
    let mut batch = std::mem::take(&mut out.batch);
    fill(seq, &mut batch, theta, rect, n, stop_radius, out);
    out.batch = batch;
}

/// Collimated rays from chosen points of the entrance plane, traced along one path on the
/// calling thread: whether each reached the sensor inside every aperture (the checks
/// [`super::bounds::widened_for`] makes along a rectangle's border).
#[derive(Clone, Debug, Default)]
pub struct PointTrace {
    /// Largest r / semi-diameter along the path (> 1: clipped somewhere); NaN for a ray that
    /// stopped (missed a surface, total internal reflection).
    pub max_rel: Vec<f32>,
    batch: RayBatch<f32>,
}

impl PointTrace {
    /// True when ray `k` reached the sensor inside every aperture.
    pub fn passes(&self, k: usize) -> bool {
        self.max_rel[k] <= 1.0
    }

    /// Traces a ray at `theta` (radians, in the y–z plane) from each of `points` (entrance
    /// plane, mm) through `seq`, replacing the previous results (buffers are reused).
    pub fn trace(
        &mut self,
        seq: &Sequence<f32>,
        theta: f64,
        points: impl IntoIterator<Item = [f64; 2]>,
    ) {
        let (s, c) = theta.sin_cos();
        let dir = [0.0, s as f32, c as f32];
        self.batch.clear();
        for [x, y] in points {
            self.batch.push([x as f32, y as f32, 0.0], dir);
        }
        seq.trace_batch_serial(&mut self.batch);
        self.max_rel.clear();
        self.max_rel.extend((0..self.batch.len()).map(|i| {
            let (_, _, _, rel) = self.batch.get(i);
            if self.batch.completed(i) {
                rel
            } else {
                f32::NAN
            }
        }));
    }
}

/// [`trace_grid`] with the rays traced in f64 (the results are stored in f32 as always): the
/// check on the f32 tracer's images.
pub fn trace_grid_f64(
    seq: &Sequence<f64>,
    theta: f64,
    rect: Rect,
    n: usize,
    stop_radius: f64,
    out: &mut GridTrace,
) {
    let mut batch = std::mem::take(&mut out.batch64);
    fill(seq, &mut batch, theta, rect, n, stop_radius, out);
    out.batch64 = batch;
}

// Generic over the tracer's float, which CODE_STYLE keeps inside `trace/`: this is the one
// place outside it, so that the f32 and f64 grids share their code; it stays private.
fn fill<T: Real>(
    seq: &Sequence<T>,
    batch: &mut RayBatch<T>,
    theta: f64,
    rect: Rect,
    n: usize,
    stop_radius: f64,
    out: &mut GridTrace,
) {
    let n = n.max(2);
    push_grid_rays(batch, theta, rect, n);
    seq.trace_batch(batch);
    let total = n * n;
    out.n = n;
    out.rect = rect;
    out.sensor.clear();
    out.stop_uv.clear();
    out.max_rel.clear();
    out.weight.clear();
    out.completed.clear();
    let inv_stop = 1.0 / stop_radius;
    let f = |v: T| v.to_f64() as f32;
    for (pi, p) in batch.packets().iter().enumerate() {
        let lanes = LANES.min(total - pi * LANES);
        for l in 0..lanes {
            out.sensor.push([f(p.x[l]), f(p.y[l])]);
            out.stop_uv.push([
                (p.stop_x[l].to_f64() * inv_stop) as f32,
                (p.stop_y[l].to_f64() * inv_stop) as f32,
            ]);
            out.max_rel.push(p.max_rel2[l].to_f64().sqrt() as f32);
            out.weight.push(f(p.weight[l]));
            out.completed.push(p.completed(l));
        }
    }
}

/// Fills `batch` with the `n × n` grid of collimated rays over `rect` at `theta`, vertex
/// `(i, j)` at `j * n + i`: the rays every grid of this module traces.
fn push_grid_rays<T: Real>(batch: &mut RayBatch<T>, theta: f64, rect: Rect, n: usize) {
    let (s, c) = theta.sin_cos();
    let dir = [T::of(0.0), T::of(s), T::of(c)];
    batch.clear();
    let d = (n - 1) as f64;
    for j in 0..n {
        let y = rect.y0 + rect.height() * j as f64 / d;
        for i in 0..n {
            let x = rect.x0 + rect.width() * i as f64 / d;
            batch.push([T::of(x), T::of(y), T::of(0.0)], dir);
        }
    }
}

/// A grid traced with probes ([`trace_grid_probed`]): per probe, per vertex, the weight a
/// reflection at the probed step would pass on.
#[derive(Clone, Debug, Default)]
pub struct ProbedGrid {
    /// Vertices per side.
    pub n: usize,
    /// The entrance-plane rectangle the grid spans.
    pub rect: Rect,
    /// Number of probes.
    pub probes: usize,
    batch: RayBatch<f32>,
    /// The rays as [`ProbedGrid::start`] left them.
    base: RayBatch<f32>,
    rows: Vec<[f32; LANES]>,
}

impl ProbedGrid {
    /// Probe `k`'s value at vertex `v` (`j * n + i`), as [`Sequence::trace_batch_probed`]
    /// records it.
    pub fn value(&self, k: usize, v: usize) -> f32 {
        self.rows[(v / LANES) * self.probes + k][v % LANES]
    }

    /// Probe `k`'s values at every vertex, in vertex order.
    pub fn values(&self, k: usize) -> impl Iterator<Item = f32> + '_ {
        self.rows
            .iter()
            .skip(k)
            .step_by(self.probes.max(1))
            .flat_map(|row| row.iter().copied())
            .take(self.n * self.n)
    }

    /// Area of one grid cell on the entrance plane (mm²).
    pub fn cell_area(&self) -> f64 {
        let d = (self.n.max(2) - 1) as f64;
        (self.rect.width() / d) * (self.rect.height() / d)
    }

    /// Traces the `n × n` grid of [`trace_grid`] (the same rays) through `prefix` on the
    /// calling thread, without probes, and keeps the rays as they are then: the start of every
    /// [`Self::continue_probed`] until the next `start`. Paths that share their first steps
    /// trace them once.
    pub fn start(&mut self, prefix: &Sequence<f32>, theta: f64, rect: Rect, n: usize) {
        let n = n.max(2);
        push_grid_rays(&mut self.base, theta, rect, n);
        prefix.trace_batch_serial(&mut self.base);
        self.n = n;
        self.rect = rect;
        self.probes = 0;
    }

    /// A copy of the rays [`Self::start`] kept, traced on through `seq` (the steps after the
    /// prefix; a sequence built to start travelling the way the prefix left the rays) with
    /// `probes` ([`Sequence::trace_batch_probed`]); bit for bit what tracing the prefix's
    /// steps followed by `seq`'s in one sequence records.
    pub fn continue_probed(&mut self, seq: &Sequence<f32>, probes: &[Probe<f32>]) {
        self.batch.clone_from(&self.base);
        seq.trace_batch_probed(&mut self.batch, probes, &mut self.rows);
        self.probes = probes.len();
    }
}

/// Traces the same `n × n` grid as [`trace_grid`] (the same rays, bit for bit) through `seq`
/// on the calling thread, recording the `probes` ([`Sequence::trace_batch_probed`]) into
/// `out` (buffers are reused).
pub fn trace_grid_probed(
    seq: &Sequence<f32>,
    theta: f64,
    rect: Rect,
    n: usize,
    probes: &[Probe<f32>],
    out: &mut ProbedGrid,
) {
    let n = n.max(2);
    push_grid_rays(&mut out.batch, theta, rect, n);
    seq.trace_batch_probed(&mut out.batch, probes, &mut out.rows);
    out.n = n;
    out.rect = rect;
    out.probes = probes.len();
}
