//! Rendering one ghost into an HDR image: trace its grid at each wavelength band, turn every
//! grid cell into two triangles on the sensor, and rasterise them with energy-conserving
//! intensities.
//!
//! **Energy.** A triangle carries the flux that crossed its half cell of the entrance plane,
//! `E · A_entrance · cos θ`, spread uniformly over its area on the sensor, then weighted by the
//! interpolated Fresnel/coating throughput, the aperture transmission at the stop and the
//! feathered clip. The rasteriser adds covered area × irradiance, so a triangle adds exactly
//! its flux to the image (when it lies in the frame), however small or folded it is.
//!
//! **Caustics.** Where the mesh folds, triangles collapse. Light cannot be focused below the
//! diffraction limit, so a triangle smaller than the Airy disc of the lens at this wavelength,
//! `π (1.22 λ N)²` (N the working f-number), is scaled up about its centroid to that area:
//! the flux is kept and the peak irradiance is bounded by what optics allows.
//!
//! **Image orientation.** The output is the photograph: the sensor image turned by 180°, so a
//! point at sensor (x, y) mm lands at pixel ((0.5 − x/W)·w, (0.5 + y/H)·h), pixel rows downward.

use crate::aperture::{Aperture, ApertureSampler};
use crate::frame::Frame;
use crate::image::HdrImage;
use crate::raster::{Coverage, RowSplit, Shader, rasterize_into, rasterize_shaded_into};
use crate::system::LensSystem;
use std::sync::Arc;

use crate::trace::{InterfaceTableSet, Sequence};

use super::bounds::GhostBounds;
use super::enumerate::GhostPath;
use super::fringe::{FringeShader, FringeTable};
use super::grid::{GridTrace, trace_grid, trace_grid_f64};

/// One wavelength band of a spectral render: where to trace and what colour it adds.
#[derive(Clone, Debug)]
pub struct Band {
    pub lambda_nm: f64,
    /// Linear-sRGB weight of the band (for a light of unit irradiance).
    pub rgb: [f32; 3],
    /// The lens's interface tables at `lambda_nm` (shared: a lens's tables at a wavelength
    /// serve every frame's plan).
    pub tables: Arc<InterfaceTableSet>,
}

impl Band {
    /// A band at `lambda_nm` with colour `rgb` for `system`.
    pub fn new(system: &LensSystem, lambda_nm: f64, rgb: [f32; 3]) -> Self {
        Band {
            lambda_nm,
            rgb,
            tables: Arc::new(InterfaceTableSet::for_system(system, lambda_nm)),
        }
    }

    /// The band as the renderer takes it.
    pub fn as_ref(&self) -> BandRef<'_> {
        BandRef {
            lambda_nm: self.lambda_nm,
            rgb: self.rgb,
            tables: &self.tables,
        }
    }
}

/// A band to trace: wavelength, colour, and the lens's interface tables at that wavelength
/// (shared between ghosts; the colour may be a ghost's own).
#[derive(Clone, Copy, Debug)]
pub struct BandRef<'a> {
    pub lambda_nm: f64,
    pub rgb: [f32; 3],
    pub tables: &'a InterfaceTableSet,
}

/// A collimated light as the ghost renderer sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GhostLight {
    /// Angle to the axis and azimuth (radians).
    pub theta: f64,
    pub phi: f64,
    /// Irradiance perpendicular to the beam (image units per mm²).
    pub irradiance: f64,
}

/// What rendering a ghost did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GhostStats {
    /// Rays traced (grid vertices × bands).
    pub rays: usize,
    /// Triangles rasterised.
    pub triangles: usize,
    /// Flux carried by the rasterised triangles (before the frame crops it), summed over the
    /// bands' luminance weights.
    pub flux: f64,
}

/// Triangles with `N` attributes each, three vertices of their own per triangle.
#[derive(Clone, Debug, Default)]
pub struct Mesh<const N: usize> {
    pub positions: Vec<[f32; 2]>,
    pub attrs: Vec<[f32; N]>,
    pub triangles: Vec<[u32; 3]>,
}

impl<const N: usize> Mesh<N> {
    /// An empty mesh with room for `triangles` triangles.
    pub fn with_capacity(triangles: usize) -> Self {
        Mesh {
            positions: Vec::with_capacity(3 * triangles),
            attrs: Vec::with_capacity(3 * triangles),
            triangles: Vec::with_capacity(triangles),
        }
    }

    /// Makes room for `triangles` more triangles.
    pub fn reserve(&mut self, triangles: usize) {
        self.positions.reserve(3 * triangles);
        self.attrs.reserve(3 * triangles);
        self.triangles.reserve(triangles);
    }

    /// Removes every triangle, keeping the buffers.
    pub fn clear(&mut self) {
        self.positions.clear();
        self.attrs.clear();
        self.triangles.clear();
    }

    /// Keeps the first `triangles` triangles.
    pub fn truncate_to(&mut self, triangles: usize) {
        if triangles < self.triangles.len() {
            let vertices = self.triangles[triangles..]
                .iter()
                .flat_map(|t| t.iter())
                .fold(usize::MAX, |m, &i| m.min(i as usize));
            self.triangles.truncate(triangles);
            self.positions.truncate(vertices);
            self.attrs.truncate(vertices);
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True without triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Adds a triangle with corners `p` (pixels) and their attributes `a`.
    pub fn push(&mut self, p: [[f32; 2]; 3], a: [[f32; N]; 3]) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&p);
        self.attrs.extend_from_slice(&a);
        self.triangles.push([base, base + 1, base + 2]);
    }

    /// Adds every triangle of `other` after this mesh's own.
    pub fn append(&mut self, other: &Mesh<N>) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.attrs.extend_from_slice(&other.attrs);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }
}

/// Attributes of a wholly open triangle's corner: its RGB irradiance (image units per
/// pixel²).
pub type OpenAttrs = [f32; 3];

/// Attributes of an edge triangle's corner: RGB irradiance before the edges, the stop
/// crossing `u`, `v` in the lens's frame, the largest relative radius, the feather width (the
/// same at every corner) and 1 where the aperture's outline must be evaluated (0 where the
/// triangle lies wholly inside the opening: only the clip radius cuts it).
pub type EdgeAttrs = [f32; 8];

/// Ghost triangles ready to rasterize (any number of ghosts and bands): the wholly open ones,
/// whose shade is their interpolated irradiance, and those on an edge (the clip radius or the
/// aperture's outline), which are feathered per pixel ([`rasterize_ghost_mesh`]).
#[derive(Clone, Debug, Default)]
pub struct GhostMesh {
    pub open: Mesh<3>,
    pub edge: Mesh<8>,
    /// Triangles standing for all of a ghost's bands at once, their colour fringes shaded per
    /// pixel ([`super::fringe`]), and the ghosts' colour tables they index.
    pub fringe: Mesh<12>,
    pub fringe_tables: Vec<FringeTable>,
}

impl GhostMesh {
    /// An empty mesh with room for `open` wholly open and `edge` edge triangles.
    pub fn with_capacity(open: usize, edge: usize) -> Self {
        GhostMesh {
            open: Mesh::with_capacity(open),
            edge: Mesh::with_capacity(edge),
            fringe: Mesh::default(),
            fringe_tables: Vec::new(),
        }
    }

    /// Removes every triangle, keeping the buffers.
    pub fn clear(&mut self) {
        self.open.clear();
        self.edge.clear();
        self.fringe.clear();
        self.fringe_tables.clear();
    }

    /// Makes room for the triangles of `meshes`.
    pub fn reserve<'a>(&mut self, meshes: impl Iterator<Item = &'a GhostMesh> + Clone) {
        let open: usize = meshes.clone().map(|m| m.open.len()).sum();
        let edge: usize = meshes.clone().map(|m| m.edge.len()).sum();
        let fringe: usize = meshes.map(|m| m.fringe.len()).sum();
        self.open.reserve(open);
        self.edge.reserve(edge);
        self.fringe.reserve(fringe);
    }

    /// Adds every triangle of `other` after this mesh's own.
    pub fn append(&mut self, other: &GhostMesh) {
        self.open.append(&other.open);
        self.edge.append(&other.edge);
        // The appended fringe triangles index the appended tables.
        let first = self.fringe.attrs.len();
        self.fringe.append(&other.fringe);
        let base = self.fringe_tables.len() as f32;
        for a in &mut self.fringe.attrs[first..] {
            a[11] += base;
        }
        self.fringe_tables.extend_from_slice(&other.fringe_tables);
    }
}

/// Reusable buffers for [`render_ghost`].
#[derive(Debug, Default)]
pub struct GhostScratch {
    grid: GridTrace,
    mesh: GhostMesh,
}

/// Everything fixed for a frame: lens data the renderer needs per ghost.
#[derive(Clone, Copy, Debug)]
pub struct GhostContext<'a> {
    pub system: &'a LensSystem,
    pub aperture: &'a Aperture,
    pub frame: Frame,
    /// The stop's working radius (mm) and the working f-number.
    pub stop_radius: f64,
    pub f_number: f64,
    /// Trace the grids in f64 instead of f32. The f32 images agree with the f64 ones to a
    /// relative RMSE of 6e-6 (Heliar), 4.5e-4 (Nikon zoom), 1.6e-5 (fisheye at 60°)
    /// (`algorithms/ghost-raytrace/tests/precision.rs`).
    pub trace_f64: bool,
}

/// Renders `path` lit by `light` into `img` with an `n × n` grid over `bounds.entrance`, one
/// trace per band: [`mesh_ghost`], then [`rasterize_ghost_mesh`].
#[allow(clippy::too_many_arguments)]
pub fn render_ghost(
    ctx: &GhostContext<'_>,
    path: GhostPath,
    bounds: &GhostBounds,
    n: usize,
    light: &GhostLight,
    bands: &[BandRef<'_>],
    scratch: &mut GhostScratch,
    img: &mut HdrImage,
) -> GhostStats {
    scratch.mesh.clear();
    let stats = mesh_ghost(
        ctx,
        path,
        bounds,
        n,
        light,
        bands,
        &mut scratch.grid,
        &mut scratch.mesh,
    );
    rasterize_ghost_mesh(img, &scratch.mesh, ctx.aperture);
    stats
}

/// Traces `path` lit by `light` with an `n × n` grid over `bounds.entrance` at each band and
/// appends its triangles, in pixels of `ctx.frame`, to `mesh`.
#[allow(clippy::too_many_arguments)]
pub fn mesh_ghost(
    ctx: &GhostContext<'_>,
    path: GhostPath,
    bounds: &GhostBounds,
    n: usize,
    light: &GhostLight,
    bands: &[BandRef<'_>],
    grid: &mut GridTrace,
    mesh: &mut GhostMesh,
) -> GhostStats {
    let mut stats = GhostStats::default();
    let aperture = ctx.aperture.sampler();
    for band in bands {
        if !trace_band(ctx, path, bounds, n, light, band, grid) {
            return stats;
        }
        stats.rays += n * n;
        let emit = BandTriangles::new(ctx, bounds, n, light, band, &aperture, grid);
        for tri in grid_triangles(n) {
            emit.push(tri, mesh, &mut stats);
        }
    }
    stats
}

/// Traces `path` at `band` into `grid` (f32 or f64 as `ctx` says); false when the path has
/// no sequence at this wavelength.
pub(crate) fn trace_band(
    ctx: &GhostContext<'_>,
    path: GhostPath,
    bounds: &GhostBounds,
    n: usize,
    light: &GhostLight,
    band: &BandRef<'_>,
    grid: &mut GridTrace,
) -> bool {
    let Ok(seq) = Sequence::ghost_path(ctx.system, band.lambda_nm, &path) else {
        return false;
    };
    // The aperture's shape clips at the stop (from the recorded crossing), so the grid's
    // radius clip must not clip there a second time.
    let seq = seq.with_tables_from(band.tables).aperture_by_mask();
    if ctx.trace_f64 {
        trace_grid_f64(&seq, light.theta, bounds.entrance, n, ctx.stop_radius, grid);
    } else {
        trace_grid(
            &seq.cast::<f32>(),
            light.theta,
            bounds.entrance,
            n,
            ctx.stop_radius,
            grid,
        );
    }
    true
}

/// The two triangles of every cell of an `n × n` grid (vertex indices, row-major).
pub(crate) fn grid_triangles(n: usize) -> impl Iterator<Item = [usize; 3]> {
    let cells = n.saturating_sub(1);
    (0..cells * cells).flat_map(move |c| {
        let k00 = (c / cells) * n + c % cells;
        let quad = [k00, k00 + 1, k00 + n + 1, k00 + n];
        [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]]
    })
}

/// What one band's triangles need, fixed for a traced grid: turns a grid triangle into a
/// mesh triangle ([`BandTriangles::push`]).
pub(crate) struct BandTriangles<'a> {
    pub grid: &'a GridTrace,
    frame: Frame,
    px_area: f64,
    pub feather: f32,
    /// Smallest sensor area a triangle may have (the Airy disc, mm²) and the Airy radius.
    pub min_area: f64,
    airy: f64,
    /// Flux per unit weight through half a grid cell.
    pub half_cell: f64,
    irradiance: f64,
    pub rgb: [f32; 3],
    lum: f64,
    sin_cos_phi: (f64, f64),
    convex: bool,
    aperture: &'a ApertureSampler<'a>,
}

impl<'a> BandTriangles<'a> {
    pub(crate) fn new(
        ctx: &GhostContext<'_>,
        bounds: &GhostBounds,
        n: usize,
        light: &GhostLight,
        band: &BandRef<'_>,
        aperture: &'a ApertureSampler<'a>,
        grid: &'a GridTrace,
    ) -> Self {
        let frame = ctx.frame;
        let airy = 1.22 * band.lambda_nm * 1e-6 * ctx.f_number;
        let rgb = band.rgb;
        BandTriangles {
            grid,
            frame,
            px_area: frame.pixel_area_mm2(),
            feather: feather_width(bounds, n, &frame),
            min_area: std::f64::consts::PI * airy * airy,
            airy,
            half_cell: 0.5 * grid.cell_area() * light.theta.cos(),
            irradiance: light.irradiance,
            rgb,
            lum: 0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64,
            sin_cos_phi: light.phi.sin_cos(),
            convex: aperture.is_convex(),
            aperture,
        }
    }

    /// Where vertex `k` landed (sensor mm, the lens's frame: the grid is traced with the light
    /// in the y–z plane; the lens frame is that turned by φ).
    #[inline]
    pub(crate) fn sensor(&self, k: usize) -> [f64; 2] {
        let (sphi, cphi) = self.sin_cos_phi;
        let [x, y] = self.grid.sensor[k].map(f64::from);
        [x * cphi - y * sphi, x * sphi + y * cphi]
    }

    /// Vertex `k`'s stop crossing in the lens's frame, where the aperture's shape is fixed.
    #[inline]
    pub(crate) fn stop_uv(&self, k: usize) -> [f32; 2] {
        let (sphi, cphi) = self.sin_cos_phi;
        let (s32, c32) = (sphi as f32, cphi as f32);
        let [u, v] = self.grid.stop_uv[k];
        [u * c32 - v * s32, u * s32 + v * c32]
    }

    /// The flux a triangle with these corners' weights carries (luminance-weighted).
    #[inline]
    pub(crate) fn flux(&self, tri: [usize; 3]) -> f64 {
        let w_mean = tri.iter().map(|&k| self.grid.weight[k] as f64).sum::<f64>() / 3.0;
        self.half_cell * self.irradiance * w_mean * self.lum
    }

    /// Irradiance (image units per pixel²) of unit weight spread over `area` mm².
    #[inline]
    pub(crate) fn irradiance_over(&self, area: f64) -> f64 {
        self.half_cell / area * self.irradiance * self.px_area
    }

    #[inline]
    pub(crate) fn to_pixel(&self, q: [f64; 2]) -> [f32; 2] {
        self.frame.to_pixel(q[0], q[1])
    }

    /// True when a convex aperture holds the stop point `uv` by half a feather.
    #[inline]
    pub(crate) fn inside_aperture(&self, uv: [f32; 2]) -> bool {
        self.convex && self.aperture.signed_distance(uv[0], uv[1]) <= -0.5 * self.feather
    }

    /// Adds grid triangle `tri` to `mesh` (wholly open, or on an edge) and counts it and its
    /// flux in `stats`; nothing when it adds nothing (a ray stopped, wholly clipped, not
    /// finite).
    pub(crate) fn push(&self, tri: [usize; 3], mesh: &mut GhostMesh, stats: &mut GhostStats) {
        if let Some(flux) = self.triangle(tri, mesh) {
            stats.flux += flux;
            stats.triangles += 1;
        }
    }

    /// [`BandTriangles::push`] without the counting: the triangle's flux, or `None`.
    fn triangle(&self, tri: [usize; 3], mesh: &mut GhostMesh) -> Option<f64> {
        let g = self.grid;
        let feather = self.feather;
        if !tri.iter().all(|&k| g.completed[k]) {
            return None;
        }
        // Fully clipped triangles add nothing.
        if tri.iter().all(|&k| g.max_rel[k] > 1.0 + feather) {
            return None;
        }
        let mut p = tri.map(|k| self.sensor(k));
        let area = 0.5
            * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
                .abs();
        if !area.is_finite() {
            return None;
        }
        let c = [
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ];
        let area = if area >= self.min_area {
            area
        } else if area > 0.0 {
            // Grow about the centroid to the diffraction limit.
            let s = (self.min_area / area).sqrt();
            for q in &mut p {
                *q = [c[0] + (q[0] - c[0]) * s, c[1] + (q[1] - c[1]) * s];
            }
            self.min_area
        } else {
            // Degenerate: a small triangle of area 2·airy² at the point.
            let r = self.airy;
            p = [[c[0] - r, c[1] - r], [c[0] + r, c[1] - r], [c[0], c[1] + r]];
            2.0 * r * r
        };
        let irr = self.irradiance_over(area) as f32;
        let pixels = p.map(|q| self.to_pixel(q));
        let rgb = self.rgb;
        let colour = |k: usize| {
            let e = irr * g.weight[k];
            [rgb[0] * e, rgb[1] * e, rgb[2] * e]
        };
        // Inside the clip radius, and (for a convex opening) inside the aperture, by half a
        // feather at every corner — so everywhere inside.
        let radius_open = tri.iter().all(|&k| g.max_rel[k] <= 1.0 - 0.5 * feather);
        let aperture_open = tri.iter().all(|&k| self.inside_aperture(self.stop_uv(k)));
        if radius_open && aperture_open {
            mesh.open.push(pixels, tri.map(colour));
        } else {
            let flag = if aperture_open { 0.0 } else { 1.0 };
            mesh.edge.push(
                pixels,
                tri.map(|k| {
                    let [r, gr, b] = colour(k);
                    let [u, v] = self.stop_uv(k);
                    [r, gr, b, u, v, g.max_rel[k], feather, flag]
                }),
            );
        }
        Some(self.flux(tri))
    }
}

/// Rasterizes `mesh` (made by [`mesh_ghost`] for a frame of `img`'s size) into `img`: the open
/// triangles at their interpolated irradiance, the edge ones feathered at the clip radius
/// and, where flagged, at `aperture`'s outline. Triangles of at least [`SAMPLED_MIN_AREA`]
/// pixels² are point-sampled.
pub fn rasterize_ghost_mesh(img: &mut HdrImage, mesh: &GhostMesh, aperture: &Aperture) {
    rasterize_ghost_mesh_into(&mut img.pixels, img.width, mesh, aperture);
}

/// [`rasterize_ghost_mesh`] into a row-major pixel buffer `width` pixels wide.
pub fn rasterize_ghost_mesh_into(
    pixels: &mut [[f32; 3]],
    width: usize,
    mesh: &GhostMesh,
    aperture: &Aperture,
) {
    let coverage = Coverage::Sampled {
        min_area: SAMPLED_MIN_AREA,
    };
    rasterize_into(
        pixels,
        width,
        &mesh.open.positions,
        &mesh.open.attrs,
        &mesh.open.triangles,
        coverage,
        |a: &OpenAttrs| *a,
    );
    // The circle (the usual case) is evaluated inline in f32: its distance to the edge is
    // exact to 1e-7 of the stop's radius, against a feather of at least 1e-4; measured on
    // the Nikon zoom's default frame, 10–15% faster than through the general sampler. Its
    // rows are split too: the pixels outside it are skipped and those wholly inside it take
    // the open shade (`EdgeShader::split_row`).
    if matches!(aperture, Aperture::Circular) {
        let shader = EdgeShader {
            circle: true,
            aperture: |u: f32, v: f32, feather: f32| {
                smoothstep(0.5 * feather, -0.5 * feather, (u * u + v * v).sqrt() - 1.0)
            },
        };
        rasterize_edges(pixels, width, &mesh.edge, coverage, &shader);
    } else {
        let sampler = aperture.sampler();
        let shader = EdgeShader {
            circle: false,
            aperture: |u, v, feather| sampler.transmission_soft(u, v, feather),
        };
        rasterize_edges(pixels, width, &mesh.edge, coverage, &shader);
    }
    // Made for the circular stop only (`super::fringe`).
    if !mesh.fringe.is_empty() {
        let fringe = &mesh.fringe;
        rasterize_shaded_into(
            pixels,
            width,
            &fringe.positions,
            &fringe.attrs,
            &fringe.triangles,
            coverage,
            &FringeShader {
                tables: &mesh.fringe_tables,
            },
        );
    }
}

/// Rasterizes edge triangles with `shader`.
fn rasterize_edges<A: Fn(f32, f32, f32) -> f32 + Sync>(
    pixels: &mut [[f32; 3]],
    width: usize,
    mesh: &Mesh<8>,
    coverage: Coverage,
    shader: &EdgeShader<A>,
) {
    rasterize_shaded_into(
        pixels,
        width,
        &mesh.positions,
        &mesh.attrs,
        &mesh.triangles,
        coverage,
        shader,
    );
}

/// The shade of an edge triangle ([`EdgeAttrs`]): the irradiance times the clip radius's
/// feathered step and, where flagged, `aperture(u, v, feather)` (the aperture's soft
/// transmission; `circle` when it is the unit circle's).
struct EdgeShader<A> {
    circle: bool,
    aperture: A,
}

/// Margin (in relative radius at the stop) by which [`EdgeShader::split_row`] keeps pixels
/// near a transition on the full shade: far more than the f32 rounding of the interpolated
/// attributes along a tile's row (a few 1e-6).
pub(crate) const SPLIT_MARGIN: f64 = 1e-4;

impl<A: Fn(f32, f32, f32) -> f32 + Sync> Shader<8> for EdgeShader<A> {
    type Rows = ();

    #[inline]
    fn shade(&self, a: &EdgeAttrs) -> [f32; 3] {
        let feather = a[6];
        let mut t = smoothstep(1.0 + 0.5 * feather, 1.0 - 0.5 * feather, a[5]);
        if a[7] > 0.5 {
            t *= (self.aperture)(a[3], a[4], feather);
        }
        [a[0] * t, a[1] * t, a[2] * t]
    }

    /// The clip radius `a[5]` is affine along the row, and for the circle `u² + v²` is a
    /// quadratic: the pixels where the step is 0 (the radius beyond `1 + feather/2`) are
    /// left out, those where every factor is 1 (within `1 − feather/2`) take the open shade,
    /// each up to [`SPLIT_MARGIN`]. An aperture other than the circle keeps the full shade on
    /// flagged triangles.
    fn split_row(&self, _: &(), a: &EdgeAttrs, step: &EdgeAttrs, n: usize) -> RowSplit {
        let f = f64::from(a[6]);
        let (outer, inner) = (1.0 + 0.5 * f + SPLIT_MARGIN, 1.0 - 0.5 * f - SPLIT_MARGIN);
        let last = n.saturating_sub(1) as f64;
        let (mut lit, mut core) =
            linear_split(f64::from(a[5]), f64::from(step[5]), [outer, inner], n);
        if a[7] > 0.5 && lit.start < lit.end {
            if self.circle {
                let (u, v) = (f64::from(a[3]), f64::from(a[4]));
                let (du, dv) = (f64::from(step[3]), f64::from(step[4]));
                let (ue, ve) = (u + last * du, v + last * dv);
                let (r0, r1) = (u * u + v * v, ue * ue + ve * ve);
                // r² = |(u, v) + k (du, dv)|² is convex along the row: within the inner
                // circle at both ends, it is everywhere (the usual case on the clip's edge).
                if r0.max(r1) >= inner * inner || inner <= 0.0 {
                    let (lit_a, core_a) = parabola_split(u, v, du, dv, [outer, inner], n);
                    lit = intersect(lit, lit_a);
                    core = if inner > 0.0 {
                        intersect(core, core_a)
                    } else {
                        0..0
                    };
                }
            } else {
                core = 0..0;
            }
        }
        RowSplit { lit, core }
    }

    #[inline]
    fn shade_core(&self, a: &EdgeAttrs) -> [f32; 3] {
        [a[0], a[1], a[2]]
    }
}

/// The pixels `k` in `[0, n)` with `m0 + k·dm < outer`, and those with `m0 + k·dm < inner`.
pub(crate) fn linear_split(
    m0: f64,
    dm: f64,
    [outer, inner]: [f64; 2],
    n: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    linear_split_with(m0, dm, 1.0 / dm, [outer, inner], n)
}

/// [`linear_split`] with `1 / dm` given (`id`): a triangle's rows share it.
#[inline]
pub(crate) fn linear_split_with(
    m0: f64,
    dm: f64,
    id: f64,
    [outer, inner]: [f64; 2],
    n: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let below = |t: f64| if m0 < t { 0..n } else { 0..0 };
    if dm == 0.0 || dm.is_nan() {
        return (below(outer), below(inner));
    }
    let m1 = m0 + n.saturating_sub(1) as f64 * dm;
    if m0.max(m1) < inner {
        return (0..n, 0..n);
    }
    if m0.min(m1) >= outer {
        return (0..0, 0..0);
    }
    let (xl, xc) = ((outer - m0) * id, (inner - m0) * id);
    if dm > 0.0 {
        (0..ceil_index(xl, n), 0..ceil_index(xc, n))
    } else {
        (after_index(xl, n)..n, after_index(xc, n)..n)
    }
}

/// The pixels `k` in `[0, n)` with `|(u, v) + k (du, dv)| < outer`, and those with it
/// `< inner`.
pub(crate) fn parabola_split(
    u: f64,
    v: f64,
    du: f64,
    dv: f64,
    [outer, inner]: [f64; 2],
    n: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let below = parabola_below(u, v, du, dv, n);
    (below(outer * outer), below(inner * inner))
}

/// The pixels `k` in `[0, n)` with `|(u, v) + k (du, dv)|² < t`, as a function of `t` (one
/// square root a call: where only one of [`parabola_split`]'s two bounds is wanted).
#[inline]
pub(crate) fn parabola_below(
    u: f64,
    v: f64,
    du: f64,
    dv: f64,
    n: usize,
) -> impl Fn(f64) -> std::ops::Range<usize> {
    parabola_below_with(u, v, du, dv, StepNorm::new(du, dv), n)
}

/// `|(du, dv)|²` and its reciprocal (0 where it is 0), for [`parabola_below_with`]: a
/// triangle's rows share their step.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct StepNorm {
    a2: f64,
    ia: f64,
}

impl StepNorm {
    #[inline]
    pub(crate) fn new(du: f64, dv: f64) -> StepNorm {
        let a2 = du * du + dv * dv;
        StepNorm {
            a2,
            ia: if a2 > 0.0 { 1.0 / a2 } else { 0.0 },
        }
    }
}

/// [`parabola_below`] with the step's [`StepNorm`] given.
#[inline]
pub(crate) fn parabola_below_with(
    u: f64,
    v: f64,
    du: f64,
    dv: f64,
    StepNorm { a2, ia }: StepNorm,
    n: usize,
) -> impl Fn(f64) -> std::ops::Range<usize> {
    // Least at kc, where it is q0 (the row's own |(u, v)|² where it does not move).
    let (ia, kc, q0) = if a2 > 0.0 {
        let kc = -(u * du + v * dv) * ia;
        let (pu, pv) = (u + kc * du, v + kc * dv);
        (ia, kc, pu * pu + pv * pv)
    } else {
        (0.0, 0.0, u * u + v * v)
    };
    move |t: f64| {
        if a2 > 0.0 {
            // Below t for |k − kc| < √((t − q0)/a2).
            if t.is_nan() || q0.is_nan() || t <= q0 {
                return 0..0;
            }
            let h = ((t - q0) * ia).sqrt();
            after_index(kc - h, n)..ceil_index(kc + h, n)
        } else if q0 < t {
            // The row does not move across the stop.
            0..n
        } else {
            0..0
        }
    }
}

/// `⌈x⌉` clamped to `[0, n]` (0 for NaN), without a libm call or a conversion to an
/// unsigned integer (each a sequence of instructions on baseline x86-64; a row's split makes
/// several of these). For `n ≤ 2⁵¹` (a row of a tile: [`round_index`]).
#[inline]
fn ceil_index(x: f64, n: usize) -> usize {
    debug_assert!(n <= 1 << 51, "a row of {n} pixels");
    let x = x.clamp(0.0, n as f64);
    if x.is_nan() {
        return 0;
    }
    let (r, rf) = round_index(x);
    (r + usize::from(rf < x)).min(n)
}

/// `⌊x⌋ + 1`, the first index above `x`, clamped to `[0, n]` (`n` for NaN: with
/// [`ceil_index`]'s 0, a NaN bound gives an empty range). For `n ≤ 2⁵¹`, as
/// [`ceil_index`].
#[inline]
fn after_index(x: f64, n: usize) -> usize {
    debug_assert!(n <= 1 << 51, "a row of {n} pixels");
    if x < 0.0 {
        return 0;
    }
    let x = x.min(n as f64);
    if x.is_nan() {
        return n;
    }
    let (r, rf) = round_index(x);
    (r - usize::from(rf > x) + 1).min(n)
}

/// `x` (in `[0, 2⁵¹]`) rounded to the nearest integer, as an index and as an f64: adding 2⁵²
/// leaves the integer in the low bits of the sum.
#[inline]
fn round_index(x: f64) -> (usize, f64) {
    const SHIFT: f64 = 4_503_599_627_370_496.0;
    let r = x + SHIFT;
    ((r.to_bits() & ((1 << 52) - 1)) as usize, r - SHIFT)
}

pub(crate) fn intersect(
    a: std::ops::Range<usize>,
    b: std::ops::Range<usize>,
) -> std::ops::Range<usize> {
    a.start.max(b.start)..a.end.min(b.end)
}

/// Width of the ghost's edge (the clip at relative radius 1 and the aperture's outline), in
/// units of the relative radius at the stop: [`EDGE_PIXELS`] pixels of `frame` on the ghost's
/// image (whose radius on the sensor, relative radius 1, is half its sensor extent), but never
/// wider than two grid cells (`2/(n − 1)`, where the interpolated radius stops resolving the
/// edge) nor narrower than 1e-4.
pub fn feather_width(bounds: &GhostBounds, n: usize, frame: &Frame) -> f32 {
    let s = &bounds.sensor;
    let radius_px = 0.5 * (s.x1 - s.x0).max(s.y1 - s.y0) / frame.pixel_mm();
    let cells = 2.0 / (n.max(2) - 1) as f64;
    let f = if radius_px > 0.0 {
        (EDGE_PIXELS / radius_px).min(cells)
    } else {
        cells
    };
    f.max(1e-4) as f32
}

/// Triangles of at least this many pixels² (of the frame drawn into) are point-sampled
/// ([`Coverage::Sampled`]); smaller ones — folds, caustics, diffraction-sized triangles —
/// keep exact coverage. Measured at light 10°, 30°, default quality: the Heliar's error at
/// 1920 × 1080 is 1.863% exact and 1.861% for 2, 4 and 16 px²; the Nikon zoom's at 960 × 540
/// is 2.00% exact, 2.08% at 4 px² and 2.01% at 16 px² — below 16, sampling small folded
/// triangles starts to cost accuracy.
pub const SAMPLED_MIN_AREA: f32 = 16.0;

/// Width of a ghost's edge on the image, in pixels of the frame it is drawn into.
pub const EDGE_PIXELS: f64 = 1.0;

/// 0 at `edge0`, 1 at `edge1`, smooth (C¹) in between; works for either order of the edges.
pub(crate) fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn row_indices_are_ceilings_and_floors_clamped_to_the_row() {
        let xs = [
            -3.0,
            -0.5,
            -0.0,
            0.0,
            1e-300,
            0.25,
            0.5,
            0.75,
            1.0,
            1.5,
            2.5,
            3.5,
            7.999_999_9,
            8.0,
            8.000_001,
            63.5,
            64.0,
            64.5,
            1e9,
            1e30,
            f64::INFINITY,
            f64::NAN,
        ];
        for n in [0, 1, 2, 8, 64, 100] {
            for &x in &xs {
                let nf = n as f64;
                let ceil = if x.is_nan() {
                    0
                } else {
                    x.clamp(0.0, nf).ceil() as usize
                };
                let after = if x.is_nan() {
                    n
                } else if x < 0.0 {
                    0
                } else {
                    (x.min(nf).floor() as usize + 1).min(n)
                };
                assert_eq!(ceil_index(x, n), ceil, "ceil {x} {n}");
                assert_eq!(after_index(x, n), after, "after {x} {n}");
            }
        }
    }

    /// The attributes of pixel `k` as the rasterizer steps them along a row.
    fn stepped(a: &EdgeAttrs, step: &EdgeAttrs, k: usize) -> EdgeAttrs {
        let mut x = *a;
        for _ in 0..k {
            for (v, d) in x.iter_mut().zip(step) {
                *v += d;
            }
        }
        x
    }

    fn check_split<A: Fn(f32, f32, f32) -> f32 + Sync>(
        shader: &EdgeShader<A>,
        a: EdgeAttrs,
        step: EdgeAttrs,
        n: usize,
        tight: bool,
    ) -> Result<(), TestCaseError> {
        let split = shader.split_row(&(), &a, &step, n);
        prop_assert!(split.lit.end <= n && split.core.end <= n);
        let mut zeros_inside = 0;
        for k in 0..n {
            let x = stepped(&a, &step, k);
            let full = shader.shade(&x);
            if !split.lit.contains(&k) {
                prop_assert_eq!(full, [0.0; 3], "pixel {} outside {:?}", k, split.lit);
            } else if split.core.contains(&k) {
                prop_assert_eq!(full, shader.shade_core(&x), "pixel {} in core", k);
            } else if full == [0.0; 3] {
                zeros_inside += 1;
            }
        }
        // The circle's split is tight: at most a pixel or two of zeros kept at each end
        // (the margin).
        prop_assert!(
            !tight || zeros_inside <= 4,
            "{} zero pixels left in {:?}",
            zeros_inside,
            split
        );
        Ok(())
    }

    proptest! {
        /// Pixels left out of a row's lit span shade to zero, and those in its core shade
        /// exactly as the open triangle, for the circle and for a general aperture.
        #[test]
        fn an_edge_rows_split_keeps_every_pixel_s_shade(
            rgb in prop::array::uniform3(0.1_f32..10.0),
            u in -1.5_f32..1.5, v in -1.5_f32..1.5,
            du in -0.05_f32..0.05, dv in -0.05_f32..0.05,
            m in 0.8_f32..1.2, dm in -0.02_f32..0.02,
            feather in 1e-4_f32..0.05,
            flag in prop::bool::ANY,
            n in 1_usize..64,
        ) {
            let flag = if flag { 1.0 } else { 0.0 };
            let a = [rgb[0], rgb[1], rgb[2], u, v, m, feather, flag];
            let step = [0.01, -0.02, 0.0, du, dv, dm, 0.0, 0.0];
            let circle = EdgeShader {
                circle: true,
                aperture: |u: f32, v: f32, f: f32| {
                    smoothstep(0.5 * f, -0.5 * f, (u * u + v * v).sqrt() - 1.0)
                },
            };
            check_split(&circle, a, step, n, true)?;
            let iris = Aperture::Iris { blades: 6, rotation_rad: 0.2, roundness: 0.2 };
            let sampler = iris.sampler();
            let general = EdgeShader {
                circle: false,
                aperture: |u, v, f| sampler.transmission_soft(u, v, f),
            };
            check_split(&general, a, step, n, flag == 0.0)?;
        }
    }
}
