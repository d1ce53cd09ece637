//! The messages between the terminal editor and the viewer window running beside it in the
//! same process (`flarebench edit --window`). Lens changes travel separately, through
//! `Document::subscribe`; these carry selections and notes. No UI types: both sides build
//! without the other's feature.

use flarebench_sdk::ghost::GhostPath;

/// What the window tells the editor.
#[derive(Clone, Debug, PartialEq)]
pub enum ToEditor {
    /// A surface clicked in the lens view: select its row.
    SelectRow(usize),
    /// A ghost clicked in the flare view: select it in the ghost list.
    SelectGhost(GhostPath),
    /// A note for the status line (e.g. why the window closed or could not open).
    Note(String),
}

/// What the editor tells the window.
#[derive(Clone, Debug, PartialEq)]
pub enum FromEditor {
    /// The editor's selected surface row.
    Row(Option<usize>),
    /// The ghost selected in the editor's ghost list.
    Ghost(Option<GhostPath>),
}
