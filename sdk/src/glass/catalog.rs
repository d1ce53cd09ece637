//! The bundled glass catalogue: 1613 glasses from the refractiveindex.info database (CC0),
//! `sdk/data/glass_catalog.csv`, compiled into the library.

use std::sync::OnceLock;

use super::Dispersion;

const BUNDLED_CSV: &str = include_str!("../../data/glass_catalog.csv");

/// One catalogue glass.
#[derive(Clone, Debug, PartialEq)]
pub struct CatalogEntry {
    /// Maker's catalogue (`SCHOTT`, `OHARA`, `HOYA`, `CDGM`, …), upper case.
    pub catalog: String,
    /// Glass name as the maker spells it (`N-BK7`).
    pub name: String,
    /// The dispersion formula with its coefficients.
    pub dispersion: Dispersion,
    /// Wavelength range (µm) over which the formula is valid.
    pub range_um: (f64, f64),
    /// nd and Vd as listed in the catalogue file.
    pub nd: f64,
    pub vd: f64,
}

impl CatalogEntry {
    /// `CATALOG:NAME`, the form written to our files.
    pub fn canonical_name(&self) -> String {
        format!("{}:{}", self.catalog, self.name)
    }

    /// The glass's dispersion.
    pub fn dispersion(&self) -> &Dispersion {
        &self.dispersion
    }
}

/// Why a glass name did not resolve.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GlassLookupError {
    #[error("unknown glass `{name}`{}", suggestion_text(.suggestions))]
    Unknown {
        name: String,
        suggestions: Vec<String>,
    },
    #[error("glass `{name}` is ambiguous: it is in {}; write one of them as CATALOG:NAME", .candidates.join(", "))]
    Ambiguous {
        name: String,
        candidates: Vec<String>,
    },
}

fn suggestion_text(s: &[String]) -> String {
    if s.is_empty() {
        String::new()
    } else {
        format!(" (did you mean {}?)", s.join(", "))
    }
}

/// A line of the catalogue file that could not be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("glass catalogue line {line}: {message}")]
pub struct CatalogParseError {
    pub line: usize,
    pub message: String,
}

/// A searchable glass catalogue.
#[derive(Clone, Debug, Default)]
pub struct GlassCatalog {
    entries: Vec<CatalogEntry>,
}

/// Catalogues searched first when a bare name is in several (SCHOTT is the common reference,
/// as Zemax's default `GCAT SCHOTT`).
const PREFERRED_ORDER: &[&str] = &["SCHOTT"];

impl GlassCatalog {
    /// The catalogue compiled into the library (parsed once).
    pub fn bundled() -> &'static GlassCatalog {
        static CATALOG: OnceLock<GlassCatalog> = OnceLock::new();
        CATALOG.get_or_init(|| {
            GlassCatalog::parse(BUNDLED_CSV).expect("the bundled glass catalogue is well formed")
        })
    }

    /// Parses the CSV format of `sdk/data/glass_catalog.csv`
    /// (`catalog,name,formula,min_um,max_um,coefficients,nd,vd`; `#` comment lines).
    pub fn parse(text: &str) -> Result<GlassCatalog, CatalogParseError> {
        let mut entries = Vec::new();
        let mut header_seen = false;
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let l = raw.trim();
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            if !header_seen {
                header_seen = true;
                if l.starts_with("catalog,") {
                    continue;
                }
            }
            let err = |message: String| CatalogParseError { line, message };
            let f: Vec<&str> = l.split(',').collect();
            if f.len() != 8 {
                return Err(err(format!("expected 8 fields, found {}", f.len())));
            }
            let num = |s: &str, what: &str| -> Result<f64, CatalogParseError> {
                s.trim()
                    .parse::<f64>()
                    .map_err(|_| err(format!("field {what}: `{s}` is not a number")))
            };
            let coeffs = f[5]
                .split_whitespace()
                .map(|c| num(c, "coefficients"))
                .collect::<Result<Vec<f64>, _>>()?;
            let formula = f[2].trim();
            let dispersion = dispersion_from_formula(formula, &coeffs).map_err(err)?;
            entries.push(CatalogEntry {
                catalog: f[0].trim().to_ascii_uppercase(),
                name: f[1].trim().to_string(),
                dispersion,
                range_um: (num(f[3], "min_um")?, num(f[4], "max_um")?),
                nd: num(f[6], "nd")?,
                vd: num(f[7], "vd")?,
            });
        }
        Ok(GlassCatalog { entries })
    }

    /// Every glass.
    pub fn entries(&self) -> &[CatalogEntry] {
        &self.entries
    }

    /// Finds a glass by `NAME` or `CATALOG:NAME`, case-insensitively. A bare name found in
    /// several catalogues resolves to SCHOTT's when SCHOTT has it, else it is ambiguous.
    pub fn find(&self, query: &str) -> Result<&CatalogEntry, GlassLookupError> {
        let q = query.trim();
        let (cat, name) = match q.split_once(':') {
            Some((c, n)) => (Some(c.trim()), n.trim()),
            None => (None, q),
        };
        let hits: Vec<&CatalogEntry> = self
            .entries
            .iter()
            .filter(|e| e.name.eq_ignore_ascii_case(name))
            .filter(|e| cat.is_none_or(|c| e.catalog.eq_ignore_ascii_case(c)))
            .collect();
        match hits.len() {
            0 => Err(GlassLookupError::Unknown {
                name: q.to_string(),
                suggestions: self.suggest(name, 3),
            }),
            1 => Ok(hits[0]),
            _ => {
                for pref in PREFERRED_ORDER {
                    if let Some(e) = hits.iter().find(|e| e.catalog == *pref) {
                        return Ok(e);
                    }
                }
                Err(GlassLookupError::Ambiguous {
                    name: q.to_string(),
                    candidates: hits.iter().map(|e| e.canonical_name()).collect(),
                })
            }
        }
    }

    /// Canonical names starting with `prefix` (case-insensitive, catalogue prefix optional):
    /// completion for editors.
    pub fn complete(&self, prefix: &str) -> Vec<String> {
        let p = prefix.trim().to_ascii_uppercase();
        self.entries
            .iter()
            .filter(|e| {
                e.name.to_ascii_uppercase().starts_with(&p)
                    || e.canonical_name().to_ascii_uppercase().starts_with(&p)
            })
            .map(CatalogEntry::canonical_name)
            .collect()
    }

    /// Up to `n` names close to `name` (for error messages).
    fn suggest(&self, name: &str, n: usize) -> Vec<String> {
        let key = normalise(name);
        let mut scored: Vec<(usize, String)> = self
            .entries
            .iter()
            .map(|e| (edit_distance(&key, &normalise(&e.name)), e.canonical_name()))
            .filter(|(d, _)| *d <= 2)
            .collect();
        scored.sort();
        scored.into_iter().take(n).map(|(_, s)| s).collect()
    }
}

fn normalise(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_uppercase())
        .collect()
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Builds a [`Dispersion`] from a refractiveindex.info formula number and its coefficients
/// (`c0` followed by pairs).
fn dispersion_from_formula(formula: &str, c: &[f64]) -> Result<Dispersion, String> {
    if c.is_empty() || c.len().is_multiple_of(2) {
        return Err(format!(
            "formula {formula} needs c0 and coefficient pairs, got {} numbers",
            c.len()
        ));
    }
    let c0 = c[0];
    let terms: Vec<(f64, f64)> = c[1..].chunks_exact(2).map(|p| (p[0], p[1])).collect();
    Ok(match formula {
        "1" => Dispersion::Sellmeier { c0, terms },
        "2" => Dispersion::Sellmeier2 { c0, terms },
        "3" => Dispersion::Polynomial { c0, terms },
        "5" => Dispersion::CauchyGeneral { c0, terms },
        other => return Err(format!("unsupported dispersion formula `{other}`")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCHOTT_30: &str = include_str!("../../data/schott_sellmeier_30.csv");

    #[test]
    fn bundled_catalogue_has_every_glass() {
        assert_eq!(GlassCatalog::bundled().entries().len(), 1613);
    }

    #[test]
    fn every_glass_reproduces_its_listed_nd_and_vd() {
        for e in GlassCatalog::bundled().entries() {
            let d = e.dispersion();
            // Formulas valid only in the infrared (AMTIR, IG2) are skipped at the d line.
            if e.range_um.0 > 0.5876 || e.range_um.1 < 0.6563 {
                continue;
            }
            assert!(
                (d.nd() - e.nd).abs() < 2e-6,
                "{}: nd {} vs {}",
                e.canonical_name(),
                d.nd(),
                e.nd
            );
            assert!(
                (d.vd() - e.vd).abs() < 2e-3 * e.vd.max(1.0),
                "{}: vd {} vs {}",
                e.canonical_name(),
                d.vd(),
                e.vd
            );
        }
    }

    #[test]
    fn schott_sellmeier_reference_glasses_match_catalogue_nd_vd() {
        let cat = GlassCatalog::bundled();
        let mut n = 0;
        for line in SCHOTT_30
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("glass,"))
        {
            let f: Vec<&str> = line.split(',').collect();
            let (name, nd, vd): (&str, f64, f64) =
                (f[0], f[2].parse().unwrap(), f[3].parse().unwrap());
            let e = cat.find(&format!("SCHOTT:{name}")).unwrap();
            let d = e.dispersion();
            assert!(
                (d.nd() - nd).abs() < 1e-5,
                "{name}: nd {} vs catalogue {nd}",
                d.nd()
            );
            assert!(
                (d.vd() - vd).abs() < 0.05,
                "{name}: vd {} vs catalogue {vd}",
                d.vd()
            );
            // The independent Sellmeier coefficients in the reference file give the same index.
            let b: Vec<f64> = f[4..10].iter().map(|s| s.parse().unwrap()).collect();
            let indep = Dispersion::Sellmeier2 {
                c0: 0.0,
                terms: vec![(b[0], b[1]), (b[2], b[3]), (b[4], b[5])],
            };
            for l in [400.0, 550.0, 700.0] {
                assert!(
                    (indep.index(l) - d.index(l)).abs() < 1e-9,
                    "{name} at {l} nm"
                );
            }
            n += 1;
        }
        assert_eq!(n, 30);
    }

    #[test]
    fn names_resolve_case_insensitively_with_optional_catalogue() {
        let cat = GlassCatalog::bundled();
        let a = cat.find("SCHOTT:N-BK7").unwrap();
        assert_eq!(cat.find("n-bk7").unwrap(), a);
        assert_eq!(cat.find(" schott:n-bk7 ").unwrap(), a);
        assert_eq!(a.canonical_name(), "SCHOTT:N-BK7");
        assert!((a.dispersion().nd() - 1.5168).abs() < 1e-4);
    }

    #[test]
    fn unknown_glass_error_suggests_near_names() {
        let err = GlassCatalog::bundled().find("N-BK8").unwrap_err();
        let text = err.to_string();
        assert!(text.contains("unknown glass `N-BK8`"), "{text}");
        assert!(text.contains("SCHOTT:N-BK7"), "{text}");
    }

    #[test]
    fn cauchy_errs_for_dense_flint_in_the_blue_as_design_notes_say() {
        let sf = GlassCatalog::bundled().find("SCHOTT:N-SF66").unwrap();
        let d = sf.dispersion();
        let cauchy = Dispersion::cauchy_from_abbe(d.nd(), d.vd());
        let err = (cauchy.index(400.0) - d.index(400.0)).abs();
        assert!(
            err > 1e-3,
            "Cauchy error at 400 nm for N-SF66 is only {err}"
        );
    }

    #[test]
    fn malformed_rows_give_line_numbers() {
        let bad =
            "catalog,name,formula,min_um,max_um,coefficients,nd,vd\nX,G,2,0.3,2.5,0 1 x,1.5,60\n";
        let e = GlassCatalog::parse(bad).unwrap_err();
        assert_eq!(e.line, 2);
        let bad = "X,G,9,0.3,2.5,0 1 0.01,1.5,60\n";
        assert!(
            GlassCatalog::parse(bad)
                .unwrap_err()
                .message
                .contains("formula")
        );
    }
}
