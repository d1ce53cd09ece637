//! The reference renderer: the ground truth for every error figure.
//!
//! Every ghost that has light (no culling); each ghost at enough wavelength bands, each traced
//! on its own, that neighbouring bands move it by at most an eighth of a pixel (paraxially),
//! and at least 31, up to 160; and grids ten times finer a side than the planned ones (at
//! least 240 vertices a side).
//!
//! The spectrum, measured on the Nikon zoom's most dispersive ghost (7-0, light 10°, 30°,
//! 960 × 540, reference grid) against 160 bands (the example `bands_by_ghost`): 31 bands
//! (about one pixel apart) 0.96% of the ghost's own light, 40 bands 0.65%, 80 bands 0.20%, an
//! eighth of a pixel apart (121 bands) 0.11%. The Heliar's most dispersive ghosts at
//! 1920 × 1080 are within 0.16% at 31 bands against 80.
//!
//! The grids, measured on the Heliar (5°, 160×90) with ghost edges feathered over a grid
//! cell: the relative RMSE between successive densities ×√2 apart falls as 2.7e-3,
//! 1.6e-3, 1.1e-3, 6.0e-4 from 4× a side, under 1e-3 at 10×. `tests/reference.rs` checks that
//! twice its rays, and twice its bands, change the image by under 0.1%.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::ghost::table::fingerprint;
use flarebench_sdk::image::HdrImage;

use crate::GhostRenderError;
use crate::ghosts;
use crate::plan::{self, DrawMethod, LightPlan, PlanOptions};
use crate::scene::{LightSpec, Quality};

/// The reference draws every band on its own: no fringe model between it and the truth.
const BAND_BY_BAND: ghosts::RenderOptions = ghosts::RenderOptions {
    trace_f64: false,
    band_by_band: true,
    replace: false,
    exact_coverage: false,
};

/// The fewest wavelength bands a ghost of the reference is traced at.
pub const REFERENCE_MIN_BANDS: usize = 31;
/// The most wavelength bands a ghost of the reference is traced at.
pub const REFERENCE_MAX_BANDS: usize = 160;
/// Pixels (full resolution) by which neighbouring bands of a reference ghost may move it,
/// paraxially: a quarter of the presets' [`plan::BAND_SPACING_PX`].
pub const REFERENCE_BAND_SPACING_PX: f64 = 0.125;
/// Smallest grid (vertices a side) of the reference renderer.
pub const REFERENCE_MIN_GRID: usize = 240;
/// Grid multiplier of the reference renderer over the planned grid.
pub const REFERENCE_GRID_SCALE: f64 = 10.0;

/// Bumped whenever the reference renderer's output changes, so that saved references made by
/// an older one are refused ([`reference_key`]). 2: the precise bounds search widens a
/// rectangle the ghost reaches the side of (`ghost::bounds::precise_from`), which had cut
/// some ghosts — the Heliar's 6-4 lost a third of its width. 3: each ghost at as many bands
/// as its dispersion needs (an eighth of a pixel apart, 31 to 160), each band's colour its exact
/// share of the 5 nm cells it spans. 4: bounds that follow a ghost's thin parts and find its
/// small entry regions (`ghost::bounds`: `edge_dips`, `zoom`), energies measured over the
/// pupil — ghosts the reference had cut or missed. 5: Fresnel tables of light leaving the
/// denser medium tabulated in the refracted cosine (`trace::InterfaceTable`: exact near the
/// critical angle), grids refined where the throughput changes fast
/// (`bounds::grid_for_spread`), small pupils found (`bounds::direct_flux`). 6: grids refined
/// for ghosts whose edge cells carry much of their light (`bounds::grid_for_edges`). 7: ghosts
/// whose search rays all stop found from their paraxial entrance rectangle, and smaller entry
/// regions zoomed into (`bounds::paraxial_seed`, `zoom`). 8: a spectral ghost's rectangle
/// holds its region at its first and last band (`bounds::widened_for`). 9: every edge
/// feathered over one drawn pixel along its own gradient (`triangles::edge_feathers`). 10: the
/// rasterizer sums each tile's pixels in f64 (`raster::TileSums`). 11: slivers under the Airy
/// disc's area widened across their longest edge, not scaled (`triangles::grow_to_area`).
pub const REFERENCE_VERSION: u32 = 11;

/// A text naming everything the reference image depends on: the renderer's version and
/// settings, the reflection order, the lens (fingerprint of its canonical XML), the aperture, the frame and every
/// light. Two scenes with the same key have the same reference; the workbench stores it with
/// a saved reference (`render --reference-file`) and refuses a file whose key differs.
pub fn reference_key(
    system: &LensSystem,
    aperture: &Aperture,
    frame: &Frame,
    lights: &[LightSpec],
    reflections: ReflectionOrder,
) -> String {
    use std::fmt::Write;
    let mut key = format!(
        "flarebench-reference v{REFERENCE_VERSION} bands {REFERENCE_MIN_BANDS}-{REFERENCE_MAX_BANDS} at {REFERENCE_BAND_SPACING_PX} px grid x{REFERENCE_GRID_SCALE} min {REFERENCE_MIN_GRID} reflections {}; lens {} {}; aperture {}; frame {}x{} px {}x{} mm",
        reflections.count(),
        system.name,
        fingerprint(system),
        aperture_key(aperture),
        frame.width,
        frame.height,
        frame.film_width_mm,
        frame.film_height_mm,
    );
    for l in lights {
        let _ = write!(
            key,
            "; light {},{},{} {:?}",
            l.theta_deg, l.phi_deg, l.intensity, l.spectrum
        );
    }
    key
}

/// The aperture in a reference key; a mask by a fingerprint of its pixels.
fn aperture_key(aperture: &Aperture) -> String {
    match aperture {
        Aperture::Mask(mask) => {
            let mut h = flarebench_sdk::hash::Fnv1a::new();
            for v in mask.data() {
                h.write(&v.to_le_bytes());
            }
            format!("mask {}x{} {}", mask.width(), mask.height(), h.hex())
        }
        other => format!("{other:?}"),
    }
}

/// Renders the reference image of `lights` through `system`.
pub fn reference_image(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lights: &[LightSpec],
) -> Result<HdrImage, GhostRenderError> {
    reference_image_with_density(system, aperture, frame, lights, 1.0)
}

/// The reference with the ghosts of `reflections` (every four-reflection ghost that has light
/// too, for [`ReflectionOrder::Four`]: no energy bound, no culling).
pub fn reference_image_of_order(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lights: &[LightSpec],
    reflections: ReflectionOrder,
) -> Result<HdrImage, GhostRenderError> {
    let plans = reference_plans_of_order(system, lights, &frame, 1.0, reflections)?;
    Ok(ghosts::render_with(system, aperture, frame, &plans, BAND_BY_BAND)?.0)
}

/// The reference ghost by ghost: each of its ghosts rendered alone
/// ([`ghosts::render_each_ghost`]) and handed to `each` with its light's index and path;
/// returns what `each` returned, in plan order, and their sum, the reference image (equal to
/// [`reference_image_of_order`]'s but for the order of the f32 additions).
pub fn reference_by_ghost<R: Send>(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lights: &[LightSpec],
    reflections: ReflectionOrder,
    each: impl Fn(usize, &flarebench_sdk::ghost::GhostPath, &HdrImage) -> R + Sync,
) -> Result<(Vec<R>, HdrImage), GhostRenderError> {
    let plans = reference_plans_of_order(system, lights, &frame, 1.0, reflections)?;
    ghosts::render_each_ghost(
        system,
        aperture,
        frame,
        &plans,
        BAND_BY_BAND,
        |li, job, img| each(li, &job.path, img),
    )
}

/// The reference with `density` times as many grid vertices a side (the convergence check).
pub fn reference_image_with_density(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lights: &[LightSpec],
    density: f64,
) -> Result<HdrImage, GhostRenderError> {
    let plans = reference_plans(system, lights, &frame, density)?;
    Ok(ghosts::render_with(system, aperture, frame, &plans, BAND_BY_BAND)?.0)
}

/// The reference's plan: no culling, each ghost at its dispersion's bands, grids `density` ×
/// the reference's.
pub fn reference_plans(
    system: &LensSystem,
    lights: &[LightSpec],
    frame: &Frame,
    density: f64,
) -> Result<Vec<LightPlan>, GhostRenderError> {
    reference_plans_of_order(system, lights, frame, density, ReflectionOrder::Two)
}

/// [`reference_plans`] with the ghosts of `reflections`.
pub fn reference_plans_of_order(
    system: &LensSystem,
    lights: &[LightSpec],
    frame: &Frame,
    density: f64,
    reflections: ReflectionOrder,
) -> Result<Vec<LightPlan>, GhostRenderError> {
    reference_plans_dense(system, lights, frame, density, 1.0, reflections)
}

/// The reference's plan options for the ghosts of `reflections`: no culling, every ghost at
/// full resolution, exact tables, its bands and grid scale. Its plans also raise every grid
/// to [`REFERENCE_MIN_GRID`] ([`reference_plans_dense`]).
pub fn reference_options(reflections: ReflectionOrder) -> PlanOptions<'static> {
    PlanOptions {
        quality: Quality::High,
        bands: REFERENCE_MAX_BANDS,
        min_bands: REFERENCE_MIN_BANDS,
        band_spacing_px: REFERENCE_BAND_SPACING_PX,
        cull: false,
        dim_budget: 0.0,
        grid_scale: REFERENCE_GRID_SCALE,
        smooth_grid_scale: 1.0,
        precomputed: None,
        exact_tables: true,
        max_downscale: 1,
        coarse_pixels_per_radius: Quality::High.coarse_pixels_per_radius(),
        // From 31 bins up the colours' spectral error is within 0.1% for every ghost (the
        // Heliar at 0°, 10°, 30° and the Nikon zoom at 5°, 10°, 20°, 480 × 270, measured
        // 2026-12-05): the reference's bands are set by its dispersion alone.
        spectral_tolerance: f64::INFINITY,
        reflections,
        lens_tables: None,
        warm_start: None,
        // Exact coverage everywhere: the reference is what the other methods are measured by.
        method: Some(DrawMethod::Mesh),
        method_error_budget: 0.0,
    }
}

/// [`reference_plans_of_order`] with `band_density` times the bands too: neighbouring bands
/// closer by that factor, and that many more at most and at least (the spectral convergence
/// check).
pub fn reference_plans_dense(
    system: &LensSystem,
    lights: &[LightSpec],
    frame: &Frame,
    density: f64,
    band_density: f64,
    reflections: ReflectionOrder,
) -> Result<Vec<LightPlan>, GhostRenderError> {
    let scaled = |n: usize| ((n as f64 * band_density).round() as usize).max(1);
    let base = reference_options(reflections);
    let opts = PlanOptions {
        bands: scaled(base.bands),
        min_bands: scaled(base.min_bands),
        band_spacing_px: base.band_spacing_px / band_density,
        grid_scale: base.grid_scale * density,
        ..base
    };
    let mut plans = plan::plan(system, lights, frame, &opts)?;
    let min_grid = (REFERENCE_MIN_GRID as f64 * density).round() as usize;
    for lp in &mut plans {
        for g in &mut lp.ghosts {
            g.grid = g.grid.max(min_grid);
        }
    }
    Ok(plans)
}
