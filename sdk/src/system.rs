//! The lens prescription model: surfaces front (object side) to sensor, and their validation.

use crate::glass::Dispersion;
use crate::lens_kind::LensKind;
use crate::spectrum::LAMBDA_D_NM;

pub use crate::coating::{Coating, CoatingLayer};
pub use sensor_stack::{Plate, SensorStack, SpectralReflectance};

mod sensor_stack;

/// What a surface does in the sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceKind {
    /// A refracting (and, for ghosts, reflecting) interface between two media.
    Refracting,
    /// The aperture stop: a flat opening; its semi-diameter is the wide-open radius.
    ApertureStop,
    /// The image plane; always the last surface.
    Sensor,
}

impl SurfaceKind {
    /// The name used in files and tables.
    pub fn name(self) -> &'static str {
        match self {
            SurfaceKind::Refracting => "refracting",
            SurfaceKind::ApertureStop => "stop",
            SurfaceKind::Sensor => "sensor",
        }
    }
}

/// The medium that fills the space after a surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium {
    /// Air (index 1 by the catalogue convention: catalogue indices are relative to air).
    Air,
    /// A model glass from nd and the Abbe number (exact two-term Cauchy fit); `vd: None` is
    /// non-dispersive (a table that gives nd alone, like PBRT's).
    Model { nd: f64, vd: Option<f64> },
    /// A catalogue glass, `name` canonical as `CATALOG:NAME`.
    Glass {
        name: String,
        dispersion: Dispersion,
    },
}

impl Medium {
    /// Refractive index at `lambda_nm`.
    pub fn index(&self, lambda_nm: f64) -> f64 {
        match self {
            Medium::Air => 1.0,
            Medium::Model { nd, vd: None } => *nd,
            Medium::Model { nd, vd: Some(vd) } => {
                Dispersion::cauchy_from_abbe(*nd, *vd).index(lambda_nm)
            }
            Medium::Glass { dispersion, .. } => dispersion.index(lambda_nm),
        }
    }

    /// nd (index at 587.5618 nm).
    pub fn nd(&self) -> f64 {
        match self {
            Medium::Model { nd, .. } => *nd,
            _ => self.index(LAMBDA_D_NM),
        }
    }

    /// Abbe number Vd; `None` for air and non-dispersive media.
    pub fn vd(&self) -> Option<f64> {
        match self {
            Medium::Air => None,
            Medium::Model { vd, .. } => *vd,
            Medium::Glass { dispersion, .. } => Some(dispersion.vd()).filter(|v| v.is_finite()),
        }
    }

    /// True for air.
    pub fn is_air(&self) -> bool {
        matches!(self, Medium::Air)
    }

    /// A short label for tables: the glass name, `air`, or `nd/Vd`.
    pub fn label(&self) -> String {
        match self {
            Medium::Air => "air".to_string(),
            Medium::Model { nd, vd: Some(vd) } => format!("{nd:.5}/{vd:.2}"),
            Medium::Model { nd, vd: None } => format!("{nd:.5}"),
            Medium::Glass { name, .. } => name.clone(),
        }
    }
}

/// One surface of the prescription. Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pub kind: SurfaceKind,
    /// Curvature `c = 1/R` (1/mm); 0 is flat. `c > 0`: centre of curvature toward the sensor.
    pub curvature: f64,
    /// Conic constant k (0 sphere, −1 paraboloid).
    pub conic: f64,
    /// Even-asphere coefficients of r², r⁴, …, r¹⁶ (Zemax EVENASPH PARM 1–8).
    pub aspheric: [f64; 8],
    /// Distance from this vertex to the next one along the axis.
    pub thickness: f64,
    /// Medium between this surface and the next.
    pub medium: Medium,
    /// Clear semi-diameter (mm); for the stop, its wide-open radius.
    pub semi_diameter: f64,
    /// Anti-reflection coating on this interface.
    pub coating: Coating,
    /// Aperture mask image (stops), as named in the file.
    pub mask: Option<String>,
    /// Precomputed Fourier image of the mask (OpenLensFlare `maskFT`), kept for round trips.
    pub mask_ft: Option<String>,
}

impl Surface {
    /// A spherical refracting surface with no coating.
    pub fn spherical(radius: f64, thickness: f64, medium: Medium, semi_diameter: f64) -> Self {
        Surface {
            kind: SurfaceKind::Refracting,
            curvature: curvature_from_radius(radius),
            conic: 0.0,
            aspheric: [0.0; 8],
            thickness,
            medium,
            semi_diameter,
            coating: Coating::None,
            mask: None,
            mask_ft: None,
        }
    }

    /// A flat aperture stop followed by air.
    pub fn stop(thickness: f64, semi_diameter: f64) -> Self {
        Surface {
            kind: SurfaceKind::ApertureStop,
            ..Surface::spherical(0.0, thickness, Medium::Air, semi_diameter)
        }
    }

    /// The sensor plane.
    pub fn sensor(semi_diameter: f64) -> Self {
        Surface {
            kind: SurfaceKind::Sensor,
            ..Surface::spherical(0.0, 0.0, Medium::Air, semi_diameter)
        }
    }

    /// Radius of curvature (mm); `f64::INFINITY` when flat.
    pub fn radius(&self) -> f64 {
        if self.curvature == 0.0 {
            f64::INFINITY
        } else {
            1.0 / self.curvature
        }
    }

    /// True when the surface is not a plain sphere/plane (conic or polynomial terms).
    pub fn is_aspheric(&self) -> bool {
        self.conic != 0.0 || self.aspheric.iter().any(|&a| a != 0.0)
    }

    /// Sag z(r) of the surface at radial distance `r` from the axis; `None` outside the conic's
    /// domain.
    pub fn sag(&self, r: f64) -> Option<f64> {
        let r2 = r * r;
        let c = self.curvature;
        let arg = 1.0 - (1.0 + self.conic) * c * c * r2;
        if arg < 0.0 {
            return None;
        }
        let mut z = c * r2 / (1.0 + arg.sqrt());
        let mut rp = r2;
        for a in self.aspheric {
            z += a * rp;
            rp *= r2;
        }
        Some(z)
    }
}

/// `1/R`, with the file convention that radius 0 (or ±∞) means flat.
pub fn curvature_from_radius(radius: f64) -> f64 {
    if radius == 0.0 || radius.is_infinite() {
        0.0
    } else {
        1.0 / radius
    }
}

/// A lens prescription with its global attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct LensSystem {
    pub name: String,
    /// Who made the lens (`Nikon`, `Carl Zeiss`), for finding it; empty when not known.
    pub maker: String,
    /// What kind of lens it is (prime or zoom, fisheye, macro, …), sorted; empty when not known.
    pub kind: Vec<LensKind>,
    /// The focal length the maker names the lens by (mm): shortest and longest for a zoom,
    /// the same twice for a prime. The prescription's own is `stated_efl_mm` (a zoom's is one
    /// position of its range; a patent's often differs from the marketed one by a few %).
    pub nominal_focal_mm: Option<[f64; 2]>,
    /// The aperture setting: the stop is closed down so the paraxial f-number is at least this;
    /// `None` uses the stop's full semi-diameter.
    pub f_number: Option<f64>,
    /// The focal length the file claims (informational; the paraxial EFL is computed).
    pub stated_efl_mm: Option<f64>,
    /// The full field of view the file claims (degrees, informational).
    pub field_of_view_deg: Option<f64>,
    /// The design's primary wavelength (nm), e.g. Zemax `PWAV`: paraxial data and single-ray
    /// traces default to it; `None` means the d line (587.5618 nm).
    pub primary_wavelength_nm: Option<f64>,
    pub film_width_mm: f64,
    pub film_height_mm: f64,
    /// Free-form notes (patent, caveats).
    pub notes: String,
    /// Where the prescription comes from (file, repository, licence).
    pub source: String,
    /// Surfaces, object side first; the last one is the sensor. With a sensor stack, its
    /// plates' faces are the surfaces in front of the sensor.
    pub surfaces: Vec<Surface>,
    /// The plates in front of the sensor and the sensor's reflectance, when the lens has them
    /// (`sensor_stack.rs`); set with [`LensSystem::with_sensor_stack`], which also puts the
    /// plates' faces into `surfaces`. `None`: the sensor does not reflect.
    pub sensor_stack: Option<SensorStack>,
}

/// One thing wrong with a prescription; readers map it to file, line and column.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidationIssue {
    /// The surface concerned (0-based), or `None` for a system field.
    pub surface: Option<usize>,
    /// The field, named as in our XML (`radius`, `thickness`, `height`, …).
    pub field: &'static str,
    pub message: String,
}

impl std::fmt::Display for ValidationIssue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.surface {
            Some(s) => write!(f, "surface {s}, field `{}`: {}", self.field, self.message),
            None => write!(f, "field `{}`: {}", self.field, self.message),
        }
    }
}

impl LensSystem {
    /// A system with the given surfaces, a 36 × 24 mm film and no f-number setting.
    pub fn new(name: &str, surfaces: Vec<Surface>) -> Self {
        LensSystem {
            name: name.to_string(),
            maker: String::new(),
            kind: Vec::new(),
            nominal_focal_mm: None,
            f_number: None,
            stated_efl_mm: None,
            field_of_view_deg: None,
            primary_wavelength_nm: None,
            film_width_mm: 36.0,
            film_height_mm: 24.0,
            notes: String::new(),
            source: String::new(),
            surfaces,
            sensor_stack: None,
        }
    }

    /// The wavelength paraxial data and single-ray traces default to: the primary wavelength
    /// when the file names one, else the d line.
    pub fn default_wavelength_nm(&self) -> f64 {
        self.primary_wavelength_nm.unwrap_or(LAMBDA_D_NM)
    }

    /// Index of the aperture stop, if there is one.
    pub fn stop_index(&self) -> Option<usize> {
        self.surfaces
            .iter()
            .position(|s| s.kind == SurfaceKind::ApertureStop)
    }

    /// Index of the sensor (the last surface of a valid system).
    pub fn sensor_index(&self) -> usize {
        self.surfaces.len().saturating_sub(1)
    }

    /// Axial position of every vertex, the first at z = 0.
    pub fn vertex_z(&self) -> Vec<f64> {
        let mut z = 0.0;
        self.surfaces
            .iter()
            .map(|s| {
                let here = z;
                z += s.thickness;
                here
            })
            .collect()
    }

    /// Distance from the front vertex to the sensor plane.
    pub fn total_track(&self) -> f64 {
        self.surfaces[..self.sensor_index()]
            .iter()
            .map(|s| s.thickness)
            .sum()
    }

    /// The medium in front of surface `i` (air in object space).
    pub fn medium_before(&self, i: usize) -> &Medium {
        const AIR: &Medium = &Medium::Air;
        if i == 0 {
            AIR
        } else {
            &self.surfaces[i - 1].medium
        }
    }

    /// Refractive index after each surface at `lambda_nm`, and the object-space index first:
    /// `n[0]` is object space, `n[i + 1]` follows surface `i`.
    pub fn indices(&self, lambda_nm: f64) -> Vec<f64> {
        std::iter::once(1.0)
            .chain(self.surfaces.iter().map(|s| s.medium.index(lambda_nm)))
            .collect()
    }

    /// Every problem with the prescription, or `Ok` when it can be traced.
    pub fn validate(&self) -> Result<(), Vec<ValidationIssue>> {
        let mut issues = Vec::new();
        let mut sys = |field: &'static str, message: String| {
            issues.push(ValidationIssue {
                surface: None,
                field,
                message,
            })
        };
        if self.surfaces.len() < 2 {
            sys(
                "elements",
                "a system needs at least one surface and the sensor".into(),
            );
        }
        if let Some(n) = self.f_number
            && !(n.is_finite() && n > 0.0)
        {
            sys("fnumber", format!("must be a positive number, got {n}"));
        }
        if let Some(w) = self.primary_wavelength_nm
            && !(w.is_finite() && w > 0.0)
        {
            sys(
                "primaryWavelength",
                format!("must be a positive wavelength in nm, got {w}"),
            );
        }
        for (field, v) in [
            ("filmWidth", self.film_width_mm),
            ("filmHeight", self.film_height_mm),
        ] {
            if !(v.is_finite() && v > 0.0) {
                sys(field, format!("must be a positive length in mm, got {v}"));
            }
        }
        let stops = self
            .surfaces
            .iter()
            .filter(|s| s.kind == SurfaceKind::ApertureStop)
            .count();
        if stops == 0 {
            sys(
                "type",
                "no aperture stop: one element must have type apertureStop".into(),
            );
        } else if stops > 1 {
            sys(
                "type",
                format!("{stops} aperture stops; exactly one is supported"),
            );
        }
        let last = self.surfaces.len().saturating_sub(1);
        for (i, s) in self.surfaces.iter().enumerate() {
            let mut at = |field: &'static str, message: String| {
                issues.push(ValidationIssue {
                    surface: Some(i),
                    field,
                    message,
                })
            };
            match (s.kind, i == last) {
                (SurfaceKind::Sensor, false) => {
                    at("type", "the sensor must be the last element".into())
                }
                (k, true) if k != SurfaceKind::Sensor && !self.surfaces.is_empty() => {
                    at("type", "the last element must be the sensor".into())
                }
                _ => {}
            }
            if !s.curvature.is_finite() {
                at(
                    "radius",
                    format!("curvature must be finite, got {}", s.curvature),
                );
            }
            if s.kind != SurfaceKind::Refracting && s.curvature != 0.0 {
                at(
                    "radius",
                    format!("a {} must be flat (radius 0)", s.kind.name()),
                );
            }
            if !s.conic.is_finite() {
                at("conic", format!("must be finite, got {}", s.conic));
            }
            if s.aspheric.iter().any(|a| !a.is_finite()) {
                at("aspheric", "coefficients must be finite".into());
            }
            if !(s.thickness.is_finite() && s.thickness >= 0.0) && i != last {
                at(
                    "thickness",
                    format!("must be a finite length ≥ 0 mm, got {}", s.thickness),
                );
            }
            let sd_ok = s.semi_diameter.is_finite()
                && (s.semi_diameter > 0.0
                    || (s.kind == SurfaceKind::Sensor && s.semi_diameter == 0.0));
            if !sd_ok {
                at(
                    "height",
                    format!("semi-diameter must be > 0 mm, got {}", s.semi_diameter),
                );
            } else if s.kind == SurfaceKind::Refracting && s.curvature != 0.0 {
                let r = s.semi_diameter;
                if s.sag(r).is_none() {
                    at(
                        "height",
                        format!(
                            "semi-diameter {r} mm exceeds what the surface allows (|R| = {} mm)",
                            s.radius().abs()
                        ),
                    );
                }
            }
            match &s.medium {
                Medium::Model { nd, vd } => {
                    if !(nd.is_finite() && *nd >= 1.0) {
                        at("refractiveIndex", format!("must be ≥ 1, got {nd}"));
                    }
                    if let Some(v) = vd
                        && !(v.is_finite() && *v > 0.0)
                    {
                        at("abbeNumber", format!("must be a positive number, got {v}"));
                    }
                }
                Medium::Glass { .. } | Medium::Air => {}
            }
            if let Err(m) = s.coating.validate() {
                at("coating", m);
            }
        }
        if let Some(stack) = &self.sensor_stack {
            let mut stack_issue = |message: String| {
                issues.push(ValidationIssue {
                    surface: None,
                    field: "sensorStack",
                    message,
                })
            };
            match self
                .without_sensor_stack()
                .with_sensor_stack(Some(stack.clone()))
            {
                Err(m) => stack_issue(m),
                Ok(rebuilt) if rebuilt != *self => stack_issue(
                    "the surfaces in front of the sensor do not match the sensor stack".into(),
                ),
                Ok(_) => {}
            }
        }
        if issues.is_empty() {
            Ok(())
        } else {
            Err(issues)
        }
    }
}
