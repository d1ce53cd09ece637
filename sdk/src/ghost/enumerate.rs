//! Ghost paths of a lens: every two-reflection path, and on request every four-reflection one.

use serde::{Deserialize, Serialize};

use crate::spectrum::LAMBDA_D_NM;
use crate::system::{LensSystem, SurfaceKind};

pub use crate::ghost_path::{GhostPath, ParseGhostPathError};

/// Which ghosts to render: two-reflection paths only (the default), or two- and
/// four-reflection paths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ReflectionOrder {
    #[default]
    #[serde(rename = "2")]
    Two,
    #[serde(rename = "4")]
    Four,
}

impl ReflectionOrder {
    /// 2 or 4.
    pub fn count(self) -> usize {
        match self {
            ReflectionOrder::Two => 2,
            ReflectionOrder::Four => 4,
        }
    }
}

impl std::fmt::Display for ReflectionOrder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.count())
    }
}

impl std::str::FromStr for ReflectionOrder {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "2" => Ok(ReflectionOrder::Two),
            "4" => Ok(ReflectionOrder::Four),
            _ => Err(format!(
                "reflections must be 2 (two-reflection ghosts) or 4 (two- and four-reflection ghosts), got `{s}`"
            )),
        }
    }
}

/// Surfaces that can reflect: refracting surfaces with different indices on their two sides
/// (at the d line) — with a sensor stack, its plates' faces among them — and the sensor when
/// it has a reflectance (a sensor stack; it is last, so it is only ever the first or third
/// reflection of a path). Dummy surfaces and the stop do not reflect.
pub fn reflecting_surfaces(system: &LensSystem) -> Vec<usize> {
    let n = system.indices(LAMBDA_D_NM);
    let sensor = system.sensor_index();
    let mut out: Vec<usize> = (0..sensor)
        .filter(|&i| system.surfaces[i].kind == SurfaceKind::Refracting && n[i] != n[i + 1])
        .collect();
    if system.sensor_stack.is_some() && !system.surfaces.is_empty() {
        out.push(sensor);
    }
    out
}

/// All N(N−1)/2 two-reflection paths over the N reflecting surfaces, including paths whose
/// reflections lie on different sides of the stop; ordered by `first`, then `second`.
pub fn enumerate_ghosts(system: &LensSystem) -> Vec<GhostPath> {
    let r = reflecting_surfaces(system);
    let mut out = Vec::with_capacity(r.len() * r.len().saturating_sub(1) / 2);
    for (a, &first) in r.iter().enumerate() {
        for &second in &r[..a] {
            out.push(GhostPath::two(first, second));
        }
    }
    out
}

/// Number of four-reflection paths over `n` reflecting surfaces:
/// Σ over the second reflection's rank `b` of (n − 1 − b) choices of `a` times
/// Σ_{c > b} c choices of (`c`, `d < c`). About n⁴/8 for large n.
pub fn four_reflection_count(n: usize) -> usize {
    (0..n)
        .map(|b| (n - 1 - b) * ((b + 1)..n).sum::<usize>())
        .sum()
}

/// Every four-reflection path over the reflecting surfaces (`a > b < c > d`; `c` may equal
/// `a`, and `d` may equal `b` or lie before it), ordered by `a`, `b`, `c`, then `d`: there
/// are [`four_reflection_count`] of them. Nothing is traced: cheap even for ~10⁵ paths.
pub fn enumerate_four_reflection_ghosts(system: &LensSystem) -> Vec<GhostPath> {
    let r = reflecting_surfaces(system);
    let mut out = Vec::with_capacity(four_reflection_count(r.len()));
    for (ia, &a) in r.iter().enumerate() {
        for (ib, &b) in r[..ia].iter().enumerate() {
            for (ic, &c) in r.iter().enumerate().skip(ib + 1) {
                for &d in &r[..ic] {
                    out.push(GhostPath::four(a, b, c, d));
                }
            }
        }
    }
    out
}

/// The paths of `order`: [`enumerate_ghosts`], followed for [`ReflectionOrder::Four`] by
/// [`enumerate_four_reflection_ghosts`].
pub fn enumerate_ghosts_of_order(system: &LensSystem, order: ReflectionOrder) -> Vec<GhostPath> {
    let mut out = enumerate_ghosts(system);
    if order == ReflectionOrder::Four {
        out.extend(enumerate_four_reflection_ghosts(system));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_round_trips_and_two_reflection_form_is_unchanged() {
        let two = GhostPath::two(7, 2);
        assert_eq!(two.to_string(), "7-2");
        assert_eq!("7-2".parse::<GhostPath>().unwrap(), two);
        let four = GhostPath::four(7, 2, 8, 0);
        assert_eq!(four.to_string(), "7-2-8-0");
        assert_eq!("7-2-8-0".parse::<GhostPath>().unwrap(), four);
        assert_eq!(four.reflections(), &[7, 2, 8, 0]);
        assert_eq!((four.first(), four.second()), (7, 2));
        for bad in ["", "7", "7-2-8", "7-2-8-0-1", "a-b", "7--2"] {
            assert!(bad.parse::<GhostPath>().is_err(), "{bad}");
        }
    }

    #[test]
    fn json_of_two_reflections_is_unchanged_and_four_round_trips() {
        let two = GhostPath::two(2, 1);
        assert_eq!(
            serde_json::to_string(&two).unwrap(),
            r#"{"first":2,"second":1}"#
        );
        let four = GhostPath::four(3, 1, 4, 0);
        let text = serde_json::to_string(&four).unwrap();
        assert_eq!(text, r#"{"first":3,"second":1,"third":4,"fourth":0}"#);
        assert_eq!(serde_json::from_str::<GhostPath>(&text).unwrap(), four);
        assert_eq!(
            serde_json::from_str::<GhostPath>(r#"{"first":2,"second":1}"#).unwrap(),
            two
        );
        assert!(serde_json::from_str::<GhostPath>(r#"{"first":3,"second":1,"third":4}"#).is_err());
    }

    #[test]
    fn reflection_order_parses() {
        assert_eq!("2".parse::<ReflectionOrder>(), Ok(ReflectionOrder::Two));
        assert_eq!("4".parse::<ReflectionOrder>(), Ok(ReflectionOrder::Four));
        assert!("3".parse::<ReflectionOrder>().is_err());
        assert_eq!(ReflectionOrder::default(), ReflectionOrder::Two);
    }

    #[test]
    fn four_reflection_count_matches_a_brute_force_count() {
        for n in 0..9 {
            let mut brute = 0;
            for a in 0..n {
                for b in 0..n {
                    for c in 0..n {
                        for d in 0..n {
                            brute += usize::from(a > b && c > b && c > d);
                        }
                    }
                }
            }
            assert_eq!(four_reflection_count(n), brute, "n = {n}");
        }
    }
}
