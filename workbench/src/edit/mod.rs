//! `flarebench edit`: the terminal prescription editor (ratatui + crossterm), built as The Elm
//! Architecture: keys → `Action` → `App::update` → `Effect`s; drawing is a pure function.
//!
//! - `document` (re-exported from `crate::document`, built without the `tui` feature): the lens
//!   document with reversible edits, undo/redo and change subscription, driven and observed
//!   by the window too
//! - `cell`: columns, cell display, parsing and validation of typed values, the cell editor
//! - `action`, `keymap`: actions and effects; keys per mode and the key map
//! - `app`: the editor state and `update`
//! - `layout`: the screen areas, table rows and hit-testing, shared by `app` and `view`
//! - `analysis`: paraxial data, lens outline, ray fans, ghosts
//! - `view`: drawing (table, header form, analysis panel, ghost list, side view, help)
//! - `files`: opening, atomic saving, the recovery file, running effects
//! - `runner`: the terminal event loop

pub mod action;
pub mod analysis;
pub mod app;
pub mod cell;
/// The document model lives outside the editor (no terminal types): the window drives it too.
pub use crate::document;
pub mod files;
pub mod keymap;
pub mod layout;
pub mod runner;
pub mod view;

use std::collections::VecDeque;

use action::{Action, Effect};
use app::App;

/// Applies `action` and runs the effects it asks for, feeding their results back, until
/// nothing is left to do. True when the editor should quit.
pub fn dispatch(app: &mut App, action: Action) -> bool {
    dispatch_with(app, action, None)
}

/// [`dispatch`] with a window beside the editor: `OpenWindow` opens it through `host`, or
/// says why there is none.
pub fn dispatch_with(app: &mut App, action: Action, host: Option<&runner::WindowHost>) -> bool {
    let mut queue = VecDeque::from([action]);
    while let Some(a) = queue.pop_front() {
        for effect in app.update(a) {
            match effect {
                Effect::Quit => return true,
                Effect::OpenWindow => queue.push_back(match host {
                    Some(h) => match (h.open)() {
                        Ok(()) => Action::Note("window open".into()),
                        Err(e) => Action::Failed(format!("no window: {e}")),
                    },
                    None => Action::Failed(
                        "no window: this editor was started without one (no display, or a build \
                         without the `window` feature)"
                            .into(),
                    ),
                }),
                e => queue.extend(files::perform(&e)),
            }
        }
    }
    false
}
