//! The fits' caches: made once, then read from memory or disk; a corrupt, stale or foreign
//! file is ignored and the fit made again, never a panic.

use flarebench_test_support::plate;
use ghost_polynomial::cache::{FitsFile, fits_path, forget, table_path};
use ghost_polynomial::fit::FitSettings;
use ghost_polynomial::model::{LensModel, Source};

fn settings() -> FitSettings {
    FitSettings {
        samples: 512,
        degree: 3,
        terms: 10,
        seed: 4,
    }
}

/// The plate with a curved front face (so that it focuses: the tables' angles come from its
/// focal length), of radius `r` mm: each test a lens of its own in the process-wide memory
/// cache, so that they do not meet there.
fn lens(r: f64) -> flarebench_sdk::LensSystem {
    let mut sys = plate();
    sys.surfaces[1].curvature = 1.0 / r;
    sys
}

#[test]
fn fits_are_made_once_then_read_from_memory_and_from_disk() {
    let dir = tempfile::tempdir().unwrap();
    let sys = lens(40.0);
    let model = LensModel::new(&sys, Some(dir.path())).unwrap();
    assert_eq!(model.table_timing.source, Source::Made);
    assert!(table_path(dir.path(), &model.fingerprint).is_file());
    let (made, t) = model.fits(&settings());
    assert_eq!(t.source, Source::Made);
    assert!(!made.is_empty());
    assert!(fits_path(dir.path(), &model.fingerprint, &settings()).is_file());
    let (again, t) = model.fits(&settings());
    assert_eq!(t.source, Source::Memory);
    assert_eq!(*again, *made);
    forget(&model.fingerprint);
    let model = LensModel::new(&sys, Some(dir.path())).unwrap();
    assert_eq!(model.table_timing.source, Source::Disk);
    let (read, t) = model.fits(&settings());
    assert_eq!(t.source, Source::Disk);
    assert_eq!(*read, *made, "the disk round trip keeps every bit");
    // Other settings are another file.
    let other = FitSettings {
        seed: 5,
        ..settings()
    };
    assert_eq!(model.fits(&other).1.source, Source::Made);
}

#[test]
fn a_corrupt_or_stale_cache_file_is_ignored_and_the_fit_made_again() {
    let dir = tempfile::tempdir().unwrap();
    let sys = lens(41.0);
    let model = LensModel::new(&sys, Some(dir.path())).unwrap();
    let (made, _) = model.fits(&settings());
    let path = fits_path(dir.path(), &model.fingerprint, &settings());
    let good = std::fs::read_to_string(&path).unwrap();
    let mut stale: FitsFile = serde_json::from_str(&good).unwrap();
    stale.version += 1;
    let mut foreign: FitsFile = serde_json::from_str(&good).unwrap();
    foreign.lens_fingerprint = "0123456789abcdef".into();
    let mut malformed: FitsFile = serde_json::from_str(&good).unwrap();
    malformed.fits[0].outputs.pop();
    for bad in [
        "not json".to_string(),
        good[..good.len() / 2].to_string(),
        serde_json::to_string(&stale).unwrap(),
        serde_json::to_string(&foreign).unwrap(),
        serde_json::to_string(&malformed).unwrap(),
    ] {
        std::fs::write(&path, &bad).unwrap();
        forget(&model.fingerprint);
        let (fits, t) = model.fits(&settings());
        assert_eq!(t.source, Source::Made, "{}", &bad[..bad.len().min(40)]);
        assert_eq!(*fits, *made);
        // Written again, whole.
        assert_eq!(std::fs::read_to_string(&path).unwrap(), good);
    }
    // A corrupt bounds table is traced again.
    std::fs::write(table_path(dir.path(), &model.fingerprint), "{").unwrap();
    forget(&model.fingerprint);
    let model = LensModel::new(&sys, Some(dir.path())).unwrap();
    assert_eq!(model.table_timing.source, Source::Made);
}
