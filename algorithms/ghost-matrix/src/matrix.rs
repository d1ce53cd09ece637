//! One ghost by 2×2 ray-transfer matrices: the path's matrices from the entrance plane (z = 0)
//! to the stop and to the sensor, and what follows from them — the ghost is the stop's opening
//! scaled by `m = A_sensor / A_stop` and centred at `(B_sensor − m·B_stop) · tan θ`.
//!
//! Matrices act on (y, n·u) with signed indices: an index is negative while the ray travels
//! toward the object (after an odd number of reflections), so a transfer of signed length
//! `t = z_next − z` in a medium of signed index `n` is `[[1, t/n], [0, 1]]` in both directions,
//! refraction from `n` to `n′` has power `c (n′ − n)`, and a reflection is a refraction into
//! `n′ = −n` (power `−2 n c`). The stop is taken at its last pass, as the traced renderer does.

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::paraxial::Abcd;
use flarebench_sdk::trace::{Interaction, Sequence};

/// The matrices of a path: entrance plane → stop (last pass) and entrance plane → sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathMatrices {
    pub to_stop: Abcd,
    pub to_sensor: Abcd,
    /// Product of the interface factors at normal incidence: Fresnel/coating transmittances at
    /// refractions and reflectances at reflections.
    pub throughput: f64,
}

/// The matrices of `seq` (built with interface tables for `throughput`; without them the
/// throughput is 1). `None` when the path never crosses the stop.
pub fn path_matrices(seq: &Sequence<f64>) -> Option<PathMatrices> {
    let mut m = Abcd::IDENTITY;
    let mut z = 0.0;
    let mut n = 1.0; // object space is air, travelling toward the sensor
    let mut to_stop = None;
    let mut throughput = 1.0;
    for s in &seq.steps {
        m = m.then(Abcd::transfer(s.z - z, n));
        z = s.z;
        if s.record_stop {
            to_stop = Some(m);
        }
        let sign = if s.forward { 1.0 } else { -1.0 };
        let n_from = sign * s.n_from;
        match s.interaction {
            Interaction::Sensor => {
                return Some(PathMatrices {
                    to_stop: to_stop?,
                    to_sensor: m,
                    throughput,
                });
            }
            Interaction::Refract => {
                let n_to = sign * s.n_to;
                m = m.then(Abcd::refraction(s.c * (n_to - n_from)));
                n = n_to;
            }
            Interaction::Reflect => {
                m = m.then(Abcd::refraction(s.c * (-2.0 * n_from)));
                n = -n_from;
            }
        }
        if let Some(t) = s.table {
            throughput *= seq.tables[t as usize].at(1.0);
        }
    }
    None
}

/// One ghost at one wavelength, in the meridional frame (light tilted toward +y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixGhost {
    /// Sensor size over stop size (negative: the aperture's image is inverted).
    pub magnification: f64,
    /// Centre of the aperture's image on the sensor along y (mm) per unit of tan θ.
    pub centre_per_tan: f64,
    /// Entrance-plane area per unit of stop area, `1 / A_stop²`: the beam that fills an
    /// opening of area `S` at the stop is `S / A_stop²` wide on the entrance plane.
    pub entrance_area_scale: f64,
    pub throughput: f64,
}

/// The ghost `path` (two or four reflections) of `system` at `lambda_nm`; `None` if the path
/// cannot be built (`Sequence::ghost_path` refuses its order) or its
/// stop matrix is singular (`A_stop` = 0: every entrance height meets the stop at one point).
pub fn ghost(system: &LensSystem, path: GhostPath, lambda_nm: f64) -> Option<MatrixGhost> {
    let seq = Sequence::ghost_path(system, lambda_nm, &path)
        .ok()?
        .with_interface_tables();
    let p = path_matrices(&seq)?;
    let (a_s, b_s) = (p.to_stop.a, p.to_stop.b);
    if a_s.abs() < 1e-12 {
        return None;
    }
    let m = p.to_sensor.a / a_s;
    Some(MatrixGhost {
        magnification: m,
        centre_per_tan: p.to_sensor.b - m * b_s,
        entrance_area_scale: 1.0 / (a_s * a_s),
        throughput: p.throughput,
    })
}
