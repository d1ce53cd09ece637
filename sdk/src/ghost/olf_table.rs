//! OpenLensFlare's precomputed ghost bounds (`<ghostList>` XML, [`crate::io::olf_bounds`]) as
//! one of our [`BoundsTable`]s, so `render --precomputed` can use them (docs/formats.md §8).
//!
//! **Taken from the file:** the ghost list, the angle list, each entry's entrance rectangle
//! (converted to mm in our meridional frame and moved from OpenLensFlare's entrance plane,
//! 0.1 mm in front of the first vertex, to ours, the first vertex's), whether the ghost has
//! light at all (an invisible entry stays without light), and the grid size (`optimalRays`,
//! when the file gives one).
//!
//! **Computed here,** because the file's numbers do not mean ours: every visible entry's
//! rectangle is traced once along our ghost path at 550 nm on a 33² grid, as the precise
//! bounds' last step is. That gives the energy share (the flux of the rays that pass over the
//! on-axis direct image's, [`bounds::reference_flux`]; `avgIntensity` being a clamped mean reflectance product — 1 throughout the
//! Heliar file), the mean throughput, the sensor rectangle (the landing points of the rays
//! that pass: OpenLensFlare's sensor rectangles come from another model — flat surfaces
//! unrefracted, another stop radius — and disagree with where our rays land, e.g. ghost 7-6
//! of the Heliar at 10°: its file's y range −24…−11 mm, our rays 11…41 mm), and our grid rule
//! where the file has no `optimalRays`. The same trace tells where the file's rectangle cuts
//! our ghost (rays pass on its border) and where our ghost has no light in it;
//! [`OlfImport`] lists both, and the ghosts of the lens the file does not hold.
//!
//! A file carries no fingerprint of its lens; [`BoundsTable::from_olf`] checks what it can:
//! every element index is a refracting surface of the lens, and the file's ghosts are exactly
//! the pairs OpenLensFlare enumerates for it (both reflections on the same side of the stop).

use std::collections::BTreeSet;

use rayon::prelude::*;

use crate::io::{OlfGhostBounds, OlfGhostEntry};
use crate::paraxial::stop_opening;
use crate::system::{LensSystem, SurfaceKind};
use crate::trace::InterfaceTableSet;

use super::bounds::{self, BoundsMode, GhostBounds, Rect};
use super::enumerate::{GhostPath, enumerate_ghosts};
use super::grid::{GridTrace, trace_grid};
use super::table::{BoundsTable, FORMAT, VERSION, fingerprint};

/// Wavelength (nm) the energies of a converted table are traced at (that of `precompute`).
pub const OLF_TRACE_LAMBDA_NM: f64 = 550.0;
/// Grid vertices per side of the trace over each rectangle (the precise bounds' measuring
/// grid).
pub const OLF_TRACE_GRID: usize = 33;
/// OpenLensFlare's entrance plane lies this far in front of the first vertex (mm).
pub const OLF_ENTRANCE_PLANE_MM: f64 = 0.1;

/// What the conversion found besides the table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OlfImport {
    /// Ghosts of the lens (`enumerate_ghosts`) the file does not hold: OpenLensFlare leaves
    /// out pairs whose reflections straddle the stop. `render` traces their bounds per light.
    pub missing: Vec<GhostPath>,
    /// Ghosts of the file that are not ghosts of ours (a surface without a change of index
    /// reflects nothing in our model); never looked up.
    pub unused: Vec<GhostPath>,
    /// Entries whose rectangle cuts our ghost: rays pass on its border, so part of the ghost
    /// is left out of the picture (ghost, angle in degrees).
    pub cut: Vec<(GhostPath, f64)>,
    /// Visible entries where none of our rays pass inside the file's rectangle: without
    /// light in the table (ghost, angle).
    pub dark: Vec<(GhostPath, f64)>,
    /// Visible entries, and how many of them took their grid from `optimalRays`.
    pub visible: usize,
    pub grids_from_file: usize,
}

/// Why a bounds file does not fit the lens.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OlfTableError {
    #[error("the file holds no angles")]
    NoAngles,
    #[error("the file lists no ghosts")]
    NoGhosts,
    #[error(
        "the ghosts at {angle_deg}° differ from those at {first_deg}° (the file must list the same ghosts in the same order at every angle)"
    )]
    GhostsDiffer { angle_deg: f64, first_deg: f64 },
    #[error("ghost {ghost} (at {angle_deg}°): element {element} {what}")]
    Element {
        ghost: GhostPath,
        angle_deg: f64,
        element: usize,
        what: String,
    },
    #[error(
        "the file's {file_count} ghosts are not those of lens `{lens}`, for which OpenLensFlare would list {lens_count} (every pair of refracting surfaces on the same side of the stop, surface {stop}): {detail}"
    )]
    GhostSet {
        lens: String,
        file_count: usize,
        lens_count: usize,
        stop: usize,
        detail: String,
    },
}

/// The two-reflection paths OpenLensFlare enumerates for `system` (`generateGhosts(2,
/// apertureCross = false)`): every pair of refracting surfaces on the same side of the stop,
/// the later one first.
pub fn olf_ghost_set(system: &LensSystem) -> Vec<GhostPath> {
    let stop = system.stop_index().unwrap_or(usize::MAX);
    let refracting: Vec<usize> = (0..system.surfaces.len())
        .filter(|&i| system.surfaces[i].kind == SurfaceKind::Refracting)
        .collect();
    let mut out = Vec::new();
    for (k, &a) in refracting.iter().enumerate() {
        for &b in &refracting[..k] {
            if (a < stop) == (b < stop) {
                out.push(GhostPath::two(a, b));
            }
        }
    }
    out
}

/// The entrance rectangle of a visible entry in mm on our entrance plane (z = 0): the file's
/// rectangle in our meridional frame ([`OlfGhostEntry::entrance_mm`]), moved by
/// `0.1 mm · tan θ` along y, where rays started 0.1 mm in front of the first vertex cross it.
pub fn olf_entrance_on_our_plane(
    entry: &OlfGhostEntry,
    front_semi_diameter_mm: f64,
    theta_deg: f64,
) -> Option<Rect> {
    let r = entry.entrance_mm(front_semi_diameter_mm)?;
    let dy = OLF_ENTRANCE_PLANE_MM * theta_deg.to_radians().tan();
    Some(Rect {
        y0: r.y0 + dy,
        y1: r.y1 + dy,
        ..r
    })
}

impl BoundsTable {
    /// OpenLensFlare's bounds (`olf`, read by [`crate::io::read_olf_bounds`]) as a table for
    /// `system`, after checking that they fit it (module docs: what is taken from the file
    /// and what is traced). The table's ghosts are the file's, in its order; its angles the
    /// file's; its fingerprint `system`'s, so it passes [`BoundsTable::check_for`] for the
    /// lens it was converted for.
    pub fn from_olf(
        olf: &OlfGhostBounds,
        system: &LensSystem,
    ) -> Result<(BoundsTable, OlfImport), OlfTableError> {
        let paths = check_fit(olf, system)?;
        let ours = enumerate_ghosts(system);
        let mut import = OlfImport {
            missing: ours
                .iter()
                .copied()
                .filter(|p| !paths.contains(p))
                .collect(),
            unused: paths
                .iter()
                .copied()
                .filter(|p| !ours.contains(p))
                .collect(),
            ..OlfImport::default()
        };
        let h0 = system.surfaces[0].semi_diameter;
        let stop = stop_opening(system);
        let tables = InterfaceTableSet::for_system(system, OLF_TRACE_LAMBDA_NM);
        let angles: Vec<f64> = olf.entries.iter().map(|e| e.angle_deg).collect();
        // The flux energy shares are measured against.
        let reference = bounds::reference_flux(system, &tables, &mut GridTrace::default());
        // Per ghost (in parallel), per angle: the entry traced over its rectangle.
        let rows: Vec<Vec<(Option<GhostBounds>, EntryNote)>> = paths
            .par_iter()
            .enumerate()
            .map_init(GridTrace::default, |scratch, (g, &path)| {
                let seq = bounds::ghost_sequence(system, path, &tables);
                olf.entries
                    .iter()
                    .map(|e| {
                        let entry = &e.ghosts[g];
                        let Some(rect) = olf_entrance_on_our_plane(entry, h0, e.angle_deg) else {
                            return (None, EntryNote::Invisible);
                        };
                        let Some(seq) = &seq else {
                            return (None, EntryNote::Dark);
                        };
                        let theta = e.angle_deg.to_radians();
                        trace_grid(seq, theta, rect, OLF_TRACE_GRID, stop, scratch);
                        traced_entry(scratch, entry, theta, reference)
                    })
                    .collect()
            })
            .collect();
        let mut table_rows = Vec::with_capacity(rows.len());
        for (row, &path) in rows.into_iter().zip(&paths) {
            let mut out = Vec::with_capacity(row.len());
            for ((b, note), &angle) in row.into_iter().zip(&angles) {
                match note {
                    EntryNote::Invisible => {}
                    EntryNote::Dark => {
                        import.visible += 1;
                        import.dark.push((path, angle));
                    }
                    EntryNote::Traced {
                        cut,
                        grid_from_file,
                    } => {
                        import.visible += 1;
                        import.grids_from_file += usize::from(grid_from_file);
                        if cut {
                            import.cut.push((path, angle));
                        }
                    }
                }
                out.push(b);
            }
            table_rows.push(out);
        }
        let table = BoundsTable {
            format: FORMAT.to_string(),
            version: VERSION,
            lens: system.name.clone(),
            lens_fingerprint: fingerprint(system),
            mode: BoundsMode::Precise,
            wavelength_nm: OLF_TRACE_LAMBDA_NM,
            angles_deg: angles,
            ghosts: paths,
            bounds: table_rows,
            four_reflection_bound_threshold: None,
            four_reflection_paths: None,
        };
        Ok((table, import))
    }
}

/// What the trace of one visible entry showed.
#[derive(Clone, Copy, Debug)]
enum EntryNote {
    Invisible,
    /// No ray of ours passes inside the file's rectangle.
    Dark,
    Traced {
        cut: bool,
        grid_from_file: bool,
    },
}

/// The bounds of one visible entry from the grid traced over its rectangle (`g`).
fn traced_entry(
    g: &GridTrace,
    entry: &OlfGhostEntry,
    theta: f64,
    reference: f64,
) -> (Option<GhostBounds>, EntryNote) {
    let n = g.n;
    let passing: Vec<usize> = (0..n * n).filter(|&k| g.passes(k)).collect();
    let Some(sensor) = Rect::bounding(passing.iter().map(|&k| g.sensor[k].map(f64::from))) else {
        return (None, EntryNote::Dark);
    };
    let cut = passing.iter().any(|&k| {
        let (i, j) = (k % n, k / n);
        i == 0 || j == 0 || i == n - 1 || j == n - 1
    });
    let weights: f64 = passing.iter().map(|&k| f64::from(g.weight[k])).sum();
    let flux = weights * g.cell_area() * theta.cos();
    let grid_from_file = entry.optimal_rays > 0;
    let grid = if grid_from_file {
        entry.optimal_rays as usize
    } else {
        bounds::grid_for_spread(g)
    };
    let b = GhostBounds {
        entrance: g.rect,
        sensor,
        grid,
        mean_intensity: weights / passing.len() as f64,
        energy_share: if reference > 0.0 {
            flux / reference
        } else {
            0.0
        },
    };
    (
        Some(b),
        EntryNote::Traced {
            cut,
            grid_from_file,
        },
    )
}

/// The file's ghost paths, after checking that every angle lists the same ones, that every
/// element is a refracting surface of `system`, and that they are the pairs OpenLensFlare
/// enumerates for it.
fn check_fit(olf: &OlfGhostBounds, system: &LensSystem) -> Result<Vec<GhostPath>, OlfTableError> {
    let first = olf.entries.first().ok_or(OlfTableError::NoAngles)?;
    if first.ghosts.is_empty() {
        return Err(OlfTableError::NoGhosts);
    }
    let paths: Vec<GhostPath> = first.ghosts.iter().map(OlfGhostEntry::path).collect();
    for e in &olf.entries {
        if e.ghosts.len() != paths.len() || e.ghosts.iter().zip(&paths).any(|(g, p)| g.path() != *p)
        {
            return Err(OlfTableError::GhostsDiffer {
                angle_deg: e.angle_deg,
                first_deg: first.angle_deg,
            });
        }
    }
    let last = system.surfaces.len() - 1;
    for g in &first.ghosts {
        for &element in &g.interfaces {
            let what = match system.surfaces.get(element).map(|s| s.kind) {
                None => format!("is beyond this lens's surfaces (0–{last})"),
                Some(SurfaceKind::ApertureStop) => "is this lens's aperture stop".to_string(),
                Some(SurfaceKind::Sensor) => "is this lens's sensor".to_string(),
                Some(SurfaceKind::Refracting) => continue,
            };
            return Err(OlfTableError::Element {
                ghost: g.path(),
                angle_deg: first.angle_deg,
                element,
                what: format!("{what}: the file is not for lens `{}`", system.name),
            });
        }
    }
    let expected: BTreeSet<(usize, usize)> = olf_ghost_set(system)
        .iter()
        .map(|p| (p.first(), p.second()))
        .collect();
    let got: BTreeSet<(usize, usize)> = paths.iter().map(|p| (p.first(), p.second())).collect();
    if expected != got || got.len() != paths.len() {
        let list = |s: Vec<&(usize, usize)>| {
            let n = s.len();
            let mut t: Vec<String> = s.iter().take(6).map(|(a, b)| format!("{a}-{b}")).collect();
            if n > 6 {
                t.push(format!("… ({n} in all)"));
            }
            t.join(", ")
        };
        let missing: Vec<_> = expected.difference(&got).collect();
        let extra: Vec<_> = got.difference(&expected).collect();
        let mut detail = Vec::new();
        if !missing.is_empty() {
            detail.push(format!("not in the file: {}", list(missing)));
        }
        if !extra.is_empty() {
            detail.push(format!("in the file but not of this lens: {}", list(extra)));
        }
        if got.len() != paths.len() {
            detail.push("the file lists a ghost twice".to_string());
        }
        return Err(OlfTableError::GhostSet {
            lens: system.name.clone(),
            file_count: paths.len(),
            lens_count: expected.len(),
            stop: system.stop_index().unwrap_or(last),
            detail: detail.join("; "),
        });
    }
    Ok(paths)
}
