//! The sampler: a [`SamplerConfig`] read and resolved (its lenses found, its mask files
//! checked), and [`Sampler::sample`], which draws sample `index` of the dataset seeded `seed`
//! as a [`SampleSpec`] — a pure function of `(seed, index)` and the configuration.
//!
//! Draws are made in a fixed order from the sample's stream ([`super::rng`]): the lens, the
//! f-number, the aperture (mask or not, circle or not, blades, roundness, rotation), the dust,
//! the light count, then per light: inside the frame or not, its pixel position (drawn again
//! when the lens has no direction that images there), its EV and its temperature.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use flarebench_sdk::LensSystem;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::analyse;
use ghost_raytrace::scene::Quality;
use serde::Serialize;

use super::config::{Library, SamplerConfig};
use super::rng::SampleRng;
use crate::flare::frame_for;
use crate::lens_library::{self, BundledLens};
use crate::lens_listing::{self, Filter, Span};

/// Position draws per light before the sample fails: a light outside the frame of a
/// wide-angle lens may lie beyond its field (no direction images there) and is drawn again.
const POSITION_ATTEMPTS: usize = 64;

/// A sampler file that cannot be used: where and why.
#[derive(Debug, thiserror::Error)]
pub enum SamplerError {
    /// The file could not be read.
    #[error("could not read the sampler `{origin}`: {message}")]
    Read { origin: String, message: String },
    /// A field is wrong: the file, its 1-based line and column (0 when not known), the field
    /// and what is wrong.
    #[error("sampler `{origin}`, line {line}, column {column}, field `{field}`: {message}")]
    Field {
        origin: String,
        line: usize,
        column: usize,
        field: String,
        message: String,
    },
}

/// One lens the sampler may draw.
#[derive(Clone, Debug, Serialize)]
pub struct LensChoice {
    /// The bundled lens's `maker/stem` name, or the name or path given.
    pub name: String,
    #[serde(skip)]
    pub path: PathBuf,
    pub weight: f64,
}

/// A sampler ready to draw samples.
#[derive(Debug)]
pub struct Sampler {
    config: SamplerConfig,
    lenses: Vec<LensChoice>,
    masks: Vec<PathBuf>,
    dust: Vec<PathBuf>,
    /// Each lens, read when first drawn.
    systems: Vec<OnceLock<Result<Arc<LensSystem>, String>>>,
}

/// The aperture of a sample.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "shape", rename_all = "lowercase")]
pub enum ApertureSpec {
    Circle,
    Iris {
        blades: u32,
        /// Rotation (degrees), within one blade's period.
        rotation_deg: f64,
        roundness: f64,
    },
    /// A mask image, as the sampler file names it.
    Mask {
        file: String,
        #[serde(skip)]
        path: PathBuf,
    },
}

/// One light of a sample, as drawn.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightSample {
    /// Where its image was placed (pixels, x right, y down, (0, 0) the top-left corner); may
    /// lie outside the frame.
    pub target_px: [f64; 2],
    pub outside_frame: bool,
    /// Its direction: angle to the axis and azimuth (degrees, as `render --light`), aimed by
    /// the lens's chief ray at `target_px`.
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Intensity in stops and as irradiance (`2^ev`).
    pub ev: f64,
    pub intensity: f64,
    /// Blackbody temperature (K).
    pub kelvin: f64,
}

/// Everything sample `index` is made of: what [`super::render_sample`] renders.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SampleSpec {
    pub seed: u64,
    pub index: u64,
    pub lens: String,
    #[serde(skip)]
    pub lens_path: PathBuf,
    /// `[width, height]` in pixels.
    pub size: [usize; 2],
    #[serde(serialize_with = "quality_name")]
    pub quality: Quality,
    pub starburst_texels: usize,
    /// The f-number drawn (the lens may not open that far: the annotation gives the working
    /// one).
    pub f_number: f64,
    pub aperture: ApertureSpec,
    /// The dust overlay, as the sampler file names it, if one was drawn.
    pub dust: Option<String>,
    #[serde(skip)]
    pub dust_path: Option<PathBuf>,
    pub lights: Vec<LightSample>,
    pub layers: super::config::LayerConfig,
}

fn quality_name<S: serde::Serializer>(q: &Quality, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(q.name())
}

/// 1-based line and column of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before
        .rfind('\n')
        .map_or(before.len(), |i| before.len() - i - 1)
        + 1;
    (line, column)
}

/// The key on line `line` (1-based) of `text`, with the section it is in (`lights.ev`), or the
/// section header itself.
fn field_at(text: &str, line: usize) -> String {
    let mut section = String::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.starts_with('[') {
            section = t.trim_matches(|c| c == '[' || c == ']').trim().to_string();
        }
        if i + 1 == line {
            if t.starts_with('[') {
                return section;
            }
            let key = t.split('=').next().unwrap_or("").trim();
            return match (section.is_empty(), key.is_empty()) {
                (_, true) => section,
                (true, false) => key.to_string(),
                (false, false) => format!("{section}.{key}"),
            };
        }
    }
    section
}

/// The first line of `text` setting `key` in `[section]` (1-based; 0 when not written there).
fn line_of(text: &str, section: &str, key: &str) -> usize {
    let mut current = String::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.starts_with('[') {
            current = t.trim_matches(|c| c == '[' || c == ']').trim().to_string();
        } else if current == section && t.split('=').next().is_some_and(|k| k.trim() == key) {
            return i + 1;
        }
    }
    0
}

impl Sampler {
    /// The sampler of the defaults (docs/datasets.md): the core lenses, 512×512.
    pub fn with_defaults() -> Result<Sampler, SamplerError> {
        Sampler::from_toml_str("", "(defaults)", Path::new("."))
    }

    /// Reads a sampler file; mask paths in it are relative to its directory.
    pub fn from_file(path: &Path) -> Result<Sampler, SamplerError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SamplerError::Read {
            origin: origin.clone(),
            message: e.to_string(),
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        Sampler::from_toml_str(&text, &origin, base)
    }

    /// Reads a sampler from TOML `text`; `origin` names it in errors, mask paths are relative
    /// to `base`.
    pub fn from_toml_str(text: &str, origin: &str, base: &Path) -> Result<Sampler, SamplerError> {
        let config: SamplerConfig = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_column(text, s.start));
            SamplerError::Field {
                origin: origin.to_string(),
                line,
                column,
                field: field_at(text, line),
                message: e.message().trim().to_string(),
            }
        })?;
        let field = |section: &str, key: &str, message: String| SamplerError::Field {
            origin: origin.to_string(),
            line: line_of(text, section, key),
            column: 1,
            field: format!("{section}.{key}"),
            message,
        };
        let lenses = resolve_lenses(&config).map_err(|(key, m)| field("lenses", key, m))?;
        let files = |list: &[String], key: &str| -> Result<Vec<PathBuf>, SamplerError> {
            list.iter()
                .map(|f| {
                    let p = base.join(f);
                    if p.is_file() {
                        Ok(p)
                    } else {
                        Err(field("aperture", key, format!("no file `{}`", p.display())))
                    }
                })
                .collect()
        };
        let masks = files(&config.aperture.masks, "masks")?;
        let dust = files(&config.aperture.dust, "dust")?;
        if config.aperture.mask_probability.0 > 0.0 && masks.is_empty() {
            return Err(field(
                "aperture",
                "mask_probability",
                "is above 0 but `masks` lists no file".into(),
            ));
        }
        if config.aperture.dust_probability.0 > 0.0 && dust.is_empty() {
            return Err(field(
                "aperture",
                "dust_probability",
                "is above 0 but `dust` lists no file".into(),
            ));
        }
        let systems = lenses.iter().map(|_| OnceLock::new()).collect();
        Ok(Sampler {
            config,
            lenses,
            masks,
            dust,
            systems,
        })
    }

    /// The configuration, every default filled in.
    pub fn config(&self) -> &SamplerConfig {
        &self.config
    }

    /// The lenses drawn from, with their weights, sorted by name.
    pub fn lenses(&self) -> &[LensChoice] {
        &self.lenses
    }

    /// Lens `k`, read once.
    fn system(&self, k: usize) -> anyhow::Result<Arc<LensSystem>> {
        self.systems[k]
            .get_or_init(|| {
                read_lens(&self.lenses[k].path)
                    .map(|l| Arc::new(l.system))
                    .map_err(|e| format!("{e}"))
            })
            .clone()
            .map_err(|e| anyhow::anyhow!("could not load lens `{}`: {e}", self.lenses[k].name))
    }

    /// Sample `index` of the dataset seeded `seed`.
    pub fn sample(&self, seed: u64, index: u64) -> anyhow::Result<SampleSpec> {
        let c = &self.config;
        let mut rng = SampleRng::new(seed, index);
        let weights: Vec<f64> = self.lenses.iter().map(|l| l.weight).collect();
        let k = rng.weighted(&weights);
        let system = self.system(k)?;
        let f_number = rng.log_uniform(c.f_number.0);

        let a = &c.aperture;
        let aperture = if rng.chance(a.mask_probability.0) {
            let m = rng.int([0, self.masks.len() as u32 - 1]) as usize;
            ApertureSpec::Mask {
                file: a.masks[m].clone(),
                path: self.masks[m].clone(),
            }
        } else if rng.chance(a.circle_probability.0) {
            ApertureSpec::Circle
        } else {
            let blades = rng.int(a.blades.0);
            let roundness = rng.uniform(a.roundness.0);
            let rotation_deg = rng.uniform([0.0, 360.0 / f64::from(blades)]);
            ApertureSpec::Iris {
                blades,
                rotation_deg,
                roundness,
            }
        };
        let (dust, dust_path) = if rng.chance(a.dust_probability.0) {
            let d = rng.int([0, self.dust.len() as u32 - 1]) as usize;
            (Some(a.dust[d].clone()), Some(self.dust[d].clone()))
        } else {
            (None, None)
        };

        let l = &c.lights;
        let [w, h] = c.size.0;
        let frame = frame_for(&system, (w, h));
        let count = rng.int(l.count.0);
        let mut lights = Vec::with_capacity(count as usize);
        for n in 0..count {
            let outside_frame = rng.chance(l.outside_probability.0);
            let mut placed = None;
            for _ in 0..POSITION_ATTEMPTS {
                let (x, y) = if outside_frame {
                    outside_point(&mut rng, w as f64, h as f64, l.outside_margin.0)
                } else {
                    (rng.uniform([0.0, w as f64]), rng.uniform([0.0, h as f64]))
                };
                if let Ok((theta, phi)) = crate::sources::direction_of(&system, &frame, x, y)
                    && theta < 89.0
                {
                    placed = Some(([x, y], theta, phi));
                    break;
                }
            }
            let Some((target_px, theta_deg, phi_deg)) = placed else {
                anyhow::bail!(
                    "sample {index}: light {n} could not be placed on `{}` in \
                     {POSITION_ATTEMPTS} draws (no direction images there)",
                    self.lenses[k].name
                );
            };
            let ev = rng.uniform(l.ev.0);
            let kelvin = rng.uniform(l.kelvin.0);
            lights.push(LightSample {
                target_px,
                outside_frame,
                theta_deg,
                phi_deg,
                ev,
                intensity: ev.exp2(),
                kelvin,
            });
        }
        Ok(SampleSpec {
            seed,
            index,
            lens: self.lenses[k].name.clone(),
            lens_path: self.lenses[k].path.clone(),
            size: [w, h],
            quality: c.quality.0,
            starburst_texels: c.starburst_texels,
            f_number,
            aperture,
            dust,
            dust_path,
            lights,
            layers: c.layers.clone(),
        })
    }
}

/// A point in the band of width `margin·w` (and `margin·h`) around the `w × h` frame, uniform
/// over the band's area (drawn in the enlarged rectangle until it falls outside the frame; the
/// band holds at least 1 − 1/(1+2·margin)² of it, so few draws are needed).
fn outside_point(rng: &mut SampleRng, w: f64, h: f64, margin: f64) -> (f64, f64) {
    loop {
        let x = rng.uniform([-margin * w, (1.0 + margin) * w]);
        let y = rng.uniform([-margin * h, (1.0 + margin) * h]);
        if !(0.0..=w).contains(&x) || !(0.0..=h).contains(&y) {
            return (x, y);
        }
    }
}

/// The lenses `config` asks for, sorted by name, with their weights; on error the field's key
/// in `[lenses]` and the message.
fn resolve_lenses(config: &SamplerConfig) -> Result<Vec<LensChoice>, (&'static str, String)> {
    let c = &config.lenses;
    let bundled = lens_library::bundled();
    let qualified_of = |path: &Path| -> Option<String> {
        let canon = path.canonicalize().ok()?;
        bundled
            .iter()
            .find(|b| b.path.canonicalize().ok().as_deref() == Some(canon.as_path()))
            .map(|b| b.qualified.clone())
    };
    let mut chosen: Vec<(String, PathBuf)> = if c.names.is_empty() {
        let pool: Vec<BundledLens> = bundled
            .iter()
            .filter(|b| c.library == Library::All || b.folder.is_none())
            .cloned()
            .collect();
        let filter = Filter {
            maker: c.maker.clone(),
            focal: c.focal_mm.map(|r| Span {
                lo: r.0[0],
                hi: r.0[1],
            }),
            fnum: None,
            kind: c.kind.clone(),
            terms: Vec::new(),
        };
        if filter == Filter::default() {
            pool.into_iter().map(|b| (b.qualified, b.path)).collect()
        } else {
            let root = lens_library::library_dirs()
                .into_iter()
                .next()
                .ok_or(("library", "no bundled lens library was found".to_string()))?;
            lens_listing::load_all(&pool, &root)
                .into_iter()
                .zip(pool)
                .filter_map(|(listed, b)| {
                    listed
                        .ok()
                        .filter(|l| filter.matches(l))
                        .map(|_| (b.qualified, b.path))
                })
                .collect()
        }
    } else {
        c.names
            .iter()
            .map(|n| {
                let path = lens_library::resolve(n).map_err(|e| ("names", format!("{e:#}")))?;
                Ok((qualified_of(&path).unwrap_or_else(|| n.clone()), path))
            })
            .collect::<Result<_, _>>()?
    };
    chosen.sort();
    chosen.dedup();
    if chosen.is_empty() {
        return Err((
            "library",
            "no lens matches the filters (`flarebench lenses` lists the library)".into(),
        ));
    }
    for (name, w) in &c.weights {
        if !(w.is_finite() && *w >= 0.0) {
            return Err((
                "weights",
                format!("the weight of `{name}` must be a number ≥ 0, got {w}"),
            ));
        }
        if !chosen.iter().any(|(q, _)| q == name || stem(q) == name) {
            return Err((
                "weights",
                format!("`{name}` is not one of the {} lenses chosen", chosen.len()),
            ));
        }
    }
    let out: Vec<LensChoice> = chosen
        .into_iter()
        .map(|(name, path)| {
            let weight = c
                .weights
                .get(&name)
                .or_else(|| c.weights.get(stem(&name)))
                .copied()
                .unwrap_or(1.0);
            LensChoice { name, path, weight }
        })
        .collect();
    if out.iter().all(|l| l.weight == 0.0) {
        return Err(("weights", "every lens has weight 0".into()));
    }
    Ok(out)
}

/// `stem` of `maker/stem`.
fn stem(qualified: &str) -> &str {
    qualified.rsplit('/').next().unwrap_or(qualified)
}

/// The working f-number of `system` set to `f_number`: the stop closes down to it, or stays
/// wide open when the lens cannot open that far.
pub fn working_f_number(system: &LensSystem, f_number: f64) -> anyhow::Result<f64> {
    let open = analyse(system, system.default_wavelength_nm())?.open_f_number;
    Ok(f_number.max(open))
}
