//! A lens's render in a gallery, kept as `lenses/<slug>.json` beside its image and section:
//! what the lens is, where the light was and what the render gave.

use std::path::Path;

use anyhow::Context;
use serde::{Deserialize, Serialize};

/// One lens of a gallery.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// What made it ([`super::key`]): the record is reused while this stays the same.
    pub key: String,
    /// `maker/stem` for a bundled lens, else the path given.
    pub name: String,
    /// The lens file.
    pub file: String,
    /// The lens's own name.
    pub title: String,
    /// Empty when the file names none.
    pub maker: String,
    pub kind: Vec<String>,
    /// The focal length the lens is named by (a zoom's shortest and longest; the stated or
    /// paraxial one twice when the file names none), mm.
    pub focal_mm: [f64; 2],
    pub f_number: f64,
    pub elements: usize,
    /// The edge of the lens's field: where its chief ray lands on the film's corner (degrees).
    pub field_edge_deg: f64,
    pub light_theta_deg: f64,
    pub light_phi_deg: f64,
    /// Ghosts drawn, and two-reflection ghost paths in all.
    pub ghosts_drawn: usize,
    pub ghosts_total: usize,
    /// The ghosts' energy over the light's direct image.
    pub ghost_energy_share: f64,
    /// The PNG's exposure (stops).
    pub exposure_ev: f32,
    /// Time per stage of the frame, and the whole render with the renderer opened (ms).
    pub plan_ms: f64,
    pub ghosts_ms: f64,
    pub starburst_ms: f64,
    pub total_ms: f64,
    /// The tone-mapped image and the lens section, file names in `lenses/`.
    pub image: String,
    pub section: String,
}

impl Record {
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(self)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("could not write `{}`", path.display()))
    }
}
