//! The selection list, `lenses/sources/flaresim-selection.txt`: one FlareSim lens per line,
//! `file | maker-folder/name | maker | kind | focal | film`, `#` comments. Every error
//! names the list's file, its line and the column.

use std::collections::HashMap;

use anyhow::{Context, bail};
use flarebench_sdk::LensKind;
use flarebench_sdk::lens_kind::parse_kinds;

use super::film::Film;

/// The columns, in order (named in errors).
const COLUMNS: [&str; 6] = ["file", "name", "maker", "kind", "focal", "film"];

/// Folders of `lenses/` that hold no lenses.
const RESERVED_FOLDERS: [&str; 2] = ["sources", "masks"];

/// One selected lens.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Its line in the list (1-based).
    pub line: usize,
    /// The file in FlareSim's `lens_files/`.
    pub file: String,
    /// The maker folder under `lenses/` (lowercase).
    pub folder: String,
    /// The file stem: lowercase words of letters and digits joined by `-` or `.`, unique in
    /// the whole library.
    pub name: String,
    /// The maker as written (`Carl Zeiss`).
    pub maker: String,
    pub kind: Vec<LensKind>,
    /// The focal length its name gives (mm): a prime's twice, a zoom's shortest and longest.
    pub nominal_focal_mm: [f64; 2],
    pub film: Film,
}

impl Entry {
    /// `folder/name`.
    pub fn qualified(&self) -> String {
        format!("{}/{}", self.folder, self.name)
    }
}

/// True for a lowercase word (`[a-z0-9]+`) or words joined by single `-` or `.`.
pub fn is_kebab(s: &str) -> bool {
    !s.is_empty()
        && s.split(['-', '.']).all(|w| {
            !w.is_empty()
                && w.bytes()
                    .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit())
        })
}

/// Reads the list; `label` names it in errors.
pub fn parse(text: &str, label: &str) -> anyhow::Result<Vec<Entry>> {
    let mut out: Vec<Entry> = Vec::new();
    let mut names: HashMap<String, usize> = HashMap::new();
    let mut files: HashMap<String, usize> = HashMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or_default().trim();
        if content.is_empty() {
            continue;
        }
        let entry = parse_line(content, line).with_context(|| format!("{label}:{line}"))?;
        if let Some(first) = names.insert(entry.name.clone(), line) {
            bail!(
                "{label}:{line}: column `name`: `{}` is already the name of line {first}: names \
                 are unique across the library",
                entry.name
            );
        }
        if let Some(first) = files.insert(entry.file.clone(), line) {
            bail!(
                "{label}:{line}: column `file`: `{}` is already selected on line {first}",
                entry.file
            );
        }
        out.push(entry);
    }
    Ok(out)
}

fn parse_line(content: &str, line: usize) -> anyhow::Result<Entry> {
    let cells: Vec<&str> = content.split('|').map(str::trim).collect();
    if cells.len() != COLUMNS.len() {
        bail!(
            "expected {} columns separated by `|` ({}), found {}",
            COLUMNS.len(),
            COLUMNS.join(" | "),
            cells.len()
        );
    }
    let column = |i: usize, why: String| anyhow::anyhow!("column `{}`: {why}", COLUMNS[i]);
    let file = cells[0];
    if !file.ends_with(".lens") || file.contains('/') {
        return Err(column(
            0,
            format!("`{file}` is not a `.lens` file name of FlareSim's lens_files/"),
        ));
    }
    let Some((folder, name)) = cells[1].split_once('/') else {
        return Err(column(
            1,
            format!("`{}` is not `maker-folder/name`", cells[1]),
        ));
    };
    if !is_kebab(folder) || RESERVED_FOLDERS.contains(&folder) {
        return Err(column(
            1,
            format!("`{folder}` is no maker folder (lowercase, not sources/ or masks/)"),
        ));
    }
    if !is_kebab(name) {
        return Err(column(
            1,
            format!("`{name}` is not lowercase words joined by `-` or `.`"),
        ));
    }
    let maker = cells[2];
    if maker.is_empty() {
        return Err(column(2, "the maker is empty".into()));
    }
    let kind = parse_kinds(cells[3]).map_err(|e| column(3, e))?;
    if !kind.contains(&LensKind::Prime) && !kind.contains(&LensKind::Zoom) {
        return Err(column(3, "a lens is a prime or a zoom: name one".into()));
    }
    let zoom = kind.contains(&LensKind::Zoom);
    let nominal_focal_mm = parse_focal(cells[4], zoom).ok_or_else(|| {
        column(
            4,
            format!(
                "`{}` is not {} in mm",
                cells[4],
                if zoom {
                    "a zoom's `shortest-longest` (`24-70`)"
                } else {
                    "a prime's focal length (`135`)"
                }
            ),
        )
    })?;
    let film = Film::parse(cells[5]).ok_or_else(|| {
        let codes: Vec<&str> = Film::ALL.iter().map(|f| f.code()).collect();
        column(
            5,
            format!(
                "unknown film `{}`; expected one of {}",
                cells[5],
                codes.join(", ")
            ),
        )
    })?;
    Ok(Entry {
        line,
        file: file.to_string(),
        folder: folder.to_string(),
        name: name.to_string(),
        maker: maker.to_string(),
        kind,
        nominal_focal_mm,
        film,
    })
}

/// A prime's `f` or a zoom's `a-b` (`a < b`), positive numbers.
fn parse_focal(s: &str, zoom: bool) -> Option<[f64; 2]> {
    let number = |t: &str| t.parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0);
    match (s.split_once('-'), zoom) {
        (Some((a, b)), true) => {
            let (a, b) = (number(a)?, number(b)?);
            (a < b).then_some([a, b])
        }
        (None, false) => number(s).map(|f| [f, f]),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "# comment\n\
        AI_Nikkor_135mm_F2.lens | nikon/ai-nikkor-135mm-f2 | Nikon | prime | 135 | ff\n\
        \n\
        X.lens | canon/ef-s18-55mm-f3.5-5.6 | Canon | zoom | 18-55 | aps-c-canon  # a zoom\n";

    #[test]
    fn a_good_list_reads_every_column() {
        let e = parse(GOOD, "sel.txt").unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].qualified(), "nikon/ai-nikkor-135mm-f2");
        assert_eq!((e[0].line, e[0].film), (2, Film::FullFrame));
        assert_eq!(e[0].nominal_focal_mm, [135.0, 135.0]);
        assert_eq!(e[1].nominal_focal_mm, [18.0, 55.0]);
        assert_eq!(e[1].kind, vec![LensKind::Zoom]);
        assert_eq!(e[1].film, Film::ApsCCanon);
    }

    #[test]
    fn bad_lines_are_errors_naming_the_line_and_column() {
        let cases = [
            (
                "a.lens | nikon/x | Nikon | prime | - ",
                "expected 6 columns",
            ),
            ("a.txt | nikon/x | Nikon | prime | 50 | ff", "column `file`"),
            ("a.lens | x | Nikon | prime | 50 | ff", "column `name`"),
            (
                "a.lens | Nikon/x | Nikon | prime | 50 | ff",
                "no maker folder",
            ),
            (
                "a.lens | sources/x | Nikon | prime | 50 | ff",
                "no maker folder",
            ),
            (
                "a.lens | nikon/X_1 | Nikon | prime | 50 | ff",
                "lowercase words",
            ),
            (
                "a.lens | nikon/a--b | Nikon | prime | 50 | ff",
                "lowercase words",
            ),
            ("a.lens | nikon/x |  | prime | 50 | ff", "column `maker`"),
            (
                "a.lens | nikon/x | Nikon | wide | - | ff",
                "unknown lens kind",
            ),
            (
                "a.lens | nikon/x | Nikon | macro | - | ff",
                "prime or a zoom",
            ),
            (
                "a.lens | nikon/x | Nikon | zoom | 70-24 | ff",
                "column `focal`",
            ),
            ("a.lens | nikon/x | Nikon | zoom | 70 | ff", "a zoom's"),
            ("a.lens | nikon/x | Nikon | prime | 24-70 | ff", "a prime's"),
            ("a.lens | nikon/x | Nikon | prime | - | ff", "a prime's"),
            (
                "a.lens | nikon/x | Nikon | prime | 50 | dx",
                "unknown film `dx`",
            ),
        ];
        for (line, says) in cases {
            let e = format!(
                "{:#}",
                parse(&format!("\n{line}\n"), "sel.txt").unwrap_err()
            );
            assert!(e.starts_with("sel.txt:2"), "{line}: {e}");
            assert!(e.contains(says), "{line}: {e}");
        }
    }

    #[test]
    fn names_and_files_are_unique() {
        let twice = "a.lens | nikon/x | Nikon | prime | 50 | ff\nb.lens | canon/x | Canon | prime | 50 | ff\n";
        let e = parse(twice, "sel.txt").unwrap_err().to_string();
        assert!(e.contains("sel.txt:2") && e.contains("line 1"), "{e}");
        let twice = "a.lens | nikon/x | Nikon | prime | 50 | ff\na.lens | nikon/y | Nikon | prime | 50 | ff\n";
        let e = parse(twice, "sel.txt").unwrap_err().to_string();
        assert!(e.contains("already selected on line 1"), "{e}");
    }

    #[test]
    fn kebab_names_are_lowercase_words_joined_by_dashes_or_dots() {
        for good in ["ai-nikkor-135mm-f2", "ef24-70mm-f2.8l-ii-usm", "7artisans"] {
            assert!(is_kebab(good), "{good}");
        }
        for bad in ["", "-a", "a-", "a..b", "A", "a_b", "a b", "ä"] {
            assert!(!is_kebab(bad), "{bad}");
        }
    }
}
