//! One sample rendered: [`render_sample`] turns a [`SampleSpec`] into its layers (linear
//! images) and its [`Annotation`], always on the CPU (a GPU's bits differ from machine to
//! machine), so a sample is the same bytes on every machine and in every run.
//!
//! The flare is rendered once ([`Flare::render`], its ghosts kept before the starbursts are
//! added); the starbursts alone once more. Each drawn ghost is then drawn alone on a black
//! frame, in plan order, for its energy and box, the ID layer (the ghost adding the most
//! luminance at each pixel; the first in plan order on a tie) and the per-light layers.

use anyhow::Context;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::color::srgb::luminance_f32;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::{StarburstSettings, chief_ray_landing};
use ghost_raytrace::ghosts::{self, RenderOptions, RenderScratch};
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::LightSpec;

use super::annotation::{
    Annotation, GhostAnnotation, GhostMeasure, LensFigures, LightAnnotation, RenderFigures,
};
use super::sampler::{ApertureSpec, SampleSpec};
use crate::aperture_file::{MaskEncoding, load_aperture_mask};
use crate::flare::{BackendChoice, Flare, Preset, Scene, StarburstMode, frame_for};

/// The annotation file's format name.
pub const ANNOTATION_FORMAT: &str = "flarebench-dataset-sample-1";

/// A rendered sample: its layers, linear, and its annotation.
#[derive(Debug)]
pub struct SampleOutput {
    /// Ghosts and starbursts (ghosts only when the sampler leaves starbursts out).
    pub flare: HdrImage,
    pub ghosts: HdrImage,
    /// The starbursts alone (with starbursts).
    pub starburst: Option<HdrImage>,
    /// Per light: its ghosts and its starburst (with `per_light`).
    pub per_light: Vec<HdrImage>,
    /// Per pixel, row-major: the `id` of the ghost adding the most luminance, 0 for none
    /// (with `ghost_id`).
    pub ghost_id: Option<Vec<u32>>,
    pub annotation: Annotation,
}

impl SampleOutput {
    /// The layers as named channels of the EXR file, in the annotation's channel order: the
    /// float layers (`R`, `G`, `B`; `ghosts.R`, …) and the ID layer.
    pub fn float_layers(&self) -> Vec<(String, &HdrImage)> {
        let mut out = vec![
            (String::new(), &self.flare),
            ("ghosts".into(), &self.ghosts),
        ];
        if let Some(s) = &self.starburst {
            out.push(("starburst".into(), s));
        }
        for (k, l) in self.per_light.iter().enumerate() {
            out.push((format!("light{k}"), l));
        }
        out
    }
}

/// The aperture of `spec`, read and checked.
fn aperture_of(spec: &SampleSpec) -> anyhow::Result<Aperture> {
    let aperture = match &spec.aperture {
        ApertureSpec::Circle => Aperture::Circular,
        ApertureSpec::Iris {
            blades,
            rotation_deg,
            roundness,
        } => Aperture::Iris {
            blades: *blades,
            rotation_rad: rotation_deg.to_radians(),
            roundness: *roundness,
        },
        ApertureSpec::Mask { file, path } => Aperture::Mask(
            load_aperture_mask(path, MaskEncoding::Auto)
                .with_context(|| format!("aperture mask `{file}`"))?
                .mask,
        ),
    };
    aperture.validate().context("aperture")?;
    Ok(aperture)
}

/// Renders `spec`.
pub fn render_sample(spec: &SampleSpec) -> anyhow::Result<SampleOutput> {
    let mut system = read_lens(&spec.lens_path)
        .with_context(|| format!("could not load lens `{}`", spec.lens))?
        .system;
    system.f_number = Some(spec.f_number);
    let sys = &system;
    let para = analyse(sys, sys.default_wavelength_nm()).context("paraxial analysis")?;
    let frame = frame_for(sys, (spec.size[0], spec.size[1]));
    let aperture = aperture_of(spec)?;
    let dust = match &spec.dust_path {
        Some(p) => Some(
            load_aperture_mask(p, MaskEncoding::Transmission)
                .with_context(|| format!("dust `{}`", spec.dust.as_deref().unwrap_or("")))?
                .mask,
        ),
        None => None,
    };
    let lights: Vec<LightSpec> = spec
        .lights
        .iter()
        .map(|l| LightSpec {
            theta_deg: l.theta_deg,
            phi_deg: l.phi_deg,
            intensity: l.intensity,
            spectrum: LightSpectrum::Blackbody { kelvin: l.kelvin },
        })
        .collect();
    let settings = StarburstSettings {
        pupil_texels: spec.starburst_texels,
        ..StarburstSettings::default()
    };
    settings.validate().context("starburst_texels")?;
    let with_starbursts = spec.layers.starburst;
    let scene = Scene {
        starburst: if with_starbursts {
            StarburstMode::On
        } else {
            StarburstMode::Off
        },
        starburst_settings: settings,
        dust: dust.as_ref(),
        ..Scene::new(sys, &lights, &aperture, frame)
    };
    let plan = PlanOptions::for_quality(spec.quality, None);
    let preset = Preset {
        exposure: true,
        keep_ghosts: with_starbursts,
        ..Preset::new(plan)
    };
    let mut flare = Flare::open(BackendChoice::Cpu)?;
    let mut rendered = flare
        .render(&scene, &preset)
        .with_context(|| format!("sample {}", spec.index))?;
    let flare_img = flare.take_image();
    let ghosts_img = rendered
        .ghosts_image
        .take()
        .unwrap_or_else(|| flare_img.clone());

    // The starbursts alone: all lights, then (for the per-light layers) each.
    let only = |lights: &[LightSpec], flare: &mut Flare| -> anyhow::Result<HdrImage> {
        let s = Scene {
            starburst: StarburstMode::Only,
            lights,
            ..scene
        };
        flare.render(&s, &Preset::new(plan))?;
        Ok(flare.take_image())
    };
    let starburst = if with_starbursts {
        Some(only(&lights, &mut flare)?)
    } else {
        None
    };
    let mut per_light: Vec<HdrImage> = Vec::new();
    if spec.layers.per_light {
        for light in &lights {
            per_light.push(if with_starbursts {
                only(std::slice::from_ref(light), &mut flare)?
            } else {
                HdrImage::new(frame.width, frame.height)
            });
        }
    }

    // Each ghost alone.
    let n_px = frame.width * frame.height;
    let mut ghost_id = spec.layers.ghost_id.then(|| vec![0u32; n_px]);
    let mut best = if spec.layers.ghost_id {
        vec![0f32; n_px]
    } else {
        Vec::new()
    };
    let mut alone = HdrImage::new(frame.width, frame.height);
    let mut scratch = RenderScratch::default();
    let mut ghost_notes = Vec::new();
    let options = RenderOptions {
        replace: false,
        ..preset.render
    };
    for (li, lp) in rendered.plans.iter().enumerate() {
        for (gi, job) in lp.ghosts.iter().enumerate() {
            let id = ghost_notes.len() as u32 + 1;
            let mut one = lp.clone();
            one.ghosts = vec![job.clone()];
            one.dropped.clear();
            alone.fill_black();
            ghosts::render_into_reusing(
                sys,
                &aperture,
                frame,
                std::slice::from_ref(&one),
                options,
                &mut scratch,
                &mut alone.pixels,
            )
            .with_context(|| format!("sample {}: ghost {}", spec.index, job.path))?;
            if let Some(ids) = ghost_id.as_mut() {
                for ((p, b), i) in alone.pixels.iter().zip(best.iter_mut()).zip(ids.iter_mut()) {
                    let l = luminance_f32(*p);
                    if l > *b {
                        *b = l;
                        *i = id;
                    }
                }
            }
            if let Some(layer) = per_light.get_mut(li) {
                for (o, p) in layer.pixels.iter_mut().zip(&alone.pixels) {
                    for c in 0..3 {
                        o[c] += p[c];
                    }
                }
            }
            ghost_notes.push(GhostAnnotation {
                id,
                light: li,
                path: job.path.to_string(),
                measure: GhostMeasure::of(&alone),
                flux: rendered.ghost_stats[li].get(gi).map_or(0.0, |s| s.flux),
            });
        }
    }

    let light_notes = spec
        .lights
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let position_px = chief_ray_landing(
                sys,
                LAMBDA_D_NM,
                l.theta_deg.to_radians(),
                l.phi_deg.to_radians(),
            )
            .ok()
            .map(|c| frame.to_pixel(c[0], c[1]).map(f64::from));
            let plan = rendered.plans.get(k);
            let sb = rendered.starbursts.get(k);
            LightAnnotation {
                light: k,
                theta_deg: l.theta_deg,
                phi_deg: l.phi_deg,
                position_px,
                inside_frame: !l.outside_frame,
                rgb: LightSpectrum::Blackbody { kelvin: l.kelvin }.linear_srgb(),
                ghosts_drawn: plan.map_or(0, |p| p.ghosts.len()),
                ghosts_left_out: plan.map_or(0, |p| p.dropped.len()),
                culled_share: plan.map_or(0.0, |p| p.culled_share),
                starburst_flux: sb.map_or(0.0, |s| s.flux),
                starburst_added: sb.map_or(0.0, |s| s.added),
            }
        })
        .collect();

    let figures = RenderFigures {
        ghosts_drawn: rendered.ghosts_drawn(),
        ghosts_left_out: rendered.plans.iter().map(|p| p.dropped.len()).sum(),
        rays_traced: rendered.rays_traced(),
        triangles: rendered.triangles(),
        flare_sum_rgb: flare_img.sum(),
        ghosts_sum_rgb: ghosts_img.sum(),
        starburst_sum_rgb: starburst.as_ref().map(HdrImage::sum),
        flare_max: flare_img.max(),
        exposure_ev: rendered.exposure_ev.unwrap_or(0.0),
    };
    let mut out = SampleOutput {
        flare: flare_img,
        ghosts: ghosts_img,
        starburst,
        per_light,
        ghost_id,
        annotation: Annotation {
            format: ANNOTATION_FORMAT,
            sample: spec.clone(),
            lens: LensFigures {
                title: sys.name.clone(),
                efl_mm: para.efl_mm,
                working_f_number: para.f_number,
                open_f_number: para.open_f_number,
                film_width_mm: frame.film_width_mm,
                film_height_mm: frame.film_height_mm,
            },
            lights: light_notes,
            ghosts: ghost_notes,
            figures,
            channels: Vec::new(),
        },
    };
    out.annotation.channels = super::layers::channel_names(&out);
    Ok(out)
}
