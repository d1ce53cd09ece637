//! The scalar f64 tracer: one ray at a time, with every hit recorded on request and the
//! Fresnel/coating throughput along the path.

use glam::DVec3;

use super::fate::Fate;
use super::lane::advance_dyn;
use super::sequence::{Interaction, Sequence};

/// A ray: a point and a unit direction (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub dir: DVec3,
}

impl Ray {
    /// A ray through `origin` along `dir` (normalised here).
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        Ray {
            origin,
            dir: dir.normalize(),
        }
    }

    /// A collimated ray at `field_rad` from the axis in the y–z plane, rotated by `azimuth_rad`
    /// about the axis, crossing the plane z = 0 (the front vertex) at height `height_mm` along
    /// the rotated y axis. Positive field tilts the ray toward +y.
    pub fn collimated(field_rad: f64, azimuth_rad: f64, height_mm: f64) -> Self {
        let (sa, ca) = field_rad.sin_cos();
        let (sp, cp) = azimuth_rad.sin_cos();
        Ray {
            origin: DVec3::new(-height_mm * sp, height_mm * cp, 0.0),
            dir: DVec3::new(-sa * sp, sa * cp, ca),
        }
    }
}

/// One surface interaction of a traced ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub surface: usize,
    pub interaction: Interaction,
    /// Where the ray met the surface (global coordinates, mm).
    pub position: DVec3,
    /// Direction after the interaction.
    pub direction: DVec3,
    /// Distance from the axis over the clear semi-diameter (> 1: outside the aperture).
    pub relative_radius: f64,
    /// Angle of incidence (radians).
    pub incidence_rad: f64,
}

/// The result of tracing one ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceResult {
    pub fate: Fate,
    /// The ray after its last completed step (on the sensor plane when `completed`).
    pub ray: Ray,
    /// True when every step was carried out (the ray met the last surface, even if it was
    /// vignetted on the way).
    pub completed: bool,
    /// The largest relative radius met along the path.
    pub max_relative_radius: f64,
    /// Product of the Fresnel/coating transmittances at refractions and reflectances at
    /// reflections, up to where tracing stopped.
    pub throughput: f64,
}

impl Sequence<f64> {
    /// Traces one ray.
    pub fn trace(&self, ray: &Ray) -> TraceResult {
        self.trace_inner(ray, None)
    }

    /// Traces one ray and appends every hit to `hits`.
    pub fn trace_with_hits(&self, ray: &Ray, hits: &mut Vec<Hit>) -> TraceResult {
        self.trace_inner(ray, Some(hits))
    }

    fn trace_inner(&self, ray: &Ray, mut hits: Option<&mut Vec<Hit>>) -> TraceResult {
        let mut p = ray.origin.to_array();
        let mut d = ray.dir.to_array();
        let mut fate = Fate::Sensor;
        let mut max_rel2 = 0.0f64;
        let mut throughput = 1.0;
        for step in &self.steps {
            let before = Ray {
                origin: DVec3::from_array(p),
                dir: DVec3::from_array(d),
            };
            let out = advance_dyn(step, &mut p, &mut d);
            let surface = step.surface;
            let terminal = if out.missed {
                Some(Fate::Missed { surface })
            } else if out.no_convergence {
                Some(Fate::NoConvergence { surface })
            } else if out.tir {
                Some(Fate::TotalInternalReflection { surface })
            } else {
                None
            };
            if let Some(f) = terminal {
                if fate == Fate::Sensor {
                    fate = f;
                }
                return TraceResult {
                    fate,
                    ray: before,
                    completed: false,
                    max_relative_radius: max_rel2.sqrt(),
                    throughput,
                };
            }
            let rel2 = out.r2 * step.inv_semi2;
            max_rel2 = max_rel2.max(rel2);
            if rel2 > 1.0 && fate == Fate::Sensor {
                fate = Fate::Vignetted {
                    surface: step.surface,
                };
            }
            let r = || self.reflectance(step, out.cos_i);
            match step.interaction {
                Interaction::Refract => throughput *= 1.0 - r(),
                Interaction::Reflect => throughput *= r(),
                Interaction::Sensor => {}
            }
            if let Some(h) = hits.as_deref_mut() {
                h.push(Hit {
                    surface: step.surface,
                    interaction: step.interaction,
                    position: DVec3::from_array(p),
                    direction: DVec3::from_array(d),
                    relative_radius: rel2.sqrt(),
                    incidence_rad: out.cos_i.min(1.0).acos(),
                });
            }
        }
        TraceResult {
            fate,
            ray: Ray {
                origin: DVec3::from_array(p),
                dir: DVec3::from_array(d),
            },
            completed: true,
            max_relative_radius: max_rel2.sqrt(),
            throughput,
        }
    }
}
