//! The lens in meridional section as an SVG drawing (`crate::lens_drawing`): glass elements
//! filled, surfaces outlined, the stop's jaws, the sensor, and the default ray fans (the axis,
//! 0.7 and full field) — what the viewer window draws, for a page.

use std::fmt::Write as _;

use flarebench_sdk::LensSystem;

use crate::lens_drawing::{LensDrawing, default_fans};

/// Width of the drawing (SVG user units); the height follows the lens's proportions.
const WIDTH: f64 = 480.0;
/// Margin around the drawing, as a fraction of its larger side.
const MARGIN: f64 = 0.04;
/// Colours of the fans, axis to full field.
const FAN_COLOURS: [&str; 3] = ["#2a7de1", "#2fa84f", "#d9822b"];

/// The section of `system` as a standalone SVG document.
pub fn svg(system: &LensSystem) -> String {
    let drawing = LensDrawing::new(system);
    let fans = if system.surfaces.is_empty() {
        Vec::new()
    } else {
        default_fans(system)
    };
    let b = drawing.bounds;
    let (w_mm, h_mm) = (b.max[0] - b.min[0], b.max[1] - b.min[1]);
    let pad = MARGIN * w_mm.max(h_mm);
    let (x0, y0) = (b.min[0] - pad, -(b.max[1] + pad));
    let (vw, vh) = (w_mm + 2.0 * pad, h_mm + 2.0 * pad);
    let height = (WIDTH * vh / vw).max(1.0);
    // Strokes in screen units whatever the lens's size in mm.
    let px = vw / WIDTH;
    let pt = |p: &[f64; 2]| format!("{:.3},{:.3}", p[0], -p[1]);
    let poly = |points: &[[f64; 2]]| points.iter().map(pt).collect::<Vec<_>>().join(" ");

    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH:.0}\" height=\"{height:.0}\" \
         viewBox=\"{x0:.3} {y0:.3} {vw:.3} {vh:.3}\">"
    );
    let _ = writeln!(out, "<title>{}</title>", escape(&system.name));
    let _ = writeln!(
        out,
        "<rect x=\"{x0:.3}\" y=\"{y0:.3}\" width=\"{vw:.3}\" height=\"{vh:.3}\" fill=\"#fff\"/>"
    );
    // The optical axis.
    let _ = writeln!(
        out,
        "<line x1=\"{x0:.3}\" y1=\"0\" x2=\"{:.3}\" y2=\"0\" stroke=\"#999\" \
         stroke-width=\"{:.4}\" stroke-dasharray=\"{:.3} {:.3}\"/>",
        x0 + vw,
        px,
        6.0 * px,
        4.0 * px
    );
    for e in &drawing.elements {
        let _ = writeln!(
            out,
            "<polygon points=\"{}\" fill=\"#cfe3f5\" stroke=\"none\"/>",
            poly(&e.outline)
        );
    }
    for (fan, colour) in fans.iter().zip(FAN_COLOURS.iter().cycle()) {
        for ray in &fan.rays {
            let _ = writeln!(
                out,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" \
                 stroke-width=\"{:.4}\" stroke-opacity=\"0.8\"/>",
                poly(ray.completed_points()),
                0.7 * px
            );
        }
    }
    for s in &drawing.surfaces {
        if s.points.len() > 1
            && s.row != drawing.sensor.row
            && Some(s.row) != drawing.stop.map(|m| m.row)
        {
            let _ = writeln!(
                out,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"#1d3557\" stroke-width=\"{:.4}\"/>",
                poly(&s.points),
                1.2 * px
            );
        }
    }
    if let Some(stop) = drawing.stop {
        for jaw in stop.jaws() {
            let _ = writeln!(
                out,
                "<polyline points=\"{}\" stroke=\"#000\" stroke-width=\"{:.4}\"/>",
                poly(&jaw),
                2.5 * px
            );
        }
    }
    let _ = writeln!(
        out,
        "<polyline points=\"{}\" stroke=\"#c0392b\" stroke-width=\"{:.4}\"/>",
        poly(&drawing.sensor.line()),
        2.0 * px
    );
    out.push_str("</svg>\n");
    out
}

/// `s` with `&`, `<`, `>` and `"` escaped for XML text and attributes.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            _ => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use flarebench_sdk::io::read_lens;

    #[test]
    fn the_section_draws_every_element_the_stop_the_sensor_and_the_fans() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../lenses/heliar-tronnier.xml");
        let sys = read_lens(std::path::Path::new(path)).unwrap().system;
        let svg = svg(&sys);
        assert!(svg.starts_with("<svg ") && svg.ends_with("</svg>\n"));
        let drawing = LensDrawing::new(&sys);
        assert_eq!(svg.matches("<polygon ").count(), drawing.elements.len());
        // Refracting surfaces, the two jaws, the sensor, and 3 fans of 7 rays.
        let refracting = sys.surfaces.len() - 2;
        assert_eq!(
            svg.matches("<polyline ").count(),
            refracting + 2 + 1 + 3 * 7
        );
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(escape("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
    }
}
