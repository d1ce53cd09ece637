//! The catalogue's designs against their closed forms, and an independent thin-film
//! computation (characteristic matrices) for the stacks.

use flarebench_coatings::catalogue::{
    AL2O3, BROADBAND_NM, DESIGN_NM, Design, MGF2, band_reflectance, reflectance_from_air, v_coat,
};
use flarebench_sdk::Coating;

/// Normal reflectance from air of `layers` (air side first) on glass `ns` by the
/// characteristic-matrix method (Macleod ch. 2), written out with real and imaginary parts:
/// an independent check of the SDK's substrate-outward recursion.
fn matrix_reflectance(layers: &[(f64, f64)], ns: f64, lambda: f64) -> f64 {
    // [B; C] = Π Mⱼ [1; ns], each M = [[cos δ, i sin δ / n], [i n sin δ, cos δ]].
    let (mut br, mut bi, mut cr, mut ci) = (1.0, 0.0, ns, 0.0);
    for &(n, d) in layers.iter().rev() {
        let delta = 2.0 * std::f64::consts::PI * n * d / lambda;
        let (c, s) = (delta.cos(), delta.sin());
        // B' = c B + (i s / n) C ; C' = i n s B + c C
        let (nbr, nbi) = (c * br - s / n * ci, c * bi + s / n * cr);
        let (ncr, nci) = (c * cr - n * s * bi, c * ci + n * s * br);
        (br, bi, cr, ci) = (nbr, nbi, ncr, nci);
    }
    // r = (B − C) / (B + C) with n0 = 1.
    let (nr, ni) = (br - cr, bi - ci);
    let (dr, di) = (br + cr, bi + ci);
    (nr * nr + ni * ni) / (dr * dr + di * di)
}

fn pairs(d: Design, ns: f64) -> Vec<(f64, f64)> {
    d.layers(ns)
        .iter()
        .map(|l| (l.index, l.thickness_nm))
        .collect()
}

/// A quarter-wave MgF₂ layer: `R = ((nₛ − n₁²)/(nₛ + n₁²))²` at its design wavelength.
#[test]
fn single_layer_matches_its_closed_form() {
    for ns in [1.46_f64, 1.52, 1.62, 1.8, 1.9] {
        let n1 = MGF2.index;
        let closed = ((ns - n1 * n1) / (ns + n1 * n1)).powi(2);
        for air_first in [true, false] {
            let c = Design::Mgf2.coating(ns, air_first);
            let (from, to) = if air_first { (1.0, ns) } else { (ns, 1.0) };
            let r = c.reflectance(from, to, 1.0, DESIGN_NM, true);
            assert!((r - closed).abs() < 1e-12, "ns {ns}: {r} vs {closed}");
        }
    }
}

/// The V-coat nulls the reflectance at 550 nm, seen from either side (a lossless stack
/// reflects the same both ways), and the matrix method agrees at every wavelength.
#[test]
fn v_coat_nulls_its_design_wavelength() {
    for ns in [1.46_f64, 1.52, 1.62, 1.75, 1.85] {
        let layers = v_coat(ns).expect("a V-coat exists on this glass");
        assert!(
            reflectance_from_air(&layers, ns, DESIGN_NM) < 1e-12,
            "ns {ns}"
        );
        let bare = ((ns - 1.0) / (ns + 1.0)).powi(2);
        assert!(reflectance_from_air(&layers, ns, 450.0) > 1e-4);
        assert!(reflectance_from_air(&layers, ns, 450.0) < bare);
        let from_glass = Design::VCoat.coating(ns, false);
        let r = from_glass.reflectance(ns, 1.0, 1.0, DESIGN_NM, true);
        assert!(r < 1e-12, "from the glass side, ns {ns}: {r}");
        for nm in [400.0, 500.0, 600.0, 700.0] {
            let ours = reflectance_from_air(&layers, ns, nm);
            let theirs = matrix_reflectance(&pairs(Design::VCoat, ns), ns, nm);
            assert!((ours - theirs).abs() < 1e-12, "{nm} nm: {ours} vs {theirs}");
        }
    }
    // Glass above MgF₂'s index squared has no V-coat zero: one layer is used.
    assert!(v_coat(1.95).is_none());
    assert_eq!(Design::VCoat.layers(1.95).len(), 1);
}

/// Quarter–half–quarter: the half-wave layer is absent at its wavelength, so
/// `R = ((n₃² − nₛ n₁²)/(n₃² + nₛ n₁²))²`.
#[test]
fn broadband_matches_its_closed_form() {
    for ns in [1.5_f64, 1.6, 1.7] {
        let (n1, n3) = (MGF2.index, AL2O3.index);
        let closed = ((n3 * n3 - ns * n1 * n1) / (n3 * n3 + ns * n1 * n1)).powi(2);
        let r = reflectance_from_air(&Design::Broadband.layers(ns), ns, BROADBAND_NM);
        assert!((r - closed).abs() < 1e-12, "{r} vs {closed}");
    }
}

/// The multicoat by the matrix method; below the single layer everywhere and the lowest on
/// crown glass, and every coating below bare glass.
#[test]
fn multicoat_beats_one_layer_and_agrees_with_the_matrix_method() {
    for ns in [1.5, 1.62, 1.8] {
        // Each glass's design is a local optimiser's best (catalogue docs): checked to beat
        // one layer, not to be the lowest possible.
        let layers = Design::Multicoat.layers(ns);
        assert_eq!(layers.len(), 6);
        for nm in [420.0, 480.0, 550.0, 610.0, 680.0] {
            let ours = reflectance_from_air(&layers, ns, nm);
            let theirs = matrix_reflectance(&pairs(Design::Multicoat, ns), ns, nm);
            assert!((ours - theirs).abs() < 1e-12, "{nm} nm: {ours} vs {theirs}");
        }
        let mean = |d: Design| band_reflectance(&d.layers(ns), ns);
        let (bare, single, broad, multi) = (
            mean(Design::Uncoated),
            mean(Design::Mgf2),
            mean(Design::Broadband),
            mean(Design::Multicoat),
        );
        eprintln!(
            "ns {ns}: bare {bare:.5} single {single:.5} broadband {broad:.5} multicoat {multi:.5}"
        );
        assert!(multi < single && single < bare, "ns {ns}");
        assert!(multi < 0.01, "ns {ns}: {multi}");
        // On crown glass, which it is designed on, the multicoat is the lowest; the
        // broadband's Al₂O₃ suits crown glass, and on dense flint one layer does better.
        if ns < 1.55 {
            assert!(multi < broad, "ns {ns}");
        }
        if ns < 1.7 {
            assert!(broad < single, "ns {ns}");
        }
    }
    assert!(matches!(Design::Uncoated.coating(1.5, true), Coating::None));
}

/// The designs' normal-incidence recursion is the SDK's general one (both polarisations,
/// any angle) at normal incidence, on stacks of 0–7 layers of any of the films.
#[test]
fn the_normal_incidence_reflectance_is_the_sdks_at_normal_incidence() {
    use flarebench_sdk::coating::{CoatingLayer, stack_reflectance};
    let films = [1.38, 1.46, 1.62, 2.05, 2.35];
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for count in 0..8 {
        for _ in 0..20 {
            let layers: Vec<CoatingLayer> = (0..count)
                .map(|_| CoatingLayer {
                    index: films[(next() * films.len() as f64) as usize % films.len()],
                    thickness_nm: 5.0 + 295.0 * next(),
                })
                .collect();
            let ns = 1.45 + 0.6 * next();
            let nm = 400.0 + 300.0 * next();
            let ours = reflectance_from_air(&layers, ns, nm);
            let sdk = stack_reflectance(1.0, ns, &layers, 1.0, nm, true);
            assert!(
                (ours - sdk).abs() < 1e-13,
                "{count} layers: {ours} vs {sdk}"
            );
        }
    }
}
