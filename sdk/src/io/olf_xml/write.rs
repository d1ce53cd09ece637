//! Writing a [`LensSystem`] as our XML (OpenLensFlare tags plus our extensions) or as strict
//! OpenLensFlare XML.

use std::fmt::Write as _;

use crate::coating::Coating;
use crate::glass::GlassCatalog;
use crate::lens_kind::kinds_text;
use crate::system::{LensSystem, Medium, Surface, SurfaceKind};

/// The Abbe number OpenLensFlare's own files give air (ignored when reading: n = 1 is air).
const AIR_ABBE: &str = "89.3";

/// Which tags to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Flavor {
    /// OpenLensFlare's tags plus ours: lossless.
    Flarebench,
    /// Only the tags OpenLensFlare's LensPlanner accepts (it rejects unknown tags).
    OpenLensFlare,
}

/// Writes the system as flarebench XML: every OpenLensFlare tag, plus `<curvature>` (exact),
/// `<conic>`, `<aspheric>`, `<glass>`, `<coatingStack>`, `<source>`, `<notes>`, `<maker>`,
/// `<kind>`, `<nominalFocalLength>` and `<sensorStack>` where they carry information (the
/// elements are the lens without its sensor stack). Reading the result gives back an equal [`LensSystem`] (strings are
/// trimmed). The format is described in `docs/formats.md`.
pub fn write_xml(system: &LensSystem) -> String {
    write(system, Flavor::Flarebench)
}

/// Writes the system with OpenLensFlare's tags only, for OpenLensFlare's LensPlanner, which
/// refuses files with tags it does not know. Lossy: conic and aspheric terms, catalogue glass
/// names (their nd/Vd are kept), coating stacks beyond the first layer, maker, kind, focal
/// range and the sensor stack (the elements are the bare lens) are dropped, and the source
/// and notes go into a comment.
pub fn write_olf_xml(system: &LensSystem) -> String {
    write(system, Flavor::OpenLensFlare)
}

/// `{}` formatting: Rust's shortest representation that parses back to the same `f64`.
fn num(v: f64) -> String {
    format!("{v}")
}

/// OpenLensFlare's `radius` for curvature `c`: the shortest decimal whose reciprocal is exactly
/// `c` (so a radius typed as 25.462532 is written so, not as 25.462531999999996); 0 when flat
/// or when the radius would not be finite.
fn radius_text(c: f64) -> String {
    let r = 1.0 / c;
    if !r.is_finite() {
        return "0".into();
    }
    for digits in 0..17 {
        if let Ok(v) = format!("{r:.digits$e}").parse::<f64>()
            && 1.0 / v == c
        {
            return num(v);
        }
    }
    num(r)
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn write(system: &LensSystem, flavor: Flavor) -> String {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    match flavor {
        Flavor::Flarebench => out.push_str(
            "<!-- OpenLensFlare optical system with flarebench extensions (docs/formats.md) -->\n",
        ),
        Flavor::OpenLensFlare => {
            let mut comment = String::from("Exported by flarebench for OpenLensFlare.");
            for (label, text) in [("Source", &system.source), ("Notes", &system.notes)] {
                if !text.trim().is_empty() {
                    let _ = write!(comment, "\n{label}: {}", text.trim());
                }
            }
            if let Some(w) = system.primary_wavelength_nm {
                let _ = write!(comment, "\nPrimary wavelength: {} nm", num(w));
            }
            // `--` may not appear inside an XML comment.
            let _ = writeln!(out, "<!--\n{}\n-->", comment.replace("--", "- -"));
        }
    }
    out.push_str("<opticalSystem>\n");
    let mut tag = |name: &str, value: &str| {
        let _ = writeln!(out, "    <{name}>{value}</{name}>");
    };
    tag("name", &escape(system.name.trim()));
    if flavor == Flavor::Flarebench {
        if !system.maker.trim().is_empty() {
            tag("maker", &escape(system.maker.trim()));
        }
        if !system.kind.is_empty() {
            tag("kind", &kinds_text(&system.kind));
        }
        match system.nominal_focal_mm {
            Some([a, b]) if a == b => tag("nominalFocalLength", &num(a)),
            Some([a, b]) => tag("nominalFocalLength", &format!("{} {}", num(a), num(b))),
            None => {}
        }
    }
    for (name, value) in [
        ("fnumber", system.f_number),
        ("effectiveFocalLength", system.stated_efl_mm),
        ("fieldOfView", system.field_of_view_deg),
    ] {
        if let Some(v) = value {
            tag(name, &num(v));
        }
    }
    tag("filmWidth", &num(system.film_width_mm));
    tag("filmHeight", &num(system.film_height_mm));
    if flavor == Flavor::Flarebench {
        if let Some(w) = system.primary_wavelength_nm {
            tag("primaryWavelength", &num(w));
        }
        for (name, text) in [("source", &system.source), ("notes", &system.notes)] {
            if !text.trim().is_empty() {
                tag(name, &escape(text.trim()));
            }
        }
    }
    // The elements are the bare lens; the stack's plates are written as `<sensorStack>` (ours
    // only: OpenLensFlare gets the lens without them).
    let bare = system.without_sensor_stack();
    out.push_str("    <elements>\n");
    for s in &bare.surfaces {
        write_element(&mut out, s, flavor);
    }
    out.push_str("    </elements>\n");
    if flavor == Flavor::Flarebench
        && let Some(stack) = &system.sensor_stack
    {
        super::sensor_stack::write_sensor_stack(&mut out, stack, index_and_abbe, num, escape);
    }
    out.push_str("</opticalSystem>\n");
    out
}

fn type_name(s: &Surface) -> &'static str {
    match s.kind {
        SurfaceKind::Refracting if s.is_aspheric() => "lensAspherical",
        SurfaceKind::Refracting => "lensSpherical",
        SurfaceKind::ApertureStop => "apertureStop",
        SurfaceKind::Sensor => "sensor",
    }
}

/// `refractiveIndex` and `abbeNumber` as written; catalogue glasses give their listed nd/Vd.
fn index_and_abbe(medium: &Medium) -> (String, String) {
    let abbe = |v: Option<f64>| v.filter(|v| v.is_finite()).map_or("inf".to_string(), num);
    match medium {
        Medium::Air => ("1".into(), AIR_ABBE.into()),
        Medium::Model { nd, vd } => (num(*nd), abbe(*vd)),
        Medium::Glass { name, .. } => match GlassCatalog::bundled().find(name) {
            Ok(e) if e.canonical_name() == *name => (num(e.nd), num(e.vd)),
            _ => (num(medium.nd()), abbe(medium.vd())),
        },
    }
}

/// `coatingLambda` and `coatingIor`: a stack is approximated by its first layer as a
/// quarter-wave layer (read back, `<coatingStack>` takes precedence).
fn single_layer(coating: &Coating) -> (f64, f64) {
    match coating {
        Coating::None => (0.0, 0.0),
        Coating::SingleLayer {
            design_wavelength_nm,
            index,
        } => (*design_wavelength_nm, *index),
        Coating::Stack(layers) => layers
            .first()
            .map(|l| (4.0 * l.index * l.thickness_nm, l.index))
            .filter(|(lambda, _)| lambda.is_finite())
            .unwrap_or((0.0, 0.0)),
    }
}

fn write_element(out: &mut String, s: &Surface, flavor: Flavor) {
    let ours = flavor == Flavor::Flarebench;
    out.push_str("        <element>\n");
    let mut tag = |name: &str, value: &str| {
        let _ = writeln!(out, "            <{name}>{value}</{name}>");
    };
    tag("type", type_name(s));
    tag("height", &num(s.semi_diameter));
    tag("thickness", &num(s.thickness));
    tag("radius", &radius_text(s.curvature));
    if ours {
        tag("curvature", &num(s.curvature));
        if s.conic != 0.0 {
            tag("conic", &num(s.conic));
        }
        let used = s
            .aspheric
            .iter()
            .rposition(|&a| a != 0.0)
            .map_or(0, |i| i + 1);
        if used > 0 {
            let words: Vec<String> = s.aspheric[..used].iter().map(|&a| num(a)).collect();
            tag("aspheric", &words.join(" "));
        }
    }
    let (nd, vd) = index_and_abbe(&s.medium);
    tag("refractiveIndex", &nd);
    tag("abbeNumber", &vd);
    if ours && let Medium::Glass { name, .. } = &s.medium {
        tag("glass", &escape(name));
    }
    let (lambda, ior) = single_layer(&s.coating);
    tag("coatingLambda", &num(lambda));
    tag("coatingIor", &num(ior));
    if let Some(m) = &s.mask {
        tag("mask", &escape(m));
    }
    if let Some(m) = &s.mask_ft {
        tag("maskFT", &escape(m));
    }
    if ours && let Coating::Stack(layers) = &s.coating {
        out.push_str("            <coatingStack>\n");
        for l in layers {
            let _ = writeln!(
                out,
                "                <layer><index>{}</index><thicknessNm>{}</thicknessNm></layer>",
                num(l.index),
                num(l.thickness_nm)
            );
        }
        out.push_str("            </coatingStack>\n");
    }
    out.push_str("        </element>\n");
}
