//! From a ghost's traced band to mesh triangles: [`trace_band`] traces the band's grid,
//! [`grid_triangles`] lists the grid's cells as triangles, and [`BandTriangles`] makes each
//! into a mesh triangle — its flux `E · A_entrance · cos θ` over its area on the sensor, grown to
//! the Airy disc `π (1.22 λ N)²` where it collapses (a caustic), wholly open or on an edge
//! feathered over one drawn pixel ([`edge_feathers`]).

use crate::aperture::ApertureSampler;
use crate::frame::Frame;
use crate::trace::Sequence;

use super::bounds::GhostBounds;
use super::context::{BandRef, GhostContext, GhostLight, GhostStats};
use super::enumerate::GhostPath;
use super::grid::{GridTrace, trace_grid, trace_grid_f64};
use super::mesh::{EdgeAttrs, GhostMesh};
use super::render::edge_shade;
use super::splat::{splat_area, splat_triangle};

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
    /// The widest feather an edge may have ([`max_feather`]).
    pub max_feather: f32,
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
    /// Small triangles drawn as box splats ([`super::splat`]) rather than meshed.
    splat: bool,
}

impl<'a> BandTriangles<'a> {
    pub(crate) fn new(
        ctx: &GhostContext<'_>,
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
            max_feather: max_feather(n),
            min_area: std::f64::consts::PI * airy * airy,
            airy,
            half_cell: 0.5 * grid.cell_area() * light.theta.cos(),
            irradiance: light.irradiance,
            rgb,
            lum: 0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64,
            sin_cos_phi: light.phi.sin_cos(),
            convex: aperture.is_convex(),
            aperture,
            splat: false,
        }
    }

    /// The same, drawing its small triangles as box splats ([`super::splat`]) when `splat`.
    pub(crate) fn splatted(self, splat: bool) -> Self {
        BandTriangles { splat, ..self }
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

    /// True when a convex aperture holds the stop point `uv` by half of `feather`.
    #[inline]
    pub(crate) fn inside_aperture(&self, uv: [f32; 2], feather: f32) -> bool {
        self.convex && self.aperture.signed_distance(uv[0], uv[1]) <= -0.5 * feather
    }

    /// The feathers of a triangle with sensor corners `p` (mm, the lens's frame), clip radii
    /// `r` and stop crossings `uv` ([`edge_feathers`] at this frame's pixel size).
    #[inline]
    pub(crate) fn feathers(
        &self,
        p: [[f64; 2]; 3],
        r: [f64; 3],
        uv: [[f64; 2]; 3],
    ) -> EdgeFeathers {
        edge_feathers(p, r, uv, self.frame.pixel_mm(), f64::from(self.max_feather))
    }

    /// True when the aperture is open (its soft transmission over `feather` 1) all over the
    /// triangle of stop crossings `uv` (within the disc about its centroid through its
    /// farthest corner).
    #[inline]
    fn open_around(&self, uv: [[f32; 2]; 3], feather: f32) -> bool {
        let c = [
            (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0,
            (uv[0][1] + uv[1][1] + uv[2][1]) / 3.0,
        ];
        let radius = uv
            .iter()
            .map(|p| len_f32(p[0] - c[0], p[1] - c[1]))
            .fold(0.0_f32, f32::max);
        self.aperture.uniform_around(c[0], c[1], radius, feather) == Some(1.0)
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
        if !tri.iter().all(|&k| g.completed[k]) {
            return None;
        }
        // Fully clipped triangles add nothing (first against the widest feather, which needs
        // no corners on the sensor).
        let r = tri.map(|k| f64::from(g.max_rel[k]));
        if r.iter().all(|&x| x > 1.0 + f64::from(self.max_feather)) {
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
        // The feathers from the corners where the rays landed: growing a caustic's triangle
        // to the Airy disc spreads its light, but does not move what part of its cell passes
        // (so an edge's share of the cell is the same at any scale of the lens).
        let uv = tri.map(|k| self.stop_uv(k));
        let feathers = self.feathers(p, r, uv.map(|q| q.map(f64::from)));
        if r.iter().all(|&x| x > 1.0 + f64::from(feathers.clip)) {
            return None;
        }
        let c = [
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ];
        let area = if area >= self.min_area {
            area
        } else if area > 0.0 {
            grow_to_area(
                &mut p,
                c,
                area,
                self.min_area,
                SLIVER_REACH_AIRY * self.airy,
            );
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
        // Inside the clip radius, and (for a convex opening) inside the aperture, by half the
        // wider feather at every corner — so everywhere inside; for a mask, open all around
        // the stop crossings' triangle (the disc about its centroid through its corners).
        let wide = feathers.widest();
        let radius_open = r.iter().all(|&x| x <= 1.0 - 0.5 * f64::from(wide));
        let aperture_open = if self.convex {
            uv.iter().all(|&q| self.inside_aperture(q, wide))
        } else {
            radius_open && self.open_around(uv, wide)
        };
        let splat = if self.splat {
            splat_area(&pixels)
        } else {
            None
        };
        if radius_open && aperture_open {
            let attrs = tri.map(colour);
            match splat {
                Some(area) => {
                    splat_triangle(&pixels, &attrs, area, |a| *a, &mut mesh.boxes);
                }
                None => mesh.open.push(pixels, attrs),
            }
        } else {
            let flag = if aperture_open { 0.0 } else { 1.0 };
            let feather = feathers.drawn(radius_open, aperture_open);
            let attrs: [EdgeAttrs; 3] = std::array::from_fn(|c| {
                let [red, green, blue] = colour(tri[c]);
                let [u, v] = uv[c];
                [red, green, blue, u, v, r[c] as f32, feather, flag]
            });
            match splat {
                Some(area) => {
                    let aperture = |u, v, f| self.aperture.transmission_soft(u, v, f);
                    let shade = |a: &EdgeAttrs| edge_shade(a, &aperture);
                    splat_triangle(&pixels, &attrs, area, shade, &mut mesh.boxes);
                }
                None => mesh.edge.push(pixels, attrs),
            }
        }
        Some(self.flux(tri))
    }
}

/// A triangle's two feathers, in the relative units their edges are drawn in: the clip
/// radius's (relative radius 1) and the aperture outline's (normalised stop units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeFeathers {
    pub clip: f32,
    pub stop: f32,
}

impl EdgeFeathers {
    /// The wider of the two: the margin within which a triangle's corners must be inside
    /// both edges for it to be drawn wholly open.
    pub fn widest(self) -> f32 {
        self.clip.max(self.stop)
    }

    /// The feather a triangle on an edge is drawn with (one attribute serves both edges):
    /// the aperture's where the clip radius is open across it, the clip's where the aperture
    /// is, else the narrower, so neither edge is drawn wider than [`EDGE_PIXELS`].
    pub fn drawn(self, radius_open: bool, aperture_open: bool) -> f32 {
        if radius_open {
            self.stop
        } else if aperture_open {
            self.clip
        } else {
            self.clip.min(self.stop)
        }
    }
}

/// How far (in Airy radii) a triangle grown to the Airy disc about its centroid may reach:
/// beyond it, the triangle is a sliver and is widened across its longest edge instead.
const SLIVER_REACH_AIRY: f64 = 4.0;

/// The longest edge (as a share of the reach, [`SLIVER_REACH_AIRY`] Airy radii: so one Airy
/// radius) below which a triangle grown to the Airy disc is drawn as a compact triangle of the
/// disc's area at its centroid (the degenerate triangle's shape), whatever its own shape. A
/// ghost focused to a few µm (at f/64: the Zhong Yi 135 mm's 8-7, 1 × 0.2 µm… its cells
/// 40 × 10 µm) has triangles whose shape is set by the last digits of their corners: scaled
/// about the centroid, each reached up to 4 Airy radii in a direction the rounding chose; as
/// slivers widened across their longest edge, needles 290 mm long. Such a triangle's light is
/// spread by diffraction, not by its shape: f32 against f64 went from relative RMSE 9.5e-2
/// to 3.3e-5 on that lens (`flarebench stability`, f/64, θ 5°).
const COMPACT_BELOW_REACH: f64 = 0.25;

/// Grows triangle `p` (centroid `c`, area `area` > 0) to `min_area`, keeping its centroid:
/// replaced by a compact triangle of `min_area` when its longest edge is below
/// [`COMPACT_BELOW_REACH`] × `reach` or widening it across would reach beyond `reach` (a
/// triangle below the Airy disc's resolution); else scaled about the centroid while that keeps
/// its longest edge within `reach`, else (a sliver: a fold or a grazing ray stretches one
/// corner far off) widened across its longest edge. Scaling a sliver by the same factor would stretch it to many times its length — a
/// needle of the right area that crosses the frame, whose exact coverage the rasterizer's
/// f32 arithmetic cannot resolve.
fn grow_to_area(p: &mut [[f64; 2]; 3], c: [f64; 2], area: f64, min_area: f64, reach: f64) {
    let s = (min_area / area).sqrt();
    let edge = |a: usize, b: usize| len(p[b][0] - p[a][0], p[b][1] - p[a][1]);
    let (a, b, apex) = [(0, 1, 2), (1, 2, 0), (2, 0, 1)]
        .into_iter()
        .max_by(|x, y| edge(x.0, x.1).total_cmp(&edge(y.0, y.1)))
        .expect("three edges");
    let len = edge(a, b);
    // Below an Airy radius, or so short that widening it across would take it beyond `reach`,
    // a triangle's shape is finer than the Airy disc resolves: the disc's area at its centroid.
    let grow = 2.0 * (min_area - area) / len;
    if len < COMPACT_BELOW_REACH * reach || grow > reach {
        // Base 2r, height 2r, its centroid at `c`.
        let r = (0.5 * min_area).sqrt();
        let (below, above) = (c[1] - 2.0 * r / 3.0, c[1] + 4.0 * r / 3.0);
        *p = [[c[0] - r, below], [c[0] + r, below], [c[0], above]];
        return;
    }
    if s * len <= reach || len <= 0.0 {
        for q in p.iter_mut() {
            *q = [c[0] + (q[0] - c[0]) * s, c[1] + (q[1] - c[1]) * s];
        }
        return;
    }
    // The unit normal of the longest edge towards the apex; the apex moves out along it until
    // the height is 2·min_area/len, and every corner back by a third of that (the centroid
    // stays).
    let u = [(p[b][0] - p[a][0]) / len, (p[b][1] - p[a][1]) / len];
    let mut n = [-u[1], u[0]];
    let to_apex = [p[apex][0] - p[a][0], p[apex][1] - p[a][1]];
    if to_apex[0] * n[0] + to_apex[1] * n[1] < 0.0 {
        n = [-n[0], -n[1]];
    }
    p[apex] = [p[apex][0] + n[0] * grow, p[apex][1] + n[1] * grow];
    for q in p.iter_mut() {
        *q = [q[0] - n[0] * grow / 3.0, q[1] - n[1] * grow / 3.0];
    }
}

/// The feathers of a triangle with corners `p` on the sensor (mm), clip radii `r` and stop
/// crossings `uv` (normalised), drawn on pixels `pixel_mm` wide: each the change of its value
/// over [`EDGE_PIXELS`] pixels along its own gradient — the clip radius's, and for the
/// aperture that of `|(u, v)|` at the centroid's crossing (the outline's normal on the
/// circle) — so each edge is one drawn pixel wide however fast or slowly its value moves.
/// `p` are the corners where the rays landed, before a caustic's triangle is grown to the Airy
/// disc. Each is at most its value's change over [`MAX_FEATHER_CELLS`] of the grid (twice its
/// spread over the triangle's corners: where a caustic folds the cell to a point, the edge
/// is not blurred over more of the entrance than that) and `max`, and at least
/// [`MIN_FEATHER`].
pub fn edge_feathers(
    p: [[f64; 2]; 3],
    r: [f64; 3],
    uv: [[f64; 2]; 3],
    pixel_mm: f64,
    max: f64,
) -> EdgeFeathers {
    let clamp = |slope: f64, values: [f64; 3]| -> f32 {
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let cap = (MAX_FEATHER_CELLS * (hi - lo)).min(max).max(MIN_FEATHER);
        let f = slope * pixel_mm * EDGE_PIXELS;
        if f.is_finite() {
            f.clamp(MIN_FEATHER, cap) as f32
        } else {
            cap as f32
        }
    };
    let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1]];
    let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1]];
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    // The gradient of the linear interpolant of `v` over the triangle (per mm).
    let gradient = |v: [f64; 3]| -> [f64; 2] {
        let (d1, d2) = (v[1] - v[0], v[2] - v[0]);
        [
            (d1 * e2[1] - d2 * e1[1]) / det,
            (d2 * e1[0] - d1 * e2[0]) / det,
        ]
    };
    let gr = gradient(r);
    let gu = gradient(uv.map(|q| q[0]));
    let gv = gradient(uv.map(|q| q[1]));
    let cu = (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0;
    let cv = (uv[0][1] + uv[1][1] + uv[2][1]) / 3.0;
    let cr = len(cu, cv);
    // The stop's value across the outline: the crossing along the centroid's direction (its
    // radius, where that is too near the centre to have a direction).
    let (stop_slope, radial) = if cr > 1e-9 {
        let (nu, nv) = (cu / cr, cv / cr);
        (
            len(nu * gu[0] + nv * gv[0], nu * gu[1] + nv * gv[1]),
            uv.map(|q| nu * q[0] + nv * q[1]),
        )
    } else {
        (
            len(gu[0], gu[1]).max(len(gv[0], gv[1])),
            uv.map(|q| len(q[0], q[1])),
        )
    };
    EdgeFeathers {
        clip: clamp(len(gr[0], gr[1]), r),
        stop: clamp(stop_slope, radial),
    }
}

/// The length of `(x, y)`, as a plain square root: `hypot` guards against overflow and
/// underflow the values here never reach (millimetres, normalised units, their gradients; an
/// infinite or NaN gradient stays so) and costs several times more (13% of the reference's
/// time went to it).
#[inline]
pub(crate) fn len(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// [`len`] in f32 (stop crossings, normalised units).
#[inline]
pub(crate) fn len_f32(x: f32, y: f32) -> f32 {
    (x * x + y * y).sqrt()
}

/// The most grid cells an edge's feather may span, measured by its value's change across the
/// triangle (see [`edge_feathers`]).
pub const MAX_FEATHER_CELLS: f64 = 2.0;

/// The widest feather of an `n × n` grid's triangles, in relative units: two grid cells
/// (`2/(n − 1)`), beyond which the interpolated radius stops resolving the edge.
pub fn max_feather(n: usize) -> f32 {
    (2.0 / (n.max(2) - 1) as f64) as f32
}

/// The narrowest feather (relative units): an edge whose value hardly moves is drawn this
/// sharp rather than sharper than f32 attributes resolve.
pub const MIN_FEATHER: f64 = 1e-4;

/// Width of a ghost's edge on the image, in pixels of the frame it is drawn into.
pub const EDGE_PIXELS: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// A right triangle 0.1 mm a side at the origin, drawn on pixels 0.01 mm wide.
    const P: [[f64; 2]; 3] = [[0.0, 0.0], [0.1, 0.0], [0.0, 0.1]];
    const PIXEL_MM: f64 = 0.01;

    fn area_and_centroid(p: &[[f64; 2]; 3]) -> (f64, [f64; 2]) {
        let a = 0.5
            * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
                .abs();
        let c = [
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ];
        (a, c)
    }

    fn extent(p: &[[f64; 2]; 3]) -> f64 {
        let e = |a: usize, b: usize| (p[b][0] - p[a][0]).hypot(p[b][1] - p[a][1]);
        e(0, 1).max(e(1, 2)).max(e(2, 0))
    }

    #[test]
    fn a_small_triangle_grows_about_its_centroid_and_a_sliver_only_across() {
        let (airy, min_area) = (1e-3, std::f64::consts::PI * 1e-6);
        // A compact triangle of a third of the Airy disc's area, its longest edge over an Airy
        // radius: scaled, shape kept.
        let mut p = [[1.0, 2.0], [1.0015, 2.0], [1.0, 2.0015]];
        let (a0, c0) = area_and_centroid(&p);
        grow_to_area(&mut p, c0, a0, min_area, SLIVER_REACH_AIRY * airy);
        let (a, c) = area_and_centroid(&p);
        assert!((a / min_area - 1.0).abs() < 1e-9, "{a}");
        assert!((c[0] - c0[0]).abs() < 1e-12 && (c[1] - c0[1]).abs() < 1e-12);
        assert!(((p[1][0] - p[0][0]) / (p[2][1] - p[0][1]) - 1.0).abs() < 1e-9);
        // A sliver 5 mm long and 1e-9 mm thick (a corner stretched off by a grazing ray):
        // scaled alike it would reach 5 mm × 56 = 280 mm, across any frame; widened, it keeps
        // its length and reaches the Airy disc's area.
        let mut p = [[0.0, 0.0], [5.0, 0.0], [2.0, 1e-9]];
        let (a0, c0) = area_and_centroid(&p);
        grow_to_area(&mut p, c0, a0, min_area, SLIVER_REACH_AIRY * airy);
        let (a, c) = area_and_centroid(&p);
        assert!((a / min_area - 1.0).abs() < 1e-9, "{a}");
        assert!((c[0] - c0[0]).abs() < 1e-12 && (c[1] - c0[1]).abs() < 1e-12);
        assert!(extent(&p) < 5.0 + 1e-6, "{p:?}");
    }

    #[test]
    fn a_triangle_below_the_airy_disc_grows_to_the_same_compact_triangle_whatever_its_shape() {
        // The Zhong Yi 135 mm's ghost 8-7 at f/64: focused to about 1 × 0.2 µm, its cells
        // 40 × 10 µm (landing 11.84 mm off axis, where f32 resolves 1 µm), Airy radius 43 µm.
        let (airy, min_area) = (0.043, std::f64::consts::PI * 0.043 * 0.043);
        let reach = SLIVER_REACH_AIRY * airy;
        let thin = [[0.0, 11.84], [4e-5, 11.84], [0.0, 11.84001]];
        // The same cell with one corner moved by f32's rounding: its longest edge turns.
        let turned = [[0.0, 11.84], [4e-5, 11.840001], [1e-6, 11.84001]];
        let mut grown = Vec::new();
        for mut p in [thin, turned] {
            let (a0, c0) = area_and_centroid(&p);
            grow_to_area(&mut p, c0, a0, min_area, reach);
            let (a, c) = area_and_centroid(&p);
            assert!((a / min_area - 1.0).abs() < 1e-9, "{a}");
            assert!((c[0] - c0[0]).abs() < 1e-9 && (c[1] - c0[1]).abs() < 1e-9);
            // Widened across its 40 µm edge it was a needle 2·min_area/len = 290 mm long.
            assert!(extent(&p) <= reach, "{p:?}");
            grown.push(p);
        }
        // One shape about (almost) one centroid: the rounding moves nothing but the centroid.
        for k in 0..3 {
            for i in 0..2 {
                assert!((grown[0][k][i] - grown[1][k][i]).abs() < 1e-6, "{grown:?}");
            }
        }
    }

    #[test]
    fn each_edge_is_one_drawn_pixel_wide_along_its_own_gradient() {
        // Clip radius rising 0.3 per mm along (3, 4)/5: 0.003 over a pixel.
        let r = P.map(|q| 0.99 + 0.3 * (0.6 * q[0] + 0.8 * q[1]));
        // Stop crossings about (0.9, 0) moving 2 per mm in u along y, 0.5 per mm in v along
        // x: at the centroid's crossing (on the u axis) |(u, v)| moves as u, 0.02 a pixel.
        let uv = P.map(|q| [0.9 + 2.0 * q[1], 0.5 * q[0] - 0.5 * 0.1 / 3.0]);
        let f = edge_feathers(P, r, uv, PIXEL_MM, 0.1);
        assert!((f64::from(f.clip) - 0.003).abs() < 1e-7, "{f:?}");
        assert!((f64::from(f.stop) - 0.02).abs() < 1e-6, "{f:?}");
        assert_eq!(f.widest(), f.stop);
        assert_eq!(f.drawn(true, false), f.stop);
        assert_eq!(f.drawn(false, true), f.clip);
        assert_eq!(f.drawn(false, false), f.clip);
    }

    #[test]
    fn feathers_stay_between_their_floor_and_two_cells() {
        // A radius that does not move: the floor, however wide the triangle.
        let flat = edge_feathers(P, [1.0; 3], [[0.5, 0.0]; 3], PIXEL_MM, 0.04);
        assert_eq!(flat.clip, MIN_FEATHER as f32);
        assert_eq!(flat.stop, MIN_FEATHER as f32);
        // One moving by 1 over a pixel: two cells of a 51² grid.
        let steep = edge_feathers(P, [0.0, 10.0, 0.0], [[0.0; 2]; 3], PIXEL_MM, 0.04);
        assert_eq!(steep.clip, 0.04);
        assert_eq!(max_feather(51), 0.04);
        // A triangle of no area: as wide as its values' change over two cells allows (the
        // stop's crossing does not move: the floor).
        let line = [[0.0, 0.0], [0.1, 0.0], [0.2, 0.0]];
        let d = edge_feathers(line, [0.9, 1.0, 1.1], [[0.0; 2]; 3], PIXEL_MM, 0.04);
        assert_eq!((d.clip, d.stop), (0.04, MIN_FEATHER as f32));
    }

    #[test]
    fn a_caustic_s_edge_spans_at_most_two_cells_of_its_grid() {
        // Folded to a thousandth of a pixel: a pixel of it is far more than the cell's
        // change, 0.001 in the radius and 0.002 in the crossing.
        let tiny = P.map(|q| q.map(|x| x * 1e-4));
        let r = [0.9995, 1.0005, 1.0];
        let uv = [[0.99, 0.0], [0.991, 0.0], [0.992, 0.0]];
        let f = edge_feathers(tiny, r, uv, PIXEL_MM, 0.04);
        assert!((f64::from(f.clip) - 0.002).abs() < 1e-9, "{f:?}");
        assert!((f64::from(f.stop) - 0.004).abs() < 1e-9, "{f:?}");
    }
}
