//! A gallery's two overviews: `contact.png`, every lens's flare in rows under its name, maker,
//! focal length and f-number; and `index.html`, an offline page (no scripts or styles from
//! elsewhere) with each lens's flare, its section and the render's figures, and a box that
//! filters the cards by any word on them.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use flarebench_sdk::image::HdrImage;

use super::section::escape;
use super::{LENS_DIR, Record, Settings, StandardLight};
use crate::flare::StarburstMode;
use crate::input_image::read_input_image;
use crate::lens_listing::focal_text;
use crate::output::{ToneMap, ToneOperator, save_image};
use crate::sweep::sheet::{THUMB_WIDTH, Tile, contact_sheet, thumbnail};

/// Tiles per row of the contact sheet.
pub const SHEET_COLUMNS: usize = 6;

/// The second line under a lens: maker, focal length, f-number.
fn caption(r: &Record) -> String {
    let maker = if r.maker.is_empty() { "" } else { &r.maker };
    format!("{maker} {} mm f/{:.1}", focal_text(r.focal_mm), r.f_number)
        .trim()
        .to_string()
}

/// The short name of a lens: its file stem without the maker folder.
fn short(r: &Record) -> &str {
    r.name.rsplit('/').next().unwrap_or(&r.name)
}

/// Writes `contact.png` in `dir` from the lenses' PNGs (decoded to linear and written back with
/// the clamp curve, so each tile keeps its own exposure).
pub fn write_contact_sheet(records: &[Record], dir: &Path) -> anyhow::Result<()> {
    let mut thumbs: Vec<HdrImage> = Vec::with_capacity(records.len());
    for r in records {
        let img = read_input_image(&dir.join(LENS_DIR).join(&r.image))?.image;
        thumbs.push(thumbnail(&img, THUMB_WIDTH));
    }
    let w = thumbs.iter().map(|t| t.width).max().unwrap_or(1);
    let h = thumbs.iter().map(|t| t.height).max().unwrap_or(1);
    let tiles: Vec<Tile<'_>> = records
        .iter()
        .zip(&thumbs)
        .map(|(r, t)| Tile {
            image: Some(t),
            // The sheet's font has no en dash.
            lines: [short(r).to_string(), caption(r).replace('–', "-")],
        })
        .collect();
    let sheet = contact_sheet(&tiles, SHEET_COLUMNS, w, h, 1.0);
    save_image(
        &sheet,
        &dir.join("contact.png"),
        &ToneMap {
            exposure_ev: 0.0,
            operator: ToneOperator::Clamp,
        },
    )
}

/// What the page says the gallery was made with.
fn settings_text(s: &Settings) -> String {
    let light = match &s.light {
        StandardLight::Field { fraction, phi_deg } => format!(
            "one light at {:.0}% of the way to the edge of each lens's field, azimuth {phi_deg}°",
            100.0 * fraction
        ),
        StandardLight::Fixed(l) => format!("one light at {}°, {}°", l.theta_deg, l.phi_deg),
    };
    let exposure = match s.exposure_ev {
        Some(ev) => format!("exposure {ev:+} EV for every lens"),
        None => {
            "each lens at its own exposure (its ghosts' brightest at a quarter of white)".into()
        }
    };
    let starburst = match s.starburst {
        StarburstMode::On => "with its starburst",
        StarburstMode::Off => "ghosts only",
        StarburstMode::Only => "starburst only",
    };
    format!(
        "{}×{}, the {} preset, {starburst}; {light}; {exposure}",
        s.size.0, s.size.1, s.quality
    )
}

/// Writes `index.html` in `dir`.
pub fn write_index(records: &[Record], settings: &Settings, dir: &Path) -> anyhow::Result<()> {
    let mut out = String::new();
    out.push_str(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>flarebench gallery</title>\n<style>\n\
         body{font-family:sans-serif;margin:1em;background:#f4f4f4;color:#222}\n\
         #cards{display:grid;grid-template-columns:repeat(auto-fill,minmax(330px,1fr));gap:12px}\n\
         .card{background:#fff;border-radius:6px;padding:8px;box-shadow:0 1px 3px #0002}\n\
         .card img{width:100%;display:block}\n\
         .flare{background:#000}\n\
         .card h2{font-size:1em;margin:.4em 0 .1em;word-break:break-all}\n\
         .card p{margin:.2em 0;font-size:.85em}\n\
         .figures{color:#555}\n\
         input{font-size:1em;padding:.3em;width:20em}\n\
         </style>\n</head>\n<body>\n",
    );
    let _ = writeln!(
        out,
        "<h1>flarebench gallery: {} lenses</h1>\n<p>{}. <a href=\"contact.png\">Contact \
         sheet</a>.</p>\n<p><input id=\"filter\" type=\"search\" placeholder=\"filter: maker, \
         name, kind, focal length…\"> <span id=\"shown\"></span></p>\n<div id=\"cards\">",
        records.len(),
        escape(&settings_text(settings))
    );
    for r in records {
        let kind = r.kind.join(" ");
        let words = format!(
            "{} {} {} {} {} mm f/{:.1}",
            r.name,
            r.title,
            r.maker,
            kind,
            focal_text(r.focal_mm),
            r.f_number
        )
        .to_lowercase();
        let _ = writeln!(
            out,
            "<div class=\"card\" data-words=\"{}\">\n\
             <img class=\"flare\" src=\"{LENS_DIR}/{}\" alt=\"flare of {}\" loading=\"lazy\">\n\
             <img src=\"{LENS_DIR}/{}\" alt=\"section of {}\" loading=\"lazy\">\n\
             <h2>{}</h2>\n<p>{}</p>\n<p>{} · {} elements · {}</p>\n\
             <p class=\"figures\">light {:.1}°, {:.0}° (field edge {:.1}°) · {} of {} ghosts \
             drawn · ghost energy {:.2e} of the direct image · {:.0} ms (plan {:.0}, ghosts \
             {:.0}, starburst {:.0}) · {:+.1} EV</p>\n</div>",
            escape(&words),
            escape(&r.image),
            escape(&r.title),
            escape(&r.section),
            escape(&r.title),
            escape(&r.name),
            escape(&r.title),
            escape(&caption(r)),
            r.elements,
            if kind.is_empty() {
                "-".into()
            } else {
                escape(&kind)
            },
            r.light_theta_deg,
            r.light_phi_deg,
            r.field_edge_deg,
            r.ghosts_drawn,
            r.ghosts_total,
            r.ghost_energy_share,
            r.total_ms,
            r.plan_ms,
            r.ghosts_ms,
            r.starburst_ms,
            r.exposure_ev
        );
    }
    out.push_str(
        "</div>\n<script>\n\
         const box = document.getElementById('filter');\n\
         const cards = [...document.querySelectorAll('.card')];\n\
         function show() {\n\
         \x20 const words = box.value.toLowerCase().split(/\\s+/).filter(w => w);\n\
         \x20 let n = 0;\n\
         \x20 for (const c of cards) {\n\
         \x20   const on = words.every(w => c.dataset.words.includes(w));\n\
         \x20   c.style.display = on ? '' : 'none';\n\
         \x20   n += on;\n\
         \x20 }\n\
         \x20 document.getElementById('shown').textContent = n + ' of ' + cards.length;\n\
         }\n\
         box.addEventListener('input', show);\n\
         show();\n\
         </script>\n</body>\n</html>\n",
    );
    let path = dir.join("index.html");
    std::fs::write(&path, out).with_context(|| format!("could not write `{}`", path.display()))
}
