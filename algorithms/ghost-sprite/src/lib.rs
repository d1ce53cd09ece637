//! The naive ghost flare most games draw: a row of sprites on the line through the light's
//! image and the image centre, with no lens behind it. Sprite `k` sits at
//! `C + t_k · (L − C)` (`C` the image centre, `L` the light's paraxial image, `EFL · tan θ` from
//! the axis), is a disc or the iris polygon (the scene's aperture) of radius
//! `size · s_k · frame height`, and carries energy `gain · intensity · w_k` in colour `tint_k`,
//! spread uniformly over its area. The layout table ([`SPRITES`]) is ours; games tune theirs by
//! eye. It is the baseline `flarebench compare` measures the physical algorithms against.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};
use flarebench_sdk::aperture::{Aperture, polygon_area};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::raster::rasterize;
use flarebench_sdk::spectrum::LAMBDA_D_NM;

/// One sprite of the layout: position along the line (0 at the centre, 1 at the light's
/// image), radius relative to the `size` parameter, energy weight, linear RGB tint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sprite {
    pub t: f64,
    pub scale: f64,
    pub weight: f64,
    pub tint: [f32; 3],
}

/// The layout: mostly on the far side of the centre, as ghosts of a light fall.
pub const SPRITES: [Sprite; 8] = [
    Sprite {
        t: -1.20,
        scale: 1.00,
        weight: 1.0,
        tint: [0.55, 0.75, 1.00],
    },
    Sprite {
        t: -0.75,
        scale: 0.45,
        weight: 0.5,
        tint: [0.70, 1.00, 0.70],
    },
    Sprite {
        t: -0.45,
        scale: 0.70,
        weight: 0.8,
        tint: [1.00, 0.80, 0.55],
    },
    Sprite {
        t: -0.20,
        scale: 0.25,
        weight: 0.3,
        tint: [1.00, 0.60, 0.90],
    },
    Sprite {
        t: 0.15,
        scale: 0.35,
        weight: 0.3,
        tint: [0.60, 0.90, 1.00],
    },
    Sprite {
        t: 0.40,
        scale: 0.55,
        weight: 0.6,
        tint: [0.90, 0.90, 0.60],
    },
    Sprite {
        t: 0.65,
        scale: 0.20,
        weight: 0.2,
        tint: [0.80, 0.60, 1.00],
    },
    Sprite {
        t: 1.60,
        scale: 0.80,
        weight: 0.7,
        tint: [0.60, 1.00, 0.85],
    },
];

/// Vertices of a circle drawn as a polygon.
const CIRCLE_SIDES: usize = 48;

/// The plugin: the lens's focal length (mm).
#[derive(Debug, Default)]
pub struct GhostSprite {
    efl_mm: f64,
}

/// Pixel position of the paraxial image of a light at (`theta_deg`, `phi_deg`).
pub fn light_image_px(
    efl_mm: f64,
    frame: &flarebench_sdk::frame::Frame,
    theta_deg: f64,
    phi_deg: f64,
) -> [f64; 2] {
    // Rays tilted toward +y at φ = 0 (`Ray::collimated`) land at y = −EFL·tan θ, and the
    // sensor frame turns with φ.
    let r = -efl_mm * theta_deg.to_radians().tan();
    let phi = phi_deg.to_radians();
    let [x, y] = frame.to_pixel(-r * phi.sin(), r * phi.cos());
    [x as f64, y as f64]
}

/// The polygon of a sprite's shape, unit circumradius, in pixels' orientation.
fn shape(aperture: &Aperture) -> Vec<[f64; 2]> {
    let (n, rot) = match *aperture {
        Aperture::Iris {
            blades,
            rotation_rad,
            ..
        } => (blades as usize, rotation_rad),
        _ => (CIRCLE_SIDES, 0.0),
    };
    (0..n)
        .map(|k| {
            let a = rot + std::f64::consts::TAU * k as f64 / n as f64;
            [a.cos(), a.sin()]
        })
        .collect()
}

/// Draws the sprites of every light into `img`; returns how many were drawn.
pub fn draw(
    efl_mm: f64,
    scene: &Scene,
    size: f64,
    gain: f64,
    count: usize,
    img: &mut HdrImage,
) -> u32 {
    let frame = scene.frame;
    let unit = shape(&scene.aperture);
    let unit_area = polygon_area(&unit);
    let centre = [frame.width as f64 / 2.0, frame.height as f64 / 2.0];
    let mut positions = Vec::new();
    let mut attrs = Vec::new();
    let mut triangles = Vec::new();
    let mut drawn = 0;
    for light in &scene.lights {
        let l = light_image_px(efl_mm, &frame, light.theta_deg, light.phi_deg);
        for s in SPRITES.iter().take(count) {
            let c = [
                centre[0] + s.t * (l[0] - centre[0]),
                centre[1] + s.t * (l[1] - centre[1]),
            ];
            let r = size * s.scale * frame.height as f64;
            // Uniform radiance: energy over area, per channel of the tint.
            let radiance = gain * light.intensity * s.weight / (unit_area * r * r);
            let rgb = s.tint.map(|t| (t as f64 * radiance) as f32);
            let base = positions.len() as u32;
            positions.push([c[0] as f32, c[1] as f32]);
            attrs.push(rgb);
            for v in &unit {
                positions.push([(c[0] + r * v[0]) as f32, (c[1] + r * v[1]) as f32]);
                attrs.push(rgb);
            }
            let n = unit.len() as u32;
            for k in 0..n {
                triangles.push([base, base + 1 + k, base + 1 + (k + 1) % n]);
            }
            drawn += 1;
        }
    }
    rasterize(img, &positions, &attrs, &triangles, |&c| c);
    drawn
}

impl FlarePlugin for GhostSprite {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "ghost-sprite",
            version: env!("CARGO_PKG_VERSION"),
            description: "the game baseline: sprites on the line through the light's image and the centre (no optics)",
            kind: PluginKind::Ghosts,
            params: vec![
                ParamSpec::int(
                    "count",
                    "sprites per light",
                    1,
                    SPRITES.len() as i64,
                    SPRITES.len() as i64,
                ),
                ParamSpec::float(
                    "size",
                    "largest sprite's radius over the frame height",
                    0.001,
                    2.0,
                    0.25,
                ),
                ParamSpec::float(
                    "gain",
                    "energy of a weight-1 sprite per unit of light intensity (image units)",
                    0.0,
                    1e9,
                    1.0,
                ),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(GhostSprite::default())
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
        let mut img = HdrImage::new(out.width, out.height);
        out.items_drawn = draw(
            self.efl_mm,
            scene,
            params.get("size")?,
            params.get("gain")?,
            params.get_int("count")? as usize,
            &mut img,
        );
        out.add_image(&img)
    }
}

flarebench_sdk::export_plugin!(GhostSprite);
