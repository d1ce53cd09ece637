//! The system records of a `.zmx` file: lens units (`UNIT`), name and notes, glass catalogues
//! (`GCAT`), wavelengths (`WAVM`, `PWAV`), fields (`FTYP`, `XFLN`, `YFLN`) and the system
//! aperture (`ENPD`, `FNUM`, `OBNA`, `FLOA`).

use crate::glass::GlassCatalog;
use crate::io::LensFileError;
use crate::io::located::Reporter;

use super::records::Records;

/// Lens units: their name and millimetres per unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Units {
    pub name: &'static str,
    pub mm: f64,
}

/// `UNIT MM|CM|IN|METER …` (default millimetres).
pub(super) fn units(ctx: &Reporter<'_>, recs: &Records<'_>) -> Result<Units, LensFileError> {
    let Some(r) = recs.get("UNIT") else {
        return Ok(Units {
            name: "MM",
            mm: 1.0,
        });
    };
    let (name, mm) = match r.arg(0).map(str::to_ascii_uppercase).as_deref() {
        Some("MM") => ("MM", 1.0),
        Some("CM") => ("CM", 10.0),
        Some("IN" | "INCH" | "INCHES") => ("IN", 25.4),
        Some("METER" | "METERS" | "M") => ("METER", 1000.0),
        other => {
            return Err(ctx.error(
                r.arg_pos(0),
                "UNIT",
                format!(
                    "unknown lens unit `{}`; expected MM, CM, IN or METER",
                    other.unwrap_or("")
                ),
            ));
        }
    };
    Ok(Units { name, mm })
}

/// The catalogues of `GCAT`, upper case, in the file's order, mapped to the bundled
/// catalogue's names (`OHARA_2021-04` → `OHARA`); unknown ones are kept (they match nothing).
pub(super) fn catalogues(recs: &Records<'_>) -> Vec<String> {
    let known: Vec<&str> = {
        let mut v: Vec<&str> = GlassCatalog::bundled()
            .entries()
            .iter()
            .map(|e| e.catalog.as_str())
            .collect();
        v.dedup();
        v
    };
    recs.get("GCAT")
        .map(|r| {
            r.args
                .iter()
                .map(|(_, t)| {
                    let up = t.to_ascii_uppercase();
                    match up.split_once('_') {
                        Some((base, _)) if !known.contains(&up.as_str()) => base.to_string(),
                        _ => up,
                    }
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The primary wavelength in nm (`WAVM i λµm w` and `PWAV i`; older files `WAVL λ…`), with the
/// byte offset of its record; `None` when the file gives no wavelengths.
pub(super) fn primary_wavelength(
    ctx: &mut Reporter<'_>,
    recs: &Records<'_>,
) -> Result<Option<(f64, usize)>, LensFileError> {
    let mut waves: Vec<(usize, f64, usize)> = Vec::new();
    for r in recs.all("WAVM") {
        waves.push((r.integer(ctx, 0)?, r.number(ctx, 1)?, r.arg_pos(1)));
    }
    if waves.is_empty()
        && let Some(r) = recs.get("WAVL")
    {
        for i in 0..r.args.len() {
            waves.push((i + 1, r.number(ctx, i)?, r.arg_pos(i)));
        }
    }
    if waves.is_empty() {
        return Ok(None);
    }
    let (primary, ppos) = match recs.get("PWAV") {
        Some(r) => (r.integer(ctx, 0)?, r.arg_pos(0)),
        None => (1, waves[0].2),
    };
    let Some(&(_, um, pos)) = waves.iter().find(|w| w.0 == primary) else {
        ctx.warn(
            ppos,
            format!(
                "PWAV names wavelength {primary}, which the file does not define; using the d line"
            ),
        );
        return Ok(None);
    };
    if um.is_nan() || um <= 0.0 {
        return Err(ctx.error(
            pos,
            "WAVM",
            format!("the primary wavelength must be positive (µm), got {um}"),
        ));
    }
    // µm → nm, rounded to 1e-9 nm so that 0.58756180000000002 µm reads as 587.5618 nm.
    let nm = format!("{:.9}", um * 1e3).parse().unwrap_or(um * 1e3);
    Ok(Some((nm, pos)))
}

/// How the file gives its field points (`FTYP` first number).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum FieldKind {
    /// Angle in object space, degrees.
    Angle,
    /// Object height, lens units.
    ObjectHeight,
    /// Paraxial image height, lens units.
    ParaxialImageHeight,
    /// Real image height, lens units.
    RealImageHeight,
    Other(usize),
}

/// The largest field point: its kind, radial value (degrees, or mm for heights) and record.
#[derive(Clone, Copy, Debug)]
pub(super) struct MaxField {
    pub kind: FieldKind,
    pub value: f64,
    pub pos: usize,
}

/// The largest radial field `√(x² + y²)` among the file's field points (`FTYP type 0 count …`,
/// `XFLN`/`YFLN`, or the older `XFLD`/`YFLD`). Heights are converted to mm.
pub(super) fn max_field(
    ctx: &Reporter<'_>,
    recs: &Records<'_>,
    units: Units,
) -> Result<Option<MaxField>, LensFileError> {
    let (kind, count, pos) = match recs.get("FTYP") {
        Some(r) => {
            let kind = match r.integer(ctx, 0)? {
                0 => FieldKind::Angle,
                1 => FieldKind::ObjectHeight,
                2 => FieldKind::ParaxialImageHeight,
                3 => FieldKind::RealImageHeight,
                k => FieldKind::Other(k),
            };
            let count = match r.arg(2) {
                Some(_) => Some(r.integer(ctx, 2)?),
                None => None,
            };
            (kind, count, r.pos)
        }
        None => (FieldKind::Angle, None, 0),
    };
    let values = |key: &str, alt: &str| -> Result<Vec<f64>, LensFileError> {
        match recs.get(key).or_else(|| recs.get(alt)) {
            Some(r) => (0..r.args.len()).map(|i| r.number(ctx, i)).collect(),
            None => Ok(Vec::new()),
        }
    };
    let xs = values("XFLN", "XFLD")?;
    let ys = values("YFLN", "YFLD")?;
    let n = count.unwrap_or(xs.len().max(ys.len()));
    let scale = if kind == FieldKind::Angle {
        1.0
    } else {
        units.mm
    };
    let value = (0..n)
        .map(|i| {
            let x = xs.get(i).copied().unwrap_or(0.0);
            let y = ys.get(i).copied().unwrap_or(0.0);
            x.hypot(y) * scale
        })
        .fold(0.0, f64::max);
    let pos = recs
        .get("YFLN")
        .or_else(|| recs.get("YFLD"))
        .map_or(pos, |r| r.pos);
    Ok((n > 0).then_some(MaxField { kind, value, pos }))
}

/// The system aperture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Aperture {
    /// Entrance pupil diameter (`ENPD`), mm.
    EntrancePupil(f64),
    /// Image-space or paraxial working f-number (`FNUM value 0|1`): for an object at infinity
    /// both are EFL / EPD.
    FNumber(f64),
    /// Object-space numerical aperture (`OBNA`).
    ObjectNa(f64),
    /// Float by stop size (`FLOA`): the stop surface's semi-diameter.
    FloatByStop,
}

impl Aperture {
    /// The same kind of aperture with another value (a configuration's `APER`), in lens units.
    pub fn with_value(self, v: f64, units: Units) -> Aperture {
        match self {
            Aperture::EntrancePupil(_) => Aperture::EntrancePupil(v * units.mm),
            Aperture::FNumber(_) => Aperture::FNumber(v),
            Aperture::ObjectNa(_) => Aperture::ObjectNa(v),
            Aperture::FloatByStop => Aperture::FloatByStop,
        }
    }
}

/// The last aperture record of the file (Zemax writes one), with its byte offset; float by
/// stop size when there is none.
pub(super) fn aperture(
    ctx: &Reporter<'_>,
    recs: &Records<'_>,
    units: Units,
) -> Result<(Aperture, usize), LensFileError> {
    let Some(r) = recs
        .system
        .iter()
        .rev()
        .find(|r| matches!(r.key, "ENPD" | "FNUM" | "OBNA" | "FLOA"))
    else {
        return Ok((Aperture::FloatByStop, 0));
    };
    let positive = |v: f64| -> Result<f64, LensFileError> {
        if v > 0.0 {
            Ok(v)
        } else {
            Err(ctx.error(
                r.arg_pos(0),
                r.key,
                format!("the system aperture must be positive, got {v}"),
            ))
        }
    };
    let a = match r.key {
        "ENPD" => Aperture::EntrancePupil(positive(r.number(ctx, 0)?)? * units.mm),
        "FNUM" => Aperture::FNumber(positive(r.number(ctx, 0)?)?),
        "OBNA" => {
            let na = positive(r.number(ctx, 0)?)?;
            if na >= 1.0 {
                return Err(ctx.error(
                    r.arg_pos(0),
                    "OBNA",
                    format!("an object-space numerical aperture in air is below 1, got {na}"),
                ));
            }
            Aperture::ObjectNa(na)
        }
        _ => Aperture::FloatByStop,
    };
    Ok((a, r.arg_pos(0)))
}

/// `NOTE` lines joined (Zemax splits long notes over several records; `NOTE 4` lines are
/// paragraph breaks).
pub(super) fn notes(recs: &Records<'_>) -> String {
    let mut text = String::new();
    for r in recs.all("NOTE") {
        let body = r
            .rest
            .split_once(char::is_whitespace)
            .map_or("", |(_, b)| b);
        if r.arg(0) == Some("0") {
            text.push_str(body);
        } else if !text.ends_with('\n') && !text.is_empty() {
            text.push('\n');
        }
    }
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}
