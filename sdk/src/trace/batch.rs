//! Batched tracing in structure-of-arrays packets (AoSoA): `LANES` rays per packet, one array
//! per coordinate, so the per-ray physics compiles to SIMD; packets are spread over cores
//! with rayon. No allocation happens while tracing.

use rayon::prelude::*;

use super::fate::Fate;
use super::lane::{advance, dispatch_step};
use super::real::Real;
use super::sequence::{InterfaceTable, Sequence, Step};

/// Rays per packet.
pub const LANES: usize = 64;

/// Set in a fate code once tracing of that ray has stopped.
const TERMINATED: u32 = 1 << 31;

/// `LANES` rays in structure-of-arrays form.
#[derive(Clone, Debug)]
pub struct Packet<T> {
    pub x: [T; LANES],
    pub y: [T; LANES],
    pub z: [T; LANES],
    pub dx: [T; LANES],
    pub dy: [T; LANES],
    pub dz: [T; LANES],
    /// Largest squared relative radius met so far.
    pub max_rel2: [T; LANES],
    /// Encoded [`Fate`] (first event) plus a terminated flag.
    pub fate: [u32; LANES],
    /// Fresnel/coating throughput so far (starts at 1; updated only by sequences with
    /// interface tables, see [`Sequence::with_interface_tables`]).
    pub weight: [T; LANES],
    /// Where the ray crossed the aperture stop (its last pass), global x and y.
    pub stop_x: [T; LANES],
    pub stop_y: [T; LANES],
}

impl<T: Real> Default for Packet<T> {
    fn default() -> Self {
        let z = [T::zero(); LANES];
        Packet {
            x: z,
            y: z,
            z,
            dx: z,
            dy: z,
            dz: [T::one(); LANES],
            max_rel2: z,
            fate: [0; LANES],
            weight: [T::one(); LANES],
            stop_x: z,
            stop_y: z,
        }
    }
}

impl<T> Packet<T> {
    /// True when the ray in `lane` carried out every step so far (it did not stop).
    pub fn completed(&self, lane: usize) -> bool {
        self.fate[lane] & TERMINATED == 0
    }

    /// The fate (first event) of the ray in `lane`.
    pub fn fate_of(&self, lane: usize) -> Fate {
        Fate::decode(self.fate[lane])
    }
}

/// A batch of rays in packets. Rays past `len` in the last packet are padding.
#[derive(Clone, Debug, Default)]
pub struct RayBatch<T> {
    packets: Vec<Packet<T>>,
    len: usize,
}

impl<T: Real> RayBatch<T> {
    /// An empty batch with room for `n` rays.
    pub fn with_capacity(n: usize) -> Self {
        RayBatch {
            packets: Vec::with_capacity(n.div_ceil(LANES)),
            len: 0,
        }
    }

    /// Number of rays.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the batch holds no ray.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Removes every ray, keeping the memory.
    pub fn clear(&mut self) {
        self.packets.clear();
        self.len = 0;
    }

    /// Adds a ray at `origin` with unit direction `dir`.
    pub fn push(&mut self, origin: [T; 3], dir: [T; 3]) {
        let lane = self.len % LANES;
        if lane == 0 {
            self.packets.push(Packet::default());
        }
        let p = self.packets.last_mut().expect("a packet was just ensured");
        (p.x[lane], p.y[lane], p.z[lane]) = (origin[0], origin[1], origin[2]);
        (p.dx[lane], p.dy[lane], p.dz[lane]) = (dir[0], dir[1], dir[2]);
        p.max_rel2[lane] = T::zero();
        p.fate[lane] = 0;
        p.weight[lane] = T::one();
        self.len += 1;
    }

    /// The packets (for kernels that read the rays in SoA form).
    pub fn packets(&self) -> &[Packet<T>] {
        &self.packets
    }

    /// Position, direction, fate and largest relative radius of ray `i`. Position and direction
    /// are meaningful only for a ray that [completed](Self::completed) every step; for one that
    /// stopped (missed a surface, total internal reflection) they are unspecified.
    pub fn get(&self, i: usize) -> ([T; 3], [T; 3], Fate, T) {
        assert!(i < self.len, "ray {i} of {}", self.len);
        let (p, l) = (&self.packets[i / LANES], i % LANES);
        (
            [p.x[l], p.y[l], p.z[l]],
            [p.dx[l], p.dy[l], p.dz[l]],
            Fate::decode(p.fate[l]),
            p.max_rel2[l].sqrt(),
        )
    }

    /// True when ray `i` carried out every step (it met the last surface, possibly after being
    /// vignetted).
    pub fn completed(&self, i: usize) -> bool {
        self.packets[i / LANES].fate[i % LANES] & TERMINATED == 0
    }
}

impl<T: Real> Sequence<T> {
    /// Traces every ray of `batch` through the sequence, in place, on all cores.
    pub fn trace_batch(&self, batch: &mut RayBatch<T>) {
        batch
            .packets
            .par_iter_mut()
            .with_min_len(4)
            .for_each(|p| self.trace_packet(p));
    }

    /// Traces every ray of `batch` on the calling thread only.
    pub fn trace_batch_serial(&self, batch: &mut RayBatch<T>) {
        batch.packets.iter_mut().for_each(|p| self.trace_packet(p));
    }

    /// Traces one packet through every step.
    pub fn trace_packet(&self, p: &mut Packet<T>) {
        trace_packet_dispatch(&self.steps, &self.tables, p);
    }

    /// Traces every ray of `batch` like [`Self::trace_batch`], on the calling thread, and at
    /// each probed step records per ray what a reflection there would pass on: the ray's
    /// weight as it arrives (the Fresnel/coating throughput of every step before) times the
    /// probe's table at the ray's actual incidence cosine there — exactly the weight the ray
    /// would carry after reflecting at that surface on a path that shares every step before
    /// it — and 0 for a ray that has stopped (missed a surface, total internal reflection,
    /// asphere failure) before or at the step, or that met a clear semi-diameter (this one
    /// included) beyond [`PROBE_CLIP_SLACK`] × its radius. A total internal reflection *at*
    /// the probed step is not a loss there: the ray is recorded with the probe's factor
    /// (a reflectance table is 1 beyond the critical angle), then stops.
    ///
    /// `probes` are in increasing step order; `out` is resized to `packets × probes.len()`
    /// rows of [`LANES`] values: row `packet * probes.len() + k` holds probe `k` for the
    /// packet's rays (padding lanes hold meaningless values). Nothing is allocated while
    /// tracing. Only the probes are the result: a packet stops being traced after the last
    /// probe, or once all its rays are lost, so the batch's rays are left part-way.
    pub fn trace_batch_probed(
        &self,
        batch: &mut RayBatch<T>,
        probes: &[Probe<T>],
        out: &mut Vec<[T; LANES]>,
    ) {
        debug_assert!(probes.windows(2).all(|w| w[0].step < w[1].step));
        let k = probes.len();
        out.clear();
        out.resize(batch.packets.len() * k, [T::zero(); LANES]);
        if k == 0 {
            self.trace_batch_serial(batch);
            return;
        }
        for (p, rows) in batch.packets.iter_mut().zip(out.chunks_mut(k)) {
            trace_packet_probed_dispatch(&self.steps, &self.tables, probes, p, rows);
        }
    }
}

/// Slack on the clip test of [`Sequence::trace_batch_probed`]: a ray counts as inside a clear
/// aperture up to this many radii. Grids decide "inside" on the square root of the squared
/// relative radius rounded to f32 (`GridTrace::passes`), which lets through up to one ulp
/// more than the packet's squared test; the slack keeps the probe on the generous side of
/// that, so it never drops a ray a grid counts.
pub const PROBE_CLIP_SLACK: f64 = 1.0 + 1e-5;

/// A reflectance read at one step of a sequence by [`Sequence::trace_batch_probed`].
#[derive(Clone, Debug)]
pub struct Probe<T> {
    /// Index of the step in [`Sequence::steps`].
    pub step: usize,
    /// The factor to read at the ray's incidence cosine there (a reflectance table).
    pub table: InterfaceTable<T>,
}

/// [`trace_packet_dispatch`] with probes (see [`Sequence::trace_batch_probed`]).
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma"
))]
fn trace_packet_probed_dispatch<T: Real>(
    steps: &[Step<T>],
    tables: &[InterfaceTable<T>],
    probes: &[Probe<T>],
    p: &mut Packet<T>,
    out: &mut [[T; LANES]],
) {
    let slack2 = T::of(PROBE_CLIP_SLACK * PROBE_CLIP_SLACK);
    let mut next = 0;
    for (i, s) in steps.iter().enumerate() {
        // Once every ray of the packet has stopped or been clipped, no later probe can read
        // anything but 0 (the rows are zeroed): the rest of the steps are skipped.
        let lost = |l: usize| p.fate[l] & TERMINATED != 0 || p.max_rel2[l] > slack2;
        if next == probes.len() || (0..LANES).all(lost) {
            break;
        }
        let table = s.table.map(|t| &tables[t as usize]);
        match probes.get(next).filter(|pr| pr.step == i) {
            Some(pr) => {
                dispatch_step!(
                    s,
                    step_packet_probed,
                    s,
                    table,
                    &pr.table,
                    p,
                    &mut out[next]
                );
                next += 1;
            }
            None => match table {
                Some(t) => dispatch_step!(s, step_packet_weighted, s, t, p),
                None => dispatch_step!(s, step_packet, s, p),
            },
        }
        if s.record_stop {
            p.stop_x = p.x;
            p.stop_y = p.y;
        }
    }
}

/// A step that records, per lane, the weight as the ray arrives times `probe` at its
/// incidence cosine, or 0 when the ray is lost by then (see [`Sequence::trace_batch_probed`]),
/// then weights the rays as [`step_packet_weighted`] does (when the step has a table).
#[inline(always)]
fn step_packet_probed<T: Real, const MODE: u8, const SHAPE: u8>(
    s: &Step<T>,
    table: Option<&InterfaceTable<T>>,
    probe: &InterfaceTable<T>,
    p: &mut Packet<T>,
    out: &mut [T; LANES],
) {
    let arriving = p.weight;
    let mut cos = [T::zero(); LANES];
    let mut open = [false; LANES];
    step_lanes::<T, MODE, SHAPE, true>(s, p, &mut cos, &mut open);
    for ((o, (&w, &c)), &open) in out.iter_mut().zip(arriving.iter().zip(&cos)).zip(&open) {
        *o = if open { w * probe.at(c) } else { T::zero() };
    }
    if let Some(table) = table {
        for (w, &c) in p.weight.iter_mut().zip(&cos) {
            *w = *w * table.at(c);
        }
    }
}

/// The packet kernel, compiled for the baseline CPU, for AVX2 + FMA and for AVX-512
/// (x86-64-v4), chosen at run time.
/// (Products and sums are not contracted into FMAs, so every version gives the same bits.)
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma"
))]
fn trace_packet_dispatch<T: Real>(
    steps: &[Step<T>],
    tables: &[InterfaceTable<T>],
    p: &mut Packet<T>,
) {
    for (i, s) in steps.iter().enumerate() {
        // Every few steps: once every ray of the packet has stopped, the rest are skipped
        // (a stopped ray's position and direction are unspecified anyway).
        if i % 4 == 3 && p.fate.iter().fold(TERMINATED, |a, &f| a & f) != 0 {
            break;
        }
        match s.table.map(|t| &tables[t as usize]) {
            Some(t) => dispatch_step!(s, step_packet_weighted, s, t, p),
            None => dispatch_step!(s, step_packet, s, p),
        }
        if s.record_stop {
            p.stop_x = p.x;
            p.stop_y = p.y;
        }
    }
}

/// A step that also multiplies each ray's weight by the interface's Fresnel/coating factor
/// at its angle of incidence.
#[inline(always)]
fn step_packet_weighted<T: Real, const MODE: u8, const SHAPE: u8>(
    s: &Step<T>,
    table: &InterfaceTable<T>,
    p: &mut Packet<T>,
) {
    let mut cos = [T::zero(); LANES];
    step_lanes::<T, MODE, SHAPE, false>(s, p, &mut cos, &mut [false; LANES]);
    for (w, &c) in p.weight.iter_mut().zip(&cos) {
        *w = *w * table.at(c);
    }
}

#[inline(always)]
fn step_packet<T: Real, const MODE: u8, const SHAPE: u8>(s: &Step<T>, p: &mut Packet<T>) {
    let mut cos = [T::zero(); LANES];
    step_lanes::<T, MODE, SHAPE, false>(s, p, &mut cos, &mut [false; LANES]);
}

#[inline(always)]
#[allow(
    clippy::needless_range_loop,
    reason = "one index walks eight parallel lane arrays; this shape vectorises"
)]
#[allow(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "`!(a > b)` in the probe is deliberate: true for NaN, which must count as open"
)]
/// One step for every lane; writes each lane's incidence cosine into `cos` and, when `PROBE`,
/// whether the ray is still open after it into `open`: it had not stopped, it met this
/// surface (a total internal reflection here counts as met), and no clear semi-diameter so
/// far, this one included, clipped it beyond [`PROBE_CLIP_SLACK`]. Without `PROBE`, `open` is
/// not written (the test compiles away).
fn step_lanes<T: Real, const MODE: u8, const SHAPE: u8, const PROBE: bool>(
    s: &Step<T>,
    p: &mut Packet<T>,
    cos: &mut [T; LANES],
    open: &mut [bool; LANES],
) {
    let slack2 = T::of(PROBE_CLIP_SLACK * PROBE_CLIP_SLACK);
    let surface = s.surface;
    let vignetted = Fate::Vignetted { surface }.encode();
    let missed = Fate::Missed { surface }.encode();
    let tir = Fate::TotalInternalReflection { surface }.encode();
    let no_convergence = Fate::NoConvergence { surface }.encode();
    // Every lane is written unconditionally with values selected in registers: conditional
    // read-modify-writes would keep the loop scalar or become masked stores, which are slow on
    // AMD cores. A ray that has stopped keeps computing (harmlessly, on NaNs) but its fate and
    // largest radius no longer change.
    for i in 0..LANES {
        let mut pos = [p.x[i], p.y[i], p.z[i]];
        let mut dir = [p.dx[i], p.dy[i], p.dz[i]];
        let (m0, f0) = (p.max_rel2[i], p.fate[i]);
        let out = advance::<T, MODE, SHAPE>(s, &mut pos, &mut dir);
        cos[i] = out.cos_i;
        let alive = f0 & TERMINATED == 0;
        let fail = out.missed | out.tir | out.no_convergence;
        let upd = alive & !fail;
        let rel2 = out.r2 * s.inv_semi2;
        if PROBE {
            // `!(x > limit)`: a NaN radius counts as open, on the generous side.
            open[i] = alive & !(out.missed | out.no_convergence) & !(m0.max(rel2) > slack2);
        }
        [p.x[i], p.y[i], p.z[i]] = pos;
        [p.dx[i], p.dy[i], p.dz[i]] = dir;
        p.max_rel2[i] = m0.max(if upd { rel2 } else { T::zero() });
        let fail_code = if out.missed {
            missed
        } else if out.no_convergence {
            no_convergence
        } else {
            tir
        };
        let event = if fail {
            fail_code | TERMINATED
        } else if rel2 > T::one() {
            vignetted
        } else {
            0
        };
        // Only the first event is kept; a stopped ray's code no longer changes.
        let first = if f0 == 0 {
            event
        } else {
            f0 | (event & TERMINATED)
        };
        p.fate[i] = if alive { first } else { f0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fate_codes_round_trip() {
        for f in [
            Fate::Sensor,
            Fate::Vignetted { surface: 3 },
            Fate::Missed { surface: 0 },
            Fate::TotalInternalReflection { surface: 21 },
            Fate::NoConvergence { surface: 7 },
        ] {
            assert_eq!(Fate::decode(f.encode()), f);
            assert_eq!(Fate::decode(f.encode() | TERMINATED), f);
        }
    }
}
