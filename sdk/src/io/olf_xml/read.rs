//! Reading OpenLensFlare XML and our superset of it into a [`LensSystem`].

use super::coating::read_coating;
use super::fields::{Ctx, Fields, number, text};
use super::medium::read_medium;
use super::sensor_stack::read_sensor_stack;
use super::spans::{ElementSpans, SystemSpans};
use super::tags;
use crate::io::LensFileError;
use crate::io::xml_tree::{self, Node};
use crate::lens_kind::parse_kinds;
use crate::system::{LensSystem, SensorStack, Surface, SurfaceKind, curvature_from_radius};

/// Film size used when a file gives none (full-frame 35 mm).
const DEFAULT_FILM_MM: (f64, f64) = (36.0, 24.0);

/// A parsed but not yet validated system, with the positions of its fields.
#[derive(Debug)]
pub(super) struct Parsed {
    /// The lens without its sensor stack.
    pub system: LensSystem,
    pub spans: SystemSpans,
    pub warnings: Vec<String>,
    /// `<sensorStack>` as read, with the byte offset of its tag: put behind the lens once the
    /// lens is valid.
    pub sensor_stack: Option<(SensorStack, usize)>,
}

/// Parses the document without validating the resulting system.
pub(super) fn parse_document(text: &str, file: &str) -> Result<Parsed, LensFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ctx = Ctx::new(file, text);
    let root = xml_tree::parse(text).map_err(|e| {
        let field = e.element.unwrap_or_default();
        ctx.error(e.pos, &field, e.message)
    })?;
    let (system, spans, sensor_stack) = read_system(&mut ctx, &root, file)?;
    Ok(Parsed {
        system,
        spans,
        warnings: ctx.warnings,
        sensor_stack,
    })
}

/// What [`read_system`] reads: the bare lens, where its fields are, its sensor stack.
type SystemRead = (LensSystem, SystemSpans, Option<(SensorStack, usize)>);

fn read_system(ctx: &mut Ctx<'_>, root: &Node, file: &str) -> Result<SystemRead, LensFileError> {
    if root.name != tags::SYSTEM {
        return Err(ctx.error(
            root.pos,
            &root.name,
            format!(
                "expected <{}> as the root element, found <{}>",
                tags::SYSTEM,
                root.name
            ),
        ));
    }
    let f = Fields::collect(ctx, root, tags::SYSTEM_TAGS);
    let name = match text(f.get("name")) {
        Some(n) => n,
        None => {
            let stem = std::path::Path::new(file)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            ctx.warn(
                root.pos,
                format!("no <name>; the system is called `{stem}`"),
            );
            stem
        }
    };
    let kind = match f.get("kind") {
        Some(node) => {
            parse_kinds(node.value()).map_err(|m| ctx.error(node.value_pos(), "kind", m))?
        }
        None => Vec::new(),
    };
    let nominal_focal_mm = read_nominal_focal(ctx, f.get("nominalFocalLength"))?;
    // OpenLensFlare writes 0 for an unset f-number, focal length or field of view.
    let unset_zero = |v: Option<f64>| v.filter(|x| *x != 0.0);
    let f_number = unset_zero(number(ctx, f.get("fnumber"))?);
    let stated_efl_mm = unset_zero(number(ctx, f.get("effectiveFocalLength"))?);
    let field_of_view_deg = unset_zero(number(ctx, f.get("fieldOfView"))?);
    let primary_wavelength_nm = number(ctx, f.get("primaryWavelength"))?;
    let mut film = [
        ("filmWidth", DEFAULT_FILM_MM.0),
        ("filmHeight", DEFAULT_FILM_MM.1),
    ];
    for (tag, value) in &mut film {
        match number(ctx, f.get(tag))? {
            Some(v) => *value = v,
            None => ctx.warn(root.pos, format!("no <{tag}>; using {value} mm")),
        }
    }
    let [(_, film_width_mm), (_, film_height_mm)] = film;
    let Some(elements) = f.get("elements") else {
        return Err(ctx.error(
            root.pos,
            "elements",
            "no <elements>: a system needs its surfaces",
        ));
    };
    let half_diagonal = 0.5 * film_width_mm.hypot(film_height_mm);
    let mut surfaces = Vec::new();
    let mut element_spans = Vec::new();
    for child in &elements.children {
        if child.name != tags::ELEMENT {
            ctx.warn(
                child.pos,
                format!("unknown tag <{}> in <elements> ignored", child.name),
            );
            continue;
        }
        let (surface, spans) = read_element(ctx, child, half_diagonal)?;
        surfaces.push(surface);
        element_spans.push(spans);
    }
    if let Some(p) = elements.text_pos {
        ctx.warn(p, "text directly inside <elements> ignored");
    }
    let system = LensSystem {
        name,
        maker: text(f.get("maker")).unwrap_or_default(),
        kind,
        nominal_focal_mm,
        f_number,
        stated_efl_mm,
        field_of_view_deg,
        primary_wavelength_nm,
        film_width_mm,
        film_height_mm,
        notes: text(f.get("notes")).unwrap_or_default(),
        source: text(f.get("source")).unwrap_or_default(),
        surfaces,
        sensor_stack: None,
    };
    let spans = SystemSpans {
        pos: root.pos,
        fields: f.positions(),
        elements_pos: Some(elements.pos),
        elements: element_spans,
    };
    let sensor_stack = match f.get("sensorStack") {
        Some(node) => Some((read_sensor_stack(ctx, node)?, node.pos)),
        None => None,
    };
    Ok((system, spans, sensor_stack))
}

fn read_element(
    ctx: &mut Ctx<'_>,
    node: &Node,
    sensor_default_sd: f64,
) -> Result<(Surface, ElementSpans), LensFileError> {
    let f = Fields::collect(ctx, node, tags::ELEMENT_TAGS);
    let (kind, declared_aspheric) = match f.get("type") {
        Some(t) => match t.value() {
            "lensSpherical" => (SurfaceKind::Refracting, false),
            "lensAspherical" => (SurfaceKind::Refracting, true),
            "apertureStop" => (SurfaceKind::ApertureStop, false),
            "sensor" => (SurfaceKind::Sensor, false),
            other => {
                return Err(ctx.error(
                    t.value_pos(),
                    "type",
                    format!(
                        "unknown element type `{other}`; expected lensSpherical, \
                         lensAspherical, apertureStop or sensor"
                    ),
                ));
            }
        },
        None => {
            ctx.warn(node.pos, "no <type>; taken as lensSpherical");
            (SurfaceKind::Refracting, false)
        }
    };
    let lens = kind == SurfaceKind::Refracting;

    let semi_diameter = match number(ctx, f.get("height"))? {
        Some(h) if h < 0.0 => {
            let at = f.get("height").map_or(node.pos, Node::value_pos);
            return Err(ctx.error(
                at,
                "height",
                format!("the clear semi-diameter must not be negative, got {h}"),
            ));
        }
        Some(h) => h,
        None if kind == SurfaceKind::Sensor => {
            ctx.warn(
                node.pos,
                format!(
                    "sensor without <height>; using the film's half diagonal {sensor_default_sd} mm"
                ),
            );
            sensor_default_sd
        }
        None => {
            return Err(ctx.error(
                node.pos,
                "height",
                "missing <height>: the clear semi-diameter (mm) is required",
            ));
        }
    };
    let thickness = match number(ctx, f.get("thickness"))? {
        Some(t) => t,
        None => {
            if kind != SurfaceKind::Sensor {
                ctx.warn(node.pos, "no <thickness>; using 0 mm");
            }
            0.0
        }
    };
    let curvature = read_curvature(ctx, &f, node, lens)?;
    let conic = number(ctx, f.get("conic"))?.unwrap_or(0.0);
    let aspheric = read_aspheric(ctx, f.get("aspheric"))?;
    let medium = read_medium(ctx, &f, node, lens)?;
    let coating = read_coating(ctx, &f)?;
    let surface = Surface {
        kind,
        curvature,
        conic,
        aspheric,
        thickness,
        medium,
        semi_diameter,
        coating,
        mask: text(f.get("mask")),
        mask_ft: text(f.get("maskFT")),
    };
    if declared_aspheric && !surface.is_aspheric() {
        ctx.warn(
            node.pos,
            "lensAspherical without <conic> or <aspheric> terms is traced as a sphere",
        );
    }
    let spans = ElementSpans {
        pos: node.pos,
        fields: f.positions(),
    };
    Ok((surface, spans))
}

/// `<curvature>` (exact) takes precedence over `<radius>`; 0 or a missing radius is flat.
fn read_curvature(
    ctx: &mut Ctx<'_>,
    f: &Fields<'_>,
    node: &Node,
    lens: bool,
) -> Result<f64, LensFileError> {
    let radius = number(ctx, f.get("radius"))?;
    let curvature = number(ctx, f.get("curvature"))?;
    Ok(match (curvature, radius) {
        (Some(c), Some(r)) => {
            let from_r = curvature_from_radius(r);
            if (from_r - c).abs() > 1e-9 * c.abs().max(from_r.abs()) {
                let at = f.get("radius").map_or(node.pos, Node::value_pos);
                ctx.warn(
                    at,
                    format!("<radius> {r} disagrees with <curvature> {c}; the curvature is used"),
                );
            }
            c
        }
        (Some(c), None) => c,
        (None, Some(r)) => curvature_from_radius(r),
        (None, None) => {
            if lens {
                ctx.warn(node.pos, "no <radius>; the surface is taken as flat");
            }
            0.0
        }
    })
}

/// `<nominalFocalLength>`: the focal length the maker names the lens by (mm), one positive
/// number (a prime) or the shortest and longest in order (a zoom).
fn read_nominal_focal(
    ctx: &mut Ctx<'_>,
    node: Option<&Node>,
) -> Result<Option<[f64; 2]>, LensFileError> {
    let Some(node) = node else { return Ok(None) };
    let values: Option<Vec<f64>> = node
        .value()
        .split_whitespace()
        .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0))
        .collect();
    match values.as_deref() {
        Some(&[f]) => Ok(Some([f, f])),
        Some(&[a, b]) if a <= b => Ok(Some([a, b])),
        _ => Err(ctx.error(
            node.value_pos(),
            "nominalFocalLength",
            format!(
                "expected the focal length the lens is named by in mm, one positive number \
                 (`135`) or a zoom's shortest and longest in order (`24 70`), got `{}`",
                node.value()
            ),
        )),
    }
}

fn read_aspheric(ctx: &mut Ctx<'_>, node: Option<&Node>) -> Result<[f64; 8], LensFileError> {
    let mut coeffs = [0.0; 8];
    let Some(node) = node else {
        return Ok(coeffs);
    };
    let words: Vec<&str> = node.value().split_whitespace().collect();
    if words.len() > coeffs.len() {
        return Err(ctx.error(
            node.value_pos(),
            "aspheric",
            format!(
                "at most 8 coefficients (r² … r¹⁶) are allowed, got {}",
                words.len()
            ),
        ));
    }
    for (slot, word) in coeffs.iter_mut().zip(&words) {
        *slot = match word.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            Ok(_) => {
                return Err(ctx.error(
                    node.value_pos(),
                    "aspheric",
                    format!("must be finite, got {word}"),
                ));
            }
            Err(_) => {
                return Err(ctx.error(
                    node.value_pos(),
                    "aspheric",
                    format!("expected numbers, got `{word}`"),
                ));
            }
        };
    }
    Ok(coeffs)
}
