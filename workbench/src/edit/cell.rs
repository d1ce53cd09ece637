//! Spreadsheet cells: the columns of the surface table and the header form, how a value is
//! shown, and how typed text is checked and turned into a new surface or header.

use flarebench_sdk::system::curvature_from_radius;
use flarebench_sdk::{Coating, GlassCatalog, Medium, Surface, SurfaceKind};

use super::document::Header;

/// The columns of the surface table, left to right.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    Kind,
    Radius,
    Thickness,
    Glass,
    Nd,
    Vd,
    SemiDiameter,
    Conic,
    Coating,
}

impl Column {
    /// Every column in table order.
    pub const ALL: [Column; 9] = [
        Column::Kind,
        Column::Radius,
        Column::Thickness,
        Column::Glass,
        Column::Nd,
        Column::Vd,
        Column::SemiDiameter,
        Column::Conic,
        Column::Coating,
    ];

    /// The column title.
    pub fn title(self) -> &'static str {
        match self {
            Column::Kind => "kind",
            Column::Radius => "radius",
            Column::Thickness => "thickness",
            Column::Glass => "glass",
            Column::Nd => "nd",
            Column::Vd => "Vd",
            Column::SemiDiameter => "semi-diam",
            Column::Conic => "conic",
            Column::Coating => "coating",
        }
    }

    /// Display width (characters).
    pub fn width(self) -> u16 {
        match self {
            Column::Kind => 7,
            Column::Radius | Column::Thickness | Column::SemiDiameter | Column::Coating => 9,
            Column::Glass => 12,
            Column::Nd => 7,
            Column::Vd => 5,
            Column::Conic => 6,
        }
    }
}

/// The fields of the header form, left to right.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeaderField {
    Name,
    FNumber,
    FilmWidth,
    FilmHeight,
}

impl HeaderField {
    pub const ALL: [HeaderField; 4] = [
        HeaderField::Name,
        HeaderField::FNumber,
        HeaderField::FilmWidth,
        HeaderField::FilmHeight,
    ];

    /// The label shown before the value.
    pub fn title(self) -> &'static str {
        match self {
            HeaderField::Name => "name",
            HeaderField::FNumber => "f-number",
            HeaderField::FilmWidth => "film w",
            HeaderField::FilmHeight => "film h",
        }
    }
}

/// Formats a number compactly: up to 4 decimals, trailing zeros removed.
pub fn fmt_num(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// The text shown in a surface cell.
pub fn show(surface: &Surface, column: Column) -> String {
    match column {
        Column::Kind => match surface.kind {
            SurfaceKind::Refracting => "refract".into(),
            k => k.name().into(),
        },
        Column::Radius => {
            if surface.curvature == 0.0 {
                "flat".into()
            } else {
                fmt_num(surface.radius())
            }
        }
        Column::Thickness => fmt_num(surface.thickness),
        Column::Glass => match &surface.medium {
            Medium::Air => "air".into(),
            Medium::Model { .. } => "model".into(),
            Medium::Glass { name, .. } => name.clone(),
        },
        Column::Nd => match &surface.medium {
            Medium::Air => "1".into(),
            m => format!("{:.5}", m.nd()),
        },
        Column::Vd => surface
            .medium
            .vd()
            .map(|v| format!("{v:.2}"))
            .unwrap_or("-".into()),
        Column::SemiDiameter => fmt_num(surface.semi_diameter),
        Column::Conic => fmt_num(surface.conic),
        Column::Coating => match &surface.coating {
            Coating::None => "none".into(),
            Coating::SingleLayer {
                design_wavelength_nm,
                index,
            } => format!("{}@{}", fmt_num(*index), fmt_num(*design_wavelength_nm)),
            Coating::Stack(layers) => format!("stack×{}", layers.len()),
        },
    }
}

/// The text a cell editor starts with (the value in a form that parses back to itself).
pub fn edit_text(surface: &Surface, column: Column) -> String {
    match column {
        Column::Radius if surface.curvature != 0.0 => format!("{}", surface.radius()),
        Column::Radius => "0".into(),
        Column::Thickness => format!("{}", surface.thickness),
        Column::SemiDiameter => format!("{}", surface.semi_diameter),
        Column::Conic => format!("{}", surface.conic),
        Column::Glass => match &surface.medium {
            Medium::Model { nd, vd: Some(vd) } => format!("{nd}/{vd}"),
            Medium::Model { nd, vd: None } => format!("{nd}"),
            _ => show(surface, column),
        },
        _ => show(surface, column),
    }
}

/// The text shown for a header field.
pub fn show_header(header: &Header, field: HeaderField) -> String {
    match field {
        HeaderField::Name => header.name.clone(),
        HeaderField::FNumber => header.f_number.map(fmt_num).unwrap_or("open".into()),
        HeaderField::FilmWidth => fmt_num(header.film_width_mm),
        HeaderField::FilmHeight => fmt_num(header.film_height_mm),
    }
}

/// The text a header editor starts with.
pub fn header_edit_text(header: &Header, field: HeaderField) -> String {
    match field {
        HeaderField::FNumber => header.f_number.map(|v| format!("{v}")).unwrap_or_default(),
        HeaderField::FilmWidth => format!("{}", header.film_width_mm),
        HeaderField::FilmHeight => format!("{}", header.film_height_mm),
        HeaderField::Name => header.name.clone(),
    }
}

/// Parses a finite number; the message names the column.
fn number(text: &str, what: &str) -> Result<f64, String> {
    let t = text.trim();
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{what}: `{t}` is not a number")),
    }
}

/// `text` as a positive length (mm).
fn positive(text: &str, what: &str) -> Result<f64, String> {
    let v = number(text, what)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{what} must be > 0, got {}", fmt_num(v)))
    }
}

/// Parses the glass cell: `air`, a catalogue name (`N-BK7`, `SCHOTT:N-BK7`), or `nd/Vd`
/// (`1.5168/64.17`), or `nd` alone (non-dispersive).
pub fn parse_medium(text: &str) -> Result<Medium, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("air") {
        return Ok(Medium::Air);
    }
    let first = t
        .chars()
        .next()
        .ok_or("glass: empty (air, a catalogue name or nd/Vd)")?;
    if first.is_ascii_digit() {
        let (nd, vd) = match t.split_once('/') {
            Some((a, b)) => (a, Some(b)),
            None => (t, None),
        };
        let nd = number(nd, "nd")?;
        if !(1.0..=4.0).contains(&nd) {
            return Err(format!("nd must be between 1 and 4, got {}", fmt_num(nd)));
        }
        let vd = vd.map(|v| number(v, "Vd")).transpose()?;
        if let Some(v) = vd
            && !(v > 0.0 && v <= 200.0)
        {
            return Err(format!("Vd must be in (0, 200], got {}", fmt_num(v)));
        }
        return Ok(Medium::Model { nd, vd });
    }
    let entry = GlassCatalog::bundled()
        .find(t)
        .map_err(|e| format!("glass: {e}"))?;
    Ok(Medium::Glass {
        name: entry.canonical_name(),
        dispersion: entry.dispersion().clone(),
    })
}

/// Glass names completing `prefix` (at most `max`), from the bundled catalogue.
pub fn glass_completions(prefix: &str, max: usize) -> Vec<String> {
    let p = prefix.trim();
    if p.is_empty() || p.starts_with(|c: char| c.is_ascii_digit()) {
        return Vec::new();
    }
    let mut names = GlassCatalog::bundled().complete(p);
    names.truncate(max);
    names
}

/// Parses a coating cell: `none`, or `INDEX@WAVELENGTH_NM` (a quarter-wave single layer).
fn parse_coating(text: &str, old: &Coating) -> Result<Coating, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("none") || t.is_empty() {
        return Ok(Coating::None);
    }
    if matches!(old, Coating::Stack(_)) && t.starts_with("stack") {
        return Ok(old.clone());
    }
    let (n, wl) = t
        .split_once('@')
        .ok_or("coating: `none` or INDEX@WAVELENGTH_NM, e.g. 1.38@550")?;
    let index = number(n, "coating index")?;
    let wl = number(wl, "coating wavelength")?;
    if !(1.0..=3.0).contains(&index) {
        return Err(format!(
            "coating index must be between 1 and 3, got {}",
            fmt_num(index)
        ));
    }
    if !(200.0..=2500.0).contains(&wl) {
        return Err(format!(
            "coating wavelength must be 200–2500 nm, got {}",
            fmt_num(wl)
        ));
    }
    Ok(Coating::SingleLayer {
        design_wavelength_nm: wl,
        index,
    })
}

/// Checks `text` typed into `column` of `surface` and returns the edited surface, or a
/// message saying what is wrong. Checks here are per cell; the document then checks the whole
/// system (one stop, sensor last, semi-diameter within the radius, …).
pub fn parse_cell(surface: &Surface, column: Column, text: &str) -> Result<Surface, String> {
    let mut s = surface.clone();
    match column {
        Column::Kind => {
            s.kind = match text.trim().to_ascii_lowercase().as_str() {
                "refracting" | "refract" | "r" => SurfaceKind::Refracting,
                "stop" | "s" | "aperturestop" => SurfaceKind::ApertureStop,
                "sensor" => SurfaceKind::Sensor,
                t => return Err(format!("kind: `{t}` is not refracting, stop or sensor")),
            };
        }
        Column::Radius => {
            let t = text.trim();
            let r = if matches!(t, "flat" | "inf" | "infinity") {
                0.0
            } else {
                number(t, "radius")?
            };
            s.curvature = curvature_from_radius(r);
        }
        Column::Thickness => {
            let v = number(text, "thickness")?;
            if v < 0.0 {
                return Err(format!("thickness must be ≥ 0, got {}", fmt_num(v)));
            }
            s.thickness = v;
        }
        Column::Glass => s.medium = parse_medium(text)?,
        Column::Nd => {
            let nd = number(text, "nd")?;
            if !(1.0..=4.0).contains(&nd) {
                return Err(format!("nd must be between 1 and 4, got {}", fmt_num(nd)));
            }
            s.medium = if nd == 1.0 && s.medium.vd().is_none() {
                Medium::Air
            } else {
                Medium::Model {
                    nd,
                    vd: s.medium.vd(),
                }
            };
        }
        Column::Vd => {
            let t = text.trim();
            if s.medium.is_air() {
                return Err("Vd: air has no Abbe number; set nd or a glass first".into());
            }
            let vd = if t == "-" || t.is_empty() {
                None
            } else {
                let v = number(t, "Vd")?;
                if !(v > 0.0 && v <= 200.0) {
                    return Err(format!("Vd must be in (0, 200], got {}", fmt_num(v)));
                }
                Some(v)
            };
            s.medium = Medium::Model {
                nd: s.medium.nd(),
                vd,
            };
        }
        Column::SemiDiameter => s.semi_diameter = positive(text, "semi-diameter")?,
        Column::Conic => s.conic = number(text, "conic")?,
        Column::Coating => s.coating = parse_coating(text, &s.coating)?,
    }
    Ok(s)
}

/// Checks `text` typed into a header field and returns the edited header.
pub fn parse_header(header: &Header, field: HeaderField, text: &str) -> Result<Header, String> {
    let mut h = header.clone();
    match field {
        HeaderField::Name => {
            let t = text.trim();
            if t.is_empty() {
                return Err("name: must not be empty".into());
            }
            h.name = t.to_string();
        }
        HeaderField::FNumber => {
            let t = text.trim();
            h.f_number = if t.is_empty() || t == "open" {
                None
            } else {
                let v = number(t, "f-number")?;
                if !(0.5..=128.0).contains(&v) {
                    return Err(format!("f-number must be 0.5–128, got {}", fmt_num(v)));
                }
                Some(v)
            };
        }
        HeaderField::FilmWidth => h.film_width_mm = positive(text, "film width")?,
        HeaderField::FilmHeight => h.film_height_mm = positive(text, "film height")?,
    }
    Ok(h)
}

/// A cell being edited: its text and the caret (a char index).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CellEditor {
    pub text: String,
    pub caret: usize,
    /// Which completion Ctrl-n / Ctrl-p last chose (glass cells).
    pub completion: Option<usize>,
    /// The text the completions are computed from.
    pub typed: String,
}

impl CellEditor {
    /// An editor holding `text` with the caret at its end.
    pub fn new(text: String) -> Self {
        let caret = text.chars().count();
        CellEditor {
            typed: text.clone(),
            text,
            caret,
            completion: None,
        }
    }

    fn byte(&self, char_index: usize) -> usize {
        self.text
            .char_indices()
            .nth(char_index)
            .map_or(self.text.len(), |(b, _)| b)
    }

    /// Inserts `c` at the caret.
    pub fn insert(&mut self, c: char) {
        let b = self.byte(self.caret);
        self.text.insert(b, c);
        self.caret += 1;
        self.typed = self.text.clone();
        self.completion = None;
    }

    /// Deletes the character before the caret.
    pub fn backspace(&mut self) {
        if self.caret > 0 {
            self.caret -= 1;
            let b = self.byte(self.caret);
            self.text.remove(b);
            self.typed = self.text.clone();
            self.completion = None;
        }
    }

    /// Deletes the character at the caret.
    pub fn delete(&mut self) {
        if self.caret < self.text.chars().count() {
            let b = self.byte(self.caret);
            self.text.remove(b);
            self.typed = self.text.clone();
            self.completion = None;
        }
    }

    /// Moves the caret by `delta` characters, within the text.
    pub fn move_caret(&mut self, delta: isize) {
        let len = self.text.chars().count() as isize;
        self.caret = (self.caret as isize + delta).clamp(0, len) as usize;
    }

    /// Caret to the start / end.
    pub fn home(&mut self) {
        self.caret = 0;
    }
    pub fn end(&mut self) {
        self.caret = self.text.chars().count();
    }

    /// Clears the text.
    pub fn clear(&mut self) {
        self.text.clear();
        self.typed.clear();
        self.caret = 0;
        self.completion = None;
    }

    /// Replaces the text with the next (`step` = 1) or previous (−1) of `candidates`.
    pub fn cycle(&mut self, candidates: &[String], step: isize) {
        if candidates.is_empty() {
            return;
        }
        let n = candidates.len() as isize;
        let i = match self.completion {
            None if step > 0 => 0,
            None => n - 1,
            Some(i) => (i as isize + step).rem_euclid(n),
        };
        self.completion = Some(i as usize);
        self.text = candidates[i as usize].clone();
        self.caret = self.text.chars().count();
    }
}
