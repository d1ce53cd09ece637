//! The medium after a Zemax surface, from its `GLAS` record: a catalogue glass looked up in the
//! bundled catalogue in the order of the file's `GCAT`, a legacy name through its documented
//! successor, a model glass (`___BLANK`, nd and Vd) or a six-digit glass code.
//!
//! `GLAS name mode pickup nd vd …`: for catalogue names the nd/Vd fields are whatever Zemax
//! last saved (often placeholders), so the name decides; `___BLANK` reads nd and Vd from them.

use crate::glass::{CatalogEntry, GlassCatalog, GlassLookupError};
use crate::io::LensFileError;
use crate::io::located::Reporter;
use crate::system::Medium;

use super::records::Record;

/// Names of materials the bundled catalogue holds under another maker's name, with what they
/// are. Zemax's `MISC` catalogue calls fused silica `SILICA`; Corning's is `C79-80`.
const ALIASES: &[(&[&str], &str, &str)] = &[
    (
        &[
            "SILICA",
            "F_SILICA",
            "FUSED_SILICA",
            "FUSEDSILICA",
            "SIO2",
            "C79-80",
            "C7980",
        ],
        "SCHOTT:LITHOSIL-Q",
        "synthetic fused silica",
    ),
    (
        &["CAF2", "CALCIUM_FLUORIDE"],
        "SCHOTT:LITHOTEC-CAF2",
        "calcium fluoride",
    ),
];

/// Successor prefixes: Schott's lead- and arsenic-free `N-` glasses replaced the classic names
/// (BK7 → N-BK7), Ohara's `S-` glasses its older ones (LAH64 → S-LAH64).
const SUCCESSORS: &[(&str, &str)] = &[("SCHOTT", "N-"), ("OHARA", "S-")];

/// Glass names already resolved in this file, so that each substitution is reported once.
#[derive(Debug, Default)]
pub(super) struct Seen(Vec<String>);

impl Seen {
    /// True the first time `name` is seen.
    fn first(&mut self, name: &str) -> bool {
        let up = name.to_ascii_uppercase();
        if self.0.contains(&up) {
            false
        } else {
            self.0.push(up);
            true
        }
    }
}

/// A resolved glass: the medium and, the first time a name is substituted, a note for the
/// user.
pub(super) struct Resolved {
    pub medium: Medium,
    pub substitution: Option<String>,
}

impl Resolved {
    /// Drops the substitution note after the first time.
    fn once(mut self, first: bool) -> Self {
        if !first {
            self.substitution = None;
        }
        self
    }
}

fn from_entry(e: &CatalogEntry) -> Medium {
    Medium::Glass {
        name: e.canonical_name(),
        dispersion: e.dispersion.clone(),
    }
}

/// Resolves a `GLAS` record (not `MIRROR`, which the caller refuses). `gcat` lists the file's
/// catalogues in its order of preference; `lambda_nm` is the primary wavelength, checked
/// against the glass formula's range.
pub(super) fn resolve(
    ctx: &mut Reporter<'_>,
    rec: &Record<'_>,
    gcat: &[String],
    lambda_nm: Option<f64>,
    seen: &mut Seen,
) -> Result<Resolved, LensFileError> {
    let name = rec.arg(0).unwrap_or_default();
    let first = seen.first(name);
    let mut quiet = Reporter::new(ctx.file, "");
    let ctx = if first { ctx } else { &mut quiet };
    let name_pos = rec.arg_pos(0);
    if name.is_empty() {
        return Err(ctx.error(rec.pos, "GLAS", "`GLAS` needs a glass name"));
    }
    if rec.arg(1) == Some("4") {
        ctx.warn(
            rec.arg_pos(1),
            format!("glass `{name}` has an nd/Vd offset (mode 4); the offset is ignored"),
        );
    }
    if name.eq_ignore_ascii_case("___BLANK") {
        return model_glass(ctx, rec);
    }
    if name.bytes().all(|b| b.is_ascii_digit()) {
        return glass_code(ctx, name, name_pos).map(|r| r.once(first));
    }
    let cat = GlassCatalog::bundled();
    let upper = name.to_ascii_uppercase();
    let found = |r: Resolved, entry: &CatalogEntry, ctx: &mut Reporter<'_>| {
        if let Some(l) = lambda_nm {
            let (lo, hi) = entry.range_um;
            if !(lo * 1e3..=hi * 1e3).contains(&l) {
                ctx.warn(
                    name_pos,
                    format!(
                        "the primary wavelength {l} nm lies outside {}'s formula range \
                         {}–{} nm: its index there is extrapolated",
                        entry.canonical_name(),
                        lo * 1e3,
                        hi * 1e3
                    ),
                );
            }
        }
        Ok(r.once(first))
    };
    // 1. In the file's catalogues, in its order.
    for c in gcat {
        if let Ok(e) = cat.find(&format!("{c}:{name}")) {
            let r = Resolved {
                medium: from_entry(e),
                substitution: None,
            };
            return found(r, e, ctx);
        }
    }
    if gcat.is_empty()
        && let Ok(e) = cat.find(name)
    {
        let r = Resolved {
            medium: from_entry(e),
            substitution: None,
        };
        return found(r, e, ctx);
    }
    // 2. Another name for a material the catalogue holds.
    for (names, canonical, what) in ALIASES {
        if names.contains(&upper.as_str()) {
            let e = cat
                .find(canonical)
                .expect("every alias names a glass of the bundled catalogue");
            let note = format!(
                "glass `{name}` ({what}) is read as {} (nd {:.5}, Vd {:.2})",
                e.canonical_name(),
                e.nd,
                e.vd
            );
            ctx.warn(name_pos, &note);
            let r = Resolved {
                medium: from_entry(e),
                substitution: Some(note),
            };
            return found(r, e, ctx);
        }
    }
    // 3. A legacy name whose successor is in the catalogue.
    for (maker, prefix) in SUCCESSORS {
        if let Ok(e) = cat.find(&format!("{maker}:{prefix}{name}")) {
            let note = format!(
                "glass `{name}` is not in the bundled catalogue; read as its successor {} \
                 (nd {:.5}, Vd {:.2})",
                e.canonical_name(),
                e.nd,
                e.vd
            );
            ctx.warn(name_pos, &note);
            let r = Resolved {
                medium: from_entry(e),
                substitution: Some(note),
            };
            return found(r, e, ctx);
        }
    }
    // 4. Any catalogue.
    let hits: Vec<&CatalogEntry> = cat
        .entries()
        .iter()
        .filter(|e| e.name.eq_ignore_ascii_case(name))
        .collect();
    if let Some(e) = hits
        .iter()
        .find(|e| e.catalog == "SCHOTT")
        .or_else(|| hits.first())
    {
        let others: Vec<String> = hits
            .iter()
            .filter(|o| o.catalog != e.catalog)
            .map(|o| o.canonical_name())
            .collect();
        let also = if others.is_empty() {
            String::new()
        } else {
            format!("; also in {}", others.join(", "))
        };
        let listed = if gcat.is_empty() {
            String::new()
        } else {
            format!(" (GCAT {})", gcat.join(" "))
        };
        let note = format!(
            "glass `{name}` is not in the file's catalogues{listed}; read as {}{also}",
            e.canonical_name()
        );
        ctx.warn(name_pos, &note);
        let r = Resolved {
            medium: from_entry(e),
            substitution: Some(note),
        };
        return found(r, e, ctx);
    }
    let suggestions = match cat.find(name) {
        Err(GlassLookupError::Unknown { suggestions, .. }) if !suggestions.is_empty() => {
            format!(" (did you mean {}?)", suggestions.join(", "))
        }
        _ => String::new(),
    };
    Err(ctx.error(
        name_pos,
        "GLAS",
        format!(
            "unknown glass `{name}`{suggestions}: it is not in the bundled catalogue \
             (sdk/data/glass_catalog.csv); replace it by a catalogue name or a model glass \
             (___BLANK with nd and Vd)"
        ),
    ))
}

/// `GLAS ___BLANK mode pickup nd vd …`: a model glass; Vd 0 is non-dispersive (as Zemax).
fn model_glass(ctx: &Reporter<'_>, rec: &Record<'_>) -> Result<Resolved, LensFileError> {
    let nd = rec.number(ctx, 3)?;
    let vd = rec.number(ctx, 4)?;
    if nd < 1.0 {
        return Err(ctx.error(
            rec.arg_pos(3),
            "GLAS",
            format!("the model glass's nd must be ≥ 1, got {nd}"),
        ));
    }
    if vd < 0.0 {
        return Err(ctx.error(
            rec.arg_pos(4),
            "GLAS",
            format!("the model glass's Vd must be ≥ 0 (0: no dispersion), got {vd}"),
        ));
    }
    let medium = if nd == 1.0 {
        Medium::Air
    } else {
        Medium::Model {
            nd,
            vd: (vd > 0.0).then_some(vd),
        }
    };
    Ok(Resolved {
        medium,
        substitution: None,
    })
}

/// A six-digit glass code `nnnvvv`: nd = 1.nnn, Vd = vv.v — a model glass, rounded as the
/// code is.
fn glass_code(ctx: &mut Reporter<'_>, code: &str, pos: usize) -> Result<Resolved, LensFileError> {
    if code.len() != 6 {
        return Err(ctx.error(
            pos,
            "GLAS",
            format!("a glass code has six digits (nnnvvv: nd 1.nnn, Vd vv.v), got `{code}`"),
        ));
    }
    let (n, v) = code.split_at(3);
    let nd = 1.0 + n.parse::<f64>().unwrap_or(0.0) / 1000.0;
    let vd = v.parse::<f64>().unwrap_or(0.0) / 10.0;
    if vd <= 0.0 || nd == 1.0 {
        return Err(ctx.error(
            pos,
            "GLAS",
            format!("glass code `{code}` gives nd {nd}, Vd {vd}: not a glass"),
        ));
    }
    let note = format!(
        "glass code {code} is read as a model glass nd {nd:.3}, Vd {vd:.1} (the code's rounding)"
    );
    ctx.warn(pos, &note);
    Ok(Resolved {
        medium: Medium::Model { nd, vd: Some(vd) },
        substitution: Some(note),
    })
}
