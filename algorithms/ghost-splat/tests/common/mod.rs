//! The scene the tests render (the Heliar, one light at 10°) and the plugin called directly.

#![allow(dead_code, reason = "each test file uses part of it")]

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Mesh, Output, Params, PluginError, Scene, SceneLight,
};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::load_lens;
use ghost_splat::plugin::GhostSplat;

/// The Heliar and a scene of one D65 light at θ = 10°, φ = 30° on a `w × h` frame across its
/// film, through a circular stop.
pub fn heliar_scene(w: usize, h: usize) -> (LensSystem, Scene) {
    let sys = load_lens("heliar-tronnier");
    let scene = Scene {
        lights: vec![SceneLight {
            theta_deg: 10.0,
            phi_deg: 30.0,
            intensity: 1.0,
            spectrum: LightSpectrum::D65,
        }],
        frame: Frame::across_film(w, h, sys.film_width_mm),
        aperture: Aperture::Circular,
    };
    (sys, scene)
}

/// Parameter values for the plugin, in the order of its specifications.
pub struct Values {
    pub rays: f64,
    pub kernel_px: f64,
    pub bands: f64,
    pub seed: f64,
}

/// Renders `scene` with the plugin called directly (no library boundary).
pub fn render(sys: &LensSystem, scene: &Scene, v: &Values) -> Result<HdrImage, PluginError> {
    let specs = GhostSplat::info().params;
    let values: Vec<f64> = specs
        .iter()
        .map(|s| match s.name {
            "rays" => v.rays,
            "kernel_px" => v.kernel_px,
            "bands" => v.bands,
            "seed" => v.seed,
            other => panic!("a parameter the tests do not know: {other}"),
        })
        .collect();
    let mut plugin = GhostSplat::create()?;
    plugin.prepare(sys)?;
    let frame = scene.frame;
    let mut img = HdrImage::new(frame.width, frame.height);
    let mut out = Output {
        width: frame.width,
        height: frame.height,
        pixels: &mut img.pixels,
        mesh: Mesh::default(),
        items_drawn: 0,
    };
    plugin.render(scene, &Params::new(&specs, &values), &mut out)?;
    Ok(img)
}
