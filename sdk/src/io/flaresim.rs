//! FlareSim `.lens` files: a header (`name:`, `focal_length:`, `#` comments), then after a
//! line `surfaces:` one row per surface, object side first — radius (`stop` for the aperture
//! stop, `0` or `inf` flat), thickness to the next vertex (the last row's is the distance to
//! the sensor), ior (nd) and abbe (Vd) of the medium after the surface, `semi_ap`, coating
//! layers (0, 1, 2), and optionally a surface type (`cyl_x`, `cyl_y`, `toric`) and a second
//! radius. `#` starts a comment anywhere.
//!
//! The `semi_ap` column holds semi-diameters or diameters depending on the file
//! ([`LensApertureConvention`], decided from the data in [`convention`] unless forced); clear
//! apertures that stay impossible are refused, or clamped when the reader is lenient
//! ([`clearance`]). Glasses are model glasses from nd and Vd (the two-term Cauchy fit, as for
//! OpenLensFlare XML); the coating column maps to the stacks of [`coating`]; the f-number
//! comes from the comment header, the name or the file name ([`f_number`]). See
//! `docs/formats.md` §16.

mod clearance;
mod coating;
mod convention;
mod f_number;
mod table;

#[cfg(test)]
mod tests;

use std::path::Path;

use super::located::Reporter;
use super::{LensFileError, LoadedLens};
use crate::paraxial::analyse;
use crate::spectrum::LAMBDA_D_NM;
use crate::system::{LensSystem, Medium, Surface, SurfaceKind, ValidationIssue};
use clearance::round;
use convention::{Evidence, Reading};
use table::{ABBE, COATING, COLUMNS, IOR, RADIUS, Radius, Row, SEMI_AP, THICKNESS, Table};

pub use coating::stack as coating_stack;
pub use convention::LensApertureConvention;

/// Film size given to `.lens` lenses (full-frame 35 mm), as for the other formats.
const FILM_MM: (f64, f64) = (36.0, 24.0);

/// A paraxial focal length longer than this (mm) is no camera lens but a system without
/// power up to rounding (an afocal attachment): the longest lens of FlareSim's library is
/// 1,200 mm.
const AFOCAL_EFL_MM: f64 = 1e5;

/// Parses a FlareSim `.lens` file and validates the system. `file_label` names the file in
/// errors and warnings (and gives the lens its name when the file has none); `aperture`
/// forces what the `semi_ap` column holds (else it is decided from the data, with a
/// warning); `lenient` clamps clear apertures that are still impossible, each with a warning,
/// instead of refusing the lens.
pub fn parse_flaresim(
    text: &str,
    file_label: &str,
    aperture: Option<LensApertureConvention>,
    lenient: bool,
) -> Result<LoadedLens, LensFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ctx = Reporter::new(file_label, text);
    let table = table::read(&mut ctx, text)?;
    if table.rows.is_empty() {
        return Err(ctx.error(
            table.surfaces_pos,
            "surfaces",
            "the surface table is empty: one row per surface follows `surfaces:`",
        ));
    }
    if let Some(f) = &table.focal_length
        && f.value.is_infinite()
    {
        return Err(ctx.error(
            f.pos,
            "focal_length",
            "the file states an infinite focal length: an afocal attachment (a converter), \
             which forms no image on its own; flarebench reads lenses that do",
        ));
    }
    for row in &table.rows {
        check_row(&ctx, row)?;
    }
    let file_name = Path::new(file_label)
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut notes = Vec::new();
    let surfaces = build_surfaces(&mut ctx, &table, &mut notes)?;
    let mut system = new_system(&mut ctx, &table, &file_name, surfaces);

    let (convention, stated) =
        choose_convention(&mut ctx, &table, &system, &file_name, aperture, &mut notes)?;
    for s in &mut system.surfaces[..table.rows.len()] {
        s.semi_diameter *= convention.scale();
    }
    settle_apertures(
        &mut ctx,
        &table,
        &mut system,
        convention,
        lenient,
        &mut notes,
    )?;

    if let Some((n, from)) = stated {
        system.f_number = Some(n);
        notes.push(format!(
            "The f-number setting f/{n} is the one the file states ({from})."
        ));
    }
    notes.push(
        "Glasses are model glasses from the ior (nd) and abbe (Vd) columns. The sensor is at \
         the last row's thickness behind the last surface; the film is taken as 36 × 24 mm."
            .to_string(),
    );
    if !table.comments.is_empty() {
        notes.insert(0, format!("File header: {}", table.comments.join("; ")));
    }
    system.notes = notes.join("\n");

    if let Err(issues) = system.validate() {
        return Err(located(&ctx, &table, &issues));
    }
    Ok(LoadedLens {
        system,
        warnings: ctx.warnings,
    })
}

/// Reads the `semi_ap` column both ways and settles what it holds: as forced, or decided from
/// the data ([`convention`]), said in a warning and in the notes. Returns the convention and
/// the stated f-number. `system` holds the column's values as semi-diameters.
fn choose_convention(
    ctx: &mut Reporter<'_>,
    table: &Table,
    system: &LensSystem,
    file_name: &str,
    aperture: Option<LensApertureConvention>,
    notes: &mut Vec<String>,
) -> Result<(LensApertureConvention, Option<f_number::Stated>), LensFileError> {
    let open_f_number = open_f_number(ctx, table, system)?;
    let stated = f_number::stated(&table.comments, &system.name, file_name);
    let lens_rows = table.rows.len();
    let reading = |scale: f64| {
        let scaled: Vec<Surface> = system.surfaces[..lens_rows]
            .iter()
            .map(|s| Surface {
                semi_diameter: s.semi_diameter * scale,
                ..s.clone()
            })
            .collect();
        Reading {
            impossible: clearance::check(&scaled),
            f_number: Some(open_f_number / scale),
        }
    };
    let evidence = Evidence {
        semi: reading(LensApertureConvention::Semi.scale()),
        diameter: reading(LensApertureConvention::Diameter.scale()),
        stated_f_number: stated,
    };
    let (detected, basis) = evidence.decide();
    let convention = aperture.unwrap_or(detected);
    let lines: Vec<usize> = table.rows.iter().map(|r| r.line).collect();
    let why = evidence.explain(detected, basis, &lines);
    match aperture {
        None => {
            ctx.warn(
                table.surfaces_pos,
                format!(
                    "semi_ap read as {}, decided from the data ({}): {why} (choose with \
                     --lens-aperture semi|diameter)",
                    convention.reading(),
                    basis.label()
                ),
            );
            notes.push(format!(
                "The semi_ap column is read as {}, decided from the data ({}): {why}.",
                convention.reading(),
                basis.label()
            ));
        }
        Some(forced) => {
            if forced != detected {
                ctx.warn(
                    table.surfaces_pos,
                    format!(
                        "semi_ap read as {} as asked, although the data point to {}: {why}",
                        forced.reading(),
                        detected.reading()
                    ),
                );
            }
            notes.push(format!(
                "The semi_ap column is read as {}, as asked (--lens-aperture {}).",
                forced.reading(),
                forced.name()
            ));
        }
    }
    Ok((convention, stated))
}

/// Per-row checks of values the model cannot hold or that mean something unsupported.
fn check_row(ctx: &Reporter<'_>, row: &Row) -> Result<(), LensFileError> {
    let at = |k: usize, m: String| Err(ctx.error(row.pos[k], COLUMNS[k], m));
    if row.thickness.is_infinite() {
        return at(
            THICKNESS,
            format!(
                "must be finite, got {}: an infinite distance belongs to an afocal system or \
                 an object at infinity, not to a lens's table",
                row.thickness
            ),
        );
    }
    if row.thickness < 0.0 {
        return at(
            THICKNESS,
            format!(
                "must be ≥ 0 mm, got {}: light travelling backwards (a mirror lens) or a \
                 virtual surface is not supported",
                row.thickness
            ),
        );
    }
    if !(row.ior.is_finite() && row.ior >= 1.0) {
        return at(
            IOR,
            format!(
                "the refractive index must be ≥ 1 (1 is air), got {}",
                row.ior
            ),
        );
    }
    if !(row.abbe.is_finite() && row.abbe >= 0.0) {
        return at(
            ABBE,
            format!(
                "the Abbe number must be ≥ 0 (0: air or not given), got {}",
                row.abbe
            ),
        );
    }
    if !(row.semi_ap.is_finite() && row.semi_ap > 0.0) {
        return at(
            SEMI_AP,
            format!("the clear aperture must be > 0 mm, got {}", row.semi_ap),
        );
    }
    Ok(())
}

/// The table's surfaces (semi-diameters still as the column gives them) and the sensor.
fn build_surfaces(
    ctx: &mut Reporter<'_>,
    table: &Table,
    notes: &mut Vec<String>,
) -> Result<Vec<Surface>, LensFileError> {
    let mut surfaces = Vec::with_capacity(table.rows.len() + 1);
    let mut stop_seen = false;
    let mut bare = Vec::new();
    let mut before = 1.0;
    let gap = stop_in_glass(&table.rows);
    if let Some(g) = &gap {
        notes.push(format!(
            "Stop: the rows on lines {} to {} put the stop in a film of air of no thickness \
             between two flat faces of the same glass (nd {}); read as the stop inside the \
             glass (a gap of no width is no interface: light crosses it whatever the angle, \
             where a film of air would reflect every ray past the critical angle), the flats' \
             semi-diameters kept as the opening and the far face's coating left out.",
            table.rows[*g.start()].line,
            table.rows[g.end() + 1].line,
            table.rows[g.start() - 1].ior
        ));
    }
    for (i, row) in table.rows.iter().enumerate() {
        let mut row = *row;
        if let Some(g) = &gap {
            if g.contains(&i) {
                let glass = table.rows[g.start() - 1];
                (row.ior, row.abbe, row.coating) = (glass.ior, glass.abbe, 0);
            } else if i == g.end() + 1 {
                row.coating = 0;
            }
        }
        let row = &row;
        let medium = if row.ior == 1.0 {
            Medium::Air
        } else if row.abbe > 0.0 {
            Medium::Model {
                nd: row.ior,
                vd: Some(row.abbe),
            }
        } else {
            ctx.warn(
                row.pos[ABBE],
                format!(
                    "glass of ior {} with abbe 0 is taken as non-dispersive",
                    row.ior
                ),
            );
            Medium::Model {
                nd: row.ior,
                vd: None,
            }
        };
        let (kind, radius) = match row.radius {
            Radius::Curved(r) => (SurfaceKind::Refracting, r),
            Radius::Flat => (SurfaceKind::Refracting, 0.0),
            Radius::Stop if !stop_seen => {
                stop_seen = true;
                (SurfaceKind::ApertureStop, 0.0)
            }
            Radius::Stop => {
                ctx.warn(
                    row.pos[RADIUS],
                    "a second stop row: read as a flat surface that clips rays at its clear \
                     aperture (one stop per system)",
                );
                (SurfaceKind::Refracting, 0.0)
            }
        };
        let coating = match coating::stack(row.coating, before, row.ior) {
            Some(c) => c,
            None => {
                bare.push(i);
                crate::coating::Coating::None
            }
        };
        before = row.ior;
        surfaces.push(Surface {
            kind,
            coating,
            ..Surface::spherical(radius, row.thickness, medium, row.semi_ap)
        });
    }
    if !stop_seen {
        return Err(ctx.error(
            table.surfaces_pos,
            COLUMNS[RADIUS],
            "no stop row: one row of the table must give `stop` as its radius (the aperture \
             stop)",
        ));
    }
    let lines = |v: &[usize]| {
        v.iter()
            .map(|&i| table.rows[i].line.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let coated = table.rows.iter().filter(|r| r.coating > 0).count();
    if coated > 0 {
        notes.push(format!(
            "Coatings: 1 layer is a quarter-wave MgF2 layer (n {}) at {} nm, 2 layers the \
             quarter-quarter MgF2 over a high-index layer designed for the glass (docs/formats.md \
             §16).",
            coating::MGF2_INDEX,
            coating::DESIGN_NM
        ));
    }
    if !bare.is_empty() {
        let (s, are) = if bare.len() == 1 {
            ("", "is")
        } else {
            ("s", "are")
        };
        ctx.warn(
            table.surfaces_pos,
            format!(
                "the coating{s} on line{s} {} {are} left out: no air on either side (a \
                 cemented interface, or air on both)",
                lines(&bare)
            ),
        );
        notes.push(format!(
            "The coating{s} the file gives on line{s} {} {are} left out: no air on either side.",
            lines(&bare)
        ));
    }
    surfaces.push(Surface::sensor(0.5 * FILM_MM.0.hypot(FILM_MM.1)));
    Ok(surfaces)
}

/// The rows of a stop set in a film of air of no thickness between two flat faces of the same
/// glass (the Zeiss Hologon 15 mm's stop, in a slot of its middle element): a flat row into air
/// of thickness 0, the stop (and any other flat rows) in air of thickness 0, then a flat row
/// into the glass the first was in. `None` for any other table.
fn stop_in_glass(rows: &[Row]) -> Option<std::ops::RangeInclusive<usize>> {
    let stop = rows.iter().position(|r| r.radius == Radius::Stop)?;
    let in_film = |r: &Row| {
        r.ior == 1.0 && r.thickness == 0.0 && matches!(r.radius, Radius::Flat | Radius::Stop)
    };
    if !in_film(&rows[stop]) {
        return None;
    }
    let mut first = stop;
    while first > 0 && in_film(&rows[first - 1]) {
        first -= 1;
    }
    let mut last = stop;
    while last + 1 < rows.len() && in_film(&rows[last + 1]) {
        last += 1;
    }
    let (before, after) = (rows.get(first.checked_sub(1)?)?, rows.get(last + 1)?);
    let same_glass = before.ior > 1.0 && before.ior == after.ior && before.abbe == after.abbe;
    (same_glass && rows[first].radius == Radius::Flat && after.radius == Radius::Flat)
        .then_some(first..=last)
}

/// The system around `surfaces`: name, stated focal length, film, source.
fn new_system(
    ctx: &mut Reporter<'_>,
    table: &Table,
    file_name: &str,
    surfaces: Vec<Surface>,
) -> LensSystem {
    let stem = file_name
        .strip_suffix(".lens")
        .or_else(|| file_name.strip_suffix(".LENS"))
        .unwrap_or(file_name);
    let name = match &table.name {
        Some(n) => n.value.clone(),
        None => {
            ctx.warn(0, "no `name:` line; the lens is named after the file");
            stem.to_string()
        }
    };
    let mut system = LensSystem::new(&name, surfaces);
    system.film_width_mm = FILM_MM.0;
    system.film_height_mm = FILM_MM.1;
    if let Some(f) = &table.focal_length {
        if f.value > 0.0 {
            system.stated_efl_mm = Some(f.value);
        } else if f.value < 0.0 {
            ctx.warn(
                f.pos,
                format!(
                    "a negative focal_length ({}) is not kept as the stated focal length",
                    f.value
                ),
            );
        }
    }
    let patent = table
        .comments
        .iter()
        .find(|c| c.starts_with("Patent:"))
        .map(|c| format!("; {c}"))
        .unwrap_or_default();
    system.source = format!("FlareSim .lens file {file_name}{patent}");
    system
}

/// The stop's paraxial f-number with the `semi_ap` column read as semi-diameters; refuses a
/// system without power.
fn open_f_number(
    ctx: &Reporter<'_>,
    table: &Table,
    system: &LensSystem,
) -> Result<f64, LensFileError> {
    let (pos, field) = table
        .focal_length
        .as_ref()
        .map_or((table.surfaces_pos, "surfaces"), |f| {
            (f.pos, "focal_length")
        });
    let p = analyse(system, LAMBDA_D_NM).map_err(|e| {
        ctx.error(
            pos,
            field,
            format!(
                "{e}: an afocal attachment (a converter), which forms no image on its own; \
                 flarebench reads lenses that do"
            ),
        )
    })?;
    if !(p.efl_mm.is_finite() && p.efl_mm.abs() <= AFOCAL_EFL_MM) {
        return Err(ctx.error(
            pos,
            field,
            format!(
                "the paraxial focal length is {} mm: the system has next to no power, an \
                 afocal attachment (a converter) or broken data",
                round(p.efl_mm)
            ),
        ));
    }
    Ok(p.open_f_number)
}

/// Clear apertures that are still impossible with the chosen convention: clamped (lenient,
/// each a warning), or refused when beyond |R|, and crossings of neighbouring surfaces
/// reported as warnings.
fn settle_apertures(
    ctx: &mut Reporter<'_>,
    table: &Table,
    system: &mut LensSystem,
    convention: LensApertureConvention,
    lenient: bool,
    notes: &mut Vec<String>,
) -> Result<(), LensFileError> {
    let rows = table.rows.len();
    let lines: Vec<usize> = table.rows.iter().map(|r| r.line).collect();
    let column = |i: usize| match convention {
        LensApertureConvention::Semi => String::new(),
        LensApertureConvention::Diameter => {
            format!(" (the column's {} mm halved)", table.rows[i].semi_ap)
        }
    };
    let crossing_warning = |c: &clearance::Crossing| {
        let fix = if c.meet > 0.0 {
            format!(
                "--lenient-apertures limits both to {} mm, where they meet",
                round(c.meet)
            )
        } else {
            "they cross from the axis out, which no clamp undoes".to_string()
        };
        format!(
            "the surfaces on lines {} and {} cross inside their clear apertures (by {} mm at \
             {} mm from the axis; missing aspheres or oversized apertures); {fix}",
            lines[c.first],
            lines[c.first + 1],
            round(c.depth),
            round(c.height),
        )
    };
    let cause = |c: &clearance::Clamp| match c.cause {
        clearance::Cause::Radius { limit } => format!("|R| = {} mm", round(limit)),
        clearance::Cause::Crossing(x) => format!(
            "the surfaces on lines {} and {} cross beyond it, by {} mm at {} mm",
            lines[x.first],
            lines[x.first + 1],
            round(x.depth),
            round(x.height)
        ),
    };
    if lenient {
        let (clamps, left) = clearance::clamp(&mut system.surfaces[..rows]);
        for c in &left {
            ctx.warn(table.rows[c.first].pos[THICKNESS], crossing_warning(c));
        }
        for c in &clamps {
            ctx.warn(
                table.rows[c.surface].pos[SEMI_AP],
                format!(
                    "clear semi-diameter {} mm clamped to {} mm ({}), as asked \
                     (--lenient-apertures)",
                    round(c.from),
                    round(c.to),
                    cause(c)
                ),
            );
        }
        if !clamps.is_empty() {
            let list: Vec<String> = clamps
                .iter()
                .map(|c| {
                    format!(
                        "line {}: {} → {} mm ({})",
                        lines[c.surface],
                        round(c.from),
                        round(c.to),
                        cause(c)
                    )
                })
                .collect();
            notes.push(format!(
                "Clear apertures clamped to what the surfaces allow (lenient): {}.",
                list.join("; ")
            ));
        }
        return Ok(());
    }
    let impossible = clearance::check(&system.surfaces[..rows]);
    let errors: Vec<LensFileError> = impossible
        .beyond_radius
        .iter()
        .map(|b| {
            ctx.error(
                table.rows[b.surface].pos[SEMI_AP],
                COLUMNS[SEMI_AP],
                format!(
                    "clear semi-diameter {} mm{} exceeds |R| = {} mm, which no surface can \
                     have: the file mixes conventions or its data are wrong \
                     (--lenient-apertures clamps it)",
                    round(b.semi_diameter),
                    column(b.surface),
                    round(b.limit)
                ),
            )
        })
        .collect();
    if let Some(e) = Reporter::combine(errors) {
        return Err(e);
    }
    for c in &impossible.crossings {
        ctx.warn(table.rows[c.first].pos[THICKNESS], crossing_warning(c));
    }
    if !impossible.crossings.is_empty() {
        notes.push(format!(
            "Neighbouring surfaces cross inside their clear apertures: {}.",
            impossible.describe(&lines)
        ));
    }
    Ok(())
}

/// The first validation issue at its row and column, the others listed in its message.
fn located(ctx: &Reporter<'_>, table: &Table, issues: &[ValidationIssue]) -> LensFileError {
    let errors = issues
        .iter()
        .map(|issue| {
            let column = match issue.field {
                "radius" => Some(RADIUS),
                "thickness" => Some(THICKNESS),
                "refractiveIndex" => Some(IOR),
                "abbeNumber" => Some(ABBE),
                "height" => Some(SEMI_AP),
                "coating" => Some(COATING),
                _ => None,
            };
            let row = issue.surface.and_then(|s| table.rows.get(s));
            match (row, column) {
                (Some(r), Some(k)) => ctx.error(r.pos[k], COLUMNS[k], issue.message.clone()),
                (Some(r), None) => ctx.error(r.pos[RADIUS], issue.field, issue.message.clone()),
                (None, _) => ctx.error(table.surfaces_pos, issue.field, issue.message.clone()),
            }
        })
        .collect();
    Reporter::combine(errors).expect("validation failed with at least one issue")
}
