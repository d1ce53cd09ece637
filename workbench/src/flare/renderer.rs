//! The flare pipeline, one frame at a time: plan the ghosts, draw them on the backend, find
//! the exposure, add the starbursts. [`Flare`] is the one place it is written; `render`,
//! `apply`, `bench`, `sweep` and the viewer's render thread all call [`Flare::render`].
//!
//! What a frame costs to set up is kept from frame to frame here: the backend (the GPU
//! renderer, or the CPU's coarse frames), the output image's buffer, the starburst patterns,
//! the lens's interface tables and the last frame's ghost rectangles (warm starts).

use std::time::Instant;

use anyhow::ensure;
use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::Scene as AbiScene;
use flarebench_sdk::abi::host::{PluginInstance, RenderStats};
use flarebench_sdk::ghost::context::GhostStats;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::starburst::StarburstCache;
use ghost_raytrace::plan::{self, LensTables, LightPlan, PlanOptions, WarmStart};
use ghost_raytrace::scene::LightSpec;

use super::backend::{BackendChoice, GhostBackend};
use super::compose::StarburstLine;
use super::exposure::{auto_exposure, ghost_exposure};
use super::preset::Preset;
use super::scene::Scene;
use crate::report::LightReport;

/// The flare renderer: a backend and what it keeps between frames.
#[derive(Debug)]
pub struct Flare {
    backend: GhostBackend,
    starbursts: StarburstCache,
    /// The last frame's image (its buffer is drawn into again).
    image: HdrImage,
    /// The interface tables of the last lens a preset asked them for.
    lens_tables: Option<LensTables>,
    /// The last frame's ghost rectangles, light by light (before `solo`).
    warm: Vec<WarmStart>,
}

/// What drawing a frame gave besides its image ([`Flare::image`]).
#[derive(Debug, Default)]
pub struct Rendered {
    /// Per light, the ghosts drawn (after `solo`) and those left out.
    pub plans: Vec<LightPlan>,
    /// The plans as made, before `solo` kept one ghost (only with `solo`).
    pub planned: Option<Vec<LightPlan>>,
    /// Per light, each drawn ghost's statistics in plan order.
    pub ghost_stats: Vec<Vec<GhostStats>>,
    /// Each light's starburst (none when starbursts are off).
    pub starbursts: Vec<StarburstLine>,
    /// The ghosts alone, before the starbursts (with [`Preset::keep_ghosts`]).
    pub ghosts_image: Option<HdrImage>,
    /// The automatic exposure (stops, with [`Preset::exposure`]): the ghosts' with
    /// [`super::exposure::GHOST_HEADROOM_EV`] when any is lit, else the whole frame's.
    pub exposure_ev: Option<f32>,
    /// The plan started from the last frame's rectangles.
    pub warm_started: bool,
    pub timings: FrameTimings,
}

/// Time per stage of a frame (milliseconds).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameTimings {
    pub plan_ms: f64,
    pub ghosts_ms: f64,
    pub starburst_ms: f64,
}

impl FrameTimings {
    /// Planning, ghosts and starbursts together.
    pub fn total_ms(&self) -> f64 {
        self.plan_ms + self.ghosts_ms + self.starburst_ms
    }
}

impl Rendered {
    /// Rays traced over every ghost drawn.
    pub fn rays_traced(&self) -> usize {
        self.ghost_stats.iter().flatten().map(|s| s.rays).sum()
    }

    /// Triangles drawn over every ghost.
    pub fn triangles(&self) -> usize {
        self.ghost_stats.iter().flatten().map(|s| s.triangles).sum()
    }

    /// Ghosts drawn over every light.
    pub fn ghosts_drawn(&self) -> usize {
        self.plans.iter().map(|p| p.ghosts.len()).sum()
    }

    /// Each light's report: its ghosts, their energies and what was left out.
    pub fn light_reports(&self) -> Vec<LightReport> {
        self.plans
            .iter()
            .zip(&self.ghost_stats)
            .map(|(lp, s)| LightReport::new(lp, s))
            .collect()
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

impl Flare {
    /// A renderer on the backend `choice` asks for ([`GhostBackend::open`]).
    pub fn open(choice: BackendChoice) -> anyhow::Result<Flare> {
        Ok(Flare::on(GhostBackend::open(choice)?))
    }

    /// A renderer on `backend`.
    pub fn on(backend: GhostBackend) -> Flare {
        Flare {
            backend,
            starbursts: StarburstCache::new(),
            image: HdrImage::new(0, 0),
            lens_tables: None,
            warm: Vec::new(),
        }
    }

    /// The backend the ghosts are drawn on.
    pub fn backend(&self) -> &GhostBackend {
        &self.backend
    }

    pub fn backend_mut(&mut self) -> &mut GhostBackend {
        &mut self.backend
    }

    /// The last frame's image: ghosts and starbursts, linear.
    pub fn image(&self) -> &HdrImage {
        &self.image
    }

    /// The last frame's image, taken (the next frame draws into a new buffer).
    pub fn take_image(&mut self) -> HdrImage {
        std::mem::replace(&mut self.image, HdrImage::new(0, 0))
    }

    /// The interface tables of `system`, built unless they are kept already: what a plugin
    /// does when the lens is prepared. Presets with [`Preset::lens_tables`] plan with them.
    pub fn prepare(&mut self, system: &LensSystem) -> &LensTables {
        if self.lens_tables.as_ref().is_none_or(|l| !l.is_for(system)) {
            self.lens_tables = Some(LensTables::new(system));
        }
        self.lens_tables.as_ref().expect("just built")
    }

    /// Sets the rectangles the next frame's plan starts from (with [`Preset::warm_start`]), in
    /// place of the last frame's: a sequence starts every frame from the same anchor, so a
    /// frame does not depend on the frames rendered before it.
    pub fn set_warm_start(&mut self, warm: Vec<WarmStart>) {
        self.warm = warm;
    }

    /// Draws one frame of `scene` as `preset` says, into [`Flare::image`]: plan, ghosts,
    /// exposure, starbursts.
    pub fn render(&mut self, scene: &Scene<'_>, preset: &Preset<'_>) -> anyhow::Result<Rendered> {
        let sys = scene.system;
        let mut out = Rendered::default();

        let t = Instant::now();
        if preset.lens_tables && preset.plan.lens_tables.is_none() {
            self.prepare(sys);
        }
        if scene.starburst.ghosts() && !scene.lights.is_empty() {
            let mut opts: PlanOptions<'_> = preset.plan;
            if preset.lens_tables && opts.lens_tables.is_none() {
                opts.lens_tables = self.lens_tables.as_ref();
            }
            if preset.warm_start && self.warm.len() == scene.lights.len() {
                opts.warm_start = Some(self.warm.as_slice());
                out.warm_started = true;
            }
            out.plans = plan::plan(sys, scene.lights, &scene.frame, &opts)?;
        }
        out.timings.plan_ms = ms(t);
        if !out.plans.is_empty() {
            self.warm = out.plans.iter().map(WarmStart::of).collect();
        }
        if let Some(solo) = preset.solo {
            out.planned = Some(out.plans.clone());
            for p in &mut out.plans {
                p.ghosts.retain(|g| g.path == solo);
            }
        }

        let t = Instant::now();
        out.ghost_stats = self.backend.render_into(
            sys,
            scene.aperture,
            scene.frame,
            &out.plans,
            preset.render,
            &mut self.image,
        )?;
        out.timings.ghosts_ms = ms(t);
        self.finish(scene, preset.exposure, preset.keep_ghosts, false, &mut out)?;
        Ok(out)
    }

    /// One frame of `scene` whose ghosts a plugin instance draws with its parameter values
    /// (its pixels, and its mesh drawn by the backend: [`GhostBackend::render_plugin`]), then
    /// the starbursts — on the CPU whatever the backend: the GPU's starburst pass composites
    /// onto its own output, which holds the plugin's mesh but not its pixels. Without a
    /// plugin (or with starbursts only) no ghosts are drawn and there are no statistics.
    pub fn render_plugin(
        &mut self,
        scene: &Scene<'_>,
        plugin: Option<(&mut PluginInstance<'_>, &[f64])>,
        exposure: bool,
    ) -> anyhow::Result<(Rendered, Option<RenderStats>)> {
        let mut out = Rendered::default();
        let frame = scene.frame;
        let t = Instant::now();
        let stats = match plugin.filter(|_| scene.starburst.ghosts()) {
            Some((instance, values)) => {
                let abi_scene = AbiScene {
                    lights: scene.lights.iter().map(LightSpec::scene_light).collect(),
                    frame,
                    aperture: scene.aperture.clone(),
                };
                self.image = HdrImage::new(frame.width, frame.height);
                Some(
                    self.backend
                        .render_plugin(instance, &abi_scene, values, &mut self.image)?,
                )
            }
            None => {
                self.image = HdrImage::new(frame.width, frame.height);
                None
            }
        };
        out.timings.ghosts_ms = ms(t);
        self.finish(scene, exposure, false, true, &mut out)?;
        Ok((out, stats))
    }

    /// The rest of a frame whose ghosts are drawn into [`Flare::image`]: the automatic
    /// exposure, the starbursts (on the CPU when `cpu_starbursts`, else by the backend).
    fn finish(
        &mut self,
        scene: &Scene<'_>,
        exposure: bool,
        keep_ghosts: bool,
        cpu_starbursts: bool,
        out: &mut Rendered,
    ) -> anyhow::Result<()> {
        // The automatic exposure is the ghosts' (when some are drawn), taken before the
        // starbursts are added: a light in the frame is far brighter than its ghosts, and a
        // photograph that shows the flare lets the light itself clip.
        let ghosts_ev = if exposure && scene.starburst.ghosts() {
            ghost_exposure(&self.image)
        } else {
            None
        };
        if keep_ghosts {
            out.ghosts_image = Some(self.image.clone());
        }

        let t = Instant::now();
        if scene.starburst.starbursts() {
            // A plugin's pixels are in the image, not in the GPU's output the GPU's starburst
            // pass composites onto: such a frame's starbursts are added on the CPU.
            let mut cpu;
            let backend = if cpu_starbursts {
                cpu = GhostBackend::cpu(None);
                &mut cpu
            } else {
                &mut self.backend
            };
            out.starbursts = backend.add_starbursts(
                &mut self.image,
                scene.system,
                &scene.frame,
                scene.lights,
                &scene.starburst_setup(),
                &mut self.starbursts,
            )?;
        }
        out.timings.starburst_ms = ms(t);
        ensure!(
            !self.image.has_non_finite(),
            "internal error: the flare has non-finite pixels"
        );
        if exposure {
            out.exposure_ev = Some(ghosts_ev.unwrap_or_else(|| auto_exposure(&self.image)));
        }
        Ok(())
    }
}
