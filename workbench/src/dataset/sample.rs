//! One sample rendered: [`render_sample`] turns a [`SampleSpec`] into its layers (linear
//! images) and its [`Annotation`], always on the CPU (a GPU's bits differ from machine to
//! machine), so a sample is the same bytes on every machine and in every run.
//!
//! The pipeline is `Flare::render`'s (plan, ghosts, starbursts, automatic exposure) with the
//! ghosts drawn differently: each drawn ghost is drawn once, alone, into the window of the
//! frame it lights (`ghost_raytrace::tiles`, ghosts in parallel), and the ghost layers are
//! summed from those windows in plan order ([`super::ghost_layers`]): the ghosts, each
//! light's ghosts, and the ID layer. A ghost's window gives its energy and box. The ghosts'
//! sum is the frame `Flare::render` draws up to the order of the f32 additions (relative
//! RMSE and energy within 1e-6, `workbench/tests/dataset.rs`). The starbursts are then added
//! to the ghosts (the flare), to black (the starburst layer) and to each light's layer.

use anyhow::Context;
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::{Aperture, ApertureMask};
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::StarburstCache;
use flarebench_sdk::starburst::{StarburstSettings, chief_ray_landing};
use ghost_raytrace::ghosts::RenderOptions;
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::LightSpec;
use ghost_raytrace::tiles::{GhostTile, TileBuffers, render_ghost_tiles};
use rayon::prelude::*;

use super::annotation::{
    Annotation, GhostAnnotation, GhostMeasure, LensFigures, LightAnnotation, RenderFigures,
};
use super::ghost_layers::{add_tiles, ghost_ids};
use super::sampler::{ApertureSpec, SampleSpec};
use crate::aperture_file::{MaskEncoding, load_aperture_mask};
use crate::flare::compose::add_starbursts;
use crate::flare::exposure::{auto_exposure, ghost_exposure};
use crate::flare::{BackendChoice, Flare, Preset, Scene, StarburstMode, frame_for};

/// The frame-sized buffers ghosts are drawn into, kept from sample to sample (at most one per
/// ghost drawn at once, of the last frame size met).
static TILE_BUFFERS: TileBuffers = TileBuffers::new();

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

/// What a sample is rendered from: its lens at its f-number, aperture, dust, lights, frame
/// and starburst settings.
struct Setup {
    system: LensSystem,
    aperture: Aperture,
    dust: Option<ApertureMask>,
    lights: Vec<LightSpec>,
    frame: Frame,
    settings: StarburstSettings,
    with_starbursts: bool,
}

impl Setup {
    fn of(spec: &SampleSpec) -> anyhow::Result<Setup> {
        let mut system = read_lens(&spec.lens_path)
            .with_context(|| format!("could not load lens `{}`", spec.lens))?
            .system;
        system.f_number = Some(spec.f_number);
        let frame = frame_for(&system, (spec.size[0], spec.size[1]));
        let aperture = aperture_of(spec)?;
        let dust = match &spec.dust_path {
            Some(p) => Some(
                load_aperture_mask(p, MaskEncoding::Transmission)
                    .with_context(|| format!("dust `{}`", spec.dust.as_deref().unwrap_or("")))?
                    .mask,
            ),
            None => None,
        };
        let lights = spec
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
        Ok(Setup {
            system,
            aperture,
            dust,
            lights,
            frame,
            settings,
            with_starbursts: spec.layers.starburst,
        })
    }

    fn scene(&self) -> Scene<'_> {
        Scene {
            starburst: if self.with_starbursts {
                StarburstMode::On
            } else {
                StarburstMode::Off
            },
            starburst_settings: self.settings,
            dust: self.dust.as_ref(),
            ..Scene::new(&self.system, &self.lights, &self.aperture, self.frame)
        }
    }
}

/// `spec`'s scene drawn the ordinary way, by `Flare::render` on the CPU (all ghosts at
/// once, then the starbursts): the flare and its ghosts alone. [`render_sample`]'s flare and
/// ghost layers are this up to the order of the f32 additions.
pub fn render_whole(spec: &SampleSpec) -> anyhow::Result<(HdrImage, HdrImage)> {
    let setup = Setup::of(spec)?;
    let preset = Preset {
        keep_ghosts: true,
        ..Preset::new(PlanOptions::for_quality(spec.quality, None))
    };
    let mut flare = Flare::open(BackendChoice::Cpu)?;
    let mut rendered = flare.render(&setup.scene(), &preset)?;
    let ghosts = rendered.ghosts_image.take().expect("kept with keep_ghosts");
    Ok((flare.take_image(), ghosts))
}

/// Renders `spec`.
pub fn render_sample(spec: &SampleSpec) -> anyhow::Result<SampleOutput> {
    let setup = Setup::of(spec)?;
    let scene = setup.scene();
    let (sys, frame, lights) = (&setup.system, setup.frame, &setup.lights);
    let aperture = &setup.aperture;
    let with_starbursts = setup.with_starbursts;
    let para = analyse(sys, sys.default_wavelength_nm()).context("paraxial analysis")?;
    let plan_options = PlanOptions::for_quality(spec.quality, None);
    let plans = if lights.is_empty() {
        Vec::new()
    } else {
        plan::plan(sys, lights, &frame, &plan_options)
            .with_context(|| format!("sample {}", spec.index))?
    };

    // Every ghost drawn once, alone, into the window it lights; the layers are their sums.
    let tiles = render_ghost_tiles(
        sys,
        aperture,
        frame,
        &plans,
        RenderOptions::default(),
        &TILE_BUFFERS,
    )
    .with_context(|| format!("sample {}", spec.index))?;
    let all: Vec<&GhostTile> = tiles.iter().collect();
    let mut ghosts_img = HdrImage::new(frame.width, frame.height);
    add_tiles(&mut ghosts_img, &all);
    let mut per_light: Vec<HdrImage> = Vec::new();
    if spec.layers.per_light {
        for li in 0..lights.len() {
            let mut layer = HdrImage::new(frame.width, frame.height);
            let own: Vec<&GhostTile> = tiles.iter().filter(|t| t.light == li).collect();
            add_tiles(&mut layer, &own);
            per_light.push(layer);
        }
    }
    let ghost_id = spec
        .layers
        .ghost_id
        .then(|| ghost_ids(frame.width, frame.height, &tiles));

    // The starbursts: added to the ghosts (the flare), alone (all lights), and to each
    // light's layer — what `Flare::render` does after drawing the ghosts.
    let starburst_setup = scene.starburst_setup();
    let mut cache = StarburstCache::new();
    let mut flare_img = ghosts_img.clone();
    let mut starburst_lines = Vec::new();
    let mut starburst = None;
    if with_starbursts {
        starburst_lines = add_starbursts(
            &mut flare_img,
            sys,
            &frame,
            lights,
            &starburst_setup,
            &mut cache,
        )
        .with_context(|| format!("sample {}", spec.index))?;
        let mut alone = HdrImage::new(frame.width, frame.height);
        add_starbursts(
            &mut alone,
            sys,
            &frame,
            lights,
            &starburst_setup,
            &mut cache,
        )?;
        starburst = Some(alone);
        for (layer, light) in per_light.iter_mut().zip(lights) {
            add_starbursts(
                layer,
                sys,
                &frame,
                std::slice::from_ref(light),
                &starburst_setup,
                &mut cache,
            )?;
        }
    }
    anyhow::ensure!(
        !flare_img.has_non_finite(),
        "internal error: sample {} has non-finite pixels",
        spec.index
    );
    // The automatic exposure as `Flare::render` finds it: the ghosts', else the flare's.
    let exposure_ev = ghost_exposure(&ghosts_img).unwrap_or_else(|| auto_exposure(&flare_img));

    // Each ghost's measure on its own (in parallel; each is the same bits on any thread).
    let ghost_notes: Vec<GhostAnnotation> = tiles
        .par_iter()
        .enumerate()
        .map(|(k, t)| GhostAnnotation {
            id: k as u32 + 1,
            light: t.light,
            path: plans[t.light].ghosts[t.ghost].path.to_string(),
            measure: GhostMeasure::of(&t.image).at(t.x0, t.y0),
            flux: t.stats.flux,
        })
        .collect();

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
            let plan = plans.get(k);
            let sb = starburst_lines.get(k);
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
        ghosts_drawn: tiles.len(),
        ghosts_left_out: plans.iter().map(|p| p.dropped.len()).sum(),
        rays_traced: tiles.iter().map(|t| t.stats.rays).sum(),
        triangles: tiles.iter().map(|t| t.stats.triangles).sum(),
        flare_sum_rgb: flare_img.sum(),
        ghosts_sum_rgb: ghosts_img.sum(),
        starburst_sum_rgb: starburst.as_ref().map(HdrImage::sum),
        flare_max: flare_img.max(),
        exposure_ev,
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
