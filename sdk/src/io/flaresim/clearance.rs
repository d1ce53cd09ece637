//! Whether clear apertures are possible: a surface's semi-diameter can never exceed |R| (the
//! sphere ends there), and two neighbouring surfaces must not cross inside their common clear
//! aperture (the sag of the one behind stays behind the one in front). These decide the
//! `semi_ap` convention, give the warnings, and with the lenient option the clamps.

use crate::system::{Surface, SurfaceKind};

/// How far two neighbouring surfaces may overlap before they count as crossing (mm): the
/// files give radii and thicknesses to 1e-4 mm, so an overlap under a micron is rounding of
/// surfaces that touch at their rims.
pub(super) const CROSSING_TOL_MM: f64 = 1e-3;

/// Points sampled from the axis to the common clear aperture when looking for a crossing.
const CROSSING_SAMPLES: usize = 32;

/// A semi-diameter beyond what its sphere allows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BeyondRadius {
    /// The surface (= table row).
    pub surface: usize,
    pub semi_diameter: f64,
    /// |R| (mm).
    pub limit: f64,
}

/// Surfaces `first` and `first + 1` cross inside their common clear aperture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Crossing {
    pub first: usize,
    /// The largest overlap found (mm, > 0): how far the second surface lies in front of the
    /// first at `height`.
    pub depth: f64,
    pub height: f64,
    /// The height where they meet (mm): the clear apertures that keep them apart.
    pub meet: f64,
}

/// What is impossible about a set of clear apertures.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Impossible {
    pub beyond_radius: Vec<BeyondRadius>,
    pub crossings: Vec<Crossing>,
}

impl Impossible {
    pub fn is_empty(&self) -> bool {
        self.beyond_radius.is_empty() && self.crossings.is_empty()
    }

    /// One sentence for messages, e.g. "2 semi-diameters exceed |R| (first: line 14, 61.8 mm
    /// against |R| = 51.5 mm) and 1 pair of neighbouring surfaces crosses (first: lines 16 and
    /// 17, by 0.52 mm at 12.3 mm from the axis)"; `lines` gives each surface's line in the file.
    pub fn describe(&self, lines: &[usize]) -> String {
        let line = |i: usize| lines.get(i).copied().unwrap_or(0);
        let mut parts = Vec::new();
        if let Some(b) = self.beyond_radius.first() {
            let n = self.beyond_radius.len();
            parts.push(format!(
                "{n} semi-diameter{} |R| (first: line {}, {} mm against |R| = {} mm)",
                if n == 1 { " exceeds" } else { "s exceed" },
                line(b.surface),
                round(b.semi_diameter),
                round(b.limit)
            ));
        }
        if let Some(c) = self.crossings.first() {
            let n = self.crossings.len();
            parts.push(format!(
                "{n} pair{} of neighbouring surfaces cross{} (first: lines {} and {}, by {} mm \
                 at {} mm from the axis)",
                if n == 1 { "" } else { "s" },
                if n == 1 { "es" } else { "" },
                line(c.first),
                line(c.first + 1),
                round(c.depth),
                round(c.height)
            ));
        }
        parts.join(" and ")
    }
}

/// A number rounded to 4 decimals for messages (the files' precision).
pub(super) fn round(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

/// Every impossible clear aperture among `surfaces` (the table's, without the sensor).
pub(super) fn check(surfaces: &[Surface]) -> Impossible {
    let beyond_radius = surfaces
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kind == SurfaceKind::Refracting && s.curvature != 0.0)
        .filter(|(_, s)| s.sag(s.semi_diameter).is_none())
        .map(|(i, s)| BeyondRadius {
            surface: i,
            semi_diameter: s.semi_diameter,
            limit: s.radius().abs(),
        })
        .collect();
    let crossings = surfaces
        .windows(2)
        .enumerate()
        .filter_map(|(i, w)| crossing(&w[0], &w[1]).map(|c| Crossing { first: i, ..c }))
        .collect();
    Impossible {
        beyond_radius,
        crossings,
    }
}

/// Where `b` (behind `a`) lies in front of `a` inside both clear apertures, if anywhere:
/// `gap(r) = t + z_b(r) − z_a(r)` sampled out to the smaller semi-diameter (only as far as
/// both spheres reach), the crossing reported where the gap is most negative.
fn crossing(a: &Surface, b: &Surface) -> Option<Crossing> {
    let t = a.thickness;
    if t.is_nan() || t < 0.0 {
        return None;
    }
    let h = a.semi_diameter.min(b.semi_diameter);
    let gap = |r: f64| Some(t + b.sag(r)? - a.sag(r)?);
    let mut worst: Option<(f64, f64)> = None;
    let mut last_ok = 0.0;
    let mut first_bad = None;
    for j in 1..=CROSSING_SAMPLES {
        let r = h * j as f64 / CROSSING_SAMPLES as f64;
        let Some(g) = gap(r) else { break };
        if g < -CROSSING_TOL_MM {
            if first_bad.is_none() {
                first_bad = Some(r);
            }
            if worst.is_none_or(|(w, _)| g < w) {
                worst = Some((g, r));
            }
        } else if first_bad.is_none() {
            last_ok = r;
        }
    }
    let ((g, r), bad) = (worst?, first_bad?);
    // Bisect for the height where the gap closes, between the last sample that was open
    // and the first that was not.
    let (mut lo, mut hi) = (last_ok, bad);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        match gap(mid) {
            Some(gm) if gm >= 0.0 => lo = mid,
            _ => hi = mid,
        }
    }
    Some(Crossing {
        first: 0,
        depth: -g,
        height: r,
        meet: lo,
    })
}

/// One clamp the lenient option made, for its warning and the notes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Clamp {
    pub surface: usize,
    pub from: f64,
    pub to: f64,
    pub cause: Cause,
}

/// Why a semi-diameter was clamped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Cause {
    /// It exceeded |R| (mm).
    Radius { limit: f64 },
    /// It and its neighbour `crossing.first + 1` (or `crossing.first`) crossed beyond the
    /// height they were clamped to.
    Crossing(Crossing),
}

/// Makes every clear aperture possible: a semi-diameter beyond |R| becomes |R| (the last float
/// the sphere reaches), then each pair of neighbouring surfaces that cross has both
/// semi-diameters limited to the height where they meet (front to back, so a clamp is seen by
/// the next pair). Returns the clamps, and the crossings no clamp can undo: surfaces that
/// cross from the axis out (an element of thickness 0 between convex faces), which are left
/// as they are.
pub(super) fn clamp(surfaces: &mut [Surface]) -> (Vec<Clamp>, Vec<Crossing>) {
    let mut clamps = Vec::new();
    let mut left = Vec::new();
    for b in check(surfaces).beyond_radius {
        let s = &mut surfaces[b.surface];
        // |R| itself, or the next float below it where `c²r²` rounds above 1.
        let mut to = b.limit;
        for _ in 0..64 {
            if s.sag(to).is_some() {
                break;
            }
            to = to.next_down();
        }
        clamps.push(Clamp {
            surface: b.surface,
            from: s.semi_diameter,
            to,
            cause: Cause::Radius { limit: b.limit },
        });
        s.semi_diameter = to;
    }
    for i in 0..surfaces.len().saturating_sub(1) {
        let Some(c) = crossing(&surfaces[i], &surfaces[i + 1]) else {
            continue;
        };
        if c.meet.is_nan() || c.meet <= 0.0 {
            left.push(Crossing { first: i, ..c });
            continue;
        }
        for k in [i, i + 1] {
            let s = &mut surfaces[k];
            if s.semi_diameter > c.meet {
                clamps.push(Clamp {
                    surface: k,
                    from: s.semi_diameter,
                    to: c.meet,
                    cause: Cause::Crossing(Crossing { first: i, ..c }),
                });
                s.semi_diameter = c.meet;
            }
        }
    }
    (clamps, left)
}
