//! The bundled library as a listing (`flarebench lenses`): each lens's maker, kind, focal
//! length, f-number, elements and ghosts, read from its file in parallel, and the filters
//! that find a lens by what it is.

use std::path::Path;

use anyhow::{Context, bail};
use flarebench_sdk::ghost::enumerate::enumerate_ghosts;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::{ParaxialData, analyse};
use flarebench_sdk::{LensKind, LensSystem, SurfaceKind};
use rayon::prelude::*;
use serde::Serialize;

use crate::lens_library::BundledLens;

/// One lens of the listing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ListedLens {
    /// The bundled name (file stem).
    pub name: String,
    /// The file, relative to the library (`nikon/ai-nikkor-135mm-f2.xml`).
    pub file: String,
    /// The lens's own name (`<name>`).
    pub title: String,
    /// Empty when the file names none.
    pub maker: String,
    pub kind: Vec<LensKind>,
    /// The focal length it is named by: a zoom's shortest and longest, a prime's twice; the
    /// file's stated focal length, else the paraxial one, when it gives none.
    pub focal_mm: [f64; 2],
    /// The paraxial EFL at its primary wavelength (mm).
    pub efl_mm: f64,
    /// The f-number setting of the file, else the stop's wide open.
    pub f_number: f64,
    /// Glass elements (a cemented group counts each of its glasses).
    pub elements: usize,
    /// Two-reflection ghost paths.
    pub ghosts: usize,
    #[serde(skip)]
    pub notes: String,
}

/// Glass elements: surfaces followed by a medium other than air.
pub fn elements(system: &LensSystem) -> usize {
    system
        .surfaces
        .iter()
        .filter(|s| s.kind == SurfaceKind::Refracting && !s.medium.is_air())
        .count()
}

/// The focal length `system` is named by: a zoom's shortest and longest, a prime's twice; the
/// file's stated focal length, else the paraxial one (`p`), when it gives none.
pub fn named_focal_mm(system: &LensSystem, p: &ParaxialData) -> [f64; 2] {
    let focal = system.stated_efl_mm.unwrap_or(p.efl_mm);
    system.nominal_focal_mm.unwrap_or([focal, focal])
}

/// The f-number setting of `system`, else its stop's wide open (`p`).
pub fn f_number(system: &LensSystem, p: &ParaxialData) -> f64 {
    system.f_number.unwrap_or(p.open_f_number)
}

/// Reads one lens of the library for the listing.
pub fn load(lens: &BundledLens, root: &Path) -> anyhow::Result<ListedLens> {
    let sys = read_lens(&lens.path)
        .with_context(|| format!("could not load bundled lens `{}`", lens.qualified))?
        .system;
    let p = analyse(&sys, sys.default_wavelength_nm())
        .with_context(|| format!("bundled lens `{}`", lens.qualified))?;
    let file = lens
        .path
        .strip_prefix(root)
        .unwrap_or(&lens.path)
        .to_string_lossy()
        .replace('\\', "/");
    Ok(ListedLens {
        name: lens.name.clone(),
        file,
        title: sys.name.clone(),
        maker: sys.maker.clone(),
        kind: sys.kind.clone(),
        focal_mm: named_focal_mm(&sys, &p),
        efl_mm: p.efl_mm,
        f_number: f_number(&sys, &p),
        elements: elements(&sys),
        ghosts: enumerate_ghosts(&sys).len(),
        notes: sys.notes,
    })
}

/// Reads every lens of `lenses` (in the library at `root`) in parallel, in their order.
pub fn load_all(lenses: &[BundledLens], root: &Path) -> Vec<anyhow::Result<ListedLens>> {
    lenses.par_iter().map(|l| load(l, root)).collect()
}

/// A closed range of numbers, either end open: `24..35`, `..2`, `200..`, or one number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    pub lo: f64,
    pub hi: f64,
}

impl Span {
    /// Parses `a..b`, `..b`, `a..` or `a` (positive numbers, `a ≤ b`); `what` names the option
    /// in errors.
    pub fn parse(s: &str, what: &str) -> anyhow::Result<Span> {
        let number = |t: &str| -> anyhow::Result<Option<f64>> {
            let t = t.trim();
            if t.is_empty() {
                return Ok(None);
            }
            match t.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(Some(v)),
                _ => bail!(
                    "{what} `{s}`: `{t}` is not a positive number (ranges are `24..35`, `..2`, \
                     `200..` or one number)"
                ),
            }
        };
        let span = match s.split_once("..") {
            Some((a, b)) if a.trim().is_empty() && b.trim().is_empty() => {
                bail!("{what} is empty: give `24..35`, `..2`, `200..` or one number")
            }
            Some((a, b)) => Span {
                lo: number(a)?.unwrap_or(0.0),
                hi: number(b)?.unwrap_or(f64::INFINITY),
            },
            None => match number(s)? {
                Some(v) => Span { lo: v, hi: v },
                None => bail!("{what} is empty: give `24..35`, `..2`, `200..` or one number"),
            },
        };
        if span.lo > span.hi {
            bail!(
                "{what} `{s}`: the range is empty ({} > {})",
                span.lo,
                span.hi
            );
        }
        Ok(span)
    }

    /// True when `[a, b]` overlaps the span.
    pub fn overlaps(&self, a: f64, b: f64) -> bool {
        a <= self.hi && self.lo <= b
    }
}

/// What `flarebench lenses` filters by; a lens is listed when it matches every one given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Filter {
    /// Part of the maker's name or the maker folder, case-insensitive.
    pub maker: Option<String>,
    /// The lens's focal length (a zoom's range) overlaps it.
    pub focal: Option<Span>,
    /// The lens's f-number is in it.
    pub fnum: Option<Span>,
    /// Kinds the lens has, all of them.
    pub kind: Vec<LensKind>,
    /// Words each found (case-insensitive) in the name, the lens's own name, the maker or the
    /// notes.
    pub terms: Vec<String>,
}

impl Filter {
    pub fn matches(&self, l: &ListedLens) -> bool {
        let lower = |s: &str| s.to_lowercase();
        let folder = l.file.split_once('/').map_or("", |(f, _)| f);
        if let Some(m) = &self.maker {
            let m = lower(m);
            if !(lower(&l.maker).contains(&m) || folder == m) {
                return false;
            }
        }
        if let Some(f) = &self.focal
            && !f.overlaps(l.focal_mm[0], l.focal_mm[1])
        {
            return false;
        }
        // The f-numbers of the files carry two or three decimals (f/2.8 is 2.8, 2.88 or 2.92):
        // compared at one decimal, as the listing shows them.
        if let Some(f) = &self.fnum {
            let shown = (l.f_number * 10.0).round() / 10.0;
            if !f.overlaps(shown, shown) {
                return false;
            }
        }
        if !self.kind.iter().all(|k| l.kind.contains(k)) {
            return false;
        }
        self.terms.iter().all(|t| {
            let t = lower(t);
            [&l.name, &l.title, &l.maker, &l.notes]
                .iter()
                .any(|field| lower(field).contains(&t))
        })
    }
}

/// The focal length as listed: `135`, or `24–70` for a zoom.
pub fn focal_text(f: [f64; 2]) -> String {
    let one = |v: f64| {
        if (v - v.round()).abs() < 0.05 {
            format!("{v:.0}")
        } else {
            format!("{v:.1}")
        }
    };
    if f[0] == f[1] {
        one(f[0])
    } else {
        format!("{}–{}", one(f[0]), one(f[1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(
        name: &str,
        maker: &str,
        kind: &[LensKind],
        focal: [f64; 2],
        f_number: f64,
    ) -> ListedLens {
        ListedLens {
            name: name.into(),
            file: format!("{}/{name}.xml", maker.to_lowercase()),
            title: name.into(),
            maker: maker.into(),
            kind: kind.to_vec(),
            focal_mm: focal,
            efl_mm: focal[0],
            f_number,
            elements: 6,
            ghosts: 66,
            notes: "from a patent".into(),
        }
    }

    #[test]
    fn spans_parse_every_form_and_refuse_the_rest_clearly() {
        assert_eq!(
            Span::parse("24..35", "--focal").unwrap(),
            Span { lo: 24.0, hi: 35.0 }
        );
        assert_eq!(Span::parse("..2", "--fnum").unwrap().hi, 2.0);
        assert_eq!(Span::parse("..2", "--fnum").unwrap().lo, 0.0);
        assert!(Span::parse("200..", "--focal").unwrap().hi.is_infinite());
        assert_eq!(
            Span::parse("50", "--focal").unwrap(),
            Span { lo: 50.0, hi: 50.0 }
        );
        for (bad, says) in [
            ("35..24", "the range is empty"),
            ("a..3", "`a` is not a positive number"),
            ("-5", "not a positive number"),
            ("", "is empty"),
            ("..", "is empty"),
        ] {
            let e = Span::parse(bad, "--focal")
                .map(|_| ())
                .unwrap_err()
                .to_string();
            assert!(e.contains(says) && e.contains("--focal"), "{bad}: {e}");
        }
    }

    #[test]
    fn a_zoom_matches_a_focal_span_it_overlaps() {
        let zoom = lens("z", "Canon", &[LensKind::Zoom], [24.0, 70.0], 2.8);
        let prime = lens("p", "Nikon", &[LensKind::Prime], [135.0, 135.0], 2.0);
        let f = |s: &str| Filter {
            focal: Some(Span::parse(s, "--focal").unwrap()),
            ..Filter::default()
        };
        assert!(f("16..24").matches(&zoom) && f("70..200").matches(&zoom));
        assert!(!f("71..200").matches(&zoom) && !f("..23").matches(&zoom));
        assert!(f("135").matches(&prime) && !f("24..35").matches(&prime));
    }

    #[test]
    fn each_filter_keeps_only_what_it_names() {
        let a = lens(
            "ai-nikkor-135mm-f2",
            "Nikon",
            &[LensKind::Prime],
            [135.0; 2],
            2.0,
        );
        let b = lens(
            "ef100mm-macro",
            "Canon",
            &[LensKind::Macro, LensKind::Prime],
            [100.0; 2],
            2.88,
        );
        let by = |f: Filter| -> Vec<bool> { vec![f.matches(&a), f.matches(&b)] };
        assert_eq!(by(Filter::default()), [true, true]);
        let maker = Filter {
            maker: Some("NIK".into()),
            ..Filter::default()
        };
        assert_eq!(by(maker), [true, false]);
        let fnum = Filter {
            fnum: Some(Span::parse("..2.8", "--fnum").unwrap()),
            ..Filter::default()
        };
        // 2.88 is listed as f/2.9.
        assert_eq!(by(fnum), [true, false]);
        let fnum = Filter {
            fnum: Some(Span::parse("2.9", "--fnum").unwrap()),
            ..Filter::default()
        };
        assert_eq!(by(fnum), [false, true]);
        let kind = Filter {
            kind: vec![LensKind::Macro],
            ..Filter::default()
        };
        assert_eq!(by(kind), [false, true]);
        let terms = Filter {
            terms: vec!["135MM".into(), "nikon".into()],
            ..Filter::default()
        };
        assert_eq!(by(terms), [true, false]);
        let notes = Filter {
            terms: vec!["patent".into()],
            ..Filter::default()
        };
        assert_eq!(by(notes), [true, true]);
    }

    #[test]
    fn focal_lengths_are_listed_without_needless_decimals() {
        assert_eq!(focal_text([135.0, 135.0]), "135");
        assert_eq!(focal_text([24.0, 70.0]), "24–70");
        assert_eq!(focal_text([4.7, 17.7]), "4.7–17.7");
    }
}
