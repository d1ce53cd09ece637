//! `flarebench info`: the prescription as a table and its paraxial data.

use clap::Args;
use flarebench_sdk::paraxial::{ParaxialData, analyse};
use flarebench_sdk::{Coating, LensSystem};
use serde::Serialize;

use super::{fmt_len, wavelength};
use crate::lens_library::{self, ReadArgs};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Lens file (OpenLensFlare/flarebench `.xml`, Zemax `.zmx`, PBRT `.dat`, FlareSim
    /// `.lens`) or the name of a bundled lens.
    pub lens: String,
    /// Wavelength for indices and paraxial data (nm); default: the lens's primary wavelength
    /// (Zemax PWAV), else the d line, 587.5618 nm.
    #[arg(long)]
    pub wavelength_nm: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Print one JSON object instead of tables.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
}

/// One surface as shown in the table and in JSON.
#[derive(Debug, Serialize)]
struct SurfaceRow {
    index: usize,
    kind: &'static str,
    radius_mm: Option<f64>,
    thickness_mm: f64,
    glass: String,
    /// Index at the chosen wavelength, nd and Vd of the medium after the surface.
    n: f64,
    nd: f64,
    vd: Option<f64>,
    semi_diameter_mm: f64,
    conic: f64,
    aspheric: bool,
    coating: String,
}

#[derive(Debug, Serialize)]
struct InfoJson<'a> {
    name: &'a str,
    file: String,
    stated_efl_mm: Option<f64>,
    stated_f_number: Option<f64>,
    primary_wavelength_nm: Option<f64>,
    film_width_mm: f64,
    film_height_mm: f64,
    #[serde(flatten)]
    paraxial: ParaxialData,
    surfaces: Vec<SurfaceRow>,
    warnings: &'a [String],
}

fn coating_label(c: &Coating) -> String {
    match c {
        Coating::None => String::new(),
        Coating::SingleLayer {
            design_wavelength_nm,
            index,
        } => {
            format!("λ/4 n={index} @{design_wavelength_nm}nm")
        }
        Coating::Stack(layers) => format!("{} layers", layers.len()),
    }
}

fn rows(sys: &LensSystem, lambda: f64) -> Vec<SurfaceRow> {
    sys.surfaces
        .iter()
        .enumerate()
        .map(|(i, s)| SurfaceRow {
            index: i,
            kind: s.kind.name(),
            radius_mm: s.radius().is_finite().then(|| s.radius()),
            thickness_mm: s.thickness,
            glass: s.medium.label(),
            n: s.medium.index(lambda),
            nd: s.medium.nd(),
            vd: s.medium.vd(),
            semi_diameter_mm: s.semi_diameter,
            conic: s.conic,
            aspheric: s.aspheric.iter().any(|&a| a != 0.0),
            coating: coating_label(&s.coating),
        })
        .collect()
}

pub fn run(args: &InfoArgs, quiet: bool) -> anyhow::Result<()> {
    if let Some(nm) = args.wavelength_nm {
        wavelength(nm)?;
    }
    let path = lens_library::resolve(&args.lens)?;
    let loaded = lens_library::load_with(
        &path.to_string_lossy(),
        quiet || args.json,
        &args.read.options(),
    )?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    let lambda = wavelength(args.wavelength_nm.unwrap_or(sys.default_wavelength_nm()))?;
    let p = analyse(sys, lambda)?;
    let surfaces = rows(sys, lambda);
    if args.json {
        let out = InfoJson {
            name: &sys.name,
            file: path.display().to_string(),
            stated_efl_mm: sys.stated_efl_mm,
            stated_f_number: sys.f_number,
            primary_wavelength_nm: sys.primary_wavelength_nm,
            film_width_mm: sys.film_width_mm,
            film_height_mm: sys.film_height_mm,
            paraxial: p,
            surfaces,
            warnings: &loaded.warnings,
        };
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("{} ({})", sys.name, path.display());
    if !sys.source.is_empty() {
        println!("source: {}", sys.source);
    }
    let mut t = Table::new(&[
        "#",
        "kind",
        "radius",
        "thickness",
        "glass",
        "n(λ)",
        "nd",
        "Vd",
        "semi-diam",
        "conic",
        "coating",
    ]);
    for r in &surfaces {
        t.row(vec![
            r.index.to_string(),
            format!("{}{}", r.kind, if r.aspheric { " (asph)" } else { "" }),
            r.radius_mm.map_or("inf".into(), fmt_len),
            fmt_len(r.thickness_mm),
            r.glass.clone(),
            format!("{:.6}", r.n),
            format!("{:.6}", r.nd),
            r.vd.map_or(String::new(), |v| format!("{v:.2}")),
            fmt_len(r.semi_diameter_mm),
            if r.conic == 0.0 {
                String::new()
            } else {
                format!("{}", r.conic)
            },
            r.coating.clone(),
        ]);
    }
    print!("{}", t.render());
    println!();
    println!("paraxial data at {lambda} nm (object at infinity):");
    let mut t = Table::new(&["quantity", "value", "unit"]);
    let stated = |v: Option<f64>| v.map_or(String::new(), |v| format!("(file states {v})"));
    let lines: Vec<(&str, f64, &str, String)> = vec![
        (
            "effective focal length",
            p.efl_mm,
            "mm",
            stated(sys.stated_efl_mm),
        ),
        ("back focal length", p.bfl_mm, "mm", String::new()),
        ("front focal length", p.ffl_mm, "mm", String::new()),
        ("f-number", p.f_number, "", stated(sys.f_number)),
        (
            "f-number, stop wide open",
            p.open_f_number,
            "",
            String::new(),
        ),
        (
            "entrance pupil diameter",
            p.entrance_pupil_diameter_mm,
            "mm",
            String::new(),
        ),
        (
            "entrance pupil position",
            p.entrance_pupil_z_mm,
            "mm",
            "from first vertex".into(),
        ),
        (
            "exit pupil diameter",
            p.exit_pupil_diameter_mm,
            "mm",
            String::new(),
        ),
        (
            "exit pupil position",
            p.exit_pupil_z_mm,
            "mm",
            "from last vertex".into(),
        ),
        (
            "total track",
            p.total_track_mm,
            "mm",
            "front vertex to sensor".into(),
        ),
        (
            "sensor behind paraxial focus",
            p.focus_error_mm,
            "mm",
            String::new(),
        ),
        ("Petzval sum", p.petzval_sum, "1/mm", String::new()),
    ];
    for (name, v, unit, note) in lines {
        t.row(vec![
            name.into(),
            format!("{v:.6}"),
            format!("{unit} {note}").trim().into(),
        ]);
    }
    print!("{}", t.render());
    Ok(())
}
