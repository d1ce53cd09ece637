//! Zemax multi-configuration data (zoom and focus positions): `MNUM count active`, then one
//! record per operand and configuration, `OPER index config value …` — for example
//! `THIC 5 2 12.7 …` sets surface 5's thickness to 12.7 lens units in configuration 2.
//!
//! Applied: `THIC` (thickness), `CRVT` (curvature), `CONN` (conic), `SDIA` (semi-diameter) and
//! `APER` (the system aperture value: ENPD, FNUM or OBNA, whichever the file uses). Other
//! operands that change the lens are reported as not applied.

use crate::io::LensFileError;
use crate::io::located::Reporter;

use super::records::{Record, Records};

/// What a configuration operand sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Target {
    Thickness,
    Curvature,
    Conic,
    SemiDiameter,
    Aperture,
}

/// One value of the selected configuration.
#[derive(Clone, Copy, Debug)]
pub(super) struct Setting {
    pub target: Target,
    /// The Zemax surface number (0 for `APER`).
    pub surface: usize,
    /// In lens units (1/lens unit for curvature).
    pub value: f64,
    /// Byte offset of the value.
    pub pos: usize,
}

/// Operands that change the optics but are not applied.
const NOT_APPLIED: &[&str] = &[
    "GLSS", "PRAM", "PAR1", "PAR2", "XFIE", "YFIE", "WAVE", "PWAV",
];

/// The configuration count and active configuration (`MNUM`, default 1 of 1).
pub(super) fn count(
    ctx: &Reporter<'_>,
    recs: &Records<'_>,
) -> Result<(usize, usize), LensFileError> {
    match recs.get("MNUM") {
        Some(r) => {
            let n = r.integer(ctx, 0)?.max(1);
            let active = match r.arg(1) {
                Some(_) => r.integer(ctx, 1)?.clamp(1, n),
                None => 1,
            };
            Ok((n, active))
        }
        None => Ok((1, 1)),
    }
}

fn target(key: &str) -> Option<Target> {
    Some(match key {
        "THIC" => Target::Thickness,
        "CRVT" => Target::Curvature,
        "CONN" => Target::Conic,
        "SDIA" => Target::SemiDiameter,
        "APER" => Target::Aperture,
        _ => return None,
    })
}

/// A configuration record has at least an index, a configuration number and a value.
fn is_config_record(r: &Record<'_>) -> bool {
    r.args.len() >= 3
        && r.args[..2]
            .iter()
            .all(|(_, t)| t.bytes().all(|b| b.is_ascii_digit()))
}

/// The settings of configuration `config` (1-based), checked against the count; warns about
/// operands that are not applied.
pub(super) fn settings(
    ctx: &mut Reporter<'_>,
    recs: &Records<'_>,
    config: usize,
    total: usize,
) -> Result<Vec<Setting>, LensFileError> {
    if config == 0 || config > total {
        let (pos, field) = recs.get("MNUM").map_or((0, ""), |r| (r.pos, "MNUM"));
        let have = if total == 1 {
            "the file has one configuration".to_string()
        } else {
            format!("the file has configurations 1 to {total}")
        };
        return Err(ctx.error(
            pos,
            field,
            format!("configuration {config} was asked for, but {have}"),
        ));
    }
    let mut out = Vec::new();
    let mut skipped: Vec<(&str, usize)> = Vec::new();
    for r in recs.system.iter().filter(|r| is_config_record(r)) {
        let Some(t) = target(r.key) else {
            if NOT_APPLIED.contains(&r.key) && !skipped.iter().any(|(k, _)| *k == r.key) {
                skipped.push((r.key, r.pos));
            }
            continue;
        };
        if r.integer(ctx, 1)? != config {
            continue;
        }
        let value = r.number(ctx, 2)?;
        out.push(Setting {
            target: t,
            surface: r.integer(ctx, 0)?,
            value,
            pos: r.arg_pos(2),
        });
    }
    for (key, pos) in skipped {
        ctx.warn(
            pos,
            format!("multi-configuration operand {key} is not applied (configuration {config})"),
        );
    }
    Ok(out)
}
