//! `flarebench gallery`: lenses side by side. Each lens's flare is rendered at a standard light
//! (a fraction of the way to the edge of its own field, so the light is in every lens's frame)
//! with its lens section beside it, into a folder that holds a contact sheet and an offline
//! `index.html`. Each lens's result is kept with the key of what made it (the lens file's
//! bytes, the settings, the build's version), so a second run renders only what changed and an
//! interrupted run resumes.
//!
//! - [`record`]: what a lens's render gave, kept as JSON beside its image.
//! - [`section`]: the lens in meridional section as SVG.
//! - [`page`]: the contact sheet and `index.html`.

pub mod page;
pub mod record;
pub mod section;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::hash::fnv1a_hex;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::analyse;
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::{LightSpec, Quality};

use crate::flare::{Flare, Preset, Scene, StarburstMode, frame_for};
use crate::lens_listing::{elements, f_number, named_focal_mm};
use crate::output::{ToneMap, save_image};
use crate::stability::field;

pub use record::Record;

/// Folder of the per-lens files inside the gallery's folder.
pub const LENS_DIR: &str = "lenses";

/// Where the light of every lens's frame is.
#[derive(Clone, Debug, PartialEq)]
pub enum StandardLight {
    /// At `fraction` of the angle to the edge of the lens's field (where its chief ray lands
    /// on the film's corner), at azimuth `phi_deg`.
    Field { fraction: f64, phi_deg: f64 },
    /// The same direction for every lens.
    Fixed(LightSpec),
}

/// What every lens of a gallery is rendered with.
#[derive(Clone, Debug)]
pub struct Settings {
    pub size: (usize, usize),
    pub quality: Quality,
    pub light: StandardLight,
    pub starburst: StarburstMode,
    /// PNG exposure (stops); `None`: each lens's automatic exposure (its ghosts' brightest at
    /// a quarter of white), written in its record.
    pub exposure_ev: Option<f32>,
}

impl Settings {
    /// The settings as text, part of every record's key.
    fn key_text(&self) -> String {
        format!(
            "{}x{} {:?} {:?} {:?} {:?}",
            self.size.0, self.size.1, self.quality, self.light, self.starburst, self.exposure_ev
        )
    }
}

/// A lens of the gallery: its name (`maker/stem` for a bundled lens, else the path given) and
/// its file.
#[derive(Clone, Debug, PartialEq)]
pub struct GalleryLens {
    pub name: String,
    pub path: PathBuf,
}

impl GalleryLens {
    /// The stem of its files in the gallery: the name with `/` as `--` and anything but
    /// letters, digits, `.`, `-` and `_` as `_`.
    pub fn slug(&self) -> String {
        self.name
            .replace('/', "--")
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    }
}

/// The key of `lens`'s render with `settings`: the file's bytes, the settings and this
/// build's version.
pub fn key(lens: &GalleryLens, settings: &Settings) -> anyhow::Result<String> {
    let bytes = std::fs::read(&lens.path)
        .with_context(|| format!("could not read `{}`", lens.path.display()))?;
    let mut text = fnv1a_hex(&bytes);
    text.push(' ');
    text.push_str(&settings.key_text());
    text.push(' ');
    text.push_str(env!("CARGO_PKG_VERSION"));
    Ok(fnv1a_hex(text.as_bytes()))
}

/// The record kept in `dir` for `lens`, when it was made with `key` and its files are there.
pub fn cached(lens: &GalleryLens, key: &str, dir: &Path) -> Option<Record> {
    let lens_dir = dir.join(LENS_DIR);
    let text = std::fs::read_to_string(lens_dir.join(format!("{}.json", lens.slug()))).ok()?;
    let record: Record = serde_json::from_str(&text).ok()?;
    (record.key == key
        && lens_dir.join(&record.image).is_file()
        && lens_dir.join(&record.section).is_file())
    .then_some(record)
}

/// Renders `lens` into `dir` (its image, its section, then its record, which is written last
/// so that a run cut short leaves no record of a lens whose files are missing).
pub fn render(
    lens: &GalleryLens,
    key: String,
    settings: &Settings,
    dir: &Path,
) -> anyhow::Result<Record> {
    let sys = read_lens(&lens.path)
        .with_context(|| format!("could not load `{}`", lens.path.display()))?
        .system;
    let paraxial =
        analyse(&sys, sys.default_wavelength_nm()).with_context(|| format!("`{}`", lens.name))?;
    let edge_deg = field::edge_deg(&sys);
    let light = match &settings.light {
        StandardLight::Field { fraction, phi_deg } => {
            LightSpec::parse(&format!("{},{phi_deg}", fraction * edge_deg))
                .map_err(anyhow::Error::msg)?
        }
        StandardLight::Fixed(l) => l.clone(),
    };
    let lights = [light];
    let aperture = Aperture::Circular;
    let frame = frame_for(&sys, settings.size);
    let scene = Scene {
        starburst: settings.starburst,
        ..Scene::new(&sys, &lights, &aperture, frame)
    };
    let preset = Preset {
        exposure: settings.exposure_ev.is_none(),
        ..Preset::new(PlanOptions::for_quality(settings.quality, None))
    };
    let t = Instant::now();
    // One lens per thread: the lenses are rendered in parallel, the CPU backend each.
    let mut flare = Flare::open(crate::flare::BackendChoice::Cpu)?;
    let rendered = flare.render(&scene, &preset)?;
    let total_ms = t.elapsed().as_secs_f64() * 1e3;
    let exposure_ev = settings.exposure_ev.or(rendered.exposure_ev).unwrap_or(0.0);

    let lens_dir = dir.join(LENS_DIR);
    let slug = lens.slug();
    let image = format!("{slug}.png");
    save_image(
        flare.image(),
        &lens_dir.join(&image),
        &ToneMap {
            exposure_ev,
            ..ToneMap::default()
        },
    )?;
    let section = format!("{slug}-section.svg");
    let svg_path = lens_dir.join(&section);
    std::fs::write(&svg_path, section::svg(&sys))
        .with_context(|| format!("could not write `{}`", svg_path.display()))?;

    let report = rendered.light_reports();
    let record = Record {
        key,
        name: lens.name.clone(),
        file: lens.path.display().to_string(),
        title: sys.name.clone(),
        maker: sys.maker.clone(),
        kind: sys.kind.iter().map(|k| k.name().to_string()).collect(),
        focal_mm: named_focal_mm(&sys, &paraxial),
        f_number: f_number(&sys, &paraxial),
        elements: elements(&sys),
        field_edge_deg: edge_deg,
        light_theta_deg: lights[0].theta_deg,
        light_phi_deg: lights[0].phi_deg,
        ghosts_drawn: rendered.ghosts_drawn(),
        ghosts_total: report.iter().map(|r| r.ghosts_total).sum(),
        ghost_energy_share: report.iter().map(|r| r.ghost_energy_share).sum(),
        exposure_ev,
        plan_ms: rendered.timings.plan_ms,
        ghosts_ms: rendered.timings.ghosts_ms,
        starburst_ms: rendered.timings.starburst_ms,
        total_ms,
        image,
        section,
    };
    record.save(&lens_dir.join(format!("{slug}.json")))?;
    Ok(record)
}
