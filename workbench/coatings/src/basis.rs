//! Each ghost's image at each of its traced bands, split by the angles of incidence at its two
//! reflections, with its transmission divided out: what any choice of coatings re-weights.
//!
//! A ghost's image at one band is its traced geometry times, per ray, its path's throughput:
//! the transmittances of the surfaces it crosses and the reflectances of the two it reflects
//! at, each at the ray's angle there. Coatings change the factors, not the geometry. A coating's
//! reflectance varies with the angle of incidence steeply near its minimum (a ghost of a fast
//! lens meets its surfaces at 0–40°), so the basis keeps that variation: each band is rendered
//! once per pair of hat functions of the two reflections' incidence cosines (nodes
//! [`NODE_DEG`] for the choice, [`FIT_NODE_DEG`] for the fit: piecewise linear in `cos² θ`, one
//! at a node and zero at the next), their sum being the ghost's image with both reflectances
//! replaced by their interpolation between the nodes.
//! Divided by the path's transmission at normal incidence at the band's centre, each such
//! image times its colour under other coatings (`crate::reweight`: the two reflectances at the
//! pair's nodes, with the light's weights and the path's transmission over the band's bin) is
//! the ghost's image under those coatings. What is left out is
//! how the transmittances vary with the angle, which moves a ghost's light by a fraction of
//! the surfaces' reflectance changes; at the coatings the basis is rendered with, the
//! interpolation between the nodes is what is left. [`Basis::render`] renders the images once (every ghost
//! with light, none culled as dim: a ghost dim under one set of coatings may be bright under
//! another); a fit or a choice of coatings then costs a few products per image, not a render.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::context::Band;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::colour::{Bin, surface_factors};
use ghost_raytrace::ghosts::{RenderOptions, render_each_ghost};
use ghost_raytrace::plan::{GhostBand, GhostJob, PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};
use std::sync::Arc;

use crate::CoatingError;
use crate::reweight::transmission;

/// Angles of incidence (degrees) of the nodes of the hat functions a ghost's two reflections
/// are split by, for the choice of coatings (`crate::choice`): the coarse split.
pub const NODE_DEG: [f64; 7] = [0.0, 10.0, 20.0, 30.0, 40.0, 55.0, 90.0];

/// The fit's nodes (`crate::fit`): 8° apart to 40°. Linear interpolation of a reflectance
/// between nodes 10° apart leaves the Cooke triplet's basis 0.66% (relative RMSE) from the
/// renderer at strongly reflecting single layers; between these, 0.30%, for 30% more images.
pub const FIT_NODE_DEG: [f64; 9] = [0.0, 8.0, 16.0, 24.0, 32.0, 40.0, 50.0, 65.0, 90.0];

/// The cosines of nodes at `deg` (increasing from 0 to 90), from normal incidence (1) to
/// grazing (0).
pub fn node_cos(deg: &[f64]) -> Vec<f64> {
    deg.iter()
        .map(|&d| if d >= 90.0 { 0.0 } else { d.to_radians().cos() })
        .collect()
}

/// Hat function `i` of the incidence cosine `c` over nodes of cosines `nodes`: 1 at node
/// `i`, linear in `cos² θ` to 0 at its neighbours; the hats sum to 1 everywhere in [0, 1].
/// Linear in `cos² θ = 1 − sin² θ` because a coating's reflectance starts from normal
/// incidence as `R₀ + a sin² θ`.
pub fn hat(nodes: &[f64], i: usize, c: f64) -> f64 {
    let n = |k: usize| nodes[k] * nodes[k];
    let v = c.clamp(0.0, 1.0).powi(2);
    if i > 0 && v >= n(i) && v <= n(i - 1) {
        (n(i - 1) - v) / (n(i - 1) - n(i))
    } else if i + 1 < nodes.len() && v >= n(i + 1) && v <= n(i) {
        (v - n(i + 1)) / (n(i) - n(i + 1))
    } else {
        0.0
    }
}

/// One band of one ghost, for one pair of hats: its image over its bounding box, per unit of
/// the light its path carries over the band.
#[derive(Clone, Debug)]
pub struct BandImage {
    /// Bin `bin` of the ghost's `m` equal bins over 380–780 nm.
    pub bin: usize,
    /// The hats ([`hat`]) of its first and second reflection.
    pub hats: (usize, usize),
    /// The box (pixels) the image covers: columns `x0..x0 + w`, rows `y0..y0 + h`.
    pub x0: usize,
    pub y0: usize,
    pub w: usize,
    pub h: usize,
    /// Row-major, `w × h`.
    pub pixels: Vec<f32>,
    /// The sum of its pixels.
    pub sum: f64,
}

impl BandImage {
    /// The value at frame pixel `(x, y)` (0 outside the box).
    pub fn at(&self, x: usize, y: usize) -> f32 {
        if x < self.x0 || y < self.y0 || x >= self.x0 + self.w || y >= self.y0 + self.h {
            return 0.0;
        }
        self.pixels[(y - self.y0) * self.w + (x - self.x0)]
    }
}

/// One ghost's band images.
#[derive(Clone, Debug)]
pub struct GhostBasis {
    pub path: GhostPath,
    /// The number of equal bins its bands are (`m`).
    pub bins: usize,
    pub bands: Vec<BandImage>,
}

/// Every ghost's band images for one lens, light and frame.
#[derive(Clone, Debug)]
pub struct Basis {
    pub frame: Frame,
    pub light: LightSpec,
    /// The cosines of the hats' nodes ([`node_cos`]).
    pub nodes: Vec<f64>,
    pub ghosts: Vec<GhostBasis>,
}

impl Basis {
    /// Renders the band images of every ghost of `system` with light under `light` (its
    /// coatings those of `system`), at `quality`'s grids and bands, two reflections, split at
    /// the nodes [`NODE_DEG`].
    pub fn render(
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        light: &LightSpec,
        quality: Quality,
    ) -> Result<Basis, CoatingError> {
        Self::render_with_nodes(system, aperture, frame, light, quality, &NODE_DEG)
    }

    /// [`Basis::render`] split at the nodes `node_deg` (degrees, increasing from 0 to 90).
    pub fn render_with_nodes(
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        light: &LightSpec,
        quality: Quality,
        node_deg: &[f64],
    ) -> Result<Basis, CoatingError> {
        let mut opts = PlanOptions::for_quality(quality, None);
        opts.cull = false;
        Self::render_planned(system, aperture, frame, light, &opts, node_deg)
    }

    /// [`Basis::render_with_nodes`] planned with `opts` (culling as they say).
    pub fn render_planned(
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        light: &LightSpec,
        opts: &PlanOptions<'_>,
        node_deg: &[f64],
    ) -> Result<Basis, CoatingError> {
        // A sensor stack's sensor reflects with no angle table to split: not modelled here.
        if system.sensor_stack.is_some() {
            return Err(CoatingError::SensorStack(system.name.clone()));
        }
        let plans = plan(system, std::slice::from_ref(light), &frame, opts)?;
        let Some(mut lp) = plans.into_iter().next() else {
            return Err(CoatingError::NoLight);
        };
        // One job per ghost band and pair of hats, in a colour of one, each with its own
        // tables (the band's, with the two reflections' reflectances replaced by the hats).
        let node_cos = node_cos(node_deg);
        let nodes = node_cos.len();
        let mut jobs: Vec<(GhostPath, usize, usize, (usize, usize))> = Vec::new();
        let mut ghost_jobs = Vec::new();
        let mut bands = lp.bands.clone();
        for g in &lp.ghosts {
            let m = g.bands.len();
            let (a, b) = (g.path.first(), g.path.second());
            for (i, gb) in g.bands.iter().enumerate() {
                let base = &lp.bands[gb.band];
                for h1 in 0..nodes {
                    let Some(first) = base
                        .tables
                        .with_reflectance(a, true, |c| hat(&node_cos, h1, c))
                    else {
                        continue;
                    };
                    for h2 in 0..nodes {
                        let Some(tables) =
                            first.with_reflectance(b, false, |c| hat(&node_cos, h2, c))
                        else {
                            continue;
                        };
                        bands.push(Band {
                            lambda_nm: base.lambda_nm,
                            rgb: [0.0; 3],
                            tables: Arc::new(tables),
                        });
                        ghost_jobs.push(GhostJob {
                            bands: vec![GhostBand {
                                band: bands.len() - 1,
                                rgb: [1.0; 3],
                            }],
                            ..g.clone()
                        });
                        jobs.push((g.path, m, i, (h1, h2)));
                    }
                }
            }
        }
        lp.bands = bands;
        lp.ghosts = ghost_jobs;
        let options = RenderOptions {
            band_by_band: true,
            ..RenderOptions::default()
        };
        let (images, _) = render_each_ghost(
            system,
            aperture,
            frame,
            std::slice::from_ref(&lp),
            options,
            |_, _, img| crop(img),
        )?;
        let sensor = system.sensor_index();
        let mut ghosts: Vec<GhostBasis> = Vec::new();
        for ((path, m, i, hats), image) in jobs.into_iter().zip(images) {
            let centre = Bin::new(system, m, i).centre_nm;
            let t0 = transmission(path, &surface_factors(system, centre), sensor);
            let Some(mut band) = image.filter(|_| t0 > 0.0 && t0.is_finite()) else {
                continue;
            };
            band.bin = i;
            band.hats = hats;
            let scale = (1.0 / t0) as f32;
            band.pixels.iter_mut().for_each(|p| *p *= scale);
            band.sum = band.pixels.iter().map(|&p| f64::from(p)).sum();
            match ghosts.last_mut() {
                Some(g) if g.path == path => g.bands.push(band),
                _ => ghosts.push(GhostBasis {
                    path,
                    bins: m,
                    bands: vec![band],
                }),
            }
        }
        Ok(Basis {
            frame,
            light: light.clone(),
            nodes: node_cos,
            ghosts,
        })
    }

    /// The number of band images.
    pub fn band_count(&self) -> usize {
        self.ghosts.iter().map(|g| g.bands.len()).sum()
    }
}

/// The ghost renderer's own image of a lens's ghosts, and each ghost's energy (summed over the
/// frame, per channel), in plan order: what a basis approximates.
#[derive(Clone, Debug)]
pub struct Rendered {
    pub image: HdrImage,
    pub energies: Vec<(GhostPath, [f64; 3])>,
}

/// [`Rendered`] of `system`'s ghosts under `light`, planned as the basis is
/// ([`Basis::render_with_nodes`]: every ghost with light, none culled).
pub fn render_ghosts(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    light: &LightSpec,
    quality: Quality,
) -> Result<Rendered, CoatingError> {
    let mut opts = PlanOptions::for_quality(quality, None);
    opts.cull = false;
    let plans = plan(system, std::slice::from_ref(light), &frame, &opts)?;
    let (energies, image) = render_each_ghost(
        system,
        aperture,
        frame,
        &plans,
        RenderOptions::default(),
        |_, job, img| {
            let mut e = [0.0; 3];
            for p in &img.pixels {
                for (e, &c) in e.iter_mut().zip(p) {
                    *e += f64::from(c);
                }
            }
            (job.path, e)
        },
    )?;
    Ok(Rendered { image, energies })
}

/// The lit box of `img`'s first channel (every channel is the same: the band is drawn in a
/// colour of one), or `None` when nothing is lit.
fn crop(img: &HdrImage) -> Option<BandImage> {
    let (w, h) = (img.width, img.height);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        for x in 0..w {
            if img.pixels[y * w + x][0] != 0.0 {
                x0 = x0.min(x);
                x1 = x1.max(x + 1);
                y0 = y0.min(y);
                y1 = y1.max(y + 1);
            }
        }
    }
    if x1 <= x0 || y1 <= y0 {
        return None;
    }
    let (bw, bh) = (x1 - x0, y1 - y0);
    let mut pixels = Vec::with_capacity(bw * bh);
    for y in y0..y1 {
        pixels.extend(img.pixels[y * w + x0..y * w + x1].iter().map(|p| p[0]));
    }
    Some(BandImage {
        bin: 0,
        hats: (0, 0),
        x0,
        y0,
        w: bw,
        h: bh,
        pixels,
        sum: 0.0,
    })
}
