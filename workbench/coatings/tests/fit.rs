//! Synthetic recovery: a lens's flare rendered by the ghost renderer with hidden coatings,
//! noise and a clipped light, fitted back.

use flarebench_coatings::basis::{Basis, FIT_NODE_DEG};
use flarebench_coatings::catalogue::Design;
use flarebench_coatings::fit::{FitOptions, Target, fit, model_image};
use flarebench_coatings::model::{CoatingModel, Family};
use flarebench_coatings::reweight::{Colouring, Reweighter};
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::load_lens;
use ghost_raytrace::ghosts::{RenderOptions, render, render_each_ghost};
use ghost_raytrace::plan::{PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};

/// A small deterministic generator (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-300), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// Hidden coatings: each parameter uniform over the middle half of its range.
fn hidden_params(model: &CoatingModel, rng: &mut Rng) -> Vec<f64> {
    model
        .bounds()
        .iter()
        .map(|b| match b {
            flarebench_coatings::solve::Bound::Range(lo, hi) => {
                lo + (hi - lo) * (0.25 + 0.5 * rng.next())
            }
            flarebench_coatings::solve::Bound::Positive => 1.0,
        })
        .collect()
}

/// The renderer's image of `system`'s ghosts under `light`, every ghost with light kept.
fn truth(system: &LensSystem, frame: Frame, light: &LightSpec) -> HdrImage {
    let mut opts = PlanOptions::for_quality(Quality::Default, None);
    opts.cull = false;
    let plans = plan(system, std::slice::from_ref(light), &frame, &opts).unwrap();
    render(system, &Aperture::Circular, frame, &plans)
        .unwrap()
        .0
}

/// Each ghost's energy in the renderer's image of `system` (as [`truth`] plans it): the ghost
/// rendered alone, summed over the frame and the channels.
fn truth_energies(system: &LensSystem, frame: Frame, light: &LightSpec) -> Vec<(String, f64)> {
    let mut opts = PlanOptions::for_quality(Quality::Default, None);
    opts.cull = false;
    let plans = plan(system, std::slice::from_ref(light), &frame, &opts).unwrap();
    render_each_ghost(
        system,
        &Aperture::Circular,
        frame,
        &plans,
        RenderOptions::default(),
        |_, job, img| {
            let e = img
                .pixels
                .iter()
                .map(|p| p.iter().map(|&c| f64::from(c)).sum::<f64>())
                .sum::<f64>();
            (job.path.to_string(), e)
        },
    )
    .unwrap()
    .0
}

/// What a recovery case expects of the fit.
#[derive(PartialEq)]
enum Expect {
    /// The ghosts the fit reports as constrained carry at least 90% of the light.
    Identified,
    /// The image may not identify the coatings: only the fitted image and the ghosts the fit
    /// reports as constrained are checked.
    MaybeUnidentified,
}

/// Renders `stem` with hidden random coatings of `family` (the stream `seed`) under `light`,
/// adds noise and a clipped light, fits it back with `options`, and checks the fitted image
/// within 1% relative RMSE of the truth over the counted pixels and every ghost the fit
/// reports as constrained within 2% of its energy in the truth.
/// The fit's basis ([`FIT_NODE_DEG`]) of `system` under `light`, and its band images' colours
/// under the coatings it was rendered with.
fn fit_basis(system: &LensSystem, frame: Frame, light: &LightSpec) -> (Basis, Vec<[f64; 3]>) {
    let basis = Basis::render_with_nodes(
        system,
        &Aperture::Circular,
        frame,
        light,
        Quality::Default,
        &FIT_NODE_DEG,
    )
    .unwrap();
    let colours = Reweighter::new(&basis, system, Colouring::Renderer)
        .unwrap()
        .colours(system);
    (basis, colours)
}

fn recover(
    stem: &str,
    family: Family,
    seed: u64,
    light: &str,
    options: &FitOptions,
    expect: Expect,
) {
    let lens = load_lens(stem);
    let mut rng = Rng(seed);
    let model = CoatingModel::new(&lens, |_| family).unwrap();
    let hidden = hidden_params(&model, &mut rng);
    let hidden_lens = model.apply(&hidden);
    let frame = Frame::across_film(160, 107, lens.film_width_mm);
    let light = LightSpec::parse(light).unwrap();
    let clean = truth(&hidden_lens, frame, &light);
    // The light's own image: a disc of radius 3 px far brighter than the ghosts, clipped at
    // four times the ghosts' peak (as a sensor clips it) and masked; noise of 1% of the
    // ghosts' RMS level on every pixel.
    let peak = clean.max();
    let rms = (clean
        .pixels
        .iter()
        .map(|p| p.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (3 * clean.pixels.len()) as f64)
        .sqrt();
    let efl = flarebench_sdk::paraxial::analyse(&lens, 550.0)
        .unwrap()
        .efl_mm;
    let (theta, phi) = (light.theta_deg.to_radians(), light.phi_deg.to_radians());
    let r = efl * theta.tan();
    let [lx, ly] = frame.to_pixel(-r * phi.cos(), -r * phi.sin());
    let clip = 4.0 * peak;
    let mut image = clean.clone();
    let mut mask = vec![true; image.pixels.len()];
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let (x, y) = (
            (i % frame.width) as f32 + 0.5,
            (i / frame.width) as f32 + 0.5,
        );
        // Noise first, then the sensor's clipping: a clipped pixel reads the clip level.
        for c in p.iter_mut() {
            *c += (0.01 * rms * rng.normal()) as f32;
        }
        if (x - lx).hypot(y - ly) <= 3.0 {
            *p = [clip; 3];
        }
        for c in p.iter_mut() {
            *c = c.min(clip);
        }
        // A pixel at the clip level says only that it is at least that.
        mask[i] = p.iter().all(|&c| c < clip);
    }
    let target = Target { image, mask };
    if std::env::var("FLAREBENCH_FIT_FROM_TRUTH").is_ok() {
        // A diagnosis: the fit started at the hidden coatings, where its basis is exact.
        let mut init = hidden.clone();
        init.extend([1.0; 3]);
        let from_truth = fit(
            &model,
            &Aperture::Circular,
            &light,
            &target,
            &FitOptions {
                initial: Some(init),
                ..FitOptions::default()
            },
        )
        .unwrap();
        let f = truth(&from_truth.system, frame, &light);
        let (b, colours) = fit_basis(&from_truth.system, frame, &light);
        let m = model_image(&b, &colours, from_truth.gains);
        let g1 = model_image(&b, &colours, [1.0; 3]);
        eprintln!(
            "{stem}: hidden {hidden:?}\n model vs clean {:.4}, model vs render {:.4}, fresh model vs render {:.4}, fresh model gains 1 vs render {:.4}, fresh vs fit model {:.4}",
            from_truth.image.relative_rmse(&clean).unwrap(),
            from_truth.image.relative_rmse(&f).unwrap(),
            m.relative_rmse(&f).unwrap(),
            g1.relative_rmse(&f).unwrap(),
            m.relative_rmse(&from_truth.image).unwrap(),
        );
        eprintln!(
            "{stem}: from the truth: residual² {:.6e}, rmse {:.4}, render vs truth {:.4}, params {:?}",
            from_truth.residual_sq,
            from_truth.relative_rmse,
            f.relative_rmse(&clean).unwrap(),
            from_truth.raw
        );
    }
    let t = std::time::Instant::now();
    let found = fit(&model, &Aperture::Circular, &light, &target, options).unwrap();
    eprintln!(
        "{stem}: {} params, {} band images, {} renders, {} corrections, fit {:.0} ms, basis {:.0} ms, {:.0} evaluations/s, rmse {:.4}, wall {:?}",
        found.params.len(),
        found.band_images,
        found.renders,
        found.corrections,
        found.fit_ms,
        found.basis_ms,
        found.evaluations_per_s,
        found.relative_rmse,
        t.elapsed()
    );
    // The fitted image: the fitted lens rendered again under the fitted light (its gains, the
    // light's intensity and colour as the fit found them).
    let mut fitted = truth(&found.system, frame, &light);
    for p in fitted.pixels.iter_mut() {
        for (c, g) in p.iter_mut().zip(found.gains) {
            *c *= g as f32;
        }
    }
    let counted = |img: &HdrImage| -> HdrImage {
        let mut out = img.clone();
        for (p, &m) in out.pixels.iter_mut().zip(&target.mask) {
            if !m {
                *p = [0.0; 3];
            }
        }
        out
    };
    let rmse = counted(&fitted).relative_rmse(&counted(&clean)).unwrap();
    eprintln!(
        "{stem}: fitted image against the truth, over the counted pixels: {rmse:.4}; residual² {:.6e}\n hidden {hidden:?}\n found {:?}",
        found.residual_sq, found.raw
    );
    assert!(rmse < 0.01, "{stem}: {rmse}");
    // Every ghost the fit reports as constrained within 2% of its energy in the truth (the
    // renderer's image of it alone, summed over the frame and the channels), and those ghosts
    // carry nearly all the light.
    let hidden_energy = truth_energies(&hidden_lens, frame, &light);
    let total: f64 = hidden_energy.iter().map(|(_, e)| e).sum();
    let mut constrained = 0.0;
    let mut worst: f64 = 0.0;
    for g in &found.ghosts {
        let t = hidden_energy
            .iter()
            .find(|(p, _)| *p == g.path)
            .expect("the same ghosts")
            .1;
        let e: f64 = g.energy.iter().sum();
        eprintln!(
            "{stem} {}: energy {:+.4} of the truth's {t:.4e}, relative σ {:.4}{}",
            g.path,
            e / t - 1.0,
            g.relative_sigma,
            if g.constrained { ", constrained" } else { "" }
        );
        if g.constrained {
            worst = worst.max((e / t - 1.0).abs());
            assert!((e - t).abs() <= 0.02 * t, "{stem} {}: {e} vs {t}", g.path);
            constrained += t;
        }
    }
    eprintln!(
        "{stem}: {} of {} ghosts constrained, carrying {:.4} of the light; worst energy error {worst:.4}; wall {:?}",
        found.ghosts.iter().filter(|g| g.constrained).count(),
        found.ghosts.len(),
        constrained / total,
        t.elapsed()
    );
    if expect == Expect::Identified {
        assert!(
            constrained >= 0.9 * total,
            "{stem}: {constrained} of {total}"
        );
    }
}

#[test]
#[ignore = "slow tier: a fit from 12 scanned starts over three passes with corrections, 11 s; by default the fit of the Heliar's own coatings through `flarebench fit` (workbench/tests/fit.rs)"]
fn heliar_single_layers_are_recovered() {
    recover(
        "heliar-tronnier",
        Family::Single,
        1,
        "12,30,40",
        &FitOptions::default(),
        Expect::Identified,
    );
}

#[test]
#[ignore = "slow tier: a fit from 8 scanned starts, its two best refined and corrected, on 714 band images, 27 s; by default the fit's basis on the Cooke triplet against the renderer"]
fn cooke_triplet_single_layers_are_recovered() {
    recover_cooke_triplet(Family::Single, 2);
}

/// The Cooke triplet's recovery cases: from 4 spread starts, the two best refined.
fn recover_cooke_triplet(family: Family, seed: u64) {
    recover(
        "cooke-triplet-25mm",
        family,
        seed,
        "12,30,40",
        &FitOptions {
            spread_starts: 4,
            candidates: 2,
            ..FitOptions::default()
        },
        Expect::Identified,
    );
}

/// Two-layer V-coats (MgF₂ over ZrO₂, both thicknesses free) on every air–glass surface of
/// the Cooke triplet: multilayer coatings recovered.
#[test]
#[ignore = "slow tier: 1,064 band images, 8 scanned starts with the two best refined and corrected, 54 s; by default the fit's basis on the Cooke triplet against the renderer"]
fn cooke_triplet_v_coats_are_recovered() {
    recover_cooke_triplet(Family::Layers(Design::VCoat), 4);
}

/// Single layers on the double Gauss (8 coated surfaces, 742 band images) from the first
/// pass's basis alone, the corrections doing what the refined passes would.
#[test]
#[ignore = "slow tier: 742 band images, 8 scanned starts, three solutions corrected on one basis, 32 s; by default the fit's basis on the Cooke triplet against the renderer"]
fn double_gauss_single_layers_are_recovered_from_one_basis() {
    recover(
        "double-gauss-50mm",
        Family::Single,
        3,
        "12,30,40",
        &FitOptions {
            passes: 1,
            spread_starts: 4,
            ..FitOptions::default()
        },
        Expect::Identified,
    );
}

/// The 250 mm telephoto's model glasses do not disperse: its ghosts' colours are the coatings'
/// alone, and one light's image does not tell its coatings from the light's colour. The fit
/// reports that (the check: no ghost it calls constrained is off by more than 2%).
#[test]
#[ignore = "slow tier: a fit from 12 scanned starts over three passes, 6 s; by default the fit's basis on the Cooke triplet against the renderer"]
fn telephoto_coatings_the_image_cannot_identify_are_reported() {
    recover(
        "telephoto-250mm",
        Family::Single,
        6,
        "3,30,40",
        &FitOptions::default(),
        Expect::MaybeUnidentified,
    );
}

/// The basis re-weighted (the choice's nodes) follows the renderer: for the coatings it was
/// rendered with within 1% on the Heliar and 2% on the double Gauss (the reflectances'
/// interpolation between the nodes; docs/coatings.md has the figures), and for other coatings
/// within what the angle split leaves out besides (the transmittances' variation with the
/// angle): on the Heliar and the double Gauss, from their own coatings and from MgF₂
/// everywhere to random single layers, at 12° (and 3° on the Heliar).
#[test]
fn the_basis_reweighted_follows_the_renderer() {
    reweighted_follows_the_renderer("heliar-tronnier", 0.01, 0.01);
}

/// [`the_basis_reweighted_follows_the_renderer`] on the double Gauss.
#[test]
#[ignore = "slow tier: 49 renders a band image on a 9-surface lens, 15 s; by default the Heliar"]
fn the_basis_reweighted_follows_the_renderer_on_the_double_gauss() {
    reweighted_follows_the_renderer("double-gauss-50mm", 0.02, 0.05);
}

fn reweighted_follows_the_renderer(stem: &str, own_limit: f64, limit: f64) {
    {
        let lens = load_lens(stem);
        let model = CoatingModel::new(&lens, |_| Family::Single).unwrap();
        let mut rng = Rng(2);
        let hidden = hidden_params(&model, &mut rng);
        let b_lens = model.apply(&hidden);
        let frame = Frame::across_film(120, 80, lens.film_width_mm);
        let lights: &[&str] = if stem == "heliar-tronnier" {
            &["12,30,40", "3,30,40"]
        } else {
            &["12,30,40"]
        };
        for light in lights {
            let light = LightSpec::parse(light).unwrap();
            let t = truth(&b_lens, frame, &light);
            for a_lens in [lens.clone(), model.apply(&model.start(1.38, 550.0))] {
                let basis = Basis::render(
                    &a_lens,
                    &Aperture::Circular,
                    frame,
                    &light,
                    Quality::Default,
                )
                .unwrap();
                let rw = Reweighter::new(&basis, &a_lens, Colouring::Cells).unwrap();
                let own = model_image(&basis, &rw.colours(&a_lens), [1.0; 3]);
                let own_err = own.relative_rmse(&truth(&a_lens, frame, &light)).unwrap();
                assert!(own_err < own_limit, "{stem}: own coatings {own_err}");
                let img = model_image(&basis, &rw.colours(&b_lens), [1.0; 3]);
                let err = img.relative_rmse(&t).unwrap();
                assert!(err < limit, "{stem} at {}°: {err}", light.theta_deg);
            }
        }
    }
}

/// The fit's basis ([`FIT_NODE_DEG`]) at the coatings it was rendered with follows the
/// renderer to 0.30% on the Cooke triplet with strongly reflecting hidden single layers (the
/// choice's coarser nodes, [`flarebench_coatings::basis::NODE_DEG`], to 0.66%): what lets the
/// fit's refined passes, each at a basis of its solution's coatings, find the hidden coatings.
#[test]
fn the_fit_basis_follows_the_renderer_on_the_cooke_triplet() {
    let err = fit_basis_error("cooke-triplet-25mm", Family::Single, 2);
    assert!(err < 0.0035, "{err}");
}

/// The relative RMSE of the fit's basis of `stem` with hidden coatings of `family` (the
/// stream `seed`), at those coatings, against the renderer (160 × 107 px, light at 12°).
fn fit_basis_error(stem: &str, family: Family, seed: u64) -> f64 {
    let lens = load_lens(stem);
    let model = CoatingModel::new(&lens, |_| family).unwrap();
    let hidden = model.apply(&hidden_params(&model, &mut Rng(seed)));
    let frame = Frame::across_film(160, 107, lens.film_width_mm);
    let light = LightSpec::parse("12,30,40").unwrap();
    let (basis, colours) = fit_basis(&hidden, frame, &light);
    model_image(&basis, &colours, [1.0; 3])
        .relative_rmse(&truth(&hidden, frame, &light))
        .unwrap()
}

/// The fit's basis colours its band images as the renderer colours a band (the reflectances'
/// angle factor at the band's centre, the spectrum at normal incidence): at the Heliar's
/// hidden V-coats it follows the renderer to 0.52% (taking each reflectance at the nodes every
/// 5 nm instead, 1.39%: a V-coat's angle factor changes fast across a band near its minimum).
#[test]
fn the_fit_basis_colours_v_coats_as_the_renderer() {
    let err = fit_basis_error("heliar-tronnier", Family::Layers(Design::VCoat), 5);
    assert!(err < 0.007, "{err}");
}

/// Two-layer V-coats on the Heliar's six air–glass surfaces, from the default search.
#[test]
#[ignore = "slow tier: 551 band images, 12 scanned starts over three passes with corrections, 21 s; by default the fit's basis on the Heliar's V-coats against the renderer"]
fn heliar_v_coats_are_recovered() {
    recover(
        "heliar-tronnier",
        Family::Layers(Design::VCoat),
        5,
        "12,30,40",
        &FitOptions::default(),
        Expect::Identified,
    );
}

/// V-coats on the Zeiss Tele-Tessar 120 mm (six air–glass surfaces, light at 8°): its image
/// does not identify them, and the fit says so (the fitted image within 1%, no ghost it calls
/// constrained off by more than 2%; it calls none constrained).
#[test]
#[ignore = "slow tier: 571 band images, 12 scanned starts over three passes with corrections, 70 s; by default the fit's basis on the Heliar's V-coats against the renderer"]
fn tele_tessar_v_coats_the_image_cannot_identify_are_reported() {
    recover(
        "zeiss/zeiss-tele-tessar-120mm-f6.3",
        Family::Layers(Design::VCoat),
        7,
        "8,30,40",
        &FitOptions::default(),
        Expect::MaybeUnidentified,
    );
}
