//! Helpers shared by the tests that drive the viewer offscreen (`viewer.rs`,
//! `viewer_plugins.rs`).

use std::time::Duration;

use egui::Event;
use flarebench::viewer::Viewer;
use flarebench::viewer::offscreen::Offscreen;

/// How long the viewer may take to settle (lavapipe paints slowly).
pub const SETTLE: Duration = Duration::from_secs(240);

/// Passes until nothing is left to render; fails with the status line and any render failure.
pub fn settled(viewer: &mut Viewer, target: &mut Offscreen) {
    assert!(
        target.settle(viewer, SETTLE),
        "the viewer did not settle; status: {:?}, failure: {:?}",
        viewer.message(),
        viewer.render_failure()
    );
}

/// A key pressed and released in one pass.
pub fn key(k: egui::Key) -> Vec<Event> {
    [true, false]
        .map(|pressed| Event::Key {
            key: k,
            physical_key: None,
            pressed,
            repeat: false,
            modifiers: Default::default(),
        })
        .to_vec()
}
