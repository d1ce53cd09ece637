//! The ghost renderer as a plugin (ABI v1): the same [`crate::plan::plan`] and
//! [`crate::ghosts::render`] the workbench calls directly, behind
//! [`export_plugin!`](flarebench_sdk::export_plugin). Parameters: `quality` (the preset),
//! `bands` (wavelength bands, 0 for the preset's), `grid_scale` (0 for the preset's), the
//! planner's thresholds `smooth_grid_scale`, `dim_budget`, `band_spacing`, `coarse_px`,
//! `max_downscale` and `method_budget` (each 0, or −1 for `dim_budget` and `method_budget`, for
//! the preset's), `reflections` ("2": two-reflection ghosts, the default; "4": four-reflection
//! ghosts too).

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};

use crate::ghosts;
use crate::plan::{self, LensTables, PlanOptions};
use crate::scene::{LightSpec, Quality};
use flarebench_sdk::ghost::ReflectionOrder;

const QUALITIES: &[&str] = &["fast", "default", "high"];
const REFLECTIONS: &[&str] = &["2", "4"];

/// The plugin: holds the lens between renders.
#[derive(Debug, Default)]
pub struct GhostRaytrace {
    lens: Option<LensSystem>,
    /// The prepared lens's interface tables, for every frame's plan.
    tables: Option<LensTables>,
    /// The coarse frames, kept from frame to frame.
    scratch: ghosts::RenderScratch,
}

/// The scene's lights as the renderer's [`LightSpec`]s.
pub fn light_specs(scene: &Scene) -> Vec<LightSpec> {
    scene
        .lights
        .iter()
        .map(|l| LightSpec {
            theta_deg: l.theta_deg,
            phi_deg: l.phi_deg,
            intensity: l.intensity,
            spectrum: l.spectrum,
        })
        .collect()
}

/// The plan options of a set of parameter values.
pub fn plan_options(params: &Params<'_>) -> Result<PlanOptions<'static>, PluginError> {
    let quality = Quality::ALL[params.get_choice("quality")?.min(2)];
    let mut opts = PlanOptions::for_quality(quality, None);
    // Each setting's value when positive; 0 keeps the preset's (−1 for `dim_budget`, which
    // may be 0).
    let positive = |name: &str| -> Result<Option<f64>, PluginError> {
        let v = params.get(name)?;
        Ok((v > 0.0).then_some(v))
    };
    if let Some(b) = positive("bands")? {
        opts.bands = b.round() as usize;
    }
    if let Some(v) = positive("grid_scale")? {
        opts.grid_scale = v;
    }
    if let Some(v) = positive("smooth_grid_scale")? {
        opts.smooth_grid_scale = v;
    }
    let budget = params.get("dim_budget")?;
    if budget >= 0.0 {
        opts.dim_budget = budget;
    }
    if let Some(v) = positive("band_spacing")? {
        opts.band_spacing_px = v;
    }
    if let Some(v) = positive("coarse_px")? {
        opts.coarse_pixels_per_radius = v;
    }
    if let Some(d) = positive("max_downscale")? {
        opts.max_downscale = d.round() as usize;
    }
    let method_budget = params.get("method_budget")?;
    if method_budget >= 0.0 {
        opts.method_error_budget = method_budget;
    }
    opts.reflections = match params.get_choice("reflections")? {
        0 => ReflectionOrder::Two,
        _ => ReflectionOrder::Four,
    };
    Ok(opts)
}

impl FlarePlugin for GhostRaytrace {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "ghost-raytrace",
            version: env!("CARGO_PKG_VERSION"),
            description: "ghosts by sparse ray grids through the real lens (Hullin et al. 2011), spectral, energy-conserving",
            kind: PluginKind::Ghosts,
            params: vec![
                ParamSpec::choice(
                    "quality",
                    "preset: bands, grid size and culling threshold",
                    QUALITIES,
                    1,
                ),
                ParamSpec::int(
                    "bands",
                    "wavelength bands traced (0: the preset's 7/31/31)",
                    0,
                    31,
                    0,
                ),
                ParamSpec::float(
                    "grid_scale",
                    "multiplier on each ghost's grid (0: the preset's 0.5/1/2; the default preset also draws smooth ghosts with 3/4 of theirs)",
                    0.0,
                    16.0,
                    0.0,
                ),
                ParamSpec::float(
                    "smooth_grid_scale",
                    "multiplier, with grid_scale, on a smooth ghost's grid (0: the preset's 1/0.75/1)",
                    0.0,
                    16.0,
                    0.0,
                ),
                ParamSpec::float(
                    "dim_budget",
                    "share of the ghosts' energy on the frame the dimmest ghosts may take with them when they are left out (-1: the preset's 0.03/0.001/0.0003; 0 keeps every ghost)",
                    -1.0,
                    1.0,
                    -1.0,
                ),
                ParamSpec::float(
                    "band_spacing",
                    "drawn pixels by which neighbouring wavelength bands of a ghost may move it (0: the presets' 0.5)",
                    0.0,
                    64.0,
                    0.0,
                ),
                ParamSpec::float(
                    "coarse_px",
                    "coarse pixels a ghost's radius must span to be drawn into a coarse frame (0: the preset's 32/96/512)",
                    0.0,
                    4096.0,
                    0.0,
                ),
                ParamSpec::int(
                    "max_downscale",
                    "largest coarse-frame factor (0: the preset's 16/8/8; 1 draws every ghost at full resolution)",
                    0,
                    64,
                    0,
                ),
                ParamSpec::float(
                    "method_budget",
                    "relative RMSE the per-ghost choice of drawing method (meshed or splatted) may add to the frame (-1: the preset's 0.03/0/0; 0 meshes every ghost)",
                    -1.0,
                    1.0,
                    -1.0,
                ),
                ParamSpec::choice(
                    "reflections",
                    "ghost paths: 2 (two reflections) or 4 (two and four reflections; four-reflection paths culled by an energy bound first)",
                    REFLECTIONS,
                    0,
                ),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(GhostRaytrace::default())
    }

    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        self.lens = Some(lens.clone());
        self.tables = Some(LensTables::new(lens));
        Ok(())
    }

    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        let lens = self
            .lens
            .as_ref()
            .ok_or_else(|| PluginError::new("no lens prepared"))?;
        let opts = PlanOptions {
            lens_tables: self.tables.as_ref(),
            ..plan_options(params)?
        };
        let plans = plan::plan(lens, &light_specs(scene), &scene.frame, &opts)?;
        // Straight into the host's buffer: no image of the frame's size, no copy. (The host
        // hands it over black, and other plugins' images may be added to it: added to.)
        ghosts::render_into_reusing(
            lens,
            &scene.aperture,
            scene.frame,
            &plans,
            ghosts::RenderOptions::default(),
            &mut self.scratch,
            out.pixels,
        )?;
        out.items_drawn = plans.iter().map(|p| p.ghosts.len() as u32).sum();
        Ok(())
    }
}

flarebench_sdk::export_plugin!(GhostRaytrace);
