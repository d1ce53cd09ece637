//! Helpers for reading one element's children: the file context that turns byte offsets
//! into errors and warnings, the known-tag collection, and number parsing.

use crate::io::LensFileError;
use crate::io::xml_tree::Node;

/// The file being read (its label, line index and warnings): the same reporter the
/// line-based readers use.
pub(super) use crate::io::located::Reporter as Ctx;

/// The known children of one element, first occurrence of each; warns about the rest.
pub(super) struct Fields<'n> {
    found: Vec<(&'static str, &'n Node)>,
}

impl<'n> Fields<'n> {
    pub fn collect(ctx: &mut Ctx<'_>, parent: &'n Node, known: &[&'static str]) -> Self {
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

    pub fn get(&self, tag: &str) -> Option<&'n Node> {
        self.found
            .iter()
            .find(|(n, _)| *n == tag)
            .map(|(_, node)| *node)
    }

    pub fn positions(&self) -> Vec<(&'static str, usize)> {
        self.found
            .iter()
            .map(|(n, node)| (*n, node.value_pos()))
            .collect()
    }
}

/// A finite number, or `None` when the tag is absent or empty.
pub(super) fn number(ctx: &mut Ctx<'_>, node: Option<&Node>) -> Result<Option<f64>, LensFileError> {
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
pub(super) fn text(node: Option<&Node>) -> Option<String> {
    node.map(|n| n.value().to_string())
        .filter(|s| !s.is_empty())
}
