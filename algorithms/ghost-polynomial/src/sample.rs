//! The fit's samples: rays traced exactly (f64, with the Fresnel/coating tables) along a
//! ghost's path, at random incidence angles, wavelengths and entrance points over the ghost's
//! domain — at each angle, the entrance rectangle the bounds table gives for it — and what
//! each ray does: where it lands on the sensor, where it crosses the stop, its throughput and
//! the largest relative radius it reaches at the other surfaces. Rays that stop (miss a
//! surface, totally reflect) are left out.

use flarebench_sdk::LensSystem;
use flarebench_sdk::color::sampling::{SAMPLING_MAX_NM, SAMPLING_MIN_NM};
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::Rect;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::paraxial::stop_opening;
use flarebench_sdk::trace::{LANES, RayBatch, Sequence};
use serde::{Deserialize, Serialize};

/// What a fit predicts, by index into [`Sample::outputs`].
pub const SENSOR_X: usize = 0;
pub const SENSOR_Y: usize = 1;
/// Stop crossing (last pass) over the stop's working radius.
pub const STOP_U: usize = 2;
pub const STOP_V: usize = 3;
/// Fresnel/coating throughput along the path.
pub const THROUGHPUT: usize = 4;
/// Largest `r / semi-diameter` at the surfaces other than the stop's last pass (> 1: clipped).
pub const MAX_REL: usize = 5;
/// Number of outputs.
pub const OUTPUTS: usize = 6;
/// The outputs' names, for reports.
pub const OUTPUT_NAMES: [&str; OUTPUTS] = [
    "sensor_x",
    "sensor_y",
    "stop_u",
    "stop_v",
    "throughput",
    "max_rel",
];

/// True for the outputs odd in x (the rest are even).
pub fn x_odd(output: usize) -> bool {
    output == SENSOR_X || output == STOP_U
}

/// Rays traced per wavelength (one sequence built per chunk).
const CHUNK: usize = 32;
/// Each angle's entrance rectangle grown by this share of its size on every side, so that
/// the grid's corners lie inside the fitted domain.
pub const MARGIN: f64 = 0.05;

/// The map from a ray (entrance point mm, angle, wavelength) to the fit's normalised inputs:
/// x over `x_scale` (no shift, keeping the symmetry in x), y about `y_centre` over
/// `y_scale`, the angle over `0..=theta_max_deg` and the wavelength over 380–780 nm, each
/// onto −1..=1.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Domain {
    pub x_scale: f64,
    pub y_centre: f64,
    pub y_scale: f64,
    pub theta_max_deg: f64,
}

impl Domain {
    /// The domain of ghost `g` of `table`: the box holding its entrance rectangles at every
    /// tabulated angle (grown by [`MARGIN`]), and the table's angles; `None` when no ray of it
    /// reaches the sensor at any.
    pub fn of(table: &BoundsTable, g: usize) -> Option<Domain> {
        let rects: Vec<Rect> = table.bounds[g]
            .iter()
            .flatten()
            .map(|b| grown(&b.entrance))
            .collect();
        let all = rects
            .iter()
            .skip(1)
            .fold(*rects.first()?, |a, r| a.union(r));
        let x_scale = all.x0.abs().max(all.x1.abs());
        let y_scale = 0.5 * all.height();
        let theta_max_deg = *table.angles_deg.last()?;
        (x_scale > 0.0 && y_scale > 0.0 && theta_max_deg > 0.0).then_some(Domain {
            x_scale,
            y_centre: 0.5 * (all.y0 + all.y1),
            y_scale,
            theta_max_deg,
        })
    }

    /// The normalised inputs of a ray from `(x, y)` (mm, meridional frame) at `theta_deg`
    /// and `lambda_nm`.
    #[inline]
    pub fn inputs(&self, x: f64, y: f64, theta_deg: f64, lambda_nm: f64) -> [f64; 4] {
        [
            x / self.x_scale,
            (y - self.y_centre) / self.y_scale,
            2.0 * theta_deg / self.theta_max_deg - 1.0,
            2.0 * (lambda_nm - SAMPLING_MIN_NM) / (SAMPLING_MAX_NM - SAMPLING_MIN_NM) - 1.0,
        ]
    }
}

/// `r` grown by [`MARGIN`] of its size on every side.
pub fn grown(r: &Rect) -> Rect {
    r.expand(MARGIN * r.width(), MARGIN * r.height())
}

/// One traced ray: the fit's inputs and what the exact tracer gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub inputs: [f64; 4],
    pub outputs: [f64; OUTPUTS],
}

/// A small deterministic generator (SplitMix64): the same seed gives the same samples.
#[derive(Clone, Debug)]
pub struct SplitMix(u64);

impl SplitMix {
    pub fn new(seed: u64) -> Self {
        SplitMix(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Up to `count` completed rays of ghost `g` (`path`) of `table` traced through `system`,
/// drawn from `seed`: at a random angle in the table's range, a random point of the rectangle
/// the table gives at that angle (grown by [`MARGIN`]), as [`trace_rays`] draws them.
pub fn trace_samples(
    system: &LensSystem,
    path: GhostPath,
    table: &BoundsTable,
    g: usize,
    domain: &Domain,
    count: usize,
    seed: u64,
) -> Vec<Sample> {
    trace_rays(
        |lambda| {
            Sequence::ghost_path(system, lambda, &path)
                .ok()
                .map(|s| s.with_interface_tables().aperture_by_mask())
        },
        |theta| Some(grown(&table.lookup(g, theta)?.entrance)),
        stop_opening(system),
        domain,
        count,
        seed ^ path_seed(path),
    )
}

/// Up to `count` completed rays drawn from `seed` and traced through the sequence
/// `sequence(λ)` builds: angles uniform over `0..=domain.theta_max_deg`, entrance points
/// uniform in `region(θ)` (none where it is `None`), wavelengths uniform over 380–780 nm, a new
/// wavelength every [`CHUNK`] rays; the stop crossing over `stop_radius`. Fewer when most
/// draws fall outside the regions or their rays stop (at most `4 × count` are tried), none
/// when `sequence` gives none.
pub fn trace_rays(
    sequence: impl Fn(f64) -> Option<Sequence<f64>>,
    region: impl Fn(f64) -> Option<Rect>,
    stop_radius: f64,
    domain: &Domain,
    count: usize,
    seed: u64,
) -> Vec<Sample> {
    let mut rng = SplitMix::new(seed);
    let inv_stop = 1.0 / stop_radius;
    let mut out = Vec::with_capacity(count);
    let mut batch = RayBatch::<f64>::with_capacity(CHUNK);
    let mut starts = Vec::with_capacity(CHUNK);
    let mut tried = 0;
    while out.len() < count && tried < 4 * count {
        let lambda = SAMPLING_MIN_NM + (SAMPLING_MAX_NM - SAMPLING_MIN_NM) * rng.unit();
        let Some(seq) = sequence(lambda) else {
            return out;
        };
        batch.clear();
        starts.clear();
        for _ in 0..CHUNK {
            tried += 1;
            let theta = domain.theta_max_deg * rng.unit();
            let (u, v) = (rng.unit(), rng.unit());
            if let Some(r) = region(theta) {
                let (x, y) = (r.x0 + r.width() * u, r.y0 + r.height() * v);
                let (s, c) = theta.to_radians().sin_cos();
                batch.push([x, y, 0.0], [0.0, s, c]);
                starts.push((theta, x, y));
            }
        }
        seq.trace_batch_serial(&mut batch);
        for (i, &(theta, x, y)) in starts.iter().enumerate() {
            let p = &batch.packets()[i / LANES];
            let l = i % LANES;
            if !p.completed(l) {
                continue;
            }
            let outputs = [
                p.x[l],
                p.y[l],
                p.stop_x[l] * inv_stop,
                p.stop_y[l] * inv_stop,
                p.weight[l],
                p.max_rel2[l].sqrt(),
            ];
            if outputs.iter().all(|v| v.is_finite()) && out.len() < count {
                out.push(Sample {
                    inputs: domain.inputs(x, y, theta, lambda),
                    outputs,
                });
            }
        }
    }
    out
}

/// A seed of its own for each path, so ghosts do not share their random draws.
fn path_seed(path: GhostPath) -> u64 {
    path.reflections()
        .iter()
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, &s| {
            (h ^ s as u64).wrapping_mul(0x1000_0000_01b3)
        })
}
