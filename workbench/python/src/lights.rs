//! Lights from Python, read as the CLI reads `--light` and `--light-at`: each is written out
//! as the option's text (numbers in Rust's shortest round-trip form, so they parse back to
//! the same bits) and parsed by the same function, so a light means what it means on the
//! command line.
//!
//! A light is a string (`"8,60"`, `"8,60,2,3200"`), a tuple or list
//! `(θ°, φ°[, intensity[, colour]])`, or a dict `{"theta": θ°, "phi": φ°, "intensity": …,
//! "colour": …}`; a dict with `"x"` and `"y"` instead places the light by where it images
//! (pixels from the top-left corner, `--light-at`). A colour is a blackbody temperature in
//! kelvin or linear sRGB `(r, g, b)`. `lights` is a list of them, or one light alone.

use flarebench::cli::render::LightAt;
use flarebench_sdk::LensSystem;
use flarebench_sdk::frame::Frame;
use ghost_raytrace::scene::LightSpec;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// One light as given: by direction, or by where it images.
#[derive(Debug)]
pub enum LightInput {
    Direction(LightSpec),
    At(LightAt),
}

impl LightInput {
    /// The light's direction: `At` aimed by the lens's real chief ray, as `--light-at` is.
    pub fn resolve(&self, system: &LensSystem, frame: &Frame) -> anyhow::Result<LightSpec> {
        match self {
            LightInput::Direction(spec) => Ok(spec.clone()),
            LightInput::At(at) => {
                let (theta, phi) = flarebench::sources::direction_of(system, frame, at.x, at.y)
                    .map_err(|e| e.context(format!("light at pixel {},{}", at.x, at.y)))?;
                at.with_direction(theta, phi).map_err(anyhow::Error::msg)
            }
        }
    }
}

fn bad(msg: String) -> PyErr {
    PyValueError::new_err(msg)
}

/// A number as the CLI's text would hold it.
fn number(v: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    let x: f64 = v
        .extract()
        .map_err(|_| bad(format!("light {what} `{v}` is not a number")))?;
    Ok(format!("{x}"))
}

/// The `COLOUR` field: a temperature, `(r, g, b)`, or text as the CLI takes it.
fn colour(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(s.to_cow()?.into_owned());
    }
    if let Ok(rgb) = v.extract::<Vec<Bound<'_, PyAny>>>() {
        if rgb.len() != 3 {
            return Err(bad(format!("light colour `{v}` is not (r, g, b)")));
        }
        let parts: Vec<String> = rgb
            .iter()
            .map(|c| number(c, "colour component"))
            .collect::<PyResult<_>>()?;
        return Ok(parts.join(":"));
    }
    number(v, "colour (kelvin)")
}

/// `INTENSITY[,COLOUR]` from optional values (an empty string when neither is given).
fn rest(intensity: Option<&Bound<'_, PyAny>>, col: Option<&Bound<'_, PyAny>>) -> PyResult<String> {
    let mut out = Vec::new();
    match (intensity, col) {
        (None, None) => {}
        (i, c) => {
            out.push(match i {
                Some(i) => number(i, "intensity")?,
                None => "1".to_string(),
            });
            if let Some(c) = c {
                out.push(colour(c)?);
            }
        }
    }
    Ok(out.join(","))
}

fn direction(text: &str) -> PyResult<LightInput> {
    LightSpec::parse(text)
        .map(LightInput::Direction)
        .map_err(|e| bad(e.to_string()))
}

fn at(x: &Bound<'_, PyAny>, y: &Bound<'_, PyAny>, rest: String) -> PyResult<LightInput> {
    let mut text = format!("{},{}", number(x, "x")?, number(y, "y")?);
    if !rest.is_empty() {
        text = format!("{text},{rest}");
    }
    LightAt::parse(&text).map(LightInput::At).map_err(bad)
}

/// One light from a string, a sequence or a dict.
fn light(v: &Bound<'_, PyAny>) -> PyResult<LightInput> {
    if let Ok(s) = v.cast::<PyString>() {
        return direction(&s.to_cow()?);
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let get = |k: &str| d.get_item(k);
        let col = match get("colour")? {
            Some(c) => Some(c),
            None => get("color")?,
        };
        let known = ["theta", "phi", "x", "y", "intensity", "colour", "color"];
        for k in d.keys() {
            let k: String = k.extract()?;
            if !known.contains(&k.as_str()) {
                return Err(bad(format!(
                    "light key `{k}` is not one of theta, phi, x, y, intensity, colour"
                )));
            }
        }
        let rest = rest(get("intensity")?.as_ref(), col.as_ref())?;
        return match (get("theta")?, get("phi")?, get("x")?, get("y")?) {
            (Some(t), Some(p), None, None) => {
                let mut text = format!("{},{}", number(&t, "theta")?, number(&p, "phi")?);
                if !rest.is_empty() {
                    text = format!("{text},{rest}");
                }
                direction(&text)
            }
            (None, None, Some(x), Some(y)) => at(&x, &y, rest),
            _ => Err(bad(format!(
                "light {d} needs either `theta` and `phi` or `x` and `y`"
            ))),
        };
    }
    let items: Vec<Bound<'_, PyAny>> = v.extract().map_err(|_| {
        bad(format!(
            "light `{v}` is not a string, a (theta, phi[, intensity[, colour]]) tuple or a dict"
        ))
    })?;
    if !(2..=4).contains(&items.len()) {
        return Err(bad(format!(
            "light `{v}` is not (theta, phi[, intensity[, colour]])"
        )));
    }
    let mut text = format!(
        "{},{}",
        number(&items[0], "theta")?,
        number(&items[1], "phi")?
    );
    let rest = rest(items.get(2), items.get(3))?;
    if !rest.is_empty() {
        text = format!("{text},{rest}");
    }
    direction(&text)
}

/// `lights`: a list of lights, or one light (a string, a dict, or a tuple of numbers).
pub fn lights(v: &Bound<'_, PyAny>) -> PyResult<Vec<LightInput>> {
    let single = v.cast::<PyString>().is_ok()
        || v.cast::<PyDict>().is_ok()
        || v.extract::<Vec<Bound<'_, PyAny>>>()
            .ok()
            .and_then(|items| items.first().map(|f| f.extract::<f64>().is_ok()))
            .unwrap_or(false);
    let out = if single {
        vec![light(v)?]
    } else {
        let items: Vec<Bound<'_, PyAny>> = v
            .extract()
            .map_err(|_| bad(format!("lights `{v}` is not a list of lights")))?;
        items.iter().map(light).collect::<PyResult<Vec<_>>>()?
    };
    if out.is_empty() {
        return Err(bad("lights: at least one light is needed".to_string()));
    }
    Ok(out)
}
