//! Ghosts (Hullin et al. 2011): light reflected twice (or, on request, four times) inside the
//! lens, traced as sparse ray grids from the entrance plane to the sensor.
//!
//! - [`enumerate`]: every two-reflection path, and every four-reflection path.
//! - [`grid`]: a grid of parallel rays traced along one ghost path at one wavelength.
//! - [`bounds`]: where on the entrance plane the rays that reach the sensor start, per ghost
//!   and incidence angle (approximate paraxial and precise traced modes).
//! - [`four_bound`]: the traced upper bound on four-reflection paths' energy shares (one
//!   trace per three-reflection prefix) that culls them before their bounds are traced.
//! - [`context`]: what the renderer works from (lens context, light, wavelength bands) and
//!   what it reports (`GhostStats`).
//! - [`triangles`]: a traced band's grid cells as triangles with energy-conserving
//!   intensities, the diffraction-limit caustic bound, the feathered edge's width.
//! - [`mesh`]: ghost triangles ready to rasterize (open, edge and fringed meshes, box
//!   splats).
//! - [`splat`]: a splatted ghost's sub-pixel triangles drawn as boxes, where
//!   exact coverage would cost most of its time.
//! - `row_split`: where along a rasterized row a shade is zero or open, shared by the
//!   shaders.
//! - [`render`]: one ghost into an HDR image — mesh its bands, rasterize with the aperture's
//!   shape at the stop and feathered clipping.
//! - [`fringe`]: all of a dispersive ghost's bands as one mesh, its colour fringes shaded per
//!   pixel; [`fringe_table`]: the ghost's colour over the dispersion coordinate it looks up.
//! - [`sink`]: the seam between making a frame's triangles and drawing them — the levels,
//!   the [`sink::GhostSink`] the CPU rasterizer and the GPU backend both implement, and a
//!   recording ([`sink::FrameMeshes`]).
//! - [`monte_carlo`]: the independent reference — stratified random rays traced in f64 along a
//!   ghost path and splatted where they land (energy, centroid, second moments, image, and
//!   their error bars), sharing neither the grids, the meshing nor the rasterizer.
//! - [`table`]: bounds precomputed over a range of angles, stored and interpolated.
//! - [`olf_table`]: OpenLensFlare's precomputed bounds (`<ghostList>` XML) as such a table,
//!   checked against the lens, energies traced.

pub mod bounds;
pub mod context;
pub mod enumerate;
pub mod four_bound;
pub mod fringe;
pub mod fringe_table;
pub mod grid;
pub mod mesh;
pub mod monte_carlo;
pub mod olf_table;
pub mod render;
mod row_split;
pub mod sink;
pub mod splat;
pub mod table;
pub mod triangles;

pub use bounds::{GhostBounds, Rect};
pub use enumerate::{
    GhostPath, ParseGhostPathError, ReflectionOrder, enumerate_four_reflection_ghosts,
    enumerate_ghosts, enumerate_ghosts_of_order, four_reflection_count, reflecting_surfaces,
};
pub use four_bound::FourReflectionBounds;
pub use grid::{GridTrace, PointTrace, ProbedGrid, trace_grid, trace_grid_f64, trace_grid_probed};
