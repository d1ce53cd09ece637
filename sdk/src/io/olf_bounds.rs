//! OpenLensFlare's precomputed ghost bounds (`<ghostList>` XML, written by LensPlanner's
//! `GhostSerializer`; e.g. `tests/data/heliar-tronnier-bounds-full.xml`), read into typed
//! values. What the numbers mean — units, frames, index conventions and OpenLensFlare's
//! quirks — is in `docs/formats.md` §8; the conversions here ([`OlfGhostEntry::entrance_mm`],
//! [`OlfGhostEntry::sensor_mm`]) follow it.
//!
//! The reader is strict, as OpenLensFlare's own is: an unknown, repeated or missing tag is an
//! error, reported as `file:line:column: field `tag`: message`.

#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::Path;

use super::LensFileError;
use super::located::Reporter;
use super::text;
use super::xml_tree::{self, Node};
use crate::ghost_path::GhostPath;
use crate::rect::Rect;

/// The whole file: one entry per incidence angle, in increasing angle.
#[derive(Clone, Debug, PartialEq)]
pub struct OlfGhostBounds {
    pub entries: Vec<OlfAngleEntry>,
}

/// The ghosts at one incidence angle (`<list>`).
#[derive(Clone, Debug, PartialEq)]
pub struct OlfAngleEntry {
    /// Angle between the light and the optical axis, degrees (`<angle>`).
    pub angle_deg: f64,
    pub ghosts: Vec<OlfGhostEntry>,
}

/// One ghost at one angle (`<ghost>`).
#[derive(Clone, Debug, PartialEq)]
pub struct OlfGhostEntry {
    /// The two reflecting elements, 0-based indices into the lens file's `<elements>` (stop
    /// and sensor included), in the order the light meets them: `interfaces[0]` first (the
    /// later element), then `interfaces[1]` on the way back. Always `interfaces[0] >
    /// interfaces[1]`.
    pub interfaces: [usize; 2],
    /// Entrance-plane bounds in units of the first element's semi-diameter, OpenLensFlare's
    /// frame (the light tilted toward +x).
    pub pupil: OlfRect,
    /// Sensor bounds in units of half the film width (x) and half the film height (y).
    pub sensor: OlfRect,
    /// Mean reflectance product of the rays that passed, clamped to 1 (`<avgIntensity>`).
    pub avg_intensity: f64,
    /// Wavelength channels to render (`<minChannels>`, `<optimalChannels>`).
    pub min_channels: u32,
    pub optimal_channels: u32,
    /// Ray grid size per side chosen by OpenLensFlare; 0 when it did not choose one
    /// (`<minRays>`, `<optimalRays>`).
    pub min_rays: u32,
    pub optimal_rays: u32,
}

/// A rectangle as OpenLensFlare stores it: lower corner and size (`<x> <y> <w> <h>`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OlfRect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl OlfRect {
    /// OpenLensFlare marks a ghost that no ray of which reaches the sensor with all four
    /// values −1; any negative size means "no bounds".
    pub fn is_empty(&self) -> bool {
        !(self.w >= 0.0 && self.h >= 0.0)
    }
}

impl OlfGhostEntry {
    /// The ghost as our path: first reflection at `interfaces[0]`, second at `interfaces[1]`.
    /// OpenLensFlare's element indices are our surface indices for lenses converted from its
    /// XML (same element list, stop and sensor included).
    pub fn path(&self) -> GhostPath {
        GhostPath::two(self.interfaces[0], self.interfaces[1])
    }

    /// True when OpenLensFlare found rays of this ghost on the sensor.
    pub fn is_visible(&self) -> bool {
        !self.pupil.is_empty()
    }

    /// The entrance-plane bounds in mm in our meridional frame (light in the y–z plane):
    /// OpenLensFlare's x (the tilt direction) becomes our y, its y our x — a rotation, since
    /// its z axis points toward the object. `front_semi_diameter_mm` is the first surface's
    /// semi-diameter. `None` for an invisible ghost. The plane is 0.1 mm in front of the first
    /// vertex (docs/formats.md §8).
    pub fn entrance_mm(&self, front_semi_diameter_mm: f64) -> Option<Rect> {
        let s = front_semi_diameter_mm;
        self.is_visible().then(|| swap_axes(&self.pupil, s, s))
    }

    /// The sensor bounds in mm in our meridional frame (as [`Self::entrance_mm`]): x from
    /// OpenLensFlare's y times half the film height, y from its x times half the film width.
    /// `None` for an invisible ghost.
    pub fn sensor_mm(&self, film_width_mm: f64, film_height_mm: f64) -> Option<Rect> {
        self.is_visible()
            .then(|| swap_axes(&self.sensor, 0.5 * film_width_mm, 0.5 * film_height_mm))
    }
}

/// OpenLensFlare's `(x, y)` scaled by `(sx, sy)` into our `(y, x)`.
fn swap_axes(r: &OlfRect, sx: f64, sy: f64) -> Rect {
    Rect {
        x0: r.y * sy,
        y0: r.x * sx,
        x1: (r.y + r.h) * sy,
        y1: (r.x + r.w) * sx,
    }
}

impl OlfGhostBounds {
    /// The entry whose angle is nearest `angle_deg` (ties go to the smaller angle); `None`
    /// when there are no entries or `angle_deg` is NaN.
    pub fn nearest(&self, angle_deg: f64) -> Option<&OlfAngleEntry> {
        if angle_deg.is_nan() {
            return None;
        }
        let i = self.entries.partition_point(|e| e.angle_deg < angle_deg);
        let after = self.entries.get(i);
        let before = i.checked_sub(1).and_then(|j| self.entries.get(j));
        match (before, after) {
            (Some(b), Some(a)) => Some(if angle_deg - b.angle_deg <= a.angle_deg - angle_deg {
                b
            } else {
                a
            }),
            (b, a) => b.or(a),
        }
    }
}

/// Reads an OpenLensFlare ghost-bounds file (UTF-8, or UTF-16 with a byte-order mark).
pub fn read_olf_bounds(path: &Path) -> Result<OlfGhostBounds, LensFileError> {
    let label = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| LensFileError::io(&label, &e))?;
    let text = text::decode(&bytes).map_err(|e| {
        let valid = std::str::from_utf8(&bytes[..e.offset.min(bytes.len())]).unwrap_or("");
        let (line, column) = text::LineIndex::new(valid).line_col(valid.len());
        LensFileError::at(&label, line, column, "", e.message)
    })?;
    parse_olf_bounds(&text, &label)
}

/// Parses the text of an OpenLensFlare ghost-bounds file; `label` names it in errors.
pub fn parse_olf_bounds(text: &str, label: &str) -> Result<OlfGhostBounds, LensFileError> {
    let rep = Reporter::new(label, text);
    let root = xml_tree::parse(text)
        .map_err(|e| rep.error(e.pos, e.element.as_deref().unwrap_or(""), e.message.clone()))?;
    if root.name != "ghostList" {
        return Err(rep.error(
            root.pos,
            &root.name,
            format!(
                "not an OpenLensFlare ghost-bounds file: the root is <{}>, expected <ghostList>",
                root.name
            ),
        ));
    }
    no_text(&rep, &root)?;
    let mut entries: Vec<OlfAngleEntry> = Vec::with_capacity(root.children.len());
    for list in &root.children {
        expect_name(&rep, list, "list", "ghostList")?;
        let entry = read_list(&rep, list)?;
        // Angles are finite (`number` checks), so `<=` is "not increasing".
        if let Some(prev) = entries.last()
            && entry.angle_deg <= prev.angle_deg
        {
            let angle = fields(&rep, list, &["angle", "ghosts"])?["angle"];
            return Err(rep.error(
                angle.value_pos(),
                "angle",
                format!(
                    "angles must increase from list to list: {} after {}",
                    entry.angle_deg, prev.angle_deg
                ),
            ));
        }
        entries.push(entry);
    }
    Ok(OlfGhostBounds { entries })
}

fn read_list(rep: &Reporter<'_>, list: &Node) -> Result<OlfAngleEntry, LensFileError> {
    let f = fields(rep, list, &["angle", "ghosts"])?;
    let angle_deg = number(rep, required(rep, &f, list, "angle")?)?;
    let ghosts_node = required(rep, &f, list, "ghosts")?;
    no_text(rep, ghosts_node)?;
    let mut ghosts = Vec::with_capacity(ghosts_node.children.len());
    for g in &ghosts_node.children {
        expect_name(rep, g, "ghost", "ghosts")?;
        ghosts.push(read_ghost(rep, g)?);
    }
    Ok(OlfAngleEntry { angle_deg, ghosts })
}

const GHOST_TAGS: [&str; 8] = [
    "interfaces",
    "pupilBounds",
    "sensorBounds",
    "avgIntensity",
    "minChannels",
    "optimalChannels",
    "minRays",
    "optimalRays",
];

fn read_ghost(rep: &Reporter<'_>, g: &Node) -> Result<OlfGhostEntry, LensFileError> {
    let f = fields(rep, g, &GHOST_TAGS)?;
    let req = |name: &str| required(rep, &f, g, name);
    Ok(OlfGhostEntry {
        interfaces: interfaces(rep, req("interfaces")?)?,
        pupil: rect(rep, req("pupilBounds")?)?,
        sensor: rect(rep, req("sensorBounds")?)?,
        avg_intensity: number(rep, req("avgIntensity")?)?,
        min_channels: count(rep, req("minChannels")?)?,
        optimal_channels: count(rep, req("optimalChannels")?)?,
        min_rays: count(rep, req("minRays")?)?,
        optimal_rays: count(rep, req("optimalRays")?)?,
    })
}

fn interfaces(rep: &Reporter<'_>, node: &Node) -> Result<[usize; 2], LensFileError> {
    no_text(rep, node)?;
    let mut values = Vec::with_capacity(2);
    for child in &node.children {
        expect_name(rep, child, "interface", "interfaces")?;
        let v = child.value();
        let index = v.parse::<usize>().map_err(|_| {
            rep.error(
                child.value_pos(),
                "interface",
                format!("expected an element index (0, 1, 2, …), got `{v}`"),
            )
        })?;
        values.push(index);
    }
    match values[..] {
        [first, second] if first > second => Ok([first, second]),
        [first, second] => Err(rep.error(
            node.pos,
            "interfaces",
            format!(
                "the first reflection must be at a later element than the second, got {first} then {second}"
            ),
        )),
        _ => Err(rep.error(
            node.pos,
            "interfaces",
            format!(
                "flarebench reads two-reflection ghosts only; this one lists {} interfaces",
                values.len()
            ),
        )),
    }
}

fn rect(rep: &Reporter<'_>, node: &Node) -> Result<OlfRect, LensFileError> {
    let f = fields(rep, node, &["x", "y", "w", "h"])?;
    let get = |name: &str| number(rep, required(rep, &f, node, name)?);
    Ok(OlfRect {
        x: get("x")?,
        y: get("y")?,
        w: get("w")?,
        h: get("h")?,
    })
}

/// A finite decimal number.
fn number(rep: &Reporter<'_>, node: &Node) -> Result<f64, LensFileError> {
    let v = node.value();
    match v.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(rep.error(
            node.value_pos(),
            &node.name,
            format!("must be finite, got {v}"),
        )),
        Err(_) => Err(rep.error(
            node.value_pos(),
            &node.name,
            if v.is_empty() {
                "expected a number, the tag is empty".to_string()
            } else {
                format!("expected a number, got `{v}`")
            },
        )),
    }
}

/// A non-negative whole number (OpenLensFlare writes integers and reads them as decimals, so
/// `5.0` is accepted too).
fn count(rep: &Reporter<'_>, node: &Node) -> Result<u32, LensFileError> {
    let x = number(rep, node)?;
    if x >= 0.0 && x <= f64::from(u32::MAX) && x.fract() == 0.0 {
        // Whole and in range: the cast is exact.
        Ok(x as u32)
    } else {
        Err(rep.error(
            node.value_pos(),
            &node.name,
            format!("expected a whole number ≥ 0, got {}", node.value()),
        ))
    }
}

/// The children of `node` by name, each allowed once; an unknown or repeated tag, or text
/// between the children, is an error.
fn fields<'n>(
    rep: &Reporter<'_>,
    node: &'n Node,
    allowed: &[&str],
) -> Result<HashMap<&'n str, &'n Node>, LensFileError> {
    no_text(rep, node)?;
    let mut map = HashMap::with_capacity(node.children.len());
    for child in &node.children {
        if !allowed.contains(&child.name.as_str()) {
            return Err(rep.error(
                child.pos,
                &child.name,
                format!(
                    "unknown tag <{}> in <{}> (expected {})",
                    child.name,
                    node.name,
                    allowed.join(", ")
                ),
            ));
        }
        if map.insert(child.name.as_str(), child).is_some() {
            return Err(rep.error(
                child.pos,
                &child.name,
                format!("<{}> appears twice in one <{}>", child.name, node.name),
            ));
        }
    }
    Ok(map)
}

fn required<'n>(
    rep: &Reporter<'_>,
    fields: &HashMap<&str, &'n Node>,
    parent: &Node,
    name: &str,
) -> Result<&'n Node, LensFileError> {
    fields.get(name).copied().ok_or_else(|| {
        rep.error(
            parent.pos,
            name,
            format!("<{}> has no <{name}>", parent.name),
        )
    })
}

fn expect_name(
    rep: &Reporter<'_>,
    node: &Node,
    name: &str,
    parent: &str,
) -> Result<(), LensFileError> {
    if node.name == name {
        Ok(())
    } else {
        Err(rep.error(
            node.pos,
            &node.name,
            format!(
                "unknown tag <{}> in <{parent}> (expected <{name}>)",
                node.name
            ),
        ))
    }
}

/// Containers hold elements only.
fn no_text(rep: &Reporter<'_>, node: &Node) -> Result<(), LensFileError> {
    match node.text_pos {
        Some(pos) => Err(rep.error(
            pos,
            &node.name,
            format!("text in <{}>, where only elements belong", node.name),
        )),
        None => Ok(()),
    }
}
