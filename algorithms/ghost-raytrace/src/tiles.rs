//! Every planned ghost drawn alone, each into the window of the frame it lights
//! ([`render_ghost_tiles`]): what a per-ghost layer (its energy, its box, an ID layer, a layer
//! per light) is made from, without drawing the frame a second time or handling a whole frame
//! per ghost.
//!
//! Each ghost is drawn as [`ghosts::render_into`](crate::ghosts::render_into) draws it (its
//! light's plan holding it alone), into a black frame-sized buffer from a pool
//! ([`TileBuffers`]). Its
//! window is found from the triangles it was drawn with ([`GhostWindow`]): each level's mesh
//! bounds, in full-resolution pixels, widened by the bilinear upsampling's reach (1.5 coarse
//! pixels) and a pixel of rasterizer coverage, clipped to the frame. The window is copied out
//! and cleared in the buffer, so the next ghost starts on black. Ghosts are drawn in parallel;
//! the tiles come back in plan order, each the same bits whatever the thread count.
//!
//! Summing the tiles gives the frame's image up to the order of the f32 additions (a coarse
//! ghost is upsampled alone, not with its level's other ghosts).

use std::sync::{Mutex, PoisonError};

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::context::GhostStats;
use flarebench_sdk::ghost::mesh::GhostMesh;
use flarebench_sdk::ghost::sink::{FrameLevels, GhostSink};
use flarebench_sdk::image::{CoarseGrid, HdrImage};
use rayon::prelude::*;

use crate::GhostRenderError;
use crate::ghosts::{RenderOptions, RenderScratch, Targets, draw_into};
use crate::plan::LightPlan;

/// One ghost drawn alone: the window of the frame holding every pixel it lights.
#[derive(Clone, Debug)]
pub struct GhostTile {
    /// Its light's index and its index in that light's plan.
    pub light: usize,
    pub ghost: usize,
    /// The window's top-left pixel in the frame.
    pub x0: usize,
    pub y0: usize,
    /// The window's pixels, row-major (empty, 0 × 0, when the ghost draws nothing).
    pub image: HdrImage,
    pub stats: GhostStats,
}

impl GhostTile {
    /// The window as `[x0, y0, x1, y1]` (pixels, x1 and y1 excluded).
    pub fn rect(&self) -> [usize; 4] {
        [
            self.x0,
            self.y0,
            self.x0 + self.image.width,
            self.y0 + self.image.height,
        ]
    }
}

/// Frame-sized buffers (and their coarse frames) the ghosts are drawn into, kept for the next
/// ghost and the next call: a buffer is black between ghosts (its window is cleared as it is
/// copied out), so any ghost may take any buffer. Allocating one per ghost (or per rayon job)
/// faulted a fresh 25 MB in at 1920 × 1080 each time: the system time doubled a sample's.
/// Holds as many as ghosts were ever drawn at once; a buffer of another frame size is
/// dropped when met.
#[derive(Debug, Default)]
pub struct TileBuffers {
    free: Mutex<Vec<(HdrImage, RenderScratch)>>,
}

impl TileBuffers {
    /// No buffers yet.
    pub const fn new() -> TileBuffers {
        TileBuffers {
            free: Mutex::new(Vec::new()),
        }
    }

    /// A black buffer of `frame`'s size: a kept one, or a new one.
    fn take(&self, frame: Frame) -> (HdrImage, RenderScratch) {
        let mut free = self.free.lock().unwrap_or_else(PoisonError::into_inner);
        while let Some((img, scratch)) = free.pop() {
            if (img.width, img.height) == (frame.width, frame.height) {
                return (img, scratch);
            }
        }
        drop(free);
        (
            HdrImage::new(frame.width, frame.height),
            RenderScratch::default(),
        )
    }

    /// Gives a black buffer back.
    fn give(&self, buffer: (HdrImage, RenderScratch)) {
        self.free
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(buffer);
    }
}

/// Full-resolution pixels of rasterizer reach added on each side of a mesh's bounds: a
/// triangle with exact coverage lights the pixels its corners fall in.
const COVERAGE_MARGIN_PX: f64 = 1.0;

/// Draws every planned ghost of `plans` alone, into buffers taken from `buffers`; returns
/// the tiles in plan order (light by light, each light's ghosts in order).
pub fn render_ghost_tiles(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
    buffers: &TileBuffers,
) -> Result<Vec<GhostTile>, GhostRenderError> {
    let options = RenderOptions {
        replace: false,
        ..options
    };
    // Each light's plan without its ghosts: a ghost's own plan is this with the ghost added.
    let empty = crate::ghosts::without_ghosts(plans);
    let jobs: Vec<(usize, usize)> = plans
        .iter()
        .enumerate()
        .flat_map(|(li, p)| (0..p.ghosts.len()).map(move |gi| (li, gi)))
        .collect();
    jobs.par_iter()
        .map(|&(light, ghost)| {
            let (mut buffer, mut scratch) = buffers.take(frame);
            let tile = render_alone(
                system,
                aperture,
                frame,
                &empty[light],
                plans,
                (light, ghost),
                options,
                (&mut buffer, &mut scratch),
            );
            // Black again whether or not the ghost was drawn: its window was cleared, and a
            // failed ghost draws nothing (the error comes before its meshes).
            buffers.give((buffer, scratch));
            tile
        })
        .collect()
}

/// Draws ghost `ghost` of light `light` alone into `buffer` (black), with its light's plan
/// emptied of ghosts `empty`; copies its window out and leaves `buffer` black.
#[allow(
    clippy::too_many_arguments,
    reason = "the draw's inputs and the buffers it is drawn into"
)]
fn render_alone(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    empty: &LightPlan,
    plans: &[LightPlan],
    (light, ghost): (usize, usize),
    options: RenderOptions,
    (buffer, scratch): (&mut HdrImage, &mut RenderScratch),
) -> Result<GhostTile, GhostRenderError> {
    let mut plan = empty.clone();
    plan.ghosts.push(plans[light].ghosts[ghost].clone());
    let mut targets = Targets::new(scratch, aperture, &mut buffer.pixels, frame.width, false);
    let mut sink = GhostWindow {
        targets: &mut targets,
        grids: Vec::new(),
        bounds: None,
    };
    let stats = draw_into(
        system,
        aperture,
        frame,
        std::slice::from_ref(&plan),
        options,
        &mut sink,
    )?;
    let window = sink.window(frame);
    targets.keep(frame);
    let image = take_window(buffer, window);
    Ok(GhostTile {
        light,
        ghost,
        x0: window[0],
        y0: window[1],
        image,
        stats: stats[0].first().copied().unwrap_or_default(),
    })
}

/// The pixels of `window` (`[x0, y0, x1, y1]`) copied out of `buffer`, and made black there.
fn take_window(buffer: &mut HdrImage, [x0, y0, x1, y1]: [usize; 4]) -> HdrImage {
    let (w, h) = (x1 - x0, y1 - y0);
    let mut pixels = Vec::with_capacity(w * h);
    for y in y0..y1 {
        let row = &mut buffer.pixels[y * buffer.width + x0..y * buffer.width + x1];
        pixels.extend_from_slice(row);
        row.fill([0.0; 3]);
    }
    HdrImage::from_pixels(w, h, pixels).expect("the window's pixels were just copied")
}

/// A sink that passes every mesh on to the CPU targets and keeps the bounds of what was
/// drawn, in full-resolution pixels: `[x0, y0, x1, y1]`.
struct GhostWindow<'t, 'a> {
    targets: &'t mut Targets<'a>,
    grids: Vec<CoarseGrid>,
    bounds: Option<[f64; 4]>,
}

impl GhostWindow<'_, '_> {
    /// The window of the frame every drawn pixel lies in (empty, at 0, when nothing was
    /// drawn).
    fn window(&self, frame: Frame) -> [usize; 4] {
        let Some([x0, y0, x1, y1]) = self.bounds else {
            return [0; 4];
        };
        let clip = |v: f64, n: usize| v.clamp(0.0, n as f64) as usize;
        let (x0, x1) = (clip(x0.floor(), frame.width), clip(x1.ceil(), frame.width));
        let (y0, y1) = (
            clip(y0.floor(), frame.height),
            clip(y1.ceil(), frame.height),
        );
        if x0 >= x1 || y0 >= y1 {
            return [0; 4];
        }
        [x0, y0, x1, y1]
    }
}

/// The bounds `[x0, y0, x1, y1]` of `mesh`'s corners and boxes (pixels of its level), or
/// `None` for an empty mesh.
fn mesh_bounds(mesh: &GhostMesh) -> Option<[f32; 4]> {
    let corners = mesh
        .open
        .positions
        .iter()
        .chain(&mesh.edge.positions)
        .chain(&mesh.fringe.positions)
        .copied()
        .chain(
            mesh.boxes
                .rects
                .iter()
                .flat_map(|r| [[r[0], r[1]], [r[2], r[3]]]),
        );
    let mut b: Option<[f32; 4]> = None;
    for [x, y] in corners {
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        b = Some(match b {
            None => [x, y, x, y],
            Some([a, c, d, e]) => [a.min(x), c.min(y), d.max(x), e.max(y)],
        });
    }
    b
}

impl GhostSink for GhostWindow<'_, '_> {
    fn begin(&mut self, levels: FrameLevels<'_>) {
        self.grids = levels.grids.to_vec();
        self.bounds = None;
        self.targets.begin(levels);
    }

    fn draw(&mut self, level: usize, mesh: &GhostMesh) {
        if let Some([x0, y0, x1, y1]) = mesh_bounds(mesh) {
            // A level pixel coordinate c is c·f − offset at full resolution; a lit coarse
            // pixel reaches 1.5 coarse pixels either side of its corner through the bilinear
            // upsampling (none at full resolution), and coverage a pixel more.
            let grid = &self.grids[level];
            let f = grid.factor as f64;
            let reach = if grid.factor > 1 { 1.5 * f } else { 0.0 } + COVERAGE_MARGIN_PX;
            let full = |c: f32, o: f64| f64::from(c) * f - o;
            let b = [
                full(x0, grid.offset[0]) - reach,
                full(y0, grid.offset[1]) - reach,
                full(x1, grid.offset[0]) + reach,
                full(y1, grid.offset[1]) + reach,
            ];
            self.bounds = Some(match self.bounds {
                None => b,
                Some(a) => [
                    a[0].min(b[0]),
                    a[1].min(b[1]),
                    a[2].max(b[2]),
                    a[3].max(b[3]),
                ],
            });
        }
        self.targets.draw(level, mesh);
    }

    fn finish(&mut self) {
        self.targets.finish();
    }
}
