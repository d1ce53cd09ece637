//! How a flare frame is drawn: the planner's options, the renderer's, and what the frame keeps
//! besides its image (the automatic exposure, the ghosts alone). The scene says what is drawn
//! ([`super::Scene`]); this says how, so a command, the bench and the viewer differ only here.

use flarebench_sdk::ghost::GhostPath;
use ghost_raytrace::ghosts::RenderOptions;
use ghost_raytrace::plan::PlanOptions;

/// How one frame is planned and drawn.
#[derive(Clone, Copy, Debug)]
pub struct Preset<'a> {
    /// The planner's options. Without lens tables of their own the plan uses the
    /// [`super::Flare`]'s, kept for the lens from frame to frame, when
    /// [`Preset::lens_tables`] asks for them.
    pub plan: PlanOptions<'a>,
    pub render: RenderOptions,
    /// Plan with the lens's interface tables kept by the `Flare` (built for a new lens).
    pub lens_tables: bool,
    /// Start each ghost's bounds search from the last frame's rectangles, when the last frame
    /// had as many lights (`PlanOptions::warm_start`).
    pub warm_start: bool,
    /// Draw this ghost alone (the plan is made as for all of them).
    pub solo: Option<GhostPath>,
    /// Find the automatic exposure ([`super::exposure`]).
    pub exposure: bool,
    /// Keep a copy of the ghosts' image before the starbursts are added (to compare with the
    /// reference, which holds ghosts only).
    pub keep_ghosts: bool,
}

impl<'a> Preset<'a> {
    /// `plan` and the default render options, nothing else asked for.
    pub fn new(plan: PlanOptions<'a>) -> Preset<'a> {
        Preset {
            plan,
            render: RenderOptions::default(),
            lens_tables: false,
            warm_start: false,
            solo: None,
            exposure: false,
            keep_ghosts: false,
        }
    }
}
