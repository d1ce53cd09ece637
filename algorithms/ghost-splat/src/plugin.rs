//! The splat renderer as a plugin (ABI v1): [`crate::render::render_into`] behind
//! [`export_plugin!`](flarebench_sdk::export_plugin), writing straight into the host's image.
//! Parameters: `rays` (rays per ghost and light, over its bands), `kernel_px` (0: box; 1..=8:
//! tent half-width, 1 bilinear; default 3), `bands` (wavelength bands), `seed`.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};
use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};

use crate::render::{SplatScratch, SplatSettings, render_into};

/// Default rays per ghost: the Heliar's 28 ghosts at 480 × 270 in about a second on two
/// cores (docs/plugins.md §7).
pub const DEFAULT_RAYS: i64 = 1 << 15;
/// Default splat kernel: a tent of half-width 3 px, which at the default rays has a third of
/// the bilinear splat's error on the Heliar (82% against 265% relative RMSE, docs/plugins.md
/// §7) for a blur of a few pixels.
pub const DEFAULT_KERNEL_PX: f64 = 3.0;

/// The plugin: the lens, its ghost paths and the buffers kept between renders.
#[derive(Debug, Default)]
pub struct GhostSplat {
    lens: Option<(LensSystem, Vec<GhostPath>)>,
    scratch: SplatScratch,
}

/// The render settings of a set of parameter values (an error for values out of range).
pub fn settings(params: &Params<'_>) -> Result<SplatSettings, PluginError> {
    Ok(SplatSettings::new(
        params.get_int("rays")?,
        params.get("kernel_px")?,
        params.get_int("bands")?,
        params.get_int("seed")?,
    )?)
}

impl FlarePlugin for GhostSplat {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "ghost-splat",
            version: env!("CARGO_PKG_VERSION"),
            description: "ghosts by forward ray splatting: stratified f64 rays per ghost (the Monte-Carlo reference's tracer), each ray's flux splatted where it lands; noise falls as 1/sqrt(rays)",
            kind: PluginKind::Ghosts,
            params: vec![
                ParamSpec::int(
                    "rays",
                    "rays per ghost and light, over all its bands (at least one per band is traced)",
                    1024,
                    1 << 24,
                    DEFAULT_RAYS,
                ),
                ParamSpec::float(
                    "kernel_px",
                    "splat kernel: 0 the box (the pixel a ray lands in), 1..=8 a tent of that half-width in pixels (1: bilinear)",
                    0.0,
                    8.0,
                    DEFAULT_KERNEL_PX,
                ),
                ParamSpec::int("bands", "wavelength bands traced", 1, 64, 7),
                ParamSpec::int("seed", "seed of the random streams", 0, 1 << 31, 1),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(GhostSplat::default())
    }

    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        self.lens = Some((lens.clone(), enumerate_ghosts(lens)));
        Ok(())
    }

    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        let (lens, paths) = self
            .lens
            .as_ref()
            .ok_or_else(|| PluginError::new("no lens prepared"))?;
        let settings = settings(params)?;
        let stats = render_into(lens, paths, scene, &settings, &mut self.scratch, out.pixels)?;
        out.items_drawn = stats.ghosts_drawn;
        Ok(())
    }
}

flarebench_sdk::export_plugin!(GhostSplat);
