//! The seam between making a frame's ghost triangles and drawing them: a backend-neutral
//! frame description.
//!
//! A frame's ghosts are drawn into **levels**: coarse copies of the frame (a
//! [`CoarseGrid`] of factor > 1, each later added to the output by bilinear upsampling,
//! [`crate::image::upsample_levels_into`]) and, last, the full-resolution frame itself
//! (factor 1). Each level receives a stream of [`GhostMesh`]es in pixels of its own frame
//! ([`Frame::coarse`]), every triangle carrying what its shading needs (irradiance, stop
//! crossing, relative radius, feather, fringe tables). A renderer hands the meshes to a
//! [`GhostSink`] in draw order; the CPU rasterizer, the GPU backend and a recording
//! ([`FrameMeshes`], used to draw one frame with both and compare) are sinks alike.
//!
//! The levels are independent and each level's result is a sum, so a sink may draw its
//! meshes in any order; the CPU's is the order given, which makes its image independent of
//! the number of threads.

use crate::aperture::Aperture;
use crate::frame::Frame;
use crate::image::{CoarseGrid, HdrImage, upsample_levels_into};

use crate::raster::Coverage;

use super::mesh::{GhostMesh, SAMPLED_MIN_AREA};
use super::render::rasterize_ghost_mesh_with;

/// The shape of a frame's drawing: the output frame, its levels and the aperture the edge
/// triangles are shaded with.
#[derive(Clone, Copy, Debug)]
pub struct FrameLevels<'a> {
    /// The output frame.
    pub frame: Frame,
    /// The levels: the coarse ones (factor > 1) first, in increasing factor, then at most one
    /// of factor 1, the output frame itself.
    pub grids: &'a [CoarseGrid],
    /// The stop's opening the edge triangles are shaded with.
    pub aperture: &'a Aperture,
    /// How triangles cover pixels: [`FrameLevels::GHOSTS`] for the ghost renderer's meshes,
    /// [`Coverage::Exact`] for a plugin's (the ABI promises exact coverage).
    pub coverage: Coverage,
}

impl FrameLevels<'_> {
    /// The ghost renderer's coverage: triangles of at least [`SAMPLED_MIN_AREA`] pixels²
    /// point-sampled, smaller ones exact.
    pub const GHOSTS: Coverage = Coverage::Sampled {
        min_area: SAMPLED_MIN_AREA,
    };

    /// The frame of level `level` (pixels the meshes of that level are in).
    pub fn level_frame(&self, level: usize) -> Frame {
        self.frame.coarse(&self.grids[level])
    }

    /// The number of coarse levels (those before the full-resolution one).
    pub fn coarse_count(&self) -> usize {
        self.grids.iter().take_while(|g| g.factor > 1).count()
    }
}

/// Where a frame's ghost meshes go (module docs).
pub trait GhostSink {
    /// Starts a frame of these levels.
    fn begin(&mut self, levels: FrameLevels<'_>);
    /// Draws `mesh` (in pixels of level `level`'s frame) into that level.
    fn draw(&mut self, level: usize, mesh: &GhostMesh);
    /// Ends the frame: every mesh has been given.
    fn finish(&mut self);
}

/// A frame's description kept as data: its levels and every mesh given, in order.
#[derive(Clone, Debug, Default)]
pub struct FrameMeshes {
    /// The output frame, the levels' grids and the aperture, once a frame has begun.
    pub levels: Option<(Frame, Vec<CoarseGrid>, Aperture, Coverage)>,
    /// `(level, mesh)` in the order they were drawn.
    pub meshes: Vec<(usize, GhostMesh)>,
}

impl GhostSink for FrameMeshes {
    fn begin(&mut self, levels: FrameLevels<'_>) {
        self.levels = Some((
            levels.frame,
            levels.grids.to_vec(),
            levels.aperture.clone(),
            levels.coverage,
        ));
        self.meshes.clear();
    }

    fn draw(&mut self, level: usize, mesh: &GhostMesh) {
        self.meshes.push((level, mesh.clone()));
    }

    fn finish(&mut self) {}
}

impl FrameMeshes {
    /// Draws the recorded frame with the CPU rasterizer (each coarse level into its coarse
    /// image, added by bilinear upsampling, then the full-resolution meshes) and returns the
    /// image; black when nothing was recorded.
    pub fn draw_cpu(&self) -> HdrImage {
        let Some(levels) = self.frame_levels() else {
            return HdrImage::new(0, 0);
        };
        let frame = levels.frame;
        let mut out = HdrImage::new(frame.width, frame.height);
        let coarse_count = levels.coarse_count();
        let mut coarse: Vec<HdrImage> = levels.grids[..coarse_count]
            .iter()
            .map(|g| HdrImage::new(g.width, g.height))
            .collect();
        for (level, mesh) in &self.meshes {
            if let Some(img) = coarse.get_mut(*level) {
                let w = img.width;
                rasterize_ghost_mesh_with(
                    &mut img.pixels,
                    w,
                    mesh,
                    levels.aperture,
                    levels.coverage,
                );
            }
        }
        let pairs: Vec<(&HdrImage, &CoarseGrid)> = coarse.iter().zip(levels.grids).collect();
        upsample_levels_into(
            &mut out.pixels,
            frame.width,
            &pairs,
            crate::image::Blend::Add,
        );
        for (level, mesh) in &self.meshes {
            if *level >= coarse_count {
                rasterize_ghost_mesh_with(
                    &mut out.pixels,
                    frame.width,
                    mesh,
                    levels.aperture,
                    levels.coverage,
                );
            }
        }
        out
    }

    /// The recorded frame's levels.
    pub fn frame_levels(&self) -> Option<FrameLevels<'_>> {
        self.levels
            .as_ref()
            .map(|(frame, grids, aperture, coverage)| FrameLevels {
                frame: *frame,
                grids,
                aperture,
                coverage: *coverage,
            })
    }

    /// Replays the recorded frame into `sink`.
    pub fn replay(&self, sink: &mut dyn GhostSink) {
        if let Some(levels) = self.frame_levels() {
            sink.begin(levels);
            for (level, mesh) in &self.meshes {
                sink.draw(*level, mesh);
            }
            sink.finish();
        }
    }

    /// Triangles recorded, all kinds.
    pub fn triangles(&self) -> usize {
        self.meshes
            .iter()
            .map(|(_, m)| m.open.len() + m.edge.len() + m.fringe.len())
            .sum()
    }
}
