//! Interaction sequences: which surfaces a ray meets, in what order, and how.

use super::real::Real;
use crate::ghost_path::GhostPath;
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

/// Entries per interface table (uniform in its variable from 0 to 1: [`InterfaceTable`]).
pub const TABLE_LEN: usize = 256;

/// An interface's transmittance (refraction) or reflectance (reflection) as a function of the
/// angle of incidence, tabulated for linear interpolation in the batch kernel.
///
/// Light arriving from the rarer medium is tabulated in the cosine of incidence `c`. Light
/// arriving from the denser medium (`n1 > n2`) is tabulated in the cosine of refraction
/// `w = √(1 − k (1 − c²))`, `k = (n1/n2)²`: near the critical angle the reflectance rises to 1
/// as `√(c − c_crit)`, which no uniform table in `c` follows (256 entries in `c` were 0.9% off
/// in reflectance a thousandth of a cosine above it), while in `w` it is smooth; `w = 0` is the
/// critical angle, and every angle beyond it (total internal reflection) reads entry 0.
#[derive(Clone, Debug)]
pub struct InterfaceTable<T> {
    pub values: [T; TABLE_LEN],
    /// `k = (n1/n2)²` when the table runs in the refracted cosine `w`; 1 when it runs in `c`.
    pub k: T,
}

impl<T: Real> InterfaceTable<T> {
    /// A table in the cosine of incidence.
    pub fn in_cosine(values: [T; TABLE_LEN]) -> Self {
        InterfaceTable {
            values,
            k: T::one(),
        }
    }

    /// Linear interpolation at incidence cosine `cos` (clamped to [0, 1]; NaN reads entry 0).
    #[inline(always)]
    pub fn at(&self, cos: T) -> T {
        let var = if self.k > T::one() {
            (T::one() - self.k * (T::one() - cos * cos))
                .max(T::zero())
                .sqrt()
        } else {
            cos
        };
        let scale = T::of((TABLE_LEN - 1) as f64);
        let x = (var * scale).max(T::zero()).min(scale);
        let i = x.to_index().min(TABLE_LEN - 2);
        let f = x - T::of(i as f64);
        let (a, b) = (self.values[i], self.values[i + 1]);
        a + f * (b - a)
    }
}

/// The table variable's `k` for light from index `n1` into `n2` ([`InterfaceTable`]).
pub fn table_k(n1: f64, n2: f64) -> f64 {
    if n1 > n2 { (n1 / n2).powi(2) } else { 1.0 }
}

/// The cosine of incidence at entry `j` of a table with variable coefficient `k`.
pub fn entry_cos(j: usize, k: f64) -> f64 {
    let w = j as f64 / (TABLE_LEN - 1) as f64;
    if k > 1.0 {
        (1.0 - (1.0 - w * w) / k).sqrt()
    } else {
        w
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
    #[error(
        "a four-reflection ghost reflects a third time at a later surface than the second: got {second} then {third}"
    )]
    ThirdOrder { second: usize, third: usize },
    #[error(
        "a four-reflection ghost reflects a fourth time at an earlier surface than the third: got {third} then {fourth}"
    )]
    FourthOrder { third: usize, fourth: usize },
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
        Self::new(&seq.coatings, &seq.steps, lambda_nm, seq.sensor_reflectance)
    }

    fn new(
        coatings: &[Coating],
        steps: &[Step<f64>],
        lambda_nm: f64,
        sensor_reflectance: Option<f64>,
    ) -> Self {
        let mut tables: Vec<Option<Box<[InterfaceTable<f64>; 4]>>> = vec![None; coatings.len()];
        for b in boundaries(coatings, steps) {
            // Transmittance and reflectance tables for one direction, from one evaluation
            // of the coating per entry.
            let tables_for = |forward: bool| {
                let mut t = [0.0; TABLE_LEN];
                let mut r = [0.0; TABLE_LEN];
                for (j, (t, r)) in t.iter_mut().zip(&mut r).enumerate() {
                    *r = b.reflectance(j, lambda_nm, forward);
                    *t = 1.0 - *r;
                }
                let k = b.k(forward);
                (
                    InterfaceTable { values: t, k },
                    InterfaceTable { values: r, k },
                )
            };
            let (forward_t, forward_r) = tables_for(true);
            let (backward_t, backward_r) = tables_for(false);
            tables[b.surface] = Some(Box::new([forward_t, forward_r, backward_t, backward_r]));
        }
        if let Some(r) = sensor_reflectance
            && let Some(last) = tables.last_mut()
        {
            *last = Some(sensor_tables(r));
        }
        InterfaceTableSet { lambda_nm, tables }
    }

    /// The tables of `system` at `lambda_nm` from `a` and `b`, its tables at two wavelengths
    /// around it: [`InterfaceTableSet::interpolate`], except for the entries where the two
    /// differ by more than [`BETWEEN_EXACT_ABOVE`] (where a critical angle moves with the
    /// wavelength) and the surfaces coated with a stack of layers, which are evaluated
    /// exactly. Bare and single-layer surfaces between tables 10 nm apart are within 2e-4 of
    /// the exact tables (the test `tables_between_two_follow_the_exact_ones`), at about a
    /// quarter of the cost of building them (callgrind, the Heliar's bands). Tables of
    /// another layout (another system's) are not used: the result is then built exactly.
    pub fn between(system: &LensSystem, lambda_nm: f64, a: &Self, b: &Self) -> Self {
        let seq = Sequence::forward(system, lambda_nm);
        let bounds: Vec<Boundary<'_>> = boundaries(&seq.coatings, &seq.steps).collect();
        let fits = |s: &Self| {
            s.tables.len() == seq.coatings.len()
                && bounds.iter().all(|bd| s.tables[bd.surface].is_some())
        };
        if !(fits(a) && fits(b)) {
            return Self::new(&seq.coatings, &seq.steps, lambda_nm, seq.sensor_reflectance);
        }
        let mut out = Self::interpolate(a, b, lambda_nm);
        // The sensor's reflectance is a table in wavelength (its own points, not two of ours):
        // exact, not interpolated.
        if let Some(r) = seq.sensor_reflectance
            && let Some(last) = out.tables.last_mut()
        {
            *last = Some(sensor_tables(r));
        }
        for bd in &bounds {
            let (Some(ta), Some(tb), Some(to)) = (
                &a.tables[bd.surface],
                &b.tables[bd.surface],
                &mut out.tables[bd.surface],
            ) else {
                continue; // every boundary has tables in both (checked above), so in `out`
            };
            // A stack of layers may change its reflectance fast with the wavelength (a
            // four-layer broadband stack is off by 4e-3 halfway between tables 10 nm apart):
            // evaluated exactly throughout.
            let stack = matches!(bd.coating, Coating::Stack(_));
            for (k, forward) in [(1, true), (3, false)] {
                // The interpolated entries run in the interpolated variable; the exact ones
                // (and so the table) in this wavelength's.
                to[k].k = bd.k(forward);
                to[k - 1].k = to[k].k;
                for j in 0..TABLE_LEN {
                    if stack || (ta[k].values[j] - tb[k].values[j]).abs() > BETWEEN_EXACT_ABOVE {
                        let r = bd.reflectance(j, lambda_nm, forward);
                        to[k].values[j] = r;
                        to[k - 1].values[j] = 1.0 - r;
                    }
                }
            }
        }
        out
    }

    /// The tables at `lambda_nm` interpolated linearly in wavelength between `a` and `b`, the
    /// same system's tables at two wavelengths (either order; `lambda_nm` is clamped to the
    /// range between them). A surface without tables in either keeps `a`'s.
    ///
    /// Coatings and dispersion vary slowly with wavelength, except where a critical angle
    /// moves with it (total internal reflection sets in at a wavelength-dependent angle):
    /// [`InterfaceTableSet::between`] evaluates those entries exactly.
    pub fn interpolate(a: &Self, b: &Self, lambda_nm: f64) -> Self {
        let span = b.lambda_nm - a.lambda_nm;
        let t = if span != 0.0 && span.is_finite() {
            ((lambda_nm - a.lambda_nm) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let tables = a
            .tables
            .iter()
            .enumerate()
            .map(|(k, ta)| {
                let ta = ta.as_ref()?;
                let Some(Some(tb)) = b.tables.get(k) else {
                    return Some(ta.clone());
                };
                let mut out = ta.clone();
                for (o, q) in out.iter_mut().zip(tb.iter()) {
                    for (v, w) in o.values.iter_mut().zip(&q.values) {
                        *v += t * (w - *v);
                    }
                    o.k += t * (q.k - o.k);
                }
                Some(out)
            })
            .collect();
        InterfaceTableSet { lambda_nm, tables }
    }

    /// These tables with the reflectance of light meeting `surface` travelling `forward`
    /// replaced by `f` of the cosine of incidence (its transmittance kept): a renderer traced
    /// with them weighs each ray by `f` where it reflects there. `None` when `surface` has no
    /// tables. (A coating fit renders a ghost with `f` a hat function of the angle, to know
    /// how its light splits over angles of incidence.)
    pub fn with_reflectance(
        &self,
        surface: usize,
        forward: bool,
        f: impl Fn(f64) -> f64,
    ) -> Option<InterfaceTableSet> {
        let mut out = self.clone();
        let set = out.tables.get_mut(surface)?.as_mut()?;
        let table = &mut set[if forward { 1 } else { 3 }];
        let k = table.k;
        for (j, v) in table.values.iter_mut().enumerate() {
            *v = f(entry_cos(j, k));
        }
        Some(out)
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

/// The sensor's tables when it reflects `r` at every angle (its spectral reflectance at the
/// set's wavelength): only the forward reflection is ever read (the sensor ends every other
/// path); the forward transmittance `1 − r` is what it absorbs.
fn sensor_tables(r: f64) -> Box<[InterfaceTable<f64>; 4]> {
    let t = InterfaceTable::in_cosine([1.0 - r; TABLE_LEN]);
    let r = InterfaceTable::in_cosine([r; TABLE_LEN]);
    Box::new([t.clone(), r.clone(), t, r])
}

/// Entries of two neighbouring tables that differ by more than this are evaluated exactly by
/// [`InterfaceTableSet::between`] rather than interpolated.
pub const BETWEEN_EXACT_ABOVE: f64 = 2e-3;

/// A surface that is a real boundary: its coating and the indices on its object and sensor
/// sides.
struct Boundary<'a> {
    surface: usize,
    coating: &'a Coating,
    n_before: f64,
    n_after: f64,
}

impl Boundary<'_> {
    /// Reflectance at table entry `j` for light travelling `forward` (toward the sensor).
    fn reflectance(&self, j: usize, lambda_nm: f64, forward: bool) -> f64 {
        let (n1, n2) = self.indices(forward);
        let cos = entry_cos(j, table_k(n1, n2));
        self.coating.reflectance(n1, n2, cos, lambda_nm, forward)
    }

    /// The indices before and after the boundary for light travelling `forward`.
    fn indices(&self, forward: bool) -> (f64, f64) {
        if forward {
            (self.n_before, self.n_after)
        } else {
            (self.n_after, self.n_before)
        }
    }

    /// The table variable's `k` for light travelling `forward`.
    fn k(&self, forward: bool) -> f64 {
        let (n1, n2) = self.indices(forward);
        table_k(n1, n2)
    }
}

/// The boundaries a forward sequence's steps cross, each surface once: those with an index
/// step or a coating.
fn boundaries<'a>(
    coatings: &'a [Coating],
    steps: &'a [Step<f64>],
) -> impl Iterator<Item = Boundary<'a>> {
    let mut seen = vec![false; coatings.len()];
    steps.iter().filter_map(move |s| {
        if s.interaction == Interaction::Sensor || std::mem::replace(&mut seen[s.surface], true) {
            return None;
        }
        let coating = &coatings[s.surface];
        if s.n_from == s.n_to && *coating == Coating::None {
            return None;
        }
        let (n_before, n_after) = if s.forward {
            (s.n_from, s.n_to)
        } else {
            (s.n_to, s.n_from)
        };
        Some(Boundary {
            surface: s.surface,
            coating,
            n_before,
            n_after,
        })
    })
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
    /// The sensor's reflectance at `lambda_nm` when it reflects (a lens with a sensor stack,
    /// [`LensSystem::sensor_reflectance`]); `None` otherwise.
    pub sensor_reflectance: Option<f64>,
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
    /// reflect; forward to the sensor. [`Self::ghost_path`] with [`GhostPath::two`].
    pub fn ghost(
        system: &LensSystem,
        lambda_nm: f64,
        first: usize,
        second: usize,
    ) -> Result<Self, PathError> {
        Self::ghost_path(system, lambda_nm, &GhostPath::two(first, second))
    }

    /// The sequence of a ghost path of two or four reflections: forward to the first
    /// reflection, back to the second, (forward to the third, back to the fourth,) then forward
    /// to the sensor, refracting at every surface in between. Checks that every reflection is
    /// at a refracting surface and the order `a > b` (`a > b < c > d`).
    pub fn ghost_path(
        system: &LensSystem,
        lambda_nm: f64,
        ghost: &GhostPath,
    ) -> Result<Self, PathError> {
        let sensor = system.sensor_index();
        let r = ghost.reflections();
        // The sensor reflects when it has a reflectance (a sensor stack), and only light
        // arriving at it: the first or third reflection.
        let sensor_reflects = system.sensor_reflectance(lambda_nm).is_some();
        for (k, &s) in r.iter().enumerate() {
            let at_sensor = s == sensor && sensor_reflects && k % 2 == 0;
            if !at_sensor && (s >= sensor || system.surfaces[s].kind != SurfaceKind::Refracting) {
                return Err(PathError::NotReflecting(s));
            }
        }
        if r[1] >= r[0] {
            return Err(PathError::Order {
                first: r[0],
                second: r[1],
            });
        }
        if let [_, second, third, fourth] = *r {
            if third <= second {
                return Err(PathError::ThirdOrder { second, third });
            }
            if fourth >= third {
                return Err(PathError::FourthOrder { third, fourth });
            }
        }
        // From the entrance plane forward to the first reflection, then between reflections
        // alternately back and forward, then forward from the last one to the sensor.
        let mut path: Vec<(usize, Interaction)> = Vec::new();
        let mut at: Option<usize> = None;
        for (k, &s) in r.iter().enumerate() {
            match at {
                None => path.extend((0..s).map(|i| (i, Interaction::Refract))),
                // Even k: travelling forward from the previous reflection.
                Some(p) if k % 2 == 0 => {
                    path.extend((p + 1..s).map(|i| (i, Interaction::Refract)));
                }
                Some(p) => path.extend((s + 1..p).rev().map(|i| (i, Interaction::Refract))),
            }
            path.push((s, Interaction::Reflect));
            at = Some(s);
        }
        let last = at.expect("a path has reflections");
        path.extend((last + 1..sensor).map(|s| (s, Interaction::Refract)));
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
        let film_half_diagonal = 0.5 * system.film_width_mm.hypot(system.film_height_mm);
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
                    // The sensor clips only where it reflects (a sensor stack): over the film,
                    // whose corners may lie beyond a file's sensor semi-diameter.
                    SurfaceKind::Sensor => surf.semi_diameter.max(film_half_diagonal),
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
            sensor_reflectance: system.sensor_reflectance(lambda_nm),
        };
        // Batches record where a ray crosses the stop on its last pass (the aperture mask's UV);
        // every other pass clips at the stop's working radius (a circle), so the iris's shape
        // is taken from the last pass. Ghosts of two and four reflections follow one rule, the
        // last time the light goes through the iris before the sensor: on the final forward
        // leg when the last reflection is in front of the stop; otherwise, for a > b < c > d,
        // on the leg forward from `b` to `c` when only `b` is in front of it, and on the first
        // leg (entrance to `a`) when every reflection is behind it — as for a two-reflection
        // ghost behind the stop. `tests::stop_is_recorded_on_the_last_pass` checks each case.
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
        let set = InterfaceTableSet::new(
            &self.coatings,
            &self.steps,
            self.lambda_nm,
            self.sensor_reflectance,
        );
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
                    k: U::of(t.k),
                })
                .collect(),
            sensor_reflectance: self.sensor_reflectance,
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

    /// The exact reflectance at `step` for light arriving at incidence cosine `cos_i`: the
    /// sensor's spectral reflectance where the sensor reflects (a sensor stack), else the
    /// surface's coating (or bare Fresnel) between the step's two media.
    pub fn reflectance(&self, step: &Step<T>, cos_i: f64) -> f64 {
        match self.sensor_reflectance {
            Some(r) if step.surface + 1 == self.coatings.len() => r,
            _ => self.coatings[step.surface].reflectance(
                step.n_from,
                step.n_to,
                cos_i,
                self.lambda_nm,
                step.forward,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Light leaving glass (n = 1.5) for air: just above the critical angle the reflectance
    /// climbs to 1 as the square root of the cosine's distance from it. A table in the cosine
    /// of incidence was 0.9% off there (and the plate's ghosts at 80° 1.2% and, after four
    /// reflections, 3.1% bright); the table in the refracted cosine follows it.
    #[test]
    fn an_internal_reflectance_table_follows_fresnel_up_to_the_critical_angle() {
        let (n1, n2) = (1.5, 1.0);
        let k = table_k(n1, n2);
        let table = InterfaceTable {
            values: std::array::from_fn(|j| crate::fresnel::unpolarised(n1, n2, entry_cos(j, k))),
            k,
        };
        let critical = (1.0 - (n2 / n1).powi(2)).sqrt();
        let mut worst = 0.0_f64;
        for step in 1..2000 {
            let cos = critical + (1.0 - critical) * f64::from(step) / 2000.0;
            let exact = crate::fresnel::unpolarised(n1, n2, cos);
            worst = worst.max((table.at(cos) - exact).abs());
        }
        assert!(worst < 2e-3, "largest error {worst:e} of the reflectance");
        // Beyond the critical angle: total internal reflection.
        assert_eq!(table.at(critical * 0.9), 1.0);
        // From the rarer side the table runs in the cosine, as it always did.
        assert_eq!(table_k(n2, n1), 1.0);
        assert_eq!(entry_cos(128, 1.0), 128.0 / 255.0);
    }

    /// The Heliar-Tronnier: surfaces 0–4 in front of the stop (5), 6–8 behind it, sensor 9.
    fn heliar() -> LensSystem {
        let p =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/heliar-tronnier.xml");
        crate::io::read_lens(&p).unwrap().system
    }

    fn reflections(seq: &Sequence<f64>) -> Vec<usize> {
        seq.steps
            .iter()
            .filter(|s| s.interaction == Interaction::Reflect)
            .map(|s| s.surface)
            .collect()
    }

    #[test]
    fn four_reflection_sequence_visits_every_surface_between_reflections() {
        let sys = heliar();
        let seq = Sequence::ghost_path(&sys, 550.0, &GhostPath::four(4, 1, 7, 2)).unwrap();
        let got: Vec<(usize, Interaction)> = seq
            .steps
            .iter()
            .map(|s| (s.surface, s.interaction))
            .collect();
        use Interaction::{Reflect as L, Refract as R, Sensor as S};
        let want = vec![
            (0, R),
            (1, R),
            (2, R),
            (3, R),
            (4, L),
            (3, R),
            (2, R),
            (1, L),
            (2, R),
            (3, R),
            (4, R),
            (5, R),
            (6, R),
            (7, L),
            (6, R),
            (5, R),
            (4, R),
            (3, R),
            (2, L),
            (3, R),
            (4, R),
            (5, R),
            (6, R),
            (7, R),
            (8, R),
            (9, S),
        ];
        assert_eq!(got, want);
        // Direction flips at each reflection.
        let forward: Vec<bool> = seq.steps.iter().map(|s| s.forward).collect();
        assert!(forward[..5].iter().all(|&f| f));
        assert!(forward[5..8].iter().all(|&f| !f));
        assert!(forward[8..14].iter().all(|&f| f));
        assert!(forward[14..19].iter().all(|&f| !f));
        assert!(forward[19..].iter().all(|&f| f));
        // The two-reflection form is the same as before.
        let two = Sequence::ghost(&sys, 550.0, 4, 1).unwrap();
        assert_eq!(reflections(&two), vec![4, 1]);
        assert_eq!(two.len(), 4 + 1 + 2 + 1 + 7 + 1);
    }

    #[test]
    fn path_order_errors_are_typed() {
        let sys = heliar();
        let e = |p: GhostPath| Sequence::ghost_path(&sys, 550.0, &p).unwrap_err();
        assert_eq!(
            e(GhostPath::two(1, 4)),
            PathError::Order {
                first: 1,
                second: 4
            }
        );
        assert_eq!(
            e(GhostPath::two(3, 3)),
            PathError::Order {
                first: 3,
                second: 3
            }
        );
        assert_eq!(
            e(GhostPath::four(1, 4, 7, 2)),
            PathError::Order {
                first: 1,
                second: 4
            }
        );
        assert_eq!(
            e(GhostPath::four(4, 2, 1, 0)),
            PathError::ThirdOrder {
                second: 2,
                third: 1
            }
        );
        assert_eq!(
            e(GhostPath::four(4, 2, 2, 0)),
            PathError::ThirdOrder {
                second: 2,
                third: 2
            }
        );
        assert_eq!(
            e(GhostPath::four(4, 1, 3, 6)),
            PathError::FourthOrder {
                third: 3,
                fourth: 6
            }
        );
        // The stop (5) and the sensor (9) do not reflect; 12 is past the sensor.
        assert_eq!(e(GhostPath::four(7, 5, 8, 0)), PathError::NotReflecting(5));
        assert_eq!(e(GhostPath::four(9, 1, 3, 0)), PathError::NotReflecting(9));
        assert_eq!(e(GhostPath::two(12, 1)), PathError::NotReflecting(12));
        // `c` may equal `a`, and `d` may equal `b` or lie before it.
        assert!(Sequence::ghost_path(&sys, 550.0, &GhostPath::four(4, 1, 4, 1)).is_ok());
        assert!(Sequence::ghost_path(&sys, 550.0, &GhostPath::four(4, 2, 3, 0)).is_ok());
    }

    #[test]
    fn stop_is_recorded_on_the_last_pass() {
        let sys = heliar();
        let stop = sys.stop_index().unwrap();
        assert_eq!(stop, 5);
        // (path, reflections before the recorded pass)
        let cases = [
            // Last reflection in front of the stop: the final forward leg.
            (GhostPath::two(4, 1), 2),
            (GhostPath::two(7, 2), 2),
            (GhostPath::four(4, 1, 3, 0), 4),
            (GhostPath::four(8, 1, 7, 2), 4),
            // Only `b` in front of it: the leg from `b` forward to `c`.
            (GhostPath::four(7, 2, 8, 6), 2),
            // Every reflection behind it: the first leg.
            (GhostPath::two(8, 6), 0),
            (GhostPath::four(8, 6, 8, 7), 0),
        ];
        for (path, before) in cases {
            let seq = Sequence::ghost_path(&sys, 550.0, &path).unwrap();
            let recorded: Vec<usize> = (0..seq.len())
                .filter(|&i| seq.steps[i].record_stop)
                .collect();
            assert_eq!(recorded.len(), 1, "{path}");
            let i = recorded[0];
            assert_eq!(seq.steps[i].surface, stop, "{path}");
            assert!(
                seq.steps[i].forward,
                "{path}: the last pass goes toward the sensor"
            );
            let last_stop = seq.steps.iter().rposition(|s| s.surface == stop).unwrap();
            assert_eq!(i, last_stop, "{path}");
            let reflected = seq.steps[..i]
                .iter()
                .filter(|s| s.interaction == Interaction::Reflect)
                .count();
            assert_eq!(reflected, before, "{path}");
        }
    }
}

#[cfg(test)]
mod interpolation_tests {
    use super::*;
    use crate::system::CoatingLayer;

    fn lens(stem: &str) -> LensSystem {
        let p =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../lenses/{stem}.xml"));
        crate::io::read_lens(&p).unwrap().system
    }

    /// Tables 10 nm apart, a quarter and half of the way between them, against the exact
    /// tables there, over the visible range: single-layer coatings (interpolated, except near
    /// critical angles) and stacks of layers (evaluated exactly).
    #[test]
    fn tables_between_two_follow_the_exact_ones() {
        // A four-layer broadband stack (MgF2 / ZrO2 / Al2O3-like indices) on every surface of
        // the Heliar, for a coating whose reflectance changes faster with wavelength.
        let mut stacked = lens("heliar-tronnier");
        for s in &mut stacked.surfaces {
            if s.coating != Coating::None {
                s.coating = Coating::Stack(
                    [(1.63, 85.0), (2.05, 130.0), (1.63, 20.0), (1.38, 99.6)]
                        .map(|(index, thickness_nm)| CoatingLayer {
                            index,
                            thickness_nm,
                        })
                        .to_vec(),
                );
            }
        }
        let lenses = [
            ("heliar-tronnier", lens("heliar-tronnier")),
            ("nikon-zoom-short", lens("nikon-zoom-short")),
            ("heliar, four-layer stacks", stacked),
        ];
        for (stem, sys) in lenses {
            let mut worst = 0.0_f64;
            for k in 0..40 {
                let (l0, l1) = (380.0 + 10.0 * k as f64, 390.0 + 10.0 * k as f64);
                let (a, b) = (
                    InterfaceTableSet::for_system(&sys, l0),
                    InterfaceTableSet::for_system(&sys, l1),
                );
                for lambda in [l0 + 2.5, l0 + 5.0, l1] {
                    let exact = InterfaceTableSet::for_system(&sys, lambda);
                    let got = InterfaceTableSet::between(&sys, lambda, &a, &b);
                    assert_eq!(got.lambda_nm, lambda);
                    for (e, g) in exact.tables.iter().zip(&got.tables) {
                        let (Some(e), Some(g)) = (e, g) else {
                            assert!(e.is_none() && g.is_none());
                            continue;
                        };
                        for (te, tg) in e.iter().zip(g.iter()) {
                            for (x, y) in te.values.iter().zip(&tg.values) {
                                worst = worst.max((x - y).abs());
                            }
                        }
                    }
                }
            }
            assert!(worst < 2e-4, "{stem}: {worst:e}");
            if stem.contains("stack") {
                // Every coated surface a stack: evaluated exactly.
                assert_eq!(worst, 0.0, "{stem}");
            } else {
                assert!(
                    worst > 0.0,
                    "{stem}: the interpolation must be tested off the nodes"
                );
            }
        }
    }
}
