//! The traced upper bound on the energy share of four-reflection ghost paths, which culls
//! them before their own bounds are traced.
//!
//! A path `a-b-c-d` (reflect at `a` going toward the sensor, at `b < a` going back, at
//! `c > b` going toward the sensor, at `d < c` going back, then on to the sensor) carries, for
//! each ray, at most the weight the ray has when it reaches `d` — after reflecting at `a`, `b`
//! and `c` and refracting everywhere in between — times the reflectance at `d` at the ray's
//! actual incidence there: every later step multiplies the weight by a transmittance ≤ 1 or
//! clips the ray. So one trace of the **three-reflection prefix** `a-b-c`, continued from `c`
//! back toward the object through every surface down to the first reflecting one, bounds all
//! the paths `a-b-c-d` at once: at each reflecting surface `d < c` on that last leg, each ray
//! that is still open (not stopped, not clipped by any clear aperture so far, `d`'s included)
//! records its arriving weight × `R_d(cos θ_i)` from the same interface tables the ghost
//! traces use (coatings included, 1 beyond the critical angle: a total internal reflection at
//! `d` reflects everything; one before `d` stops the ray, as it does on the full path). That
//! is one grid per prefix `a-b-c` — about N³/3 for N reflecting surfaces, against N⁴/8
//! paths — and the legs to `a` and back to `b` are traced once per pair `a-b` and shared by
//! its prefixes. A packet whose rays are all lost stops being traced.
//!
//! **Sampling.** The prefix is traced on [`BOUND_GRID`]² rays over
//! [`bounds::entrance_search_rect`] at the light's angle: the very rays (bit for bit, same f32
//! sequence steps up to `d`) the precise search of every path starts from
//! ([`bounds::precise`]). On those rays the bound holds ray by ray, exactly. The bound is the
//! larger of two sums over that grid, times the cell area × cos θ over the reference flux (the
//! energy share, as [`bounds::precise`] defines it):
//!
//! - the **vertex sum** Σ_v p(v): strict against the path's energy share measured on this
//!   grid, vertex by vertex;
//! - the **upper cell sum** Σ_cells max over the cell's four corners of p: a cell with one
//!   open corner counts whole, so the part of a ghost's footprint between the grid's vertices
//!   is covered too; this is what makes it hold against the precise share, which is measured
//!   on a finer grid over the ghost's own rectangle. It is still a sample: a footprint that
//!   no vertex of the grid sees gets 0 here, but then the precise search (which starts from
//!   the same vertices) finds no light either.
//!
//! Measured against [`bounds::precise`] in `sdk/tests/ghosts.rs` and docs/accuracy.md
//! (§ Four-reflection energy bound).

use std::collections::HashMap;

use rayon::prelude::*;

use crate::system::LensSystem;
use crate::trace::{Interaction, InterfaceTable, InterfaceTableSet, Probe, Sequence, TABLE_LEN};

use super::bounds::{self, SEARCH_GRID};
use super::enumerate::{GhostPath, reflecting_surfaces};
use super::grid::ProbedGrid;

/// Vertices per side of the grid each prefix is traced on: the precise search's grid
/// ([`bounds::precise`] starts from the same rays).
pub const BOUND_GRID: usize = SEARCH_GRID;

/// Upper bounds on the energy share (flux over the reference flux, as [`bounds::precise`]
/// measures it) of every four-reflection path of a lens at one incidence angle, at the
/// wavelength of the interface tables they were computed with.
#[derive(Clone, Debug, Default)]
pub struct FourReflectionBounds {
    bounds: HashMap<GhostPath, f64>,
    prefixes: usize,
}

impl FourReflectionBounds {
    /// Traces every three-reflection prefix `a-b-c` of `system` at `theta` (radians, in the
    /// meridional plane) with `tables` (the lens's interface tables at the bounds'
    /// wavelength), prefixes in parallel; `reference` is [`bounds::reference_flux`] (every
    /// bound is 0 when it is 0, as energy shares are then). See the module's documentation
    /// for what is bounded and on which rays.
    pub fn compute(
        system: &LensSystem,
        tables: &InterfaceTableSet,
        theta: f64,
        reference: f64,
    ) -> Self {
        let r = reflecting_surfaces(system);
        let mut pairs = Vec::new();
        for (ia, &a) in r.iter().enumerate() {
            for &b in &r[..ia] {
                pairs.push((a, b));
            }
        }
        let bounds = pairs
            .par_iter()
            .map_init(ProbedGrid::default, |scratch, &(a, b)| {
                pair_bounds(system, tables, &r, [a, b], theta, reference, scratch)
            })
            .flatten_iter()
            .collect();
        let prefixes = pairs
            .iter()
            .map(|&(_, b)| r.iter().filter(|&&c| c > b).count())
            .sum();
        FourReflectionBounds { bounds, prefixes }
    }

    /// The bound on `path`'s energy share; `None` for a path that is not a four-reflection
    /// path of the lens.
    pub fn get(&self, path: &GhostPath) -> Option<f64> {
        self.bounds.get(path).copied()
    }

    /// How many three-reflection prefixes were traced.
    pub fn prefixes(&self) -> usize {
        self.prefixes
    }

    /// How many paths are bounded.
    pub fn len(&self) -> usize {
        self.bounds.len()
    }

    /// True when no path is bounded (a lens with fewer than two reflecting surfaces).
    pub fn is_empty(&self) -> bool {
        self.bounds.is_empty()
    }
}

/// The bounds of every path `a-b-c-d` with the first two reflections `ab`: the grid is
/// traced to `a` and back to `b` once, then on from there for each prefix `a-b-c`, `c > b`
/// over the reflecting surfaces `r`, and read at every reflecting `d < c`.
fn pair_bounds(
    system: &LensSystem,
    tables: &InterfaceTableSet,
    r: &[usize],
    [a, b]: [usize; 2],
    theta: f64,
    reference: f64,
    scratch: &mut ProbedGrid,
) -> Vec<(GhostPath, f64)> {
    let sequence = |start_forward: bool, path: &[(usize, Interaction)]| {
        Sequence::custom(system, tables.lambda_nm, start_forward, path)
            .ok()
            .map(|s| s.with_tables_from(tables).cast::<f32>())
    };
    // Forward to `a`, back to `b`: shared by every `c`.
    let mut ab: Vec<(usize, Interaction)> = (0..a).map(|i| (i, Interaction::Refract)).collect();
    ab.push((a, Interaction::Reflect));
    ab.extend((b + 1..a).rev().map(|i| (i, Interaction::Refract)));
    ab.push((b, Interaction::Reflect));
    let Some(ab) = sequence(true, &ab) else {
        return Vec::new();
    };
    let rect = bounds::entrance_search_rect(system, theta);
    scratch.start(&ab, theta, rect, BOUND_GRID);
    let scale = if reference > 0.0 {
        scratch.cell_area() * theta.cos() / reference
    } else {
        0.0
    };
    let mut out = Vec::new();
    let mut sums = SumScratch::default();
    for &c in r.iter().filter(|&&c| c > b) {
        let ds: Vec<usize> = r.iter().copied().take_while(|&d| d < c).collect();
        // Forward from `b` to `c`, then back down to the lowest reflecting surface, refracting
        // there: the steps of every `a-b-c-d` from `b` up to its `d`.
        let mut path: Vec<(usize, Interaction)> =
            (b + 1..c).map(|i| (i, Interaction::Refract)).collect();
        path.push((c, Interaction::Reflect));
        let leg = path.len();
        path.extend((ds[0]..c).rev().map(|i| (i, Interaction::Refract)));
        let Some(seq) = sequence(true, &path) else {
            continue;
        };
        let probes: Vec<Probe<f32>> = (leg..path.len())
            .filter(|&i| ds.contains(&path[i].0))
            .map(|i| Probe {
                step: i,
                // The reflectance toward the object at `d`; a surface without a table
                // reflects with weight 1 on a traced path (its step leaves the weight alone).
                table: tables.get(path[i].0, false, Interaction::Reflect).map_or(
                    InterfaceTable::in_cosine([1.0; TABLE_LEN]),
                    |t| InterfaceTable {
                        values: t.values.map(|v| v as f32),
                        k: t.k as f32,
                    },
                ),
            })
            .collect();
        scratch.continue_probed(&seq, &probes);
        for (k, p) in probes.iter().enumerate() {
            let d = path[p.step].0;
            let bound = grid_sum(scratch, k, &mut sums) * scale;
            out.push((GhostPath::four(a, b, c, d), bound));
        }
    }
    out
}

/// Rings of neighbouring cells a cell's largest corner value is spread over in the upper
/// cell sum (module docs): 1 covers a footprint reaching up to two cells past the grid's last
/// open vertex.
pub const BOUND_DILATION_CELLS: usize = 1;

/// The larger of probe `k`'s vertex sum and its dilated upper cell sum over the grid (module
/// docs). `buf` is scratch.
fn grid_sum(g: &ProbedGrid, k: usize, buf: &mut SumScratch) -> f64 {
    let n = g.n;
    let m = n - 1;
    let SumScratch {
        vertices,
        cells,
        rows,
    } = buf;
    if g.values(k).all(|v| v <= 0.0) {
        // Nothing open (the values are ≥ 0): every sum is 0. Most probes end here.
        return 0.0;
    }
    vertices.clear();
    vertices.extend(g.values(k).map(f64::from));
    let vertex_sum: f64 = vertices.iter().sum();
    // Largest corner per cell; then the largest over the cell's neighbourhood, a separable
    // max filter (along rows, then along columns).
    cells.clear();
    for j in 0..m {
        let (lo, hi) = (
            &vertices[j * n..(j + 1) * n],
            &vertices[(j + 1) * n..(j + 2) * n],
        );
        cells.extend((0..m).map(|i| lo[i].max(lo[i + 1]).max(hi[i]).max(hi[i + 1])));
    }
    let r = BOUND_DILATION_CELLS;
    let window = |i: usize| i.saturating_sub(r)..(i + r + 1).min(m);
    rows.clear();
    for j in 0..m {
        let row = &cells[j * m..(j + 1) * m];
        rows.extend((0..m).map(|i| row[window(i)].iter().copied().fold(0.0, f64::max)));
    }
    let mut dilated = 0.0;
    for j in 0..m {
        for i in 0..m {
            dilated += window(j).map(|jj| rows[jj * m + i]).fold(0.0, f64::max);
        }
    }
    vertex_sum.max(dilated)
}

/// Buffers [`grid_sum`] reuses.
#[derive(Debug, Default)]
struct SumScratch {
    vertices: Vec<f64>,
    cells: Vec<f64>,
    rows: Vec<f64>,
}
