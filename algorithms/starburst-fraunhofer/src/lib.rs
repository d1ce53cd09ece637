//! The Fraunhofer diffraction starburst as a plugin (ABI v1): for every light of the scene, the
//! spectral pattern of the scene's aperture (`sdk::starburst`, `docs/starburst.md`) times the
//! light's flux through the lens, added at the chief ray's landing point — what
//! `flarebench render --starburst only` composes (`workbench/src/compose.rs`), behind
//! [`export_plugin!`](flarebench_sdk::export_plugin).
//!
//! Per light: the landing point `starburst::chief_ray_landing` at the d line; the flux
//! `intensity × ghost::bounds::direct_flux(θ)` at 550 nm (the ghost planner's wavelength, so
//! the ghosts' energy shares are relative to the same figure); the pattern for the scene's
//! aperture (circle or iris: blades, rotation and roundness come with the scene) and the
//! light's spectrum; `starburst::add_starburst` at the lens's working f-number. A light whose
//! chief ray is lost, or whose pattern cannot reach the frame, draws nothing.
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
use flarebench_sdk::ghost::bounds::direct_flux;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::{
    StarburstCache, StarburstSettings, add_starburst, chief_ray_landing,
};
use flarebench_sdk::trace::InterfaceTableSet;

/// Wavelength of the direct-flux figure (nm): the ghost planner's, as in the workbench's
/// composition.
pub const FLUX_LAMBDA_NM: f64 = 550.0;

/// Longest wavelength a pattern is summed over (nm): its reach on the sensor is at most
/// `texels · 780 nm · N / 2`.
const LONGEST_NM: f64 = 780.0;

/// What `prepare` keeps of a lens.
#[derive(Debug)]
struct Prepared {
    lens: LensSystem,
    /// Working f-number (paraxial, d line).
    f_number: f64,
    /// Interface tables at [`FLUX_LAMBDA_NM`] for the direct flux.
    tables: InterfaceTableSet,
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
        let f_number = analyse(lens, LAMBDA_D_NM)?.f_number;
        self.prepared = Some(Prepared {
            lens: lens.clone(),
            f_number,
            tables: InterfaceTableSet::for_system(lens, FLUX_LAMBDA_NM),
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
        let reach_mm = settings.pupil_texels as f64 * LONGEST_NM * 1e-6 * p.f_number / 2.0;
        let (hw, hh) = (0.5 * frame.film_width_mm, 0.5 * frame.film_height_mm);
        let mut drawn = 0;
        for light in &scene.lights {
            let theta = light.theta_deg.to_radians();
            let phi = light.phi_deg.to_radians();
            // A lost chief ray: the light does not image (the workbench reports it, draws
            // nothing).
            let Ok(centre) = chief_ray_landing(&p.lens, LAMBDA_D_NM, theta, phi) else {
                continue;
            };
            if centre[0].abs() > hw + reach_mm || centre[1].abs() > hh + reach_mm {
                continue;
            }
            let flux = light.intensity * direct_flux(&p.lens, &p.tables, theta, &mut self.scratch);
            let pattern = self
                .cache
                .pattern(&scene.aperture, None, &settings, light.spectrum)?;
            add_starburst(&mut img, frame, &pattern, centre, p.f_number, flux)?;
            drawn += 1;
        }
        out.add_image(&img)?;
        out.items_drawn = drawn;
        Ok(())
    }
}

flarebench_sdk::export_plugin!(StarburstFraunhofer);
