//! Ghost triangles ready to rasterize: [`Mesh`] (triangles with their corners' attributes),
//! the attribute layouts of wholly open and edge triangles, [`GhostMesh`] (the open, edge and
//! fringed meshes and box splats of any number of ghosts) and the coverage they are rasterized with
//! ([`SAMPLED_MIN_AREA`]).

use super::fringe_table::FringeTable;
use crate::raster::boxes::Boxes;

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
/// aperture's outline), which are feathered per pixel ([`rasterize_ghost_mesh`](super::render::rasterize_ghost_mesh)).
#[derive(Clone, Debug, Default)]
pub struct GhostMesh {
    pub open: Mesh<3>,
    pub edge: Mesh<8>,
    /// Triangles standing for all of a ghost's bands at once, their colour fringes shaded per
    /// pixel ([`super::fringe`]), and the ghosts' colour tables they index.
    pub fringe: Mesh<12>,
    pub fringe_tables: Vec<FringeTable>,
    /// Box splats: the small triangles of ghosts drawn by splatting ([`super::splat`]).
    pub boxes: Boxes,
}

impl GhostMesh {
    /// An empty mesh with room for `open` wholly open and `edge` edge triangles.
    pub fn with_capacity(open: usize, edge: usize) -> Self {
        GhostMesh {
            open: Mesh::with_capacity(open),
            edge: Mesh::with_capacity(edge),
            fringe: Mesh::default(),
            fringe_tables: Vec::new(),
            boxes: Boxes::default(),
        }
    }

    /// Removes every triangle, keeping the buffers.
    pub fn clear(&mut self) {
        self.open.clear();
        self.edge.clear();
        self.fringe.clear();
        self.fringe_tables.clear();
        self.boxes.clear();
    }

    /// Makes room for the triangles of `meshes`.
    pub fn reserve<'a>(&mut self, meshes: impl Iterator<Item = &'a GhostMesh> + Clone) {
        let open: usize = meshes.clone().map(|m| m.open.len()).sum();
        let edge: usize = meshes.clone().map(|m| m.edge.len()).sum();
        let fringe: usize = meshes.clone().map(|m| m.fringe.len()).sum();
        let boxes: usize = meshes.map(|m| m.boxes.len()).sum();
        self.open.reserve(open);
        self.edge.reserve(edge);
        self.fringe.reserve(fringe);
        self.boxes.reserve(boxes);
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
        self.boxes.append(&other.boxes);
    }

    /// Moves the box splats into the open mesh, each as two triangles of its irradiance: a
    /// rasterizer with exact coverage draws them as `crate::raster::boxes` does (up to f32
    /// rounding), which is how the GPU backend draws boxes.
    pub fn boxes_into_open(&mut self) {
        self.open.reserve(2 * self.boxes.len());
        for (r, c) in self.boxes.rects.iter().zip(&self.boxes.irradiance) {
            let [x0, y0, x1, y1] = *r;
            self.open.push([[x0, y0], [x1, y0], [x1, y1]], [*c; 3]);
            self.open.push([[x0, y0], [x1, y1], [x0, y1]], [*c; 3]);
        }
        self.boxes.clear();
    }

    /// True without triangles or boxes.
    pub fn is_empty(&self) -> bool {
        self.open.is_empty()
            && self.edge.is_empty()
            && self.fringe.is_empty()
            && self.boxes.is_empty()
    }
}

/// Triangles of at least this many pixels² (of the frame drawn into) are point-sampled
/// ([`Coverage::Sampled`](crate::raster::Coverage::Sampled)); smaller ones — folds, caustics, diffraction-sized triangles —
/// keep exact coverage. Measured 2026-11-24 (light 10°, 30°, default quality; figures in
/// docs/performance.md): the Heliar's error at 1920 × 1080 is 1.863% exact and 1.861% for
/// 2, 4 and 16 px²; the Nikon zoom's at 960 × 540 is 2.00% exact, 2.08% at 4 px² and 2.01%
/// at 16 px², where sampling small folded triangles starts to cost accuracy.
pub const SAMPLED_MIN_AREA: f32 = 16.0;
