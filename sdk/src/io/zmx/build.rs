//! From the records of a `.zmx` file to a [`LensSystem`]: lens units to millimetres, the
//! object surface dropped, surfaces 1 … n−1 as refracting surfaces, the `STOP` surface as the
//! aperture stop (a flat stop inserted in its vertex plane when it is a lens surface), the
//! image surface as the sensor; then the stop and missing semi-diameters sized
//! ([`super::aperture`]) and the system validated, each issue reported at its record.

use std::collections::BTreeMap;

use crate::io::LensFileError;
use crate::io::located::Reporter;
use crate::spectrum::LAMBDA_D_NM;
use crate::system::{LensSystem, Medium, Surface, SurfaceKind, ValidationIssue};

use super::aperture::{ApertureSpec, derive_semi_diameters, size_stop};
use super::config::{self, Setting, Target};
use super::glass;
use super::header::{self, Aperture, MaxField, Units};
use super::records::{Block, Record, Records};

/// Film size given to Zemax lenses (full-frame 35 mm), as for the bundled library.
const FILM_MM: (f64, f64) = (36.0, 24.0);

/// Surface types that are read.
const SUPPORTED: &str = "STANDARD, EVENASPH, XASPHERE (up to 8 terms) and COORDBRK without \
                         decenter or tilt";

/// Surface records that carry nothing the model needs (drawing, tolerancing, solves,
/// mechanical data), read without a word.
const QUIET_KEYS: &[&str] = &[
    "HIDE", "MIRR", "SLAB", "POPS", "FIMP", "MEMA", "OEMA", "MAZH", "SSID", "VPAR", "VCON", "PPAR",
    "PZUP", "TCED", "EDGE", "VDSZ", "COMM", "MNUM", "PKUP", "CCON", "VCRV", "VDIS", "VCNR", "VTHI",
    "VGLA", "BLNK", "OBDC",
];

/// Where each field of one surface sits in the file, by model field name.
#[derive(Clone, Debug, Default)]
pub(super) struct SurfaceSpans {
    /// The `SURF` record.
    pub pos: usize,
    /// `(model field, zemax key, byte offset)`.
    pub fields: Vec<(&'static str, &'static str, usize)>,
}

impl SurfaceSpans {
    fn add(&mut self, field: &'static str, key: &'static str, pos: usize) {
        self.fields.push((field, key, pos));
    }

    fn locate(&self, field: &str) -> (usize, &'static str) {
        self.fields
            .iter()
            .find(|(f, _, _)| *f == field)
            .map_or((self.pos, "SURF"), |&(_, k, p)| (p, k))
    }
}

/// One surface read from a block, before the stop and apertures are settled.
struct Read {
    surface: Surface,
    /// The semi-diameter given by the file (mm), if any.
    given_semi: Option<f64>,
    zemax: usize,
    spans: SurfaceSpans,
    stop: Option<usize>,
    coating: Option<String>,
}

/// What a block turned into.
enum Item {
    Surface(Box<Read>),
    /// A coordinate break without decenter or tilt: only its thickness (mm).
    Gap(f64),
}

/// Builds and validates the system. `config` selects a multi-configuration position.
pub(super) fn build(
    ctx: &mut Reporter<'_>,
    recs: &Records<'_>,
    config: Option<usize>,
) -> Result<LensSystem, LensFileError> {
    let head = read_header(ctx, recs, config)?;
    let (object, lens_blocks, image) = split_blocks(ctx, &recs.surfaces)?;
    let object_distance = read_object(
        ctx,
        object,
        head.units,
        &head.settings,
        &head.gcat,
        head.lambda,
    )?;

    let mut notes = vec![format!(
        "Lens units {} ({} mm each); surfaces numbered as here, the file's SURF numbers in \
         messages.",
        head.units.name, head.units.mm
    )];
    let mut substitutions = Vec::new();
    let mut reads = read_lens_blocks(ctx, lens_blocks, &head, &mut substitutions)?;
    if reads.is_empty() {
        return Err(ctx.error(
            image.pos,
            "SURF",
            "no surface between the object and the image (only coordinate breaks)",
        ));
    }
    let (stop_index, stop_semi) = settle_stop(ctx, &mut reads, &mut notes)?;
    let sensor_spans = read_image(ctx, image, head.units, &mut notes)?;
    let Assembled {
        surfaces,
        spans,
        derive,
        coatings,
    } = assemble(reads, sensor_spans);
    let mut system = new_system(ctx, recs, surfaces, head.primary);
    setting_notes(ctx, &head, object, object_distance, &mut notes);

    let spec = ApertureSpec {
        aperture: head.aperture,
        pos: head.aperture_pos,
        object_distance,
        stop_semi,
    };
    notes.push(size_stop(ctx, &mut system, stop_index, head.lambda, &spec)?);
    let derived = derive_missing(
        ctx,
        &mut system,
        &head,
        (stop_index, object_distance),
        &derive,
        &spans,
    )?;
    notes.extend(derived);
    if !substitutions.is_empty() {
        notes.push(format!("Glasses: {}.", substitutions.join("; ")));
    }
    coating_notes(ctx, lens_blocks, &coatings, &mut notes);
    let file_notes = header::notes(recs);
    if !file_notes.is_empty() {
        notes.push(format!("File notes: {file_notes}"));
    }
    system.notes = notes.join("\n");

    if let Err(issues) = system.validate() {
        let wav_pos = head.primary.map_or(0, |p| p.1);
        return Err(located(ctx, &spans, &issues, wav_pos));
    }
    Ok(system)
}

/// What the file's system records say, for every surface.
struct Header {
    units: Units,
    /// The number of configurations.
    n_configs: usize,
    /// The configuration read (1-based): the one asked for, else the active one.
    config: usize,
    /// The selected configuration's values; empty when none was asked for.
    settings: Vec<Setting>,
    /// Glass catalogues (`GCAT`).
    gcat: Vec<String>,
    /// The primary wavelength (nm) and its record's byte offset.
    primary: Option<(f64, usize)>,
    /// The primary wavelength, else the d line (nm).
    lambda: f64,
    aperture: Aperture,
    /// Byte offset of the aperture value.
    aperture_pos: usize,
    max_field: Option<MaxField>,
}

/// Reads the system records: refuses a non-sequential file, selects the configuration (or warns
/// that the active one of several is read) and applies its aperture.
fn read_header(
    ctx: &mut Reporter<'_>,
    recs: &Records<'_>,
    config: Option<usize>,
) -> Result<Header, LensFileError> {
    if let Some(r) = recs.get("MODE")
        && r.arg(0).is_some_and(|m| !m.eq_ignore_ascii_case("SEQ"))
    {
        return Err(ctx.error(
            r.arg_pos(0),
            "MODE",
            "only sequential files (MODE SEQ) describe a lens; this one is non-sequential",
        ));
    }
    let units = header::units(ctx, recs)?;
    let (n_configs, active) = config::count(ctx, recs)?;
    let settings = match config {
        Some(c) => config::settings(ctx, recs, c, n_configs)?,
        None => {
            if n_configs > 1 {
                let pos = recs.get("MNUM").map_or(0, |r| r.pos);
                ctx.warn(
                    pos,
                    format!(
                        "the file has {n_configs} configurations; configuration {active}, \
                         active when it was saved, is read (choose one with --config N)"
                    ),
                );
            }
            Vec::new()
        }
    };
    let gcat = header::catalogues(recs);
    let primary = header::primary_wavelength(ctx, recs)?;
    let lambda = primary.map_or(LAMBDA_D_NM, |p| p.0);
    let (mut aperture, mut aperture_pos) = header::aperture(ctx, recs, units)?;
    for s in settings.iter().filter(|s| s.target == Target::Aperture) {
        aperture = aperture.with_value(s.value, units);
        aperture_pos = s.pos;
    }
    let max_field = header::max_field(ctx, recs, units)?;
    Ok(Header {
        units,
        n_configs,
        config: config.unwrap_or(active),
        settings,
        gcat,
        primary,
        lambda,
        aperture,
        aperture_pos,
        max_field,
    })
}

/// The object block, the lens blocks and the image block; at least one lens block, and the
/// stop on neither the object nor the image.
fn split_blocks<'b, 'a>(
    ctx: &Reporter<'_>,
    blocks: &'b [Block<'a>],
) -> Result<(&'b Block<'a>, &'b [Block<'a>], &'b Block<'a>), LensFileError> {
    if blocks.len() < 3 {
        let pos = blocks.last().map_or(0, |b| b.pos);
        return Err(ctx.error(
            pos,
            "SURF",
            format!(
                "a lens needs the object surface, at least one surface and the image surface; \
                 the file has {} SURF block(s)",
                blocks.len()
            ),
        ));
    }
    let (object, lens_blocks, image) = (
        &blocks[0],
        &blocks[1..blocks.len() - 1],
        &blocks[blocks.len() - 1],
    );
    for b in [object, image] {
        if let Some(r) = b.get("STOP") {
            return Err(ctx.error(
                r.pos,
                "STOP",
                format!(
                    "the stop is on the {} surface (SURF {}); it must be on a surface between them",
                    if std::ptr::eq(b, object) {
                        "object"
                    } else {
                        "image"
                    },
                    b.number
                ),
            ));
        }
    }
    Ok((object, lens_blocks, image))
}

/// Reads the blocks between the object and the image in order, a coordinate break's gap added
/// to the surface before it; warns once per surface keyword that is not read.
fn read_lens_blocks(
    ctx: &mut Reporter<'_>,
    lens_blocks: &[Block<'_>],
    head: &Header,
    substitutions: &mut Vec<String>,
) -> Result<Vec<Read>, LensFileError> {
    let mut unknown: BTreeMap<&str, usize> = BTreeMap::new();
    let mut reads: Vec<Read> = Vec::new();
    let mut glasses = GlassLookup {
        gcat: &head.gcat,
        lambda: head.lambda,
        seen: glass::Seen::default(),
        substitutions,
    };
    for block in lens_blocks {
        for r in &block.records {
            if !KNOWN_KEYS.contains(&r.key) && !QUIET_KEYS.contains(&r.key) {
                unknown.entry(r.key).or_insert(r.pos);
            }
        }
        let item = read_block(ctx, block, head.units, &head.settings, &mut glasses)?;
        match item {
            Item::Surface(read) => reads.push(*read),
            Item::Gap(t) => match reads.last_mut() {
                Some(prev) => prev.surface.thickness += t,
                None => {
                    // A gap right after the object only moves the object.
                }
            },
        }
    }
    for (key, pos) in &unknown {
        ctx.warn(*pos, format!("`{key}` records on surfaces are not read"));
    }
    Ok(reads)
}

/// Settles the aperture stop among `reads` (not empty): the one `STOP` surface, else the first;
/// a flat one becomes the stop, in front of a lens surface a flat stop is inserted. Returns the
/// stop's index and the semi-diameter the file gave its surface (mm).
fn settle_stop(
    ctx: &mut Reporter<'_>,
    reads: &mut Vec<Read>,
    notes: &mut Vec<String>,
) -> Result<(usize, Option<f64>), LensFileError> {
    let flagged: Vec<(usize, usize)> = reads
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.stop.map(|p| (i, p)))
        .collect();
    let (stop_read, stop_pos) = match flagged.as_slice() {
        [] => {
            ctx.warn(
                reads[0].spans.pos,
                "no STOP in the file; the first surface is the stop, as in Zemax",
            );
            (0, reads[0].spans.pos)
        }
        [one] => *one,
        [first, second, ..] => {
            return Err(ctx.error(
                second.1,
                "STOP",
                format!(
                    "a second STOP (SURF {}; the first is SURF {}): a system has one stop",
                    reads[second.0].zemax, reads[first.0].zemax
                ),
            ));
        }
    };
    let stop_semi = reads[stop_read].given_semi;
    let medium = if stop_read == 0 {
        Medium::Air
    } else {
        reads[stop_read - 1].surface.medium.clone()
    };
    let s = &reads[stop_read].surface;
    let dummy = s.curvature == 0.0 && s.aspheric.iter().all(|a| *a == 0.0) && s.medium == medium;
    let stop_zemax = reads[stop_read].zemax;
    if dummy {
        let r = &mut reads[stop_read];
        r.surface.kind = SurfaceKind::ApertureStop;
        r.surface.conic = 0.0;
        r.given_semi = None;
        notes.push(format!(
            "The aperture stop is the file's flat SURF {stop_zemax}."
        ));
    } else {
        let mut spans = SurfaceSpans {
            pos: reads[stop_read].spans.pos,
            fields: Vec::new(),
        };
        spans.add("type", "STOP", stop_pos);
        spans.add("height", "STOP", stop_pos);
        reads.insert(
            stop_read,
            Read {
                surface: Surface {
                    kind: SurfaceKind::ApertureStop,
                    ..Surface::spherical(0.0, 0.0, medium, 1.0)
                },
                given_semi: None,
                zemax: stop_zemax,
                spans,
                stop: None,
                coating: None,
            },
        );
        let msg = format!(
            "the stop is on SURF {stop_zemax}, a lens surface; a flat aperture stop is inserted \
             in its vertex plane, just in front of it: paraxial data are unchanged, real rays \
             are clipped in that plane rather than on the curved surface"
        );
        ctx.warn(stop_pos, &msg);
        notes.push(format!("{}{}.", msg[..1].to_ascii_uppercase(), &msg[1..]));
    }
    Ok((stop_read, stop_semi))
}

/// The image block: read as a flat sensor (a curvature is warned about, a semi-diameter noted).
/// Returns the sensor's spans.
fn read_image(
    ctx: &mut Reporter<'_>,
    image: &Block<'_>,
    units: Units,
    notes: &mut Vec<String>,
) -> Result<SurfaceSpans, LensFileError> {
    let mut sensor_spans = SurfaceSpans {
        pos: image.pos,
        fields: Vec::new(),
    };
    if let Some(r) = image.get("TYPE") {
        sensor_spans.add("type", "TYPE", r.arg_pos(0));
    }
    if let Some(r) = image.get("CURV") {
        let c = r.number(ctx, 0)? / units.mm;
        if c != 0.0 {
            ctx.warn(
                r.arg_pos(0),
                format!(
                    "the image surface is curved (R = {:.6} mm); it is read as a flat sensor",
                    1.0 / c
                ),
            );
        }
    }
    if let Some(r) = image.get("DIAM")
        && let Ok(d) = r.number(ctx, 0)
        && d > 0.0
    {
        notes.push(format!(
            "The file's image semi-diameter is {:.6} mm; the sensor here is the 36 x 24 mm \
             film (semi-diameter {:.6} mm).",
            d * units.mm,
            film_half_diagonal()
        ));
    }
    Ok(sensor_spans)
}

/// Half the diagonal of [`FILM_MM`] (mm): the sensor's semi-diameter.
fn film_half_diagonal() -> f64 {
    0.5 * FILM_MM.0.hypot(FILM_MM.1)
}

/// The surfaces in order, sensor last, with what sizing and the notes need.
struct Assembled {
    surfaces: Vec<Surface>,
    /// Each surface's spans, the sensor's last.
    spans: Vec<SurfaceSpans>,
    /// Refracting surfaces without a semi-diameter from the file (indices).
    derive: Vec<usize>,
    /// Surface indices by coating name.
    coatings: BTreeMap<String, Vec<usize>>,
}

/// The surfaces read, then the sensor.
fn assemble(reads: Vec<Read>, sensor_spans: SurfaceSpans) -> Assembled {
    let mut surfaces = Vec::with_capacity(reads.len() + 1);
    let mut spans = Vec::with_capacity(reads.len() + 1);
    let mut derive = Vec::new();
    let mut coatings: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, r) in reads.into_iter().enumerate() {
        if r.surface.kind == SurfaceKind::Refracting && r.given_semi.is_none() {
            derive.push(i);
        }
        if let Some(c) = r.coating {
            coatings.entry(c).or_default().push(i);
        }
        surfaces.push(r.surface);
        spans.push(r.spans);
    }
    surfaces.push(Surface::sensor(film_half_diagonal()));
    spans.push(sensor_spans);
    Assembled {
        surfaces,
        spans,
        derive,
        coatings,
    }
}

/// The system named by `NAME` (else the file's stem), with the film, primary wavelength and
/// source set.
fn new_system(
    ctx: &Reporter<'_>,
    recs: &Records<'_>,
    surfaces: Vec<Surface>,
    primary: Option<(f64, usize)>,
) -> LensSystem {
    let name = recs
        .get("NAME")
        .map(|r| r.rest.trim_matches('"').trim().to_string())
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| {
            std::path::Path::new(ctx.file)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
    let mut system = LensSystem::new(&name, surfaces);
    system.film_width_mm = FILM_MM.0;
    system.film_height_mm = FILM_MM.1;
    system.primary_wavelength_nm = primary.map(|p| p.0);
    let file_name = std::path::Path::new(ctx.file)
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    system.source = format!("Zemax OpticStudio file {file_name}");
    system
}

/// Notes on the primary wavelength, the configuration and the object; a finite object distance
/// is also a warning.
fn setting_notes(
    ctx: &mut Reporter<'_>,
    head: &Header,
    object: &Block<'_>,
    object_distance: Option<f64>,
    notes: &mut Vec<String>,
) {
    if let Some((nm, _)) = head.primary {
        notes.push(format!(
            "Primary wavelength {nm} nm (PWAV): paraxial data default to it."
        ));
    }
    if head.n_configs > 1 {
        notes.push(format!(
            "Configuration {} of {}.",
            head.config, head.n_configs
        ));
    }
    match object_distance {
        Some(d) => {
            let msg = format!(
                "the object is {d} mm in front of the first surface (finite conjugates); \
                 flarebench puts the object at infinity, so the sensor stays where the file \
                 puts it, which is not the focus for an object at infinity"
            );
            ctx.warn(
                object.get("DISZ").map_or(object.pos, |r| r.arg_pos(0)),
                &msg,
            );
            notes.push(format!("The {msg}."));
        }
        None => notes.push("The object surface (at infinity) is dropped.".into()),
    }
}

/// Gives the surfaces in `derive` semi-diameters from paraxial rays, with a warning; returns
/// the note, `None` when there are none.
fn derive_missing(
    ctx: &mut Reporter<'_>,
    system: &mut LensSystem,
    head: &Header,
    (stop_index, object_distance): (usize, Option<f64>),
    derive: &[usize],
    spans: &[SurfaceSpans],
) -> Result<Option<String>, LensFileError> {
    let note = derive_semi_diameters(
        ctx,
        system,
        (stop_index, head.lambda),
        derive,
        head.max_field.as_ref(),
        object_distance,
        spans[derive.first().copied().unwrap_or(0)].pos,
    )?;
    if note.is_some() {
        ctx.warn(
            spans[derive[0]].pos,
            format!(
                "{} surface(s) without DIAM, CLAP or FLAP get semi-diameters from paraxial \
                 marginal and chief rays (see the notes)",
                derive.len()
            ),
        );
    }
    Ok(note)
}

/// Coating names are not defined in a `.zmx` file: a warning at the first `COAT` and a note.
fn coating_notes(
    ctx: &mut Reporter<'_>,
    lens_blocks: &[Block<'_>],
    coatings: &BTreeMap<String, Vec<usize>>,
    notes: &mut Vec<String>,
) {
    if coatings.is_empty() {
        return;
    }
    let list: Vec<String> = coatings
        .iter()
        .map(|(c, s)| {
            let s: Vec<String> = s.iter().map(usize::to_string).collect();
            format!("{c} on surfaces {}", s.join(", "))
        })
        .collect();
    let msg = format!(
        "coatings are named but not defined in a .zmx file ({}); the surfaces are uncoated \
         here",
        list.join("; ")
    );
    let pos = lens_blocks
        .iter()
        .find_map(|b| b.get("COAT"))
        .map_or(0, |r| r.pos);
    ctx.warn(pos, &msg);
    notes.push(format!("Coatings {msg}."));
}

/// Surface keywords that are read.
const KNOWN_KEYS: &[&str] = &[
    "TYPE", "CURV", "DISZ", "GLAS", "DIAM", "CLAP", "FLAP", "STOP", "CONI", "PARM", "XDAT", "COAT",
    "SQAP", "ELAP", "OBSC", "SCBD", "IGNR",
];

/// The object surface: its distance (mm, `None` at infinity). Object space must be air.
fn read_object(
    ctx: &mut Reporter<'_>,
    block: &Block<'_>,
    units: Units,
    settings: &[Setting],
    gcat: &[String],
    lambda: f64,
) -> Result<Option<f64>, LensFileError> {
    if let Some(r) = block.get("GLAS") {
        let medium = if r.arg(0) == Some("MIRROR") {
            None
        } else {
            Some(glass::resolve(ctx, r, gcat, Some(lambda), &mut glass::Seen::default())?.medium)
        };
        if medium != Some(Medium::Air) {
            return Err(ctx.error(
                r.arg_pos(0),
                "GLAS",
                "the object surface is followed by glass: object space must be air",
            ));
        }
    }
    let mut d = match block.get("DISZ") {
        Some(r) if r.arg(0).is_some_and(|a| a.eq_ignore_ascii_case("INFINITY")) => None,
        Some(r) => Some(r.number(ctx, 0)?),
        None => None,
    };
    for s in settings.iter().filter(|s| s.surface == block.number) {
        if s.target == Target::Thickness {
            d = (s.value.abs() < 1e9).then_some(s.value);
        }
    }
    match d {
        Some(v) if v.abs() >= 1e9 => Ok(None),
        Some(v) if v <= 0.0 => Err(ctx.error(
            block.get("DISZ").map_or(block.pos, |r| r.arg_pos(0)),
            "DISZ",
            format!("the object distance must be positive or INFINITY, got {v}"),
        )),
        Some(v) => Ok(Some(v * units.mm)),
        None => Ok(None),
    }
}

/// The mirror policy's error.
fn mirror_error(ctx: &Reporter<'_>, block: &Block<'_>, r: &Record<'_>) -> LensFileError {
    ctx.error(
        r.arg_pos(0),
        "GLAS",
        format!(
            "SURF {} is a mirror (GLAS MIRROR): flarebench traces lenses that refract front to \
             sensor, with thicknesses ≥ 0, so mirrors and catadioptric systems are refused \
             (docs/formats.md, \"Mirrors\")",
            block.number
        ),
    )
}

/// Glass lookup for the lens blocks: the catalogues (`GCAT`), the wavelength (nm), the glasses
/// seen so far and the substitutions made.
struct GlassLookup<'a> {
    gcat: &'a [String],
    lambda: f64,
    seen: glass::Seen,
    substitutions: &'a mut Vec<String>,
}

/// A lens block's surface type, as read.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Standard,
    EvenAsphere,
    ExtendedAsphere,
    CoordinateBreak,
}

/// A surface's spacing and shape in lens units, the configuration's values applied.
struct Shape {
    thickness: f64,
    curvature: f64,
    conic: f64,
    /// The clear semi-diameter, if given.
    semi: Option<f64>,
}

/// One surface block between the object and the image.
fn read_block(
    ctx: &mut Reporter<'_>,
    block: &Block<'_>,
    units: Units,
    settings: &[Setting],
    glasses: &mut GlassLookup<'_>,
) -> Result<Item, LensFileError> {
    let mut spans = SurfaceSpans {
        pos: block.pos,
        fields: Vec::new(),
    };
    let kind = surface_kind(ctx, block, &mut spans)?;
    check_centred(ctx, block)?;
    let shape = read_shape(ctx, block, settings, &mut spans)?;
    if kind == Kind::CoordinateBreak {
        check_coordinate_break(ctx, block)?;
        return Ok(Item::Gap(shape.thickness * units.mm));
    }
    // Even-asphere coefficients of r², r⁴, … in lens units.
    let asph = match kind {
        Kind::EvenAsphere => even_asphere(ctx, block, &mut spans)?,
        Kind::ExtendedAsphere => extended_asphere(ctx, block, &mut spans)?,
        _ => [0.0; 8],
    };
    let medium = read_medium(ctx, block, glasses, &mut spans)?;
    for key in ["SQAP", "ELAP", "OBSC"] {
        if let Some(r) = block.get(key) {
            ctx.warn(
                r.pos,
                format!(
                    "SURF {}: the {key} aperture is not read; the surface is clipped by its \
                     circular semi-diameter",
                    block.number
                ),
            );
        }
    }
    let coating = block
        .get("COAT")
        .and_then(|r| r.arg(0))
        .filter(|c| !c.is_empty() && !c.eq_ignore_ascii_case("NONE"))
        .map(str::to_string);
    if let Some(r) = block.get("COAT") {
        spans.add("coating", "COAT", r.arg_pos(0));
    }
    let mm = units.mm;
    Ok(Item::Surface(Box::new(Read {
        surface: refracting_surface(&shape, &asph, medium, mm),
        given_semi: shape.semi.map(|s| s * mm),
        zemax: block.number,
        spans,
        stop: block.get("STOP").map(|r| r.pos),
        coating,
    })))
}

/// The block's `TYPE` (default `STANDARD`); an unsupported type is an error naming it.
fn surface_kind(
    ctx: &Reporter<'_>,
    block: &Block<'_>,
    spans: &mut SurfaceSpans,
) -> Result<Kind, LensFileError> {
    let type_rec = block.get("TYPE");
    let type_name = type_rec.and_then(|r| r.arg(0)).unwrap_or("STANDARD");
    if let Some(r) = type_rec {
        spans.add("type", "TYPE", r.arg_pos(0));
    }
    match type_name.to_ascii_uppercase().as_str() {
        "STANDARD" => Ok(Kind::Standard),
        "EVENASPH" => Ok(Kind::EvenAsphere),
        "XASPHERE" => Ok(Kind::ExtendedAsphere),
        "COORDBRK" => Ok(Kind::CoordinateBreak),
        other => {
            let what = match other {
                "QED_TYPE" => " (Q-type asphere)",
                "ODDASPH" | "XOSPHERE" => " (odd asphere)",
                "TOROIDAL" | "BICONICX" | "BICONIC" => " (not rotationally symmetric)",
                "PARAXIAL" => " (ideal paraxial lens)",
                "DGRATING" => " (diffraction grating)",
                _ => "",
            };
            Err(ctx.error(
                type_rec.map_or(block.pos, |r| r.arg_pos(0)),
                "TYPE",
                format!(
                    "SURF {} has type {type_name}{what}, which flarebench does not read; \
                     supported: {SUPPORTED}",
                    block.number
                ),
            ))
        }
    }
}

/// Refuses a surface marked "ignore" (`IGNR`) and a tilted or decentered one (`SCBD`).
fn check_centred(ctx: &Reporter<'_>, block: &Block<'_>) -> Result<(), LensFileError> {
    let n = block.number;
    if let Some(r) = block.get("IGNR")
        && r.arg(0).is_some_and(|a| a != "0")
    {
        return Err(ctx.error(
            r.pos,
            "IGNR",
            format!("SURF {n} is marked \"ignore this surface\"; remove the mark or the surface"),
        ));
    }
    if let Some(r) = block.get("SCBD")
        && r.args[1..]
            .iter()
            .any(|(_, t)| !t.parse::<f64>().is_ok_and(|v| v == 0.0))
    {
        return Err(ctx.error(
            r.pos,
            "SCBD",
            format!("SURF {n} is tilted or decentered: flarebench models centred systems only"),
        ));
    }
    Ok(())
}

/// `DISZ`, `CURV`, `CONI` and the semi-diameter, then the configuration's values for this
/// surface; the spans listed with the configuration's first.
fn read_shape(
    ctx: &mut Reporter<'_>,
    block: &Block<'_>,
    settings: &[Setting],
    spans: &mut SurfaceSpans,
) -> Result<Shape, LensFileError> {
    let n = block.number;
    let mut thickness = match block.get("DISZ") {
        Some(r) if r.arg(0).is_some_and(|a| a.eq_ignore_ascii_case("INFINITY")) => {
            return Err(ctx.error(
                r.arg_pos(0),
                "DISZ",
                format!("SURF {n}: only the object surface may be at an infinite distance"),
            ));
        }
        Some(r) => {
            spans.add("thickness", "DISZ", r.arg_pos(0));
            r.number(ctx, 0)?
        }
        None => 0.0,
    };
    let mut curvature = match block.get("CURV") {
        Some(r) => {
            spans.add("radius", "CURV", r.arg_pos(0));
            r.number(ctx, 0)?
        }
        None => 0.0,
    };
    let mut conic = match block.get("CONI") {
        Some(r) => {
            spans.add("conic", "CONI", r.arg_pos(0));
            r.number(ctx, 0)?
        }
        None => 0.0,
    };
    let mut semi = semi_diameter(ctx, block, spans)?;
    for s in settings.iter().filter(|s| s.surface == n) {
        match s.target {
            Target::Thickness => {
                thickness = s.value;
                spans.add("thickness", "THIC", s.pos);
            }
            Target::Curvature => {
                curvature = s.value;
                spans.add("radius", "CRVT", s.pos);
            }
            Target::Conic => {
                conic = s.value;
                spans.add("conic", "CONN", s.pos);
            }
            Target::SemiDiameter => {
                semi = (s.value > 0.0).then_some(s.value);
                spans.add("height", "SDIA", s.pos);
            }
            Target::Aperture => {}
        }
    }
    // Later entries win: put the configuration's positions first.
    spans.fields.reverse();
    Ok(Shape {
        thickness,
        curvature,
        conic,
        semi,
    })
}

/// Refuses a coordinate break that is the stop, decenters or tilts (`PARM 1` to `5`), or is
/// a mirror.
fn check_coordinate_break(ctx: &Reporter<'_>, block: &Block<'_>) -> Result<(), LensFileError> {
    let n = block.number;
    if let Some(r) = block.get("STOP") {
        return Err(ctx.error(
            r.pos,
            "STOP",
            format!("the stop is on SURF {n}, a coordinate break"),
        ));
    }
    let parm = |i: usize| block.all("PARM").find(|r| r.arg(0) == Some(&i.to_string()));
    for i in 1..=5 {
        if let Some(r) = parm(i) {
            let v = r.number(ctx, 1)?;
            if v != 0.0 {
                return Err(ctx.error(
                    r.arg_pos(1),
                    "PARM",
                    format!(
                        "SURF {n} is a coordinate break with a {} of {v}: flarebench models \
                         centred systems only",
                        if i <= 2 { "decenter" } else { "tilt" }
                    ),
                ));
            }
        }
    }
    if let Some(r) = block.get("GLAS")
        && r.arg(0) == Some("MIRROR")
    {
        return Err(mirror_error(ctx, block, r));
    }
    Ok(())
}

/// `EVENASPH` coefficients of r², …, r¹⁶ (`PARM 1` to `8`) in lens units.
fn even_asphere(
    ctx: &Reporter<'_>,
    block: &Block<'_>,
    spans: &mut SurfaceSpans,
) -> Result<[f64; 8], LensFileError> {
    let mut asph = [0.0; 8];
    for r in block.all("PARM") {
        let i = r.integer(ctx, 0)?;
        let v = r.number(ctx, 1)?;
        match i {
            1..=8 => asph[i - 1] = v,
            _ if v == 0.0 => {}
            _ => {
                return Err(ctx.error(
                    r.arg_pos(0),
                    "PARM",
                    format!("EVENASPH has parameters 1 to 8, got PARM {i} = {v}"),
                ));
            }
        }
        spans.add("aspheric", "PARM", r.arg_pos(1));
    }
    Ok(asph)
}

/// `XASPHERE` terms (`XDAT 1` their count, `XDAT 2` the normalization radius r0) as even-asphere
/// coefficients of r², …, r¹⁶ in lens units; a higher term must be zero.
fn extended_asphere(
    ctx: &Reporter<'_>,
    block: &Block<'_>,
    spans: &mut SurfaceSpans,
) -> Result<[f64; 8], LensFileError> {
    let mut asph = [0.0; 8];
    let xdat = |i: usize| block.all("XDAT").find(|r| r.arg(0) == Some(&i.to_string()));
    let terms = match xdat(1) {
        Some(r) => r.integer(ctx, 1)?,
        None => 0,
    };
    let r0 = match xdat(2) {
        Some(r) => r.number(ctx, 1)?,
        None => 1.0,
    };
    if terms > 0 && r0 <= 0.0 {
        return Err(ctx.error(
            xdat(2).map_or(block.pos, |r| r.arg_pos(1)),
            "XDAT",
            format!("XASPHERE needs a positive normalization radius, got {r0}"),
        ));
    }
    for r in block.all("XDAT") {
        let i = r.integer(ctx, 0)?;
        if i < 3 || i - 2 > terms {
            continue;
        }
        let k = i - 2;
        let v = r.number(ctx, 1)?;
        if k > 8 {
            if v != 0.0 {
                return Err(ctx.error(
                    r.arg_pos(1),
                    "XDAT",
                    format!(
                        "XASPHERE term {k} (r^{}) is not zero; flarebench reads up to r^16",
                        2 * k
                    ),
                ));
            }
            continue;
        }
        // α_k (r/r0)^(2k) = (α_k / r0^(2k)) r^(2k).
        asph[k - 1] = v / r0.powi(2 * k as i32);
        spans.add("aspheric", "XDAT", r.arg_pos(1));
    }
    Ok(asph)
}

/// The medium after the surface: air without `GLAS`, else the resolved glass (a substitution
/// recorded); a mirror is refused.
fn read_medium(
    ctx: &mut Reporter<'_>,
    block: &Block<'_>,
    glasses: &mut GlassLookup<'_>,
    spans: &mut SurfaceSpans,
) -> Result<Medium, LensFileError> {
    match block.get("GLAS") {
        None => Ok(Medium::Air),
        Some(r) if r.arg(0) == Some("MIRROR") => Err(mirror_error(ctx, block, r)),
        Some(r) => {
            spans.add("refractiveIndex", "GLAS", r.arg_pos(0));
            spans.add("abbeNumber", "GLAS", r.arg_pos(0));
            let g = glass::resolve(
                ctx,
                r,
                glasses.gcat,
                Some(glasses.lambda),
                &mut glasses.seen,
            )?;
            if let Some(s) = g.substitution {
                glasses
                    .substitutions
                    .push(format!("SURF {}: {s}", block.number));
            }
            Ok(g.medium)
        }
    }
}

/// The refracting surface in mm from its shape and even-asphere coefficients in lens units
/// (`mm` millimetres each).
fn refracting_surface(shape: &Shape, asph: &[f64; 8], medium: Medium, mm: f64) -> Surface {
    let mut aspheric = [0.0; 8];
    for (i, a) in asph.iter().enumerate() {
        // z = Σ aᵢ r^(2i): a coefficient in lens units^(1 − 2i) scales by mm^(1 − 2i).
        aspheric[i] = a * mm.powi(1 - 2 * (i as i32 + 1));
    }
    Surface {
        kind: SurfaceKind::Refracting,
        curvature: shape.curvature / mm,
        conic: shape.conic,
        aspheric,
        thickness: shape.thickness * mm,
        medium,
        semi_diameter: shape.semi.map_or(1.0, |s| s * mm),
        ..Surface::spherical(0.0, 0.0, Medium::Air, 1.0)
    }
}

/// The clear semi-diameter in lens units: `CLAP` (circular aperture, `CLAP rmin rmax …`),
/// else `FLAP` (floating aperture), else `DIAM` (Zemax's semi-diameter); `None` when absent or
/// zero.
fn semi_diameter(
    ctx: &mut Reporter<'_>,
    block: &Block<'_>,
    spans: &mut SurfaceSpans,
) -> Result<Option<f64>, LensFileError> {
    for key in ["CLAP", "FLAP"] {
        if let Some(r) = block.get(key) {
            let inner = r.number(ctx, 0)?;
            let outer = r.number(ctx, 1)?;
            if inner > 0.0 {
                ctx.warn(
                    r.arg_pos(0),
                    format!(
                        "SURF {}: the annular aperture's inner radius {inner} is not read",
                        block.number
                    ),
                );
            }
            if outer > 0.0 {
                spans.add(
                    "height",
                    if key == "CLAP" { "CLAP" } else { "FLAP" },
                    r.arg_pos(1),
                );
                return Ok(Some(outer));
            }
        }
    }
    if let Some(r) = block.get("DIAM") {
        let d = r.number(ctx, 0)?;
        if d < 0.0 {
            return Err(ctx.error(
                r.arg_pos(0),
                "DIAM",
                format!("the semi-diameter must not be negative, got {d}"),
            ));
        }
        if d > 0.0 {
            spans.add("height", "DIAM", r.arg_pos(0));
            return Ok(Some(d));
        }
    }
    Ok(None)
}

/// The first validation issue at its record, the others listed in its message.
fn located(
    ctx: &Reporter<'_>,
    spans: &[SurfaceSpans],
    issues: &[ValidationIssue],
    wavelength_pos: usize,
) -> LensFileError {
    let errors = issues
        .iter()
        .map(|issue| {
            let (pos, key) = match issue.surface.and_then(|s| spans.get(s)) {
                Some(sp) => sp.locate(issue.field),
                None if issue.field == "primaryWavelength" => (wavelength_pos, "WAVM"),
                None => (0, ""),
            };
            let which = issue
                .surface
                .map_or(String::new(), |s| format!("surface {s}: "));
            ctx.error(pos, key, format!("{which}{}", issue.message))
        })
        .collect();
    Reporter::combine(errors).expect("validation failed with at least one issue")
}
