//! [`StarburstLens`]: the starbursts of a scene's lights through one lens — what the workbench's
//! `render` composes and the `starburst-fraunhofer` plugin draws, so both give one image.
//!
//! Per light: the flux through the lens — its intensity × the direct image's flux at its angle
//! (`ghost::bounds::direct_flux` at [`FLUX_LAMBDA_NM`]; the ghosts' energy shares are relative
//! to the same flux on axis, `ghost::bounds::reference_flux`) — the chief ray's landing point
//! ([`chief_ray_landing`] at the d line, turned by the azimuth as the ghosts' meshes are), and the aperture's spectral pattern for
//! the light's spectrum (from the [`StarburstCache`]) added at the working f-number's scale
//! ([`add_starburst`]). A light whose chief ray is lost, or whose pattern cannot reach the
//! frame (it reaches ±texels·λ·N/2 for λ up to 780 nm), draws nothing.

use std::sync::Arc;

use crate::LensSystem;
use crate::aperture::{Aperture, ApertureMask};
use crate::color::LightSpectrum;
use crate::frame::Frame;
use crate::ghost::GridTrace;
use crate::ghost::bounds::direct_flux;
use crate::image::HdrImage;
use crate::paraxial::{ParaxialError, analyse};
use crate::spectrum::LAMBDA_D_NM;
use crate::trace::InterfaceTableSet;

use super::{
    SplatStats, StarburstCache, StarburstError, StarburstPattern, StarburstSettings, add_starburst,
    chief_ray_landing,
};

/// Wavelength of the direct-flux figure (nm): the ghost planner's bounds wavelength.
pub const FLUX_LAMBDA_NM: f64 = 550.0;

/// Longest wavelength a pattern holds (nm): how far it can reach.
const LONGEST_NM: f64 = 780.0;

/// A light at infinity as the starburst needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StarburstLight {
    /// Angle to the axis and azimuth (degrees).
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Irradiance perpendicular to the beam.
    pub intensity: f64,
    pub spectrum: LightSpectrum,
}

/// The aperture and settings starbursts are made with.
#[derive(Clone, Copy, Debug)]
pub struct StarburstSource<'a> {
    pub aperture: &'a Aperture,
    /// Optional dust/scratch overlay on the aperture.
    pub dust: Option<&'a ApertureMask>,
    pub settings: StarburstSettings,
}

/// The image starbursts are added to and the part of the sensor it shows.
#[derive(Debug)]
pub struct StarburstTarget<'a> {
    pub img: &'a mut HdrImage,
    pub frame: &'a Frame,
}

/// A starburst ready to draw: its pattern, centred at a sensor point, scaled for an f-number,
/// times a flux ([`add_starburst`]'s arguments).
#[derive(Clone, Debug)]
pub struct StarburstSplat {
    pub pattern: Arc<StarburstPattern>,
    /// Where the chief ray lands (sensor mm, lens frame).
    pub centre_mm: [f64; 2],
    pub f_number: f64,
    pub flux: f64,
}

/// What happened to one light's starburst.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StarburstOutcome {
    /// The light's flux through the lens: the starburst's whole energy (image units).
    pub flux: f64,
    /// Where the chief ray lands (sensor mm, lens frame), if it does.
    pub centre_mm: Option<[f64; 2]>,
    /// What was added, when the pattern was drawn.
    pub drawn: Option<SplatStats>,
}

/// What a lens needs for starbursts, found once: its working f-number and the interface
/// tables of the direct-flux figure.
#[derive(Clone, Debug)]
pub struct StarburstLens {
    pub f_number: f64,
    tables: InterfaceTableSet,
}

impl StarburstLens {
    /// Prepares `system`.
    pub fn new(system: &LensSystem) -> Result<Self, ParaxialError> {
        Ok(StarburstLens {
            f_number: analyse(system, LAMBDA_D_NM)?.f_number,
            tables: InterfaceTableSet::for_system(system, FLUX_LAMBDA_NM),
        })
    }

    /// Where the starburst of `light` through `system` (the lens this was prepared for) lands
    /// on `frame`, and its pattern — without drawing it (`outcome.drawn` is `None`): the
    /// splat, or `None` for a light whose chief ray is lost or whose pattern cannot reach the
    /// frame. [`Self::add`] draws it on the CPU; the GPU backend composites it itself.
    pub fn place(
        &self,
        system: &LensSystem,
        frame: &Frame,
        light: &StarburstLight,
        source: &StarburstSource<'_>,
        cache: &mut StarburstCache,
        scratch: &mut GridTrace,
    ) -> Result<(StarburstOutcome, Option<StarburstSplat>), StarburstError> {
        let theta = light.theta_deg.to_radians();
        let phi = light.phi_deg.to_radians();
        let flux = light.intensity * direct_flux(system, &self.tables, theta, scratch);
        let mut outcome = StarburstOutcome {
            flux,
            centre_mm: None,
            drawn: None,
        };
        let Ok(centre) = chief_ray_landing(system, LAMBDA_D_NM, theta, phi) else {
            return Ok((outcome, None));
        };
        outcome.centre_mm = Some(centre);
        let reach_mm =
            source.settings.pupil_texels as f64 * LONGEST_NM * 1e-6 * self.f_number / 2.0;
        let (hw, hh) = (0.5 * frame.film_width_mm, 0.5 * frame.film_height_mm);
        if centre[0].abs() > hw + reach_mm || centre[1].abs() > hh + reach_mm {
            return Ok((outcome, None));
        }
        let pattern = cache.pattern(
            source.aperture,
            source.dust,
            &source.settings,
            light.spectrum,
        )?;
        let splat = StarburstSplat {
            pattern,
            centre_mm: centre,
            f_number: self.f_number,
            flux,
        };
        Ok((outcome, Some(splat)))
    }

    /// Adds the starburst of `light` through `system` (the lens this was prepared for) to
    /// `target`'s image ([`Self::place`], then [`add_starburst`]).
    pub fn add(
        &self,
        system: &LensSystem,
        target: &mut StarburstTarget<'_>,
        light: &StarburstLight,
        source: &StarburstSource<'_>,
        cache: &mut StarburstCache,
        scratch: &mut GridTrace,
    ) -> Result<StarburstOutcome, StarburstError> {
        let (mut outcome, splat) =
            self.place(system, target.frame, light, source, cache, scratch)?;
        if let Some(sp) = splat {
            outcome.drawn = Some(add_starburst(
                target.img,
                target.frame,
                &sp.pattern,
                sp.centre_mm,
                sp.f_number,
                sp.flux,
            )?);
        }
        Ok(outcome)
    }
}
