//! Each ghost's image at each of its traced bands, with its colour divided out: what any
//! choice of coatings re-weights.
//!
//! A ghost's image at one band is its traced geometry times, per ray, the throughput of its
//! path at that ray's angles. Coatings change the throughput, not the geometry. Divided by the
//! path's throughput at normal incidence at the band's centre, the image keeps only how the
//! throughput varies with the rays' angles, which coatings change little; multiplied by the
//! light the path carries over the band under other coatings
//! (`GhostColours::bin_light`), it is the ghost's image under those coatings. [`Basis::render`]
//! renders the band images once (every ghost with light, none culled as dim: a ghost dim
//! under one set of coatings may be bright under another); a fit or a choice of coatings
//! then costs a few products per band, not a render. The approximation is exact for the
//! coatings the basis was rendered with, and re-rendering the basis with a fit's coatings
//! removes it at the fit's solution (`crate::fit`).

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::colour::Bin;
use ghost_raytrace::ghosts::{RenderOptions, render_each_ghost};
use ghost_raytrace::plan::{GhostBand, GhostJob, PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};

use crate::CoatingError;

/// One band of one ghost: its image over its bounding box, per unit of the light the path
/// carries over the band.
#[derive(Clone, Debug)]
pub struct BandImage {
    /// Bin `bin` of the ghost's `m` equal bins over 380–780 nm.
    pub bin: usize,
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
    pub ghosts: Vec<GhostBasis>,
}

impl Basis {
    /// Renders the band images of every ghost of `system` with light under `light` (its
    /// coatings those of `system`), at `quality`'s grids and bands, two reflections.
    pub fn render(
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        light: &LightSpec,
        quality: Quality,
    ) -> Result<Basis, CoatingError> {
        let mut opts = PlanOptions::for_quality(quality, None);
        opts.cull = false;
        let plans = plan(system, std::slice::from_ref(light), &frame, &opts)?;
        let Some(mut lp) = plans.into_iter().next() else {
            return Err(CoatingError::NoLight);
        };
        // One job per ghost band, in its colour of one.
        let jobs: Vec<(GhostPath, usize, usize)> = lp
            .ghosts
            .iter()
            .flat_map(|g| {
                let m = g.bands.len();
                (0..m).map(move |i| (g.path, m, i))
            })
            .collect();
        lp.ghosts = lp
            .ghosts
            .iter()
            .flat_map(|g| {
                g.bands.iter().map(|b| GhostJob {
                    bands: vec![GhostBand {
                        band: b.band,
                        rgb: [1.0; 3],
                    }],
                    ..g.clone()
                })
            })
            .collect();
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
        let mut ghosts: Vec<GhostBasis> = Vec::new();
        for ((path, m, i), image) in jobs.into_iter().zip(images) {
            let t0 = Bin::new(system, m, i).throughput(path, system);
            let Some(mut band) = image.filter(|_| t0 > 0.0 && t0.is_finite()) else {
                continue;
            };
            band.bin = i;
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
            ghosts,
        })
    }

    /// The number of band images.
    pub fn band_count(&self) -> usize {
        self.ghosts.iter().map(|g| g.bands.len()).sum()
    }
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
        x0,
        y0,
        w: bw,
        h: bh,
        pixels,
        sum: 0.0,
    })
}
