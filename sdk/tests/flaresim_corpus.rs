//! FlareSim's whole lens library (`tests/data/flaresim-lenses/`, 1,373 files, MIT) read by the
//! `.lens` reader, load only: nothing panics, every refusal is a `file:line:column` error in a
//! known category, at least 1,200 lenses load, and their paraxial focal lengths agree with the
//! ones the files state. The figures are printed (`--nocapture`) and written down in
//! `docs/lenses.md`; the slow tier renders every loaded lens (`tests/flaresim_render.rs`).
//!
//! Three files of the library have names cut short before `.lens` (a `/` in the lens's name);
//! they are read as `.lens` text, the others by their extension
//! (`flarebench_test_support::read_flaresim_library_file`).

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use flarebench_sdk::io::LensFileError;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_test_support::{flaresim_library_files, read_flaresim_library_file as read};

/// Lenses that must load: 1,254 did when the reader was written (`docs/lenses.md`); the issue
/// asks for at least 1,200.
const MIN_LOADED: usize = 1200;

/// Share of the loaded lenses with a stated focal length whose paraxial EFL is within 1% of
/// it: 92.7% measured (`docs/lenses.md`), as the hand conversion of the same files.
const MIN_SHARE_WITHIN_1_PERCENT: f64 = 0.85;

/// Every reason a file of the library may be refused, by the error's field and a part of its
/// message.
const REASONS: &[(&str, &[&str], &str)] = &[
    ("no stop row", &["radius"], "no stop row"),
    (
        "clear aperture beyond |R|",
        &["semi_ap"],
        "which no surface can have",
    ),
    ("clear aperture of 0", &["semi_ap"], "must be > 0 mm"),
    (
        "negative thickness (mirror lens)",
        &["thickness"],
        "must be ≥ 0 mm",
    ),
    ("infinite thickness", &["thickness"], "must be finite"),
    (
        "afocal attachment",
        &["focal_length", "surfaces"],
        "afocal attachment",
    ),
    ("anamorphic surface", &["type"], "anamorphic"),
    ("no surface table", &["surfaces"], "no `surfaces:` line"),
    (
        "empty surface table",
        &["surfaces"],
        "the surface table is empty",
    ),
    ("malformed number", &[], "expected a number"),
];

/// The category of a refusal, if it is a known one.
fn reason(e: &LensFileError) -> Option<&'static str> {
    REASONS
        .iter()
        .find(|(_, fields, says)| {
            (fields.is_empty() || fields.contains(&e.field.as_str())) && e.message.contains(says)
        })
        .map(|(name, _, _)| *name)
}

/// The median of `v` (sorted here).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[test]
fn the_whole_flaresim_library_loads_or_is_refused_for_a_known_reason() {
    let files = flaresim_library_files();
    let mut loaded = Vec::new();
    let mut refused: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    let mut unknown = Vec::new();
    let mut panics = Vec::new();
    for path in &files {
        match catch_unwind(AssertUnwindSafe(|| read(path, false))) {
            Err(_) => panics.push(path.display().to_string()),
            Ok(Ok(lens)) => loaded.push(lens),
            Ok(Err(e)) => {
                let located = e.line >= 1 && e.column >= 1 && !e.field.is_empty();
                let shown = e.to_string();
                let named =
                    shown.starts_with(&format!("{}:{}:{}: field `", e.file, e.line, e.column));
                match reason(&e) {
                    Some(r) if located && named => refused.entry(r).or_default().push(shown),
                    _ => unknown.push(shown),
                }
            }
        }
    }
    assert!(panics.is_empty(), "panicked on {panics:?}");
    assert!(
        unknown.is_empty(),
        "refused without a located error of a known reason: {unknown:#?}"
    );

    // The convention chosen, and the crossings left as warnings.
    let diameters = loaded
        .iter()
        .filter(|l| l.system.notes.contains("read as diameters"))
        .count();
    let mut bases: BTreeMap<String, usize> = BTreeMap::new();
    for l in &loaded {
        let basis = l
            .system
            .notes
            .split("decided from the data (")
            .nth(1)
            .and_then(|rest| rest.split(')').next())
            .unwrap_or("forced");
        *bases.entry(basis.to_string()).or_default() += 1;
    }
    // What the lenient option loads of the refused.
    let lenient: Vec<&PathBuf> = files
        .iter()
        .filter(|p| read(p, false).is_err() && read(p, true).is_ok())
        .collect();
    let crossing = loaded
        .iter()
        .filter(|l| l.warnings.iter().any(|w| w.contains("cross inside")))
        .count();

    // Paraxial EFL against the stated focal length.
    let efls: Vec<(&str, f64, f64)> = loaded
        .iter()
        .filter_map(|l| {
            let stated = l.system.stated_efl_mm?;
            let efl = analyse(&l.system, LAMBDA_D_NM).ok()?.efl_mm;
            Some((l.system.name.as_str(), efl, stated))
        })
        .collect();
    let mut deviations: Vec<f64> = efls
        .iter()
        .map(|(_, efl, stated)| (efl - stated).abs() / stated)
        .collect();
    let with_stated = deviations.len();
    let within = |limit: f64| deviations.iter().filter(|&&d| d <= limit).count();
    let (w1, w5) = (within(0.01), within(0.05));
    let over20 = deviations.iter().filter(|&&d| d > 0.20).count();
    let med = median(&mut deviations);

    let n_refused: usize = refused.values().map(Vec::len).sum();
    eprintln!("files: {}", files.len());
    eprintln!("loaded: {}", loaded.len());
    eprintln!(
        "  semi_ap as diameters: {diameters}, as semi-diameters: {}",
        loaded.len() - diameters
    );
    for (basis, n) in &bases {
        eprintln!("  decided {basis}: {n}");
    }
    eprintln!("  with crossing neighbouring surfaces (warnings): {crossing}");
    eprintln!("refused: {n_refused}");
    for (r, v) in &refused {
        eprintln!("  {r}: {} (e.g. {})", v.len(), v[0]);
    }
    eprintln!("loaded with --lenient-apertures besides: {}", lenient.len());
    for (name, efl, stated) in efls.iter().filter(|(_, e, s)| (e - s).abs() / s > 0.20) {
        eprintln!("  EFL {efl:.2} mm against the stated {stated} mm: {name}");
    }
    eprintln!("EFL against the stated focal length, {with_stated} lenses that state one:");
    eprintln!(
        "  within 1%: {w1} ({:.1}%), within 5%: {w5} ({:.1}%), over 20%: {over20}, median {:.4}%",
        100.0 * w1 as f64 / with_stated as f64,
        100.0 * w5 as f64 / with_stated as f64,
        100.0 * med
    );

    assert_eq!(loaded.len() + n_refused, files.len());
    assert!(
        loaded.len() >= MIN_LOADED,
        "{} lenses load, fewer than {MIN_LOADED}",
        loaded.len()
    );
    let share = w1 as f64 / with_stated as f64;
    assert!(
        share >= MIN_SHARE_WITHIN_1_PERCENT,
        "{share:.3} of the loaded lenses are within 1% of their stated focal length"
    );
    // Every loaded lens is a valid system (the reader validated it; checked again here).
    for l in &loaded {
        l.system
            .validate()
            .unwrap_or_else(|e| panic!("{}: {e:?}", l.system.name));
    }
}
