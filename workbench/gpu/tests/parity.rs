//! The GPU image of a frame equals the CPU image of the same frame description
//! (`flarebench_sdk::ghost::sink::FrameMeshes`, drawn by both): relative RMSE and energy
//! within the bounds, and no NaN or Inf.

use std::sync::{Arc, OnceLock};

use flarebench_gpu::{AccumFormat, AdapterChoice, GhostRenderer, GpuContext};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::sink::FrameMeshes;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::load_lens;
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Relative RMSE of the GPU image against the CPU image.
const MAX_RMSE: f64 = 0.005;
/// Relative difference of the images' luminance sums.
const MAX_ENERGY: f64 = 0.001;

fn context() -> Arc<GpuContext> {
    static CTX: OnceLock<Arc<GpuContext>> = OnceLock::new();
    CTX.get_or_init(|| Arc::new(GpuContext::new(AdapterChoice::Any).expect("a GPU adapter")))
        .clone()
}

fn record(lens: &str, lights: &[&str], aperture: &Aperture, band_by_band: bool) -> FrameMeshes {
    let sys = load_lens(lens);
    let frame = Frame::across_film(960, 540, sys.film_width_mm);
    let lights: Vec<LightSpec> = lights
        .iter()
        .map(|l| LightSpec::parse(l).unwrap())
        .collect();
    let opts = PlanOptions::for_quality(Quality::Default, None);
    let plans = plan::plan(&sys, &lights, &frame, &opts).unwrap();
    let options = RenderOptions {
        band_by_band,
        ..RenderOptions::default()
    };
    let mut recorded = FrameMeshes::default();
    ghosts::draw_into(&sys, aperture, frame, &plans, options, &mut recorded).unwrap();
    recorded
}

fn gpu_image(recorded: &FrameMeshes) -> HdrImage {
    let mut gpu = GhostRenderer::new(context(), AccumFormat::F32).unwrap();
    recorded.replay(&mut gpu);
    gpu.read_back().expect("the GPU frame")
}

fn check(name: &str, recorded: &FrameMeshes) {
    let cpu = recorded.draw_cpu();
    let gpu = gpu_image(recorded);
    assert!(!gpu.has_non_finite(), "{name}: NaN or Inf in the GPU image");
    let c = gpu.compare(&cpu).unwrap();
    eprintln!(
        "{name}: {} triangles, levels {:?}: rmse {:.2e}, energy {:.2e}",
        recorded.triangles(),
        recorded
            .levels
            .as_ref()
            .map(|l| l.1.iter().map(|g| g.factor).collect::<Vec<_>>()),
        c.relative_rmse,
        c.energy_error
    );
    assert!(cpu.luminance_sum() > 0.0, "{name}: the frame is black");
    assert!(
        c.relative_rmse <= MAX_RMSE,
        "{name}: rmse {}",
        c.relative_rmse
    );
    assert!(
        c.energy_error.abs() <= MAX_ENERGY,
        "{name}: energy {}",
        c.energy_error
    );
}

#[test]
fn heliar_circle_fringed_and_band_by_band() {
    let r = record("heliar-tronnier", &["8,60"], &Aperture::Circular, false);
    assert!(
        r.meshes.iter().any(|(_, m)| !m.fringe.is_empty()),
        "the default frame has fringed groups"
    );
    check("heliar circle, fringed", &r);
    let r = record("heliar-tronnier", &["8,60"], &Aperture::Circular, true);
    check("heliar circle, band by band", &r);
}

fn iris() -> Aperture {
    Aperture::Iris {
        blades: 6,
        rotation_rad: 0.3,
        roundness: 0.2,
    }
}

/// OpenLensFlare's own aperture mask (lenses/masks/aperture.bmp).
fn olf_mask() -> Aperture {
    let path = flarebench_test_support::lenses_dir().join("masks/aperture.bmp");
    let img = image::open(&path).expect("the bundled mask").to_luma8();
    let (w, h) = img.dimensions();
    let mask =
        flarebench_sdk::aperture::ApertureMask::from_luma(w as usize, h as usize, img.as_raw())
            .expect("a valid mask");
    Aperture::Mask(mask)
}

#[test]
fn heliar_iris_and_mask() {
    check(
        "heliar iris",
        &record("heliar-tronnier", &["8,60"], &iris(), true),
    );
    check(
        "heliar mask",
        &record("heliar-tronnier", &["8,60"], &olf_mask(), true),
    );
}

/// The Nikon zoom's default frame (fringed groups, two lights), and with an iris and a mask
/// (drawn band by band: the fringe model is the circle's).
#[test]
fn nikon_two_lights_iris_and_mask() {
    let r = record(
        "nikon-zoom-short",
        &["10,30", "4,200,0.5"],
        &Aperture::Circular,
        false,
    );
    check("nikon circle, two lights, fringed", &r);
    let r = record("nikon-zoom-short", &["10,30"], &iris(), false);
    check("nikon iris", &r);
    let r = record("nikon-zoom-short", &["10,30"], &olf_mask(), false);
    check("nikon mask", &r);
}

/// Starbursts composited on the GPU from the patterns the CPU splats: two lights in the frame
/// (one pattern shared, one of its own colour), added after the ghosts.
#[test]
fn heliar_with_starbursts() {
    use flarebench_sdk::ghost::GridTrace;
    use flarebench_sdk::starburst::{
        StarburstCache, StarburstLens, StarburstLight, StarburstSettings, StarburstSource,
        add_starburst,
    };
    let sys = load_lens("heliar-tronnier");
    let lights = ["8,60", "3,200,0.5,3200"];
    let recorded = record("heliar-tronnier", &lights, &Aperture::Circular, true);
    let (frame, _, _, _) = recorded.levels.clone().unwrap();
    let lens = StarburstLens::new(&sys).unwrap();
    let aperture = Aperture::Circular;
    let source = StarburstSource {
        aperture: &aperture,
        dust: None,
        settings: StarburstSettings {
            pupil_texels: 128,
            ..StarburstSettings::default()
        },
    };
    let mut cache = StarburstCache::new();
    let mut scratch = GridTrace::default();
    let splats: Vec<_> = lights
        .iter()
        .filter_map(|l| {
            let spec = LightSpec::parse(l).unwrap();
            let light = StarburstLight {
                theta_deg: spec.theta_deg,
                phi_deg: spec.phi_deg,
                intensity: spec.intensity,
                spectrum: spec.spectrum,
            };
            lens.place(&sys, &frame, &light, &source, &mut cache, &mut scratch)
                .unwrap()
                .1
        })
        .collect();
    assert_eq!(splats.len(), 2, "both lights are in the frame");
    let mut cpu = recorded.draw_cpu();
    let ghosts_only = cpu.luminance_sum();
    for s in &splats {
        add_starburst(
            &mut cpu,
            &frame,
            &s.pattern,
            s.centre_mm,
            s.f_number,
            s.flux,
        )
        .unwrap();
    }
    assert!(
        cpu.luminance_sum() > 2.0 * ghosts_only,
        "the starbursts dominate"
    );
    let mut gpu = GhostRenderer::new(context(), AccumFormat::F32).unwrap();
    recorded.replay(&mut gpu);
    gpu.add_starbursts(&splats).unwrap();
    let img = gpu.read_back().unwrap();
    assert!(!img.has_non_finite());
    let c = img.compare(&cpu).unwrap();
    eprintln!(
        "heliar with starbursts: rmse {:.2e}, energy {:.2e}",
        c.relative_rmse, c.energy_error
    );
    assert!(c.relative_rmse <= MAX_RMSE, "rmse {}", c.relative_rmse);
    assert!(
        c.energy_error.abs() <= MAX_ENERGY,
        "energy {}",
        c.energy_error
    );
}
