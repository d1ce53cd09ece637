//! Golden images: the ghosts of the Heliar-Tronnier and the Nikon zoom rendered at 192×108
//! (default quality, light at 10°, 30°, no starburst) must match the committed EXR files in
//! `tests/golden/`.
//!
//! Tolerance: relative RMSE 1e-4 and energy 1e-5 — enough for the order in which the cores'
//! accumulators are summed, far below any visible change (a one-pixel shift of a ghost is
//! several per cent). A missing golden fails; `UPDATE_GOLDEN=1 cargo test -p flarebench
//! --test golden` writes them anew (look at the PNGs it writes next to them before
//! committing).

mod common;

use std::path::PathBuf;

use common::{flarebench, temp_dir};
use flarebench::output::read_exr;

/// Relative RMSE against the golden image: the order in which the cores' accumulators are
/// summed (see the module's comment).
const GOLDEN_RMSE_TOL: f64 = 1e-4;
/// Energy error against the golden image (relative): the same summation order.
const GOLDEN_ENERGY_TOL: f64 = 1e-5;

fn golden(lens: &str) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let want = dir.join(format!("{lens}.exr"));
    let tmp = temp_dir("golden");
    let out = tmp.path().join(format!("{lens}.exr"));
    let args = [
        "render",
        lens,
        "--light",
        "10,30",
        "--size",
        "192x108",
        "--starburst",
        "off",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    let run = flarebench(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let got = read_exr(&out).unwrap();
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(&out, &want).unwrap();
        let png = dir.join(format!("{lens}.png"));
        let mut args = args.to_vec();
        let png_s = png.to_str().unwrap().to_string();
        *args.last_mut().unwrap() = &png_s;
        assert!(flarebench(&args).status.success());
        eprintln!("wrote {} and {}", want.display(), png.display());
        return;
    }
    let reference = read_exr(&want).unwrap_or_else(|e| {
        panic!(
            "missing golden image {} ({e}); run with UPDATE_GOLDEN=1 to create it",
            want.display()
        )
    });
    let c = got.compare(&reference).unwrap();
    assert!(
        c.relative_rmse < GOLDEN_RMSE_TOL && c.energy_error.abs() < GOLDEN_ENERGY_TOL,
        "{lens}: differs from its golden image: relative RMSE {:.3e}, energy {:.3e}",
        c.relative_rmse,
        c.energy_error
    );
}

#[test]
fn heliar_matches_its_golden_image() {
    golden("heliar-tronnier");
}

#[test]
fn nikon_zoom_matches_its_golden_image() {
    golden("nikon-zoom-short");
}
