//! OpenLensFlare XML and our superset of it (`docs/formats.md`).
//!
//! OpenLensFlare files are read exactly as OpenLensFlare means them: `height` is the clear
//! semi-diameter, `radius` 0 is flat, `refractiveIndex`/`abbeNumber` describe the medium after
//! the surface (n = 1 is air), `coatingLambda`/`coatingIor` of 0 mean no coating. Our files add
//! optional tags (`curvature`, `conic`, `aspheric`, `glass`, `coatingStack`, `notes`,
//! `source`, the catalogue's `maker`, `kind`, `nominalFocalLength`, and `sensorStack`, read and
//! written by `sensor_stack`); see [`write_xml`].

mod coating;
mod fields;
mod medium;
mod read;
mod sensor_stack;
mod spans;
mod write;

#[cfg(test)]
pub(crate) mod tests;

pub use write::{write_olf_xml, write_xml};

use super::{LensFileError, LoadedLens};
use crate::io::located::Reporter;
use crate::io::text::LineIndex;

/// Tag names of the format.
mod tags {
    pub const SYSTEM: &str = "opticalSystem";
    pub const ELEMENT: &str = "element";
    pub const LAYER: &str = "layer";
    pub const SYSTEM_TAGS: &[&str] = &[
        "name",
        "maker",
        "kind",
        "nominalFocalLength",
        "fnumber",
        "effectiveFocalLength",
        "fieldOfView",
        "filmWidth",
        "filmHeight",
        "primaryWavelength",
        "elements",
        "notes",
        "source",
        "sensorStack",
    ];
    pub const ELEMENT_TAGS: &[&str] = &[
        "type",
        "height",
        "thickness",
        "radius",
        "curvature",
        "conic",
        "aspheric",
        "refractiveIndex",
        "abbeNumber",
        "glass",
        "coatingLambda",
        "coatingIor",
        "coatingStack",
        "mask",
        "maskFT",
    ];
    pub const LAYER_TAGS: &[&str] = &["index", "thicknessNm"];
    pub const PLATE: &str = "plate";
    pub const SENSOR_REFLECTANCE: &str = "sensorReflectance";
    pub const POINT: &str = "point";
    pub const PLATE_TAGS: &[&str] = &[
        "thickness",
        "gap",
        "height",
        "refractiveIndex",
        "abbeNumber",
        "glass",
        "front",
        "back",
    ];
    pub const FACE_TAGS: &[&str] = &["coatingLambda", "coatingIor", "coatingStack"];
    pub const POINT_TAGS: &[&str] = &["wavelength", "reflectance"];
}

/// Parses OpenLensFlare XML (or ours) and validates the system. `file_label` names the file
/// in errors and warnings. Every [`ValidationIssue`](crate::system::ValidationIssue) is
/// reported at the line and column of the tag it concerns; when there are several, the error
/// describes the first and lists the others in its message.
pub fn parse_olf_xml(text: &str, file_label: &str) -> Result<LoadedLens, LensFileError> {
    let parsed = read::parse_document(text, file_label)?;
    if let Err(issues) = parsed.system.validate() {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let lines = LineIndex::new(text);
        let located = issues
            .iter()
            .map(|issue| {
                let (pos, field) = parsed.spans.locate(issue);
                let (line, column) = lines.line_col(pos);
                LensFileError::at(file_label, line, column, field, issue.message.clone())
            })
            .collect();
        if let Some(e) = Reporter::combine(located) {
            return Err(e);
        }
    }
    // The stack goes behind a lens that is valid by itself, so the lens's own errors are
    // reported at its elements first.
    let system = match parsed.sensor_stack {
        None => parsed.system,
        Some((stack, pos)) => parsed.system.with_sensor_stack(Some(stack)).map_err(|m| {
            let text = text.strip_prefix('\u{feff}').unwrap_or(text);
            let (line, column) = LineIndex::new(text).line_col(pos);
            LensFileError::at(file_label, line, column, "sensorStack", m)
        })?,
    };
    Ok(LoadedLens {
        system,
        warnings: parsed.warnings,
    })
}
