//! `<sensorStack>`: the plates in front of the sensor and the sensor's spectral reflectance
//! (docs/formats.md §2, *The sensor stack*), read and written.

#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "NaN-aware checks of validity: `!(x > 0)` is true for NaN (docs/CODE_STYLE.md)"
)]

use std::fmt::Write as _;

use super::coating::read_coating;
use super::fields::{Ctx, Fields, number};
use super::medium::read_medium;
use super::tags;
use crate::coating::Coating;
use crate::io::LensFileError;
use crate::io::xml_tree::Node;
use crate::system::{Plate, SensorStack, SpectralReflectance};

/// Reads `<sensorStack>`; every bad value is an error at its own tag.
pub(super) fn read_sensor_stack(
    ctx: &mut Ctx<'_>,
    node: &Node,
) -> Result<SensorStack, LensFileError> {
    let mut plates = Vec::new();
    let mut reflectance = None;
    for child in &node.children {
        match child.name.as_str() {
            tags::PLATE => plates.push(read_plate(ctx, child, plates.len() + 1)?),
            tags::SENSOR_REFLECTANCE if reflectance.is_none() => {
                reflectance = Some(read_reflectance(ctx, child)?);
            }
            tags::SENSOR_REFLECTANCE => ctx.warn(
                child.pos,
                "<sensorReflectance> appears again in <sensorStack>; the first one is used",
            ),
            other => ctx.warn(
                child.pos,
                format!("unknown tag <{other}> in <sensorStack> ignored"),
            ),
        }
    }
    if let Some(p) = node.text_pos {
        ctx.warn(p, "text directly inside <sensorStack> ignored");
    }
    let Some(reflectance) = reflectance else {
        return Err(ctx.error(
            node.pos,
            tags::SENSOR_REFLECTANCE,
            "a sensor stack needs <sensorReflectance>: the sensor's reflectance by wavelength",
        ));
    };
    Ok(SensorStack::new(plates, reflectance))
}

fn read_plate(ctx: &mut Ctx<'_>, node: &Node, k: usize) -> Result<Plate, LensFileError> {
    let f = Fields::collect(ctx, node, tags::PLATE_TAGS);
    // A required length: present, finite and above `min` (or at least `min` when `open`).
    let mut length = |tag: &str, min_open: bool, what: &str| -> Result<f64, LensFileError> {
        let Some(v) = number(ctx, f.get(tag))? else {
            return Err(ctx.error(node.pos, tag, format!("plate {k} needs <{tag}>: {what}")));
        };
        let ok = if min_open { v > 0.0 } else { v >= 0.0 };
        if !ok {
            let at = f.get(tag).map_or(node.pos, Node::value_pos);
            let bound = if min_open { "> 0" } else { "≥ 0" };
            return Err(ctx.error(at, tag, format!("plate {k}: must be {bound} mm, got {v}")));
        }
        Ok(v)
    };
    let thickness = length("thickness", true, "its thickness in mm")?;
    let gap = length(
        "gap",
        false,
        "the distance in mm from its back face to the next plate or the sensor",
    )?;
    let semi_diameter = length("height", true, "its clear semi-diameter in mm")?;
    if f.get("glass").is_none() && f.get("refractiveIndex").is_none() {
        return Err(ctx.error(
            node.pos,
            "refractiveIndex",
            format!("plate {k} needs its glass: <glass> or <refractiveIndex> (and <abbeNumber>)"),
        ));
    }
    let medium = read_medium(ctx, &f, node, true)?;
    let mut face = |tag: &str| -> Result<Coating, LensFileError> {
        match f.get(tag) {
            None => Ok(Coating::None),
            Some(n) => {
                let cf = Fields::collect(ctx, n, tags::FACE_TAGS);
                let c = read_coating(ctx, &cf)?;
                if let Err(m) = c.validate() {
                    let at = ["coatingStack", "coatingIor", "coatingLambda"]
                        .iter()
                        .find_map(|t| cf.get(t))
                        .map_or(n.pos, Node::value_pos);
                    return Err(ctx.error(at, tag, format!("plate {k}: {m}")));
                }
                Ok(c)
            }
        }
    };
    let front_coating = face("front")?;
    let back_coating = face("back")?;
    Ok(Plate {
        medium,
        thickness,
        gap,
        semi_diameter,
        front_coating,
        back_coating,
    })
}

fn read_reflectance(ctx: &mut Ctx<'_>, node: &Node) -> Result<SpectralReflectance, LensFileError> {
    let mut points: Vec<(f64, f64)> = Vec::new();
    for child in &node.children {
        if child.name != tags::POINT {
            ctx.warn(
                child.pos,
                format!(
                    "unknown tag <{}> in <sensorReflectance> ignored",
                    child.name
                ),
            );
            continue;
        }
        let k = points.len() + 1;
        let pf = Fields::collect(ctx, child, tags::POINT_TAGS);
        let mut value = |tag: &str| -> Result<(f64, usize), LensFileError> {
            let v = number(ctx, pf.get(tag))?
                .ok_or_else(|| ctx.error(child.pos, tag, format!("point {k} needs <{tag}>")))?;
            Ok((v, pf.get(tag).map_or(child.pos, Node::value_pos)))
        };
        let (nm, nm_at) = value("wavelength")?;
        let (r, r_at) = value("reflectance")?;
        if !(nm > 0.0) {
            return Err(ctx.error(
                nm_at,
                "wavelength",
                format!("point {k}: must be a positive wavelength in nm, got {nm}"),
            ));
        }
        if let Some(&(prev, _)) = points.last()
            && !(nm > prev)
        {
            return Err(ctx.error(
                nm_at,
                "wavelength",
                format!("point {k}: wavelengths must increase, got {nm} nm after {prev} nm"),
            ));
        }
        if !(0.0..=1.0).contains(&r) {
            return Err(ctx.error(
                r_at,
                "reflectance",
                format!("point {k}: must lie in [0, 1], got {r}"),
            ));
        }
        points.push((nm, r));
    }
    SpectralReflectance::new(points).map_err(|m| ctx.error(node.pos, tags::SENSOR_REFLECTANCE, m))
}

/// Writes `<sensorStack>` at one level of indentation below the system.
pub(super) fn write_sensor_stack(
    out: &mut String,
    stack: &SensorStack,
    index_and_abbe: impl Fn(&crate::system::Medium) -> (String, String),
    num: impl Fn(f64) -> String,
    escape: impl Fn(&str) -> String,
) {
    out.push_str("    <sensorStack>\n");
    for p in &stack.plates {
        out.push_str("        <plate>\n");
        let mut tag = |name: &str, value: &str| {
            let _ = writeln!(out, "            <{name}>{value}</{name}>");
        };
        tag("thickness", &num(p.thickness));
        tag("gap", &num(p.gap));
        tag("height", &num(p.semi_diameter));
        let (nd, vd) = index_and_abbe(&p.medium);
        tag("refractiveIndex", &nd);
        tag("abbeNumber", &vd);
        if let crate::system::Medium::Glass { name, .. } = &p.medium {
            tag("glass", &escape(name));
        }
        for (name, c) in [("front", &p.front_coating), ("back", &p.back_coating)] {
            match c {
                Coating::None => {}
                Coating::SingleLayer {
                    design_wavelength_nm,
                    index,
                } => {
                    let _ = writeln!(
                        out,
                        "            <{name}><coatingLambda>{}</coatingLambda><coatingIor>{}</coatingIor></{name}>",
                        num(*design_wavelength_nm),
                        num(*index)
                    );
                }
                Coating::Stack(layers) => {
                    let _ = writeln!(out, "            <{name}>\n                <coatingStack>");
                    for l in layers {
                        let _ = writeln!(
                            out,
                            "                    <layer><index>{}</index><thicknessNm>{}</thicknessNm></layer>",
                            num(l.index),
                            num(l.thickness_nm)
                        );
                    }
                    let _ = writeln!(
                        out,
                        "                </coatingStack>\n            </{name}>"
                    );
                }
            }
        }
        out.push_str("        </plate>\n");
    }
    out.push_str("        <sensorReflectance>\n");
    for &(nm, r) in stack.sensor_reflectance.points() {
        let _ = writeln!(
            out,
            "            <point><wavelength>{}</wavelength><reflectance>{}</reflectance></point>",
            num(nm),
            num(r)
        );
    }
    out.push_str("        </sensorReflectance>\n    </sensorStack>\n");
}
