//! The precise bounds search (`ghost::bounds`) against the independent Monte-Carlo reference
//! (`ghost::monte_carlo`): the direct flux every energy share is measured against, and the
//! three defects an independent tracer found (issue #25) — the flux normalisation measured
//! over the front element, the Heliar's ghost 8-0 cut at 10°, and the Nikon zoom's small
//! ghosts at 5°, 10° and 20° reported as having no light.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::bounds::{self, GhostBounds};
use flarebench_sdk::ghost::monte_carlo::{
    McBand, McEstimate, McSettings, ghost_monte_carlo, path_flux,
};
use flarebench_sdk::ghost::{GhostPath, GridTrace, PointTrace};
use flarebench_sdk::trace::{InterfaceTableSet, Sequence};
use flarebench_test_support::load_lens;

/// Standard errors a figure may lie from the Monte-Carlo estimate, besides its own error:
/// a 4σ miss has odds of 6e-5 for a normal estimate.
const SIGMAS: f64 = 4.0;

/// How far the bounds' figures may be from the truth beyond the Monte-Carlo error bar: the
/// direct flux (a 129² grid over the pupil, the edge placed between vertices) — measured
/// within 0.05% on both lenses; a ghost's share (a 33² grid over its rectangle) — measured
/// within 0.2% on the Heliar's large ghosts, 1% on the Nikon's small ones. Before the fixes the
/// direct flux was 2.1% low on the Heliar (every share 2% high).
const DIRECT_TOLERANCE: f64 = 1e-3;
const SHARE_TOLERANCE: f64 = 0.02;

fn settings() -> McSettings {
    McSettings {
        rays: 60_000,
        batches: 16,
        seed: 3,
        pilot: 129,
        outside_weight: 1.0,
    }
}

struct Lens {
    sys: LensSystem,
    tables: InterfaceTableSet,
    reference: f64,
    direct_mc: McEstimate,
}

fn lens(stem: &str) -> Lens {
    let sys = load_lens(stem);
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let reference = bounds::reference_flux(&sys, &tables, &mut GridTrace::default());
    let direct_mc = path_flux(&sys, &Sequence::forward(&sys, 550.0), 0.0, &settings());
    Lens {
        sys,
        tables,
        reference,
        direct_mc,
    }
}

impl Lens {
    fn bounds(&self, path: GhostPath, theta: f64) -> Option<GhostBounds> {
        bounds::precise(
            &self.sys,
            path,
            &self.tables,
            theta,
            self.reference,
            &mut GridTrace::default(),
        )
    }

    /// The Monte-Carlo share and its standard error.
    fn share(&self, path: GhostPath, theta: f64) -> (f64, f64) {
        let seq = Sequence::ghost_path(&self.sys, 550.0, &path).expect("a ghost path");
        let g = path_flux(&self.sys, &seq, theta, &settings());
        let share = g.mean / self.direct_mc.mean;
        let rel = (g.relative_error().powi(2) + self.direct_mc.relative_error().powi(2)).sqrt();
        (share, rel * share)
    }

    fn check_share(&self, path: GhostPath, deg: f64) {
        self.check_share_within(path, deg, SHARE_TOLERANCE);
    }

    fn check_share_within(&self, path: GhostPath, deg: f64, tolerance: f64) {
        let theta = deg.to_radians();
        let b = self
            .bounds(path, theta)
            .unwrap_or_else(|| panic!("{path} at {deg}°: reported as having no light"));
        let (mc, err) = self.share(path, theta);
        assert!(
            mc > 0.0,
            "{path} at {deg}°: the Monte-Carlo reference sees no light"
        );
        assert!(
            (b.energy_share - mc).abs() <= SIGMAS * err + tolerance * mc,
            "{path} at {deg}°: bounds {:e}, Monte-Carlo {mc:e} ± {err:e}",
            b.energy_share
        );
    }
}

#[test]
fn the_direct_flux_agrees_with_the_monte_carlo_reference() {
    for stem in ["heliar-tronnier", "nikon-zoom-short"] {
        let l = lens(stem);
        let mc = l.direct_mc;
        assert!(
            (l.reference - mc.mean).abs() <= SIGMAS * mc.std_error + DIRECT_TOLERANCE * mc.mean,
            "{stem}: bounds {}, Monte-Carlo {mc:?}",
            l.reference
        );
    }
}

/// A small stop behind a large front element: the fisheye at f/64 (a 0.16 mm entrance pupil,
/// a front element 60 mm across) and f/256. Its direct flux on the axis is the paraxial
/// pupil's area times the axial ray's transmittance (so small a pupil has no aberration and
/// no vignetting); the bounds search (which once found it 2.4% and 23% low: its grid was laid
/// over the front element and a few vertices fell in the pupil) and the Monte-Carlo reference
/// (which saw no light at f/256) must both find it.
#[test]
fn a_small_pupil_behind_a_large_front_element_carries_its_paraxial_flux() {
    for n in [64.0, 256.0] {
        let mut sys = load_lens("fisheye-10mm");
        sys.f_number = Some(n);
        let para = flarebench_sdk::paraxial::analyse(&sys, 550.0).unwrap();
        let seq = Sequence::forward(&sys, 550.0);
        let axial = seq.trace(&flarebench_sdk::trace::Ray::collimated(0.0, 0.0, 0.0));
        assert!(axial.completed);
        let want = std::f64::consts::PI
            * (0.5 * para.entrance_pupil_diameter_mm).powi(2)
            * axial.throughput;
        let tables = InterfaceTableSet::for_system(&sys, 550.0);
        let got = bounds::reference_flux(&sys, &tables, &mut GridTrace::default());
        assert!(
            (got / want - 1.0).abs() < DIRECT_TOLERANCE,
            "f/{n}: bounds {got:e} against the pupil's {want:e}"
        );
        let mc = path_flux(&sys, &seq, 0.0, &settings());
        assert!(
            (mc.mean - want).abs() <= SIGMAS * mc.std_error + DIRECT_TOLERANCE * want,
            "f/{n}: Monte-Carlo {mc:?} against the pupil's {want:e}"
        );
    }
}

#[test]
fn heliar_ghost_8_0_at_10_degrees_is_bounded_around_every_ray_that_carries_it() {
    let l = lens("heliar-tronnier");
    let path: GhostPath = "8-0".parse().expect("a ghost name");
    let theta = 10f64.to_radians();
    let b = l.bounds(path, theta).expect("8-0 has light at 10°");
    let span = entrance_span(&l, path, theta, 550.0);
    // Its rays span x = ±0.47 mm; the bounds held ±0.32 mm before the fix.
    let e = b.entrance;
    assert!(
        e.x0 <= span.x0 && e.x1 >= span.x1 && e.y0 <= span.y0 && e.y1 >= span.y1,
        "entrance {e:?} does not hold the rays' span {span:?}"
    );
    l.check_share(path, 10.0);
}

#[test]
fn the_nikon_zoom_s_small_ghosts_at_5_degrees_are_found_with_their_light() {
    let l = lens("nikon-zoom-short");
    // Entry regions under 1 mm across, between the 2.07 mm spacing of the search grid.
    for name in ["10-3", "10-6", "13-3", "13-6", "13-8"] {
        l.check_share(name.parse().expect("a ghost name"), 5.0);
    }
}

#[test]
fn the_nikon_zoom_s_ghosts_whose_search_rays_all_stop_are_found_with_their_light() {
    let l = lens("nikon-zoom-short");
    // Every ray of the 33² search grid misses a surface or is totally reflected; the regions,
    // 0.5–0.7 mm across, are found from the paraxial entrance rectangle.
    for name in ["13-1", "13-3", "13-4", "13-5", "13-6", "13-8"] {
        l.check_share(name.parse().expect("a ghost name"), 10.0);
    }
    for name in ["10-6", "13-3", "13-6"] {
        l.check_share(name.parse().expect("a ghost name"), 20.0);
    }
}

#[test]
fn thin_rings_carry_their_monte_carlo_share() {
    let l = lens("nikon-zoom-short");
    // Rings a cell or two wide, whose excess has a kink where two clear apertures meet inside
    // a cell: −3.3% and −3.0% before their edge cells were traced again, now within 0.9%.
    l.check_share_within("14-11".parse().expect("a ghost name"), 0.0, 0.015);
    l.check_share_within("8-3".parse().expect("a ghost name"), 5.0, 0.015);
}

#[test]
fn the_heliar_s_large_ghosts_agree_with_the_monte_carlo_reference() {
    let l = lens("heliar-tronnier");
    for name in ["1-0", "2-1", "4-0", "7-6", "8-7"] {
        l.check_share(name.parse().expect("a ghost name"), 10.0);
    }
}

/// The bounding box of the entrance points of a ghost's rays that carry light at one
/// wavelength, by the Monte-Carlo reference.
fn entrance_span(l: &Lens, path: GhostPath, theta: f64, lambda_nm: f64) -> bounds::Rect {
    let frame = Frame::across_film(64, 36, l.sys.film_width_mm);
    let band = [McBand {
        lambda_nm,
        rgb: [1.0; 3],
    }];
    ghost_monte_carlo(
        &l.sys,
        &Aperture::Circular,
        &frame,
        path,
        (theta, 0.0, 1.0),
        &band,
        &settings(),
        None,
    )
    .expect("a ghost path")
    .entrance_span
    .unwrap_or_else(|| panic!("{path}: no Monte-Carlo ray carries light at {lambda_nm} nm"))
}

fn holds(outer: &bounds::Rect, inner: &bounds::Rect) -> bool {
    outer.x0 <= inner.x0 && outer.x1 >= inner.x1 && outer.y0 <= inner.y0 && outer.y1 >= inner.y1
}

#[test]
fn a_ghost_s_rectangle_widened_for_a_band_end_holds_its_rays_there() {
    let l = lens("nikon-zoom-short");
    // (ghost, angle, band-end wavelength): 8-3's entry region is 3.4 mm wide at 400 nm against
    // 1.0 mm at 550 nm; 15-11 and 3-1 at 20° lost 9.4% and 8.2% of their flux at 390 nm over
    // their 550 nm rectangles.
    for (name, deg, nm) in [
        ("8-3", 10.0, 400.0),
        ("15-11", 20.0, 390.0),
        ("3-1", 20.0, 390.0),
    ] {
        let path: GhostPath = name.parse().expect("a ghost name");
        let theta = f64::to_radians(deg);
        let base = l.bounds(path, theta).expect("light at 550 nm");
        let tables = InterfaceTableSet::for_system(&l.sys, nm);
        let seq = bounds::ghost_sequence(&l.sys, path, &tables).expect("a ghost path");
        let widened = bounds::widened_for(
            &l.sys,
            &seq,
            theta,
            &base,
            &mut GridTrace::default(),
            &mut PointTrace::default(),
        );
        let span = entrance_span(&l, path, theta, nm);
        assert!(
            !holds(&base.entrance, &span),
            "{name} at {deg}°: the 550 nm rectangle {:?} already holds the {nm} nm rays {span:?}",
            base.entrance
        );
        assert!(
            holds(&widened.entrance, &span),
            "{name} at {deg}°: widened {:?} does not hold the {nm} nm rays {span:?}",
            widened.entrance
        );
        assert!(holds(&widened.entrance, &base.entrance) && widened.grid >= base.grid);
        assert_eq!(widened.energy_share, base.energy_share);
    }
    // At the wavelength the bounds were found at, nothing moves.
    let path: GhostPath = "4-2".parse().expect("a ghost name");
    let theta = f64::to_radians(5.0);
    let base = l.bounds(path, theta).expect("light at 550 nm");
    let seq = bounds::ghost_sequence(&l.sys, path, &l.tables).expect("a ghost path");
    let same = bounds::widened_for(
        &l.sys,
        &seq,
        theta,
        &base,
        &mut GridTrace::default(),
        &mut PointTrace::default(),
    );
    assert_eq!(same, base);
}
