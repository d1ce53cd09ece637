//! The sensor stack: plane-parallel plates behind the last lens surface (an IR-cut filter, a
//! cover glass) and the sensor's own spectral reflectance (docs/physics.md §9).
//!
//! A [`LensSystem`] with a stack holds it twice: as its description
//! ([`LensSystem::sensor_stack`]) and as surfaces, so that the tracer, the ghost enumeration,
//! the bounds and the Monte-Carlo reference need nothing of their own for it. Each plate is two
//! flat refracting surfaces (front face: the plate's glass after it; back face: the image-space
//! medium after it) inserted in front of the sensor. [`LensSystem::with_sensor_stack`] builds
//! them, [`LensSystem::without_sensor_stack`] takes them out again, exactly.
//!
//! **Focus.** A plate of thickness t and index n in a medium of index n₀ moves the paraxial
//! focus back by `t (1 − n₀/n)` (at the d line). The stack keeps the sensor at the lens's
//! focus: the distance from the last lens surface to the sensor grows by the sum of these
//! shifts, and the plates sit in front of the sensor, each `gap` ahead of the next plate (the
//! last one `gap` ahead of the sensor); what is left in front of the first plate is the air
//! gap after the lens. A stack longer than that is an error.

#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "NaN-aware checks of validity: `!(x > 0)` is true for NaN (docs/CODE_STYLE.md)"
)]

use super::{LensSystem, Medium, Surface, SurfaceKind};
use crate::coating::Coating;
use crate::spectrum::LAMBDA_D_NM;

/// The sensor's reflectance as a table of (wavelength nm, reflectance) points, linear between
/// them and constant beyond the first and last; the same at every angle of incidence.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralReflectance {
    points: Vec<(f64, f64)>,
}

impl SpectralReflectance {
    /// The table; wavelengths must be finite, positive and strictly increasing, reflectances
    /// in [0, 1], at least one point. The message says what is wrong.
    pub fn new(points: Vec<(f64, f64)>) -> Result<Self, String> {
        if points.is_empty() {
            return Err("a spectral reflectance needs at least one point".into());
        }
        for (k, &(nm, r)) in points.iter().enumerate() {
            if !(nm.is_finite() && nm > 0.0) {
                return Err(format!(
                    "point {}: the wavelength must be a positive number of nm, got {nm}",
                    k + 1
                ));
            }
            if !(0.0..=1.0).contains(&r) {
                return Err(format!(
                    "point {}: the reflectance must lie in [0, 1], got {r}",
                    k + 1
                ));
            }
            if k > 0 && !(nm > points[k - 1].0) {
                return Err(format!(
                    "point {}: wavelengths must increase, got {nm} nm after {} nm",
                    k + 1,
                    points[k - 1].0
                ));
            }
        }
        Ok(SpectralReflectance { points })
    }

    /// The same reflectance `r` at every wavelength.
    pub fn constant(r: f64) -> Result<Self, String> {
        Self::new(vec![(550.0, r)])
    }

    /// The (wavelength nm, reflectance) points, wavelengths increasing.
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }

    /// The reflectance at `lambda_nm`: linear between points, constant beyond the ends.
    pub fn at(&self, lambda_nm: f64) -> f64 {
        let p = &self.points;
        let (first, last) = (p[0], p[p.len() - 1]);
        if !(lambda_nm > first.0) {
            return first.1;
        }
        if lambda_nm >= last.0 {
            return last.1;
        }
        let i = p.partition_point(|&(nm, _)| nm <= lambda_nm);
        let ((x0, y0), (x1, y1)) = (p[i - 1], p[i]);
        y0 + (y1 - y0) * (lambda_nm - x0) / (x1 - x0)
    }
}

/// One plane-parallel plate of the stack. Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct Plate {
    /// The plate's glass.
    pub medium: Medium,
    /// Thickness along the axis (mm), > 0.
    pub thickness: f64,
    /// Distance from the plate's back face to the next plate's front face, or to the sensor
    /// for the last plate (mm), ≥ 0.
    pub gap: f64,
    /// Clear semi-diameter (mm), > 0.
    pub semi_diameter: f64,
    /// Coating of the face toward the lens, its layers listed from the lens side.
    pub front_coating: Coating,
    /// Coating of the face toward the sensor, its layers listed from the lens side.
    pub back_coating: Coating,
}

/// The plates behind the lens, lens side first, and the sensor's reflectance.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorStack {
    pub plates: Vec<Plate>,
    /// What the sensor reflects back toward the lens.
    pub sensor_reflectance: SpectralReflectance,
    /// The bare lens's distance from its last surface to the sensor, kept so that
    /// [`LensSystem::without_sensor_stack`] restores it bit for bit; set by
    /// [`LensSystem::with_sensor_stack`] (any value given is replaced).
    lens_back_mm: f64,
}

impl SensorStack {
    /// A stack of `plates` in front of a sensor reflecting `sensor_reflectance`.
    pub fn new(plates: Vec<Plate>, sensor_reflectance: SpectralReflectance) -> Self {
        SensorStack {
            plates,
            sensor_reflectance,
            lens_back_mm: f64::NAN,
        }
    }

    /// The bare lens's back distance (last lens surface to sensor, mm) once the stack is in a
    /// system; NaN before.
    pub fn lens_back_mm(&self) -> f64 {
        self.lens_back_mm
    }

    /// Surfaces the stack adds in front of the sensor: two per plate.
    pub fn surface_count(&self) -> usize {
        2 * self.plates.len()
    }

    /// The paraxial focus shift of the plates in a medium of index `n0` (at the d line):
    /// `Σ t (1 − n₀/n)` (mm; > 0 moves the focus toward the sensor's side).
    pub fn focus_shift_mm(&self, n0: f64) -> f64 {
        self.plates
            .iter()
            .map(|p| p.thickness * (1.0 - n0 / p.medium.index(LAMBDA_D_NM)))
            .sum()
    }

    /// The stack's length from the first plate's front face to the sensor (mm).
    pub fn length_mm(&self) -> f64 {
        self.plates.iter().map(|p| p.thickness + p.gap).sum()
    }

    /// Checks the stack's own numbers; each message names the plate and the value.
    pub fn validate(&self) -> Result<(), Vec<String>> {
        let mut issues = Vec::new();
        for (k, p) in self.plates.iter().enumerate() {
            let k = k + 1;
            if !(p.thickness.is_finite() && p.thickness > 0.0) {
                issues.push(format!(
                    "plate {k}: thickness must be > 0 mm, got {}",
                    p.thickness
                ));
            }
            if !(p.gap.is_finite() && p.gap >= 0.0) {
                issues.push(format!("plate {k}: gap must be ≥ 0 mm, got {}", p.gap));
            }
            if !(p.semi_diameter.is_finite() && p.semi_diameter > 0.0) {
                issues.push(format!(
                    "plate {k}: height (semi-diameter) must be > 0 mm, got {}",
                    p.semi_diameter
                ));
            }
            let nd = p.medium.nd();
            if !(nd.is_finite() && nd >= 1.0) {
                issues.push(format!("plate {k}: refractive index must be ≥ 1, got {nd}"));
            }
            for (face, c) in [("front", &p.front_coating), ("back", &p.back_coating)] {
                if let Err(m) = c.validate() {
                    issues.push(format!("plate {k}, {face} face: {m}"));
                }
            }
        }
        // The table is checked when built; a second check keeps `validate` complete.
        if let Err(m) = SpectralReflectance::new(self.sensor_reflectance.points.clone()) {
            issues.push(format!("sensor reflectance: {m}"));
        }
        if issues.is_empty() {
            Ok(())
        } else {
            Err(issues)
        }
    }
}

impl LensSystem {
    /// The same lens with `stack` behind it (replacing any it had), or bare with `None`. The
    /// plates' faces are inserted in front of the sensor and the back distance grows by the
    /// plates' focus shift (module docs). Errors: the stack's own numbers
    /// ([`SensorStack::validate`]), a system without a lens surface in front of the sensor,
    /// and a stack that does not fit between the last lens surface and the sensor.
    pub fn with_sensor_stack(&self, stack: Option<SensorStack>) -> Result<LensSystem, String> {
        let mut out = self.without_sensor_stack();
        let Some(mut stack) = stack else {
            return Ok(out);
        };
        stack.validate().map_err(|m| m.join("; "))?;
        let sensor = out.sensor_index();
        if sensor == 0 || out.surfaces[sensor].kind != SurfaceKind::Sensor {
            return Err("a sensor stack needs a lens in front of the sensor".into());
        }
        let last = sensor - 1;
        let back = out.surfaces[last].thickness;
        let image_medium = out.surfaces[last].medium.clone();
        let n0 = image_medium.index(LAMBDA_D_NM);
        let shift = stack.focus_shift_mm(n0);
        let front_gap = back + shift - stack.length_mm();
        if !(front_gap >= 0.0) {
            return Err(format!(
                "the sensor stack is {:.4} mm long but the lens leaves {:.4} mm behind its last \
                 surface (its back distance {} mm plus the plates' focus shift {:.4} mm)",
                stack.length_mm(),
                back + shift,
                back,
                shift
            ));
        }
        stack.lens_back_mm = back;
        out.surfaces[last].thickness = front_gap;
        let faces = stack.plates.iter().flat_map(|p| {
            let face = |thickness: f64, medium: Medium, coating: Coating| Surface {
                thickness,
                coating,
                ..Surface::spherical(0.0, 0.0, medium, p.semi_diameter)
            };
            [
                face(p.thickness, p.medium.clone(), p.front_coating.clone()),
                face(p.gap, image_medium.clone(), p.back_coating.clone()),
            ]
        });
        let faces: Vec<Surface> = faces.collect();
        out.surfaces.splice(sensor..sensor, faces);
        out.sensor_stack = Some(stack);
        Ok(out)
    }

    /// The bare lens: the stack's surfaces taken out and the back distance restored, bit for
    /// bit; a clone when there is no stack.
    pub fn without_sensor_stack(&self) -> LensSystem {
        let mut out = self.clone();
        let Some(stack) = out.sensor_stack.take() else {
            return out;
        };
        let sensor = out.sensor_index();
        let first = sensor.saturating_sub(stack.surface_count());
        if first == 0 {
            return out;
        }
        out.surfaces.drain(first..sensor);
        out.surfaces[first - 1].thickness = stack.lens_back_mm;
        out
    }

    /// The sensor's reflectance at `lambda_nm` when the system has a sensor stack; `None`
    /// when the sensor does not reflect (no stack: every image is unchanged by this).
    pub fn sensor_reflectance(&self, lambda_nm: f64) -> Option<f64> {
        self.sensor_stack
            .as_ref()
            .map(|s| s.sensor_reflectance.at(lambda_nm))
    }

    /// Index of the first surface of the sensor stack (the first plate's front face, or the
    /// sensor when the stack has no plates); `None` without a stack.
    pub fn sensor_stack_start(&self) -> Option<usize> {
        let stack = self.sensor_stack.as_ref()?;
        self.sensor_index().checked_sub(stack.surface_count())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens() -> LensSystem {
        let glass = Medium::Model {
            nd: 1.5,
            vd: Some(60.0),
        };
        LensSystem::new(
            "singlet",
            vec![
                Surface::spherical(50.0, 4.0, glass, 10.0),
                Surface::stop(1.0, 8.0),
                Surface::spherical(-50.0, 48.3, Medium::Air, 10.0),
                Surface::sensor(21.6),
            ],
        )
    }

    fn plate(t: f64, gap: f64) -> Plate {
        Plate {
            medium: Medium::Model { nd: 1.5, vd: None },
            thickness: t,
            gap,
            semi_diameter: 20.0,
            front_coating: Coating::None,
            back_coating: Coating::None,
        }
    }

    #[test]
    fn reflectance_table_interpolates_linearly_and_holds_its_ends() {
        let r = SpectralReflectance::new(vec![(400.0, 0.1), (500.0, 0.3), (700.0, 0.2)]).unwrap();
        assert_eq!(r.at(300.0), 0.1);
        assert_eq!(r.at(400.0), 0.1);
        assert!((r.at(450.0) - 0.2).abs() < 1e-15);
        assert_eq!(r.at(500.0), 0.3);
        assert!((r.at(600.0) - 0.25).abs() < 1e-15);
        assert_eq!(r.at(800.0), 0.2);
        assert!(SpectralReflectance::new(vec![]).is_err());
        assert!(SpectralReflectance::new(vec![(500.0, 0.1), (500.0, 0.2)]).is_err());
        assert!(SpectralReflectance::new(vec![(500.0, 1.5)]).is_err());
        assert!(SpectralReflectance::new(vec![(f64::NAN, 0.5)]).is_err());
    }

    #[test]
    fn stack_adds_two_faces_per_plate_and_the_focus_shift_and_comes_off_exactly() {
        let bare = lens();
        let stack = SensorStack::new(
            vec![plate(2.0, 0.5), plate(0.5, 1.0)],
            SpectralReflectance::constant(0.05).unwrap(),
        );
        let with = bare.with_sensor_stack(Some(stack)).unwrap();
        assert_eq!(with.surfaces.len(), bare.surfaces.len() + 4);
        assert_eq!(with.sensor_stack_start(), Some(3));
        // t (1 − 1/n) for 2.5 mm of n = 1.5: 2.5/3 mm further to the sensor.
        let shift = 2.5 * (1.0 - 1.0 / 1.5);
        let track = |s: &LensSystem| s.total_track();
        assert!((track(&with) - track(&bare) - shift).abs() < 1e-12);
        assert!((with.surfaces[2].thickness - (48.3 + shift - 4.0)).abs() < 1e-12);
        assert_eq!(with.surfaces[3].medium.nd(), 1.5);
        assert!(with.surfaces[4].medium.is_air());
        assert_eq!(with.surfaces[6].thickness, 1.0);
        assert!(with.validate().is_ok(), "{:?}", with.validate());
        assert_eq!(with.without_sensor_stack(), bare);
        assert_eq!(with.sensor_reflectance(600.0), Some(0.05));
        assert_eq!(bare.sensor_reflectance(600.0), None);
        // Replacing a stack starts from the bare lens.
        let again = with.with_sensor_stack(with.sensor_stack.clone()).unwrap();
        assert_eq!(again, with);
        assert_eq!(with.with_sensor_stack(None).unwrap(), bare);
    }

    #[test]
    fn a_stack_longer_than_the_back_distance_is_refused() {
        let stack = SensorStack::new(
            vec![plate(2.0, 60.0)],
            SpectralReflectance::constant(0.05).unwrap(),
        );
        let e = lens().with_sensor_stack(Some(stack)).unwrap_err();
        assert!(e.contains("62.0000 mm long"), "{e}");
        let thin = SensorStack::new(
            vec![plate(0.0, 1.0)],
            SpectralReflectance::constant(0.05).unwrap(),
        );
        assert!(
            lens()
                .with_sensor_stack(Some(thin))
                .unwrap_err()
                .contains("plate 1: thickness")
        );
    }
}
