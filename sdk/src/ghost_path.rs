//! A ghost path: the surfaces light reflects at, in order (`a-b` or `a-b-c-d`), with its text
//! and stored forms. A foundation type, so the tracer (`trace::Sequence::ghost_path`) and the
//! bounds file readers (`io::olf_bounds`) name ghosts without depending on `ghost`.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A ghost: the surfaces light reflects at, in the order it meets them, alternately while
/// travelling toward the sensor and back toward the object.
///
/// - **Two reflections** ([`GhostPath::two`]): forward to `a`, reflect; back to `b < a`,
///   reflect; forward to the sensor. Written `a-b`.
/// - **Four reflections** ([`GhostPath::four`]): forward to `a`, reflect; back to `b < a`,
///   reflect; forward to `c > b`, reflect; back to `d < c`, reflect; forward to the sensor.
///   Written `a-b-c-d`.
///
/// The constructors do not check the order against a lens: `Sequence::ghost_path` does
/// (`trace::PathError`). Small and `Copy`: four indices and a count; unused slots are 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GhostPath {
    surfaces: [usize; 4],
    len: u8,
}

impl GhostPath {
    /// Reflect at `first` going toward the sensor, then at `second` going back.
    pub const fn two(first: usize, second: usize) -> Self {
        GhostPath {
            surfaces: [first, second, 0, 0],
            len: 2,
        }
    }

    /// Reflect at `a` (forward), `b` (back), `c` (forward), `d` (back), then on to the sensor.
    pub const fn four(a: usize, b: usize, c: usize, d: usize) -> Self {
        GhostPath {
            surfaces: [a, b, c, d],
            len: 4,
        }
    }

    /// The reflecting surfaces in the order the light meets them (2 or 4 of them).
    pub fn reflections(&self) -> &[usize] {
        &self.surfaces[..self.len as usize]
    }

    /// Number of reflections: 2 or 4.
    pub fn order(&self) -> usize {
        self.len as usize
    }

    /// The first reflection (the latest surface of the first pair).
    pub fn first(&self) -> usize {
        self.surfaces[0]
    }

    /// The second reflection.
    pub fn second(&self) -> usize {
        self.surfaces[1]
    }

    /// True for a four-reflection path.
    pub fn is_four(&self) -> bool {
        self.len == 4
    }
}

impl std::fmt::Display for GhostPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = self.reflections();
        write!(f, "{}-{}", r[0], r[1])?;
        for s in &r[2..] {
            write!(f, "-{s}")?;
        }
        Ok(())
    }
}

/// Why a ghost path could not be read from text (`a-b` or `a-b-c-d`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not a ghost path: write two or four surface indices, `a-b` or `a-b-c-d`")]
pub struct ParseGhostPathError(pub String);

impl std::str::FromStr for GhostPath {
    type Err = ParseGhostPathError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || ParseGhostPathError(s.to_string());
        let v: Vec<usize> = s
            .split('-')
            .map(|p| p.trim().parse::<usize>().map_err(|_| err()))
            .collect::<Result<_, _>>()?;
        match v[..] {
            [a, b] => Ok(GhostPath::two(a, b)),
            [a, b, c, d] => Ok(GhostPath::four(a, b, c, d)),
            _ => Err(err()),
        }
    }
}

/// The stored form (the bounds table, docs/formats.md §10): `{"first":a,"second":b}` for two
/// reflections, exactly as before four-reflection paths existed, and
/// `{"first":a,"second":b,"third":c,"fourth":d}` for four.
#[derive(Serialize, Deserialize)]
struct StoredPath {
    first: usize,
    second: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    third: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fourth: Option<usize>,
}

impl Serialize for GhostPath {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let r = self.reflections();
        StoredPath {
            first: r[0],
            second: r[1],
            third: r.get(2).copied(),
            fourth: r.get(3).copied(),
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for GhostPath {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let p = StoredPath::deserialize(d)?;
        match (p.third, p.fourth) {
            (None, None) => Ok(GhostPath::two(p.first, p.second)),
            (Some(c), Some(d)) => Ok(GhostPath::four(p.first, p.second, c, d)),
            _ => Err(serde::de::Error::custom(
                "a ghost path has two reflections (first, second) or four (first to fourth)",
            )),
        }
    }
}
