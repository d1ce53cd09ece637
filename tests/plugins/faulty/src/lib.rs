//! A plugin that misbehaves on request, so the host's tests (`tests/plugin_host.rs`) can check
//! that each fault becomes a clear error and the host keeps running. With `fault=none` it adds
//! `level` to every pixel and one triangle of the same radiance when `mesh=true`.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};
use flarebench_sdk::abi::v1::MeshVertex;

/// The faults, in the order of the `fault` choice.
pub const FAULTS: &[&str] = &["none", "error", "panic_render", "nan", "inf", "bad_mesh"];

/// The misbehaving plugin.
#[derive(Debug, Default)]
pub struct Faulty {
    prepared: bool,
}

impl FlarePlugin for Faulty {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "test-faulty",
            version: "1.0.0",
            description: "misbehaves on request (host tests)",
            kind: PluginKind::Other,
            params: vec![
                ParamSpec::choice("fault", "what to do wrong", FAULTS, 0),
                ParamSpec::float("level", "value added to every pixel", 0.0, 10.0, 0.25),
                ParamSpec::bool("mesh", "also return one triangle", false),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(Faulty::default())
    }

    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        // The lens name selects a fault in prepare (the host passes no parameters there).
        if lens.name.contains("panic-in-prepare") {
            panic!("asked to panic in prepare");
        }
        self.prepared = true;
        Ok(())
    }

    fn render(
        &mut self,
        _scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        if !self.prepared {
            return Err(PluginError::new("render before prepare"));
        }
        let level = params.get("level")? as f32;
        match FAULTS[params.get_choice("fault")?] {
            "error" => return Err(PluginError::new("asked to fail")),
            "panic_render" => panic!("asked to panic in render"),
            "nan" => out.pixels[out.width + 1][1] = f32::NAN,
            "inf" => out.pixels[0][2] = f32::INFINITY,
            "bad_mesh" => {
                out.mesh.vertices.push(MeshVertex {
                    x: 0.0,
                    y: 0.0,
                    rgb: [1.0; 3],
                });
                out.mesh.triangles.push([0, 1, 2]);
            }
            _ => {}
        }
        for p in out.pixels.iter_mut() {
            for c in p.iter_mut() {
                *c += level;
            }
        }
        if params.get_bool("mesh")? {
            // A right triangle of legs 4 px with corner (1, 1): area 8 px².
            let v = |x: f32, y: f32| MeshVertex {
                x,
                y,
                rgb: [level; 3],
            };
            out.mesh.vertices = vec![v(1.0, 1.0), v(5.0, 1.0), v(1.0, 5.0)];
            out.mesh.triangles = vec![[0, 1, 2]];
        }
        out.items_drawn = 1;
        Ok(())
    }
}

flarebench_sdk::export_plugin!(Faulty);
