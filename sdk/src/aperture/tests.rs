//! Tests of the aperture model: closed-form areas, the exactness of the signed distance,
//! symmetry, soft edges, and masks (layout, area, distance field, errors).

use std::f64::consts::PI;

use super::*;

/// f64 closed forms against each other: a few ulps of π.
const AREA_EXACT: f64 = 1e-12;

/// Polar integration `½∮r(θ)²dθ` with 20 000 angles and bisection to 1e-12: the rule is
/// exact for the circle and errs by far less than this on polygons (worst measured 3e-8).
const POLAR_AREA_TOL: f64 = 1e-6;

/// f32 results of f64 computations near |p| ≈ 1.
const F32_TOL: f32 = 1e-6;

fn iris(blades: u32, rotation_rad: f64, roundness: f64) -> Aperture {
    Aperture::Iris {
        blades,
        rotation_rad,
        roundness,
    }
}

/// A deterministic stream of points in [-1.3, 1.3]² (a linear congruential generator).
fn points(count: usize) -> Vec<(f32, f32)> {
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.6 - 1.3
    };
    (0..count).map(|_| (next() as f32, next() as f32)).collect()
}

/// Area enclosed by the zero set of the signed distance, found along rays from the centre.
fn polar_area(a: &Aperture) -> f64 {
    let s = a.sampler();
    let n = 20_000;
    let mut sum = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) * 2.0 * PI / n as f64;
        let (sin, cos) = t.sin_cos();
        let (mut lo, mut hi) = (0.0f64, 1.5f64);
        while hi - lo > 1e-12 {
            let mid = 0.5 * (lo + hi);
            let g = IrisProbe(s).sd(mid * cos, mid * sin);
            if g <= 0.0 { lo = mid } else { hi = mid }
        }
        sum += 0.5 * lo * lo;
    }
    sum * 2.0 * PI / n as f64
}

/// The iris geometry in f64 (the public API rounds to f32).
struct IrisProbe<'a>(ApertureSampler<'a>);

impl IrisProbe<'_> {
    fn sd(&self, u: f64, v: f64) -> f64 {
        match self.0.shape {
            Shape::Iris(g) => g.signed_distance(u, v),
            Shape::Circle => u.hypot(v) - 1.0,
            Shape::Mask(_) => unreachable!("probe is for analytic shapes"),
        }
    }
}

#[test]
fn straight_iris_area_is_n_over_two_sin_two_pi_over_n() {
    for n in 3..=16u32 {
        let expected = f64::from(n) / 2.0 * (2.0 * PI / f64::from(n)).sin();
        let a = iris(n, 0.3, 0.0);
        assert!((a.open_area() - expected).abs() < AREA_EXACT, "n = {n}");
        assert!(
            (polar_area(&a) - expected).abs() < POLAR_AREA_TOL,
            "n = {n}"
        );
    }
}

#[test]
fn rounded_iris_area_matches_the_area_inside_its_edge() {
    for n in [3u32, 5, 6, 9] {
        for roundness in [1e-9, 1e-4, 0.02, 0.3, 0.7, 0.999] {
            let a = iris(n, -0.4, roundness);
            let (closed, polar) = (a.open_area(), polar_area(&a));
            assert!(
                (closed - polar).abs() < POLAR_AREA_TOL,
                "n = {n}, roundness = {roundness}: {closed} vs {polar}"
            );
        }
    }
    // Area grows with roundness from the polygon to the circle.
    let areas: Vec<f64> = (0..=10)
        .map(|i| iris(6, 0.0, f64::from(i) / 10.0).open_area())
        .collect();
    assert!(areas.windows(2).all(|w| w[0] < w[1]), "{areas:?}");
}

#[test]
fn roundness_one_is_the_unit_circle() {
    for n in [3u32, 6, 11] {
        let a = iris(n, 1.1, 1.0);
        assert!((a.open_area() - PI).abs() < AREA_EXACT, "n = {n}");
        for (u, v) in points(2000) {
            let circle = Aperture::Circular.signed_distance(u, v);
            assert!((a.signed_distance(u, v) - circle).abs() < F32_TOL);
        }
    }
    assert!((Aperture::Circular.open_area() - PI).abs() < AREA_EXACT);
}

#[test]
fn blade_tips_lie_on_the_unit_circle_and_edges_at_their_distance() {
    for roundness in [0.0, 0.5, 1.0] {
        let (n, rot) = (7u32, 0.25);
        let a = iris(n, rot, roundness);
        for k in 0..n {
            let t = rot + 2.0 * PI * f64::from(k) / f64::from(n);
            let d = a.signed_distance(t.cos() as f32, t.sin() as f32);
            assert!(d.abs() < F32_TOL, "tip {k}: {d}");
        }
        // The centre is as far from the edge as the middle of an edge: cos(π/n) + sagitta.
        let half = PI / f64::from(n);
        let sagitta = 1.0 / roundness.max(1e-300)
            - (1.0 / roundness.max(1e-300).powi(2) - half.sin().powi(2)).sqrt();
        let sagitta = if roundness == 0.0 { 0.0 } else { sagitta };
        let expected = -(half.cos() + sagitta);
        assert!((f64::from(a.signed_distance(0.0, 0.0)) - expected).abs() < 1e-6);
    }
}

#[test]
fn signed_distance_is_the_distance_to_the_edge() {
    // Against brute force: the edge sampled densely by bisection along rays.
    for (n, rot, roundness) in [(5u32, 0.0, 0.0), (6, 0.4, 0.35), (8, -1.0, 0.8)] {
        let a = iris(n, rot, roundness);
        let probe = IrisProbe(a.sampler());
        let edge: Vec<(f64, f64)> = (0..20_000)
            .map(|i| {
                let t = i as f64 * 2.0 * PI / 20_000.0;
                let (mut lo, mut hi) = (0.0f64, 1.5f64);
                while hi - lo > 1e-12 {
                    let mid = 0.5 * (lo + hi);
                    if probe.sd(mid * t.cos(), mid * t.sin()) <= 0.0 {
                        lo = mid
                    } else {
                        hi = mid
                    }
                }
                (lo * t.cos(), lo * t.sin())
            })
            .collect();
        for (u, v) in points(300) {
            let (u, v) = (f64::from(u), f64::from(v));
            let brute = edge
                .iter()
                .map(|&(x, y)| (x - u).hypot(y - v))
                .fold(f64::INFINITY, f64::min);
            let sd = probe.sd(u, v);
            // Edge samples are at most 2π/20000 ≈ 3.1e-4 apart: brute force overestimates
            // by at most half that squared over the distance, or 1.6e-4.
            assert!(
                (sd.abs() - brute).abs() < 2e-4,
                "n = {n} at ({u}, {v}): {sd} vs {brute}"
            );
            let inside = a.transmission(u as f32, v as f32) == 1.0;
            assert_eq!(inside, sd <= 0.0);
        }
    }
}

#[test]
fn rotation_rotates_the_shape_and_blades_repeat_every_two_pi_over_n() {
    let (n, rot, roundness) = (6u32, 0.37, 0.4);
    let turned = iris(n, rot, roundness);
    let upright = iris(n, 0.0, roundness);
    for (u, v) in points(1000) {
        let (u, v) = (f64::from(u), f64::from(v));
        let rotate = |t: f64| {
            let (s, c) = t.sin_cos();
            ((c * u - s * v) as f32, (s * u + c * v) as f32)
        };
        let (ru, rv) = rotate(rot);
        assert!(
            (turned.signed_distance(ru, rv) - upright.signed_distance(u as f32, v as f32)).abs()
                < F32_TOL
        );
        let (su, sv) = rotate(2.0 * PI / f64::from(n));
        assert!(
            (upright.signed_distance(su, sv) - upright.signed_distance(u as f32, v as f32)).abs()
                < F32_TOL
        );
        // Mirror symmetry about the ray through a blade tip (the +u axis here).
        assert!(
            (upright.signed_distance(u as f32, -v as f32)
                - upright.signed_distance(u as f32, v as f32))
            .abs()
                < F32_TOL
        );
    }
    // A pentagon is not symmetric under a rotation by half its sector.
    let p = iris(5, 0.0, 0.0);
    let t = PI / 5.0;
    assert!(p.signed_distance(1.0, 0.0).abs() < F32_TOL);
    assert!(p.signed_distance(t.cos() as f32, t.sin() as f32) > 0.01);
}

#[test]
fn soft_edge_is_half_on_the_edge_and_keeps_the_area() {
    let hexagon = iris(6, 0.0, 0.0);
    let apothem = (PI / 6.0).cos() as f32;
    let feather = 0.1;
    let at = |u: f32| hexagon.transmission_soft(u, 0.0, feather);
    // Along +u the hexagon's tip; along +v the middle of an edge.
    assert!((hexagon.transmission_soft(0.0, apothem, feather) - 0.5).abs() < F32_TOL);
    assert_eq!(hexagon.transmission_soft(0.0, apothem - 0.06, feather), 1.0);
    assert_eq!(hexagon.transmission_soft(0.0, apothem + 0.06, feather), 0.0);
    assert!((at(1.0) - 0.5).abs() < F32_TOL);
    assert_eq!(
        hexagon.transmission_soft(0.0, 0.99, 0.0),
        hexagon.transmission(0.0, 0.99)
    );
    assert_eq!(hexagon.transmission_soft(0.0, 0.0, f32::NAN), 1.0);
    // Monotone across the edge.
    let ramp: Vec<f32> = (0..=40).map(|i| at(0.9 + i as f32 * 0.005)).collect();
    assert!(ramp.windows(2).all(|w| w[0] >= w[1]), "{ramp:?}");
    // The integral of the soft transmission: straight edges lose outside what they gain
    // inside; corners and curvature add (2π + 2Σ tan(θᵢ/2))·feather²/80 (module docs).
    let predicted = hexagon.open_area()
        + (2.0 * PI + 12.0 * (PI / 6.0).tan()) * f64::from(feather).powi(2) / 80.0;
    assert!((soft_area(&hexagon, feather) - predicted).abs() < SOFT_AREA_TOL);
    let circle = Aperture::Circular;
    let predicted = PI + PI * f64::from(feather).powi(2) / 20.0;
    assert!((soft_area(&circle, feather) - predicted).abs() < SOFT_AREA_TOL);
}

/// Midpoint integration of the soft transmission on a 1200² grid over [-1.2, 1.2]²: the
/// ramp spans 50 cells; measured error against the prediction 2e-7 (hexagon), 1e-8 (circle).
const SOFT_AREA_TOL: f64 = 2e-6;

fn soft_area(a: &Aperture, feather: f32) -> f64 {
    let (steps, h) = (1200, 2.4 / 1200.0);
    let mut sum = 0.0;
    for j in 0..steps {
        for i in 0..steps {
            let (u, v) = (-1.2 + (i as f64 + 0.5) * h, -1.2 + (j as f64 + 0.5) * h);
            sum += f64::from(a.transmission_soft(u as f32, v as f32, feather));
        }
    }
    sum * h * h
}

#[test]
fn validation_names_bad_iris_parameters_and_sampling_never_panics() {
    assert_eq!(
        iris(2, 0.0, 0.0).validate(),
        Err(ApertureError::TooFewBlades(2))
    );
    assert_eq!(
        iris(6, 0.0, 1.5).validate(),
        Err(ApertureError::Roundness(1.5))
    );
    assert!(matches!(
        iris(6, 0.0, f64::NAN).validate(),
        Err(ApertureError::Roundness(_))
    ));
    assert!(matches!(
        iris(6, f64::INFINITY, 0.0).validate(),
        Err(ApertureError::Rotation(_))
    ));
    assert_eq!(iris(6, 0.0, 0.5).validate(), Ok(()));
    assert_eq!(Aperture::Circular.validate(), Ok(()));
    for bad in [
        iris(0, f64::NAN, f64::NAN),
        iris(1, 0.0, -3.0),
        iris(u32::MAX, 0.0, 9.0),
    ] {
        for (u, v) in [
            (0.0, 0.0),
            (0.5, 0.2),
            (f32::NAN, 0.0),
            (f32::INFINITY, 1.0),
        ] {
            let t = bad.transmission_soft(u, v, 0.1);
            assert!((0.0..=1.0).contains(&t), "{bad:?} at ({u}, {v}): {t}");
        }
        assert!(bad.open_area().is_finite());
    }
}

// ---- masks ----

/// A `size`² mask of the unit circle, each texel open when its centre is inside.
/// A binary mask of `size × size` texels, open at the texel centres `(u, v)` where `open`
/// says so (the module's layout: row 0 at v = +1, column 0 at u = −1).
pub(crate) fn mask_of(size: usize, open: impl Fn(f64, f64) -> bool) -> ApertureMask {
    let luma: Vec<u8> = (0..size * size)
        .map(|i| {
            let (row, col) = (i / size, i % size);
            let u = -1.0 + (col as f64 + 0.5) * 2.0 / size as f64;
            let v = 1.0 - (row as f64 + 0.5) * 2.0 / size as f64;
            if open(u, v) { 255 } else { 0 }
        })
        .collect();
    ApertureMask::from_luma(size, size, &luma).unwrap()
}

fn hard_circle(size: usize) -> ApertureMask {
    mask_of(size, |u, v| u * u + v * v <= 1.0)
}

#[test]
fn a_rasterised_circle_has_area_pi() {
    // Antialiased: each texel samples the one-texel ramp at its centre, so the sum is a
    // midpoint rule on the edge; measured error 8.6e-5.
    let soft = Aperture::Circular.rasterize(512, 512).unwrap();
    assert!((soft.open_area() - PI).abs() < 3e-4, "{}", soft.open_area());
    // Hard texels: the error is the texel-counting noise along the edge, measured 7e-5.
    let hard = Aperture::Mask(hard_circle(512));
    assert!((hard.open_area() - PI).abs() < 3e-4, "{}", hard.open_area());
    // The iris rasterises to its own area too (measured 3.5e-5 at 400 × 300).
    let hexagon = iris(6, 0.2, 0.3);
    let raster = hexagon.rasterize(400, 300).unwrap();
    assert!((raster.open_area() - hexagon.open_area()).abs() < 3e-4);
}

#[test]
fn mask_distance_field_is_good_to_a_texel() {
    // Worst error measured over 20 000 points: 0.53 texel.
    let size = 256;
    let mask = Aperture::Mask(hard_circle(size));
    let texel = 2.0 / size as f32;
    for (u, v) in points(3000) {
        let exact = Aperture::Circular.signed_distance(u, v);
        let d = mask.signed_distance(u, v);
        if u.abs() <= 1.0 && v.abs() <= 1.0 {
            assert!((d - exact).abs() < texel, "({u}, {v}): {d} vs {exact}");
        } else {
            // Beyond the square: the distance to the outermost texel centres plus the field
            // there, an upper bound up to the field's own error.
            assert!(d > exact - texel, "({u}, {v}): {d} vs {exact}");
        }
    }
    // Soft edges from the field: a quarter-feather inside the edge is mostly open.
    let t = mask.transmission_soft(0.0, 1.0 - 0.05, 0.2);
    let exact = Aperture::Circular.transmission_soft(0.0, 1.0 - 0.05, 0.2);
    assert!((t - exact).abs() < 0.05, "{t} vs {exact}");
    // A feather of a texel or less is the bilinear transmission.
    assert_eq!(
        mask.transmission_soft(0.3, 0.2, texel),
        mask.transmission(0.3, 0.2)
    );
}

#[test]
fn mask_rows_run_from_v_plus_one_down_and_columns_from_u_minus_one() {
    // 2 × 2: top-left open only.
    let m = ApertureMask::from_luma(2, 2, &[255, 0, 0, 0]).unwrap();
    assert_eq!(m.transmission(-0.5, 0.5), 1.0);
    assert_eq!(m.transmission(0.5, 0.5), 0.0);
    assert_eq!(m.transmission(-0.5, -0.5), 0.0);
    // Clamp to edge inside the square, 0 outside it.
    assert_eq!(m.transmission(-0.99, 0.99), 1.0);
    assert_eq!(m.transmission(-1.01, 0.5), 0.0);
    assert_eq!(m.transmission(f32::NAN, 0.5), 0.0);
    // Bilinear halfway between texel centres.
    assert!((m.transmission(0.0, 0.5) - 0.5).abs() < F32_TOL);
    assert_eq!(m.texel_size(), (1.0, 1.0));
}

#[test]
fn mask_area_is_the_integral_of_its_bilinear_transmission() {
    let (w, h) = (7, 5);
    let values: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32 / 10.0).collect();
    let m = ApertureMask::from_luma_f32(w, h, &values).unwrap();
    let sum: f64 = values.iter().map(|&t| f64::from(t)).sum();
    assert!((m.open_area() - sum * 4.0 / 35.0).abs() < AREA_EXACT);
    // Midpoint rule on a grid fine enough that the bilinear pieces are resolved.
    let n = 2800;
    let step = 2.0 / n as f64;
    let mut integral = 0.0;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (
                -1.0 + (i as f64 + 0.5) * step,
                -1.0 + (j as f64 + 0.5) * step,
            );
            integral += f64::from(m.transmission(u as f32, v as f32));
        }
    }
    integral *= step * step;
    // Measured 2e-7: midpoint error on the bilinear kinks at texel centres.
    assert!(
        (integral - m.open_area()).abs() < 1e-5,
        "{integral} vs {}",
        m.open_area()
    );
}

#[test]
fn olf_distance_maps_open_below_the_clip() {
    let d = [0.1, 0.94, 0.96, 1.0];
    let m = ApertureMask::from_olf_distance_map(2, 2, &d, OLF_DISTANCE_CLIP).unwrap();
    assert_eq!(m.data(), &[1.0, 1.0, 0.0, 0.0]);
    assert_eq!(
        ApertureMask::from_olf_distance_map(2, 2, &d, 1.5),
        Err(ApertureError::DistanceClip(1.5))
    );
}

#[test]
fn bad_masks_are_errors_naming_the_problem() {
    assert_eq!(
        ApertureMask::from_luma(3, 2, &[0; 5]),
        Err(ApertureError::MaskLength {
            width: 3,
            height: 2,
            expected: 6,
            got: 5
        })
    );
    assert_eq!(
        ApertureMask::from_luma(0, 2, &[]),
        Err(ApertureError::EmptyMask {
            width: 0,
            height: 2
        })
    );
    assert!(matches!(
        ApertureMask::from_luma(usize::MAX, 2, &[]),
        Err(ApertureError::MaskTooLarge { .. })
    ));
    let e = ApertureMask::from_luma_f32(2, 2, &[0.0, 1.0, 0.5, f32::NAN]).unwrap_err();
    assert!(
        matches!(
            e,
            ApertureError::MaskValue {
                row: 1,
                column: 1,
                ..
            }
        ),
        "{e:?}"
    );
    let e = ApertureMask::from_luma_f32(2, 2, &[0.0, 1.5, 0.5, 0.0]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "mask texel at row 0, column 1 is 1.5; transmissions lie in 0..=1"
    );
}

#[test]
fn closed_and_fully_open_masks_sample_without_trouble() {
    let closed = Aperture::Mask(ApertureMask::from_luma(4, 4, &[0; 16]).unwrap());
    assert_eq!(closed.open_area(), 0.0);
    assert_eq!(closed.transmission_soft(0.0, 0.0, 0.5), 0.0);
    assert!(closed.signed_distance(0.0, 0.0) > 2.0);
    let open = Aperture::Mask(ApertureMask::from_luma(64, 64, &[255; 64 * 64]).unwrap());
    assert!((open.open_area() - 4.0).abs() < AREA_EXACT);
    // The square's edge closes it (the field is known at texel centres: good to a texel).
    let texel = 2.0 / 64.0;
    assert!((open.signed_distance(0.0, 0.0) + 1.0).abs() < texel);
    assert!((open.signed_distance(1.5, 0.0) - 0.5).abs() < texel);
}

// ---- uniform around a point ----

/// An answer about the disc of some radius around random points, checked on a dense sample of
/// that disc (rings out to its whole radius, the rim included): `answer` gives the soft
/// transmission it says holds all over the disc and the radius, or nothing; returns how
/// often it answered.
fn check_discs(
    aperture: &Aperture,
    feather: f32,
    seed: u64,
    answer: impl Fn(&ApertureSampler<'_>, f32, f32, f32) -> Option<(f32, f32)>,
) -> usize {
    let sampler = aperture.sampler();
    let mut state = seed;
    let mut unit = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut answered = 0;
    for _ in 0..3000 {
        let (u, v) = (2.4 * unit() - 1.2, 2.4 * unit() - 1.2);
        let asked = 0.1 * unit() * unit();
        let Some((t, radius)) = answer(&sampler, u, v, asked) else {
            continue;
        };
        answered += 1;
        for k in 0..200 {
            let r = radius * ((k % 10) as f32 + 1.0) / 10.0;
            let a = k as f32 * 0.7;
            let (x, y) = (u + r * a.cos(), v + r * a.sin());
            let s = sampler.transmission_soft(x, y, feather);
            assert_eq!(
                s, t,
                "{aperture:?} feather {feather}: ({u}, {v}) r {radius} said {t}, ({x}, {y}) has {s}"
            );
        }
    }
    answered
}

/// `uniform_around`'s answer for random radii up to 0.1: where it says open (closed), the soft
/// transmission is 1 (0) all over the disc.
fn check_uniform(aperture: &Aperture, feather: f32, seed: u64) -> usize {
    check_discs(aperture, feather, seed, |s, u, v, radius| {
        s.uniform_around(u, v, radius, feather).map(|t| (t, radius))
    })
}

#[test]
fn uniform_around_is_never_wrong() {
    for feather in [1e-3_f32, 0.01, 0.05] {
        assert!(check_uniform(&Aperture::Circular, feather, 1) > 1000);
        assert!(check_uniform(&iris(6, 0.3, 0.2), feather, 2) > 1000);
        assert!(check_uniform(&iris(5, 0.0, 0.0), feather, 3) > 1000);
        // A binary mask (a hard circle) and a grey one; feathers below and above a texel.
        let hard = Aperture::Mask(hard_circle(64));
        assert!(check_uniform(&hard, feather, 4) > 500, "{feather}");
        let grey = Aperture::Circular.rasterize(64, 64).unwrap();
        let answered = check_uniform(&Aperture::Mask(grey), feather, 5);
        let texel = 2.0 / 64.0;
        // A grey mask sampled bilinearly (feather under a texel) cannot be decided.
        assert!(
            (feather <= texel) == (answered == 0),
            "{feather}: {answered}"
        );
    }
    // No answer without a positive feather.
    let s = Aperture::Circular.sampler();
    assert_eq!(s.uniform_around(0.0, 0.0, 0.1, 0.0), None);
    assert_eq!(s.uniform_around(0.0, 0.0, f32::NAN, 0.01), None);
    assert_eq!(s.uniform_around(0.0, 0.0, 0.1, 0.01), Some(1.0));
    assert_eq!(s.uniform_around(2.0, 0.0, 0.1, 0.01), Some(0.0));
}

/// `transmission_reach`'s answer: the transmission it gives is the soft transmission at the
/// point, and the same all over the disc of its reach (where that is positive).
fn check_reach(aperture: &Aperture, feather: f32, seed: u64) -> usize {
    check_discs(aperture, feather, seed, |s, u, v, _| {
        let (t, reach) = s.transmission_reach(u, v, feather);
        assert_eq!(t, s.transmission_soft(u, v, feather), "({u}, {v})");
        (reach > 0.0).then_some((t, reach))
    })
}

#[test]
fn transmission_reach_is_never_wrong() {
    for feather in [1e-3_f32, 0.01, 0.05] {
        assert!(check_reach(&Aperture::Circular, feather, 1) > 2000);
        assert!(check_reach(&iris(6, 0.3, 0.2), feather, 2) > 2000);
        let hard = Aperture::Mask(hard_circle(64));
        assert!(check_reach(&hard, feather, 4) > 1000, "{feather}");
        let grey = Aperture::Circular.rasterize(64, 64).unwrap();
        let reached = check_reach(&Aperture::Mask(grey), feather, 5);
        let texel = 2.0 / 64.0;
        assert!((feather <= texel) == (reached == 0), "{feather}: {reached}");
    }
}
