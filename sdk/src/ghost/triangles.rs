//! From a ghost's traced band to mesh triangles: [`trace_band`] traces the band's grid,
//! [`grid_triangles`] lists the grid's cells as triangles, and [`BandTriangles`] makes each
//! into a mesh triangle — its flux `E · A_entrance · cos θ` over its area on the sensor, grown to
//! the Airy disc `π (1.22 λ N)²` where it collapses (a caustic), wholly open or on an edge
//! feathered over [`feather_width`].

use crate::aperture::ApertureSampler;
use crate::frame::Frame;
use crate::trace::Sequence;

use super::bounds::GhostBounds;
use super::context::{BandRef, GhostContext, GhostLight, GhostStats};
use super::enumerate::GhostPath;
use super::grid::{GridTrace, trace_grid, trace_grid_f64};
use super::mesh::GhostMesh;

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

    /// True when the aperture is open (its soft transmission 1) all over the triangle of stop
    /// crossings `uv` (within the disc about its centroid through its farthest corner).
    #[inline]
    fn open_around(&self, uv: [[f32; 2]; 3]) -> bool {
        let c = [
            (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0,
            (uv[0][1] + uv[1][1] + uv[2][1]) / 3.0,
        ];
        let radius = uv
            .iter()
            .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
            .fold(0.0_f32, f32::max);
        self.aperture
            .uniform_around(c[0], c[1], radius, self.feather)
            == Some(1.0)
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
        // feather at every corner — so everywhere inside; for a mask, open all around the
        // stop crossings' triangle (the disc about its centroid through its corners).
        let radius_open = tri.iter().all(|&k| g.max_rel[k] <= 1.0 - 0.5 * feather);
        let aperture_open = if self.convex {
            tri.iter().all(|&k| self.inside_aperture(self.stop_uv(k)))
        } else {
            radius_open && self.open_around(tri.map(|k| self.stop_uv(k)))
        };
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

/// Width of a ghost's edge on the image, in pixels of the frame it is drawn into.
pub const EDGE_PIXELS: f64 = 1.0;
