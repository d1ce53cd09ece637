//! Coatings as parameters, and what they make of a basis: per surface a family (a single layer
//! of free index and thickness, or a catalogue design with its layers' thicknesses free), the
//! lens with those coatings, and each band image's colour under them.

use flarebench_sdk::coating::CoatingLayer;
use flarebench_sdk::{Coating, LensSystem};
use serde::Serialize;

use crate::CoatingError;
use crate::basis::Basis;
use crate::catalogue::{Coatable, Design, coatable_surfaces, oriented};
use crate::solve::Bound;

/// Index range of a free single layer.
pub const SINGLE_INDEX: (f64, f64) = (1.2, 2.4);
/// Range of a single layer's quarter-wave wavelength (nm): its optical thickness × 4.
pub const SINGLE_QUARTER_NM: (f64, f64) = (300.0, 1000.0);
/// A design's layer may range from this fraction of its nominal thickness to its inverse.
pub const LAYER_RANGE: f64 = 0.5;

/// How one surface's coating is modelled.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "family", content = "design")]
pub enum Family {
    /// The coating the lens file gives, not fitted.
    Fixed,
    /// One layer: its index and its quarter-wave wavelength free.
    Single,
    /// A catalogue design: its layers' materials fixed, their thicknesses free.
    Layers(Design),
}

impl Family {
    /// `fixed`, `single`, or a design's name (its thicknesses then fitted).
    pub fn parse(s: &str) -> Option<Family> {
        match s {
            "fixed" => Some(Family::Fixed),
            "single" => Some(Family::Single),
            _ => Design::parse(s).map(Family::Layers),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Family::Fixed => "fixed",
            Family::Single => "single",
            Family::Layers(d) => d.name(),
        }
    }
}

/// One modelled surface.
#[derive(Clone, Debug, Serialize)]
pub struct ModelSurface {
    #[serde(flatten)]
    pub coatable: Coatable,
    pub family: Family,
    /// Its design's nominal layers (air side first) for [`Family::Layers`].
    #[serde(skip)]
    nominal: Vec<CoatingLayer>,
    /// Index of its first parameter.
    pub offset: usize,
}

impl ModelSurface {
    fn count(&self) -> usize {
        match self.family {
            Family::Fixed => 0,
            Family::Single => 2,
            Family::Layers(_) => self.nominal.len(),
        }
    }
}

/// A lens's coatings as parameters.
#[derive(Clone, Debug)]
pub struct CoatingModel {
    system: LensSystem,
    pub surfaces: Vec<ModelSurface>,
    params: usize,
}

impl CoatingModel {
    /// Every air–glass surface of `system` modelled as `family_of` says.
    pub fn new(
        system: &LensSystem,
        family_of: impl Fn(&Coatable) -> Family,
    ) -> Result<CoatingModel, CoatingError> {
        let mut offset = 0;
        let surfaces: Vec<ModelSurface> = coatable_surfaces(system)
            .into_iter()
            .map(|c| {
                let family = family_of(&c);
                let nominal = match family {
                    Family::Layers(d) => d.layers(c.substrate),
                    _ => Vec::new(),
                };
                let s = ModelSurface {
                    coatable: c,
                    family,
                    nominal,
                    offset,
                };
                offset += s.count();
                s
            })
            .collect();
        if surfaces.is_empty() {
            return Err(CoatingError::NothingToCoat(system.name.clone()));
        }
        Ok(CoatingModel {
            system: system.clone(),
            surfaces,
            params: offset,
        })
    }

    /// The lens the model's coatings go on.
    pub fn system(&self) -> &LensSystem {
        &self.system
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params
    }

    pub fn is_empty(&self) -> bool {
        self.params == 0
    }

    /// Every parameter's bounds.
    pub fn bounds(&self) -> Vec<Bound> {
        let mut b = Vec::with_capacity(self.params);
        for s in &self.surfaces {
            match s.family {
                Family::Fixed => {}
                Family::Single => {
                    b.push(Bound::Range(SINGLE_INDEX.0, SINGLE_INDEX.1));
                    b.push(Bound::Range(SINGLE_QUARTER_NM.0, SINGLE_QUARTER_NM.1));
                }
                Family::Layers(_) => b.extend(s.nominal.iter().map(|l| {
                    Bound::Range(LAYER_RANGE * l.thickness_nm, l.thickness_nm / LAYER_RANGE)
                })),
            }
        }
        b
    }

    /// Every parameter's name: `s3 index`, `s3 quarter-wave nm`, `s5 layer 2 ZrO2 nm`.
    pub fn names(&self) -> Vec<String> {
        let mut n = Vec::with_capacity(self.params);
        for s in &self.surfaces {
            let i = s.coatable.surface;
            match s.family {
                Family::Fixed => {}
                Family::Single => {
                    n.push(format!("s{i} index"));
                    n.push(format!("s{i} quarter-wave nm"));
                }
                Family::Layers(d) => n.extend(
                    d.materials()
                        .iter()
                        .enumerate()
                        .map(|(k, m)| format!("s{i} layer {} {} nm", k + 1, m.name)),
                ),
            }
        }
        n
    }

    /// The parameters of a single MgF₂-like layer quarter-wave at `quarter_nm` on every
    /// single-layer surface, and every design at its nominal thicknesses.
    pub fn start(&self, index: f64, quarter_nm: f64) -> Vec<f64> {
        let mut p = Vec::with_capacity(self.params);
        for s in &self.surfaces {
            match s.family {
                Family::Fixed => {}
                Family::Single => {
                    p.push(index);
                    p.push(quarter_nm);
                }
                Family::Layers(_) => p.extend(s.nominal.iter().map(|l| l.thickness_nm)),
            }
        }
        p
    }

    /// Surface `s`'s coating under `params`.
    pub fn coating(&self, s: &ModelSurface, params: &[f64]) -> Coating {
        let p = &params[s.offset..s.offset + s.count()];
        match s.family {
            Family::Fixed => self.system.surfaces[s.coatable.surface].coating.clone(),
            Family::Single => Coating::SingleLayer {
                design_wavelength_nm: p[1],
                index: p[0],
            },
            Family::Layers(Design::Uncoated) => Coating::None,
            Family::Layers(_) => Coating::Stack(oriented(
                s.nominal
                    .iter()
                    .zip(p)
                    .map(|(l, &d)| CoatingLayer {
                        index: l.index,
                        thickness_nm: d,
                    })
                    .collect(),
                s.coatable.air_first,
            )),
        }
    }

    /// The lens with the coatings of `params`.
    pub fn apply(&self, params: &[f64]) -> LensSystem {
        let mut sys = self.system.clone();
        for s in &self.surfaces {
            sys.surfaces[s.coatable.surface].coating = self.coating(s, params);
        }
        sys
    }
}

/// Each ghost's energy (sum over the frame, per channel) from its band images' sums and
/// colours (in the basis's order), times `gains`.
pub fn ghost_energies(basis: &Basis, colours: &[[f64; 3]], gains: [f64; 3]) -> Vec<[f64; 3]> {
    let mut c = colours.iter();
    basis
        .ghosts
        .iter()
        .map(|g| {
            g.bands.iter().fold([0.0; 3], |mut e, b| {
                let col = c.next().expect("one colour per band image");
                for ch in 0..3 {
                    e[ch] += b.sum * col[ch] * gains[ch];
                }
                e
            })
        })
        .collect()
}
