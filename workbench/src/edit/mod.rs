//! `flarebench edit`: the terminal prescription editor (ratatui + crossterm), built as The Elm
//! Architecture: keys → `Action` → `App::update` → `Effect`s; drawing is a pure function.
//!
//! - `document`: the lens document with reversible edits, undo/redo and change subscription
//!   (independent of any UI, so a window can drive and observe it too)
//! - `cell`: columns, cell display, parsing and validation of typed values, the cell editor
//! - `action`, `keymap`: actions and effects; keys per mode and the key map
//! - `app`: the editor state and `update`
//! - `analysis`: paraxial data, lens outline, ray fans, ghosts
//! - `view`: drawing (table, header form, analysis panel, ghost list, side view, help)
//! - `files`: opening, atomic saving, the recovery file, running effects
//! - `runner`: the terminal event loop

pub mod action;
pub mod analysis;
pub mod app;
pub mod cell;
pub mod document;
pub mod files;
pub mod keymap;
pub mod runner;
pub mod view;

use std::collections::VecDeque;

use action::{Action, Effect};
use app::App;

/// Applies `action` and runs the effects it asks for, feeding their results back, until
/// nothing is left to do. True when the editor should quit.
pub fn dispatch(app: &mut App, action: Action) -> bool {
    let mut queue = VecDeque::from([action]);
    while let Some(a) = queue.pop_front() {
        for effect in app.update(a) {
            if effect == Effect::Quit {
                return true;
            }
            if let Some(next) = files::perform(&effect) {
                queue.push_back(next);
            }
        }
    }
    false
}
