//! The bundled library (`lenses/` and its maker folders): every curated lens is what `flarebench
//! curate` makes of its line of the selection list, loads with its metadata, keeps its stated
//! focal length and renders finite; bundled names resolve by stem, prefix or part; `flarebench
//! lenses` lists and filters. The full checks of every curated lens (three angles, stability
//! `--quick`) are in the slow tier.

use crate::common;

use std::collections::{BTreeMap, HashSet};

use flarebench::curation::{self, checks, selection};
use flarebench::lens_library::{self, BundledLens};
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::{LensKind, LensSystem};
use rayon::prelude::*;
use serde_json::Value;

/// The issue asks for at least 300 curated lenses.
const MIN_CURATED: usize = 300;

/// Width of the default tier's renders (pixels): the smallest frame whose ghosts still cover
/// several pixels on every lens (the checks render at `checks::RENDER_WIDTH`).
const TINY_WIDTH: usize = 24;

/// The light of the default tier's render (degrees off the axis).
const TINY_THETA_DEG: f64 = 10.0;

/// The lenses in maker folders.
fn curated() -> Vec<BundledLens> {
    lens_library::bundled()
        .into_iter()
        .filter(|l| l.folder.is_some())
        .collect()
}

fn load(l: &BundledLens) -> LensSystem {
    read_lens(&l.path)
        .unwrap_or_else(|e| panic!("{}: {e}", l.qualified))
        .system
}

#[test]
fn the_library_holds_the_top_lenses_and_over_300_curated_ones_with_unique_names() {
    let all = lens_library::bundled();
    let core = lens_library::core_names();
    assert_eq!(core.len(), 19, "{core:?}");
    assert!(core.contains(&"heliar-tronnier".to_string()));
    let curated = curated();
    assert!(curated.len() >= MIN_CURATED, "{} curated", curated.len());
    assert_eq!(all.len(), core.len() + curated.len());
    let mut seen = HashSet::new();
    for l in &all {
        assert!(seen.insert(&l.name), "`{}` is bundled twice", l.name);
        assert!(selection::is_kebab(&l.name), "{}", l.qualified);
        if let Some(f) = &l.folder {
            assert!(
                selection::is_kebab(f) && f != "sources" && f != "masks",
                "{f}"
            );
            assert!(
                l.path.extension().is_some_and(|e| e == "xml"),
                "{:?}",
                l.path
            );
        }
    }
}

#[test]
fn every_curated_lens_is_what_curate_makes_of_its_selection_line() {
    let entries = curation::read_selection(&curation::selection_path()).unwrap();
    let curated = curated();
    let listed: HashSet<String> = entries.iter().map(|e| e.qualified()).collect();
    for l in &curated {
        assert!(
            listed.contains(&l.qualified),
            "{} is in lenses/ but not in the selection list",
            l.qualified
        );
    }
    assert_eq!(entries.len(), curated.len(), "a selected lens is missing");
    let corpus = curation::corpus_dir();
    entries.par_iter().for_each(|e| {
        let fresh = curation::conversion::convert(e, &corpus).unwrap();
        let path = curation::lenses_dir().join(format!("{}.xml", e.qualified()));
        let mut bundled = read_lens(&path)
            .unwrap_or_else(|err| panic!("{}: {err}", e.qualified()))
            .system;
        assert!(
            bundled.notes.ends_with('.') && bundled.notes.contains("\nChecks (flarebench curate)"),
            "{}: the notes carry no checks",
            e.qualified()
        );
        bundled.notes = curation::notes_without_checks(&bundled.notes).to_string();
        assert_eq!(
            bundled,
            fresh,
            "{}: regenerate with `flarebench curate`",
            e.qualified()
        );
    });
}

#[test]
fn every_curated_lens_has_its_metadata_and_its_stated_focal_length() {
    for l in curated() {
        let sys = load(&l);
        let q = &l.qualified;
        assert!(!sys.maker.is_empty(), "{q}: no maker");
        assert_eq!(
            sys.kind.contains(&LensKind::Prime),
            !sys.kind.contains(&LensKind::Zoom),
            "{q}: {:?}",
            sys.kind
        );
        let [lo, hi] = sys
            .nominal_focal_mm
            .unwrap_or_else(|| panic!("{q}: no focal"));
        assert_eq!(lo == hi, sys.kind.contains(&LensKind::Prime), "{q}");
        assert!(sys.f_number.is_some_and(|f| f > 0.0), "{q}: no f-number");
        assert!(sys.source.contains("MIT"), "{q}: {}", sys.source);
        let stated = sys
            .stated_efl_mm
            .unwrap_or_else(|| panic!("{q}: no stated EFL"));
        let efl = analyse(&sys, sys.default_wavelength_nm()).unwrap().efl_mm;
        let off = (efl / stated - 1.0).abs();
        assert!(
            off <= checks::MAX_EFL_DEVIATION || sys.notes.contains("EFL:"),
            "{q}: paraxial EFL {efl} against the stated {stated}"
        );
    }
}

/// One curated lens in this many is rendered in the default tier (the slow tier renders
/// every one at three angles).
const RENDER_SAMPLE_STEP: usize = 16;

#[test]
fn a_sample_of_the_curated_lenses_renders_finite_in_a_tiny_frame() {
    let sample: Vec<BundledLens> = curated().into_iter().step_by(RENDER_SAMPLE_STEP).collect();
    assert!(sample.len() * RENDER_SAMPLE_STEP >= MIN_CURATED);
    let failures: Vec<String> = sample
        .par_iter()
        .filter_map(|l| {
            let r = checks::render_check(&load(l), TINY_THETA_DEG, TINY_WIDTH);
            (r.result != Ok(0)).then(|| format!("{}: {:?}", l.qualified, r.result))
        })
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
#[ignore = "slow tier: every check of `flarebench curate` on every curated lens, as its notes \
            list them (three renders each; stability --quick where the notes say it ran)"]
fn every_curated_lens_passes_its_checks_as_its_notes_say() {
    let failures: Vec<String> = curated()
        .par_iter()
        .filter_map(|l| {
            let sys = load(l);
            // The notes give the stability suite's result, or say it was not run. Where it ran,
            // it runs again here, and the notes must say what it finds: passed, or each finding
            // outside its limit with its figure (`Checks::note`).
            let stability = !sys.notes.contains("stability --quick: not run");
            let c = checks::run(&l.name, &sys, stability);
            let f = c.failures();
            if !f.is_empty() {
                Some(format!("{}: {}", l.qualified, f.join("; ")))
            } else if !sys.notes.ends_with(&c.note()) {
                Some(format!(
                    "{}: the notes do not end with `{}`",
                    l.qualified,
                    c.note()
                ))
            } else {
                None
            }
        })
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

// Names.

fn resolve_err(spec: &str) -> String {
    format!("{:#}", lens_library::resolve(spec).unwrap_err())
}

#[test]
fn a_bundled_name_resolves_by_stem_folder_prefix_or_part() {
    let stem = |spec: &str| {
        let p = lens_library::resolve(spec).unwrap_or_else(|e| panic!("{spec}: {e:#}"));
        p.file_stem().unwrap().to_string_lossy().into_owned()
    };
    // An exact stem wins over the longer names it begins.
    assert_eq!(stem("heliar-tronnier"), "heliar-tronnier");
    assert_eq!(stem("ai-nikkor-135mm-f2"), "ai-nikkor-135mm-f2");
    assert_eq!(stem("nikon/ai-nikkor-135mm-f2"), "ai-nikkor-135mm-f2");
    assert_eq!(stem("AI-Nikkor-135MM-F2"), "ai-nikkor-135mm-f2");
    // A unique prefix, then a unique part.
    assert_eq!(stem("heliar-tronnier-l"), "heliar-tronnier-lff");
    assert_eq!(stem("ai-nikkor-135"), "ai-nikkor-135mm-f2");
    assert_eq!(stem("nikkor-135mm-f2"), "ai-nikkor-135mm-f2");
}

#[test]
fn an_ambiguous_name_lists_its_candidates() {
    let e = resolve_err("nikon-zoom");
    assert!(e.contains("a prefix of 3 bundled lenses"), "{e}");
    for c in ["nikon-zoom-long", "nikon-zoom-mid", "nikon-zoom-short"] {
        assert!(e.contains(c), "{e}");
    }
    // Many candidates: the first twelve, and how to see the rest.
    let e = resolve_err("f2.8");
    assert!(e.contains("it is a part of"), "{e}");
    assert!(
        e.contains("more (`flarebench lenses f2.8` lists them all)"),
        "{e}"
    );
    // Twelve names and the count of the rest.
    let listed = e.split_once('(').unwrap().1.split(", …").next().unwrap();
    assert_eq!(listed.split(", ").count(), 12, "{e}");
}

#[test]
fn an_unknown_name_suggests_near_ones_not_the_whole_library() {
    let e = resolve_err("heliar-tronier");
    assert!(e.contains("did you mean heliar-tronnier"), "{e}");
    let e = resolve_err("ai-nikor-135mm-f2");
    assert!(e.contains("did you mean ai-nikkor-135mm-f2"), "{e}");
    assert!(e.len() < 600, "{e}");
    let e = resolve_err("qqqqqqqqqq");
    assert!(e.contains("no bundled lens has a name like it"), "{e}");
}

// `flarebench lenses`.

fn names(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|l| l["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn lenses_json_lists_every_bundled_lens_with_its_fields() {
    let v = common::json(&["lenses", "--json"]);
    let all = v.as_array().unwrap();
    assert_eq!(all.len(), lens_library::bundled().len());
    let nikkor = all
        .iter()
        .find(|l| l["name"] == "ai-nikkor-135mm-f2")
        .expect("the AI Nikkor 135 mm f/2 is bundled");
    let mut keys: Vec<&str> = nikkor
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "efl_mm", "elements", "f_number", "file", "focal_mm", "ghosts", "kind", "maker",
            "name", "title"
        ]
    );
    assert_eq!(nikkor["file"], "nikon/ai-nikkor-135mm-f2.xml");
    assert_eq!(nikkor["maker"], "Nikon");
    assert_eq!(nikkor["kind"], serde_json::json!(["prime"]));
    assert_eq!(nikkor["focal_mm"], serde_json::json!([135.0, 135.0]));
    let (elements, ghosts) = (
        nikkor["elements"].as_u64().unwrap(),
        nikkor["ghosts"].as_u64().unwrap(),
    );
    assert!(elements >= 4, "{nikkor}");
    // One ghost per pair of reflecting surfaces: at least one more surface than elements.
    let n = elements + 1;
    assert!(ghosts >= n * (n - 1) / 2, "{nikkor}");
    let heliar = all.iter().find(|l| l["name"] == "heliar-tronnier").unwrap();
    assert_eq!(
        (heliar["ghosts"].as_u64(), heliar["maker"].as_str()),
        (Some(28), Some(""))
    );
}

#[test]
fn lenses_filters_by_maker_focal_fnum_kind_and_words() {
    let list = |args: &[&str]| -> Vec<Value> {
        let mut a = vec!["lenses", "--json"];
        a.extend_from_slice(args);
        common::json(&a).as_array().unwrap().clone()
    };
    let f = |l: &Value, k: &str| l[k].as_f64().unwrap();
    let nikon = list(&["--maker", "nikon"]);
    assert!(
        nikon.len() >= 20 && nikon.iter().all(|l| l["maker"] == "Nikon"),
        "{}",
        nikon.len()
    );
    let wide = list(&["--focal", "..16"]);
    assert!(
        !wide.is_empty()
            && wide
                .iter()
                .all(|l| l["focal_mm"][0].as_f64().unwrap() <= 16.0)
    );
    // A zoom matches when its range overlaps the span.
    let normal = list(&["--focal", "50"]);
    assert!(
        normal
            .iter()
            .any(|l| l["focal_mm"][0].as_f64() < Some(50.0)
                && l["focal_mm"][1].as_f64() > Some(50.0))
    );
    let fast = list(&["--fnum", "..1.4"]);
    assert!(!fast.is_empty() && fast.iter().all(|l| f(l, "f_number") < 1.45));
    let macro_zeiss = list(&["--kind", "macro", "--maker", "zeiss"]);
    assert!(
        macro_zeiss
            .iter()
            .all(|l| l["kind"].as_array().unwrap().contains(&"macro".into()))
    );
    let fisheyes = list(&["--kind", "fisheye"]);
    assert!(fisheyes.len() >= 5, "{}", fisheyes.len());
    let words = names(&Value::Array(list(&["nikkor", "135mm"])));
    assert!(
        words.contains(&"ai-nikkor-135mm-f2".to_string()),
        "{words:?}"
    );
    assert!(words.iter().all(|n| n.contains("135")), "{words:?}");
    let none = list(&["--maker", "nikon", "--kind", "cine", "--focal", "5000.."]);
    assert!(none.is_empty());
}

#[test]
fn lenses_counts_by_maker_cover_the_makers_of_the_selection() {
    let v = common::json(&["lenses", "--json"]);
    let mut by_maker: BTreeMap<String, usize> = BTreeMap::new();
    for l in v.as_array().unwrap() {
        *by_maker
            .entry(l["maker"].as_str().unwrap().to_string())
            .or_default() += 1;
    }
    assert!(by_maker.len() >= 30, "{by_maker:?}");
    assert!(by_maker.values().all(|&n| n <= 46), "{by_maker:?}");
}

#[test]
fn lenses_refuses_bad_filters_with_the_option_named() {
    for (args, says) in [
        (
            vec!["lenses", "--focal", "35..24"],
            "--focal `35..24`: the range is empty",
        ),
        (vec!["lenses", "--fnum", "fast"], "--fnum `fast`"),
        (vec!["lenses", "--kind", "wide"], "unknown kind `wide`"),
    ] {
        let out = common::flarebench(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
