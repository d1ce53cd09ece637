//! `flarebench trace`: one collimated ray through a lens, surface by surface.

use clap::Args;
use flarebench_sdk::trace::{Fate, Hit, Interaction, Ray, Sequence};
use serde::Serialize;

use super::wavelength;
use crate::lens_library::{self, ReadArgs};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct TraceArgs {
    /// Lens file (OpenLensFlare/flarebench `.xml`, Zemax `.zmx`, PBRT `.dat`, FlareSim
    /// `.lens`) or the name of a bundled lens.
    pub lens: String,
    /// Angle of the ray to the optical axis (degrees), in the y–z plane before rotation.
    #[arg(long, allow_negative_numbers = true)]
    pub field_deg: f64,
    /// Height (mm) at which the ray crosses the plane of the front vertex.
    #[arg(long, allow_negative_numbers = true)]
    pub height_mm: f64,
    /// Rotation of the ray's plane about the axis (degrees).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub azimuth_deg: f64,
    /// Wavelength (nm); default: the lens's primary wavelength (Zemax PWAV), else the d line,
    /// 587.5618 nm.
    #[arg(long)]
    pub wavelength_nm: Option<f64>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
}

#[derive(Debug, Serialize)]
struct HitJson {
    surface: usize,
    interaction: &'static str,
    x_mm: f64,
    y_mm: f64,
    z_mm: f64,
    dir: [f64; 3],
    relative_radius: f64,
    incidence_deg: f64,
}

#[derive(Debug, Serialize)]
struct TraceJson {
    lens: String,
    wavelength_nm: f64,
    /// `sensor`, `vignetted`, `tir`, `missed` or `no_convergence`.
    fate: &'static str,
    /// The surface where the fate happened (none for `sensor`).
    fate_surface: Option<usize>,
    /// Where the ray meets the sensor plane; null when tracing stopped before it.
    x_mm: Option<f64>,
    y_mm: Option<f64>,
    max_relative_radius: f64,
    /// Fresnel/coating transmittance along the path.
    throughput: f64,
    hits: Vec<HitJson>,
}

fn interaction_name(i: Interaction) -> &'static str {
    match i {
        Interaction::Refract => "refract",
        Interaction::Reflect => "reflect",
        Interaction::Sensor => "sensor",
    }
}

fn hit_json(h: &Hit) -> HitJson {
    HitJson {
        surface: h.surface,
        interaction: interaction_name(h.interaction),
        x_mm: h.position.x,
        y_mm: h.position.y,
        z_mm: h.position.z,
        dir: h.direction.to_array(),
        relative_radius: h.relative_radius,
        incidence_deg: h.incidence_rad.to_degrees(),
    }
}

pub fn run(args: &TraceArgs, quiet: bool) -> anyhow::Result<()> {
    if let Some(nm) = args.wavelength_nm {
        wavelength(nm)?;
    }
    anyhow::ensure!(
        args.field_deg.is_finite() && args.field_deg.abs() < 90.0,
        "--field-deg must be between -90 and 90 degrees (exclusive), got {}",
        args.field_deg
    );
    anyhow::ensure!(
        args.height_mm.is_finite(),
        "--height-mm must be a finite number"
    );
    anyhow::ensure!(
        args.azimuth_deg.is_finite(),
        "--azimuth-deg must be a finite number"
    );
    let loaded = lens_library::load_with(&args.lens, quiet || args.json, &args.read.options())?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    let lambda = wavelength(args.wavelength_nm.unwrap_or(sys.default_wavelength_nm()))?;
    let seq = Sequence::forward(sys, lambda);
    let ray = Ray::collimated(
        args.field_deg.to_radians(),
        args.azimuth_deg.to_radians(),
        args.height_mm,
    );
    let mut hits = Vec::new();
    let r = seq.trace_with_hits(&ray, &mut hits);
    let landing = r.completed.then_some(r.ray.origin);
    if args.json {
        let out = TraceJson {
            lens: sys.name.clone(),
            wavelength_nm: lambda,
            fate: r.fate.kind(),
            fate_surface: r.fate.surface(),
            x_mm: landing.map(|p| p.x),
            y_mm: landing.map(|p| p.y),
            max_relative_radius: r.max_relative_radius,
            throughput: r.throughput,
            hits: hits.iter().map(hit_json).collect(),
        };
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    let mut t = Table::new(&[
        "surface",
        "action",
        "x",
        "y",
        "z",
        "dir x",
        "dir y",
        "dir z",
        "r/semi",
        "incidence°",
    ]);
    for h in &hits {
        t.row(vec![
            h.surface.to_string(),
            interaction_name(h.interaction).into(),
            format!("{:.6}", h.position.x),
            format!("{:.6}", h.position.y),
            format!("{:.6}", h.position.z),
            format!("{:.6}", h.direction.x),
            format!("{:.6}", h.direction.y),
            format!("{:.6}", h.direction.z),
            format!("{:.4}", h.relative_radius),
            format!("{:.3}", h.incidence_rad.to_degrees()),
        ]);
    }
    print!("{}", t.render());
    match (r.fate, landing) {
        (Fate::Sensor, Some(p)) => {
            println!("reached the sensor at x = {:.6} mm, y = {:.6} mm", p.x, p.y)
        }
        (f, Some(p)) => println!(
            "{f}; it would meet the sensor at x = {:.6} mm, y = {:.6} mm",
            p.x, p.y
        ),
        (f, None) => println!("{f}; it does not reach the sensor plane"),
    }
    println!("Fresnel/coating throughput: {:.6}", r.throughput);
    Ok(())
}
