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
//! The image is the photograph's orientation ([`crate::frame`]). The renderer's inputs are in
//! [`super::context`], the triangles in [`super::triangles`] and [`super::mesh`], the row splits
//! the shaders share in [`super::row_split`].

use crate::aperture::{Aperture, ApertureSampler};
use crate::image::HdrImage;
use crate::raster::boxes::splat_boxes_into;
use crate::raster::{Coverage, RowSplit, Shader, rasterize_into, rasterize_shaded_into};

use super::context::{BandRef, GhostContext, GhostGrid, GhostStats};
use super::fringe::FringeShader;
use super::grid::GridTrace;
use super::mesh::{EdgeAttrs, GhostMesh, Mesh, OpenAttrs, SAMPLED_MIN_AREA};
use super::row_split::{
    APERTURE_SPLIT_MARGIN, SPLIT_MARGIN, aperture_split, intersect, linear_split, parabola_split,
    smoothstep,
};
use super::triangles::{BandTriangles, grid_triangles, trace_band};

/// Reusable buffers for [`render_ghost`].
#[derive(Debug, Default)]
pub struct GhostScratch {
    grid: GridTrace,
    mesh: GhostMesh,
}

/// Renders `ghost` into `img`, one trace per band: [`mesh_ghost`], then
/// [`rasterize_ghost_mesh`].
pub fn render_ghost(
    ctx: &GhostContext<'_>,
    ghost: &GhostGrid<'_>,
    bands: &[BandRef<'_>],
    scratch: &mut GhostScratch,
    img: &mut HdrImage,
) -> GhostStats {
    scratch.mesh.clear();
    let stats = mesh_ghost(ctx, ghost, bands, &mut scratch.grid, &mut scratch.mesh);
    rasterize_ghost_mesh(img, &scratch.mesh, ctx.aperture);
    stats
}

/// Traces `ghost` (its `n × n` grid over `bounds.entrance`) at each band and appends its
/// triangles, in pixels of `ctx.frame`, to `mesh`.
pub fn mesh_ghost(
    ctx: &GhostContext<'_>,
    ghost: &GhostGrid<'_>,
    bands: &[BandRef<'_>],
    grid: &mut GridTrace,
    mesh: &mut GhostMesh,
) -> GhostStats {
    mesh_or_splat_ghost(ctx, ghost, bands, grid, mesh, false)
}

/// [`mesh_ghost`], its triangles that exact coverage would draw (small and compact:
/// [`super::splat::splat_area`]) added to `mesh.boxes` as box splats instead
/// ([`super::splat`]).
pub fn splat_ghost(
    ctx: &GhostContext<'_>,
    ghost: &GhostGrid<'_>,
    bands: &[BandRef<'_>],
    grid: &mut GridTrace,
    mesh: &mut GhostMesh,
) -> GhostStats {
    mesh_or_splat_ghost(ctx, ghost, bands, grid, mesh, true)
}

fn mesh_or_splat_ghost(
    ctx: &GhostContext<'_>,
    ghost: &GhostGrid<'_>,
    bands: &[BandRef<'_>],
    grid: &mut GridTrace,
    mesh: &mut GhostMesh,
    splat: bool,
) -> GhostStats {
    let GhostGrid {
        path,
        bounds,
        n,
        ref light,
    } = *ghost;
    let mut stats = GhostStats::default();
    let aperture = ctx.aperture.sampler();
    for band in bands {
        if !trace_band(ctx, path, bounds, n, light, band, grid) {
            return stats;
        }
        stats.rays += n * n;
        let emit = BandTriangles::new(ctx, n, light, band, &aperture, grid).splatted(splat);
        for tri in grid_triangles(n) {
            emit.push(tri, mesh, &mut stats);
        }
    }
    stats
}

/// Rasterizes `mesh` (made by [`mesh_ghost`] for a frame of `img`'s size) into `img`: the open
/// triangles at their interpolated irradiance, the edge ones feathered at the clip radius
/// and, where flagged, at `aperture`'s outline, and the box splats. Triangles of at least [`SAMPLED_MIN_AREA`]
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
    rasterize_ghost_mesh_with(pixels, width, mesh, aperture, coverage);
}

/// [`rasterize_ghost_mesh_into`] with a choice of coverage (exact for a plugin's mesh, as the
/// plugin ABI promises).
pub fn rasterize_ghost_mesh_with(
    pixels: &mut [[f32; 3]],
    width: usize,
    mesh: &GhostMesh,
    aperture: &Aperture,
    coverage: Coverage,
) {
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
            sampler: None,
            aperture: |u: f32, v: f32, feather: f32| {
                smoothstep(0.5 * feather, -0.5 * feather, (u * u + v * v).sqrt() - 1.0)
            },
        };
        rasterize_edges(pixels, width, &mesh.edge, coverage, &shader);
    } else {
        let sampler = aperture.sampler();
        let shader = EdgeShader {
            circle: false,
            sampler: Some(sampler),
            aperture: |u, v, feather| sampler.transmission_soft(u, v, feather),
        };
        rasterize_edges(pixels, width, &mesh.edge, coverage, &shader);
    }
    splat_boxes_into(pixels, width, &mesh.boxes);
    // The circle's outline analytically, another aperture's stepped over τ (`super::fringe`).
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
                aperture: aperture.sampler(),
            },
        );
    }
}

/// The shade of an edge triangle's point with attributes `a` ([`EdgeAttrs`]): its irradiance
/// times the clip radius's feathered step and, where flagged, `aperture(u, v, feather)` (the
/// aperture's soft transmission). The rasterizer's per pixel, a splat's per box
/// ([`super::splat`]).
#[inline]
pub(crate) fn edge_shade(a: &EdgeAttrs, aperture: &impl Fn(f32, f32, f32) -> f32) -> [f32; 3] {
    let feather = a[6];
    let mut t = smoothstep(1.0 + 0.5 * feather, 1.0 - 0.5 * feather, a[5]);
    if a[7] > 0.5 {
        t *= aperture(a[3], a[4], feather);
    }
    [a[0] * t, a[1] * t, a[2] * t]
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
/// transmission; `circle` when it is the unit circle's, else `sampler`'s).
struct EdgeShader<'a, A> {
    circle: bool,
    sampler: Option<ApertureSampler<'a>>,
    aperture: A,
}

impl<A: Fn(f32, f32, f32) -> f32 + Sync> Shader<8> for EdgeShader<'_, A> {
    type Rows = ();

    #[inline]
    fn shade(&self, a: &EdgeAttrs) -> [f32; 3] {
        edge_shade(a, &self.aperture)
    }

    /// The clip radius `a[5]` is affine along the row, and for the circle `u² + v²` is a
    /// quadratic: the pixels where the step is 0 (the radius beyond `1 + feather/2`) are
    /// left out, those where every factor is 1 (within `1 − feather/2`) take the open shade,
    /// each up to [`SPLIT_MARGIN`]. On a flagged triangle, another aperture's transmission is
    /// traced along rows of `APERTURE_SPLIT_MIN_PIXELS` or more ([`aperture_split`]): the
    /// pixels at the row's ends where it is 0 are left out, and the run where it is 1 takes
    /// the open shade; shorter rows keep the full shade.
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
                match self.sampler {
                    Some(sampler) => {
                        let uv = [f64::from(a[3]), f64::from(a[4])];
                        let step_uv = [f64::from(step[3]), f64::from(step[4])];
                        (lit, core) = aperture_split(
                            &sampler,
                            uv,
                            step_uv,
                            a[6],
                            APERTURE_SPLIT_MARGIN,
                            lit,
                            core,
                        );
                    }
                    _ => core = 0..0,
                }
            }
        }
        RowSplit { lit, core }
    }

    #[inline]
    fn shade_core(&self, a: &EdgeAttrs) -> [f32; 3] {
        [a[0], a[1], a[2]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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
                sampler: None,
                aperture: |u: f32, v: f32, f: f32| {
                    smoothstep(0.5 * f, -0.5 * f, (u * u + v * v).sqrt() - 1.0)
                },
            };
            check_split(&circle, a, step, n, true)?;
            let iris = Aperture::Iris { blades: 6, rotation_rad: 0.2, roundness: 0.2 };
            let sampler = iris.sampler();
            let general = EdgeShader {
                circle: false,
                sampler: Some(sampler),
                aperture: |u, v, f| sampler.transmission_soft(u, v, f),
            };
            check_split(&general, a, step, n, flag == 0.0)?;
            let mask = star_mask();
            let sampler = mask.sampler();
            let masked = EdgeShader {
                circle: false,
                sampler: Some(sampler),
                aperture: |u, v, f| sampler.transmission_soft(u, v, f),
            };
            check_split(&masked, a, step, n, flag == 0.0)?;
        }
    }

    /// A binary mask: a five-pointed star's opening (not convex), 128 texels a side.
    fn star_mask() -> Aperture {
        Aperture::Mask(crate::aperture::tests::mask_of(128, |u, v| {
            u.hypot(v) < 0.6 + 0.3 * (5.0 * v.atan2(u)).cos()
        }))
    }

    /// On a long row of a flagged triangle, an iris's or a mask's transmission is traced, not
    /// taken pixel by pixel: a row crossing the opening from outside is dark up to near the
    /// outline and takes the open shade well inside it, with the same image.
    #[test]
    fn a_long_row_is_split_by_an_iris_or_a_mask() {
        let iris = Aperture::Iris {
            blades: 6,
            rotation_rad: 0.0,
            roundness: 0.0,
        };
        for aperture in [iris, star_mask()] {
            let sampler = aperture.sampler();
            let shader = EdgeShader {
                circle: false,
                sampler: Some(sampler),
                aperture: |u, v, f| sampler.transmission_soft(u, v, f),
            };
            // From u = 1.2 to 0 along v = 0.01, 0.01 a pixel; clip radius well open.
            let n = 121;
            let a = [1.0, 2.0, 3.0, 1.2, 0.01, 0.2, 0.004, 1.0];
            let step = [0.0, 0.0, 0.0, -0.01, 0.0, 0.0, 0.0, 0.0];
            let split = shader.split_row(&(), &a, &step, n);
            // The outline near u = 1 (the iris's blade tip) or 0.9 (the star's point): dark
            // before u = 1, open after u = 0.6.
            assert!(split.lit.start >= 20, "{split:?}");
            assert!(split.core.start <= 60 && split.core.end == n, "{split:?}");
            check_split(&shader, a, step, n, false).unwrap();
        }
    }
}
