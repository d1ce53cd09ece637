//! The text of a `.lens` file: the header (`name:`, `focal_length:`, comment lines) and the
//! rows of the `surfaces:` table, each number with its byte offset. Nothing is interpreted
//! here beyond the syntax: what the numbers mean is settled by the caller.

use crate::io::LensFileError;
use crate::io::located::Reporter;
use crate::io::text::tokens;

/// Names of the six columns, used as the `field` of errors, then the optional two.
pub(super) const COLUMNS: [&str; 8] = [
    "radius",
    "thickness",
    "ior",
    "abbe",
    "semi_ap",
    "coating",
    "type",
    "radius_y",
];

/// Column indices into [`Row::pos`].
pub(super) const RADIUS: usize = 0;
pub(super) const THICKNESS: usize = 1;
pub(super) const IOR: usize = 2;
pub(super) const ABBE: usize = 3;
pub(super) const SEMI_AP: usize = 4;
pub(super) const COATING: usize = 5;

/// The first column of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Radius {
    /// A radius of curvature (mm), never 0 nor infinite.
    Curved(f64),
    /// `0` or `inf`: a flat surface.
    Flat,
    /// `stop`: the aperture stop (flat).
    Stop,
}

/// One row of the surface table.
#[derive(Clone, Copy, Debug)]
pub(super) struct Row {
    pub radius: Radius,
    /// Distance to the next vertex (mm); the last row's is the distance to the sensor.
    pub thickness: f64,
    /// nd of the medium after the surface (1 is air).
    pub ior: f64,
    /// Vd of the medium after the surface (0 in air, or unknown).
    pub abbe: f64,
    /// The `semi_ap` column as written (mm): a semi-diameter or a diameter.
    pub semi_ap: f64,
    /// Coating layers: 0, 1 or 2.
    pub coating: u8,
    /// Byte offset of each of the six columns.
    pub pos: [usize; 6],
    /// The row's line in the file (1-based), for messages about several rows.
    pub line: usize,
}

/// A header field's value and the byte offset of that value.
#[derive(Clone, Debug)]
pub(super) struct Field<T> {
    pub value: T,
    pub pos: usize,
}

/// Everything the file says, in its own terms.
#[derive(Clone, Debug)]
pub(super) struct Table {
    pub name: Option<Field<String>>,
    /// `focal_length:` (mm); may be infinite (an afocal attachment) but never NaN.
    pub focal_length: Option<Field<f64>>,
    /// The comment lines before `surfaces:`, without `#`, trimmed, empty ones left out.
    pub comments: Vec<String>,
    /// Byte offset of the `surfaces:` line.
    pub surfaces_pos: usize,
    pub rows: Vec<Row>,
}

/// Reads the header and the table. Errors name the line and the column of the first bad
/// token; unknown header lines are warnings.
pub(super) fn read(ctx: &mut Reporter<'_>, text: &str) -> Result<Table, LensFileError> {
    let mut name: Option<Field<String>> = None;
    let mut focal_length: Option<Field<f64>> = None;
    let mut comments = Vec::new();
    let mut surfaces_pos = None;
    let mut rows = Vec::new();
    let mut start = 0;
    for (index, line) in text.split_inclusive('\n').enumerate() {
        let line_start = start;
        start += line.len();
        let content = line.trim_end_matches(['\n', '\r']);
        let trimmed = content.trim_start();
        let indent = content.len() - trimmed.len();
        let at = line_start + indent;
        if surfaces_pos.is_none() {
            if let Some(c) = trimmed.strip_prefix('#') {
                let c = c.trim();
                if !c.is_empty() {
                    comments.push(c.to_string());
                }
                continue;
            }
            if trimmed.trim_end().is_empty() {
                continue;
            }
            let Some((key, value)) = trimmed.split_once(':') else {
                ctx.warn(
                    at,
                    format!(
                        "line ignored: a header line is `key: value` or a `#` comment, got \
                         `{}`",
                        trimmed.trim_end()
                    ),
                );
                continue;
            };
            let value_at = at + key.len() + 1 + (value.len() - value.trim_start().len());
            match key.trim() {
                "name" => {
                    let v = value.trim().to_string();
                    if name.is_some() {
                        ctx.warn(at, "a second `name:` line is ignored");
                    } else if v.is_empty() {
                        ctx.warn(at, "`name:` is empty; the file name is used");
                    } else {
                        name = Some(Field {
                            value: v,
                            pos: value_at,
                        });
                    }
                }
                "focal_length" => {
                    let v = value.split('#').next().unwrap_or("").trim();
                    let f = parse_number(ctx, v, value_at, "focal_length")?;
                    if focal_length.is_some() {
                        ctx.warn(at, "a second `focal_length:` line is ignored");
                    } else {
                        focal_length = Some(Field {
                            value: f,
                            pos: value_at,
                        });
                    }
                }
                "surfaces" => {
                    if !value.split('#').next().unwrap_or("").trim().is_empty() {
                        ctx.warn(value_at, "text after `surfaces:` is ignored");
                    }
                    surfaces_pos = Some(at);
                }
                other => ctx.warn(at, format!("unknown header field `{other}:` is ignored")),
            }
            continue;
        }
        let data = content.split('#').next().unwrap_or("");
        let toks: Vec<(usize, &str)> = tokens(data)
            .into_iter()
            .map(|(off, t)| (line_start + off, t))
            .collect();
        if toks.is_empty() {
            continue;
        }
        let mut row = read_row(ctx, &toks, line_start + content.len())?;
        row.line = index + 1;
        rows.push(row);
    }
    let Some(surfaces_pos) = surfaces_pos else {
        return Err(ctx.error(
            text.len(),
            "surfaces",
            "no `surfaces:` line: a `.lens` file lists its surfaces in a table after a line \
             `surfaces:`",
        ));
    };
    Ok(Table {
        name,
        focal_length,
        comments,
        surfaces_pos,
        rows,
    })
}

/// A number of the file: Rust's `f64` syntax, which also reads `inf` and `NaN`; NaN is an
/// error here, infinities are left to the caller.
fn parse_number(
    ctx: &Reporter<'_>,
    token: &str,
    pos: usize,
    field: &str,
) -> Result<f64, LensFileError> {
    let v: f64 = token
        .parse()
        .map_err(|_| ctx.error(pos, field, format!("expected a number, got `{token}`")))?;
    if v.is_nan() {
        return Err(ctx.error(pos, field, format!("expected a number, got `{token}`")));
    }
    Ok(v)
}

/// One table row from its tokens; `end` is the byte offset of the end of its line.
fn read_row(ctx: &Reporter<'_>, toks: &[(usize, &str)], end: usize) -> Result<Row, LensFileError> {
    if toks.len() < 6 {
        let missing = COLUMNS[toks.len()];
        return Err(ctx.error(
            end,
            missing,
            format!(
                "a surface row has 6 columns (radius thickness ior abbe semi_ap coating), \
                 found {}: `{missing}` is missing",
                toks.len()
            ),
        ));
    }
    let mut pos = [0; 6];
    for (k, (p, _)) in toks.iter().take(6).enumerate() {
        pos[k] = *p;
    }
    let (rp, rt) = toks[RADIUS];
    let radius = if rt.eq_ignore_ascii_case("stop") {
        Radius::Stop
    } else {
        let r = parse_number(ctx, rt, rp, COLUMNS[RADIUS])?;
        if r == 0.0 || r.is_infinite() {
            Radius::Flat
        } else {
            Radius::Curved(r)
        }
    };
    let mut v = [0.0; 4];
    for (k, slot) in v.iter_mut().enumerate() {
        let (p, t) = toks[k + 1];
        *slot = parse_number(ctx, t, p, COLUMNS[k + 1])?;
    }
    let [thickness, ior, abbe, semi_ap] = v;
    let (cp, ct) = toks[COATING];
    let coating = match ct {
        "0" => 0,
        "1" => 1,
        "2" => 2,
        _ => {
            return Err(ctx.error(
                cp,
                COLUMNS[COATING],
                format!("the coating column gives 0, 1 or 2 layers, got `{ct}`"),
            ));
        }
    };
    read_surface_type(ctx, &toks[6..])?;
    Ok(Row {
        radius,
        thickness,
        ior,
        abbe,
        semi_ap,
        coating,
        pos,
        line: 0,
    })
}

/// The optional seventh and eighth columns: the surface type and, for a toric surface, its
/// second radius. Only spherical surfaces are read: cylinders and tori are anamorphic.
fn read_surface_type(ctx: &Reporter<'_>, rest: &[(usize, &str)]) -> Result<(), LensFileError> {
    let Some(&(p, t)) = rest.first() else {
        return Ok(());
    };
    let extra_from = match t {
        "sph" | "spherical" => 1,
        "cyl_x" | "cylinder_x" | "cyl_y" | "cylinder_y" | "toric" => {
            let what = if t == "toric" {
                "a toric surface"
            } else {
                "a cylindrical surface"
            };
            return Err(ctx.error(
                p,
                COLUMNS[6],
                format!(
                    "{what} (`{t}`): anamorphic lenses are not supported yet; flarebench \
                     traces rotationally symmetric systems only"
                ),
            ));
        }
        other => {
            return Err(ctx.error(
                p,
                COLUMNS[6],
                format!(
                    "unknown surface type `{other}`; the type column is sph, cyl_x, cyl_y or \
                     toric"
                ),
            ));
        }
    };
    if let Some(&(p, t)) = rest.get(extra_from) {
        return Err(ctx.error(
            p,
            COLUMNS[7],
            format!("unexpected `{t}` after the surface type (a radius_y goes with toric only)"),
        ));
    }
    Ok(())
}
