//! Reading OpenLensFlare XML and our superset of it into a [`LensSystem`].

use super::spans::{ElementSpans, SystemSpans};
use super::tags;
use crate::coating::{Coating, CoatingLayer};
use crate::glass::GlassCatalog;
use crate::io::LensFileError;
use crate::io::text::LineIndex;
use crate::io::xml_tree::{self, Node};
use crate::system::{LensSystem, Medium, Surface, SurfaceKind, curvature_from_radius};

/// Film size used when a file gives none (full-frame 35 mm).
const DEFAULT_FILM_MM: (f64, f64) = (36.0, 24.0);

/// A parsed but not yet validated system, with the positions of its fields.
#[derive(Debug)]
pub(super) struct Parsed {
    pub system: LensSystem,
    pub spans: SystemSpans,
    pub warnings: Vec<String>,
}

/// The file being read: its name, its line index and the warnings so far.
struct Ctx<'a> {
    file: &'a str,
    lines: LineIndex<'a>,
    warnings: Vec<String>,
}

impl Ctx<'_> {
    fn error(&self, pos: usize, field: &str, message: impl Into<String>) -> LensFileError {
        let (line, column) = self.lines.line_col(pos);
        LensFileError::at(self.file, line, column, field, message)
    }

    fn warn(&mut self, pos: usize, message: impl AsRef<str>) {
        let (line, column) = self.lines.line_col(pos);
        self.warnings.push(format!(
            "{}:{line}:{column}: {}",
            self.file,
            message.as_ref()
        ));
    }
}

/// Parses the document without validating the resulting system.
pub(super) fn parse_document(text: &str, file: &str) -> Result<Parsed, LensFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ctx = Ctx {
        file,
        lines: LineIndex::new(text),
        warnings: Vec::new(),
    };
    let root = xml_tree::parse(text).map_err(|e| {
        let field = e.element.unwrap_or_default();
        ctx.error(e.pos, &field, e.message)
    })?;
    let (system, spans) = read_system(&mut ctx, &root, file)?;
    Ok(Parsed {
        system,
        spans,
        warnings: ctx.warnings,
    })
}

/// The known children of one element, first occurrence of each; warns about the rest.
struct Fields<'n> {
    found: Vec<(&'static str, &'n Node)>,
}

impl<'n> Fields<'n> {
    fn collect(ctx: &mut Ctx<'_>, parent: &'n Node, known: &[&'static str]) -> Self {
        let mut found: Vec<(&'static str, &'n Node)> = Vec::new();
        for child in &parent.children {
            match known.iter().find(|k| **k == child.name) {
                Some(&k) if found.iter().any(|(n, _)| *n == k) => ctx.warn(
                    child.pos,
                    format!(
                        "<{k}> appears again in <{}>; the first one is used",
                        parent.name
                    ),
                ),
                Some(&k) => found.push((k, child)),
                None => ctx.warn(
                    child.pos,
                    format!("unknown tag <{}> in <{}> ignored", child.name, parent.name),
                ),
            }
        }
        if let Some(p) = parent.text_pos {
            ctx.warn(p, format!("text directly inside <{}> ignored", parent.name));
        }
        Fields { found }
    }

    fn get(&self, tag: &str) -> Option<&'n Node> {
        self.found
            .iter()
            .find(|(n, _)| *n == tag)
            .map(|(_, node)| *node)
    }

    fn positions(&self) -> Vec<(&'static str, usize)> {
        self.found
            .iter()
            .map(|(n, node)| (*n, node.value_pos()))
            .collect()
    }
}

/// A finite number, or `None` when the tag is absent or empty.
fn number(ctx: &mut Ctx<'_>, node: Option<&Node>) -> Result<Option<f64>, LensFileError> {
    let Some(node) = node else { return Ok(None) };
    let t = node.value();
    if t.is_empty() {
        ctx.warn(
            node.pos,
            format!("<{}> is empty; treated as absent", node.name),
        );
        return Ok(None);
    }
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(_) => Err(ctx.error(
            node.value_pos(),
            &node.name,
            format!("must be finite, got {t}"),
        )),
        Err(_) => Err(ctx.error(
            node.value_pos(),
            &node.name,
            format!("expected a number, got `{t}`"),
        )),
    }
}

/// Trimmed text, `None` when absent or empty.
fn text(node: Option<&Node>) -> Option<String> {
    node.map(|n| n.value().to_string())
        .filter(|s| !s.is_empty())
}

fn read_system(
    ctx: &mut Ctx<'_>,
    root: &Node,
    file: &str,
) -> Result<(LensSystem, SystemSpans), LensFileError> {
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
    // OpenLensFlare writes 0 for an unset f-number, focal length or field of view.
    let unset_zero = |v: Option<f64>| v.filter(|x| *x != 0.0);
    let f_number = unset_zero(number(ctx, f.get("fnumber"))?);
    let stated_efl_mm = unset_zero(number(ctx, f.get("effectiveFocalLength"))?);
    let field_of_view_deg = unset_zero(number(ctx, f.get("fieldOfView"))?);
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
        f_number,
        stated_efl_mm,
        field_of_view_deg,
        film_width_mm,
        film_height_mm,
        notes: text(f.get("notes")).unwrap_or_default(),
        source: text(f.get("source")).unwrap_or_default(),
        surfaces,
    };
    let spans = SystemSpans {
        pos: root.pos,
        fields: f.positions(),
        elements_pos: Some(elements.pos),
        elements: element_spans,
    };
    Ok((system, spans))
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

/// The Abbe number: a finite value, or `inf` for a non-dispersive medium.
enum Abbe {
    Finite(f64),
    NonDispersive,
}

fn read_abbe(ctx: &mut Ctx<'_>, node: Option<&Node>) -> Result<Option<Abbe>, LensFileError> {
    if let Some(n) = node
        && let Ok(v) = n.value().parse::<f64>()
        && v == f64::INFINITY
    {
        return Ok(Some(Abbe::NonDispersive));
    }
    Ok(number(ctx, node)?.map(Abbe::Finite))
}

/// The medium after the surface: a catalogue `<glass>`, else `refractiveIndex`/`abbeNumber`.
fn read_medium(
    ctx: &mut Ctx<'_>,
    f: &Fields<'_>,
    node: &Node,
    lens: bool,
) -> Result<Medium, LensFileError> {
    let nd = number(ctx, f.get("refractiveIndex"))?;
    let abbe = read_abbe(ctx, f.get("abbeNumber"))?;
    if let Some(g) = f.get("glass") {
        let name = g.value();
        if name.is_empty() {
            ctx.warn(g.pos, "<glass> is empty; treated as absent");
        } else {
            let entry = GlassCatalog::bundled()
                .find(name)
                .map_err(|e| ctx.error(g.value_pos(), "glass", e.to_string()))?;
            if let Some(n) = nd
                && (n - entry.nd).abs() > 5e-5
            {
                ctx.warn(
                    g.value_pos(),
                    format!(
                        "refractiveIndex {n} differs from {}'s nd {}; the glass is used",
                        entry.canonical_name(),
                        entry.nd
                    ),
                );
            }
            if let Some(Abbe::Finite(v)) = abbe
                && (v - entry.vd).abs() > 0.05
            {
                ctx.warn(
                    g.value_pos(),
                    format!(
                        "abbeNumber {v} differs from {}'s Vd {}; the glass is used",
                        entry.canonical_name(),
                        entry.vd
                    ),
                );
            }
            return Ok(Medium::Glass {
                name: entry.canonical_name(),
                dispersion: entry.dispersion.clone(),
            });
        }
    }
    Ok(match nd {
        None => {
            if lens {
                ctx.warn(
                    node.pos,
                    "no <refractiveIndex>; the medium after this surface is taken as air",
                );
            }
            Medium::Air
        }
        Some(1.0) => Medium::Air,
        Some(n) => {
            let vd = match abbe {
                Some(Abbe::Finite(v)) => Some(v),
                Some(Abbe::NonDispersive) => None,
                None => {
                    ctx.warn(
                        node.pos,
                        format!(
                            "glass n = {n} without <abbeNumber> is taken as non-dispersive \
                             (write <abbeNumber>inf</abbeNumber> to say so)"
                        ),
                    );
                    None
                }
            };
            Medium::Model { nd: n, vd }
        }
    })
}

/// `<coatingStack>` takes precedence; else `coatingLambda` + `coatingIor` (0 or absent: none).
fn read_coating(ctx: &mut Ctx<'_>, f: &Fields<'_>) -> Result<Coating, LensFileError> {
    if let Some(stack) = f.get("coatingStack") {
        let mut layers = Vec::new();
        for child in &stack.children {
            if child.name != tags::LAYER {
                ctx.warn(
                    child.pos,
                    format!("unknown tag <{}> in <coatingStack> ignored", child.name),
                );
                continue;
            }
            let lf = Fields::collect(ctx, child, tags::LAYER_TAGS);
            let mut value = |tag: &str| -> Result<f64, LensFileError> {
                number(ctx, lf.get(tag))?.ok_or_else(|| {
                    ctx.error(child.pos, tag, format!("a coating layer needs <{tag}>"))
                })
            };
            let index = value("index")?;
            let thickness_nm = value("thicknessNm")?;
            layers.push(CoatingLayer {
                index,
                thickness_nm,
            });
        }
        return Ok(Coating::Stack(layers));
    }
    let lambda = number(ctx, f.get("coatingLambda"))?.unwrap_or(0.0);
    let ior = number(ctx, f.get("coatingIor"))?.unwrap_or(0.0);
    Ok(if lambda != 0.0 && ior != 0.0 {
        Coating::SingleLayer {
            design_wavelength_nm: lambda,
            index: ior,
        }
    } else {
        if lambda != 0.0 || ior != 0.0 {
            let at = f
                .get("coatingIor")
                .or(f.get("coatingLambda"))
                .map_or(0, Node::value_pos);
            ctx.warn(
                at,
                "a coating needs both coatingLambda and coatingIor; the surface is uncoated",
            );
        }
        Coating::None
    })
}
