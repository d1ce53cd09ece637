//! A lens across its field: the chief ray aimed at every degree from the axis to 89°, and the
//! ghosts of lights from the axis to past the edge of the field and at 89°, in f32 and f64.
//!
//! The edge of the field is where the chief ray lands on the film's corner (half its
//! diagonal), found from the real chief ray, not the paraxial focal length: a fisheye's edge
//! lies far beyond `atan(half diagonal / EFL)`. A lens whose image never reaches the corner
//! (a lens made for a smaller film) has its field end where its chief ray's image height is
//! largest: the rim of its image circle. Beyond it the height falls back as the angle grows
//! (the Ricoh 18.3 mm f/2.5 on 36 × 24 mm: 15.46 mm at 57°, 15.19 mm at 61°, the corner
//! 21.6 mm) — distortion turning over, which no larger field angle can undo, not an aiming
//! defect — so the height check stops there.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::bounds::entrance_search_rect;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::chief_ray_landing;
use flarebench_sdk::trace::{Ray, Sequence};
use ghost_raytrace::ghosts::F64_ABOVE_DEG;

use super::{Finding, SuiteOptions, default_plan, frame_of, precision_findings, render_pair};

/// Largest angle of a light (degrees): grazing.
pub const GRAZING_DEG: f64 = 89.0;
/// Entrance heights of the fan that tells whether direct light reaches the sensor (rays that
/// pass every clear aperture), and whether the rays that do cross the stop on both sides of
/// its centre.
const FAN_RAYS: usize = 2049;

/// What the chief-ray scan found at one angle.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Aim {
    /// The chief ray lands at this (signed) height.
    Found(f64),
    /// No direct ray reaches the sensor: nothing to aim.
    Dark,
    /// Direct light reaches the sensor, but only through one side of the stop: the chief
    /// ray itself is vignetted.
    Vignetted,
    /// Direct light reaches the sensor through both sides of the stop, yet no chief ray was
    /// found: a defect.
    Lost,
}

/// Aims the chief ray at `theta` (radians), and when that fails, says why.
fn aim(system: &LensSystem, seq: &Sequence<f64>, stop: usize, theta: f64) -> Aim {
    if let Ok([_, y]) = chief_ray_landing(system, LAMBDA_D_NM, theta, 0.0) {
        return Aim::Found(y);
    }
    let half = entrance_search_rect(system, theta).y1;
    let mut hits = Vec::new();
    let (mut below, mut above) = (false, false);
    for k in 0..FAN_RAYS {
        let h = -half + 2.0 * half * k as f64 / (FAN_RAYS - 1) as f64;
        hits.clear();
        let r = seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
        // Only light: a ray that completes its path outside some clear aperture carries none
        // (beyond the Fujinon XF33's field, at 43°, every ray that completes passes outside
        // its front element).
        if !r.fate.reached_sensor() {
            continue;
        }
        if let Some(hit) = hits.iter().find(|hit| hit.surface == stop) {
            below |= hit.position.y <= 0.0;
            above |= hit.position.y >= 0.0;
        }
    }
    match (below, above) {
        (true, true) => Aim::Lost,
        (false, false) => Aim::Dark,
        _ => Aim::Vignetted,
    }
}

/// The chief ray at every whole degree from 0 to 89°, and the edge of the field (degrees).
struct FieldScan {
    aims: Vec<(f64, Aim)>,
    edge_deg: f64,
}

fn scan(system: &LensSystem) -> FieldScan {
    let seq = Sequence::forward(system, LAMBDA_D_NM);
    let stop = system.stop_index().unwrap_or(0);
    let corner = 0.5 * system.film_width_mm.hypot(system.film_height_mm);
    let aims: Vec<(f64, Aim)> = (0..=GRAZING_DEG as usize)
        .map(|d| {
            let deg = d as f64;
            (deg, aim(system, &seq, stop, deg.to_radians()))
        })
        .collect();
    FieldScan {
        edge_deg: field_edge(&aims, corner),
        aims,
    }
}

/// The edge of the field (degrees) from the chief rays `aims`: the first angle whose chief ray
/// lands past `corner` (mm), interpolated; else the angle whose chief ray lands highest (the
/// rim of the lens's image circle), the first of equals; 0 when none was found.
fn field_edge(aims: &[(f64, Aim)], corner: f64) -> f64 {
    let mut last: Option<(f64, f64)> = None;
    let mut highest: Option<(f64, f64)> = None;
    for &(deg, a) in aims {
        let Aim::Found(y) = a else { continue };
        let h = y.abs();
        if h >= corner {
            return match last {
                Some((d0, h0)) if h > h0 => d0 + (deg - d0) * (corner - h0) / (h - h0),
                _ => deg,
            };
        }
        if highest.is_none_or(|(_, top)| h > top) {
            highest = Some((deg, h));
        }
        last = Some((deg, h));
    }
    highest.map_or(0.0, |(deg, _)| deg)
}

/// The edge of `system`'s field (degrees): where its chief ray lands on the film's corner,
/// else where its chief ray lands highest (the lens must have a stop).
pub fn edge_deg(system: &LensSystem) -> f64 {
    scan(system).edge_deg
}

/// The light angles rendered (degrees): fractions of the field's edge, capped below grazing,
/// and grazing itself.
pub fn light_angles(edge_deg: f64, quick: bool) -> Vec<f64> {
    let fractions: &[f64] = if quick {
        &[0.0, 0.5, 1.0, 1.15]
    } else {
        &[0.0, 0.25, 0.5, 0.75, 1.0, 1.15, 1.3]
    };
    let mut out: Vec<f64> = fractions
        .iter()
        .map(|f| (f * edge_deg).min(GRAZING_DEG - 1.0))
        .collect();
    out.push(GRAZING_DEG);
    out.dedup_by(|a, b| (*a - *b).abs() < 0.05);
    out
}

/// The chief-ray findings and the ghosts' precision findings of `system` across its field.
pub fn check_lens(name: &str, system: &LensSystem, options: SuiteOptions) -> Vec<Finding> {
    let mut out = Vec::new();
    if system.stop_index().is_none() {
        out.push(Finding::failed(
            "chief-ray",
            name,
            "0–89°".into(),
            "the lens has no aperture stop".into(),
        ));
        return out;
    }
    let s = scan(system);
    let count = |want: Aim| s.aims.iter().filter(|(_, a)| *a == want).count();
    let lost: Vec<String> = s
        .aims
        .iter()
        .filter(|(_, a)| *a == Aim::Lost)
        .map(|(d, _)| format!("{d:.0}°"))
        .collect();
    let found: Vec<f64> = s
        .aims
        .iter()
        .filter_map(|&(d, a)| matches!(a, Aim::Found(_)).then_some(d))
        .collect();
    let range = match (found.first(), found.last()) {
        (Some(a), Some(b)) => format!("found at {a:.0}–{b:.0}°"),
        _ => "found at no angle".into(),
    };
    out.push(Finding::measured(
        "chief-ray",
        name,
        "0–89° by 1°".into(),
        lost.len() as f64,
        0.0,
        format!(
            "angles where direct light crosses the stop on both sides but no chief ray was \
             found{}; {range}; {} vignetted (light through one side of the stop only), {} dark; \
             field edge {:.1}°",
            if lost.is_empty() {
                String::new()
            } else {
                format!(" ({})", lost.join(", "))
            },
            count(Aim::Vignetted),
            count(Aim::Dark),
            s.edge_deg
        ),
    ));
    // The image height grows with the angle up to the field's edge.
    let heights: Vec<(f64, f64)> = s
        .aims
        .iter()
        .filter_map(|&(d, a)| match a {
            Aim::Found(y) if d <= s.edge_deg => Some((d, y.abs())),
            _ => None,
        })
        .collect();
    let backwards = heights.windows(2).filter(|w| w[1].1 <= w[0].1).count();
    out.push(Finding::measured(
        "chief-ray-height",
        name,
        format!("0–{:.0}°", s.edge_deg),
        backwards as f64,
        0.0,
        "steps where the chief ray's image height does not grow with the angle".into(),
    ));
    let frame = frame_of(system, options.width);
    let plan = default_plan();
    for theta in light_angles(s.edge_deg, options.quick) {
        let case = if theta > F64_ABOVE_DEG {
            format!("θ {theta:.1}° (f64 either way)")
        } else {
            format!("θ {theta:.1}°")
        };
        match render_pair(system, &Aperture::Circular, frame, theta, 30.0, &plan) {
            Ok(pair) => out.extend(precision_findings(name, &case, &pair)),
            Err(e) => out.push(Finding::failed("non-finite", name, case, e)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_field_ends_at_the_corner_or_where_the_image_height_turns_over() {
        let found = |v: &[(f64, f64)]| -> Vec<(f64, Aim)> {
            v.iter().map(|&(d, y)| (d, Aim::Found(y))).collect()
        };
        // Past the corner (10 mm) between 2° and 3°: interpolated.
        let a = found(&[(0.0, 0.0), (1.0, 4.0), (2.0, 8.0), (3.0, 12.0)]);
        assert_eq!(field_edge(&a, 10.0), 2.5);
        // Never past it: where the height is largest, not the last angle found.
        let mut b = found(&[(0.0, 0.0), (1.0, 4.0), (2.0, 6.0), (3.0, 5.5), (4.0, 5.0)]);
        b.push((5.0, Aim::Dark));
        assert_eq!(field_edge(&b, 10.0), 2.0);
        assert_eq!(field_edge(&[(0.0, Aim::Dark)], 10.0), 0.0);
    }

    #[test]
    fn light_angles_reach_past_the_edge_and_end_grazing() {
        assert_eq!(light_angles(20.0, true), vec![0.0, 10.0, 20.0, 23.0, 89.0]);
        // A fisheye's edge near 78°: past it is capped below grazing.
        let a = light_angles(78.0, false);
        assert_eq!(*a.last().unwrap(), GRAZING_DEG);
        assert!(a.iter().all(|&d| d <= GRAZING_DEG));
        assert!(a.windows(2).all(|w| w[0] < w[1]), "{a:?}");
    }
}
