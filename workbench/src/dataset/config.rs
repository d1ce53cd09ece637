//! The sampler's TOML file (`flarebench dataset --config sampler.toml`): every field, its
//! default and its check. Ranges are `[lo, hi]`, both included; a value out of its domain is
//! refused where it is read, so the error names the file, the line and the field
//! ([`super::SamplerError`]). docs/datasets.md § The sampler lists the fields.

use std::collections::BTreeMap;

use flarebench_sdk::LensKind;
use ghost_raytrace::scene::Quality;
use serde::{Deserialize, Serialize};

/// The whole sampler file. Every section and field may be left out.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplerConfig {
    /// Output size in pixels `[width, height]`; the frame spans the film's width.
    pub size: Size,
    /// The render's quality preset: `fast`, `default` or `high`.
    pub quality: QualityName,
    /// Texels across the pupil for the starburst's transform (as `render --starburst-texels`).
    pub starburst_texels: usize,
    /// The f-number, log-uniform in the range; a lens that cannot open that far is used wide
    /// open (the annotation gives the working f-number).
    pub f_number: PositiveRange,
    pub lenses: LensConfig,
    pub aperture: ApertureConfig,
    pub lights: LightConfig,
    pub layers: LayerConfig,
}

impl Default for SamplerConfig {
    fn default() -> SamplerConfig {
        SamplerConfig {
            size: Size([512, 512]),
            quality: QualityName(Quality::Default),
            starburst_texels: 256,
            f_number: PositiveRange([1.4, 16.0]),
            lenses: LensConfig::default(),
            aperture: ApertureConfig::default(),
            lights: LightConfig::default(),
            layers: LayerConfig::default(),
        }
    }
}

/// Which lenses are drawn, and how often.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LensConfig {
    /// `core` (the 19 lenses at the top of `lenses/`) or `all` (every bundled lens); the
    /// filters below choose among them. Ignored when `names` is given.
    pub library: Library,
    /// Lenses by name (as `flarebench render` takes them: a bundled name or a file); when
    /// given, the library and filters are not used.
    pub names: Vec<String>,
    /// Part of the maker's name, or the maker folder (`nikon`).
    pub maker: Option<String>,
    /// Kinds every chosen lens has (`zoom`, `prime`, `fisheye`, …).
    pub kind: Vec<LensKind>,
    /// Focal length (mm): a lens is chosen when its range overlaps this one.
    pub focal_mm: Option<PositiveRange>,
    /// Relative weight by lens name (default 1 each).
    pub weights: BTreeMap<String, f64>,
}

impl Default for LensConfig {
    fn default() -> LensConfig {
        LensConfig {
            library: Library::Core,
            names: Vec::new(),
            maker: None,
            kind: Vec::new(),
            focal_mm: None,
            weights: BTreeMap::new(),
        }
    }
}

/// The part of the bundled library lenses are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Library {
    Core,
    All,
}

/// The aperture stop's shape, and the dust on it.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ApertureConfig {
    /// Probability of a circular stop (no blades).
    pub circle_probability: Probability,
    /// Iris blade count, uniform in the range (at least 3).
    pub blades: BladeRange,
    /// Blade roundness, 0 (straight) to 1 (a circle), uniform in the range. The rotation is
    /// uniform over one blade's period.
    pub roundness: UnitRange,
    /// Aperture mask images (BMP or PNG, white open; paths relative to the sampler file), one
    /// of them drawn with `mask_probability` in place of the circle or iris.
    pub masks: Vec<String>,
    pub mask_probability: Probability,
    /// Dust or scratch overlays for the starburst (white clear), one drawn with
    /// `dust_probability`.
    pub dust: Vec<String>,
    pub dust_probability: Probability,
}

impl Default for ApertureConfig {
    fn default() -> ApertureConfig {
        ApertureConfig {
            circle_probability: Probability(0.2),
            blades: BladeRange([5, 9]),
            roundness: UnitRange([0.0, 0.5]),
            masks: Vec::new(),
            mask_probability: Probability(0.0),
            dust: Vec::new(),
            dust_probability: Probability(0.0),
        }
    }
}

/// The lights of a sample.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightConfig {
    /// How many, uniform in the range (at least 1).
    pub count: CountRange,
    /// Probability that a light lies just outside the frame rather than in it.
    pub outside_probability: Probability,
    /// How far outside: up to this fraction of the frame's width (and height) beyond each
    /// edge.
    pub outside_margin: UnitRange1,
    /// Intensity in stops: the light's irradiance is `2^ev` (`render --light`'s INTENSITY),
    /// uniform in the range.
    pub ev: Range,
    /// Colour as a blackbody temperature (K), uniform in the range.
    pub kelvin: PositiveRange,
}

impl Default for LightConfig {
    fn default() -> LightConfig {
        LightConfig {
            count: CountRange([1, 3]),
            outside_probability: Probability(0.25),
            outside_margin: UnitRange1(0.25),
            ev: Range([0.0, 4.0]),
            kelvin: PositiveRange([2700.0, 9000.0]),
        }
    }
}

/// What each sample writes besides the flare and the ghosts' layer.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LayerConfig {
    /// Add the lights' starbursts to the flare, and write them as a layer of their own.
    pub starburst: bool,
    /// A layer per light: its ghosts and its starburst.
    pub per_light: bool,
    /// The per-ghost ID layer: at each pixel, the ghost that adds the most luminance.
    pub ghost_id: bool,
    /// A tone-mapped PNG of the flare beside the EXR.
    pub png: bool,
    /// The PNG's exposure (stops); absent: each sample's automatic exposure.
    pub png_exposure_ev: Option<f32>,
}

impl Default for LayerConfig {
    fn default() -> LayerConfig {
        LayerConfig {
            starburst: true,
            per_light: false,
            ghost_id: true,
            png: true,
            png_exposure_ev: None,
        }
    }
}

/// `[lo, hi]`, finite, `lo ≤ hi`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "[f64; 2]", into = "[f64; 2]")]
pub struct Range(pub [f64; 2]);

fn check_range([lo, hi]: [f64; 2]) -> Result<[f64; 2], String> {
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(format!("[{lo}, {hi}] is not a range of finite numbers"));
    }
    if lo > hi {
        return Err(format!(
            "the range [{lo}, {hi}] is empty (give [lo, hi] with lo ≤ hi)"
        ));
    }
    Ok([lo, hi])
}

impl TryFrom<[f64; 2]> for Range {
    type Error = String;
    fn try_from(r: [f64; 2]) -> Result<Range, String> {
        check_range(r).map(Range)
    }
}

impl From<Range> for [f64; 2] {
    fn from(r: Range) -> [f64; 2] {
        r.0
    }
}

/// A [`Range`] of positive numbers.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "[f64; 2]", into = "[f64; 2]")]
pub struct PositiveRange(pub [f64; 2]);

impl TryFrom<[f64; 2]> for PositiveRange {
    type Error = String;
    fn try_from(r: [f64; 2]) -> Result<PositiveRange, String> {
        let [lo, hi] = check_range(r)?;
        if lo <= 0.0 {
            return Err(format!("[{lo}, {hi}] must hold positive numbers only"));
        }
        Ok(PositiveRange([lo, hi]))
    }
}

impl From<PositiveRange> for [f64; 2] {
    fn from(r: PositiveRange) -> [f64; 2] {
        r.0
    }
}

/// A [`Range`] within [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "[f64; 2]", into = "[f64; 2]")]
pub struct UnitRange(pub [f64; 2]);

impl TryFrom<[f64; 2]> for UnitRange {
    type Error = String;
    fn try_from(r: [f64; 2]) -> Result<UnitRange, String> {
        let [lo, hi] = check_range(r)?;
        if lo < 0.0 || hi > 1.0 {
            return Err(format!("[{lo}, {hi}] must lie within [0, 1]"));
        }
        Ok(UnitRange([lo, hi]))
    }
}

impl From<UnitRange> for [f64; 2] {
    fn from(r: UnitRange) -> [f64; 2] {
        r.0
    }
}

/// A number in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "f64", into = "f64")]
pub struct Probability(pub f64);

impl TryFrom<f64> for Probability {
    type Error = String;
    fn try_from(p: f64) -> Result<Probability, String> {
        if (0.0..=1.0).contains(&p) {
            Ok(Probability(p))
        } else {
            Err(format!("{p} is not a probability (0 to 1)"))
        }
    }
}

impl From<Probability> for f64 {
    fn from(p: Probability) -> f64 {
        p.0
    }
}

/// A fraction in (0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "f64", into = "f64")]
pub struct UnitRange1(pub f64);

impl TryFrom<f64> for UnitRange1 {
    type Error = String;
    fn try_from(p: f64) -> Result<UnitRange1, String> {
        if p > 0.0 && p <= 1.0 {
            Ok(UnitRange1(p))
        } else {
            Err(format!("{p} is not a fraction above 0 and at most 1"))
        }
    }
}

impl From<UnitRange1> for f64 {
    fn from(p: UnitRange1) -> f64 {
        p.0
    }
}

/// Whole numbers `[lo, hi]` with `MIN ≤ lo ≤ hi ≤ 64`.
fn check_count<const MIN: u32>([lo, hi]: [u32; 2]) -> Result<[u32; 2], String> {
    if lo < MIN || lo > hi || hi > 64 {
        return Err(format!(
            "[{lo}, {hi}] must be whole numbers with {MIN} ≤ lo ≤ hi ≤ 64"
        ));
    }
    Ok([lo, hi])
}

/// Iris blade counts, at least 3.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "[u32; 2]", into = "[u32; 2]")]
pub struct BladeRange(pub [u32; 2]);

impl TryFrom<[u32; 2]> for BladeRange {
    type Error = String;
    fn try_from(r: [u32; 2]) -> Result<BladeRange, String> {
        check_count::<3>(r).map(BladeRange)
    }
}

impl From<BladeRange> for [u32; 2] {
    fn from(r: BladeRange) -> [u32; 2] {
        r.0
    }
}

/// Light counts, at least 1.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "[u32; 2]", into = "[u32; 2]")]
pub struct CountRange(pub [u32; 2]);

impl TryFrom<[u32; 2]> for CountRange {
    type Error = String;
    fn try_from(r: [u32; 2]) -> Result<CountRange, String> {
        check_count::<1>(r).map(CountRange)
    }
}

impl From<CountRange> for [u32; 2] {
    fn from(r: CountRange) -> [u32; 2] {
        r.0
    }
}

/// An image size `[width, height]`, 1 to 16384 pixels a side.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "[usize; 2]", into = "[usize; 2]")]
pub struct Size(pub [usize; 2]);

impl TryFrom<[usize; 2]> for Size {
    type Error = String;
    fn try_from([w, h]: [usize; 2]) -> Result<Size, String> {
        if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
            return Err(format!(
                "size [{w}, {h}] must be between 1 and 16384 pixels per side"
            ));
        }
        Ok(Size([w, h]))
    }
}

impl From<Size> for [usize; 2] {
    fn from(s: Size) -> [usize; 2] {
        s.0
    }
}

/// A quality preset by name.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "String", into = "String")]
pub struct QualityName(pub Quality);

impl TryFrom<String> for QualityName {
    type Error = String;
    fn try_from(s: String) -> Result<QualityName, String> {
        s.parse::<Quality>()
            .map(QualityName)
            .map_err(|_| format!("`{s}` is not a quality preset (fast, default or high)"))
    }
}

impl From<QualityName> for String {
    fn from(q: QualityName) -> String {
        q.0.name().to_string()
    }
}
