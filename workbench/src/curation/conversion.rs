//! One selected FlareSim lens as a bundled lens: read by the `.lens` reader (as `flarebench
//! convert` reads it), given its maker, kind, zoom range and film, its rear glass-to-air faces
//! coated like their element's front face, and its source and notes written.

use std::path::Path;

use anyhow::Context;
use flarebench_sdk::io::{ReadOptions, flaresim_coating, read_lens_with};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::{Coating, LensSystem, SurfaceKind};

use super::film::Film;
use super::selection::Entry;

/// FlareSim's library, its file and licence, as every curated lens's source names them.
pub const LIBRARY: &str = "FlareSim lens library (github.com/petermercell/flaresim_nuke, \
                           lenses/lens_files/; MIT licence, its notice in \
                           lenses/LICENSE-flaresim)";

/// A stated f-number this much slower than the stop wide open is noted as closing the stop
/// (0.5%: below it the difference is the files' rounding of the f-number).
const F_NUMBER_NOTE_RATIO: f64 = 1.005;

/// The layer count of a coating the `.lens` reader made (0, 1, 2).
fn layers(c: &Coating) -> u8 {
    match c {
        Coating::None => 0,
        Coating::SingleLayer { .. } => 1,
        Coating::Stack(l) => l.len().min(2) as u8,
    }
}

/// Coats every uncoated glass-to-air face with the coating of its element's front face (the
/// first face of the glass, or of the cemented group, it ends), designed for its own glass;
/// returns the faces coated (0-based).
pub fn coat_rear_faces(system: &mut LensSystem, lambda_nm: f64) -> Vec<usize> {
    let n: Vec<f64> = system.indices(lambda_nm);
    let nd: Vec<f64> = (0..system.surfaces.len())
        .map(|i| system.medium_before(i).nd())
        .collect();
    let mut coated = Vec::new();
    for i in 0..system.sensor_index() {
        let s = &system.surfaces[i];
        let glass_to_air =
            s.kind == SurfaceKind::Refracting && n[i] != 1.0 && system.surfaces[i].medium.is_air();
        if !glass_to_air || s.coating != Coating::None {
            continue;
        }
        // The front face: back to the last surface with air before it.
        let Some(front) = (0..i).rev().find(|&j| n[j] == 1.0) else {
            continue;
        };
        let count = layers(&system.surfaces[front].coating);
        if count == 0 {
            continue;
        }
        if let Some(c) = flaresim_coating(count, nd[i], 1.0) {
            system.surfaces[i].coating = c;
            coated.push(i);
        }
    }
    coated
}

/// Reads `entry`'s file from `corpus` (FlareSim's `lens_files/`) and makes it the bundled
/// lens, without its checks (see [`super::checks`]).
pub fn convert(entry: &Entry, corpus: &Path) -> anyhow::Result<LensSystem> {
    let path = corpus.join(&entry.file);
    let loaded = read_lens_with(&path, &ReadOptions::default())
        .with_context(|| format!("line {}: could not load `{}`", entry.line, entry.file))?;
    let mut sys = loaded.system;
    sys.maker = entry.maker.clone();
    sys.kind = entry.kind.clone();
    sys.nominal_focal_mm = Some(entry.nominal_focal_mm);
    let (w, h) = entry.film.size_mm();
    sys.film_width_mm = w;
    sys.film_height_mm = h;
    let sensor = sys.sensor_index();
    sys.surfaces[sensor].semi_diameter = 0.5 * w.hypot(h);
    let lambda = sys.default_wavelength_nm();
    let coated = coat_rear_faces(&mut sys, lambda);

    let patent = sys
        .source
        .split("; ")
        .find(|p| p.starts_with("Patent:"))
        .map(|p| format!("; {p}"))
        .unwrap_or_default();
    sys.source = format!(
        "{LIBRARY}, file {}, converted there from the Optical Bench data of \
         photonstophotos.net (published patent data){patent}",
        entry.file
    );
    let mut notes = vec![format!(
        "Bundled from FlareSim's lens library (file {}; MIT licence, lenses/LICENSE-flaresim) \
         by `flarebench curate` from lenses/sources/flaresim-selection.txt.",
        entry.file
    )];
    if !sys.notes.trim().is_empty() {
        notes.push(sys.notes.trim().to_string());
    }
    notes.push(if entry.film == Film::FullFrame {
        format!(
            "Film: {} (FlareSim's for every lens; kept: the name names no other system).",
            entry.film
        )
    } else {
        format!(
            "Film: {}, from the system the lens's name names; FlareSim gave every lens 36 × 24 \
             mm.",
            entry.film
        )
    });
    if !coated.is_empty() {
        let list: Vec<String> = coated.iter().map(usize::to_string).collect();
        notes.push(format!(
            "Coatings: FlareSim's converter coats only the surfaces followed by glass; the \
             rear glass-to-air faces (surfaces {}) carry their element's front-face coating \
             here, designed for their own glass.",
            list.join(", ")
        ));
    }
    if let (None, Ok(p)) = (sys.f_number, analyse(&sys, lambda)) {
        // A lens listed and filtered by its f-number needs one: the stop wide open.
        sys.f_number = Some(p.open_f_number);
        notes.push(format!(
            "F-number: the file states none; the setting is the stop wide open, f/{:.3}.",
            p.open_f_number
        ));
    } else if let (Some(stated), Ok(p)) = (sys.f_number, analyse(&sys, lambda)) {
        let open = p.open_f_number;
        let stop = sys.stop_index().map(|i| &sys.surfaces[i]);
        let widest_lens = sys
            .surfaces
            .iter()
            .filter(|s| s.kind == SurfaceKind::Refracting)
            .map(|s| s.semi_diameter)
            .fold(0.0, f64::max);
        if let Some(stop) = stop.filter(|s| s.semi_diameter > widest_lens) {
            // A placeholder size (FlareSim writes 1000000 for a stop it does not know).
            notes.push(format!(
                "F-number: the file's stop row gives no size (semi-diameter {} mm, wider than \
                 every surface); the stated f/{stated} sets it.",
                stop.semi_diameter
            ));
        } else if stated > open * F_NUMBER_NOTE_RATIO {
            notes.push(format!(
                "F-number: the stated f/{stated} closes the stop to {:.1}% of its diameter \
                 (wide open the prescription is f/{open:.3}).",
                100.0 * open / stated
            ));
        } else if stated * F_NUMBER_NOTE_RATIO < open {
            notes.push(format!(
                "F-number: wide open the prescription is f/{open:.3}, slower than the stated \
                 f/{stated}; the stop stays wide open."
            ));
        }
    }
    sys.notes = notes.join("\n");
    Ok(sys)
}
