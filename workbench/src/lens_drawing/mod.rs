//! The lens drawn in meridional section, for the viewer window: every surface's profile, the
//! glass elements as filled outlines, the aperture stop's jaws, the sensor, and ray fans
//! (forward at the standard fields, or along one ghost's path).
//!
//! Pure geometry on a [`LensSystem`], no UI: lengths in mm, points `[z, y]` with z along the
//! optical axis (toward the sensor, the first vertex at 0) and y the meridional height.
//!
//! - [`profile`]: surface profiles, sampled adaptively, clipped where the sag is undefined;
//! - [`element`]: glass elements as closed outlines with their triangles;
//! - [`rays`]: ray fans traced through the lens, each ray to where it ends.

pub mod element;
pub mod profile;
pub mod rays;

use flarebench_sdk::paraxial::stop_opening;
use flarebench_sdk::{LensSystem, SurfaceKind};

pub use element::ElementFill;
pub use profile::{drawn_semi_diameter, profile_uniform, rim};
pub use rays::{
    DEFAULT_FAN_RAYS, RayEnd, RayFan, RayPath, default_fans, ghost_fan, lead_in, pupil_fan,
    ray_fans, standard_fields, trace_path,
};

/// The lens as a drawing shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct LensDrawing {
    /// Every surface's profile to its semi-diameter, in prescription order (the stop and the
    /// sensor too, as flat lines over their semi-diameters; [`LensDrawing::stop`] and
    /// [`LensDrawing::sensor`] are how drawings usually show those).
    pub surfaces: Vec<SurfaceLine>,
    /// Glass elements as closed outlines with triangles, front to back.
    pub elements: Vec<ElementFill>,
    /// The aperture stop, drawn as two jaws; `None` for a system without one.
    pub stop: Option<StopMark>,
    /// The sensor plane.
    pub sensor: SensorMark,
    /// Everything above and the [`default_fans`], for fitting the view.
    pub bounds: Bounds,
}

/// One surface's profile: points (z, y) from its bottom rim through the vertex to its top
/// rim, dense enough to look smooth when zoomed in (see [`profile::profile_heights`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceLine {
    pub row: usize,
    pub kind: SurfaceKind,
    pub points: Vec<[f64; 2]>,
}

/// The aperture stop at `z`: open from the axis to `opening` (its working radius after the
/// f-number setting), closed from there out to `outer` on either side (the two jaws).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopMark {
    pub row: usize,
    pub z: f64,
    pub opening: f64,
    pub outer: f64,
}

impl StopMark {
    /// The stop of `system` at surface `row` (assumed to be a stop): its opening
    /// (`paraxial::stop_opening`) and an outer radius 1.2 times its full semi-diameter (or
    /// the opening, if larger).
    pub fn new(system: &LensSystem, row: usize) -> StopMark {
        let opening = stop_opening(system);
        let full = system.surfaces.get(row).map_or(0.0, |s| s.semi_diameter);
        StopMark {
            row,
            z: system.vertex_z().get(row).copied().unwrap_or(0.0),
            opening,
            outer: full.max(opening) * 1.2,
        }
    }

    /// The stop of `system`, if it has one.
    pub fn of(system: &LensSystem) -> Option<StopMark> {
        system.stop_index().map(|row| StopMark::new(system, row))
    }

    /// The two jaws as segments, upper then lower, each from the opening outward.
    pub fn jaws(&self) -> [[[f64; 2]; 2]; 2] {
        let z = self.z;
        [
            [[z, self.opening], [z, self.outer]],
            [[z, -self.opening], [z, -self.outer]],
        ]
    }
}

/// The sensor plane at `z`, `half_height` (half the film diagonal) either side of the axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorMark {
    pub row: usize,
    pub z: f64,
    pub half_height: f64,
}

impl SensorMark {
    /// The sensor of `system` (its last surface).
    pub fn of(system: &LensSystem) -> SensorMark {
        let row = system.sensor_index();
        SensorMark {
            row,
            z: system.vertex_z().get(row).copied().unwrap_or(0.0),
            half_height: 0.5 * system.film_width_mm.hypot(system.film_height_mm),
        }
    }

    /// The sensor as a segment, bottom to top.
    pub fn line(&self) -> [[f64; 2]; 2] {
        [[self.z, -self.half_height], [self.z, self.half_height]]
    }
}

/// An axis-aligned box in the meridional plane: z in `min[0]..=max[0]`, y in
/// `min[1]..=max[1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

impl Bounds {
    /// The smallest box holding every finite point of `points`; a unit box around the origin
    /// when there is none.
    pub fn of_points<'a>(points: impl IntoIterator<Item = &'a [f64; 2]>) -> Bounds {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for p in points {
            if p[0].is_finite() && p[1].is_finite() {
                for k in 0..2 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
        }
        if min[0] > max[0] {
            return Bounds {
                min: [-1.0, -1.0],
                max: [1.0, 1.0],
            };
        }
        Bounds { min, max }
    }

    /// True when `p` lies in the box (edges included).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        (0..2).all(|k| self.min[k] <= p[k] && p[k] <= self.max[k])
    }
}

impl LensDrawing {
    /// The drawing of `system`. Any system is drawn without panicking; a valid one
    /// (`LensSystem::validate`) as a lens drawing shows it.
    pub fn new(system: &LensSystem) -> LensDrawing {
        let z = system.vertex_z();
        let surfaces: Vec<SurfaceLine> = system
            .surfaces
            .iter()
            .zip(&z)
            .enumerate()
            .map(|(row, (s, &z0))| SurfaceLine {
                row,
                kind: s.kind,
                points: profile::profile(s, z0),
            })
            .collect();
        let elements = element::elements(system, &z);
        let stop = StopMark::of(system);
        let sensor = SensorMark::of(system);
        let fans = if system.surfaces.is_empty() {
            Vec::new()
        } else {
            default_fans(system)
        };
        let marks: Vec<[f64; 2]> = stop
            .iter()
            .flat_map(|s| s.jaws().into_iter().flatten())
            .chain(sensor.line())
            .collect();
        let bounds = Bounds::of_points(
            surfaces
                .iter()
                .flat_map(|s| &s.points)
                .chain(elements.iter().flat_map(|e| &e.outline))
                .chain(&marks)
                .chain(fans.iter().flat_map(|f| &f.rays).flat_map(|r| &r.points)),
        );
        LensDrawing {
            surfaces,
            elements,
            stop,
            sensor,
            bounds,
        }
    }

    /// The row of the surface (or stop, sensor) whose drawn line passes within `tol_mm` of
    /// (z, y), nearest first.
    ///
    /// The lines are the surface profiles, the stop's jaws and the sensor's line.
    pub fn surface_at(&self, z: f64, y: f64, tol_mm: f64) -> Option<usize> {
        self.surfaces_near(z, y, tol_mm)
            .first()
            .map(|&(row, _)| row)
    }

    /// Every row whose drawn line passes within `tol_mm` of (z, y), with its distance (mm),
    /// nearest first.
    pub fn surfaces_near(&self, z: f64, y: f64, tol_mm: f64) -> Vec<(usize, f64)> {
        let p = [z, y];
        let mut near: Vec<(usize, f64)> = Vec::new();
        let mut consider = |row: usize, d: f64| {
            if d <= tol_mm {
                match near.iter_mut().find(|(r, _)| *r == row) {
                    Some(e) => e.1 = e.1.min(d),
                    None => near.push((row, d)),
                }
            }
        };
        for s in &self.surfaces {
            consider(s.row, polyline_distance(&s.points, p));
        }
        if let Some(stop) = &self.stop {
            for jaw in stop.jaws() {
                consider(stop.row, polyline_distance(&jaw, p));
            }
        }
        consider(self.sensor.row, polyline_distance(&self.sensor.line(), p));
        near.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        near
    }

    /// The index (into [`LensDrawing::elements`]) of the element whose outline contains
    /// (z, y), if any.
    pub fn element_at(&self, z: f64, y: f64) -> Option<usize> {
        self.elements
            .iter()
            .position(|e| polygon_contains(&e.outline, [z, y]))
    }
}

/// Distance from `p` to the polyline `points` (infinite for no points).
fn polyline_distance(points: &[[f64; 2]], p: [f64; 2]) -> f64 {
    match points {
        [] => f64::INFINITY,
        [a] => (p[0] - a[0]).hypot(p[1] - a[1]),
        _ => points
            .windows(2)
            .map(|w| segment_distance(w[0], w[1], p))
            .fold(f64::INFINITY, f64::min),
    }
}

fn segment_distance(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - (a[0] + t * dx)).hypot(p[1] - (a[1] + t * dy))
}

/// Even–odd point-in-polygon test.
fn polygon_contains(outline: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    let n = outline.len();
    for i in 0..n {
        let (a, b) = (outline[i], outline[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let z = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < z {
                inside = !inside;
            }
        }
    }
    inside
}
