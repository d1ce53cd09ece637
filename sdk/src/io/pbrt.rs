//! PBRT realistic-camera lens tables (`.dat`): one row per surface, object side first, four
//! numbers each — radius of curvature, a thickness, the refractive index after the surface and
//! the aperture **diameter** (mm). `#` starts a comment.
//!
//! The second column comes in two conventions ([`PbrtConvention`]): pbrt's own, the thickness
//! after each surface (the `*.NNmm.dat` files of pbrt-v4-scenes, whose last row is 0: pbrt
//! focuses the film itself), and the separation before each surface (the unscaled tables from
//! Smith's *Modern Lens Design*, such as `dgauss.dat`, whose first row is 0).
//!
//! A row with radius 0 is the aperture stop (pbrt allows flat surfaces only as apertures); an
//! index of 0 means air, as in pbrt. The tables give nd alone, so every glass is a
//! non-dispersive model glass. The sensor is placed at the table's film distance, or at the
//! paraxial focus when the table leaves it to pbrt. See `docs/formats.md`.

use std::str::FromStr;

use super::located::Reporter;
use super::text::tokens;
use super::{LensFileError, LoadedLens};
use crate::paraxial::analyse;
use crate::spectrum::LAMBDA_D_NM;
use crate::system::{LensSystem, Medium, Surface, SurfaceKind, ValidationIssue};

/// What the second column of a PBRT table means.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PbrtConvention {
    /// pbrt's convention: the distance from this surface to the next; the last row's is the
    /// distance to the film, 0 when pbrt is to focus it.
    ThicknessAfter,
    /// The distance from the previous surface to this one; the first row's is 0.
    SeparationBefore,
}

impl PbrtConvention {
    /// The name used on the command line and in messages.
    pub fn name(self) -> &'static str {
        match self {
            PbrtConvention::ThicknessAfter => "thickness-after",
            PbrtConvention::SeparationBefore => "separation-before",
        }
    }
}

impl FromStr for PbrtConvention {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "thickness-after" => Ok(PbrtConvention::ThicknessAfter),
            "separation-before" => Ok(PbrtConvention::SeparationBefore),
            other => Err(format!(
                "unknown PBRT convention `{other}`; expected thickness-after or separation-before"
            )),
        }
    }
}

/// Film size given to PBRT lenses (full-frame 35 mm), as for the bundled library.
const FILM_MM: (f64, f64) = (36.0, 24.0);

/// Column names, used as the `field` of errors.
const COLUMNS: [&str; 4] = ["radius", "thickness", "index", "aperture"];

/// One table row: its four numbers and the byte offset of each.
#[derive(Clone, Copy, Debug)]
struct Row {
    values: [f64; 4],
    pos: [usize; 4],
}

impl Row {
    fn radius(&self) -> f64 {
        self.values[0]
    }
    fn thickness(&self) -> f64 {
        self.values[1]
    }
    fn index(&self) -> f64 {
        self.values[2]
    }
    fn aperture(&self) -> f64 {
        self.values[3]
    }
}

/// Parses a PBRT lens table and validates the system. `file_label` names the file in errors
/// and warnings (and gives the lens its name and, from a `NNmm` part, its stated focal length);
/// `convention` overrides the detection of the second column's meaning.
pub fn parse_pbrt(
    text: &str,
    file_label: &str,
    convention: Option<PbrtConvention>,
) -> Result<LoadedLens, LensFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ctx = Reporter::new(file_label, text);
    let (rows, comments) = read_rows(&ctx, text)?;
    let Some((first, last)) = rows.first().zip(rows.last()) else {
        return Err(ctx.error(
            text.len(),
            "",
            "no lens rows: a PBRT table has one row per surface \
             (radius, thickness, index, aperture diameter)",
        ));
    };
    let convention = match convention {
        Some(c) => c,
        None => detect(&mut ctx, first, last, rows.len())?,
    };
    for row in &rows {
        check_row(&ctx, row)?;
    }

    // Which row gives each surface's thickness, and the film distance (None: focus).
    let (thickness_rows, film): (Vec<Option<&Row>>, Option<f64>) = match convention {
        PbrtConvention::ThicknessAfter => (
            rows.iter().map(Some).collect(),
            Some(last.thickness()).filter(|t| *t != 0.0),
        ),
        PbrtConvention::SeparationBefore => {
            if first.thickness() != 0.0 {
                ctx.warn(
                    first.pos[1],
                    format!(
                        "the separation in front of the first surface ({} mm) is ignored: \
                         the object is at infinity",
                        first.thickness()
                    ),
                );
            }
            let mut v: Vec<Option<&Row>> = rows.iter().skip(1).map(Some).collect();
            v.push(None);
            (v, None)
        }
    };

    let mut surfaces = Vec::with_capacity(rows.len() + 1);
    let mut stop_row: Option<&Row> = None;
    for (row, thickness_row) in rows.iter().zip(&thickness_rows) {
        let medium = match row.index() {
            0.0 | 1.0 => Medium::Air,
            n => Medium::Model { nd: n, vd: None },
        };
        let thickness = thickness_row.map_or(0.0, Row::thickness);
        let semi_diameter = row.aperture() / 2.0;
        let surface = if row.radius() != 0.0 {
            Surface::spherical(row.radius(), thickness, medium, semi_diameter)
        } else if stop_row.is_none() {
            if !medium.is_air() {
                ctx.warn(
                    row.pos[2],
                    format!(
                        "the stop row gives index {}: the medium after the stop is taken as \
                         that glass (pbrt rows usually give 0, air)",
                        row.index()
                    ),
                );
            }
            stop_row = Some(row);
            Surface {
                kind: SurfaceKind::ApertureStop,
                ..Surface::spherical(0.0, thickness, medium, semi_diameter)
            }
        } else {
            ctx.warn(
                row.pos[0],
                "a second row with radius 0: pbrt treats it as another aperture; it is read as \
                 a flat surface that clips rays at its semi-diameter (one stop per system)",
            );
            Surface::spherical(0.0, thickness, medium, semi_diameter)
        };
        surfaces.push(surface);
    }
    if stop_row.is_none() {
        return Err(ctx.error(
            first.pos[0],
            "radius",
            "no aperture stop: one row must have radius 0 (pbrt's stop row)",
        ));
    }
    let half_diagonal = 0.5 * FILM_MM.0.hypot(FILM_MM.1);
    surfaces.push(Surface::sensor(half_diagonal));

    let stem = std::path::Path::new(file_label)
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = stem
        .strip_suffix(".dat")
        .or_else(|| stem.strip_suffix(".DAT"))
        .unwrap_or(&stem)
        .to_string();
    let mut system = LensSystem::new(&name, surfaces);
    system.film_width_mm = FILM_MM.0;
    system.film_height_mm = FILM_MM.1;
    system.stated_efl_mm = stated_focal_length(&name);
    system.source = format!("PBRT realistic-camera lens table {stem}");

    let mut notes = Vec::new();
    if !comments.is_empty() {
        notes.push(format!("Table header: {}.", comments.join("; ")));
    }
    notes.push(format!(
        "Read as PBRT `{}`: {}.",
        convention.name(),
        match convention {
            PbrtConvention::ThicknessAfter =>
                "column 2 is the thickness after each surface (pbrt's convention)",
            PbrtConvention::SeparationBefore => "column 2 is the separation before each surface",
        }
    ));
    notes.push(
        "PBRT tables give nd only: every glass is non-dispersive. Semi-diameters are half the \
         table's aperture diameters; uncoated."
            .into(),
    );

    // Locations of every field, for validation errors: surface i's thickness comes from
    // `thickness_rows[i]`.
    let spans: Vec<[usize; 4]> = rows
        .iter()
        .zip(&thickness_rows)
        .map(|(r, t)| {
            let mut p = r.pos;
            p[1] = t.map_or(r.pos[0], |t| t.pos[1]);
            p
        })
        .collect();
    let sensor_gap = system.surfaces.len() - 2;
    match film {
        Some(d) => system.surfaces[sensor_gap].thickness = d,
        None => {
            // The film is at the paraxial focus of an object at infinity (indices are
            // constant, so the wavelength does not matter).
            let bfl = match analyse(&system, LAMBDA_D_NM) {
                Ok(p) => p.bfl_mm,
                Err(e) => return Err(ctx.error(last.pos[0], "radius", e.to_string())),
            };
            if !(bfl.is_finite() && bfl > 0.0) {
                return Err(ctx.error(
                    last.pos[0],
                    "radius",
                    format!(
                        "the paraxial focus lies {:.3} mm in front of the last surface: there \
                         is no film position behind the lens",
                        -bfl
                    ),
                ));
            }
            system.surfaces[sensor_gap].thickness = bfl;
            notes.push(format!(
                "The table leaves the film distance to pbrt: the sensor is placed at the \
                 paraxial focus for an object at infinity, {bfl:.6} mm behind the last surface."
            ));
        }
    }
    system.notes = notes.join("\n");

    if let Err(issues) = system.validate() {
        return Err(located(&ctx, &spans, &issues));
    }
    Ok(LoadedLens {
        system,
        warnings: ctx.warnings,
    })
}

/// The rows and the comment lines (without `#`) of the table.
fn read_rows(ctx: &Reporter<'_>, text: &str) -> Result<(Vec<Row>, Vec<String>), LensFileError> {
    let mut rows = Vec::new();
    let mut comments = Vec::new();
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let line_start = start;
        start += line.len();
        let (data, comment) = match line.find('#') {
            Some(i) => (&line[..i], Some(&line[i + 1..])),
            None => (line, None),
        };
        if let Some(c) = comment {
            let c = c.trim().trim_matches('"').trim();
            if !c.is_empty() && rows.is_empty() {
                comments.push(c.to_string());
            }
        }
        let tokens: Vec<(usize, &str)> = tokens(data)
            .into_iter()
            .map(|(off, t)| (line_start + off, t))
            .collect();
        if tokens.is_empty() {
            continue;
        }
        if tokens.len() != 4 {
            let at = tokens.get(4).map_or(tokens[0].0, |t| t.0);
            return Err(ctx.error(
                at,
                "",
                format!(
                    "expected 4 numbers (radius, thickness, index, aperture diameter), found {}",
                    tokens.len()
                ),
            ));
        }
        let mut row = Row {
            values: [0.0; 4],
            pos: [0; 4],
        };
        for (k, (pos, t)) in tokens.into_iter().enumerate() {
            let v: f64 = t
                .parse()
                .map_err(|_| ctx.error(pos, COLUMNS[k], format!("expected a number, got `{t}`")))?;
            if !v.is_finite() {
                return Err(ctx.error(pos, COLUMNS[k], format!("must be finite, got {t}")));
            }
            row.values[k] = v;
            row.pos[k] = pos;
        }
        rows.push(row);
    }
    Ok((rows, comments))
}

/// Per-row checks that the model's validation cannot phrase in the table's terms.
fn check_row(ctx: &Reporter<'_>, row: &Row) -> Result<(), LensFileError> {
    if row.aperture() <= 0.0 {
        return Err(ctx.error(
            row.pos[3],
            "aperture",
            format!(
                "the aperture diameter must be > 0 mm, got {}",
                row.aperture()
            ),
        ));
    }
    let n = row.index();
    if n != 0.0 && n < 1.0 {
        return Err(ctx.error(
            row.pos[2],
            "index",
            format!("the refractive index must be ≥ 1 (0 means air), got {n}"),
        ));
    }
    if row.thickness() < 0.0 {
        return Err(ctx.error(
            row.pos[1],
            "thickness",
            format!(
                "must be ≥ 0 mm, got {} (negative distances, as behind a mirror, are not \
                 supported)",
                row.thickness()
            ),
        ));
    }
    Ok(())
}

/// The convention from the zeros. pbrt's tables end with 0 (the film distance left to pbrt)
/// or with the film distance; separation tables start with 0 (nothing lies in front of the
/// first surface). A table whose first row is 0 and last is not reads as separations; one
/// whose first row is not 0 reads as pbrt's (a separation in front of the first surface would
/// mean nothing for an object at infinity); both 0 is ambiguous.
fn detect(
    ctx: &mut Reporter<'_>,
    first: &Row,
    last: &Row,
    n_rows: usize,
) -> Result<PbrtConvention, LensFileError> {
    let (f, l) = (first.thickness() == 0.0, last.thickness() == 0.0);
    match (f, l) {
        (false, _) => Ok(PbrtConvention::ThicknessAfter),
        (true, false) => {
            ctx.warn(
                first.pos[1],
                "column 2 read as the separation before each surface (the first row's is 0, \
                 the last row's is not); use the `thickness-after` convention if that is wrong",
            );
            Ok(PbrtConvention::SeparationBefore)
        }
        (true, true) if n_rows == 1 => Ok(PbrtConvention::ThicknessAfter),
        (true, true) => Err(ctx.error(
            first.pos[1],
            "thickness",
            "cannot tell what column 2 means: the first and the last row both give 0; pbrt's \
             thickness-after tables end with 0, separation-before tables start with 0; choose \
             the convention explicitly (--pbrt-convention)",
        )),
    }
}

/// The focal length in a pbrt-v4-scenes file name such as `dgauss.50mm`.
fn stated_focal_length(name: &str) -> Option<f64> {
    name.split('.')
        .filter_map(|part| part.strip_suffix("mm"))
        .find_map(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0)
}

/// The first validation issue at its row and column, the others listed in its message.
fn located(ctx: &Reporter<'_>, spans: &[[usize; 4]], issues: &[ValidationIssue]) -> LensFileError {
    let errors = issues
        .iter()
        .map(|issue| {
            let column = match issue.field {
                "thickness" => 1,
                "refractiveIndex" | "abbeNumber" => 2,
                "height" => 3,
                _ => 0,
            };
            let pos = issue
                .surface
                .and_then(|s| spans.get(s))
                .or(spans.last())
                .map_or(0, |p| p[column]);
            ctx.error(pos, COLUMNS[column], issue.message.clone())
        })
        .collect();
    Reporter::combine(errors).expect("validation failed with at least one issue")
}

#[cfg(test)]
mod tests;
