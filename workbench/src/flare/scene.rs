//! What a flare frame is of: the lens, the lights, the aperture, the part of the sensor the
//! output shows, and whether it holds ghosts, starbursts or both. Every command and the viewer
//! describe their frames with it, so the pipeline that draws them is written once
//! ([`super::Flare`]).

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::{Aperture, ApertureMask};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::starburst::StarburstSettings;
use ghost_raytrace::scene::LightSpec;

use super::compose::StarburstSetup;

/// What the flare is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StarburstMode {
    /// Ghosts and starbursts.
    On,
    /// Ghosts only.
    Off,
    /// Starbursts only.
    Only,
}

impl StarburstMode {
    /// True when ghosts are drawn.
    pub fn ghosts(self) -> bool {
        self != StarburstMode::Only
    }

    /// True when starbursts are added.
    pub fn starbursts(self) -> bool {
        self != StarburstMode::Off
    }
}

/// The output frame: `size` pixels spanning the film's width, the height following the
/// aspect ratio.
pub fn frame_for(sys: &LensSystem, (w, h): (usize, usize)) -> Frame {
    Frame {
        width: w,
        height: h,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * h as f64 / w as f64,
    }
}

/// One flare frame's scene.
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    pub system: &'a LensSystem,
    pub lights: &'a [LightSpec],
    pub aperture: &'a Aperture,
    /// The output image and the part of the sensor it shows.
    pub frame: Frame,
    pub starburst: StarburstMode,
    /// How the starbursts are computed (wavelengths, texels, padding).
    pub starburst_settings: StarburstSettings,
    /// A dust or scratch overlay on the aperture for the starbursts.
    pub dust: Option<&'a ApertureMask>,
}

impl<'a> Scene<'a> {
    /// Ghosts and starbursts of `lights` on `frame`, the starbursts by the default settings
    /// without dust.
    pub fn new(
        system: &'a LensSystem,
        lights: &'a [LightSpec],
        aperture: &'a Aperture,
        frame: Frame,
    ) -> Scene<'a> {
        Scene {
            system,
            lights,
            aperture,
            frame,
            starburst: StarburstMode::On,
            starburst_settings: StarburstSettings::default(),
            dust: None,
        }
    }

    /// The aperture, dust and settings the starbursts are made with.
    pub fn starburst_setup(&self) -> StarburstSetup<'a> {
        StarburstSetup {
            aperture: self.aperture,
            dust: self.dust,
            settings: self.starburst_settings,
        }
    }
}
