//! What can happen in the editor (`Action`, produced by keys, the mouse or finished file
//! operations) and what `App::update` asks the outside world to do (`Effect`).

use std::path::PathBuf;

use flarebench_sdk::LensSystem;

/// A cursor movement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    Up,
    Down,
    Left,
    Right,
    /// Next / previous cell, wrapping to the next / previous row (Tab, Shift-Tab).
    Next,
    Prev,
    Top,
    Bottom,
}

/// One thing the user (or a finished effect) did. Independent of the terminal library.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    Move(Move),
    /// Select a screen position (mouse click): column, row in terminal cells.
    Click {
        x: u16,
        y: u16,
    },
    /// The terminal's size changed (columns, rows).
    Resize {
        width: u16,
        height: u16,
    },
    /// Start editing the selected cell with its current value (Enter, F2).
    Edit,
    /// Start editing the selected cell with this character replacing its value.
    EditWith(char),
    /// Text editing (cell editor, command line, prompts for paths).
    Input(char),
    Backspace,
    Delete,
    CaretLeft,
    CaretRight,
    CaretHome,
    CaretEnd,
    ClearInput,
    /// Glass completion: next (+1) / previous (−1) catalogue name.
    Complete(isize),
    /// Accept the edited text (Enter); with a move, accept and move on (Tab).
    Commit,
    CommitAndMove(Move),
    /// Abandon the cell edit, command or prompt (Esc).
    Cancel,
    /// Rows: insert a flat air surface above / below, duplicate, delete, move up / down.
    InsertAbove,
    InsertBelow,
    Duplicate,
    DeleteRow,
    MoveRowUp,
    MoveRowDown,
    Undo,
    Redo,
    /// Show or hide the key map.
    Help,
    /// Select the next / previous ghost in the ghost list (wrapping; past the ends: none).
    NextGhost,
    PrevGhost,
    /// Save to the current file (asks for a path when there is none).
    Save,
    /// Ask for a path to save to / a lens to open.
    SaveAs,
    Open,
    /// Open the `:` command line.
    Command,
    /// Quit (asks when there are unsaved changes); `ForceQuit` does not ask.
    Quit,
    ForceQuit,
    /// Open the viewer window beside the editor (`W`, `:window`).
    Window,
    /// From the window: a surface clicked in the lens view.
    SelectRow(usize),
    /// From the window: a ghost clicked in the flare view.
    SelectGhost(flarebench_sdk::ghost::GhostPath),
    /// From the window: a note for the status line (e.g. why it could not open).
    Note(String),
    /// An answer to a one-key prompt (`y`, `n`, `r`, `d`, `s`, …).
    Answer(char),
    /// Results of effects.
    Saved(Result<PathBuf, String>),
    Opened(Result<Box<Opened>, String>),
    /// An effect failed (message shown).
    Failed(String),
}

/// A lens read by an [`Effect::Open`], with a recovery file if one was found beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct Opened {
    /// Where saves go (`None`: not an XML file of ours; save asks for a path).
    pub path: Option<PathBuf>,
    /// Shown in the title bar.
    pub label: String,
    pub system: LensSystem,
    /// The recovery file for this lens (written after every committed edit).
    pub recovery_path: PathBuf,
    /// What an existing recovery file holds, when it differs from the lens.
    pub recovered: Option<LensSystem>,
    pub warnings: Vec<String>,
}

/// What `App::update` asks the runner to do; the runner feeds results back as actions.
#[derive(Clone, Debug, PartialEq)]
pub enum Effect {
    /// Save `system` as our XML at `path`, atomically; then remove `recovery`.
    Save {
        path: PathBuf,
        system: Box<LensSystem>,
        recovery: PathBuf,
    },
    /// Write the recovery file (atomically) after a committed edit.
    WriteRecovery {
        path: PathBuf,
        system: Box<LensSystem>,
    },
    /// Remove a recovery file (changes discarded or saved).
    RemoveRecovery(PathBuf),
    /// Read a lens (path or bundled name).
    Open(String),
    /// Open the viewer window (the runner knows whether there can be one).
    OpenWindow,
    /// Leave the editor.
    Quit,
}
