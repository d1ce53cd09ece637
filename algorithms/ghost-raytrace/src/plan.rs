//! Planning: for each light, which ghosts to trace and at how many wavelengths — and what is
//! left out and how much energy that drops.
//!
//! A ghost is left out when its sensor bounds miss the frame, or when it is among the
//! dimmest on the frame that together carry at most the quality's budget of the ghosts'
//! energy ([`dim_threshold`]; a ghost's energy share is its flux over the on-axis direct image's,
//! from its bounds). With
//! [`ReflectionOrder::Four`] the four-reflection ghosts come too, but first each is checked
//! against an upper bound on its energy share (`FourReflectionBounds`: one grid traced per
//! three-reflection prefix, none per path): those whose bound is under the threshold are left
//! out before their own bounds are traced, reported with the bound as their energy share
//! ([`DropReason::Bound`]).
//!
//! Each ghost gets its own spectral sampling: `m` equal bins over 380–780 nm, each traced at
//! its centre in the colour of its whole bin, with `m` as small as keeps neighbouring bins
//! within half a drawn pixel of the ghost's (paraxial) dispersion and at most the plan's band
//! count. A ghost whose image moves less than half a pixel over the spectrum is traced once.

use flarebench_sdk::LensSystem;
use flarebench_sdk::color::SpectralSampling;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::bounds::{self, GhostBounds, MAX_GRID, MIN_GRID};
use flarebench_sdk::ghost::context::Band;
use flarebench_sdk::ghost::grid::trace_grid;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::ghost::{
    FourReflectionBounds, GhostPath, GridTrace, PointTrace, Rect, ReflectionOrder,
    enumerate_ghosts_of_order,
};
use flarebench_sdk::paraxial::stop_opening;
use flarebench_sdk::trace::InterfaceTableSet;
use std::borrow::Cow;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use rayon::prelude::*;
use serde::Serialize;

use crate::GhostRenderError;
use crate::colour::{Bin, GhostColours, SHAPE_NODES_NM, SpectralShape};
use crate::method;
pub use crate::method::{DrawMethod, MethodPrediction};
use crate::scene::{LightSpec, Quality};

/// Wavelength at which bounds and energies are found (nm).
pub const BOUNDS_LAMBDA_NM: f64 = 550.0;

/// What a light needs.
#[derive(Clone, Debug)]
pub struct LightPlan {
    pub light: LightSpec,
    /// Every wavelength some ghost is traced at (the bins of the light's spectral sampling
    /// and of the coarser ones ghosts take, [`GhostJob::bands`]), with its interface tables.
    /// Their `rgb` is zero: a ghost's colour at each band is its [`GhostBand::rgb`].
    pub bands: Vec<Band>,
    /// Bands of the light's own spectral sampling (the plan's band count).
    pub sampled: usize,
    pub ghosts: Vec<GhostJob>,
    pub dropped: Vec<DroppedGhost>,
    /// The reflection order planned for.
    pub reflections: ReflectionOrder,
    /// With a precomputed table: the ghosts it does not hold (an OpenLensFlare file's ghosts
    /// that straddle the stop, four-reflection ghosts of a table made without them), whose
    /// bounds were traced for this light as without a table. Empty without a table.
    pub not_in_table: Vec<GhostPath>,
    /// The share of the frame's ghost energy the plan left out as too dim: the on-frame
    /// energy ([`on_frame_share`]) of the ghosts dropped as [`DropReason::Dim`] and
    /// [`DropReason::Bound`], over that of every ghost that reaches the frame. What the image
    /// loses by culling; ghosts off the frame or without light take nothing from it.
    pub culled_share: f64,
}

/// Each drawn ghost's entrance rectangle in one light's plan: where the next plan of that light
/// may start its searches ([`PlanOptions::warm_start`]).
#[derive(Clone, Debug, Default)]
pub struct WarmStart {
    entrance: HashMap<GhostPath, Rect>,
}

impl WarmStart {
    /// The rectangles of `plan`'s drawn ghosts.
    pub fn of(plan: &LightPlan) -> WarmStart {
        WarmStart {
            entrance: plan
                .ghosts
                .iter()
                .map(|g| (g.path, g.bounds.entrance))
                .collect(),
        }
    }
}

/// A ghost to render.
#[derive(Clone, Debug, Serialize)]
pub struct GhostJob {
    pub path: GhostPath,
    #[serde(skip)]
    pub bounds: GhostBounds,
    /// Grid vertices per side.
    pub grid: usize,
    /// The ghost is drawn into a coarse copy of the frame with this many pixels a side per
    /// coarse pixel (a power of two; 1 = full resolution): see [`coarse_factor`].
    pub downscale: usize,
    /// The wavelengths the ghost is traced at: the `m` equal bins of its own spectral
    /// sampling (`m` up to the plan's band count, as many as keep neighbouring bins within
    /// half a drawn pixel of dispersion), each traced at its centre in the colour of its
    /// whole bin ([`GhostColours::bin_colour`]).
    pub bands: Vec<GhostBand>,
    pub energy_share: f64,
    /// How the ghost is drawn ([`crate::method`]), and what the plan predicted of each way.
    pub method: DrawMethod,
    pub prediction: MethodPrediction,
}

/// One traced wavelength of a ghost.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct GhostBand {
    /// Index into [`LightPlan::bands`] of the band traced (its wavelength and tables).
    pub band: usize,
    /// The colour it adds: the ghost's colour over the bands it stands for
    /// ([`GhostColours::group_colour`]).
    pub rgb: [f32; 3],
}

impl GhostJob {
    /// True when traced at more than one wavelength.
    pub fn spectral(&self) -> bool {
        self.bands.len() > 1
    }
}

/// Why a ghost was left out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DropReason {
    /// No ray of the ghost reaches the sensor at this angle.
    NoLight,
    /// Energy share under the threshold.
    Dim,
    /// Sensor bounds outside the frame.
    OffFrame,
    /// A four-reflection ghost whose energy bound (`FourReflectionBounds`, found before its
    /// own bounds are traced) is under the threshold; its `energy_share` is that bound, not a
    /// traced energy.
    Bound,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct DroppedGhost {
    pub path: GhostPath,
    pub reason: DropReason,
    pub energy_share: f64,
}

impl LightPlan {
    /// Energy share of all ghosts (relative to the on-axis direct image) and the part of it
    /// left out.
    pub fn energy(&self) -> (f64, f64) {
        let kept: f64 = self.ghosts.iter().map(|g| g.energy_share).sum();
        let dropped: f64 = self.dropped.iter().map(|d| d.energy_share).sum();
        (kept + dropped, dropped)
    }

    /// The four-reflection ghosts' part of the plan (all zero for two-reflection plans).
    pub fn four_reflection_summary(&self) -> FourReflectionSummary {
        let mut s = FourReflectionSummary::default();
        for g in self.ghosts.iter().filter(|g| g.path.is_four()) {
            s.traced += 1;
            s.traced_energy_share += g.energy_share;
        }
        for d in self.dropped.iter().filter(|d| d.path.is_four()) {
            if d.reason == DropReason::Bound {
                s.bounded_out += 1;
                s.bounded_out_energy_share += d.energy_share;
            } else {
                s.dropped_after_bounds += 1;
                s.dropped_energy_share += d.energy_share;
            }
        }
        s.paths = s.traced + s.bounded_out + s.dropped_after_bounds;
        s
    }
}

/// What became of a light's four-reflection ghosts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FourReflectionSummary {
    /// Four-reflection paths enumerated.
    pub paths: usize,
    /// Left out before tracing by the energy bound ([`DropReason::Bound`]), and the sum of
    /// their bounds (an upper bound on the energy they carry).
    pub bounded_out: usize,
    pub bounded_out_energy_share: f64,
    /// Survived the bound, had their bounds found, then were left out (no light, too dim, off
    /// the frame), and their energy share.
    pub dropped_after_bounds: usize,
    pub dropped_energy_share: f64,
    /// Rendered, and their energy share.
    pub traced: usize,
    pub traced_energy_share: f64,
}

/// How to plan: quality, bands, culling, grid scale and where bounds come from.
#[derive(Clone, Copy, Debug)]
pub struct PlanOptions<'a> {
    pub quality: Quality,
    /// The most bands a ghost is traced at (and the light's own spectral sampling).
    pub bands: usize,
    /// The fewest bands a ghost is traced at, however small its dispersion (1 for the
    /// presets; the reference's `REFERENCE_MIN_BANDS`).
    pub min_bands: usize,
    /// Neighbouring bands of a ghost move it by at most this many drawn pixels (paraxially):
    /// a ghost takes the fewest bands that keep them so, between `min_bands` and `bands`
    /// ([`BAND_SPACING_PX`] for the presets; the reference an eighth of a pixel).
    pub band_spacing_px: f64,
    /// False keeps every ghost that has light (the reference renderer).
    pub cull: bool,
    /// The share of the ghosts' energy on the frame that culling may leave out, dimmest ghost
    /// first ([`dim_threshold`]; the preset's [`Quality::dim_budget`]).
    pub dim_budget: f64,
    /// Multiplies each ghost's grid.
    pub grid_scale: f64,
    /// Multiplies, with `grid_scale`, the grid of a smooth ghost: one whose bounds' grid is at
    /// most [`SMOOTH_GRID`] (`Quality::smooth_grid_scale`; 1 for the reference).
    pub smooth_grid_scale: f64,
    /// Precomputed bounds (`flarebench precompute`, or an OpenLensFlare file converted by
    /// `BoundsTable::from_olf`); without them, bounds are traced for each light's angle. A
    /// ghost the table does not hold has its bounds traced ([`LightPlan::not_in_table`]); a
    /// light outside the table's angles is an error.
    pub precomputed: Option<&'a BoundsTable>,
    /// Build every band's interface tables at its own wavelength (the reference), rather than
    /// interpolate them between tables every [`TABLE_STEP_NM`].
    pub exact_tables: bool,
    /// Largest coarse-frame factor a ghost may be drawn at (1: every ghost at full
    /// resolution, as the reference does).
    pub max_downscale: usize,
    /// Coarse pixels a ghost's radius must span when it is drawn into a coarse frame
    /// ([`coarse_factor`]; the preset's [`Quality::coarse_pixels_per_radius`]).
    pub coarse_pixels_per_radius: f64,
    /// A ghost whose dispersion asks for fewer bands than `bands`, and that carries at least
    /// [`SHAPE_MIN_SHARE`] of the drawn ghosts' light on the frame, has its flux measured at
    /// [`SHAPE_NODES_NM`] ([`SHAPE_GRID`]² rays over its entrance rectangle each) and takes
    /// at least the fewest bands whose colour error from the flux's spectral variation is
    /// within this ([`GhostColours::bins_for`]; the preset's [`Quality::spectral_tolerance`];
    /// infinite: bands by dispersion alone).
    pub spectral_tolerance: f64,
    /// Two-reflection ghosts only (the default), or four-reflection ghosts too. A precomputed
    /// table without some four-reflection ghost that survives the energy bound is not an
    /// error: that ghost's bounds are traced for the light, as without a table.
    pub reflections: ReflectionOrder,
    /// The lens's interface tables every [`TABLE_STEP_NM`], built once per lens
    /// ([`LensTables::new`]; a plugin does it when the lens is prepared): the plan then
    /// interpolates between them instead of building them, and keeps each band's tables for
    /// the next plans. Tables of another lens are ignored. The plan is the same with or
    /// without them, bit for bit: a plan of fewer bands than tables every [`TABLE_STEP_NM`]
    /// builds each band's tables exactly either way (and the lens keeps those too).
    pub lens_tables: Option<&'a LensTables>,
    /// The plans of a nearby frame — the same lights on the lens before a small edit, or the
    /// lights a little moved —, light by light: a ghost traced here starts its search from
    /// its entrance rectangle there (`bounds::precise_from`: one grid over that rectangle
    /// widened by a quarter, instead of a search and a refinement over the whole front
    /// element; the full search runs where the ghost is not found inside it with room to
    /// spare). Bounds looked up in `precomputed` do not use it.
    pub warm_start: Option<&'a [WarmStart]>,
    /// Draw every ghost this way rather than each by the cheapest that keeps the frame within
    /// `method_error_budget` ([`crate::method::choose`]).
    pub method: Option<DrawMethod>,
    /// The relative RMSE the choice of methods may add to the frame, in quadrature (the
    /// preset's [`Quality::method_error_budget`]).
    pub method_error_budget: f64,
}

impl<'a> PlanOptions<'a> {
    /// The preset's bands, grid scale and culling, with bounds from `precomputed` if given.
    pub fn for_quality(quality: Quality, precomputed: Option<&'a BoundsTable>) -> Self {
        PlanOptions {
            quality,
            bands: quality.bands(),
            min_bands: 1,
            band_spacing_px: BAND_SPACING_PX,
            cull: true,
            dim_budget: quality.dim_budget(),
            grid_scale: quality.grid_scale(),
            smooth_grid_scale: quality.smooth_grid_scale(),
            precomputed,
            exact_tables: false,
            max_downscale: quality.max_downscale(),
            coarse_pixels_per_radius: quality.coarse_pixels_per_radius(),
            spectral_tolerance: quality.spectral_tolerance(),
            reflections: ReflectionOrder::Two,
            lens_tables: None,
            warm_start: None,
            method: None,
            method_error_budget: quality.method_error_budget(),
        }
    }
}

/// Plans every light of a scene.
pub fn plan(
    system: &LensSystem,
    lights: &[LightSpec],
    frame: &Frame,
    opts: &PlanOptions<'_>,
) -> Result<Vec<LightPlan>, GhostRenderError> {
    let planner = Planner::new(system, frame, opts);
    lights
        .iter()
        .enumerate()
        .map(|(i, light)| planner.light(light, opts.warm_start.and_then(|w| w.get(i))))
        .collect()
}

/// What the plans of a scene's lights share: the lens, frame and options, the ghost paths, the
/// tables bounds are traced with and the reference flux.
struct Planner<'p, 'o> {
    system: &'p LensSystem,
    frame: &'p Frame,
    opts: &'p PlanOptions<'o>,
    paths: Vec<GhostPath>,
    /// The tables the plan traces bounds with, built only when something is traced (a frame
    /// whose every ghost is looked up in a table needs none).
    bounds_tables: OnceLock<InterfaceTableSet>,
    /// The tables at [`SHAPE_NODES_NM`] (the lens's held ones when given), built when a
    /// ghost's spectral shape is first measured.
    shape_tables: OnceLock<Vec<Cow<'o, InterfaceTableSet>>>,
    /// The flux energy shares are measured against (the on-axis direct image's): for traced
    /// energies, and for the four-reflection bound; the same for every light.
    reference: Option<f64>,
}

/// A ghost path with its bounds (`None`: no light).
type Found = (GhostPath, Option<GhostBounds>);

/// One light as its ghosts are planned: its direction (radians), its band range (nm) and the
/// ghosts' colours.
struct LightJob {
    theta: f64,
    phi: f64,
    lo: f64,
    hi: f64,
    colours: GhostColours,
}

/// The bins a light's ghosts are traced at, each once: `(m, i)` → index into `bins` (and then
/// the plan's bands) of bin i of an m-band sampling.
#[derive(Default)]
struct Bins {
    bins: Vec<Bin>,
    index: HashMap<(usize, usize), usize>,
}

impl Bins {
    /// The band of bin `i` of an `m`-band sampling, made the first time it is asked for.
    fn band(&mut self, system: &LensSystem, m: usize, i: usize) -> usize {
        *self.index.entry((m, i)).or_insert_with(|| {
            self.bins.push(Bin::new(system, m, i));
            self.bins.len() - 1
        })
    }
}

impl<'p, 'o> Planner<'p, 'o> {
    fn new(system: &'p LensSystem, frame: &'p Frame, opts: &'p PlanOptions<'o>) -> Self {
        let paths = enumerate_ghosts_of_order(system, opts.reflections);
        let mut planner = Planner {
            system,
            frame,
            opts,
            paths,
            bounds_tables: OnceLock::new(),
            shape_tables: OnceLock::new(),
            reference: None,
        };
        let four = opts.reflections == ReflectionOrder::Four;
        // A table lacking some ghost: its bounds are traced, which needs the reference flux.
        let table_lacks = opts
            .precomputed
            .is_some_and(|t| planner.paths.iter().any(|p| t.ghost_index(*p).is_none()));
        let reference = (opts.precomputed.is_none() || four || table_lacks)
            .then(|| bounds::reference_flux(system, planner.tables(), &mut GridTrace::default()));
        planner.reference = reference;
        planner
    }

    fn shape_tables(&self) -> &[Cow<'o, InterfaceTableSet>] {
        self.shape_tables.get_or_init(|| {
            let held = self.opts.lens_tables.filter(|l| l.is_for(self.system));
            SHAPE_NODES_NM
                .par_iter()
                .map(|&nm| {
                    held.and_then(|l| l.node(nm)).map_or_else(
                        || Cow::Owned(InterfaceTableSet::for_system(self.system, nm)),
                        Cow::Borrowed,
                    )
                })
                .collect()
        })
    }

    /// `path`'s flux over its entrance rectangle at each of [`SHAPE_NODES_NM`] (its spectral
    /// shape), or `None` where it is dark at one of them.
    fn spectral_shape(
        &self,
        path: GhostPath,
        b: &GhostBounds,
        job: &LightJob,
    ) -> Option<SpectralShape> {
        let stop = stop_opening(self.system);
        let mut grid = GridTrace::default();
        let mut flux = [0.0; SHAPE_NODES_NM.len()];
        for (f, tables) in flux.iter_mut().zip(self.shape_tables()) {
            let seq = bounds::ghost_sequence(self.system, path, tables)?;
            trace_grid(&seq, job.theta, b.entrance, SHAPE_GRID, stop, &mut grid);
            *f = bounds::clipped_flux(&grid, job.theta);
        }
        job.colours.shape(path, flux)
    }

    fn tables(&self) -> &InterfaceTableSet {
        self.bounds_tables
            .get_or_init(|| InterfaceTableSet::for_system(self.system, BOUNDS_LAMBDA_NM))
    }

    /// One light's plan; `warm`: its ghosts' rectangles in a nearby frame
    /// (`PlanOptions::warm_start`).
    fn light(
        &self,
        light: &LightSpec,
        warm: Option<&WarmStart>,
    ) -> Result<LightPlan, GhostRenderError> {
        let (system, opts) = (self.system, self.opts);
        let sampling = SpectralSampling::new(opts.bands, light.spectrum)?;
        let job = LightJob {
            colours: GhostColours::new(system, light.spectrum, light.intensity as f32)?,
            theta: light.theta_deg.to_radians(),
            phi: light.phi_deg.to_radians(),
            lo: sampling.wavelengths_nm()[0],
            hi: sampling.wavelengths_nm()[opts.bands - 1],
        };
        let (candidates, bounded_out) = self.bound_four(job.theta);
        let (found, not_in_table) = self.find_bounds(light, job.theta, &candidates, warm)?;
        let on_frame = |b: &GhostBounds| overlaps_frame(&b.sensor.rotated(job.phi), self.frame);
        let visible = |b: &GhostBounds| on_frame_share(b, job.phi, self.frame);
        let dim_below = if opts.cull {
            dim_threshold(
                found
                    .iter()
                    .filter_map(|(_, b)| b.as_ref().filter(|b| on_frame(b)))
                    .map(visible),
                opts.dim_budget,
            )
        } else {
            0.0
        };
        let (mut kept_visible, mut culled_visible) = (0.0, 0.0);
        let mut bins = Bins::default();
        let mut ghosts = Vec::new();
        let mut kept = Vec::new();
        let mut dropped = Vec::new();
        for (path, b) in found {
            let Some(b) = b else {
                dropped.push(DroppedGhost {
                    path,
                    reason: DropReason::NoLight,
                    energy_share: 0.0,
                });
                continue;
            };
            let drop = |reason| DroppedGhost {
                path,
                reason,
                energy_share: b.energy_share,
            };
            if opts.cull && !on_frame(&b) {
                dropped.push(drop(DropReason::OffFrame));
                continue;
            }
            let share = visible(&b);
            if opts.cull && share < dim_below {
                culled_visible += share;
                dropped.push(drop(DropReason::Dim));
                continue;
            }
            kept_visible += share;
            kept.push((path, b, share));
        }
        // Each kept ghost's bands by dispersion, raised where its spectral shape asks for
        // more: measured (in parallel, 1.5 k rays a ghost) for the ghosts that carry at least
        // SHAPE_MIN_SHARE of the kept ghosts' light on the frame.
        let bands: Vec<usize> = kept
            .par_iter()
            .map(|(path, b, share)| {
                let measure = *share >= SHAPE_MIN_SHARE * kept_visible;
                self.bands_for(*path, b, &job, measure)
            })
            .collect();
        // Each ghost's bands: bins of its own sampling, each traced once per light.
        let ghost_bins: Vec<Vec<usize>> = bands
            .iter()
            .map(|&m| (0..m).map(|i| bins.band(system, m, i)).collect())
            .collect();
        let plan_bands = band_tables(system, &bins.bins, opts.exact_tables, opts.lens_tables);
        // A spectral ghost's rectangles hold its region at its first and last band, not only
        // at the wavelength its bounds were found at.
        let widened: Vec<GhostBounds> = kept
            .par_iter()
            .zip(&ghost_bins)
            .map_init(
                || (GridTrace::default(), PointTrace::default()),
                |(scratch, probe), ((path, b, _), own)| {
                    let ends = match own.as_slice() {
                        [first, .., last] => [*first, *last],
                        _ => return *b,
                    };
                    ends.iter().fold(*b, |b, &band| {
                        bounds::ghost_sequence(system, *path, &plan_bands[band].tables)
                            .map_or(b, |seq| {
                                bounds::widened_for(system, &seq, job.theta, &b, scratch, probe)
                            })
                    })
                },
            )
            .collect();
        let shares: Vec<f64> = kept.iter().map(|k| k.2).collect();
        for (((path, _, _), b), own) in kept.into_iter().zip(widened).zip(ghost_bins) {
            ghosts.push(self.ghost_job(path, b, &own, &job, &bins));
        }
        self.choose_methods(&mut ghosts, &shares);
        // A four-reflection ghost's bound is all its energy might be, on the frame or not.
        culled_visible += bounded_out.iter().map(|d| d.energy_share).sum::<f64>();
        let seen = kept_visible + culled_visible;
        dropped.extend(bounded_out);
        Ok(LightPlan {
            light: light.clone(),
            bands: plan_bands,
            sampled: opts.bands,
            ghosts,
            dropped,
            reflections: opts.reflections,
            not_in_table,
            culled_share: if seen > 0.0 {
                culled_visible / seen
            } else {
                0.0
            },
        })
    }

    /// The paths whose bounds are found for a light at `theta` (radians): all of them, but for
    /// four-reflection ghosts when culling, those whose energy bound is under the threshold are
    /// left out here (returned as dropped), before anything of theirs is traced or looked up.
    fn bound_four(&self, theta: f64) -> (Vec<GhostPath>, Vec<DroppedGhost>) {
        let mut bounded_out = Vec::new();
        let four = self.opts.reflections == ReflectionOrder::Four;
        let candidates = match self.reference {
            Some(reference) if four && self.opts.cull => {
                let refl =
                    FourReflectionBounds::compute(self.system, self.tables(), theta, reference);
                let threshold = self.opts.quality.energy_threshold();
                self.paths
                    .iter()
                    .copied()
                    .filter(|p| {
                        if !p.is_four() {
                            return true;
                        }
                        // Every four-reflection path of the lens has a bound.
                        let bound = refl.get(p).unwrap_or(f64::INFINITY);
                        let keep = bound >= threshold;
                        if !keep {
                            bounded_out.push(DroppedGhost {
                                path: *p,
                                reason: DropReason::Bound,
                                energy_share: bound,
                            });
                        }
                        keep
                    })
                    .collect()
            }
            _ => self.paths.clone(),
        };
        (candidates, bounded_out)
    }

    /// Each candidate's bounds (`None`: no light), looked up in the precomputed table or
    /// traced, and the candidates the table lacks; a light outside the table's angles is an
    /// error.
    fn find_bounds(
        &self,
        light: &LightSpec,
        theta: f64,
        candidates: &[GhostPath],
        warm: Option<&WarmStart>,
    ) -> Result<(Vec<Found>, Vec<GhostPath>), GhostRenderError> {
        let system = self.system;
        let Some(table) = self.opts.precomputed else {
            let reference = self.reference.unwrap_or_default();
            let start = |path: GhostPath| warm?.entrance.get(&path).copied();
            let found = candidates
                .par_iter()
                .map_init(GridTrace::default, |scratch, &path| {
                    let b = bounds::ghost_sequence(system, path, self.tables()).and_then(|seq| {
                        bounds::precise_from(system, &seq, theta, reference, start(path), scratch)
                    });
                    (path, b)
                })
                .collect();
            return Ok((found, Vec::new()));
        };
        let min = table.angles_deg.first().copied().unwrap_or(0.0);
        let max = table.angles_deg.last().copied().unwrap_or(0.0);
        if !(light.theta_deg >= min && light.theta_deg <= max) {
            return Err(GhostRenderError::OutsideTable {
                theta_deg: light.theta_deg,
                min_deg: min,
                max_deg: max,
            });
        }
        // A ghost missing from the table (a four-reflection ghost of a table made without them
        // or with a higher bound threshold; a ghost straddling the stop in an OpenLensFlare
        // file) is traced, as without a table.
        let not_in_table = candidates
            .iter()
            .copied()
            .filter(|&p| table.ghost_index(p).is_none())
            .collect();
        let found = candidates
            .par_iter()
            .map_init(GridTrace::default, |scratch, &p| {
                let b = match (table.ghost_index(p), self.reference) {
                    (Some(g), _) => table.lookup(g, light.theta_deg),
                    (None, Some(reference)) => {
                        bounds::precise(system, p, self.tables(), theta, reference, scratch)
                    }
                    // `reference` is traced whenever the table lacks a ghost.
                    (None, None) => None,
                };
                (p, b)
            })
            .collect();
        Ok((found, not_in_table))
    }

    /// Each ghost's method ([`crate::method`]): predicted from its triangles and drawn
    /// rectangle, and its on-frame energy `shares` for its part of the frame's signal; chosen
    /// within the error budget, or the one [`PlanOptions::method`] forces.
    fn choose_methods(&self, ghosts: &mut [GhostJob], shares: &[f64]) {
        let px = self.frame.pixel_mm();
        let full_px = |g: &GhostJob| g.bounds.sensor.area() / (px * px);
        let signal: Vec<f64> = ghosts
            .iter()
            .zip(shares)
            .map(|(g, &e)| method::signal2(e, full_px(g)))
            .collect();
        let total: f64 = signal.iter().sum();
        for (g, s) in ghosts.iter_mut().zip(&signal) {
            let d = g.downscale.max(1) as f64;
            let triangles = 2.0 * ((g.grid.max(2) - 1) as f64).powi(2);
            let share = if total > 0.0 { s / total } else { 0.0 };
            g.prediction = method::predict(triangles, g.bands.len(), full_px(g) / (d * d), share);
        }
        let methods = match self.opts.method {
            Some(m) => vec![m; ghosts.len()],
            None => {
                let predictions: Vec<MethodPrediction> =
                    ghosts.iter().map(|g| g.prediction).collect();
                method::choose(&predictions, self.opts.method_error_budget)
            }
        };
        for (g, m) in ghosts.iter_mut().zip(methods) {
            g.method = m;
        }
    }

    /// A kept ghost's grid and coarse factor.
    fn grid_and_downscale(&self, b: &GhostBounds) -> (usize, usize) {
        let opts = self.opts;
        let cap = (MAX_GRID as f64 * opts.grid_scale.max(1.0)).ceil() as usize;
        let scale = if b.grid <= SMOOTH_GRID {
            opts.grid_scale * opts.smooth_grid_scale
        } else {
            opts.grid_scale
        };
        let grid = ((b.grid as f64 * scale).round() as usize).clamp(MIN_GRID / 2, cap);
        let downscale = coarse_factor(
            &b.sensor,
            grid,
            self.frame,
            opts.max_downscale,
            opts.coarse_pixels_per_radius,
        );
        (grid, downscale)
    }

    /// How many bands a kept ghost is traced at: enough that neighbouring ones move it by at
    /// most the band spacing (m bands over a dispersion of D drawn pixels step D/(m − 1)),
    /// and, with `measure`, enough that its colour stays within the spectral tolerance.
    fn bands_for(&self, path: GhostPath, b: &GhostBounds, job: &LightJob, measure: bool) -> usize {
        let (system, opts) = (self.system, self.opts);
        let (_, downscale) = self.grid_and_downscale(b);
        let d =
            dispersion_px(system, path, job.theta, job.lo, job.hi, self.frame) / downscale as f64;
        let m = if d.is_finite() {
            ((d / opts.band_spacing_px).ceil() as usize).saturating_add(1)
        } else {
            opts.bands
        };
        let m = m.min(opts.bands).max(opts.min_bands.min(opts.bands)).max(1);
        if !measure || m >= opts.bands || !opts.spectral_tolerance.is_finite() {
            return m;
        }
        match self.spectral_shape(path, b, job) {
            Some(shape) => {
                job.colours
                    .bins_for(path, &shape, m, opts.bands, opts.spectral_tolerance)
            }
            None => m,
        }
    }

    /// A kept ghost's job: its grid, coarse factor, its bands (`own`: indices into `bins`,
    /// the bins of its own sampling) and their colours.
    fn ghost_job(
        &self,
        path: GhostPath,
        b: GhostBounds,
        own: &[usize],
        job: &LightJob,
        bins: &Bins,
    ) -> GhostJob {
        let (grid, downscale) = self.grid_and_downscale(&b);
        // The ghost's own sampling: equal bins, each traced at its centre in the colour of its
        // whole bin. (Grouping the light's bands unevenly instead — 31 into 16, say — draws
        // copies of uneven weight and spacing.)
        let ghost_bands = own
            .iter()
            .map(|&band| GhostBand {
                band,
                rgb: job.colours.bin_colour(path, &bins.bins[band]),
            })
            .collect();
        GhostJob {
            path,
            bounds: b,
            grid,
            downscale,
            bands: ghost_bands,
            energy_share: b.energy_share,
            method: DrawMethod::Mesh,
            prediction: MethodPrediction::default(),
        }
    }
}

/// Drawn pixels by which neighbouring bands of a ghost may move it (paraxially), for the
/// presets: at half a pixel the copies blend under the one-pixel feather of its edge.
pub const BAND_SPACING_PX: f64 = 0.5;

/// Rays a side of the grid a ghost's flux is measured on at each of [`SHAPE_NODES_NM`] for
/// its spectral shape ([`PlanOptions::spectral_tolerance`]): only the flux's variation with
/// the wavelength counts, and the same grid at every node keeps the sampling error common.
pub const SHAPE_GRID: usize = 13;

/// The share of a frame's drawn ghost light (on the frame) from which a ghost's spectral
/// shape is measured ([`PlanOptions::spectral_tolerance`]): a dimmer ghost's colour error
/// moves the frame's light by less than this times its own error.
pub const SHAPE_MIN_SHARE: f64 = 5e-3;

/// Wavelength step (nm) of the interface tables a plan builds exactly: a band between two
/// of them takes their interpolation (`InterfaceTableSet::between`: linear, with the entries
/// near a critical angle and stacks of layers evaluated exactly), so a frame builds at most
/// 41 sets of tables over 380–780 nm however many bands its ghosts take (the Nikon zoom's
/// ghosts take up to 31 bands each, about 500 distinct wavelengths in all). Measured at 10°,
/// 30° (1920 × 1080 Heliar, 960 × 540 Nikon zoom, default quality): the error against the
/// reference moved from 1.844% to 1.839% (Heliar) and 2.009% to 2.011% (Nikon), the energy
/// by +0.04 and +0.05 points.
pub const TABLE_STEP_NM: f64 = 10.0;

/// A lens's interface tables every [`TABLE_STEP_NM`] over 380–780 nm: what a plan
/// interpolates its bands' tables between ([`PlanOptions::lens_tables`]); and the tables of
/// every band a plan has needed so far, interpolated or (for a plan of few bands) exact, kept
/// for the next frames' plans (a ghost's bands are the centres of `m` equal bins, so a lens's
/// frames use a few hundred at most).
#[derive(Debug)]
pub struct LensTables {
    system: LensSystem,
    nodes: Vec<InterfaceTableSet>,
    /// Band tables by their wavelength's bits and whether they are exact.
    bands: Mutex<HashMap<(u64, bool), Arc<InterfaceTableSet>>>,
}

impl LensTables {
    /// First and last wavelengths tabulated (nm): every band centre lies between them.
    const RANGE_NM: [f64; 2] = [380.0, 780.0];

    /// Most bands whose tables are kept: twice the 496 centres of every sampling of 1 to 31
    /// bins (a plan asked for more bands computes the rest each time rather than holding
    /// tables without bound). A band's tables take 8 KB per boundary: about 170 KB for the
    /// Nikon zoom's 21, so at most about 170 MB.
    const MAX_HELD_BANDS: usize = 1024;

    /// The tables of `system` (built in parallel).
    pub fn new(system: &LensSystem) -> Self {
        let [lo, hi] = Self::RANGE_NM;
        let count = ((hi - lo) / TABLE_STEP_NM).round() as usize + 1;
        LensTables {
            system: system.clone(),
            nodes: tables_every_step(system, lo, count),
            bands: Mutex::new(HashMap::new()),
        }
    }

    /// The tables at `lambda_nm`, built once and kept: with `exact`, built at that wavelength
    /// (`InterfaceTableSet::for_system`), else interpolated between the two held around it.
    /// `None` outside the held range.
    fn band(&self, lambda_nm: f64, exact: bool) -> Option<Arc<InterfaceTableSet>> {
        let key = (lambda_nm.to_bits(), exact);
        if let Some(t) = self.bands.lock().ok()?.get(&key) {
            return Some(Arc::clone(t));
        }
        let i = bracket(lambda_nm, Self::RANGE_NM[0] / TABLE_STEP_NM)?;
        let (a, b) = (self.nodes.get(i)?, self.nodes.get(i + 1)?);
        let t = Arc::new(if exact {
            InterfaceTableSet::for_system(&self.system, lambda_nm)
        } else {
            InterfaceTableSet::between(&self.system, lambda_nm, a, b)
        });
        // Built outside the lock; another thread building the same band builds the same.
        let mut held = self.bands.lock().ok()?;
        if held.len() >= Self::MAX_HELD_BANDS {
            return Some(t);
        }
        Some(Arc::clone(held.entry(key).or_insert(t)))
    }

    /// The held tables at `lambda_nm` when it is one of the steps (exact there).
    fn node(&self, lambda_nm: f64) -> Option<&InterfaceTableSet> {
        let k = (lambda_nm - Self::RANGE_NM[0]) / TABLE_STEP_NM;
        if (k - k.round()).abs() > 1e-9 {
            return None;
        }
        self.nodes.get(k.round() as usize)
    }

    /// True when these are `system`'s tables.
    pub fn is_for(&self, system: &LensSystem) -> bool {
        self.system == *system
    }
}

/// `count` sets of `system`'s interface tables every [`TABLE_STEP_NM`] from `first_nm`,
/// built in parallel.
fn tables_every_step(system: &LensSystem, first_nm: f64, count: usize) -> Vec<InterfaceTableSet> {
    (0..count)
        .into_par_iter()
        .map(|k| InterfaceTableSet::for_system(system, first_nm + k as f64 * TABLE_STEP_NM))
        .collect()
}

/// Each bin's band (its centre wavelength and interface tables; colour zero): with `exact`
/// (the reference), tables built at every centre; otherwise, when there are no more bins
/// than tables every [`TABLE_STEP_NM`] over their range, built at every centre, and else
/// interpolated between those (`InterfaceTableSet::between`, from the table at or below the
/// centre and the next). With `lens` (this system's; not for the reference), the same tables
/// come from it, built once per lens and wavelength ([`LensTables`]). Built in parallel.
fn band_tables(
    system: &LensSystem,
    bins: &[Bin],
    exact: bool,
    lens: Option<&LensTables>,
) -> Vec<Band> {
    let (lo, hi) = bins.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), b| {
        (lo.min(b.centre_nm), hi.max(b.centre_nm))
    });
    let first = (lo / TABLE_STEP_NM).floor();
    // Every centre between the tables at its own step and the next.
    let count = ((hi / TABLE_STEP_NM).floor() - first).max(0.0) as usize + 2;
    // Fewer bands than tables to interpolate between: each built exactly, for less.
    let each_exact = bins.len() <= count;
    if !exact && let Some(lens) = lens.filter(|l| l.is_for(system)) {
        let held: Option<Vec<Band>> = bins
            .par_iter()
            .map(|b| {
                lens.band(b.centre_nm, each_exact).map(|tables| Band {
                    lambda_nm: b.centre_nm,
                    rgb: [0.0; 3],
                    tables,
                })
            })
            .collect();
        if let Some(bands) = held {
            return bands;
        }
    }
    if exact || each_exact {
        return bins
            .par_iter()
            .map(|b| Band::new(system, b.centre_nm, [0.0; 3]))
            .collect();
    }
    let nodes = tables_every_step(system, first * TABLE_STEP_NM, count);
    bins.par_iter()
        .map(|b| {
            let i = bracket(b.centre_nm, first).unwrap_or(0).min(count - 2);
            Band {
                lambda_nm: b.centre_nm,
                rgb: [0.0; 3],
                tables: Arc::new(InterfaceTableSet::between(
                    system,
                    b.centre_nm,
                    &nodes[i],
                    &nodes[i + 1],
                )),
            }
        })
        .collect()
}

/// Index of the table every [`TABLE_STEP_NM`] at or below `lambda_nm`, counted from the
/// one at `first` steps: the tables a band is interpolated between are it and the next.
fn bracket(lambda_nm: f64, first: f64) -> Option<usize> {
    let k = (lambda_nm / TABLE_STEP_NM).floor() - first;
    (k >= 0.0).then_some(k as usize)
}

/// The energy share under which ghosts are dim: the dimmest ghosts of `shares` (each ghost's
/// energy over the on-axis direct image's) are dropped, dimmest first, while together they carry at
/// most `budget` of the sum of all; the result is the share of the first ghost kept (ghosts
/// with less are dropped, ties kept together); +∞ when all of them fit the budget (or there
/// are none).
pub fn dim_threshold(shares: impl Iterator<Item = f64>, budget: f64) -> f64 {
    let mut s: Vec<f64> = shares
        .filter(|e| e.is_finite())
        .map(|e| e.max(0.0))
        .collect();
    s.sort_by(f64::total_cmp);
    let allowed = budget * s.iter().sum::<f64>();
    let mut acc = 0.0;
    let mut i = 0;
    // Whole runs of equal shares go together, so that the threshold splits no tie.
    while i < s.len() {
        let j = s[i..].partition_point(|&e| e == s[i]) + i;
        let run: f64 = s[i..j].iter().sum();
        if acc + run > allowed {
            return s[i];
        }
        acc += run;
        i = j;
    }
    // Everything fits the budget (a budget ≥ 1): drop all.
    f64::INFINITY
}

/// Largest grid (of a ghost's bounds: precomputed, or traced for the light) of a smooth ghost,
/// whose cells land on the sensor with areas spreading by at most `(19/16)² ≈ 1.41` between
/// the median and the 90th percentile (`flarebench_sdk::ghost::bounds::grid_for_spread`):
/// such a ghost is drawn well by fewer triangles ([`PlanOptions::smooth_grid_scale`]).
/// Measured on the Nikon zoom (960 × 540, light 10°, 30°, with a table): three
/// quarters of the grid for ghosts up to 18 raised its error from 1.752% to 1.783%, up to 19
/// to 1.809%, up to 21 to 1.876%, and up to 25 to 2.30% — and for every ghost (all grids ×
/// 0.85) to 2.01%.
pub const SMOOTH_GRID: usize = 19;

/// Coarse pixels a grid cell must span at least: the ghost's irradiance is interpolated
/// linearly across each triangle, so a coarse pixel of a quarter cell resolves it.
pub const COARSE_PIXELS_PER_CELL: f64 = 4.0;

/// The coarse-frame factor for a ghost landing on `sensor` (mm) with an `n × n` grid: the
/// largest power of two, at most `max`, whose coarse pixel is no larger than a
/// [`COARSE_PIXELS_PER_CELL`]th of a grid cell on the sensor nor than a `per_radius`th of the
/// ghost's radius. The ghost's edge is one drawn pixel wide
/// (`flarebench_sdk::ghost::triangles::EDGE_PIXELS`), so a coarser frame blurs it over `factor`
/// output pixels, which touches about `factor / radius` of the ghost's area
/// ([`Quality::coarse_pixels_per_radius`]).
pub fn coarse_factor(sensor: &Rect, n: usize, frame: &Frame, max: usize, per_radius: f64) -> usize {
    let extent_px = (sensor.x1 - sensor.x0).max(sensor.y1 - sensor.y0) / frame.pixel_mm();
    let cell_px = extent_px / (n.max(2) - 1) as f64;
    let limit = (cell_px / COARSE_PIXELS_PER_CELL).min(0.5 * extent_px / per_radius);
    let mut f = 1;
    while 2 * f <= max && (2 * f) as f64 <= limit {
        f *= 2;
    }
    f
}

/// True when a sensor rectangle (mm) overlaps the frame.
/// A ghost's energy share ([`GhostBounds::energy_share`]) times the part of its sensor
/// rectangle (rotated by the light's azimuth `phi`) inside the frame: the energy it brings to
/// the image, if it were spread evenly over its rectangle. Culling weighs ghosts by it, so a
/// large ghost mostly off the frame does not make the frame's dim ghosts look dimmer than they
/// are.
pub fn on_frame_share(b: &GhostBounds, phi: f64, frame: &Frame) -> f64 {
    let r = b.sensor.rotated(phi);
    let (hw, hh) = (0.5 * frame.film_width_mm, 0.5 * frame.film_height_mm);
    // Along each axis, the part of the extent inside the frame (a point inside counts whole).
    let part = |lo: f64, hi: f64, half: f64| {
        let inside = hi.min(half) - lo.max(-half);
        if hi > lo {
            (inside / (hi - lo)).clamp(0.0, 1.0)
        } else if inside >= 0.0 {
            1.0
        } else {
            0.0
        }
    };
    b.energy_share * part(r.x0, r.x1, hw) * part(r.y0, r.y1, hh)
}

fn overlaps_frame(sensor: &Rect, frame: &Frame) -> bool {
    let (hw, hh) = (0.5 * frame.film_width_mm, 0.5 * frame.film_height_mm);
    sensor.x1 >= -hw && sensor.x0 <= hw && sensor.y1 >= -hh && sensor.y0 <= hh
}

/// How far (pixels) a ghost's paraxial image moves or grows between two wavelengths.
fn dispersion_px(
    system: &LensSystem,
    path: GhostPath,
    theta: f64,
    lo: f64,
    hi: f64,
    frame: &Frame,
) -> f64 {
    let (Some(a), Some(b)) = (
        bounds::approximate(system, path, lo, theta),
        bounds::approximate(system, path, hi, theta),
    ) else {
        // Paraxially empty: assume it shows.
        return f64::INFINITY;
    };
    let d = [
        (a.sensor.x0 - b.sensor.x0).abs(),
        (a.sensor.x1 - b.sensor.x1).abs(),
        (a.sensor.y0 - b.sensor.y0).abs(),
        (a.sensor.y1 - b.sensor.y1).abs(),
    ];
    d.iter().cloned().fold(0.0, f64::max) / frame.pixel_mm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dim_threshold_drops_the_dimmest_within_the_budget() {
        let t = |v: &[f64], b| dim_threshold(v.iter().copied(), b);
        // 10 in all, 3 may go: 1 and 2 go, 3 stays.
        assert_eq!(t(&[4.0, 1.0, 3.0, 2.0], 0.3), 3.0);
        assert_eq!(t(&[4.0, 1.0, 3.0, 2.0], 0.0), 1.0);
        // Ties go together or stay together.
        assert_eq!(t(&[1.0, 1.0, 1.0, 7.0], 0.2), 1.0);
        assert_eq!(t(&[1.0, 1.0, 1.0, 7.0], 0.3), 7.0);
        // Dark ghosts always go; NaN is ignored; when everything fits, everything goes.
        assert_eq!(t(&[0.0, 0.0, 5.0, f64::NAN], 0.0), 5.0);
        assert_eq!(t(&[], 0.5), f64::INFINITY);
        assert_eq!(t(&[2.0], 1.0), f64::INFINITY);
    }

    fn frame() -> Frame {
        // 1920 px over 36 mm: a pixel is 0.01875 mm.
        Frame {
            width: 1920,
            height: 1080,
            film_width_mm: 36.0,
            film_height_mm: 20.25,
        }
    }

    fn square(px: f64) -> Rect {
        let h = 0.5 * px * 36.0 / 1920.0;
        Rect::square(0.0, 0.0, h)
    }

    /// A warm start (a nearby frame's rectangles) finds the ghosts a cold search finds: from
    /// the same frame, after a small edit of the lens, and from a rectangle far from the ghost
    /// (the full search then runs). Rectangles agree to the search's refinement.
    #[test]
    fn a_warm_start_finds_what_a_cold_search_finds() {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../lenses/heliar-tronnier.xml");
        let sys = flarebench_sdk::io::read_lens(&p).unwrap().system;
        let mut edited = sys.clone();
        edited.surfaces[0].curvature *= 1.01;
        let lights = [LightSpec::parse("8,30").unwrap()];
        let f = Frame::across_film(480, 270, sys.film_width_mm);
        let plan_of = |sys: &LensSystem, warm: Option<&[WarmStart]>| {
            let opts = PlanOptions {
                warm_start: warm,
                ..PlanOptions::for_quality(Quality::Fast, None)
            };
            plan(sys, &lights, &f, &opts).unwrap().remove(0)
        };
        let cold = plan_of(&sys, None);
        assert!(!cold.ghosts.is_empty(), "the Heliar at 8° draws ghosts");
        let warm = [WarmStart::of(&cold)];
        let mut far = warm.clone();
        for r in far[0].entrance.values_mut() {
            *r = Rect::square(-1e3, -1e3, 1e-3);
        }
        let same = |a: &LightPlan, b: &LightPlan, what: &str| {
            let paths = |p: &LightPlan| p.ghosts.iter().map(|g| g.path).collect::<Vec<_>>();
            assert_eq!(paths(a), paths(b), "{what}: other ghosts drawn");
            for (x, y) in a.ghosts.iter().zip(&b.ghosts) {
                let (x, y) = (x.bounds, y.bounds);
                let size = y.sensor.width().max(y.sensor.height());
                let d = (x.sensor.x0 - y.sensor.x0)
                    .abs()
                    .max((x.sensor.x1 - y.sensor.x1).abs())
                    .max((x.sensor.y0 - y.sensor.y0).abs())
                    .max((x.sensor.y1 - y.sensor.y1).abs());
                assert!(d <= 0.1 * size, "{what}: {x:?} against {y:?}");
                let e = (x.energy_share - y.energy_share).abs();
                assert!(e <= 0.05 * y.energy_share, "{what}: {x:?} against {y:?}");
            }
        };
        same(&plan_of(&sys, Some(&warm)), &cold, "the same frame");
        same(&plan_of(&sys, Some(&far)), &cold, "a far start");
        same(
            &plan_of(&edited, Some(&warm)),
            &plan_of(&edited, None),
            "after an edit",
        );
    }

    /// Lens tables (built once per lens) give the same bands as tables built by the plan,
    /// and another lens's are ignored.
    #[test]
    fn lens_tables_give_the_same_plan() {
        let read = |stem: &str| {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("../../lenses/{stem}.xml"));
            flarebench_sdk::io::read_lens(&p).unwrap().system
        };
        let (sys, other) = (read("nikon-zoom-short"), read("heliar-tronnier"));
        let lights = [LightSpec::parse("10,30").unwrap()];
        let f = Frame {
            width: 480,
            height: 270,
            film_width_mm: sys.film_width_mm,
            film_height_mm: sys.film_width_mm * 270.0 / 480.0,
        };
        let mine = LensTables::new(&sys);
        let theirs = LensTables::new(&other);
        assert!(mine.is_for(&sys) && !theirs.is_for(&sys));
        let plan_of = |quality: Quality, lens_tables: Option<&LensTables>| {
            plan(
                &sys,
                &lights,
                &f,
                &PlanOptions {
                    lens_tables,
                    ..PlanOptions::for_quality(quality, None)
                },
            )
            .unwrap()
            .remove(0)
        };
        let plan_with = |lens_tables| plan_of(Quality::Default, lens_tables);
        let without = plan_with(None);
        // Enough distinct bands that the plan interpolates between tables.
        assert!(without.bands.len() > 42, "{} bands", without.bands.len());
        // The lens's tables keep each band's: the next plan shares them.
        let (first, second) = (plan_with(Some(&mine)), plan_with(Some(&mine)));
        for (a, b) in first.bands.iter().zip(&second.bands) {
            assert!(Arc::ptr_eq(&a.tables, &b.tables));
        }
        // A plan of few bands (the fast preset's 7) builds each exactly, with the lens's
        // tables too: the images do not depend on whether the lens was prepared.
        let fast_with = |lens_tables| plan_of(Quality::Fast, lens_tables);
        let pairs = [
            (first, without),
            (plan_with(Some(&theirs)), plan_with(None)),
            (fast_with(Some(&mine)), fast_with(None)),
        ];
        for (with, without) in pairs {
            assert_eq!(with.bands.len(), without.bands.len());
            for (a, b) in with.bands.iter().zip(&without.bands) {
                assert_eq!(a.lambda_nm, b.lambda_nm);
                for s in 0..sys.surfaces.len() {
                    for forward in [true, false] {
                        use flarebench_sdk::trace::Interaction::Reflect;
                        let (x, y) = (
                            a.tables.get(s, forward, Reflect),
                            b.tables.get(s, forward, Reflect),
                        );
                        assert_eq!(x.map(|t| t.values), y.map(|t| t.values), "surface {s}");
                    }
                }
            }
        }
    }

    /// The lens's tables hold at most `MAX_HELD_BANDS` bands; past that a band's tables are
    /// still given (the same as a held band's would be), just not kept.
    #[test]
    fn lens_tables_hold_a_bounded_number_of_bands() {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../lenses/heliar-tronnier.xml");
        let sys = flarebench_sdk::io::read_lens(&p).unwrap().system;
        let lens = LensTables::new(&sys);
        let extra = 8;
        let count = LensTables::MAX_HELD_BANDS + extra;
        let lambda = |i: usize| 400.0 + 300.0 * i as f64 / count as f64;
        let given: Vec<Arc<InterfaceTableSet>> = (0..count)
            .map(|i| lens.band(lambda(i), false).unwrap())
            .collect();
        assert_eq!(lens.bands.lock().unwrap().len(), LensTables::MAX_HELD_BANDS);
        // A held band is shared; one past the cap is built anew each time, with equal tables.
        assert!(Arc::ptr_eq(
            &given[0],
            &lens.band(lambda(0), false).unwrap()
        ));
        let last = count - 1;
        let again = lens.band(lambda(last), false).unwrap();
        assert!(!Arc::ptr_eq(&given[last], &again));
        use flarebench_sdk::trace::Interaction::Reflect;
        for s in 0..sys.surfaces.len() {
            for forward in [true, false] {
                let (x, y) = (
                    given[last].get(s, forward, Reflect),
                    again.get(s, forward, Reflect),
                );
                assert_eq!(x.map(|t| t.values), y.map(|t| t.values), "surface {s}");
            }
        }
        // Outside the tabulated range: none.
        assert!(lens.band(300.0, false).is_none() && lens.band(300.0, true).is_none());
    }

    #[test]
    fn coarse_factor_follows_cells_and_radius() {
        let f = frame();
        // 1000 px wide, 17² grid: cells of 62.5 px allow 15.6, the radius (500 px) over 128
        // allows 3.9: factor 2.
        assert_eq!(coarse_factor(&square(1000.0), 17, &f, 16, 128.0), 2);
        // Over 32: 15.6 either way → 8.
        assert_eq!(coarse_factor(&square(1000.0), 17, &f, 16, 32.0), 8);
        // Capped by `max`, and 1 for small ghosts or fine grids.
        assert_eq!(coarse_factor(&square(1000.0), 17, &f, 4, 32.0), 4);
        assert_eq!(coarse_factor(&square(40.0), 17, &f, 16, 4.0), 1);
        assert_eq!(coarse_factor(&square(1000.0), 17, &f, 1, 4.0), 1);
        assert_eq!(coarse_factor(&square(0.0), 17, &f, 16, 4.0), 1);
    }
}
