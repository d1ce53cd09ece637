//! A ghost's bands drawn as one fringed mesh (`ghost::fringe`) against the same bands drawn
//! one by one.

use std::path::Path;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::bounds::{self, GhostBounds};
use flarebench_sdk::ghost::fringe::mesh_ghost_fringed;
use flarebench_sdk::ghost::render::{
    Band, Frame, GhostContext, GhostLight, GhostMesh, mesh_ghost, rasterize_ghost_mesh,
};
use flarebench_sdk::ghost::{GhostPath, GridTrace};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::trace::InterfaceTableSet;
use flarebench_sdk::{LensSystem, Medium, Surface};

/// `m` equal bins over 400–700 nm, each band at its centre with a colour running from blue to
/// red; returns the bands and the bins' edges.
fn bands(sys: &LensSystem, m: usize) -> (Vec<Band>, Vec<f64>) {
    let width = 300.0 / m as f64;
    let edges: Vec<f64> = (0..=m).map(|i| 400.0 + width * i as f64).collect();
    let bands = (0..m)
        .map(|i| {
            let t = (i as f32 + 0.5) / m as f32;
            let lambda = 400.0 + width * (i as f64 + 0.5);
            Band::new(sys, lambda, [t, 1.0 - (2.0 * t - 1.0).abs(), 1.0 - t])
        })
        .collect();
    (bands, edges)
}

/// The ghost `path` of `sys` at `theta` on a `px`-pixel-wide frame, fringed and band by band.
fn both(
    sys: &LensSystem,
    path: GhostPath,
    theta: f64,
    m: usize,
    n: usize,
    px: usize,
) -> (HdrImage, HdrImage, GhostMesh) {
    let mut scratch = GridTrace::default();
    let tables = InterfaceTableSet::for_system(sys, 550.0);
    let direct = bounds::direct_flux(sys, &tables, theta, &mut scratch);
    let b: GhostBounds = bounds::precise(sys, path, &tables, theta, direct, &mut scratch)
        .expect("the ghost reaches the sensor");
    let height = px * 2 / 3;
    let frame = Frame {
        width: px,
        height,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * height as f64 / px as f64,
    };
    let aperture = Aperture::Circular;
    let ctx = GhostContext {
        system: sys,
        aperture: &aperture,
        frame,
        stop_radius: stop_opening(sys),
        f_number: analyse(sys, 587.6).map(|p| p.f_number).unwrap_or(4.0),
        trace_f64: false,
    };
    let light = GhostLight {
        theta,
        phi: 0.3,
        irradiance: 1.0,
    };
    let (bands, edges) = bands(sys, m);
    let refs: Vec<_> = bands.iter().map(Band::as_ref).collect();
    let mut fringed = GhostMesh::default();
    mesh_ghost_fringed(
        &ctx,
        path,
        &b,
        n,
        &light,
        &refs,
        &edges,
        &mut Vec::new(),
        &mut fringed,
    );
    let mut one_by_one = GhostMesh::default();
    mesh_ghost(
        &ctx,
        path,
        &b,
        n,
        &light,
        &refs,
        &mut scratch,
        &mut one_by_one,
    );
    let mut a = HdrImage::new(px, height);
    rasterize_ghost_mesh(&mut a, &fringed, &aperture);
    let mut c = HdrImage::new(px, height);
    rasterize_ghost_mesh(&mut c, &one_by_one, &aperture);
    (a, c, fringed)
}

/// Without dispersion every band lands in the same place: the fringed mesh is the bands'
/// sum, drawn once, and its image is theirs.
#[test]
fn without_dispersion_the_fringed_ghost_is_the_bands_sum() {
    let mut sys = LensSystem::new(
        "plate",
        vec![
            Surface::stop(5.0, 2.0),
            Surface::spherical(0.0, 3.0, Medium::Model { nd: 1.5, vd: None }, 10.0),
            Surface::spherical(0.0, 10.0, Medium::Air, 10.0),
            Surface::sensor(15.0),
        ],
    );
    sys.film_width_mm = 20.0;
    sys.film_height_mm = 20.0;
    let (fringed, bands, mesh) = both(&sys, GhostPath::two(2, 1), 8f64.to_radians(), 7, 33, 300);
    assert!(
        !mesh.fringe.is_empty() && mesh.edge.is_empty(),
        "drawn fringed"
    );
    assert!(!fringed.has_non_finite());
    let c = fringed.compare(&bands).unwrap();
    assert!(
        c.relative_rmse < 1e-4 && c.energy_error.abs() < 1e-5,
        "relative RMSE {:.2e}, energy {:.2e}",
        c.relative_rmse,
        c.energy_error
    );
}

/// On a real lens, a dispersive ghost's fringed image keeps each colour's light and differs
/// from the bands drawn one by one only along its edges and where the bands' interiors
/// shift. Measured when written (7-4, 8 bands): relative RMSE 1.2%, colour sums within 0.2%.
#[test]
fn a_dispersive_ghost_fringed_keeps_its_light_and_shape() {
    let lens = Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/heliar-tronnier.xml");
    let sys = read_lens(&lens).unwrap().system;
    let (fringed, bands, mesh) = both(&sys, GhostPath::two(7, 4), 10f64.to_radians(), 8, 17, 480);
    assert!(!mesh.fringe.is_empty(), "drawn fringed");
    assert!(!fringed.has_non_finite());
    let c = fringed.compare(&bands).unwrap();
    let (a, b) = (fringed.sum(), bands.sum());
    eprintln!(
        "relative RMSE {:.3e}, sums {a:?} against {b:?}",
        c.relative_rmse
    );
    for ch in 0..3 {
        assert!(
            (a[ch] / b[ch] - 1.0).abs() < 3e-3,
            "channel {ch}: {} against {}",
            a[ch],
            b[ch]
        );
    }
    assert!(
        c.relative_rmse < 0.03,
        "relative RMSE {:.3e}",
        c.relative_rmse
    );
}
