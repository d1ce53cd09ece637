//! A catalogue of anti-reflection designs a lens maker might put on an air–glass surface, from
//! bare glass to a six-layer multicoat, each with its layers (materials and thicknesses for
//! the surface's own glass) and a cost rank.
//!
//! Layer indices are those of evaporated films at 550 nm, taken as non-dispersive as the
//! coating model does (`flarebench_sdk::coating`): MgF₂ 1.38, SiO₂ 1.46, Al₂O₃ 1.62,
//! ZrO₂ 2.05, TiO₂ 2.35 (H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., ch. 4 and
//! table of film materials). Thicknesses are physical, in nanometres. Layers are listed from
//! the air side toward the glass; [`oriented`] turns them into a surface's order.

use flarebench_sdk::coating::CoatingLayer;
use flarebench_sdk::{Coating, LensSystem};
use serde::Serialize;
use std::f64::consts::PI;

use rayon::prelude::*;

use crate::solve::{Bound, minimise};

/// A thin-film material: its name and index.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Material {
    pub name: &'static str,
    pub index: f64,
}

pub const MGF2: Material = Material {
    name: "MgF2",
    index: 1.38,
};
pub const SIO2: Material = Material {
    name: "SiO2",
    index: 1.46,
};
pub const AL2O3: Material = Material {
    name: "Al2O3",
    index: 1.62,
};
pub const ZRO2: Material = Material {
    name: "ZrO2",
    index: 2.05,
};
pub const TIO2: Material = Material {
    name: "TiO2",
    index: 2.35,
};

/// Wavelength (nm) the single layer and the V-coat are designed for.
pub const DESIGN_NM: f64 = 550.0;
/// Wavelength (nm) of the broadband quarter–half–quarter design.
pub const BROADBAND_NM: f64 = 510.0;
/// The band (nm) the multicoat's thicknesses minimise the mean reflectance over.
pub const MULTICOAT_BAND_NM: (f64, f64) = (420.0, 680.0);

/// One design of the catalogue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Design {
    /// Bare glass: Fresnel reflection, some 4–8% a surface.
    Uncoated,
    /// One quarter-wave layer of MgF₂ at 550 nm: the classic single coating (about 1.3% on
    /// crown glass, least on glass of index near 1.9).
    Mgf2,
    /// Two layers, MgF₂ over ZrO₂, whose thicknesses null the reflectance at 550 nm on the
    /// surface's glass (a V-shaped curve).
    VCoat,
    /// Three layers, MgF₂ λ/4, ZrO₂ λ/2, Al₂O₃ λ/4 at 510 nm (quarter–half–quarter): low
    /// across the visible.
    Broadband,
    /// Six layers, MgF₂ / TiO₂ / SiO₂ / TiO₂ / SiO₂ / Al₂O₃ from the air side, thicknesses
    /// minimising the RMS normal reflectance over 420–680 nm on the surface's glass.
    Multicoat,
}

impl Design {
    /// Every design, cheapest first.
    pub const ALL: [Design; 5] = [
        Design::Uncoated,
        Design::Mgf2,
        Design::VCoat,
        Design::Broadband,
        Design::Multicoat,
    ];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Design::Uncoated => "uncoated",
            Design::Mgf2 => "mgf2",
            Design::VCoat => "v-coat",
            Design::Broadband => "broadband",
            Design::Multicoat => "multicoat",
        }
    }

    /// The design of that name.
    pub fn parse(s: &str) -> Option<Design> {
        Design::ALL.into_iter().find(|d| d.name() == s)
    }

    /// Cost rank: the number of layers' worth of process, 0 (bare) to 4 (multicoat).
    pub fn cost_rank(self) -> u32 {
        match self {
            Design::Uncoated => 0,
            Design::Mgf2 => 1,
            Design::VCoat => 2,
            Design::Broadband => 3,
            Design::Multicoat => 4,
        }
    }

    /// True for the designs a budget of premium surfaces counts (broadband and multicoat).
    pub fn is_premium(self) -> bool {
        self.cost_rank() >= 3
    }

    /// The materials of its layers from the air side.
    pub fn materials(self) -> &'static [Material] {
        match self {
            Design::Uncoated => &[],
            Design::Mgf2 => &[MGF2],
            Design::VCoat => &[MGF2, ZRO2],
            Design::Broadband => &[MGF2, ZRO2, AL2O3],
            Design::Multicoat => &[MGF2, TIO2, SIO2, TIO2, SIO2, AL2O3],
        }
    }

    /// Its layers, from the air side, for glass of index `substrate` (at 550 nm).
    pub fn layers(self, substrate: f64) -> Vec<CoatingLayer> {
        let quarter = |m: Material, nm: f64| CoatingLayer {
            index: m.index,
            thickness_nm: nm / (4.0 * m.index),
        };
        match self {
            Design::Uncoated => Vec::new(),
            Design::Mgf2 => vec![quarter(MGF2, DESIGN_NM)],
            Design::VCoat => v_coat(substrate).unwrap_or_else(|| vec![quarter(MGF2, DESIGN_NM)]),
            Design::Broadband => vec![
                quarter(MGF2, BROADBAND_NM),
                CoatingLayer {
                    index: ZRO2.index,
                    thickness_nm: BROADBAND_NM / (2.0 * ZRO2.index),
                },
                quarter(AL2O3, BROADBAND_NM),
            ],
            Design::Multicoat => multicoat(substrate),
        }
    }

    /// The design as a surface's coating, for glass of index `substrate`, with `air_first`
    /// telling whether the air is on the surface's object side.
    pub fn coating(self, substrate: f64, air_first: bool) -> Coating {
        match self {
            Design::Uncoated => Coating::None,
            Design::Mgf2 => Coating::SingleLayer {
                design_wavelength_nm: DESIGN_NM,
                index: MGF2.index,
            },
            _ => Coating::Stack(oriented(self.layers(substrate), air_first)),
        }
    }
}

/// Layers listed from the air side put in a surface's order (object side first): reversed
/// when the glass is on the object side.
pub fn oriented(mut layers: Vec<CoatingLayer>, air_first: bool) -> Vec<CoatingLayer> {
    if !air_first {
        layers.reverse();
    }
    layers
}

/// Normal reflectance of `layers` (air side first) from air onto glass of index `substrate`:
/// [`flarebench_sdk::coating::stack_reflectance`] at normal incidence, where both polarisations are one and every
/// angle's cosine is 1, so the Airy recursion runs on one amplitude with real Fresnel
/// coefficients `(n₁ − n₂)/(n₁ + n₂)` and phases `2π n d / λ` (the multicoat's design
/// evaluates it hundreds of thousands of times a glass).
pub fn reflectance_from_air(layers: &[CoatingLayer], substrate: f64, lambda_nm: f64) -> f64 {
    let fresnel = |a: f64, b: f64| (a - b) / (a + b);
    let Some(last) = layers.last() else {
        return fresnel(1.0, substrate).powi(2);
    };
    // Γ from the substrate outward: Γ ← (r + Γ e^{−2iδ}) / (1 + r Γ e^{−2iδ}).
    let (mut re, mut im) = (fresnel(last.index, substrate), 0.0);
    for (k, layer) in layers.iter().enumerate().rev() {
        let n_left = if k == 0 { 1.0 } else { layers[k - 1].index };
        let r = fresnel(n_left, layer.index);
        let delta = 2.0 * PI * layer.index * layer.thickness_nm / lambda_nm;
        let (sin, cos) = (2.0 * delta).sin_cos();
        // g = Γ e^{−2iδ}
        let (gr, gi) = (re * cos + im * sin, im * cos - re * sin);
        let (nr, ni) = (r + gr, gi);
        let (dr, di) = (1.0 + r * gr, r * gi);
        let d2 = dr * dr + di * di;
        (re, im) = ((nr * dr + ni * di) / d2, (ni * dr - nr * di) / d2);
    }
    re * re + im * im
}

/// The two-layer V-coat (MgF₂ over ZrO₂) nulling the normal reflectance at [`DESIGN_NM`] on
/// glass of index `ns`, in closed form: with `t₁ = tan δ₁` (outer layer, n₁), `t₂ = tan δ₂`
/// (inner, n₂), the characteristic matrices give zero reflectance from a medium n₀ when
/// `t₁ t₂ = (nₛ − n₀) n₁ n₂ / (n₁² nₛ − n₀ n₂²)` and
/// `t₁ = t₂ · n₁ (n₀ nₛ − n₂²) / (n₂ (n₁² − n₀ nₛ))`. `None` where no real solution exists
/// (glass whose index is close to or above n₁²: there one MgF₂ layer is the better coating).
pub fn v_coat(ns: f64) -> Option<Vec<CoatingLayer>> {
    let (n0, n1, n2) = (1.0, MGF2.index, ZRO2.index);
    let p = (ns - n0) * n1 * n2 / (n1 * n1 * ns - n0 * n2 * n2);
    let k = n1 * (n0 * ns - n2 * n2) / (n2 * (n1 * n1 - n0 * ns));
    let t2sq = p / k;
    if !(t2sq.is_finite() && t2sq > 0.0) {
        return None;
    }
    let t2 = t2sq.sqrt();
    let t1 = k * t2;
    // Phases in (0, π): the thinner inner layer.
    let phase = |t: f64| {
        let a = t.atan();
        if a < 0.0 { a + PI } else { a }
    };
    let (d1, d2) = (phase(t1), phase(t2));
    let thickness = |delta: f64, n: f64| delta * DESIGN_NM / (2.0 * PI * n);
    Some(vec![
        CoatingLayer {
            index: n1,
            thickness_nm: thickness(d1, n1),
        },
        CoatingLayer {
            index: n2,
            thickness_nm: thickness(d2, n2),
        },
    ])
}

/// Wavelengths the multicoat's mean reflectance is taken at: every 10 nm over
/// [`MULTICOAT_BAND_NM`].
fn multicoat_band() -> Vec<f64> {
    let (lo, hi) = MULTICOAT_BAND_NM;
    let n = ((hi - lo) / 10.0).round() as usize;
    (0..=n).map(|i| lo + 10.0 * i as f64).collect()
}

/// Starts of the multicoat's thicknesses: quarter-wave stacks at 450, 510 and 600 nm (the
/// second layer half-wave), the broadband design in its materials, and 12 spread over 10–200 nm a layer (an additive recurrence with
/// the square roots of primes: spread, and the same each run).
fn multicoat_starts() -> Vec<Vec<f64>> {
    let materials = Design::Multicoat.materials();
    let mut starts: Vec<Vec<f64>> = [450.0, 510.0, 600.0]
        .iter()
        .map(|&nm| {
            materials
                .iter()
                .enumerate()
                .map(|(i, m)| nm / (if i == 1 { 2.0 } else { 4.0 } * m.index))
                .collect()
        })
        .collect();
    // The broadband design in these materials: TiO₂ half-wave for its ZrO₂, the middle
    // layers at their thinnest.
    starts.push(vec![
        510.0 / (4.0 * MGF2.index),
        510.0 / (2.0 * TIO2.index),
        5.0,
        5.0,
        5.0,
        510.0 / (4.0 * AL2O3.index),
    ]);
    let steps = [2f64, 3.0, 5.0, 7.0, 11.0, 13.0].map(|p| p.sqrt().fract());
    starts.extend((1..=12).map(|k| {
        steps
            .iter()
            .map(|a| 10.0 + 190.0 * (k as f64 * a).fract())
            .collect()
    }));
    starts
}

/// The best of Levenberg–Marquardt runs from `starts` for glass `ns` (module docs).
fn multicoat_from(ns: f64, starts: &[Vec<f64>]) -> Vec<f64> {
    let materials = Design::Multicoat.materials();
    let band = multicoat_band();
    let bounds = vec![Bound::Range(5.0, 300.0); materials.len()];
    let residuals = |t: &[f64]| -> Vec<f64> {
        let layers = multicoat_layers(t);
        band.iter()
            .map(|&nm| reflectance_from_air(&layers, ns, nm))
            .collect()
    };
    starts
        .par_iter()
        .map(|s| minimise(&residuals, s, &bounds))
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .expect("at least one start")
        .params
}

fn multicoat_layers(t: &[f64]) -> Vec<CoatingLayer> {
    Design::Multicoat
        .materials()
        .iter()
        .zip(t)
        .map(|(m, &d)| CoatingLayer {
            index: m.index,
            thickness_nm: d,
        })
        .collect()
}

/// The multicoat for glass of index `ns`: its six layers' thicknesses (each 5–300 nm) that
/// minimise the RMS normal reflectance every 10 nm over [`MULTICOAT_BAND_NM`]: the best of
/// Levenberg–Marquardt runs from [`multicoat_starts`] and, on other glass, crown glass's
/// (n = 1.52) design (about 1 s on 2 cores a glass). A local optimiser's best, not a global
/// optimum. Kept per glass index (to 1e-4) for the process.
pub fn multicoat(ns: f64) -> Vec<CoatingLayer> {
    multicoat_layers(&multicoat_thicknesses(ns))
}

/// Crown glass (n = 1.52) as a key of [`multicoat_thicknesses`]: its design is a start of
/// every other glass's.
const CROWN_KEY: i64 = 15200;

fn multicoat_thicknesses(ns: f64) -> Vec<f64> {
    static MADE: std::sync::Mutex<Vec<(i64, Vec<f64>)>> = std::sync::Mutex::new(Vec::new());
    let key = (ns * 1e4).round() as i64;
    let held = MADE
        .lock()
        .ok()
        .and_then(|m| m.iter().find(|(k, _)| *k == key).map(|(_, t)| t.clone()));
    held.unwrap_or_else(|| {
        let mut starts = multicoat_starts();
        if key != CROWN_KEY {
            starts.push(multicoat_thicknesses(CROWN_KEY as f64 * 1e-4));
        }
        let t = multicoat_from(key as f64 * 1e-4, &starts);
        if let Ok(mut m) = MADE.lock() {
            m.push((key, t.clone()));
        }
        t
    })
}

/// RMS normal reflectance of `layers` (air side first) on glass `ns` over
/// [`MULTICOAT_BAND_NM`], every 10 nm: what the multicoat minimises.
pub fn band_reflectance(layers: &[CoatingLayer], ns: f64) -> f64 {
    let band = multicoat_band();
    (band
        .iter()
        .map(|&nm| reflectance_from_air(layers, ns, nm).powi(2))
        .sum::<f64>()
        / band.len() as f64)
        .sqrt()
}

/// An air–glass surface of a lens a coating can go on.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Coatable {
    /// Index of the surface in the prescription.
    pub surface: usize,
    /// The glass's index at 550 nm.
    pub substrate: f64,
    /// True when the air is on the object side of the surface.
    pub air_first: bool,
}

/// Every refracting surface of `system` between air and glass (cemented surfaces and the
/// stop are not coated).
pub fn coatable_surfaces(system: &LensSystem) -> Vec<Coatable> {
    let n = system.indices(DESIGN_NM);
    system
        .surfaces
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kind == flarebench_sdk::system::SurfaceKind::Refracting)
        .filter_map(|(i, _)| {
            let (before, after) = (n[i], n[i + 1]);
            let air = |v: f64| (v - 1.0).abs() < 1e-9;
            match (air(before), air(after)) {
                (true, false) => Some(Coatable {
                    surface: i,
                    substrate: after,
                    air_first: true,
                }),
                (false, true) => Some(Coatable {
                    surface: i,
                    substrate: before,
                    air_first: false,
                }),
                _ => None,
            }
        })
        .collect()
}
