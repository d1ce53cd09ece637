//! `--sensor-stack`: put a typical digital camera's sensor stack behind a lens, or take the
//! one its file has away. The preset's values and their sources: docs/physics.md §9.

use anyhow::Context as _;
use clap::{Args, ValueEnum};
use flarebench_sdk::coating::CoatingLayer;
use flarebench_sdk::system::{Plate, SensorStack, SpectralReflectance, SurfaceKind};
use flarebench_sdk::{Coating, GlassCatalog, LensSystem, Medium};

/// The `--sensor-stack` option, shared by the commands that take a lens.
#[derive(Args, Clone, Debug, Default)]
pub struct SensorStackArgs {
    /// Put a sensor stack behind the lens (`digital`: an IR-cut filter, a cover glass and a
    /// sensor reflecting a few percent; docs/physics.md §9), or take away the one its file has
    /// (`none`). Default: the lens file's own (none for most files).
    #[arg(long = "sensor-stack", value_enum, value_name = "STACK")]
    pub sensor_stack: Option<SensorStackPreset>,
}

/// The stacks `--sensor-stack` knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SensorStackPreset {
    /// No sensor stack: the sensor does not reflect (as every lens file without one).
    None,
    /// A full-frame digital camera's stack: a 1.5 mm IR-cut filter (N-BK7) with a four-layer
    /// AR coating on both faces, a 0.5 mm cover glass (N-BK7) with MgF₂ on both faces, and a
    /// sensor reflecting 4–7%.
    Digital,
}

impl SensorStackArgs {
    /// `system` with the stack the option asks for (unchanged without the option).
    pub fn apply(&self, system: LensSystem) -> anyhow::Result<LensSystem> {
        let Some(preset) = self.sensor_stack else {
            return Ok(system);
        };
        let stack = match preset {
            SensorStackPreset::None => None,
            SensorStackPreset::Digital => Some(digital(&system)),
        };
        system
            .with_sensor_stack(stack)
            .map_err(anyhow::Error::msg)
            .with_context(|| format!("could not put the sensor stack behind `{}`", system.name))
    }
}

/// The IR-cut filter's thickness (mm).
pub const IR_CUT_MM: f64 = 1.5;
/// The cover glass's thickness (mm).
pub const COVER_GLASS_MM: f64 = 0.5;
/// Air from the IR-cut filter to the cover glass, and from the cover glass to the sensor (mm).
pub const GAPS_MM: [f64; 2] = [0.5, 0.5];
/// The plates' clear semi-diameter over the sensor's: the larger of its semi-diameter and the
/// film's half diagonal.
pub const PLATE_OVER_SENSOR: f64 = 1.1;
/// The preset's sensor reflectance, (wavelength nm, reflectance).
pub const SENSOR_REFLECTANCE: [(f64, f64); 5] = [
    (380.0, 0.07),
    (450.0, 0.045),
    (550.0, 0.04),
    (650.0, 0.05),
    (780.0, 0.07),
];
/// The IR-cut filter's broadband AR coating, (index, thickness nm), listed from the air
/// side toward the glass: MgF₂ (1.38) and ZrO₂ (2.05), non-dispersive. Found for this preset
/// by a direct search minimising the mean normal-incidence reflectance on N-BK7 over
/// 400–780 nm: about 0.1% from 450 to 650 nm, 1.8% at 400 nm, 1.3% at 780 nm
/// (docs/physics.md §9).
pub const BROADBAND_AR: [(f64, f64); 4] = [(1.38, 98.1), (2.05, 139.7), (1.38, 31.7), (2.05, 16.6)];

/// The `digital` preset for `system`'s sensor (the plates' size follows the sensor's and the
/// film's).
pub fn digital(system: &LensSystem) -> SensorStack {
    let glass = GlassCatalog::bundled()
        .find("SCHOTT:N-BK7")
        .expect("the bundled glass catalogue holds N-BK7");
    let bk7 = Medium::Glass {
        name: glass.canonical_name(),
        dispersion: glass.dispersion.clone(),
    };
    // The plates cover the film's corners and the file's sensor, whichever reaches further.
    let sensor = system
        .surfaces
        .last()
        .filter(|s| s.kind == SurfaceKind::Sensor)
        .map_or(0.0, |s| s.semi_diameter)
        .max(0.5 * system.film_width_mm.hypot(system.film_height_mm));
    // The front face meets air first: the outer (low-index) layer first. The back face is
    // met from the glass: the same design mirrored, listed from the lens side (glass) on.
    let front: Vec<CoatingLayer> = BROADBAND_AR
        .iter()
        .map(|&(index, thickness_nm)| CoatingLayer {
            index,
            thickness_nm,
        })
        .collect();
    let back: Vec<CoatingLayer> = front.iter().rev().copied().collect();
    let mgf2 = Coating::SingleLayer {
        design_wavelength_nm: 550.0,
        index: 1.38,
    };
    let plate = |thickness: f64, gap: f64, front: Coating, back: Coating| Plate {
        medium: bk7.clone(),
        thickness,
        gap,
        semi_diameter: PLATE_OVER_SENSOR * sensor,
        front_coating: front,
        back_coating: back,
    };
    SensorStack::new(
        vec![
            plate(
                IR_CUT_MM,
                GAPS_MM[0],
                Coating::Stack(front),
                Coating::Stack(back),
            ),
            plate(COVER_GLASS_MM, GAPS_MM[1], mgf2.clone(), mgf2),
        ],
        SpectralReflectance::new(SENSOR_REFLECTANCE.to_vec())
            .expect("the preset's reflectance table is well formed"),
    )
}
