//! `--precomputed FILE`: ghost bounds from our JSON table (`flarebench precompute`,
//! docs/formats.md §10) or from OpenLensFlare's `<ghostList>` XML (§8), told apart by content,
//! checked against the lens and returned as one [`BoundsTable`].

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::olf_table::OlfImport;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::io::read_olf_bounds;

/// What a bounds file is, from its first non-blank character.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundsFileKind {
    /// Our table: a JSON object.
    Json,
    /// OpenLensFlare's ghost bounds: XML.
    OlfXml,
}

/// The kind of a bounds file from its bytes: `{` starts our JSON, `<` (or a UTF-16 byte-order
/// mark, which JSON cannot have) OpenLensFlare's XML; anything else is neither.
pub fn detect(bytes: &[u8]) -> Option<BoundsFileKind> {
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Some(BoundsFileKind::OlfXml);
    }
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match body.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Some(BoundsFileKind::Json),
        Some(b'<') => Some(BoundsFileKind::OlfXml),
        _ => None,
    }
}

/// Reads `path` as either kind of bounds file and checks it against `system`: our table by
/// its fingerprint, an OpenLensFlare file by its ghost list ([`BoundsTable::from_olf`]). What
/// an OpenLensFlare file leaves out or cuts is printed as warnings unless `quiet`.
pub fn load_precomputed(
    path: &Path,
    system: &LensSystem,
    quiet: bool,
) -> anyhow::Result<BoundsTable> {
    let label = path.display().to_string();
    let bytes = std::fs::read(path).with_context(|| format!("could not read {label}"))?;
    match detect(&bytes) {
        Some(BoundsFileKind::Json) => {
            let text = String::from_utf8_lossy(&bytes);
            let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
            let table: BoundsTable =
                serde_json::from_str(text).map_err(|e| json_error(&label, text, &e))?;
            table
                .check_for(system)
                .map_err(anyhow::Error::msg)
                .with_context(|| label.clone())?;
            Ok(table)
        }
        Some(BoundsFileKind::OlfXml) => {
            let olf = read_olf_bounds(path)?;
            let (table, import) = BoundsTable::from_olf(&olf, system)
                .with_context(|| format!("{label}: OpenLensFlare ghost bounds"))?;
            if !quiet {
                for w in import_warnings(&import, table.ghosts.len()) {
                    eprintln!("warning: {label}: {w}");
                }
            }
            Ok(table)
        }
        None => anyhow::bail!(
            "{label}: neither a flarebench bounds table (JSON, starting with `{{`) nor an OpenLensFlare ghost-bounds file (XML, `<ghostList>`)"
        ),
    }
}

/// A JSON error as `file:line:column: field `key`: message`, the field being the nearest key
/// before the error (serde names it itself for missing and unknown fields).
fn json_error(label: &str, text: &str, e: &serde_json::Error) -> anyhow::Error {
    let (line, column) = (e.line(), e.column());
    // serde_json's message ends with " at line L column C", which the prefix says already.
    let full = e.to_string();
    let suffix = format!(" at line {line} column {column}");
    let message = full.strip_suffix(&suffix).unwrap_or(&full);
    let offset = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum::<usize>()
        + column;
    match nearest_key(text, offset.min(text.len())) {
        Some(key) => anyhow::anyhow!("{label}:{line}:{column}: field `{key}`: {message}"),
        None => anyhow::anyhow!("{label}:{line}:{column}: {message}"),
    }
}

/// The last `"key":` that starts before byte `offset`.
fn nearest_key(text: &str, offset: usize) -> Option<&str> {
    let head = text.get(..offset)?;
    let mut end = head.len();
    while let Some(colon) = head[..end].rfind("\":") {
        let open = head[..colon].rfind('"')?;
        let key = &head[open + 1..colon];
        if !key.is_empty() && !key.contains(['{', '}', '[', ']', ',', ':']) {
            return Some(key);
        }
        end = open;
    }
    None
}

/// The conversion's findings as warning lines.
fn import_warnings(import: &OlfImport, file_ghosts: usize) -> Vec<String> {
    let mut out = Vec::new();
    if !import.missing.is_empty() {
        out.push(format!(
            "the file holds {file_ghosts} of the lens's {} ghosts; the bounds of the other {} (OpenLensFlare leaves out ghosts whose reflections straddle the stop) are traced for each light: {}",
            file_ghosts + import.missing.len() - import.unused.len(),
            import.missing.len(),
            paths(&import.missing)
        ));
    }
    if !import.unused.is_empty() {
        out.push(format!(
            "{} of the file's ghosts reflect at a surface without a change of index and are not ghosts here: {}",
            import.unused.len(),
            paths(&import.unused)
        ));
    }
    if !import.cut.is_empty() {
        out.push(format!(
            "at {} of the file's {} entries with light its entrance rectangle cuts the ghost (our rays pass on its edge; the part outside is not drawn), e.g. {}",
            import.cut.len(),
            import.visible,
            entries(&import.cut)
        ));
    }
    if !import.dark.is_empty() {
        out.push(format!(
            "at {} entries with light in the file none of our rays pass inside its rectangle (left without light), e.g. {}",
            import.dark.len(),
            entries(&import.dark)
        ));
    }
    out
}

fn paths(p: &[GhostPath]) -> String {
    p.iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

fn entries(e: &[(GhostPath, f64)]) -> String {
    let mut s = String::new();
    for (i, (p, deg)) in e.iter().take(4).enumerate() {
        if i > 0 {
            s += ", ";
        }
        let _ = write!(s, "{p} at {deg}°");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kind_is_told_by_the_first_character() {
        assert_eq!(detect(b"  \n{\"format\":1}"), Some(BoundsFileKind::Json));
        assert_eq!(detect(b"\xEF\xBB\xBF{}"), Some(BoundsFileKind::Json));
        assert_eq!(
            detect(b"<?xml version=\"1.0\"?>"),
            Some(BoundsFileKind::OlfXml)
        );
        assert_eq!(detect(b"\n <ghostList/>"), Some(BoundsFileKind::OlfXml));
        assert_eq!(detect(b"\xFF\xFE<\x00"), Some(BoundsFileKind::OlfXml));
        assert_eq!(detect(b"angle,ghost\n"), None);
        assert_eq!(detect(b""), None);
    }

    #[test]
    fn json_errors_name_the_nearest_key() {
        let text = "{\"format\":\"x\",\n \"angles_deg\":[0.0,\"a\"]}";
        let e = serde_json::from_str::<BoundsTable>(text).unwrap_err();
        let msg = json_error("t.json", text, &e).to_string();
        assert!(msg.starts_with("t.json:2:"), "{msg}");
        assert!(msg.contains("field `angles_deg`"), "{msg}");
        assert!(!msg.contains(" at line "), "{msg}");
    }
}
