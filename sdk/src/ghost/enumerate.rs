//! Every two-reflection ghost path of a lens.

use serde::{Deserialize, Serialize};

use crate::spectrum::LAMBDA_D_NM;
use crate::system::{LensSystem, SurfaceKind};

/// A ghost: light reflects at `first` while travelling toward the sensor, then at `second`
/// (an earlier surface) travelling back, then goes on to the sensor. `first > second`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct GhostPath {
    pub first: usize,
    pub second: usize,
}

impl std::fmt::Display for GhostPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}-{}", self.first, self.second)
    }
}

/// Surfaces that can reflect: refracting surfaces with different indices on their two sides
/// (at the d line). Dummy surfaces, the stop and the sensor do not reflect.
pub fn reflecting_surfaces(system: &LensSystem) -> Vec<usize> {
    let n = system.indices(LAMBDA_D_NM);
    let sensor = system.sensor_index();
    (0..sensor)
        .filter(|&i| system.surfaces[i].kind == SurfaceKind::Refracting && n[i] != n[i + 1])
        .collect()
}

/// All N(N−1)/2 two-reflection paths over the N reflecting surfaces, including paths whose
/// reflections lie on different sides of the stop; ordered by `first`, then `second`.
pub fn enumerate_ghosts(system: &LensSystem) -> Vec<GhostPath> {
    let r = reflecting_surfaces(system);
    let mut out = Vec::with_capacity(r.len() * r.len().saturating_sub(1) / 2);
    for (a, &first) in r.iter().enumerate() {
        for &second in &r[..a] {
            out.push(GhostPath { first, second });
        }
    }
    out
}
