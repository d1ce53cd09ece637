//! Where each system field and element field sits in the file, so that a
//! [`ValidationIssue`](crate::system::ValidationIssue) found after parsing can be reported at
//! the line and column of the tag it concerns.

use crate::system::ValidationIssue;

/// Byte offsets of one `<element>` and of its fields' values.
#[derive(Clone, Debug, Default)]
pub(super) struct ElementSpans {
    /// The `<element>` tag.
    pub pos: usize,
    /// `(tag, offset of its value)` for every field present.
    pub fields: Vec<(&'static str, usize)>,
}

/// Byte offsets of the system tag, its fields and its elements.
#[derive(Clone, Debug, Default)]
pub(super) struct SystemSpans {
    /// The `<opticalSystem>` tag.
    pub pos: usize,
    pub fields: Vec<(&'static str, usize)>,
    /// The `<elements>` tag, if present.
    pub elements_pos: Option<usize>,
    pub elements: Vec<ElementSpans>,
}

/// The tags that hold a model field, most specific first.
fn tags_for(field: &str) -> &[&'static str] {
    match field {
        "radius" => &["curvature", "radius"],
        "coating" => &["coatingStack", "coatingIor", "coatingLambda"],
        "refractiveIndex" => &["refractiveIndex", "glass"],
        "type" => &["type"],
        "height" => &["height"],
        "thickness" => &["thickness"],
        "conic" => &["conic"],
        "aspheric" => &["aspheric"],
        "abbeNumber" => &["abbeNumber"],
        "fnumber" => &["fnumber"],
        "filmWidth" => &["filmWidth"],
        "filmHeight" => &["filmHeight"],
        "primaryWavelength" => &["primaryWavelength"],
        _ => &[],
    }
}

fn find(fields: &[(&'static str, usize)], tags: &[&'static str]) -> Option<(usize, &'static str)> {
    tags.iter().find_map(|t| {
        fields
            .iter()
            .find(|(name, _)| name == t)
            .map(|&(name, pos)| (pos, name))
    })
}

impl SystemSpans {
    /// The byte offset and the field name to report for a validation issue: the field's tag
    /// when the file has it, else the element (or for system issues, `<elements>` or the
    /// system tag).
    pub fn locate(&self, issue: &ValidationIssue) -> (usize, &'static str) {
        let tags = tags_for(issue.field);
        match issue.surface {
            Some(i) => match self.elements.get(i) {
                Some(el) => find(&el.fields, tags).unwrap_or((el.pos, issue.field)),
                None => (self.pos, issue.field),
            },
            None => {
                if let Some(hit) = find(&self.fields, tags) {
                    return hit;
                }
                match (issue.field, self.elements_pos) {
                    ("elements" | "type", Some(p)) => (p, issue.field),
                    _ => (self.pos, issue.field),
                }
            }
        }
    }
}
