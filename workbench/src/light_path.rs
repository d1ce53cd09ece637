//! Light paths for `render --frames A..B --light-path FILE`: each light's keyframes of time
//! (a frame number), direction, intensity and colour, read from TOML, and the lights of any
//! frame between them (`docs/formats.md` § Light paths).
//!
//! Interpolation is per light: `linear` (piecewise linear) or `smooth`, a monotone cubic
//! Hermite curve (Fritsch–Carlson slopes): it passes through every keyframe, has a continuous
//! first derivative, and never overshoots — between two keyframes each value stays between
//! theirs, so θ stays in [0°, 90°) and the intensity positive. Before the first keyframe and
//! after the last the light holds that keyframe's values. φ is interpolated as written (from
//! 350 to 370 crosses 0; from 350 to 10 turns the long way round).

use std::ops::Range;
use std::path::Path;

use anyhow::Context;
use flarebench_sdk::color::LightSpectrum;
use ghost_raytrace::scene::LightSpec;
use serde::Deserialize;
use toml::Spanned;

/// How a light's values go between its keyframes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Piecewise linear.
    Linear,
    /// Monotone cubic Hermite (Fritsch–Carlson): smooth, through the keyframes, no overshoot.
    Smooth,
}

/// A keyframe's colour; all keyframes of a light give it the same way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KeyColour {
    /// Daylight D65 (no `colour`).
    D65,
    /// A blackbody temperature (kelvin), interpolated in kelvin.
    Kelvin(f64),
    /// Linear sRGB, interpolated per component.
    Rgb([f64; 3]),
}

/// One keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// Time, in frames (need not be whole).
    pub frame: f64,
    /// Angle to the axis and azimuth (degrees), as `--light` takes them.
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Irradiance, as `--light` takes it (default 1).
    pub intensity: f64,
    pub colour: KeyColour,
}

/// One light's path: its keyframes in increasing time.
#[derive(Clone, Debug, PartialEq)]
pub struct PathLight {
    pub interpolation: Interpolation,
    pub keys: Vec<Key>,
}

/// The lights of a sequence, each along its path.
#[derive(Clone, Debug, PartialEq)]
pub struct LightPath {
    pub lights: Vec<PathLight>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileToml {
    light: Vec<Spanned<LightToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightToml {
    #[serde(default)]
    interpolation: Option<Spanned<String>>,
    key: Vec<Spanned<KeyToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyToml {
    frame: Spanned<f64>,
    theta: Spanned<f64>,
    phi: Spanned<f64>,
    #[serde(default)]
    intensity: Option<Spanned<f64>>,
    #[serde(default)]
    colour: Option<Spanned<ColourToml>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ColourToml {
    Number(f64),
    Text(String),
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.chars().rev().take_while(|&c| c != '\n').count() + 1;
    (line, col)
}

impl LightPath {
    /// Reads and checks a light path file.
    pub fn read(path: &Path) -> anyhow::Result<LightPath> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("could not read the light path `{}`", path.display()))?;
        LightPath::parse(&text, &path.display().to_string()).map_err(anyhow::Error::msg)
    }

    /// Parses a light path file's `text`; `file` names it in errors, which give the file, the
    /// 1-based line and column, and the field.
    pub fn parse(text: &str, file: &str) -> Result<LightPath, String> {
        let raw: FileToml = toml::from_str(text).map_err(|e| {
            let at = match e.span() {
                Some(s) => {
                    let (l, c) = line_col(text, s.start);
                    format!("{file}:{l}:{c}")
                }
                None => file.to_string(),
            };
            format!("{at}: {}", e.message().trim_end())
        })?;
        let err = |span: Range<usize>, what: String| {
            let (l, c) = line_col(text, span.start);
            format!("{file}:{l}:{c}: {what}")
        };
        if raw.light.is_empty() {
            return Err(format!("{file}: no `[[light]]`"));
        }
        let mut lights = Vec::new();
        for (i, light) in raw.light.iter().enumerate() {
            let span = light.span();
            let light = light.get_ref();
            let interpolation = match &light.interpolation {
                None => Interpolation::Linear,
                Some(s) => match s.get_ref().as_str() {
                    "linear" => Interpolation::Linear,
                    "smooth" => Interpolation::Smooth,
                    other => {
                        return Err(err(
                            s.span(),
                            format!(
                                "light {i}, field `interpolation`: `{other}` is neither \
                                 `linear` nor `smooth`"
                            ),
                        ));
                    }
                },
            };
            if light.key.is_empty() {
                return Err(err(span, format!("light {i} has no `[[light.key]]`")));
            }
            let mut keys: Vec<Key> = Vec::new();
            for (k, key) in light.key.iter().enumerate() {
                let key = key.get_ref();
                let field = |f: &Spanned<f64>, name: &str, ok: bool, rule: &str| {
                    if ok {
                        Ok(*f.get_ref())
                    } else {
                        Err(err(
                            f.span(),
                            format!("light {i}, key {k}, field `{name}`: {} {rule}", f.get_ref()),
                        ))
                    }
                };
                let frame = *key.frame.get_ref();
                field(&key.frame, "frame", frame.is_finite(), "is not finite")?;
                // Both are finite (checked), so `<=` is the whole test.
                if let Some(prev) = keys.last()
                    && frame <= prev.frame
                {
                    return Err(err(
                        key.frame.span(),
                        format!(
                            "light {i}, key {k}, field `frame`: {frame} does not come after \
                             the key before ({})",
                            prev.frame
                        ),
                    ));
                }
                let t = *key.theta.get_ref();
                let theta_deg = field(
                    &key.theta,
                    "theta",
                    (0.0..90.0).contains(&t),
                    "is not in [0, 90) degrees",
                )?;
                let phi_deg = field(
                    &key.phi,
                    "phi",
                    key.phi.get_ref().is_finite(),
                    "is not finite",
                )?;
                let intensity = match &key.intensity {
                    None => 1.0,
                    Some(v) => {
                        let x = *v.get_ref();
                        field(
                            v,
                            "intensity",
                            x.is_finite() && x > 0.0,
                            "is not a positive number",
                        )?
                    }
                };
                let colour = match &key.colour {
                    None => KeyColour::D65,
                    Some(c) => {
                        let text = match c.get_ref() {
                            ColourToml::Number(x) => x.to_string(),
                            ColourToml::Text(s) => s.clone(),
                        };
                        let bad = |why: String| {
                            err(
                                c.span(),
                                format!("light {i}, key {k}, field `colour`: {why}"),
                            )
                        };
                        let spec = LightSpec::parse(&format!("0,0,1,{text}"))
                            .map_err(|e| bad(format!("`{text}`: {e}")))?;
                        match spec.spectrum {
                            LightSpectrum::Blackbody { kelvin } => KeyColour::Kelvin(kelvin),
                            LightSpectrum::Rgb(v) => {
                                KeyColour::Rgb([v[0] as f64, v[1] as f64, v[2] as f64])
                            }
                            other => return Err(bad(format!("unexpected colour {other:?}"))),
                        }
                    }
                };
                if let Some(first) = keys.first()
                    && std::mem::discriminant(&first.colour) != std::mem::discriminant(&colour)
                {
                    let span = key.colour.as_ref().map_or(key.frame.span(), |c| c.span());
                    return Err(err(
                        span,
                        format!(
                            "light {i}, key {k}, field `colour`: every key of a light gives \
                             its colour the same way (all in kelvin, all R:G:B, or none), \
                             key 0 does not as this one"
                        ),
                    ));
                }
                keys.push(Key {
                    frame,
                    theta_deg,
                    phi_deg,
                    intensity,
                    colour,
                });
            }
            lights.push(PathLight {
                interpolation,
                keys,
            });
        }
        Ok(LightPath { lights })
    }

    /// The lights at `frame`, in the file's order.
    pub fn lights_at(&self, frame: f64) -> anyhow::Result<Vec<LightSpec>> {
        self.lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                l.at(frame)
                    .with_context(|| format!("light {i} of the light path at frame {frame}"))
            })
            .collect()
    }
}

impl PathLight {
    /// The light at time `frame`.
    pub fn at(&self, frame: f64) -> anyhow::Result<LightSpec> {
        let x: Vec<f64> = self.keys.iter().map(|k| k.frame).collect();
        let value = |f: &dyn Fn(&Key) -> f64| {
            let y: Vec<f64> = self.keys.iter().map(f).collect();
            interpolate(self.interpolation, &x, &y, frame)
        };
        let spectrum = match self.keys[0].colour {
            KeyColour::D65 => LightSpectrum::D65,
            KeyColour::Kelvin(_) => LightSpectrum::Blackbody {
                kelvin: value(&|k| match k.colour {
                    KeyColour::Kelvin(t) => t,
                    _ => unreachable_colour(),
                }),
            },
            KeyColour::Rgb(_) => {
                let c = |j: usize| {
                    value(&|k: &Key| match k.colour {
                        KeyColour::Rgb(v) => v[j],
                        _ => unreachable_colour(),
                    }) as f32
                };
                LightSpectrum::Rgb([c(0), c(1), c(2)])
            }
        };
        spectrum.validate()?;
        Ok(LightSpec {
            theta_deg: value(&|k| k.theta_deg),
            phi_deg: value(&|k| k.phi_deg),
            intensity: value(&|k| k.intensity),
            spectrum,
        })
    }
}

/// Parsing checks that every key of a light gives its colour the same way.
fn unreachable_colour() -> f64 {
    unreachable!("every key of a light gives its colour the same way (checked when read)")
}

/// The value at `t` of the curve through `(x[k], y[k])` (`x` increasing, not empty), held
/// constant outside `x`. At a keyframe it is that keyframe's value exactly.
pub fn interpolate(how: Interpolation, x: &[f64], y: &[f64], t: f64) -> f64 {
    let n = x.len();
    if n == 1 || t <= x[0] {
        return y[0];
    }
    if t >= x[n - 1] {
        return y[n - 1];
    }
    // The segment x[k] ≤ t < x[k + 1].
    let k = x.partition_point(|&v| v <= t) - 1;
    let h = x[k + 1] - x[k];
    let s = (t - x[k]) / h;
    match how {
        Interpolation::Linear => y[k] + (y[k + 1] - y[k]) * s,
        Interpolation::Smooth => {
            let m = monotone_slopes(x, y);
            // Cubic Hermite basis: p(s) = h00 y0 + h10 h m0 + h01 y1 + h11 h m1.
            let s2 = s * s;
            let s3 = s2 * s;
            let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
            let h10 = s3 - 2.0 * s2 + s;
            let h01 = -2.0 * s3 + 3.0 * s2;
            let h11 = s3 - s2;
            h00 * y[k] + h10 * h * m[k] + h01 * y[k + 1] + h11 * h * m[k + 1]
        }
    }
}

/// Fritsch–Carlson slopes of the monotone cubic through `(x, y)`: secants `d_k`, the mean of
/// the neighbouring secants inside (0 where they differ in sign or one is 0), one-sided at the
/// ends, then scaled down where `α² + β² > 9` (α = m_k/d_k, β = m_{k+1}/d_k) so no segment
/// overshoots.
fn monotone_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let d: Vec<f64> = (0..n - 1)
        .map(|k| (y[k + 1] - y[k]) / (x[k + 1] - x[k]))
        .collect();
    let mut m = vec![0.0; n];
    m[0] = d[0];
    m[n - 1] = d[n - 2];
    for k in 1..n - 1 {
        m[k] = if d[k - 1] * d[k] <= 0.0 {
            0.0
        } else {
            0.5 * (d[k - 1] + d[k])
        };
    }
    for k in 0..n - 1 {
        if d[k] == 0.0 {
            m[k] = 0.0;
            m[k + 1] = 0.0;
            continue;
        }
        let a = m[k] / d[k];
        let b = m[k + 1] / d[k];
        let r = a * a + b * b;
        if r > 9.0 {
            let tau = 3.0 / r.sqrt();
            m[k] = tau * a * d[k];
            m[k + 1] = tau * b * d[k];
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    const PATH: &str = r#"
[[light]]
interpolation = "smooth"
key = [
  { frame = 1, theta = 2, phi = 30 },
  { frame = 5, theta = 10, phi = 90, intensity = 2 },
  { frame = 9, theta = 4, phi = 120 },
]

[[light]]
[[light.key]]
frame = 0
theta = 5
phi = 0
colour = 3200
[[light.key]]
frame = 10
theta = 15
phi = 0
colour = "5600"
"#;

    #[test]
    fn keyframes_are_met_exactly_and_held_outside() {
        let p = LightPath::parse(PATH, "p.toml").unwrap();
        assert_eq!(p.lights.len(), 2);
        for light in &p.lights {
            for k in &light.keys {
                let l = light.at(k.frame).unwrap();
                assert_eq!((l.theta_deg, l.phi_deg), (k.theta_deg, k.phi_deg));
                assert_eq!(l.intensity, k.intensity);
            }
        }
        assert_eq!(p.lights[0].at(-3.0).unwrap().theta_deg, 2.0);
        assert_eq!(p.lights[0].at(100.0).unwrap().theta_deg, 4.0);
        // Linear: half way between 5° and 15° at frame 5.
        assert_eq!(p.lights[1].at(5.0).unwrap().theta_deg, 10.0);
        assert_eq!(
            p.lights[1].at(5.0).unwrap().spectrum,
            LightSpectrum::Blackbody { kelvin: 4400.0 }
        );
    }

    #[test]
    fn smooth_interpolation_does_not_overshoot_its_keyframes() {
        let x = [0.0, 1.0, 2.0, 6.0];
        let y = [0.0, 10.0, 10.5, 0.0];
        for i in 0..=600 {
            let t = i as f64 / 100.0;
            let v = interpolate(Interpolation::Smooth, &x, &y, t);
            let seg = x.partition_point(|&a| a <= t).clamp(1, 3);
            let (lo, hi) = (y[seg - 1].min(y[seg]), y[seg - 1].max(y[seg]));
            assert!(v >= lo - 1e-12 && v <= hi + 1e-12, "{t}: {v}");
        }
        // Two keys: the smooth curve is the straight line.
        let v = interpolate(Interpolation::Smooth, &[0.0, 4.0], &[1.0, 3.0], 1.0);
        assert!((v - 1.5).abs() < 1e-12);
    }

    #[test]
    fn bad_files_are_refused_with_file_line_and_field() {
        let cases = [
            (
                "[[light]]\nkey = [{ frame = 1, theta = 95, phi = 0 }]\n",
                "p.toml:2:",
                "`theta`",
            ),
            (
                "[[light]]\nkey = [{ frame = 1, theta = 5 }]\n",
                "p.toml:2:",
                "phi",
            ),
            (
                "[[light]]\ninterpolation = \"cubic\"\nkey = [{ frame = 1, theta = 5, phi = 0 }]\n",
                "p.toml:2:",
                "`interpolation`",
            ),
            (
                "[[light]]\nkey = [\n { frame = 2, theta = 5, phi = 0 },\n { frame = 1, theta = 5, phi = 0 },\n]\n",
                "p.toml:4:",
                "`frame`",
            ),
            (
                "[[light]]\nkey = [{ frame = 1, theta = 5, phi = 0, intensity = -1 }]\n",
                "p.toml:2:",
                "`intensity`",
            ),
            (
                "[[light]]\nkey = [{ frame = 1, theta = 5, phi = 0, colour = \"red\" }]\n",
                "p.toml:2:",
                "`colour`",
            ),
            (
                "[[light]]\nkey = [{ frame = 1, theta = 5, phi = 0, speed = 3 }]\n",
                "p.toml:2:",
                "speed",
            ),
            ("[[light]]\nkey = [{ frame = 1, theta = \n", "p.toml:2:", ""),
        ];
        for (text, at, field) in cases {
            let e = LightPath::parse(text, "p.toml").unwrap_err();
            assert!(e.starts_with(at) && e.contains(field), "{text:?}: {e}");
        }
    }
}
