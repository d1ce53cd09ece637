//! Thin-film anti-reflection coatings: the exact (Airy) multiple-beam reflectance of a layer
//! stack, per polarisation, with complex angles so total internal reflection inside a stack is
//! handled too.
//!
//! For one layer of index n₁ and thickness d between media n₀ and n₂:
//! `r = (r01 + r12 e^{−2iδ}) / (1 + r01 r12 e^{−2iδ})`, `δ = 2π n₁ d cos θ₁ / λ`.
//! A stack is reduced from the substrate outward with the same recurrence. A quarter-wave
//! single layer designed for λ₀ has `n₁ d = λ₀/4`.

use num_complex::Complex64;
use std::f64::consts::PI;

/// One layer of a coating stack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatingLayer {
    /// Refractive index of the layer (non-dispersive).
    pub index: f64,
    /// Physical thickness in nanometres.
    pub thickness_nm: f64,
}

/// The anti-reflection treatment of one interface.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Coating {
    /// Bare interface: plain Fresnel reflection.
    #[default]
    None,
    /// A quarter-wave single layer of `index` designed for `design_wavelength_nm`
    /// (OpenLensFlare's `coatingLambda`/`coatingIor`).
    SingleLayer {
        design_wavelength_nm: f64,
        index: f64,
    },
    /// A stack of layers listed from the medium before the surface (object side) toward the
    /// medium after it.
    Stack(Vec<CoatingLayer>),
}

impl Coating {
    /// Checks the coating's numbers; the message names what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let check = |index: f64, len: f64, what: &str| -> Result<(), String> {
            if !(index.is_finite() && index > 0.0) {
                return Err(format!("coating index must be > 0, got {index}"));
            }
            if !(len.is_finite() && len > 0.0) {
                return Err(format!("coating {what} must be > 0 nm, got {len}"));
            }
            Ok(())
        };
        match self {
            Coating::None => Ok(()),
            Coating::SingleLayer {
                design_wavelength_nm,
                index,
            } => check(*index, *design_wavelength_nm, "design wavelength"),
            Coating::Stack(layers) => {
                if layers.is_empty() {
                    return Err("a coating stack needs at least one layer".into());
                }
                layers
                    .iter()
                    .try_for_each(|l| check(l.index, l.thickness_nm, "layer thickness"))
            }
        }
    }

    /// The layers as a stack (a single layer becomes one quarter-wave layer).
    pub fn layers(&self) -> Vec<CoatingLayer> {
        match self {
            Coating::None => Vec::new(),
            Coating::SingleLayer {
                design_wavelength_nm,
                index,
            } => vec![CoatingLayer {
                index: *index,
                thickness_nm: design_wavelength_nm / (4.0 * index),
            }],
            Coating::Stack(layers) => layers.clone(),
        }
    }

    /// Unpolarised reflectance of light arriving from the medium `n_from` at `cos_i` and going
    /// into `n_to`, at `lambda_nm`. `forward` is true when light travels from the medium before
    /// the surface to the one after it (so the stack is met in its listed order).
    pub fn reflectance(
        &self,
        n_from: f64,
        n_to: f64,
        cos_i: f64,
        lambda_nm: f64,
        forward: bool,
    ) -> f64 {
        match self {
            Coating::None => crate::fresnel::unpolarised(n_from, n_to, cos_i),
            Coating::SingleLayer {
                design_wavelength_nm,
                index,
            } => {
                let layer = CoatingLayer {
                    index: *index,
                    thickness_nm: design_wavelength_nm / (4.0 * index),
                };
                single_layer_reflectance(n_from, n_to, layer, cos_i, lambda_nm).unwrap_or_else(
                    || stack_reflectance(n_from, n_to, &[layer], cos_i, lambda_nm, true),
                )
            }
            Coating::Stack(layers) => {
                stack_reflectance(n_from, n_to, layers, cos_i, lambda_nm, forward)
            }
        }
    }
}

/// [`stack_reflectance`] of one layer in closed form (Airy's summation of the layer's
/// multiple reflections, per polarisation
/// `R = (r₁² + r₂² + 2 r₁ r₂ cos 2δ) / (1 + r₁² r₂² + 2 r₁ r₂ cos 2δ)` with real interface
/// coefficients), when the light propagates in the layer and beyond it; `None` when it is
/// evanescent in either (then the complex recursion is needed). Tables of a lens's
/// interfaces evaluate this at every entry, so it avoids complex arithmetic.
fn single_layer_reflectance(
    n_from: f64,
    n_to: f64,
    layer: CoatingLayer,
    cos_i: f64,
    lambda_nm: f64,
) -> Option<f64> {
    let c0 = cos_i.abs().min(1.0);
    let s2 = n_from * n_from * (1.0 - c0 * c0);
    let n1 = layer.index;
    let (k1, k2) = (1.0 - s2 / (n1 * n1), 1.0 - s2 / (n_to * n_to));
    if !(k1 > 0.0 && k2 > 0.0) {
        return None;
    }
    let (c1, c2) = (k1.sqrt(), k2.sqrt());
    let cos_2delta = (4.0 * PI * n1 * layer.thickness_nm * c1 / lambda_nm).cos();
    let airy = |r1: f64, r2: f64| {
        let x = 2.0 * r1 * r2 * cos_2delta;
        (r1 * r1 + r2 * r2 + x) / (1.0 + r1 * r1 * r2 * r2 + x)
    };
    let [s01, p01] = real_interface(n_from, c0, n1, c1);
    let [s12, p12] = real_interface(n1, c1, n_to, c2);
    Some(0.5 * (airy(s01, s12) + airy(p01, p12)))
}

/// Reflectance (unpolarised) of a layer stack between `n_from` (incidence side) and `n_to`.
/// `in_order` tells whether `layers[0]` is the layer met first. With no layers this is the bare
/// Fresnel reflectance.
pub fn stack_reflectance(
    n_from: f64,
    n_to: f64,
    layers: &[CoatingLayer],
    cos_i: f64,
    lambda_nm: f64,
    in_order: bool,
) -> f64 {
    let cos_i = cos_i.abs().min(1.0);
    // The invariant (n sin θ)², the same in every medium of the stack.
    let s2 = n_from * n_from * (1.0 - cos_i * cos_i);
    // cos θ in a medium; evanescent beyond the critical angle, on the branch Im ≤ 0 so that
    // e^{−2iδ} decays through the layer.
    let cos_in = |n: f64| -> Complex64 {
        let v = Complex64::new(1.0 - s2 / (n * n), 0.0).sqrt();
        if v.im > 0.0 { v.conj() } else { v }
    };
    let layer_at = |k: usize| -> CoatingLayer {
        if in_order {
            layers[k]
        } else {
            layers[layers.len() - 1 - k]
        }
    };
    // Media met in order: n_from, layer 0 .. layer L−1, n_to. Reduce from the substrate outward:
    // Γ ← (r_j + Γ e^{−2iδ}) / (1 + r_j Γ e^{−2iδ}), δ the phase thickness of the layer behind
    // interface j.
    let mut n_right = n_to;
    let mut cos_right = cos_in(n_to);
    let mut gamma: Option<[Complex64; 2]> = None;
    let mut behind: Option<CoatingLayer> = None;
    for k in (0..=layers.len()).rev() {
        let n_left = if k == 0 {
            n_from
        } else {
            layer_at(k - 1).index
        };
        let cos_left = if k == 0 {
            Complex64::new(cos_i, 0.0)
        } else {
            cos_in(n_left)
        };
        let r = interface(n_left, cos_left, n_right, cos_right);
        gamma = Some(match (gamma, behind) {
            (Some(g), Some(layer)) => {
                let delta = 2.0 * PI * layer.index * layer.thickness_nm * cos_right / lambda_nm;
                let e = (Complex64::new(0.0, -2.0) * delta).exp();
                [0, 1].map(|p| (r[p] + g[p] * e) / (1.0 + r[p] * g[p] * e))
            }
            _ => r,
        });
        if k > 0 {
            behind = Some(layer_at(k - 1));
        }
        n_right = n_left;
        cos_right = cos_left;
    }
    let g = gamma.expect("the loop runs at least once");
    0.5 * (g[0].norm_sqr() + g[1].norm_sqr())
}

/// Amplitude reflection coefficients `[s, p]` at an interface from (n1, cos θ1) into (n2, cos θ2).
fn interface(n1: f64, c1: Complex64, n2: f64, c2: Complex64) -> [Complex64; 2] {
    let rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2);
    let rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2);
    [rs, rp]
}

/// [`interface`] with real cosines (the light propagates on both sides).
fn real_interface(n1: f64, c1: f64, n2: f64, c2: f64) -> [f64; 2] {
    let rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2);
    let rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2);
    [rs, rp]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::glass::GlassCatalog;

    fn quarter_wave(index: f64, lambda0: f64) -> Coating {
        Coating::SingleLayer {
            design_wavelength_nm: lambda0,
            index,
        }
    }

    #[test]
    fn no_layers_is_bare_fresnel() {
        for &c in &[1.0, 0.8, 0.3, 0.05] {
            let bare = crate::fresnel::unpolarised(1.0, 1.52, c);
            let stack = stack_reflectance(1.0, 1.52, &[], c, 550.0, true);
            assert!((bare - stack).abs() < 1e-14, "{bare} vs {stack}");
        }
    }

    #[test]
    fn ideal_quarter_wave_cancels_reflection_at_design_wavelength() {
        let (n0, n2) = (1.0f64, 1.7);
        let n1 = (n0 * n2).sqrt();
        let r = quarter_wave(n1, 550.0).reflectance(n0, n2, 1.0, 550.0, true);
        assert!(r < 1e-15, "R = {r}");
        // Away from the design wavelength it reflects again, but less than bare glass.
        let r_blue = quarter_wave(n1, 550.0).reflectance(n0, n2, 1.0, 420.0, true);
        assert!(r_blue > 1e-4 && r_blue < crate::fresnel::unpolarised(n0, n2, 1.0));
    }

    #[test]
    fn mgf2_on_nbk7_matches_published_values() {
        let cat = GlassCatalog::bundled();
        let bk7 = cat.find("N-BK7").expect("N-BK7 in catalogue").dispersion();
        let n2 = bk7.index(550.0);
        let c = quarter_wave(1.38, 550.0);
        let r0 = c.reflectance(1.0, n2, 1.0, 550.0, true);
        let r45 = c.reflectance(1.0, n2, 45f64.to_radians().cos(), 550.0, true);
        assert!(
            (r0 * 100.0 - 1.28).abs() < 0.02,
            "R(0°) = {:.4}%",
            r0 * 100.0
        );
        assert!(
            (r45 * 100.0 - 2.09).abs() < 0.02,
            "R(45°) = {:.4}%",
            r45 * 100.0
        );
    }

    #[test]
    fn single_layer_is_symmetric_in_direction_and_a_stack_is_not() {
        let c = quarter_wave(1.38, 550.0);
        let a = c.reflectance(1.0, 1.6, 0.9, 480.0, true);
        let b = c.reflectance(1.0, 1.6, 0.9, 480.0, false);
        assert_eq!(a, b);
        let stack = Coating::Stack(vec![
            CoatingLayer {
                index: 1.38,
                thickness_nm: 99.6,
            },
            CoatingLayer {
                index: 2.1,
                thickness_nm: 65.5,
            },
        ]);
        let f = stack.reflectance(1.0, 1.6, 1.0, 480.0, true);
        let r = stack.reflectance(1.0, 1.6, 1.0, 480.0, false);
        assert!((f - r).abs() > 1e-4, "{f} vs {r}");
    }

    /// The closed form of one layer against the general recursion, over angles (up to and past
    /// the critical ones), wavelengths, layer and substrate indices.
    #[test]
    fn one_layer_in_closed_form_matches_the_stack_recursion() {
        let mut checked = 0;
        for (n0, n2) in [
            (1.0, 1.52),
            (1.0, 1.9),
            (1.62, 1.0),
            (1.5, 1.75),
            (1.8, 1.5),
        ] {
            for (n1, lambda0) in [(1.38, 550.0), (1.38, 620.0), (2.1, 500.0)] {
                let layer = CoatingLayer {
                    index: n1,
                    thickness_nm: lambda0 / (4.0 * n1),
                };
                for lambda in [380.0, 455.5, 550.0, 700.0, 780.0] {
                    for k in 0..=200 {
                        let c = k as f64 / 200.0;
                        let stack = stack_reflectance(n0, n2, &[layer], c, lambda, true);
                        if let Some(r) = single_layer_reflectance(n0, n2, layer, c, lambda) {
                            assert!((r - stack).abs() < 1e-13, "{n0} {n1} {n2} {c} {lambda}");
                            checked += 1;
                        }
                        let both = Coating::SingleLayer {
                            design_wavelength_nm: lambda0,
                            index: n1,
                        }
                        .reflectance(n0, n2, c, lambda, true);
                        assert!((both - stack).abs() < 1e-13);
                    }
                }
            }
        }
        // Most of the cases propagate (the closed form is used), some do not.
        assert!(checked > 10_000 && checked < 15 * 5 * 201, "{checked}");
    }

    #[test]
    fn total_internal_reflection_through_a_coating_is_total() {
        // From glass at 60° (beyond the 41.8° critical angle for 1.5 → 1) through MgF2.
        let r =
            quarter_wave(1.38, 550.0).reflectance(1.5, 1.0, 60f64.to_radians().cos(), 550.0, true);
        assert!((r - 1.0).abs() < 1e-12, "R = {r}");
    }
}
