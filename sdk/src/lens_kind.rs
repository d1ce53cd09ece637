//! What kind of lens a prescription is, for finding it in a library: prime or zoom, and the
//! special kinds (fisheye, macro, cine, tilt-shift). Our XML writes them as the words of
//! `<kind>` (`docs/formats.md` §2).

use std::fmt;

use serde::{Deserialize, Serialize};

/// One word of a lens's kind (serialized as its [`name`](LensKind::name)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LensKind {
    /// One focal length.
    Prime,
    /// A zoom (the prescription is one of its positions).
    Zoom,
    /// A fisheye: a field of 150° or more, not rectilinear.
    Fisheye,
    /// A macro lens (close focusing, 1:2 or closer), as its maker names it.
    Macro,
    /// A cinema lens (T-stops, PL mount or a cine line's name).
    Cine,
    /// A tilt-shift (perspective control) lens.
    TiltShift,
}

impl LensKind {
    /// Every kind, in the order they are written.
    pub const ALL: [LensKind; 6] = [
        LensKind::Prime,
        LensKind::Zoom,
        LensKind::Fisheye,
        LensKind::Macro,
        LensKind::Cine,
        LensKind::TiltShift,
    ];

    /// The word used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            LensKind::Prime => "prime",
            LensKind::Zoom => "zoom",
            LensKind::Fisheye => "fisheye",
            LensKind::Macro => "macro",
            LensKind::Cine => "cine",
            LensKind::TiltShift => "tilt-shift",
        }
    }

    /// The kind named `word` (case-insensitive).
    pub fn parse(word: &str) -> Option<LensKind> {
        LensKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(word))
    }
}

impl fmt::Display for LensKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The words of `text` (space or comma separated) as kinds, sorted: an unknown word, a word
/// given twice, or both `prime` and `zoom` is an error that says which.
pub fn parse_kinds(text: &str) -> Result<Vec<LensKind>, String> {
    let mut kinds = Vec::new();
    for word in text
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|w| !w.is_empty())
    {
        let Some(kind) = LensKind::parse(word) else {
            let known: Vec<&str> = LensKind::ALL.iter().map(|k| k.name()).collect();
            return Err(format!(
                "unknown lens kind `{word}`; expected some of {}",
                known.join(", ")
            ));
        };
        if kinds.contains(&kind) {
            return Err(format!("the kind `{kind}` is given twice"));
        }
        kinds.push(kind);
    }
    if kinds.contains(&LensKind::Prime) && kinds.contains(&LensKind::Zoom) {
        return Err("a lens is a prime or a zoom, not both".into());
    }
    kinds.sort();
    Ok(kinds)
}

/// The kinds as written in files: their words separated by spaces.
pub fn kinds_text(kinds: &[LensKind]) -> String {
    let words: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
    words.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_reads_back_from_its_name() {
        for k in LensKind::ALL {
            assert_eq!(LensKind::parse(k.name()), Some(k));
            assert_eq!(LensKind::parse(&k.name().to_uppercase()), Some(k));
        }
        let all = kinds_text(&LensKind::ALL[1..]);
        assert_eq!(parse_kinds(&all).unwrap(), LensKind::ALL[1..].to_vec());
    }

    #[test]
    fn kinds_are_sorted_and_may_be_separated_by_commas() {
        assert_eq!(
            parse_kinds(" macro, prime ").unwrap(),
            vec![LensKind::Prime, LensKind::Macro]
        );
        assert_eq!(parse_kinds("").unwrap(), vec![]);
    }

    #[test]
    fn unknown_repeated_and_contradictory_kinds_are_errors_saying_which() {
        let e = parse_kinds("prime wide").unwrap_err();
        assert!(e.contains("`wide`") && e.contains("tilt-shift"), "{e}");
        let e = parse_kinds("zoom zoom").unwrap_err();
        assert!(e.contains("`zoom` is given twice"), "{e}");
        let e = parse_kinds("prime zoom").unwrap_err();
        assert!(e.contains("not both"), "{e}");
    }
}
