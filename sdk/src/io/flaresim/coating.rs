//! The coating column (0, 1 or 2 layers) as coating stacks, on air–glass interfaces.
//!
//! - 1 layer: a quarter-wave layer of MgF₂ (n = 1.38) designed for 550 nm, as FlareSim's own
//!   renderer uses for one layer.
//! - 2 layers: the double-layer quarter–quarter ("V") antireflection coating (H. A. Macleod,
//!   *Thin-Film Optical Filters*, chapter "Antireflection coatings"): MgF₂ (1.38) on the air
//!   side over a high-index layer, both a quarter wave thick at 550 nm. Two quarter-wave layers
//!   turn the substrate's admittance n_s into n_L² n_s / n_H², so the reflectance vanishes at
//!   550 nm, at normal incidence, when n_H = n_L √(n_s / n_air): the high-index layer is
//!   designed for the glass it sits on (n_s its nd), 1.65–1.96 for glasses of nd 1.43–2.0
//!   (Al₂O₃, CeF₃, ZrO₂-like indices).
//!
//! A coating is applied only where one side is air: cemented interfaces (glass on both sides)
//! and air–air surfaces (the stop, a flat dummy) have none to carry, so a coating the file
//! gives them is left out (FlareSim's converter marks every surface followed by glass).

use crate::coating::{Coating, CoatingLayer};

/// Index of the low-index (outer) layer, MgF₂.
pub(super) const MGF2_INDEX: f64 = 1.38;

/// Design wavelength of every layer (nm).
pub(super) const DESIGN_NM: f64 = 550.0;

/// A quarter-wave layer of `index` at [`DESIGN_NM`].
fn quarter_wave(index: f64) -> CoatingLayer {
    CoatingLayer {
        index,
        thickness_nm: DESIGN_NM / (4.0 * index),
    }
}

/// The coating of `layers` (0, 1, 2) on an interface from index `before` to `after` (nd; 1 is
/// air). `None` when the file asks for a coating where there is no air–glass interface.
pub fn stack(layers: u8, before: f64, after: f64) -> Option<Coating> {
    if layers == 0 {
        return Some(Coating::None);
    }
    let (air_first, glass) = match (before == 1.0, after == 1.0) {
        (true, false) => (true, after),
        (false, true) => (false, before),
        _ => return None,
    };
    Some(match layers {
        1 => Coating::SingleLayer {
            design_wavelength_nm: DESIGN_NM,
            index: MGF2_INDEX,
        },
        _ => {
            let low = quarter_wave(MGF2_INDEX);
            let high = quarter_wave(MGF2_INDEX * glass.sqrt());
            // Listed from the medium before the surface toward the one after it.
            Coating::Stack(if air_first {
                vec![low, high]
            } else {
                vec![high, low]
            })
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reflectance a designed quarter–quarter stack leaves at its design point: the design
    /// condition is exact, so only rounding (measured 1e-32).
    const DESIGN_REFLECTANCE: f64 = 1e-15;

    #[test]
    fn the_two_layer_stack_cancels_reflection_at_550_nm_on_its_glass() {
        for nd in [1.43, 1.5168, 1.7, 1.92] {
            for (before, after) in [(1.0, nd), (nd, 1.0)] {
                let c = stack(2, before, after).unwrap();
                let r = c.reflectance(before, after, 1.0, DESIGN_NM, true);
                assert!(r < DESIGN_REFLECTANCE, "nd {nd}: R = {r}");
                // Backwards through the same interface too.
                let r = c.reflectance(after, before, 1.0, DESIGN_NM, false);
                assert!(r < DESIGN_REFLECTANCE, "nd {nd} reversed: R = {r}");
            }
        }
    }

    #[test]
    fn one_layer_is_quarter_wave_mgf2_and_cemented_interfaces_are_bare() {
        assert_eq!(
            stack(1, 1.0, 1.6),
            Some(Coating::SingleLayer {
                design_wavelength_nm: 550.0,
                index: 1.38
            })
        );
        // MgF₂ on n = 1.9: R = ((1.9 − 1.38²)/(1.9 + 1.38²))² at 550 nm, normal incidence.
        let c = stack(1, 1.0, 1.9).unwrap();
        let expected = ((1.9_f64 - 1.9044) / (1.9 + 1.9044)).powi(2);
        assert!((c.reflectance(1.0, 1.9, 1.0, 550.0, true) - expected).abs() < 1e-12);
        assert_eq!(stack(1, 1.6, 1.7), None);
        assert_eq!(stack(2, 1.0, 1.0), None);
        assert_eq!(stack(0, 1.6, 1.7), Some(Coating::None));
    }
}
