//! Interaction sequences: which surfaces a ray meets, in what order, and how.

use super::real::Real;
use crate::system::{Coating, LensSystem, SurfaceKind};

/// What happens at a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Interaction {
    /// Refraction into the medium on the far side.
    Refract,
    /// Specular reflection back into the medium the ray came from.
    Reflect,
    /// The sensor plane: the ray is stopped there, nothing else happens.
    Sensor,
}

/// One surface interaction with everything the per-ray physics needs, in the tracer's float.
#[derive(Clone, Copy, Debug)]
pub struct Step<T> {
    /// Index of the surface in the [`LensSystem`].
    pub surface: usize,
    pub interaction: Interaction,
    /// True when the ray travels toward the sensor (+z order) as it arrives.
    pub forward: bool,
    /// Vertex position on the axis (mm).
    pub z: T,
    /// Curvature (1/mm) and conic constant.
    pub c: T,
    pub k: T,
    /// Even-asphere coefficients of r², …, r¹⁶, used when `aspheric`.
    pub asph: [T; 8],
    pub aspheric: bool,
    /// Clear semi-diameter here (the working opening for the stop); `inv_semi2` = 1/semi²,
    /// 0 where nothing clips (the sensor).
    pub semi: T,
    pub inv_semi2: T,
    /// Index on the arrival side and on the far side (for a reflection, the far side is the
    /// medium the ray does not enter; Fresnel needs it).
    pub n_from: f64,
    pub n_to: f64,
    /// `n_from / n_to`, the refraction ratio.
    pub eta: T,
    /// Index into [`Sequence::tables`] of this interface's Fresnel/coating factor, when the
    /// sequence carries tables.
    pub table: Option<u32>,
    /// True on the ray's last pass through the aperture stop: batches record the crossing.
    pub record_stop: bool,
}

/// Entries per interface table (uniform in cos θ from 0 to 1).
pub const TABLE_LEN: usize = 256;

/// An interface's transmittance (refraction) or reflectance (reflection) as a function of the
/// cosine of the angle of incidence, tabulated for linear interpolation in the batch kernel.
#[derive(Clone, Debug)]
pub struct InterfaceTable<T> {
    pub values: [T; TABLE_LEN],
}

impl<T: Real> InterfaceTable<T> {
    /// Linear interpolation at `cos` (clamped to [0, 1]; NaN reads entry 0).
    #[inline(always)]
    pub fn at(&self, cos: T) -> T {
        let scale = T::of((TABLE_LEN - 1) as f64);
        let x = (cos * scale).max(T::zero()).min(scale);
        let i = x.to_index().min(TABLE_LEN - 2);
        let f = x - T::of(i as f64);
        let (a, b) = (self.values[i], self.values[i + 1]);
        a + f * (b - a)
    }
}

/// Why a path could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PathError {
    #[error("surface {0} does not exist or cannot reflect (only refracting surfaces can)")]
    NotReflecting(usize),
    #[error(
        "a ghost reflects first at a later surface, then at an earlier one: got {first} then {second}"
    )]
    Order { first: usize, second: usize },
    #[error("surface {0} is out of range")]
    OutOfRange(usize),
}

/// Every interface's Fresnel/coating tables at one wavelength: for each surface that is a real
/// boundary, the transmittance and reflectance for light arriving from either side.
#[derive(Clone, Debug)]
pub struct InterfaceTableSet {
    pub lambda_nm: f64,
    /// Indexed by surface: `[forward T, forward R, backward T, backward R]`, `None` where the
    /// surface is not a boundary (no index step, no coating).
    tables: Vec<Option<Box<[InterfaceTable<f64>; 4]>>>,
}

impl InterfaceTableSet {
    /// The tables of `system` at `lambda_nm`.
    pub fn for_system(system: &LensSystem, lambda_nm: f64) -> Self {
        let seq = Sequence::forward(system, lambda_nm);
        Self::new(&seq.coatings, &seq.steps, lambda_nm)
    }

    fn new(coatings: &[Coating], steps: &[Step<f64>], lambda_nm: f64) -> Self {
        let mut tables: Vec<Option<Box<[InterfaceTable<f64>; 4]>>> = vec![None; coatings.len()];
        for s in steps {
            if tables[s.surface].is_some() || s.interaction == Interaction::Sensor {
                continue;
            }
            let coating = &coatings[s.surface];
            if s.n_from == s.n_to && *coating == Coating::None {
                continue;
            }
            // Indices on the object side and the sensor side of the surface.
            let (n_before, n_after) = if s.forward {
                (s.n_from, s.n_to)
            } else {
                (s.n_to, s.n_from)
            };
            let table = |forward: bool, reflect: bool| {
                let (n1, n2) = if forward {
                    (n_before, n_after)
                } else {
                    (n_after, n_before)
                };
                let mut values = [0.0; TABLE_LEN];
                for (j, v) in values.iter_mut().enumerate() {
                    let cos = j as f64 / (TABLE_LEN - 1) as f64;
                    let r = coating.reflectance(n1, n2, cos, lambda_nm, forward);
                    *v = if reflect { r } else { 1.0 - r };
                }
                InterfaceTable { values }
            };
            tables[s.surface] = Some(Box::new([
                table(true, false),
                table(true, true),
                table(false, false),
                table(false, true),
            ]));
        }
        InterfaceTableSet { lambda_nm, tables }
    }

    /// The table for light meeting `surface` travelling `forward` (toward the sensor) and
    /// doing `interaction`.
    pub fn get(
        &self,
        surface: usize,
        forward: bool,
        interaction: Interaction,
    ) -> Option<&InterfaceTable<f64>> {
        let set = self.tables.get(surface)?.as_ref()?;
        let k = match (forward, interaction) {
            (_, Interaction::Sensor) => return None,
            (true, Interaction::Refract) => 0,
            (true, Interaction::Reflect) => 1,
            (false, Interaction::Refract) => 2,
            (false, Interaction::Reflect) => 3,
        };
        Some(&set[k])
    }
}

/// The interactions a ray goes through for one wavelength.
#[derive(Clone, Debug)]
pub struct Sequence<T> {
    pub steps: Vec<Step<T>>,
    pub lambda_nm: f64,
    /// The coating of each surface of the system (for intensities along the path).
    pub coatings: Vec<Coating>,
    /// Interface factor tables referenced by [`Step::table`] (empty unless built).
    pub tables: Vec<InterfaceTable<T>>,
}

impl Sequence<f64> {
    /// Object space to the sensor, refracting at every surface; the stop clips at its working
    /// opening (the system's f-number setting).
    pub fn forward(system: &LensSystem, lambda_nm: f64) -> Self {
        let sensor = system.sensor_index();
        let mut path: Vec<(usize, Interaction)> =
            (0..sensor).map(|s| (s, Interaction::Refract)).collect();
        path.push((sensor, Interaction::Sensor));
        Self::build(system, lambda_nm, true, &path)
    }

    /// A two-reflection ghost: forward to surface `first`, reflect; back to `second < first`,
    /// reflect; forward to the sensor.
    pub fn ghost(
        system: &LensSystem,
        lambda_nm: f64,
        first: usize,
        second: usize,
    ) -> Result<Self, PathError> {
        let sensor = system.sensor_index();
        for s in [first, second] {
            if s >= sensor || system.surfaces[s].kind != SurfaceKind::Refracting {
                return Err(PathError::NotReflecting(s));
            }
        }
        if second >= first {
            return Err(PathError::Order { first, second });
        }
        let mut path: Vec<(usize, Interaction)> =
            (0..first).map(|s| (s, Interaction::Refract)).collect();
        path.push((first, Interaction::Reflect));
        path.extend((second + 1..first).rev().map(|s| (s, Interaction::Refract)));
        path.push((second, Interaction::Reflect));
        path.extend((second + 1..sensor).map(|s| (s, Interaction::Refract)));
        path.push((sensor, Interaction::Sensor));
        Ok(Self::build(system, lambda_nm, true, &path))
    }

    /// An arbitrary sequence. `start_forward` says whether the ray starts travelling toward
    /// the sensor; it flips at each reflection.
    pub fn custom(
        system: &LensSystem,
        lambda_nm: f64,
        start_forward: bool,
        path: &[(usize, Interaction)],
    ) -> Result<Self, PathError> {
        if let Some(&(s, _)) = path.iter().find(|(s, _)| *s >= system.surfaces.len()) {
            return Err(PathError::OutOfRange(s));
        }
        Ok(Self::build(system, lambda_nm, start_forward, path))
    }

    fn build(
        system: &LensSystem,
        lambda_nm: f64,
        start_forward: bool,
        path: &[(usize, Interaction)],
    ) -> Self {
        let n = system.indices(lambda_nm);
        let z = system.vertex_z();
        let stop_semi = crate::paraxial::stop_opening(system);
        let mut forward = start_forward;
        let steps = path
            .iter()
            .map(|&(s, interaction)| {
                let surf = &system.surfaces[s];
                // n[s] is before surface s, n[s + 1] after it.
                let (n_from, n_to) = if forward {
                    (n[s], n[s + 1])
                } else {
                    (n[s + 1], n[s])
                };
                let semi = match surf.kind {
                    SurfaceKind::ApertureStop => stop_semi,
                    _ => surf.semi_diameter,
                };
                let inv_semi2 = if interaction == Interaction::Sensor || semi <= 0.0 {
                    0.0
                } else {
                    1.0 / (semi * semi)
                };
                let step = Step {
                    surface: s,
                    interaction,
                    forward,
                    z: z[s],
                    c: surf.curvature,
                    k: surf.conic,
                    asph: surf.aspheric,
                    aspheric: surf.aspheric.iter().any(|&a| a != 0.0),
                    semi,
                    inv_semi2,
                    n_from,
                    n_to,
                    eta: n_from / n_to,
                    table: None,
                    record_stop: false,
                };
                if interaction == Interaction::Reflect {
                    forward = !forward;
                }
                step
            })
            .collect();
        // Only a real boundary reflects: not the stop or the sensor, and not a dummy surface
        // with the same index on both sides (a coating there would coat nothing).
        let coatings = system
            .surfaces
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let boundary = s.kind == SurfaceKind::Refracting && n[i] != n[i + 1];
                if boundary {
                    s.coating.clone()
                } else {
                    Coating::None
                }
            })
            .collect();
        let mut seq = Sequence {
            steps,
            lambda_nm,
            coatings,
            tables: Vec::new(),
        };
        // Batches record where a ray crosses the stop on its last pass (the aperture mask's UV).
        if let Some(stop) = system.stop_index()
            && let Some(last) = seq.steps.iter().rposition(|s| s.surface == stop)
        {
            seq.steps[last].record_stop = true;
        }
        seq
    }

    /// Leaves the stop crossing that batches record (the last pass) unclipped, for renderers
    /// that apply the aperture's own shape there from the recorded crossing; other passes
    /// through the stop still clip at its working radius.
    pub fn aperture_by_mask(mut self) -> Self {
        if let Some(s) = self.steps.iter_mut().rfind(|s| s.record_stop) {
            s.inv_semi2 = 0.0;
        }
        self
    }

    /// Builds the Fresnel/coating factor table of every step that changes a ray's weight
    /// (a refraction or reflection at a real boundary), so batches track the throughput.
    pub fn with_interface_tables(self) -> Self {
        let set = InterfaceTableSet::new(&self.coatings, &self.steps, self.lambda_nm);
        self.with_tables_from(&set)
    }

    /// Like [`Self::with_interface_tables`], copying the tables from a set built once per lens
    /// and wavelength (many ghost paths share the same interfaces).
    pub fn with_tables_from(mut self, set: &InterfaceTableSet) -> Self {
        self.tables.clear();
        for i in 0..self.steps.len() {
            let s = self.steps[i];
            self.steps[i].table = set.get(s.surface, s.forward, s.interaction).map(|t| {
                self.tables.push(t.clone());
                (self.tables.len() - 1) as u32
            });
        }
        self
    }

    /// The same sequence in another float type (geometry rounded once, here).
    pub fn cast<U: Real>(&self) -> Sequence<U> {
        Sequence {
            steps: self
                .steps
                .iter()
                .map(|s| Step {
                    surface: s.surface,
                    interaction: s.interaction,
                    forward: s.forward,
                    z: U::of(s.z),
                    c: U::of(s.c),
                    k: U::of(s.k),
                    asph: s.asph.map(U::of),
                    aspheric: s.aspheric,
                    semi: U::of(s.semi),
                    inv_semi2: U::of(s.inv_semi2),
                    n_from: s.n_from,
                    n_to: s.n_to,
                    eta: U::of(s.eta),
                    table: s.table,
                    record_stop: s.record_stop,
                })
                .collect(),
            lambda_nm: self.lambda_nm,
            coatings: self.coatings.clone(),
            tables: self
                .tables
                .iter()
                .map(|t| InterfaceTable {
                    values: t.values.map(U::of),
                })
                .collect(),
        }
    }
}

impl<T: Real> Sequence<T> {
    /// Number of ray–surface steps per ray.
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    /// True when there are no steps.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
}
