//! A plugin's mesh drawn by the GPU equals the same mesh drawn by the CPU: the `ghost-matrix`
//! plugin (built by `cargo build --workspace`) renders the Heliar through the host's sink seam
//! (`PluginInstance::render_into_sink`); its frame — one full-resolution level, exact
//! coverage — is drawn by the CPU path (`render_into`) and by the GPU renderer, within the
//! ghosts' parity bounds, and with no NaN or Inf.

use std::sync::{Arc, OnceLock};

use flarebench_gpu::{AccumFormat, AdapterChoice, GhostRenderer, GpuContext};
use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::abi::host::{self, LoadedPlugin};
use flarebench_sdk::abi::params::defaults;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::sink::FrameMeshes;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::raster::Coverage;
use flarebench_test_support::{load_lens, plugin_library};
use ghost_raytrace::scene::LightSpec;

/// The frame: a sixteenth of the ghosts' parity frame across. The plugin's triangles are
/// large and all exactly covered, each drawn over its bounding box, so lavapipe's time grows
/// with the frame's area: 960 × 540 took 400 s (docs/gpu.md), 480 × 270 60 s, 240 × 135 15 s.
const WIDTH: usize = 120;
const HEIGHT: usize = 68;

/// Relative RMSE of the GPU image against the CPU image (as the ghosts' parity).
const MAX_RMSE: f64 = 0.005;
/// Relative difference of the images' sums.
const MAX_ENERGY: f64 = 0.001;

fn context() -> Arc<GpuContext> {
    static CTX: OnceLock<Arc<GpuContext>> = OnceLock::new();
    CTX.get_or_init(|| Arc::new(GpuContext::new(AdapterChoice::Any).expect("a GPU adapter")))
        .clone()
}

fn plugin() -> &'static LoadedPlugin {
    static PLUGIN: OnceLock<LoadedPlugin> = OnceLock::new();
    PLUGIN.get_or_init(|| host::load(&plugin_library("ghost_matrix")).expect("ghost-matrix loads"))
}

fn check(name: &str, aperture: Aperture) {
    let sys = load_lens("heliar-tronnier");
    let scene = Scene {
        lights: ["8,60", "3,200,0.5,3200"]
            .iter()
            .map(|l| LightSpec::parse(l).unwrap().scene_light())
            .collect(),
        frame: Frame::across_film(WIDTH, HEIGHT, sys.film_width_mm),
        aperture,
    };
    let p = plugin();
    let values = defaults(&p.params);
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&sys).unwrap();

    // The CPU path: the mesh rasterized into the plugin's image.
    let mut cpu = HdrImage::new(0, 0);
    let cpu_stats = inst.render_into(&scene, &values, &mut cpu).unwrap();

    // The seam: the plugin's pixels, and its frame recorded.
    let mut pixels = HdrImage::new(0, 0);
    let mut recorded = FrameMeshes::default();
    let stats = inst
        .render_into_sink(&scene, &values, &mut pixels, &mut recorded)
        .unwrap();
    assert_eq!(stats, cpu_stats);
    assert!(stats.mesh_triangles > 0, "{name}: no mesh");
    assert_eq!(recorded.triangles(), stats.mesh_triangles);
    let (frame, grids, _, coverage) = recorded.levels.clone().expect("a frame began");
    assert_eq!((frame.width, frame.height), (WIDTH, HEIGHT));
    assert_eq!(grids.len(), 1);
    assert_eq!(grids[0].factor, 1);
    assert_eq!(coverage, Coverage::Exact);
    // The recording drawn on the CPU and added to the plugin's pixels is the CPU path's image
    // (bit for bit when the plugin leaves its pixels black, as ghost-matrix does).
    let mut replayed = recorded.draw_cpu();
    if pixels.pixels.iter().all(|p| *p == [0.0; 3]) {
        assert!(replayed.pixels == cpu.pixels, "{name}: CPU paths differ");
    }
    replayed.add_image(&pixels).unwrap();
    let c = replayed.compare(&cpu).unwrap();
    assert!(c.relative_rmse < 1e-6, "{name}: {c:?}");

    // The GPU: the same frame through the renderer as a sink, added to the plugin's pixels.
    let mut renderer = GhostRenderer::new(context(), AccumFormat::F32).unwrap();
    let mut gpu_pixels = HdrImage::new(0, 0);
    inst.render_into_sink(&scene, &values, &mut gpu_pixels, &mut renderer)
        .unwrap();
    let mut gpu = renderer.read_back().expect("the GPU frame");
    assert!(!gpu.has_non_finite(), "{name}: NaN or Inf in the GPU image");
    gpu.add_image(&gpu_pixels).unwrap();
    assert!(!cpu.has_non_finite(), "{name}: NaN or Inf in the CPU image");
    assert!(cpu.luminance_sum() > 0.0, "{name}: the frame is black");
    let c = gpu.compare(&cpu).unwrap();
    eprintln!(
        "{name}: {} triangles: rmse {:.2e}, energy {:.2e}",
        stats.mesh_triangles, c.relative_rmse, c.energy_error
    );
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
fn ghost_matrix_meshes_on_the_gpu_equal_the_cpu_ones() {
    check("circular", Aperture::Circular);
}

#[test]
fn ghost_matrix_meshes_through_an_iris_on_the_gpu_equal_the_cpu_ones() {
    check(
        "iris",
        Aperture::Iris {
            blades: 6,
            rotation_rad: 0.2,
            roundness: 0.2,
        },
    );
}
