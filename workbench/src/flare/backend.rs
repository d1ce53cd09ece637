//! Where ghosts are drawn: the CPU rasterizer or the GPU backend (`flarebench-gpu`), chosen by
//! `--backend cpu|gpu|auto`. Both draw the same frame description
//! (`ghost_raytrace::ghosts::draw_into`); tracing and meshing stay on the CPU either way.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::context::GhostStats;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::starburst::StarburstCache;
use ghost_raytrace::ghosts::{self, RenderOptions, RenderScratch};
use ghost_raytrace::plan::LightPlan;
use ghost_raytrace::scene::LightSpec;

use super::compose::{StarburstLine, StarburstSetup};
use crate::output::ToneMap;
use serde::Serialize;

/// The `--backend` choice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendChoice {
    /// The GPU when the machine has a hardware one, else the CPU (a software adapter such as
    /// lavapipe is used only when asked for with `gpu`).
    #[default]
    Auto,
    /// The CPU rasterizer.
    Cpu,
    /// The GPU backend on the best adapter there is, a software one included.
    Gpu,
}

impl std::fmt::Display for BackendChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BackendChoice::Auto => "auto",
            BackendChoice::Cpu => "cpu",
            BackendChoice::Gpu => "gpu",
        })
    }
}

/// What a frame's ghosts were drawn with, for reports.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BackendReport {
    /// `cpu` or `gpu`.
    pub backend: String,
    /// Why `auto` chose the CPU (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The GPU adapter, its driver and graphics API (GPU only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub driver: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub api: Option<String>,
    /// True for a software adapter (its times say nothing of a real GPU's).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub software_adapter: bool,
    /// GPU only: CPU time tracing and meshing the frame (ms), the triangles uploaded (open,
    /// edge, fringed), bytes uploaded, draw calls, and GPU time per pass (ms, where the
    /// adapter measures it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh_ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub triangles: Option<[usize; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bytes_uploaded: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub draw_calls: Option<usize>,
    /// GPU only: fragments the triangles make (`flarebench_gpu::FrameReport::fragments`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fragments: Option<u64>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub passes: Vec<PassLine>,
}

/// One GPU pass's time.
#[derive(Clone, Debug, Serialize)]
pub struct PassLine {
    pub pass: String,
    pub ms: f64,
}

impl BackendReport {
    /// The GPU frame's pass times and uploads so far.
    #[cfg(feature = "gpu")]
    fn take_passes(&mut self, r: &flarebench_gpu::FrameReport) {
        self.bytes_uploaded = Some(r.bytes_uploaded);
        self.passes = r
            .passes
            .iter()
            .map(|p| PassLine {
                pass: p.name.clone(),
                ms: p.ms,
            })
            .collect();
        self.gpu_ms = (!r.passes.is_empty()).then(|| r.passes.iter().map(|p| p.ms).sum());
    }

    /// One line of text for `--report`.
    pub fn text(&self) -> String {
        let mut s = format!("backend: {}", self.backend);
        if let Some(a) = &self.adapter {
            s += &format!(
                " on {a} ({}, {}{})",
                self.driver.as_deref().unwrap_or("?"),
                self.api.as_deref().unwrap_or("?"),
                if self.software_adapter {
                    ", software"
                } else {
                    ""
                }
            );
        }
        // (Why `auto` chose the CPU is in the JSON report: it depends on the machine.)
        s += "\n";
        if let (Some(mesh), Some(t)) = (self.mesh_ms, self.triangles) {
            s += &format!(
                "  CPU tracing and meshing {mesh:.1} ms; {} triangles uploaded ({} open, {} edge, {} fringed), {:.1} MB, {} draw calls, {:.2e} fragments\n",
                t.iter().sum::<usize>(),
                t[0],
                t[1],
                t[2],
                self.bytes_uploaded.unwrap_or(0) as f64 / 1e6,
                self.draw_calls.unwrap_or(0),
                self.fragments.unwrap_or(0) as f64
            );
        }
        if !self.passes.is_empty() {
            let passes: Vec<String> = self
                .passes
                .iter()
                .map(|p| format!("{} {:.2} ms", p.pass, p.ms))
                .collect();
            s += &format!("  GPU passes: {}\n", passes.join(", "));
        }
        s
    }
}

/// An open backend, kept from frame to frame (buffers, targets, the device).
#[derive(Debug)]
pub struct GhostBackend {
    active: Active,
    report: BackendReport,
}

#[derive(Debug)]
enum Active {
    Cpu(RenderScratch),
    #[cfg(feature = "gpu")]
    Gpu(Box<flarebench_gpu::GhostRenderer>),
}

impl GhostBackend {
    /// Opens the backend `choice` asks for: `auto` falls back to the CPU (saying why in the
    /// report) when there is no hardware GPU; `gpu` fails with what to install.
    pub fn open(choice: BackendChoice) -> anyhow::Result<GhostBackend> {
        match choice {
            BackendChoice::Cpu => Ok(GhostBackend::cpu(None)),
            #[cfg(feature = "gpu")]
            BackendChoice::Gpu | BackendChoice::Auto => {
                use flarebench_gpu::{AccumFormat, AdapterChoice, GhostRenderer, GpuContext};
                let adapters = if choice == BackendChoice::Gpu {
                    AdapterChoice::Any
                } else {
                    AdapterChoice::Hardware
                };
                let opened = GpuContext::new(adapters).and_then(|ctx| {
                    GhostRenderer::new(std::sync::Arc::new(ctx), AccumFormat::default())
                });
                match opened {
                    Ok(renderer) => {
                        let r = &renderer.context().report;
                        let report = BackendReport {
                            backend: "gpu".into(),
                            adapter: Some(r.name.clone()),
                            driver: Some(r.driver.clone()),
                            api: Some(r.backend.clone()),
                            software_adapter: r.software,
                            ..BackendReport::default()
                        };
                        Ok(GhostBackend {
                            active: Active::Gpu(Box::new(renderer)),
                            report,
                        })
                    }
                    Err(e) if choice == BackendChoice::Auto => {
                        let why = match e {
                            flarebench_gpu::GpuError::SoftwareOnly { name, .. } => {
                                format!("auto: no hardware GPU, only the software adapter {name}")
                            }
                            flarebench_gpu::GpuError::NoAdapter { .. } => {
                                "auto: no GPU adapter".to_string()
                            }
                            e => format!("auto: {e}"),
                        };
                        Ok(GhostBackend::cpu(Some(why)))
                    }
                    Err(e) => Err(anyhow::Error::new(e).context("--backend gpu")),
                }
            }
            #[cfg(not(feature = "gpu"))]
            BackendChoice::Gpu => anyhow::bail!(
                "--backend gpu: this flarebench was built without the GPU backend (cargo feature `gpu`)"
            ),
            #[cfg(not(feature = "gpu"))]
            BackendChoice::Auto => Ok(GhostBackend::cpu(Some(
                "auto: built without the GPU backend".into(),
            ))),
        }
    }

    /// The CPU rasterizer; `note` says why it was chosen.
    pub(super) fn cpu(note: Option<String>) -> GhostBackend {
        GhostBackend {
            active: Active::Cpu(RenderScratch::default()),
            report: BackendReport {
                backend: "cpu".into(),
                note,
                ..BackendReport::default()
            },
        }
    }

    /// True when ghosts are drawn on the GPU.
    pub fn is_gpu(&self) -> bool {
        !matches!(self.active, Active::Cpu(_))
    }

    /// What the last frame was drawn with and cost.
    pub fn report(&self) -> &BackendReport {
        &self.report
    }

    /// Adds the starbursts of `lights` to `img`, this frame's ghosts just rendered: on the CPU
    /// by splatting into it; on the GPU composited onto the frame's output from their
    /// patterns (kept there from frame to frame), `img` then read back from it.
    pub fn add_starbursts(
        &mut self,
        img: &mut HdrImage,
        system: &LensSystem,
        frame: &Frame,
        lights: &[LightSpec],
        setup: &StarburstSetup<'_>,
        cache: &mut StarburstCache,
    ) -> anyhow::Result<Vec<StarburstLine>> {
        match &mut self.active {
            Active::Cpu(_) => {
                super::compose::add_starbursts(img, system, frame, lights, setup, cache)
            }
            #[cfg(feature = "gpu")]
            Active::Gpu(renderer) => {
                let (lines, splats) =
                    super::compose::place_starbursts(system, frame, lights, setup, cache)?;
                renderer.add_starbursts(&splats)?;
                *img = renderer.read_back()?;
                self.report.take_passes(renderer.report());
                Ok(lines)
            }
        }
    }

    /// The frame's image as 8-bit sRGB by the backend's own tone pass — the GPU's, of its
    /// output as it stands (ghosts and starbursts, no background); `None` on the CPU, where
    /// the PNG writer maps the image.
    pub fn tone_map(&mut self, tone: &ToneMap) -> anyhow::Result<Option<Vec<u8>>> {
        match &mut self.active {
            Active::Cpu(_) => {
                let _ = tone;
                Ok(None)
            }
            #[cfg(feature = "gpu")]
            Active::Gpu(renderer) => {
                let curve = match tone.operator {
                    crate::output::ToneOperator::Aces => flarebench_gpu::ToneCurve::Aces,
                    crate::output::ToneOperator::Clamp => flarebench_gpu::ToneCurve::Clamp,
                };
                Ok(Some(renderer.tone_map(tone.exposure_ev, curve)?))
            }
        }
    }

    /// Draws every planned ghost into a new image of the frame's size; per light, each
    /// ghost's statistics in plan order.
    pub fn render(
        &mut self,
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        plans: &[LightPlan],
        options: RenderOptions,
    ) -> anyhow::Result<(HdrImage, Vec<Vec<GhostStats>>)> {
        let mut img = HdrImage::new(frame.width, frame.height);
        let stats = self.render_into(system, aperture, frame, plans, options, &mut img)?;
        Ok((img, stats))
    }

    /// Draws every planned ghost into `img`, replacing what it held (a buffer kept from frame
    /// to frame is not cleared first; one of another size is made anew); per light, each
    /// ghost's statistics in plan order. The image is the same, bit for bit, as [`render`]'s.
    ///
    /// [`render`]: GhostBackend::render
    pub fn render_into(
        &mut self,
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        plans: &[LightPlan],
        options: RenderOptions,
        img: &mut HdrImage,
    ) -> anyhow::Result<Vec<Vec<GhostStats>>> {
        match &mut self.active {
            Active::Cpu(scratch) => {
                if (img.width, img.height) != (frame.width, frame.height) {
                    *img = HdrImage::new(frame.width, frame.height);
                }
                Ok(ghosts::render_into_reusing(
                    system,
                    aperture,
                    frame,
                    plans,
                    RenderOptions {
                        replace: true,
                        ..options
                    },
                    scratch,
                    &mut img.pixels,
                )?)
            }
            #[cfg(feature = "gpu")]
            Active::Gpu(renderer) => {
                let t = std::time::Instant::now();
                let stats =
                    ghosts::draw_into(system, aperture, frame, plans, options, renderer.as_mut())?;
                let mesh_ms = t.elapsed().as_secs_f64() * 1e3;
                *img = renderer.read_back()?;
                let r = renderer.report();
                self.report.mesh_ms = Some(mesh_ms);
                self.report.triangles = Some(r.triangles);
                self.report.draw_calls = Some(r.draw_calls);
                self.report.fragments = Some(r.fragments);
                self.report.take_passes(r);
                Ok(stats)
            }
        }
    }
}

impl GhostBackend {
    /// Renders `scene` with plugin instance `inst` into `image`: the plugin's own pixels, and
    /// its mesh drawn by this backend with exact coverage (as the plugin ABI promises) — on
    /// the CPU rasterized into `image`
    /// ([`PluginInstance::render_into`](flarebench_sdk::abi::host::PluginInstance::render_into)),
    /// on the GPU drawn by the ghost renderer as one full-resolution level, read back and added
    /// to the plugin's pixels.
    pub fn render_plugin(
        &mut self,
        inst: &mut flarebench_sdk::abi::host::PluginInstance<'_>,
        scene: &flarebench_sdk::abi::author::Scene,
        values: &[f64],
        image: &mut HdrImage,
    ) -> anyhow::Result<flarebench_sdk::abi::host::RenderStats> {
        match &mut self.active {
            Active::Cpu(_) => Ok(inst.render_into(scene, values, image)?),
            #[cfg(feature = "gpu")]
            Active::Gpu(renderer) => {
                let stats = inst.render_into_sink(scene, values, image, renderer.as_mut())?;
                let mesh = renderer.read_back()?;
                image.add_image(&mesh)?;
                let r = renderer.report();
                self.report.triangles = Some(r.triangles);
                self.report.draw_calls = Some(r.draw_calls);
                self.report.take_passes(r);
                Ok(stats)
            }
        }
    }
}
