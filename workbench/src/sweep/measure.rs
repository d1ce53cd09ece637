//! Running a sweep's cells: the reference ghost by ghost, the built-in renderer (timed plan
//! and render, then each ghost alone) and plugins (timed through the ABI), and each cell's
//! errors against the reference.

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{FlarePlugin, Params, Scene};
use flarebench_sdk::abi::params::{ParamInfo, parse_values};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{LensTables, PlanOptions};
use ghost_raytrace::plugin::{GhostRaytrace, plan_options};
use ghost_raytrace::reference::reference_by_ghost;
use ghost_raytrace::scene::LightSpec;

use super::moments::Moments;
use super::points::{BUILTIN, Point, split_algo};
use super::{CellResult, GhostError, ReferenceRecord};
use crate::flare::{Flare, Preset, Scene as FlareScene, StarburstMode};
use crate::plugin_dirs;
use crate::stats::median;

/// The parameters of the built-in renderer, as its plugin describes them.
pub fn builtin_params() -> Vec<ParamInfo> {
    GhostRaytrace::info()
        .params
        .iter()
        .map(ParamInfo::from)
        .collect()
}

/// An algorithm's parameters: the built-in renderer's, or a plugin's (found by name or path
/// as `compare` finds it).
pub fn params_of(name: &str, plugins: &[PathBuf]) -> Result<Vec<ParamInfo>> {
    if name == BUILTIN {
        Ok(builtin_params())
    } else {
        Ok(plugin_dirs::find(name, plugins)?.params.clone())
    }
}

/// One case's scene, as every cell of it renders it.
#[derive(Debug)]
pub struct CaseScene<'a> {
    pub system: &'a LensSystem,
    pub tables: &'a LensTables,
    pub aperture: &'a Aperture,
    pub frame: Frame,
    pub light: &'a LightSpec,
}

/// The reference of a scene, ghost by ghost (its `key` left for the caller to fill).
pub fn reference(scene: &CaseScene<'_>) -> Result<(ReferenceRecord, HdrImage)> {
    let t = Instant::now();
    let (ghosts, img) = reference_by_ghost(
        scene.system,
        scene.aperture,
        scene.frame,
        std::slice::from_ref(scene.light),
        ReflectionOrder::Two,
        |_, path, img| (path.to_string(), Moments::of(img)),
    )?;
    let rec = ReferenceRecord {
        key: String::new(),
        render_ms: t.elapsed().as_secs_f64() * 1e3,
        total: Moments::of(&img),
        ghosts,
    };
    Ok((rec, img))
}

/// What timing a cell gives, before it is compared with the reference.
#[derive(Debug)]
pub struct Measurement {
    /// Every parameter's value as `key=value` text.
    pub params: String,
    pub times_ms: Vec<f64>,
    pub plan_ms: Option<f64>,
    pub render_ms: Option<f64>,
    /// The last run's image.
    pub image: HdrImage,
    pub ghosts_drawn: usize,
    pub ghosts_total: Option<usize>,
    pub dropped_estimated: Option<f64>,
    /// Each drawn ghost's moments, by path (the built-in renderer).
    pub ghosts: Option<Vec<(String, Moments)>>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn param_text(info: &[ParamInfo], values: &[f64]) -> String {
    info.iter()
        .zip(values)
        .map(|(p, &v)| format!("{}={}", p.name, p.format_value(v)))
        .collect::<Vec<_>>()
        .join(",")
}

/// Times `point` on the scene: one warm-up run, then `runs` timed ones, drawn by `flare`'s
/// backend.
pub fn measure(
    scene: &CaseScene<'_>,
    point: &Point,
    runs: usize,
    flare: &mut Flare,
    plugins: &[PathBuf],
) -> Result<Measurement> {
    let (name, text) = split_algo(&point.algo);
    if name == BUILTIN {
        measure_builtin(scene, text, runs, flare)
    } else {
        measure_plugin(scene, name, text, runs, flare, plugins)
    }
}

fn measure_builtin(
    scene: &CaseScene<'_>,
    text: &str,
    runs: usize,
    flare: &mut Flare,
) -> Result<Measurement> {
    let info = builtin_params();
    let values = parse_values(&info, text)?;
    let specs = GhostRaytrace::info().params;
    let opts = PlanOptions {
        lens_tables: Some(scene.tables),
        ..plan_options(&Params::new(&specs, &values)).map_err(|e| anyhow!("{e}"))?
    };
    let lights = std::slice::from_ref(scene.light);
    let frame_scene = FlareScene {
        starburst: StarburstMode::Off,
        ..FlareScene::new(scene.system, lights, scene.aperture, scene.frame)
    };
    let preset = Preset::new(opts);
    let (mut times, mut plan_times, mut render_times) = (vec![], vec![], vec![]);
    let mut last = None;
    for run in 0..=runs {
        let r = flare.render(&frame_scene, &preset)?;
        if run > 0 {
            times.push(r.timings.total_ms());
            plan_times.push(r.timings.plan_ms);
            render_times.push(r.timings.ghosts_ms);
        }
        last = Some(r.plans);
    }
    let plans = last.expect("at least the warm-up run");
    let image = flare.take_image();
    let culled = plans[0].culled_share;
    let ghosts_drawn = plans[0].ghosts.len();
    let ghosts_total = ghosts_drawn + plans[0].dropped.len();
    let (per, _) = ghosts::render_each_ghost(
        scene.system,
        scene.aperture,
        scene.frame,
        &plans,
        RenderOptions::default(),
        |_, job, img| (job.path.to_string(), Moments::of(img)),
    )?;
    Ok(Measurement {
        params: param_text(&info, &values),
        times_ms: times,
        plan_ms: Some(median(&plan_times)),
        render_ms: Some(median(&render_times)),
        image,
        ghosts_drawn,
        ghosts_total: Some(ghosts_total),
        dropped_estimated: Some(culled),
        ghosts: Some(per),
    })
}

fn measure_plugin(
    scene: &CaseScene<'_>,
    name: &str,
    text: &str,
    runs: usize,
    flare: &mut Flare,
    plugins: &[PathBuf],
) -> Result<Measurement> {
    let plugin = plugin_dirs::find(name, plugins)?;
    let values = parse_values(&plugin.params, text).with_context(|| format!("{name}:{text}"))?;
    let mut inst = plugin.instantiate()?;
    inst.prepare(scene.system)?;
    let abi_scene = Scene {
        lights: vec![scene.light.scene_light()],
        frame: scene.frame,
        aperture: scene.aperture.clone(),
    };
    let mut image = HdrImage::new(0, 0);
    let mut times = vec![];
    let mut drawn = 0;
    for run in 0..=runs {
        let t = Instant::now();
        let out = flare
            .backend_mut()
            .render_plugin(&mut inst, &abi_scene, &values, &mut image)?;
        if run > 0 {
            times.push(ms(t));
        }
        drawn = out.items_drawn as usize;
    }
    Ok(Measurement {
        params: param_text(&plugin.params, &values),
        times_ms: times,
        plan_ms: None,
        render_ms: None,
        image,
        ghosts_drawn: drawn,
        ghosts_total: None,
        dropped_estimated: None,
        ghosts: None,
    })
}

/// A measured cell against the reference.
pub fn finish(
    key: String,
    point: &Point,
    backend: &str,
    m: &Measurement,
    reference: &ReferenceRecord,
    reference_image: &HdrImage,
) -> Result<CellResult> {
    let c = m.image.compare(reference_image)?;
    let total = reference.total.energy;
    let mut ghosts = Vec::new();
    let mut dropped_measured = None;
    if let Some(per) = &m.ghosts {
        let drawn: HashMap<&str, &Moments> = per.iter().map(|(n, m)| (n.as_str(), m)).collect();
        let mut dropped = 0.0;
        for (name, r) in reference.ghosts.iter().filter(|(_, r)| r.energy > 0.0) {
            let share = if total > 0.0 { r.energy / total } else { 0.0 };
            ghosts.push(match drawn.get(name.as_str()) {
                Some(g) if g.energy > 0.0 => GhostError {
                    ghost: name.clone(),
                    reference_share: share,
                    drawn: true,
                    energy_error: (g.energy - r.energy) / r.energy,
                    centroid_shift_px: (g.cx - r.cx).hypot(g.cy - r.cy),
                    size_ratio: if r.rms_radius() > 0.0 {
                        g.rms_radius() / r.rms_radius()
                    } else {
                        1.0
                    },
                },
                _ => {
                    dropped += share;
                    GhostError {
                        ghost: name.clone(),
                        reference_share: share,
                        drawn: false,
                        energy_error: -1.0,
                        centroid_shift_px: 0.0,
                        size_ratio: 0.0,
                    }
                }
            });
        }
        dropped_measured = Some(dropped);
    }
    let t = &m.times_ms;
    Ok(CellResult {
        key,
        series: point.series.clone(),
        label: point.label.clone(),
        algo: point.algo.clone(),
        params: m.params.clone(),
        backend: backend.to_string(),
        median_ms: median(t),
        min_ms: t.iter().copied().fold(f64::INFINITY, f64::min),
        max_ms: t.iter().copied().fold(0.0, f64::max),
        times_ms: t.clone(),
        plan_ms: m.plan_ms,
        render_ms: m.render_ms,
        relative_rmse: c.relative_rmse,
        relative_l1: c.relative_l1,
        energy_error: c.energy_error,
        ghosts_drawn: m.ghosts_drawn,
        ghosts_total: m.ghosts_total,
        dropped_energy_estimated: m.dropped_estimated,
        dropped_energy_measured: dropped_measured,
        ghosts,
        failure: None,
    })
}

/// A cell that could not be measured: kept in the results with its reason.
pub fn failed(key: String, point: &Point, backend: &str, why: String) -> CellResult {
    CellResult {
        key,
        series: point.series.clone(),
        label: point.label.clone(),
        algo: point.algo.clone(),
        params: String::new(),
        backend: backend.to_string(),
        times_ms: vec![],
        median_ms: f64::NAN,
        min_ms: f64::NAN,
        max_ms: f64::NAN,
        plan_ms: None,
        render_ms: None,
        relative_rmse: f64::NAN,
        relative_l1: f64::NAN,
        energy_error: f64::NAN,
        ghosts_drawn: 0,
        ghosts_total: None,
        dropped_energy_estimated: None,
        dropped_energy_measured: None,
        ghosts: vec![],
        failure: Some(why),
    }
}
