//! Ghost bounds per incidence angle: the rectangle of the entrance plane whose rays reach the
//! sensor along a ghost path, where they land, how fine a grid the ghost needs and how bright
//! it is. Two modes:
//!
//! - **approximate** (paraxial): each clear aperture met along the path bounds the entrance
//!   height linearly (`|A·y0 + B·u| ≤ semi-diameter`); intervals intersect. Microseconds per
//!   ghost; exact for small angles and apertures, generous or tight elsewhere.
//! - **precise** (traced): a grid over the front element is traced, the bounding box of the
//!   rays that pass every aperture is refined twice on finer grids, and the ghost's energy
//!   share and grid size are measured on the last grid.
//!
//! Four-reflection paths are culled before either, by the traced prefix bound of
//! [`super::four_bound`].
//!
//! Bounds are computed in the meridional frame (light in the y–z plane); for a light at
//! azimuth φ the rectangle and the sensor bounds rotate with it about the axis.

use serde::{Deserialize, Serialize};

use crate::paraxial::stop_opening;
use crate::system::LensSystem;
use crate::trace::{Interaction, InterfaceTableSet, Sequence};

use super::grid::{GridTrace, PointTrace, trace_grid};
use crate::ghost_path::GhostPath;
pub use crate::rect::Rect;

/// A ghost at one incidence angle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GhostBounds {
    /// Entrance-plane rectangle (meridional frame) whose rays reach the sensor.
    pub entrance: Rect,
    /// Where those rays land (meridional frame).
    pub sensor: Rect,
    /// Grid vertices per side the ghost needs (from the spread of its triangle areas).
    pub grid: usize,
    /// Mean Fresnel/coating throughput of the rays that pass.
    pub mean_intensity: f64,
    /// The ghost's flux over the reference flux ([`reference_flux`]: the direct image's flux
    /// of the same light on axis), so it stays meaningful where the direct image itself is
    /// vignetted away (a light just outside the field still makes ghosts).
    pub energy_share: f64,
}

/// How bounds are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoundsMode {
    Approximate,
    Precise,
}

/// Grid sizes the precise mode searches with (from scratch, and from a nearby angle's
/// rectangle) and measures with.
pub(crate) const SEARCH_GRID: usize = 33;
const WARM_GRID: usize = 25;
const REFINE_GRID: usize = 33;
/// Grid size range chosen for rendering.
pub const MIN_GRID: usize = 16;
pub const MAX_GRID: usize = 128;

/// The square on the entrance plane that holds every ray which can enter the lens at
/// `theta`: the front element's semi-diameter, widened by how far an oblique ray moves
/// between the plane z = 0 and the front surface's rim.
pub fn entrance_search_rect(system: &LensSystem, theta: f64) -> Rect {
    let s0 = &system.surfaces[0];
    let sag = s0.sag(s0.semi_diameter).unwrap_or(0.0).abs();
    let h = s0.semi_diameter * 1.02 + sag * theta.tan().abs();
    Rect::square(0.0, 0.0, h)
}

/// The direct image's flux at `theta` for unit irradiance (perpendicular to the beam): the
/// forward path traced on a [`SEARCH_GRID`]² grid over the front element to find the pupil
/// (the rays that pass every aperture), then on a [`DIRECT_GRID`]² grid over it, its flux
/// integrated with the pupil's edge placed between the vertices ([`clipped_flux`]). Measuring
/// over the front element instead left about 290 vertices inside the Heliar's f/22 pupil and
/// the flux 2.1% low against the Monte-Carlo reference (`monte_carlo::path_flux`).
pub fn direct_flux(
    system: &LensSystem,
    tables: &InterfaceTableSet,
    theta: f64,
    scratch: &mut GridTrace,
) -> f64 {
    let seq = Sequence::forward(system, tables.lambda_nm)
        .with_tables_from(tables)
        .cast::<f32>();
    let stop = stop_opening(system);
    let search = entrance_search_rect(system, theta);
    trace_grid(&seq, theta, search, SEARCH_GRID, stop, scratch);
    // The pupil lies within a cell of the passing vertices. A pupil the search grid does not
    // see (a small stop behind a large front element) is looked for about the paraxial
    // entrance pupil, and else measured over the whole search square.
    let mut rect = match passing_box(scratch) {
        Some(found) => {
            let (cx, cy) = cell_size(scratch);
            found.expand(cx, cy)
        }
        None => paraxial_pupil(system, theta).unwrap_or(search),
    };
    trace_grid(&seq, theta, rect, DIRECT_GRID, stop, scratch);
    if passing_box(scratch).is_none() && rect != search {
        rect = search;
        trace_grid(&seq, theta, rect, DIRECT_GRID, stop, scratch);
    }
    // Where the pupil fills little of the rectangle (it was found by a few vertices of a
    // coarse grid), the grid is laid over it again.
    for _ in 0..PUPIL_REFINEMENTS {
        let Some(found) = passing_box(scratch) else {
            break;
        };
        let (cx, cy) = cell_size(scratch);
        let next = found.expand(cx, cy);
        if next.width() > 0.5 * rect.width() && next.height() > 0.5 * rect.height() {
            break;
        }
        rect = next;
        trace_grid(&seq, theta, rect, DIRECT_GRID, stop, scratch);
    }
    clipped_flux(scratch, theta)
}

/// How many times [`direct_flux`] may lay its grid again over a pupil that fills less than
/// half its rectangle across: the Heliar and the Nikon zoom need none; the fisheye at f/64
/// (a 0.16 mm pupil behind a front element 60 mm across) two, which bring its flux from 2.4%
/// below the paraxial pupil's to within 0.1%.
const PUPIL_REFINEMENTS: usize = 3;

/// Three times the paraxial entrance pupil's square at `theta`, about where the chief ray
/// enters (`None` when the lens has no paraxial pupil).
fn paraxial_pupil(system: &LensSystem, theta: f64) -> Option<Rect> {
    let p = crate::paraxial::analyse(system, crate::spectrum::LAMBDA_D_NM).ok()?;
    let r = 1.5 * p.entrance_pupil_diameter_mm;
    (r.is_finite() && r > 0.0).then(|| Rect::square(0.0, -p.entrance_pupil_z_mm * theta.tan(), r))
}

/// Grid vertices a side over the pupil for [`direct_flux`]: its flux then agrees with the
/// Monte-Carlo reference to 0.02% on the Heliar and the Nikon zoom (docs/accuracy.md).
const DIRECT_GRID: usize = 65;

/// The flux every energy share is measured against: the direct image's flux for a light on
/// axis ([`direct_flux`] at θ = 0), for unit irradiance. It does not depend on the light's
/// angle, so it never vanishes where the direct image at an oblique angle does (a light just
/// outside the field, whose image is vignetted away inside the lens while its ghosts still
/// reach the sensor), and shares at different angles compare directly.
pub fn reference_flux(
    system: &LensSystem,
    tables: &InterfaceTableSet,
    scratch: &mut GridTrace,
) -> f64 {
    direct_flux(system, tables, 0.0, scratch)
}

/// The flux through the grid (mm² for unit irradiance): `cos θ ×` the integral of the weight
/// over the entrance plane where the ray passes, each grid cell split into two triangles over
/// which the weight and the excess `r/semi − 1` (the largest relative radius along the path,
/// minus one) are linear, so that the edge of the passing region is placed between a
/// passing and a failing vertex where the excess crosses zero, rather than on the vertices.
/// A triangle with a stopped ray (missed surface, total internal reflection) among its corners
/// counts its passing corners' weights (a third of its area each). On a 33² grid this brings
/// the energy shares within 0.2–0.4% of the Monte-Carlo reference, where counting the passing
/// vertices (each with a cell's area) missed by up to 2%.
pub fn clipped_flux(g: &GridTrace, theta: f64) -> f64 {
    let n = g.n;
    if n < 2 {
        return 0.0;
    }
    let mut sum = 0.0;
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k00 = j * n + i;
            let quad = [k00, k00 + 1, k00 + n + 1, k00 + n];
            let passes = quad.map(|k| g.passes(k));
            if passes.iter().all(|&p| p) {
                sum += inner_cell(g, quad);
                continue;
            }
            if !passes.iter().any(|&p| p) {
                // Wholly outside, unless the excess dips below zero inside the cell, which
                // the linear model does not see either.
                continue;
            }
            for tri in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
                if tri.iter().all(|&k| g.completed[k]) {
                    sum += clipped_triangle(
                        tri.map(|k| g.max_rel[k] as f64 - 1.0),
                        tri.map(|k| g.weight[k] as f64),
                    );
                } else {
                    sum += tri
                        .iter()
                        .filter(|&&k| g.passes(k))
                        .map(|&k| g.weight[k] as f64)
                        .sum::<f64>()
                        / 3.0;
                }
            }
        }
    }
    // Each triangle is half a cell.
    sum * 0.5 * g.cell_area() * theta.cos()
}

/// [`clipped_flux`] of `g` (traced along `seq`), with each cell the passing region's edge
/// crosses (some corners passing, some not) traced again on an `(m + 1)²` grid of its own
/// and integrated over that: the edge placed `m` times more finely, where the linear
/// excess of one cell misses a kink (two clear apertures meeting inside the cell, as across a
/// thin ring). `sub` is scratch for the cells' grids.
pub fn edge_refined_flux(
    seq: &Sequence<f32>,
    theta: f64,
    stop: f64,
    g: &GridTrace,
    m: usize,
    sub: &mut GridTrace,
) -> f64 {
    let n = g.n;
    if n < 2 || m < 2 {
        return clipped_flux(g, theta);
    }
    let (cw, ch) = cell_size(g);
    let mut inner = 0.0;
    let mut edge = 0.0;
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k00 = j * n + i;
            let quad = [k00, k00 + 1, k00 + n + 1, k00 + n];
            let passing = quad.iter().filter(|&&k| g.passes(k)).count();
            if passing == 4 {
                inner += inner_cell(g, quad);
            } else if passing > 0 {
                let x0 = g.rect.x0 + cw * i as f64;
                let y0 = g.rect.y0 + ch * j as f64;
                let cell = Rect {
                    x0,
                    y0,
                    x1: x0 + cw,
                    y1: y0 + ch,
                };
                trace_grid(seq, theta, cell, m + 1, stop, sub);
                edge += clipped_flux(sub, theta);
            }
        }
    }
    inner * 0.5 * g.cell_area() * theta.cos() + edge
}

/// A cell wholly inside the passing region (corners `quad`, in order round it): the sum of
/// its two triangles' mean weights, each triangle half the cell.
fn inner_cell(g: &GridTrace, quad: [usize; 4]) -> f64 {
    let w = quad.map(|k| g.weight[k] as f64);
    (2.0 * (w[0] + w[2]) + w[1] + w[3]) / 3.0
}

/// The mean over a triangle of `w · [e ≤ 0]`, with `e` and `w` linear over it (given at its
/// corners): the triangle clipped by `e ≤ 0` (Sutherland–Hodgman against one half-plane, in
/// barycentric coordinates) and the linear `w` integrated over the pieces of the fan, as a
/// fraction of the triangle's area.
fn clipped_triangle(e: [f64; 3], w: [f64; 3]) -> f64 {
    if e.iter().all(|&v| v <= 0.0) {
        return (w[0] + w[1] + w[2]) / 3.0;
    }
    if e.iter().all(|&v| v > 0.0) {
        return 0.0;
    }
    // Corners of the reference triangle (0,0), (1,0), (0,1) with their e and w.
    let p = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let mut poly: [([f64; 2], f64); 4] = [([0.0; 2], 0.0); 4];
    let mut len = 0;
    for k in 0..3 {
        let l = (k + 1) % 3;
        if e[k] <= 0.0 {
            poly[len] = (p[k], w[k]);
            len += 1;
        }
        if (e[k] <= 0.0) != (e[l] <= 0.0) {
            let t = e[k] / (e[k] - e[l]);
            poly[len] = (
                [
                    p[k][0] + t * (p[l][0] - p[k][0]),
                    p[k][1] + t * (p[l][1] - p[k][1]),
                ],
                w[k] + t * (w[l] - w[k]),
            );
            len += 1;
        }
    }
    let mut integral = 0.0;
    for k in 1..len.saturating_sub(1) {
        let (a, b, c) = (poly[0], poly[k], poly[k + 1]);
        let area = 0.5
            * ((b.0[0] - a.0[0]) * (c.0[1] - a.0[1]) - (c.0[0] - a.0[0]) * (b.0[1] - a.0[1])).abs();
        integral += area * (a.1 + b.1 + c.1) / 3.0;
    }
    // The reference triangle's area is ½.
    integral / 0.5
}

/// Precise bounds of `path` at `theta` (radians), at the wavelength of `tables` (the lens's
/// interface tables, built once); `None` when no ray of the ghost reaches the sensor.
/// `reference` is [`reference_flux`] (energy shares are the ghost's flux over it).
pub fn precise(
    system: &LensSystem,
    path: GhostPath,
    tables: &InterfaceTableSet,
    theta: f64,
    reference: f64,
    scratch: &mut GridTrace,
) -> Option<GhostBounds> {
    let seq = ghost_sequence(system, path, tables)?;
    precise_from(system, &seq, theta, reference, None, scratch)
}

/// The f32 sequence of a ghost with its interface tables, as the precise search traces it.
pub fn ghost_sequence(
    system: &LensSystem,
    path: GhostPath,
    tables: &InterfaceTableSet,
) -> Option<Sequence<f32>> {
    Some(
        Sequence::ghost_path(system, tables.lambda_nm, &path)
            .ok()?
            .with_tables_from(tables)
            .cast::<f32>(),
    )
}

/// [`precise`], starting from the entrance rectangle found at a nearby angle (`start`): the
/// search then traces one grid over that rectangle, widened by a quarter, instead of a search
/// and a refinement over the whole front element. If the ghost reaches the edge of the
/// widened rectangle, or is not found there, the full search runs.
pub fn precise_from(
    system: &LensSystem,
    seq: &Sequence<f32>,
    theta: f64,
    reference: f64,
    start: Option<Rect>,
    scratch: &mut GridTrace,
) -> Option<GhostBounds> {
    let stop = stop_opening(system);
    let rect = entrance_rect(system, seq, theta, stop, start, true, scratch)?;
    trace_grid(seq, theta, rect, REFINE_GRID, stop, scratch);
    let g = &*scratch;
    let n = g.n;
    let passing: Vec<usize> = (0..n * n).filter(|&k| g.passes(k)).collect();
    let found = region_box(g)?;
    let (cx, cy) = cell_size(g);
    let sensor = Rect::bounding(passing.iter().map(|&k| g.sensor[k].map(f64::from)))?;
    let mean_intensity =
        passing.iter().map(|&k| g.weight[k] as f64).sum::<f64>() / passing.len() as f64;
    let grid = grid_for_spread(g);
    // The flux with the edge cells traced again (`edge_refined_flux`); a thin ring or crescent
    // (`grid_for_edges`) on the finer grid it is drawn at, where the refine grid's edge cells
    // are too many and too coarse.
    let by_edges = grid_for_edges(g).min(MAX_GRID);
    let flux = if by_edges > REFINE_GRID {
        trace_grid(seq, theta, rect, by_edges, stop, scratch);
        edge_refined_flux(
            seq,
            theta,
            stop,
            scratch,
            EDGE_SUBDIVISION,
            &mut GridTrace::default(),
        )
    } else {
        let coarse = clipped_flux(g, theta);
        if coarse >= EDGE_REFINE_MIN_SHARE * reference {
            edge_refined_flux(
                seq,
                theta,
                stop,
                g,
                EDGE_SUBDIVISION,
                &mut GridTrace::default(),
            )
        } else {
            coarse
        }
    };
    Some(GhostBounds {
        entrance: found.expand(cx, cy),
        sensor,
        grid,
        mean_intensity,
        energy_share: if reference > 0.0 {
            flux / reference
        } else {
            0.0
        },
    })
}

/// The rectangle a ghost's rays reach the sensor from, one cell of margin around them: the
/// search of [`precise_from`] (warm from `start` when given; then, if that fails and
/// `full_search`, over the whole front element), before its refinement. `scratch` is left
/// holding the last grid traced, whose passing vertices all lie inside the rectangle.
fn entrance_rect(
    system: &LensSystem,
    seq: &Sequence<f32>,
    theta: f64,
    stop: f64,
    start: Option<Rect>,
    full_search: bool,
    scratch: &mut GridTrace,
) -> Option<Rect> {
    let search = entrance_search_rect(system, theta);
    // Each plan: (rectangle, whether it is the full search).
    let mut plan: Vec<(Rect, bool)> = Vec::with_capacity(2);
    if let Some(r) = start.filter(|r| !r.is_empty()) {
        plan.push((r.expand(0.25 * r.width(), 0.25 * r.height()), false));
    }
    if full_search {
        plan.push((search, true));
    }
    'plans: for (mut r, full) in plan {
        // The full search traces twice (search, then refine); a warm start once.
        let grids: &[usize] = if full {
            &[SEARCH_GRID, SEARCH_GRID]
        } else {
            &[WARM_GRID]
        };
        for &n in grids {
            let mut widened = 0;
            loop {
                trace_grid(seq, theta, r, n, stop, scratch);
                let found = match region_box(scratch) {
                    Some(found) => found,
                    // A region smaller than the search grid's cells, between its vertices:
                    // look closer where the rays came nearest to passing.
                    None if full && widened == 0 && r == search => {
                        let found = zoom(seq, theta, stop, scratch)
                            .or_else(|| paraxial_seed(seq, theta, stop, &search, scratch));
                        match found {
                            Some(z) => {
                                r = z;
                                break;
                            }
                            None => continue 'plans,
                        }
                    }
                    None => continue 'plans,
                };
                let (cx, cy) = cell_size(scratch);
                // Sides where a passing vertex lies on the traced rectangle's edge: the ghost
                // may go on beyond it.
                let open = [
                    found.x0 - r.x0 < cx,
                    found.y0 - r.y0 < cy,
                    r.x1 - found.x1 < cx,
                    r.y1 - found.y1 < cy,
                ];
                if !full {
                    // A warm start must contain the ghost with room to spare.
                    if open.iter().any(|&o| o) {
                        continue 'plans;
                    }
                } else if let Some(wider) =
                    widen(&r, &open, &search).filter(|_| widened < MAX_WIDENINGS)
                {
                    // A coarse pass that caught only a thin slice of a ghost (its tip, say)
                    // leaves it cut by the rectangle: trace again over a wider one.
                    r = wider;
                    widened += 1;
                    continue;
                }
                // One cell of margin: the true edge lies between a passing and a failing
                // vertex.
                r = found.expand(cx, cy);
                break;
            }
        }
        return Some(r);
    }
    None
}

/// `base` (a ghost's bounds found at one wavelength) grown to hold the ghost traced through
/// `seq` (the same ghost at another wavelength), and its grid grown with the rectangle's side
/// (rounded down, capped at [`MAX_GRID`]) so the region at either wavelength keeps its
/// vertices. The energy share and mean intensity stay `base`'s. A ghost's region moves with
/// the wavelength: Nikon zoom short 15-11 at 20°, traced at 390 nm over its 550 nm rectangle,
/// lost 9.4% of its flux.
///
/// A ring of rays along the rectangle's border (at the refine grid's spacing) and, the first
/// time, a few inside it are traced ([`border_reach`]). Each side the region reaches moves out
/// by one refine cell and the ring is traced again, up to [`RING_STEPS`] times; past that, or
/// when the region has left the inside, it is searched for as [`precise_from`] searches (from
/// the rectangle widened by a quarter; then, for a region on the border, over the whole front
/// element), and the sensor rectangle takes in where its rays land.
pub fn widened_for(
    system: &LensSystem,
    seq: &Sequence<f32>,
    theta: f64,
    base: &GhostBounds,
    scratch: &mut GridTrace,
    probe: &mut PointTrace,
) -> GhostBounds {
    let d = (REFINE_GRID - 1) as f64;
    let (cx, cy) = (base.entrance.width() / d, base.entrance.height() / d);
    let mut rect = base.entrance;
    let mut sensor = base.sensor;
    for step in 0..=RING_STEPS {
        let full_search = match border_reach(seq, theta, &rect, step == 0, probe) {
            Reach::Inside => break,
            Reach::Border(sides) if step < RING_STEPS => {
                let out = |side: usize, c: f64| if sides[side] { c } else { 0.0 };
                rect = Rect {
                    x0: rect.x0 - out(0, cx),
                    y0: rect.y0 - out(1, cy),
                    x1: rect.x1 + out(2, cx),
                    y1: rect.y1 + out(3, cy),
                };
                continue;
            }
            Reach::Border(_) => true,
            Reach::Absent => false,
        };
        let stop = stop_opening(system);
        if let Some(found) =
            entrance_rect(system, seq, theta, stop, Some(rect), full_search, scratch)
        {
            let g = &*scratch;
            let landed = (0..g.n * g.n)
                .filter(|&k| g.passes(k))
                .map(|k| g.sensor[k].map(f64::from));
            sensor = Rect::bounding(landed).map_or(sensor, |s| sensor.union(&s));
            rect = rect.union(&found);
        }
        break;
    }
    let growth = (rect.area() / base.entrance.area()).sqrt();
    let grid = if growth.is_finite() && growth > 1.0 {
        ((base.grid as f64 * growth).floor() as usize).clamp(base.grid, MAX_GRID.max(base.grid))
    } else {
        base.grid
    };
    GhostBounds {
        entrance: rect,
        sensor,
        grid,
        ..*base
    }
}

/// Times [`widened_for`] moves a rectangle's sides out by a cell before it searches instead.
const RING_STEPS: usize = 3;

/// Where a ghost's region lies against a rectangle ([`border_reach`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reach {
    /// Inside it, clear of its border.
    Inside,
    /// On its border, or across it: the sides it reaches (left, bottom, right, top: x0, y0,
    /// x1, y1).
    Border([bool; 4]),
    /// Neither on its border nor at any of the few rays traced inside it.
    Absent,
}

/// Vertices a side of the grid whose inner vertices [`border_reach`] traces inside the
/// rectangle.
const INNER_PROBE: usize = 9;

/// Whether the region of `seq` reaches `rect`'s border: rays along the border at the refine
/// grid's spacing, in order round it (one passing, or the excess dipping below zero between
/// two of them, [`dips_between`]); with `inner`, a region clear of the border must also pass
/// at one of [`INNER_PROBE`]'s inner vertices to be inside.
fn border_reach(
    seq: &Sequence<f32>,
    theta: f64,
    rect: &Rect,
    inner: bool,
    probe: &mut PointTrace,
) -> Reach {
    let n = REFINE_GRID;
    let d = (n - 1) as f64;
    let at = |i: usize, j: usize, m: f64| {
        [
            rect.x0 + rect.width() * i as f64 / m,
            rect.y0 + rect.height() * j as f64 / m,
        ]
    };
    // Round the border: along the bottom, up the right, back along the top, down the left.
    let len = 4 * (n - 1);
    let ring = |k: usize| {
        let (side, t) = ((k % len) / (n - 1), k % (n - 1));
        match side {
            0 => (t, 0),
            1 => (n - 1, t),
            2 => (n - 1 - t, n - 1),
            _ => (0, n - 1 - t),
        }
    };
    let m = (INNER_PROBE - 1) as f64;
    let inside = (1..INNER_PROBE - 1)
        .flat_map(|j| (1..INNER_PROBE - 1).map(move |i| (i, j)))
        .filter(|_| inner)
        .map(|(i, j)| at(i, j, m));
    probe.trace(
        seq,
        theta,
        (0..len).map(&ring).map(|(i, j)| at(i, j, d)).chain(inside),
    );
    let e = |k: usize| probe.max_rel[k % len] - 1.0;
    let mut sides = [false; 4];
    let mut mark = |k: usize| {
        let (i, j) = ring(k);
        sides[0] |= i == 0;
        sides[1] |= j == 0;
        sides[2] |= i == n - 1;
        sides[3] |= j == n - 1;
    };
    for k in 0..len {
        if probe.passes(k) {
            mark(k);
        }
        if dips_between(e(k + len - 1), e(k), e(k + 1), e(k + 2)) {
            mark(k);
            mark(k + 1);
        }
    }
    if sides.iter().any(|&s| s) {
        Reach::Border(sides)
    } else if !inner || (len..probe.max_rel.len()).any(|k| probe.passes(k)) {
        Reach::Inside
    } else {
        Reach::Absent
    }
}

/// The energy share above which a ghost's edge cells are traced again for its flux
/// ([`edge_refined_flux`]); a dimmer ghost keeps the refine grid's [`clipped_flux`], within
/// 0.2–0.5% (its share only decides whether it is culled).
const EDGE_REFINE_MIN_SHARE: f64 = 1e-4;

/// Sub-cells a side each edge cell of the refine grid is traced again on for its flux
/// ([`edge_refined_flux`]).
const EDGE_SUBDIVISION: usize = 4;

/// Times a full search's rectangle may be widened and traced again: each at least doubles
/// a side, so a few reach the search square from any rectangle a coarse pass leaves.
const MAX_WIDENINGS: usize = 8;

/// `r` widened by its own width (height) on each side flagged in `open` (left, top, right,
/// bottom) that lies inside `search`, clamped to `search`; `None` when no flagged side can
/// move.
fn widen(r: &Rect, open: &[bool; 4], search: &Rect) -> Option<Rect> {
    let (w, h) = (r.width(), r.height());
    let wider = Rect {
        x0: if open[0] {
            (r.x0 - w).max(search.x0)
        } else {
            r.x0
        },
        y0: if open[1] {
            (r.y0 - h).max(search.y0)
        } else {
            r.y0
        },
        x1: if open[2] {
            (r.x1 + w).min(search.x1)
        } else {
            r.x1
        },
        y1: if open[3] {
            (r.y1 + h).min(search.y1)
        } else {
            r.y1
        },
    };
    (wider != *r).then_some(wider)
}

/// The bounding box of the passing vertices and of the thin parts of the region that reach
/// out from them between the grid's rows or columns: the endpoints of every grid edge along
/// which the excess `e = r/semi − 1` dips below zero between two failing vertices
/// ([`edge_dips`]), connected (8-neighbours) to a passing vertex through such endpoints.
/// Without them, the Heliar's ghost 8-0 at 10° (a sliver 0.08 mm tall tapering over ±0.47 mm)
/// was bounded to ±0.32 mm, losing 18% of its flux.
fn region_box(g: &GridTrace) -> Option<Rect> {
    let n = g.n;
    let found = passing_box(g)?;
    // The thin parts: dips connected to a passing vertex through dips.
    let excess: Vec<f32> = (0..n * n)
        .map(|k| {
            if g.completed[k] {
                g.max_rel[k] - 1.0
            } else {
                f32::NAN
            }
        })
        .collect();
    let dips = edge_dips(n, &excess);
    if dips.is_empty() {
        return Some(found);
    }
    let mut dip = vec![false; n * n];
    for (a, b) in dips {
        dip[a] = true;
        dip[b] = true;
    }
    let near_passing = |k: usize| {
        let (i, j) = (k % n, k / n);
        (j.saturating_sub(1)..=(j + 1).min(n - 1))
            .any(|jj| (i.saturating_sub(1)..=(i + 1).min(n - 1)).any(|ii| g.passes(jj * n + ii)))
    };
    let mut seen = vec![false; n * n];
    let mut stack: Vec<usize> = (0..n * n).filter(|&k| dip[k] && near_passing(k)).collect();
    for &k in &stack {
        seen[k] = true;
    }
    let mut reached = Vec::new();
    while let Some(k) = stack.pop() {
        reached.push(k);
        let (i, j) = (k % n, k / n);
        for jj in j.saturating_sub(1)..=(j + 1).min(n - 1) {
            for ii in i.saturating_sub(1)..=(i + 1).min(n - 1) {
                let v = jj * n + ii;
                if dip[v] && !seen[v] {
                    seen[v] = true;
                    stack.push(v);
                }
            }
        }
    }
    let d = (n - 1) as f64;
    let thin = Rect::bounding(reached.iter().map(|&k| {
        let (i, j) = (k % n, k / n);
        [
            g.rect.x0 + g.rect.width() * i as f64 / d,
            g.rect.y0 + g.rect.height() * j as f64 / d,
        ]
    }));
    Some(thin.map_or(found, |t| found.union(&t)))
}

/// The grid edges `(a, b)` (vertex indices, along rows and columns) whose excess dips below
/// zero between two failing vertices: with `a'` before `a` and `b'` after `b` on the same
/// line, the lines through `a'`, `a` and through `b`, `b'` both fall toward the edge and meet
/// inside it below zero — the V that the largest of two clear-aperture constraints makes
/// across a region thinner than a cell. `excess[k]` is NaN for a stopped ray.
fn edge_dips(n: usize, excess: &[f32]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    if n < 4 {
        return out;
    }
    // Lines: rows (step 1) and columns (step n), each given by its vertex at position t.
    for (step, stride) in [(1, n), (n, 1)] {
        for l in 0..n {
            let at = |t: usize| l * stride + t * step;
            for t in 1..n - 2 {
                let (a, b) = (at(t), at(t + 1));
                if dips_between(excess[at(t - 1)], excess[a], excess[b], excess[at(t + 2)]) {
                    out.push((a, b));
                }
            }
        }
    }
    out
}

/// Whether the excess dips below zero between two failing vertices `a`, `b` of a line (`ea`,
/// `eb`), given their outer neighbours' (`e_before`, `e_after`): the lines through the
/// neighbours' and the vertices' values both fall toward the edge and meet inside it below
/// zero. NaN (a stopped ray) fails.
fn dips_between(e_before: f32, ea: f32, eb: f32, e_after: f32) -> bool {
    // Both failing (NaN, a stopped ray, fails this too).
    if !(ea > 0.0 && eb > 0.0) {
        return false;
    }
    let (da, db) = (e_before - ea, e_after - eb);
    if !(da > 0.0 && db > 0.0) {
        return false;
    }
    let t_min = (ea - eb + db) / (da + db);
    t_min > 0.0 && t_min < 1.0 && ea - da * t_min <= 0.0
}

/// Zoom levels [`zoom`] may descend, the vertices a side of each level's grid, and how many
/// starting vertices it tries.
const ZOOM_LEVELS: usize = 6;
const ZOOM_GRID: usize = 9;
const ZOOM_STARTS: usize = 3;
/// Levels in a row that may come no nearer to passing before [`zoom`] gives a start up.
const ZOOM_PATIENCE: usize = 2;

/// For a search grid (in `scratch`) where no ray passes: about each of the [`ZOOM_STARTS`]
/// vertices (at least two cells apart) whose rays came nearest to passing (the smallest excess `r/semi − 1`) that may
/// have the region beside them — the excess within twice its largest change to a neighbour,
/// or a neighbour's ray stopped (the path open only in a narrow channel there) — grids of
/// ±1.5 cells, down to [`ZOOM_LEVELS`] levels each about the nearest vertex of the last;
/// the passing vertices' box, a cell wider all round, when a level finds some. The Nikon
/// zoom's short ghosts 10-3, 10-6, 13-3, 13-6 and 13-8 at 5°, under 1 mm across, fell between
/// the 2.07 mm spacing of the search grid and were reported as having no light.
fn zoom(seq: &Sequence<f32>, theta: f64, stop: f64, scratch: &mut GridTrace) -> Option<Rect> {
    let starts = candidates(scratch);
    let search_cell = cell_size(scratch);
    for start in starts {
        let mut centre = start;
        let mut cell = search_cell;
        let mut nearest = f32::INFINITY;
        let mut stalled = 0;
        for level in 0..ZOOM_LEVELS {
            let r = Rect {
                x0: centre[0] - 1.5 * cell.0,
                y0: centre[1] - 1.5 * cell.1,
                x1: centre[0] + 1.5 * cell.0,
                y1: centre[1] + 1.5 * cell.1,
            };
            trace_grid(seq, theta, r, ZOOM_GRID, stop, scratch);
            if let Some(found) = region_box(scratch) {
                let (cx, cy) = cell_size(scratch);
                return Some(found.expand(cx, cy));
            }
            // The excess nearest to passing on this level: two levels in a row that come no
            // nearer than the best before them are not closing in on a region.
            let level_nearest = (0..scratch.n * scratch.n)
                .filter(|&k| scratch.completed[k])
                .map(|k| scratch.max_rel[k])
                .fold(f32::INFINITY, f32::min);
            if level_nearest < nearest {
                nearest = level_nearest;
                stalled = 0;
            } else {
                stalled += 1;
            }
            if level + 1 == ZOOM_LEVELS || stalled == ZOOM_PATIENCE {
                break;
            }
            match candidates(scratch).first() {
                Some(&c) => centre = c,
                None => break,
            }
            cell = cell_size(scratch);
        }
    }
    None
}

/// Vertices a side of the grid [`paraxial_seed`] traces over the paraxial entrance rectangle.
const PARAXIAL_SEED_GRID: usize = 17;

/// For a ghost the search grid and [`zoom`] do not find: a grid over the paraxial entrance
/// rectangle ([`paraxial_path`]), doubled about its centre, and [`zoom`] from there when no
/// vertex of it passes. A search grid whose every ray stops (a surface missed, total internal
/// reflection) gives [`zoom`] no ray to start from, while the region may still pass light:
/// the Nikon zoom short's 13-1, 13-3, 13-4, 13-5, 13-6 and 13-8 at 10°, 0.5–0.7 mm across
/// where the paraxial rectangle falls, each cell of the 33² search grid 2.1 mm.
fn paraxial_seed(
    seq: &Sequence<f32>,
    theta: f64,
    stop: f64,
    search: &Rect,
    scratch: &mut GridTrace,
) -> Option<Rect> {
    let p = paraxial_entrance(seq, theta)?;
    let r = p.expand(0.5 * p.width(), 0.5 * p.height());
    let r = Rect {
        x0: r.x0.max(search.x0),
        y0: r.y0.max(search.y0),
        x1: r.x1.min(search.x1),
        y1: r.y1.min(search.y1),
    };
    if r.is_empty() {
        return None;
    }
    trace_grid(seq, theta, r, PARAXIAL_SEED_GRID, stop, scratch);
    match region_box(scratch) {
        Some(found) => {
            let (cx, cy) = cell_size(scratch);
            Some(found.expand(cx, cy))
        }
        None => zoom(seq, theta, stop, scratch),
    }
}

/// The vertices of `g` (entrance positions, nearest to passing first) beside which a region
/// too small for the grid may pass: see [`zoom`].
fn candidates(g: &GridTrace) -> Vec<[f64; 2]> {
    let n = g.n;
    let excess = |k: usize| g.completed[k].then(|| g.max_rel[k] as f64 - 1.0);
    let mut order: Vec<(usize, f64)> = (0..n * n)
        .filter_map(|k| excess(k).map(|e| (k, e)))
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let d = (n - 1) as f64;
    order
        .into_iter()
        .filter(|&(k, e)| {
            let (i, j) = ((k % n) as i64, (k / n) as i64);
            let mut slope = 0.0_f64;
            let mut stopped = false;
            for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (ii, jj) = (i + di, j + dj);
                if ii < 0 || jj < 0 || ii >= n as i64 || jj >= n as i64 {
                    continue;
                }
                match excess(jj as usize * n + ii as usize) {
                    Some(en) => slope = slope.max((en - e).abs()),
                    None => stopped = true,
                }
            }
            stopped || e <= 2.0 * slope
        })
        .map(|(k, _)| k)
        .fold(Vec::<usize>::new(), |mut kept, k| {
            // One start per cluster: none within two cells of a nearer one.
            let near = |a: usize| (a % n).abs_diff(k % n) <= 2 && (a / n).abs_diff(k / n) <= 2;
            if kept.len() < ZOOM_STARTS && !kept.iter().any(|&a| near(a)) {
                kept.push(k);
            }
            kept
        })
        .into_iter()
        .map(|k| {
            [
                g.rect.x0 + g.rect.width() * (k % n) as f64 / d,
                g.rect.y0 + g.rect.height() * (k / n) as f64 / d,
            ]
        })
        .collect()
}

/// The entrance-plane positions of the passing vertices' bounding box.
fn passing_box(g: &GridTrace) -> Option<Rect> {
    let n = g.n;
    let d = (n - 1) as f64;
    Rect::bounding((0..n * n).filter(|&k| g.passes(k)).map(|k| {
        let (i, j) = (k % n, k / n);
        [
            g.rect.x0 + g.rect.width() * i as f64 / d,
            g.rect.y0 + g.rect.height() * j as f64 / d,
        ]
    }))
}

/// Width and height of one grid cell on the entrance plane.
fn cell_size(g: &GridTrace) -> (f64, f64) {
    let d = (g.n - 1) as f64;
    (g.rect.width() / d, g.rect.height() / d)
}

/// Vertices per side for rendering, from how unevenly the grid's cells land on the sensor: the
/// ratio of the 90th-percentile to the median cell area. A uniform ghost (ratio 1) gets
/// `MIN_GRID`; the grid grows with the square root of the ratio (cells shrink in both
/// directions), up to `MAX_GRID`.
pub fn grid_for_spread(g: &GridTrace) -> usize {
    let n = g.n;
    let mut areas: Vec<f64> = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = [
                j * n + i,
                j * n + i + 1,
                (j + 1) * n + i + 1,
                (j + 1) * n + i,
            ];
            if k.iter().all(|&v| g.passes(v)) {
                let p = k.map(|v| g.sensor[v].map(f64::from));
                areas.push(quad_area(p));
            }
        }
    }
    if areas.len() < 4 {
        return MIN_GRID;
    }
    areas.sort_by(f64::total_cmp);
    let median = areas[areas.len() / 2];
    let p90 = areas[areas.len() * 9 / 10];
    let spread = if median > 0.0 {
        p90 / median
    } else {
        MAX_GRID as f64
    };
    let by_spread = (MIN_GRID as f64 * spread.sqrt()).ceil() as usize;
    by_spread
        .max(grid_for_throughput(g))
        .max(grid_for_edges(g))
        .clamp(MIN_GRID, MAX_GRID)
}

/// Share of a ghost's traced weight in the cells its edge crosses (some corners passing,
/// some not) above which the grid is refined ([`grid_for_edges`]). A round ghost on the 33²
/// refine grid has about 0.08 (the Nikon zoom at 5°: 59 of its 61 ghosts above 1e-5 of the
/// direct image lie between 0.08 and 0.11); a thin ring or crescent has more, and a mesh
/// drawn at that grid loses the parts of its edge cells that pass (Nikon zoom 14-11 at 5°:
/// 0.24, drawn 2.7% dark at its 33² grid, 0.3% at 66²).
pub const MAX_EDGE_SHARE: f64 = 0.15;

/// The edge share a refined grid is sized to bring a ghost down to.
const EDGE_SHARE_TARGET: f64 = 0.12;

/// Vertices per side for a ghost whose edge cells carry more than [`MAX_EDGE_SHARE`] of its
/// traced weight on `g`: the grid scaled by that share over [`EDGE_SHARE_TARGET`] (the edge
/// cells' share falls as one over the grid's side); 0 otherwise.
pub fn grid_for_edges(g: &GridTrace) -> usize {
    let n = g.n;
    if n < 2 {
        return 0;
    }
    let (mut all, mut edge) = (0.0_f64, 0.0_f64);
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let quad = [
                j * n + i,
                j * n + i + 1,
                (j + 1) * n + i + 1,
                (j + 1) * n + i,
            ];
            let passing = quad.iter().filter(|&&k| g.passes(k)).count();
            let w: f64 = quad
                .iter()
                .filter(|&&k| g.passes(k))
                .map(|&k| f64::from(g.weight[k]))
                .sum();
            all += w;
            if passing > 0 && passing < 4 {
                edge += w;
            }
        }
    }
    if all <= 0.0 || edge / all <= MAX_EDGE_SHARE {
        return 0;
    }
    (n as f64 * edge / all / EDGE_SHARE_TARGET).ceil() as usize
}

/// Largest change of the throughput across one rendering cell the grid allows (relative to
/// the ghost's brightest vertex): the mesh shades linearly between vertices, and near total
/// internal reflection the throughput climbs from a few per cent to 1 within a fraction of a
/// millimetre of entrance height.
pub const MAX_CELL_THROUGHPUT_STEP: f64 = 0.05;

/// Vertices per side for the throughput to change by at most [`MAX_CELL_THROUGHPUT_STEP`] of
/// the brightest vertex's across a cell, on all but the steepest tenth of the grid's edges
/// between passing vertices (as [`grid_for_spread`] takes the 90th percentile of the cells'
/// areas: an aperture's rim or a single fold should not refine the whole ghost).
fn grid_for_throughput(g: &GridTrace) -> usize {
    let n = g.n;
    let peak = (0..n * n)
        .filter(|&k| g.passes(k))
        .map(|k| f64::from(g.weight[k]))
        .fold(0.0, f64::max);
    if peak <= 0.0 {
        return MIN_GRID;
    }
    let mut steps: Vec<f32> = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            if !g.passes(k) {
                continue;
            }
            for m in [(i + 1 < n).then_some(k + 1), (j + 1 < n).then_some(k + n)]
                .into_iter()
                .flatten()
            {
                if g.passes(m) {
                    steps.push((g.weight[k] - g.weight[m]).abs());
                }
            }
        }
    }
    if steps.len() < 4 {
        return MIN_GRID;
    }
    steps.sort_by(f32::total_cmp);
    let step = f64::from(steps[steps.len() * 9 / 10]);
    let cells = (n - 1) as f64 * step / peak / MAX_CELL_THROUGHPUT_STEP;
    cells.ceil() as usize + 1
}

/// |area| of a quadrilateral (shoelace).
fn quad_area(p: [[f64; 2]; 4]) -> f64 {
    let mut a = 0.0;
    for i in 0..4 {
        let (q, r) = (p[i], p[(i + 1) % 4]);
        a += q[0] * r[1] - r[0] * q[1];
    }
    0.5 * a.abs()
}

/// Approximate (paraxial) bounds of `path` at `theta`: each aperture met along the path
/// bounds the entrance height, `|A·y0 + B·tan θ| ≤ s`, and the width, `|A·x0| ≤ s`.
/// Energies are not traced here: `energy_share` is the product of the normal-incidence
/// factors along the path times the ratio of entrance areas.
pub fn approximate(
    system: &LensSystem,
    path: GhostPath,
    lambda_nm: f64,
    theta: f64,
) -> Option<GhostBounds> {
    let seq = Sequence::ghost_path(system, lambda_nm, &path).ok()?;
    let u = theta.tan();
    let steps = seq.steps.iter().map(|s| ParaxialStep {
        z: s.z,
        c: s.c,
        semi: s.semi,
        clips: s.inv_semi2 > 0.0,
        interaction: s.interaction,
        n_to: s.n_to,
    });
    let ParaxialPath {
        entrance,
        sensor_ab: (a_s, b_s),
    } = paraxial_path(steps, u)?;
    // Normal-incidence Fresnel/coating factor of each step.
    let factor: f64 = seq
        .steps
        .iter()
        .filter(|s| s.interaction != Interaction::Sensor)
        .map(|s| {
            let r = seq.reflectance(s, 1.0);
            if s.interaction == Interaction::Reflect {
                r
            } else {
                1.0 - r
            }
        })
        .product();
    let (ylo, yhi, xhalf) = (entrance.y0, entrance.y1, entrance.x1);
    let ys = [a_s * ylo + b_s * u, a_s * yhi + b_s * u];
    let xs = a_s.abs() * xhalf;
    let sensor = Rect {
        x0: -xs,
        y0: ys[0].min(ys[1]),
        x1: xs,
        y1: ys[0].max(ys[1]),
    };
    let pupil_area = {
        // The direct image's entrance pupil area at the d line, paraxially.
        let p = crate::paraxial::analyse(system, lambda_nm).ok()?;
        std::f64::consts::PI * (p.entrance_pupil_diameter_mm / 2.0).powi(2)
    };
    Some(GhostBounds {
        entrance,
        sensor,
        grid: 32,
        mean_intensity: factor,
        energy_share: factor * (std::f64::consts::FRAC_PI_4 * entrance.area()) / pupil_area,
    })
}

/// One step of a path as the paraxial bounds see it.
struct ParaxialStep {
    z: f64,
    c: f64,
    semi: f64,
    /// False where nothing clips (the sensor).
    clips: bool,
    interaction: Interaction,
    n_to: f64,
}

/// What [`paraxial_path`] finds: the entrance rectangle every aperture allows, and the
/// sensor's `(A, B)` of `y = A·y0 + B·tan θ`.
struct ParaxialPath {
    entrance: Rect,
    sensor_ab: (f64, f64),
}

/// The paraxial ray transfer along `steps` at slope `u = tan θ`: `y = A·y0 + B·u` and
/// `n·u' = C·y0 + D·u`, with the index signed by the travel direction; each aperture met
/// bounds the entrance height (`|A·y0 + B·u| ≤ semi`) and half-width (`|A·x0| ≤ semi`).
/// `None` when the intervals leave nothing.
fn paraxial_path(steps: impl Iterator<Item = ParaxialStep>, u: f64) -> Option<ParaxialPath> {
    let (mut a, mut b, mut c, mut d) = (1.0, 0.0, 0.0, 1.0);
    let mut n_signed = 1.0;
    let mut z_prev = 0.0;
    let (mut ylo, mut yhi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut xhalf = f64::INFINITY;
    let mut sensor_ab = (1.0, 0.0);
    for s in steps {
        let t = s.z - z_prev;
        a += t * c / n_signed;
        b += t * d / n_signed;
        z_prev = s.z;
        if s.clips {
            if a.abs() > 1e-12 {
                let (lo, hi) = ((-s.semi - b * u) / a, (s.semi - b * u) / a);
                ylo = ylo.max(lo.min(hi));
                yhi = yhi.min(lo.max(hi));
                xhalf = xhalf.min(s.semi / a.abs());
            } else if (b * u).abs() > s.semi {
                return None;
            }
        }
        let sign = if n_signed > 0.0 { 1.0 } else { -1.0 };
        let n_to = match s.interaction {
            Interaction::Refract => sign * s.n_to,
            Interaction::Reflect => -n_signed,
            Interaction::Sensor => {
                sensor_ab = (a, b);
                n_signed
            }
        };
        let power = s.c * (n_to - n_signed);
        c -= power * a;
        d -= power * b;
        n_signed = n_to;
    }
    if !(yhi > ylo && xhalf > 0.0 && xhalf.is_finite()) {
        return None;
    }
    Some(ParaxialPath {
        entrance: Rect {
            x0: -xhalf,
            y0: ylo,
            x1: xhalf,
            y1: yhi,
        },
        sensor_ab,
    })
}

/// The paraxial entrance rectangle of the f32 sequence the precise search traces
/// ([`paraxial_path`]).
fn paraxial_entrance(seq: &Sequence<f32>, theta: f64) -> Option<Rect> {
    let steps = seq.steps.iter().map(|s| ParaxialStep {
        z: f64::from(s.z),
        c: f64::from(s.c),
        semi: f64::from(s.semi),
        clips: s.inv_semi2 > 0.0,
        interaction: s.interaction,
        n_to: s.n_to,
    });
    paraxial_path(steps, theta.tan()).map(|p| p.entrance)
}
