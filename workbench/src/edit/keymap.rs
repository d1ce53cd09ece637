//! Keys → actions, per editor mode, and the key map shown by `?` (also in `docs/editor.md`).

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use super::action::{Action, Move};

/// The input mode, as far as keys are concerned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyMode {
    /// Moving around the table.
    Normal,
    /// Editing a cell.
    Cell,
    /// Typing a `:` command or a path.
    Line,
    /// A one-key question (quit without saving? recover?).
    Prompt,
    /// The key map is shown.
    Help,
}

/// The key map: (keys, what they do), in the order shown.
pub const KEY_HELP: &[(&str, &str)] = &[
    ("↑ ↓ ← → / k j h l", "move the selection"),
    ("Tab / Shift-Tab", "next / previous cell"),
    ("g / G, Home / End", "first / last row"),
    ("Enter / F2", "edit the cell (digits start a new value)"),
    ("Esc", "cancel the edit, command or prompt"),
    ("Enter / Tab (editing)", "accept; Tab moves on"),
    ("Ctrl-n / Ctrl-p (editing)", "complete a glass name"),
    ("Ctrl-u (editing)", "clear the cell"),
    ("O / Insert, o", "insert a surface above / below"),
    ("y", "duplicate the surface"),
    ("d / Delete", "delete the surface"),
    ("K / J", "move the surface up / down"),
    ("u / Ctrl-z", "undo"),
    ("Ctrl-r / Ctrl-y", "redo"),
    ("] / [", "next / previous ghost"),
    ("W / :window", "open the viewer window beside the editor"),
    ("Ctrl-s / :w", "save"),
    (":w PATH / Ctrl-w", "save as"),
    (":e PATH / Ctrl-o", "open a lens"),
    ("q / :q / Ctrl-c", "quit (asks if unsaved)"),
    (":q!", "quit without saving"),
    ("?", "show / hide this key map"),
    ("mouse click", "select a cell"),
];

/// The action for `key` in `mode`, if any.
pub fn action_for(mode: KeyMode, key: KeyEvent) -> Option<Action> {
    let ctrl = key.modifiers.contains(KeyModifiers::CONTROL);
    if ctrl && key.code == KeyCode::Char('c') && mode != KeyMode::Cell && mode != KeyMode::Line {
        return Some(Action::Quit);
    }
    match mode {
        KeyMode::Normal => normal(key, ctrl),
        KeyMode::Cell | KeyMode::Line => text(key, ctrl, mode == KeyMode::Cell),
        KeyMode::Prompt => match key.code {
            KeyCode::Esc => Some(Action::Cancel),
            KeyCode::Char(c) => Some(Action::Answer(c.to_ascii_lowercase())),
            _ => None,
        },
        KeyMode::Help => match key.code {
            KeyCode::Esc | KeyCode::Char('?') | KeyCode::Char('q') | KeyCode::Enter => {
                Some(Action::Help)
            }
            _ => None,
        },
    }
}

fn normal(key: KeyEvent, ctrl: bool) -> Option<Action> {
    use KeyCode::*;
    if ctrl {
        return match key.code {
            Char('z') => Some(Action::Undo),
            Char('r') | Char('y') => Some(Action::Redo),
            Char('s') => Some(Action::Save),
            Char('w') => Some(Action::SaveAs),
            Char('o') => Some(Action::Open),
            _ => None,
        };
    }
    Some(match key.code {
        Up | Char('k') => Action::Move(Move::Up),
        Down | Char('j') => Action::Move(Move::Down),
        Left | Char('h') => Action::Move(Move::Left),
        Right | Char('l') => Action::Move(Move::Right),
        Tab => Action::Move(Move::Next),
        BackTab => Action::Move(Move::Prev),
        Home | Char('g') => Action::Move(Move::Top),
        End | Char('G') => Action::Move(Move::Bottom),
        Enter | F(2) => Action::Edit,
        Char(c @ ('0'..='9' | '-' | '.')) => Action::EditWith(c),
        Insert | Char('O') => Action::InsertAbove,
        Char('o') => Action::InsertBelow,
        Char('y') => Action::Duplicate,
        Delete | Char('d') => Action::DeleteRow,
        Char('K') => Action::MoveRowUp,
        Char('J') => Action::MoveRowDown,
        Char('u') => Action::Undo,
        Char(']') => Action::NextGhost,
        Char('[') => Action::PrevGhost,
        Char(':') => Action::Command,
        Char('W') => Action::Window,
        Char('q') => Action::Quit,
        Char('?') => Action::Help,
        _ => return None,
    })
}

fn text(key: KeyEvent, ctrl: bool, cell: bool) -> Option<Action> {
    use KeyCode::*;
    if ctrl {
        return match key.code {
            Char('n') => Some(Action::Complete(1)),
            Char('p') => Some(Action::Complete(-1)),
            Char('u') => Some(Action::ClearInput),
            Char('a') => Some(Action::CaretHome),
            Char('e') => Some(Action::CaretEnd),
            Char('c') => Some(Action::Cancel),
            _ => None,
        };
    }
    Some(match key.code {
        Enter => Action::Commit,
        Esc => Action::Cancel,
        Tab if cell => Action::CommitAndMove(Move::Next),
        BackTab if cell => Action::CommitAndMove(Move::Prev),
        Backspace => Action::Backspace,
        Delete => Action::Delete,
        Left => Action::CaretLeft,
        Right => Action::CaretRight,
        Home => Action::CaretHome,
        End => Action::CaretEnd,
        Char(c) => Action::Input(c),
        _ => return None,
    })
}
