//! The example plugin of `docs/plugins.md`: a soft glow — a round Gaussian of standard
//! deviation `sigma_px` pixels and total energy `gain` × the light's intensity — centred on each
//! light's paraxial image, `EFL · tan θ` from the centre of the sensor, opposite the light.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;

/// The plugin: remembers the lens's focal length (mm) between renders.
#[derive(Debug, Default)]
pub struct Glow {
    efl_mm: f64,
}

impl FlarePlugin for Glow {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "example-glow",
            version: env!("CARGO_PKG_VERSION"),
            description: "a soft glow at each light's paraxial image (the plugin guide's example)",
            kind: PluginKind::Other,
            params: vec![
                ParamSpec::float(
                    "sigma_px",
                    "glow radius: Gaussian sigma (pixels)",
                    0.5,
                    500.0,
                    8.0,
                ),
                ParamSpec::float(
                    "gain",
                    "glow energy per unit of light intensity",
                    0.0,
                    1e6,
                    1.0,
                ),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(Glow::default())
    }

    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        self.efl_mm = analyse(lens, LAMBDA_D_NM)?.efl_mm;
        Ok(())
    }

    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        let sigma = params.get("sigma_px")?;
        let gain = params.get("gain")?;
        let frame = scene.frame;
        for light in &scene.lights {
            // The image of a light at θ lies EFL·tan θ from the axis, opposite the light's
            // azimuth φ (the sdk's sensor frame: +y at φ = 0, rotated by φ).
            let (theta, phi) = (light.theta_deg.to_radians(), light.phi_deg.to_radians());
            let r = -self.efl_mm * theta.tan();
            let [cx, cy] = frame.to_pixel(-r * phi.sin(), r * phi.cos());
            let (cx, cy) = (cx as f64, cy as f64);
            let energy = gain * light.intensity;
            let norm = energy / (2.0 * std::f64::consts::PI * sigma * sigma);
            for (k, px) in out.pixels.iter_mut().enumerate() {
                let dx = (k % frame.width) as f64 + 0.5 - cx;
                let dy = (k / frame.width) as f64 + 0.5 - cy;
                let v = (norm * (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp()) as f32;
                for c in px.iter_mut() {
                    *c += v;
                }
            }
            out.items_drawn += 1;
        }
        Ok(())
    }
}

flarebench_sdk::export_plugin!(Glow);
