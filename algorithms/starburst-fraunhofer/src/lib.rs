//! The Fraunhofer diffraction starburst as a plugin (ABI v1): for every light of the scene, the
//! spectral pattern of the scene's aperture (`sdk::starburst`, `docs/starburst.md`) times the
//! light's flux through the lens, added at the chief ray's landing point — what
//! `flarebench render --starburst only` composes (`workbench/src/compose.rs`), behind
//! [`export_plugin!`](flarebench_sdk::export_plugin).
//!
//! Per light: `sdk::starburst::StarburstLens::add`, the code the workbench's composition runs
//! too — the chief ray's landing point, the light's flux through the lens, the pattern for
//! the scene's aperture (circle or iris: blades, rotation and roundness come with the scene)
//! and the light's spectrum at the lens's working f-number. A light whose chief ray is lost,
//! or whose pattern cannot reach the frame, draws nothing.
//!
//! Parameters: `texels` across the pupil, zero `padding`, `wavelengths` summed
//! ([`StarburstSettings`]). The instance keeps a [`StarburstCache`] between renders — the
//! transforms depend on the aperture and settings only, not on the lens, so it survives a new
//! lens — and `prepare` computes the lens's f-number and interface tables once.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::image::HdrImage;
pub use flarebench_sdk::starburst::FLUX_LAMBDA_NM;
use flarebench_sdk::starburst::{
    StarburstCache, StarburstLens, StarburstLight, StarburstSettings, StarburstSource,
    StarburstTarget,
};

/// What `prepare` keeps of a lens.
#[derive(Debug)]
struct Prepared {
    lens: LensSystem,
    /// Its f-number and direct-flux tables.
    starburst: StarburstLens,
}

/// The plugin: the prepared lens and the starburst cache, kept between renders.
#[derive(Debug, Default)]
pub struct StarburstFraunhofer {
    prepared: Option<Prepared>,
    cache: StarburstCache,
    scratch: GridTrace,
}

impl StarburstFraunhofer {
    /// Fourier transforms computed by this instance so far (one per aperture and settings).
    pub fn transforms(&self) -> usize {
        self.cache.transforms()
    }
}

/// The starburst settings of a set of parameter values, checked.
pub fn settings(params: &Params<'_>) -> Result<StarburstSettings, PluginError> {
    let s = StarburstSettings {
        pupil_texels: params.get_int("texels")? as usize,
        padding: params.get_int("padding")? as usize,
        wavelengths: params.get_int("wavelengths")? as usize,
    };
    s.validate()?;
    Ok(s)
}

impl FlarePlugin for StarburstFraunhofer {
    fn info() -> PluginInfo {
        let d = StarburstSettings::default();
        PluginInfo {
            name: "starburst-fraunhofer",
            version: env!("CARGO_PKG_VERSION"),
            description: "the diffraction starburst: Fraunhofer pattern (FFT) of the aperture, spectral, at each light's chief ray, carrying its flux through the lens",
            kind: PluginKind::Starburst,
            params: vec![
                ParamSpec::int(
                    "texels",
                    "texels across the pupil; the pattern reaches texels·λ·N/2 on the sensor",
                    16,
                    4096,
                    d.pupil_texels as i64,
                ),
                ParamSpec::int(
                    "padding",
                    "zero padding factor: the transform is texels × padding (at most 8192) per side",
                    2,
                    16,
                    d.padding as i64,
                ),
                ParamSpec::int(
                    "wavelengths",
                    "wavelengths summed over 380–780 nm (CIE 1931 weighted)",
                    1,
                    1024,
                    d.wavelengths as i64,
                ),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(StarburstFraunhofer::default())
    }

    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        self.prepared = Some(Prepared {
            lens: lens.clone(),
            starburst: StarburstLens::new(lens)?,
        });
        Ok(())
    }

    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        let settings = settings(params)?;
        let p = self
            .prepared
            .as_ref()
            .ok_or_else(|| PluginError::new("no lens prepared"))?;
        let frame = &scene.frame;
        let mut img = HdrImage::new(frame.width, frame.height);
        let source = StarburstSource {
            aperture: &scene.aperture,
            dust: None,
            settings,
        };
        let mut target = StarburstTarget {
            img: &mut img,
            frame,
        };
        let mut drawn = 0;
        for light in &scene.lights {
            let light = StarburstLight {
                theta_deg: light.theta_deg,
                phi_deg: light.phi_deg,
                intensity: light.intensity,
                spectrum: light.spectrum,
            };
            let o = p.starburst.add(
                &p.lens,
                &mut target,
                &light,
                &source,
                &mut self.cache,
                &mut self.scratch,
            )?;
            drawn += u32::from(o.drawn.is_some());
        }
        out.add_image(&img)?;
        out.items_drawn = drawn;
        Ok(())
    }
}

flarebench_sdk::export_plugin!(StarburstFraunhofer);
