//! The editor's state and `App::update` (The Elm Architecture): an `Action` changes the state
//! and returns the `Effect`s (saves, recovery writes, opening, quitting) for the runner to do.
//! Drawing (`view`) only reads the state.

use std::path::PathBuf;

use flarebench_sdk::{LensSystem, Medium, Surface};

use super::action::{Action, Effect, Move, Opened};
use super::analysis::{Analysis, Polyline, ghost_rays};
use super::cell::{
    CellEditor, Column, HeaderField, edit_text, glass_completions, header_edit_text, parse_cell,
    parse_header,
};
use super::document::{Document, Edit, EditError, Header};
use super::files::recovery_path;
use super::keymap::KeyMode;
pub use super::layout::Focus;
use super::layout::{hit_test, table_rows};

/// What the text line at the bottom is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinePurpose {
    Command,
    SaveAs,
    Open,
}

/// A one-key question.
#[derive(Clone, Debug, PartialEq)]
pub enum Prompt {
    /// Quit with unsaved changes: save, discard or cancel.
    QuitUnsaved,
    /// A recovery file with unsaved edits exists: recover or discard it.
    Recover(Box<LensSystem>),
}

/// The input mode.
#[derive(Clone, Debug, PartialEq)]
pub enum Mode {
    Normal,
    Cell(CellEditor),
    Line {
        purpose: LinePurpose,
        editor: CellEditor,
    },
    Prompt(Prompt),
    Help,
}

/// A message in the status line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Message {
    pub text: String,
    pub error: bool,
}

/// The whole editor state.
#[derive(Debug)]
pub struct App {
    pub doc: Document,
    pub analysis: Analysis,
    /// The selected ghost (index into `analysis.ghosts`) and its traced rays.
    pub ghost: Option<usize>,
    pub ghost_rays: Vec<Polyline>,
    pub focus: Focus,
    pub mode: Mode,
    pub message: Option<Message>,
    /// Where saves go; `None` asks for a path.
    pub path: Option<PathBuf>,
    /// What was opened (title bar).
    pub label: String,
    /// The recovery file written after every committed edit.
    pub recovery: PathBuf,
    /// The system as last saved or opened (unsaved changes = the document differs).
    saved: LensSystem,
    /// First table row shown.
    pub scroll: usize,
    /// Terminal size (columns, rows), for scrolling and mouse hits.
    pub size: (u16, u16),
    /// Live check of the text being edited: `Ok` or what is wrong.
    pub edit_status: Option<Result<(), String>>,
    quit_after_save: bool,
}

impl App {
    /// An editor on an opened lens; when a recovery file was found, asks whether to recover.
    pub fn new(opened: Opened) -> Result<App, EditError> {
        let doc = Document::new(opened.system.clone())?;
        let analysis = Analysis::compute(doc.system());
        let mut app = App {
            doc,
            analysis,
            ghost: None,
            ghost_rays: Vec::new(),
            focus: Focus::Cell { row: 0, col: 1 },
            mode: Mode::Normal,
            message: None,
            path: opened.path,
            label: opened.label,
            recovery: opened.recovery_path,
            saved: opened.system,
            scroll: 0,
            size: (120, 40),
            edit_status: None,
            quit_after_save: false,
        };
        if let Some(r) = opened.recovered {
            app.mode = Mode::Prompt(Prompt::Recover(Box::new(r)));
        } else if let Some(w) = opened.warnings.first() {
            app.info(format!("warning: {w}"));
        }
        Ok(app)
    }

    /// True when the document differs from the file.
    pub fn dirty(&self) -> bool {
        *self.doc.system() != self.saved
    }

    /// The selected surface row, if a table cell is selected.
    pub fn selected_row(&self) -> Option<usize> {
        match self.focus {
            Focus::Cell { row, .. } => Some(row),
            Focus::Header(_) => None,
        }
    }

    /// The selected ghost's path.
    pub fn selected_ghost(&self) -> Option<flarebench_sdk::ghost::GhostPath> {
        self.ghost
            .and_then(|g| self.analysis.ghosts.get(g).copied())
    }

    /// The key mode for the keymap.
    pub fn key_mode(&self) -> KeyMode {
        match self.mode {
            Mode::Normal => KeyMode::Normal,
            Mode::Cell(_) => KeyMode::Cell,
            Mode::Line { .. } => KeyMode::Line,
            Mode::Prompt(_) => KeyMode::Prompt,
            Mode::Help => KeyMode::Help,
        }
    }

    fn info(&mut self, text: String) {
        self.message = Some(Message { text, error: false });
    }

    fn error(&mut self, text: String) {
        self.message = Some(Message { text, error: true });
    }

    /// Glass completions for the cell being edited (empty unless it is a glass cell).
    pub fn completions(&self) -> Vec<String> {
        match (&self.mode, self.focus) {
            (Mode::Cell(ed), Focus::Cell { col, .. }) if Column::ALL[col] == Column::Glass => {
                glass_completions(&ed.typed, 8)
            }
            _ => Vec::new(),
        }
    }

    /// Applies `action`; returns what the runner must do.
    pub fn update(&mut self, action: Action) -> Vec<Effect> {
        if !matches!(
            action,
            Action::Resize { .. }
                | Action::Saved(_)
                | Action::Opened(_)
                | Action::Failed(_)
                | Action::SelectRow(_)
                | Action::SelectGhost(_)
        ) {
            self.message = None;
        }
        let mut fx = Vec::new();
        match action {
            Action::Resize { width, height } => {
                self.size = (width, height);
                self.ensure_visible();
            }
            Action::Saved(r) => self.saved(r, &mut fx),
            Action::Opened(r) => match r {
                Ok(o) => self.replace(*o),
                Err(e) => self.error(e),
            },
            Action::Failed(e) => self.error(e),
            Action::Note(n) => self.info(n),
            Action::SelectRow(row) => {
                let n = self.doc.system().surfaces.len();
                if row < n {
                    let col = match self.focus {
                        Focus::Cell { col, .. } => col,
                        Focus::Header(_) => 1,
                    };
                    self.focus = Focus::Cell { row, col };
                    self.ensure_visible();
                }
            }
            Action::SelectGhost(g) => {
                self.ghost = self.analysis.ghosts.iter().position(|x| *x == g);
                self.trace_ghost();
                if let Some(i) = self.ghost {
                    self.info(format!("ghost {} selected in the window", i + 1));
                }
            }
            a => match self.mode.clone() {
                Mode::Normal => self.normal(a, &mut fx),
                Mode::Cell(ed) => self.cell(ed, a, &mut fx),
                Mode::Line { purpose, editor } => self.line(purpose, editor, a, &mut fx),
                Mode::Prompt(p) => self.prompt(p, a, &mut fx),
                Mode::Help => {
                    if matches!(a, Action::Help | Action::Cancel) {
                        self.mode = Mode::Normal;
                    }
                }
            },
        }
        fx
    }

    fn normal(&mut self, a: Action, fx: &mut Vec<Effect>) {
        match a {
            Action::Move(m) => self.move_focus(m),
            Action::Click { x, y } => {
                if let Some(f) = hit_test(
                    self.size,
                    self.scroll,
                    self.doc.system().surfaces.len(),
                    x,
                    y,
                ) {
                    self.focus = f;
                }
            }
            Action::Edit => self.start_edit(None),
            Action::EditWith(c) => self.start_edit(Some(c)),
            Action::InsertAbove | Action::InsertBelow | Action::Duplicate => {
                if let Focus::Cell { row, .. } = self.focus {
                    let cur = &self.doc.system().surfaces[row];
                    let (index, surface) = match a {
                        Action::Duplicate => (row + 1, cur.clone()),
                        _ => {
                            let sd = if cur.semi_diameter > 0.0 {
                                cur.semi_diameter
                            } else {
                                1.0
                            };
                            let s = Surface::spherical(0.0, 0.0, Medium::Air, sd);
                            let at = if a == Action::InsertAbove {
                                row
                            } else {
                                row + 1
                            };
                            (at, s)
                        }
                    };
                    self.commit_edit(Edit::Insert { index, surface }, fx);
                }
            }
            Action::DeleteRow => {
                if let Focus::Cell { row, .. } = self.focus {
                    let surface = self.doc.system().surfaces[row].clone();
                    self.commit_edit(
                        Edit::Remove {
                            index: row,
                            surface,
                        },
                        fx,
                    );
                }
            }
            Action::MoveRowUp | Action::MoveRowDown => {
                if let Focus::Cell { row, col } = self.focus {
                    let (index, to) = if a == Action::MoveRowUp {
                        (row.checked_sub(1), row.saturating_sub(1))
                    } else {
                        (Some(row), row + 1)
                    };
                    match index {
                        Some(index) => {
                            if self.commit_edit(Edit::SwapDown { index }, fx) {
                                self.focus = Focus::Cell { row: to, col };
                            }
                        }
                        None => self.error("already the first surface".into()),
                    }
                }
            }
            Action::Undo => match self.doc.undo() {
                Ok(e) => {
                    self.info(format!("undone: {}", describe(&e)));
                    self.after_change(e.row(), fx);
                }
                Err(e) => self.error(e.to_string()),
            },
            Action::Redo => match self.doc.redo() {
                Ok(e) => {
                    self.info(format!("redone: {}", describe(&e)));
                    self.after_change(e.row(), fx);
                }
                Err(e) => self.error(e.to_string()),
            },
            Action::Help => self.mode = Mode::Help,
            Action::NextGhost | Action::PrevGhost => {
                let n = self.analysis.ghosts.len();
                self.ghost = match (self.ghost, a == Action::NextGhost) {
                    _ if n == 0 => None,
                    (None, true) => Some(0),
                    (None, false) => Some(n - 1),
                    (Some(i), true) => (i + 1 < n).then_some(i + 1),
                    (Some(i), false) => i.checked_sub(1),
                };
                self.trace_ghost();
            }
            Action::Save => self.save(None, fx),
            Action::SaveAs => self.open_line(LinePurpose::SaveAs),
            Action::Open => self.open_line(LinePurpose::Open),
            Action::Command => self.open_line(LinePurpose::Command),
            Action::Window => fx.push(Effect::OpenWindow),
            Action::Quit => {
                if self.dirty() {
                    self.mode = Mode::Prompt(Prompt::QuitUnsaved);
                } else {
                    fx.push(Effect::Quit);
                }
            }
            Action::ForceQuit => {
                fx.push(Effect::RemoveRecovery(self.recovery.clone()));
                fx.push(Effect::Quit);
            }
            _ => {}
        }
    }

    fn open_line(&mut self, purpose: LinePurpose) {
        let text = match purpose {
            LinePurpose::SaveAs => self
                .path
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| default_save_name(&self.doc.system().name)),
            _ => String::new(),
        };
        self.mode = Mode::Line {
            purpose,
            editor: CellEditor::new(text),
        };
    }

    fn start_edit(&mut self, first: Option<char>) {
        let text = match self.focus {
            Focus::Header(i) => {
                header_edit_text(&Header::of(self.doc.system()), HeaderField::ALL[i])
            }
            Focus::Cell { row, col } => {
                edit_text(&self.doc.system().surfaces[row], Column::ALL[col])
            }
        };
        let mut ed = CellEditor::new(text);
        if let Some(c) = first {
            ed.clear();
            ed.insert(c);
        }
        self.edit_status = Some(self.check_text(&ed.text).map(|_| ()));
        self.mode = Mode::Cell(ed);
    }

    /// The edit `text` in the selected cell would make, checked against the whole system.
    fn check_text(&self, text: &str) -> Result<Option<Edit>, String> {
        let sys = self.doc.system();
        let edit = match self.focus {
            Focus::Header(i) => {
                let old = Header::of(sys);
                let new = parse_header(&old, HeaderField::ALL[i], text)?;
                (new != old).then_some(Edit::Header { old, new })
            }
            Focus::Cell { row, col } => {
                let old = sys.surfaces[row].clone();
                let new = parse_cell(&old, Column::ALL[col], text)?;
                (new != old).then_some(Edit::Replace {
                    index: row,
                    old,
                    new,
                })
            }
        };
        if let Some(e) = &edit {
            self.doc.check(e).map_err(|e| e.to_string())?;
        }
        Ok(edit)
    }

    fn cell(&mut self, mut ed: CellEditor, a: Action, fx: &mut Vec<Effect>) {
        match a {
            Action::Commit | Action::CommitAndMove(_) => match self.check_text(&ed.text) {
                Ok(edit) => {
                    self.mode = Mode::Normal;
                    self.edit_status = None;
                    if let Some(edit) = edit {
                        self.commit_edit(edit, fx);
                    }
                    if let Action::CommitAndMove(m) = a {
                        self.move_focus(m);
                    }
                }
                Err(e) => {
                    self.error(e.clone());
                    self.edit_status = Some(Err(e));
                }
            },
            Action::Cancel => {
                self.mode = Mode::Normal;
                self.edit_status = None;
            }
            Action::Complete(step) => {
                let c = self.completions_for(&ed);
                if c.is_empty() {
                    self.error("no glass name starts with that".into());
                } else {
                    ed.cycle(&c, step);
                }
                self.set_cell_editor(ed);
            }
            other => {
                if edit_text_action(&mut ed, other) {
                    self.set_cell_editor(ed);
                }
            }
        }
    }

    fn completions_for(&self, ed: &CellEditor) -> Vec<String> {
        match self.focus {
            Focus::Cell { col, .. } if Column::ALL[col] == Column::Glass => {
                glass_completions(&ed.typed, 64)
            }
            _ => Vec::new(),
        }
    }

    fn set_cell_editor(&mut self, ed: CellEditor) {
        self.edit_status = Some(self.check_text(&ed.text).map(|_| ()));
        self.mode = Mode::Cell(ed);
    }

    fn line(&mut self, purpose: LinePurpose, mut ed: CellEditor, a: Action, fx: &mut Vec<Effect>) {
        match a {
            Action::Commit => {
                self.mode = Mode::Normal;
                let text = ed.text.trim().to_string();
                match purpose {
                    LinePurpose::Command => self.command(&text, fx),
                    LinePurpose::SaveAs => self.save(Some(text), fx),
                    LinePurpose::Open => self.open(&text, false, fx),
                }
            }
            Action::Cancel => {
                self.mode = Mode::Normal;
                self.quit_after_save = false;
            }
            other => {
                if edit_text_action(&mut ed, other) {
                    self.mode = Mode::Line {
                        purpose,
                        editor: ed,
                    };
                }
            }
        }
    }

    fn command(&mut self, text: &str, fx: &mut Vec<Effect>) {
        let (cmd, arg) = match text.split_once(char::is_whitespace) {
            Some((c, a)) => (c, Some(a.trim().to_string()).filter(|a| !a.is_empty())),
            None => (text, None),
        };
        match cmd {
            "w" => self.save(arg, fx),
            "wq" | "x" => {
                self.quit_after_save = true;
                self.save(arg, fx);
            }
            "q" => self.normal(Action::Quit, fx),
            "q!" => self.normal(Action::ForceQuit, fx),
            "e" | "e!" => match arg {
                Some(a) => self.open(&a, cmd == "e!", fx),
                None => self.error(format!(":{cmd} needs a lens path or name")),
            },
            "help" => self.mode = Mode::Help,
            "window" => fx.push(Effect::OpenWindow),
            "" => {}
            _ => self.error(format!(
                "unknown command :{cmd} (w, wq, q, q!, e PATH, window, help)"
            )),
        }
    }

    fn open(&mut self, spec: &str, force: bool, fx: &mut Vec<Effect>) {
        if spec.is_empty() {
            self.error("open: give a lens path or name".into());
        } else if self.dirty() && !force {
            self.error("unsaved changes: save first, or :e! PATH to discard them".into());
        } else {
            if force {
                fx.push(Effect::RemoveRecovery(self.recovery.clone()));
            }
            fx.push(Effect::Open(spec.to_string()));
        }
    }

    /// Saves to `to` (a path typed by the user) or to the current path; asks when neither.
    fn save(&mut self, to: Option<String>, fx: &mut Vec<Effect>) {
        let path = match to {
            Some(t) if t.is_empty() => {
                self.error("save: give a file name".into());
                return;
            }
            Some(t) => PathBuf::from(t),
            None => match &self.path {
                Some(p) => p.clone(),
                None => {
                    self.open_line(LinePurpose::SaveAs);
                    return;
                }
            },
        };
        if !path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
        {
            self.error(format!("save: {} must end in .xml", path.display()));
            self.quit_after_save = false;
            return;
        }
        fx.push(Effect::Save {
            path,
            system: Box::new(self.doc.system().clone()),
            recovery: self.recovery.clone(),
        });
    }

    fn saved(&mut self, r: Result<PathBuf, String>, fx: &mut Vec<Effect>) {
        match r {
            Ok(p) => {
                self.saved = self.doc.system().clone();
                self.recovery = recovery_path(&p);
                self.info(format!("saved {}", p.display()));
                self.path = Some(p);
                if self.quit_after_save {
                    fx.push(Effect::Quit);
                }
            }
            Err(e) => {
                self.quit_after_save = false;
                self.error(e);
            }
        }
    }

    fn prompt(&mut self, p: Prompt, a: Action, fx: &mut Vec<Effect>) {
        let answer = match a {
            Action::Answer(c) => c,
            Action::Cancel => 'c',
            _ => return,
        };
        match (p, answer) {
            (Prompt::QuitUnsaved, 's') => {
                self.mode = Mode::Normal;
                self.quit_after_save = true;
                self.save(None, fx);
            }
            (Prompt::QuitUnsaved, 'd') => {
                fx.push(Effect::RemoveRecovery(self.recovery.clone()));
                fx.push(Effect::Quit);
            }
            (Prompt::QuitUnsaved, 'c') => self.mode = Mode::Normal,
            (Prompt::Recover(sys), 'r') => {
                self.mode = Mode::Normal;
                match Document::new(*sys) {
                    Ok(mut doc) => {
                        doc.take_subscribers(&mut self.doc);
                        self.doc = doc;
                        self.after_change(None, fx);
                        self.info("recovered the unsaved edits (not saved yet)".into());
                    }
                    Err(e) => self.error(format!("the recovery file is not usable: {e}")),
                }
            }
            (Prompt::Recover(_), 'd') => {
                self.mode = Mode::Normal;
                fx.push(Effect::RemoveRecovery(self.recovery.clone()));
                self.info("recovery file discarded".into());
            }
            _ => {}
        }
    }

    /// Applies `edit` to the document; reports a refusal. True when applied.
    fn commit_edit(&mut self, edit: Edit, fx: &mut Vec<Effect>) -> bool {
        let row = edit.row();
        match self.doc.apply(edit) {
            Ok(()) => {
                self.after_change(row, fx);
                true
            }
            Err(e) => {
                self.error(e.to_string());
                false
            }
        }
    }

    /// After the document changed: recompute the analysis, keep the selection in range,
    /// and write (or remove) the recovery file.
    fn after_change(&mut self, row: Option<usize>, fx: &mut Vec<Effect>) {
        self.analysis = Analysis::compute(self.doc.system());
        let n = self.doc.system().surfaces.len();
        match (&mut self.focus, row) {
            (Focus::Cell { row: r, .. }, Some(to)) => *r = to.min(n - 1),
            (Focus::Cell { row: r, .. }, None) => *r = (*r).min(n - 1),
            _ => {}
        }
        if self.ghost.is_some_and(|g| g >= self.analysis.ghosts.len()) {
            self.ghost = None;
        }
        self.trace_ghost();
        self.ensure_visible();
        fx.push(if self.dirty() {
            Effect::WriteRecovery {
                path: self.recovery.clone(),
                system: Box::new(self.doc.system().clone()),
            }
        } else {
            Effect::RemoveRecovery(self.recovery.clone())
        });
    }

    fn trace_ghost(&mut self) {
        self.ghost_rays = match self.ghost {
            Some(g) => ghost_rays(self.doc.system(), self.analysis.ghosts[g], &self.analysis),
            None => Vec::new(),
        };
    }

    /// Replaces the whole state with a newly opened lens.
    fn replace(&mut self, o: Opened) {
        let label = o.label.clone();
        match App::new(o) {
            Ok(mut app) => {
                app.size = self.size;
                if app.message.is_none() {
                    app.info(format!("opened {label}"));
                }
                app.doc.take_subscribers(&mut self.doc);
                *self = app;
            }
            Err(e) => self.error(format!("cannot edit {label}: {e}")),
        }
    }

    fn move_focus(&mut self, m: Move) {
        let rows = self.doc.system().surfaces.len();
        let cols = Column::ALL.len();
        let hcols = HeaderField::ALL.len();
        self.focus = match (self.focus, m) {
            (Focus::Header(_), Move::Up | Move::Top) => Focus::Header(0),
            (Focus::Header(i), Move::Down) => Focus::Cell { row: 0, col: i },
            (Focus::Header(i), Move::Left) => Focus::Header(i.saturating_sub(1)),
            (Focus::Header(i), Move::Right) => Focus::Header((i + 1).min(hcols - 1)),
            (Focus::Header(i), Move::Next) if i + 1 < hcols => Focus::Header(i + 1),
            (Focus::Header(_), Move::Next) => Focus::Cell { row: 0, col: 0 },
            (Focus::Header(i), Move::Prev) => Focus::Header(i.saturating_sub(1)),
            (Focus::Header(_), Move::Bottom) => Focus::Cell {
                row: rows - 1,
                col: 0,
            },
            (Focus::Cell { row: 0, col }, Move::Up) => Focus::Header(col.min(hcols - 1)),
            (Focus::Cell { row, col }, Move::Up) => Focus::Cell { row: row - 1, col },
            (Focus::Cell { row, col }, Move::Down) => Focus::Cell {
                row: (row + 1).min(rows - 1),
                col,
            },
            (Focus::Cell { row, col }, Move::Left) => Focus::Cell {
                row,
                col: col.saturating_sub(1),
            },
            (Focus::Cell { row, col }, Move::Right) => Focus::Cell {
                row,
                col: (col + 1).min(cols - 1),
            },
            (Focus::Cell { row, col }, Move::Next) => {
                if col + 1 < cols {
                    Focus::Cell { row, col: col + 1 }
                } else if row + 1 < rows {
                    Focus::Cell {
                        row: row + 1,
                        col: 0,
                    }
                } else {
                    Focus::Cell { row, col }
                }
            }
            (Focus::Cell { row, col }, Move::Prev) => {
                if col > 0 {
                    Focus::Cell { row, col: col - 1 }
                } else if row > 0 {
                    Focus::Cell {
                        row: row - 1,
                        col: cols - 1,
                    }
                } else {
                    Focus::Header(hcols - 1)
                }
            }
            (Focus::Cell { col, .. }, Move::Top) => Focus::Cell { row: 0, col },
            (Focus::Cell { col, .. }, Move::Bottom) => Focus::Cell { row: rows - 1, col },
        };
        self.ensure_visible();
    }

    /// Scrolls the table so the selected row is visible.
    fn ensure_visible(&mut self) {
        let visible = table_rows(self.size).max(1);
        let row = match self.focus {
            Focus::Cell { row, .. } => row,
            Focus::Header(_) => 0,
        };
        if row < self.scroll {
            self.scroll = row;
        } else if row >= self.scroll + visible {
            self.scroll = row + 1 - visible;
        }
        let rows = self.doc.system().surfaces.len();
        self.scroll = self.scroll.min(rows.saturating_sub(visible));
    }
}

/// Text editing shared by the cell editor and the command line; false for other actions.
fn edit_text_action(ed: &mut CellEditor, a: Action) -> bool {
    match a {
        Action::Input(c) => ed.insert(c),
        Action::Backspace => ed.backspace(),
        Action::Delete => ed.delete(),
        Action::CaretLeft => ed.move_caret(-1),
        Action::CaretRight => ed.move_caret(1),
        Action::CaretHome => ed.home(),
        Action::CaretEnd => ed.end(),
        Action::ClearInput => ed.clear(),
        _ => return false,
    }
    true
}

/// A short description of an edit for the status line.
pub fn describe(edit: &Edit) -> String {
    match edit {
        Edit::Replace { index, .. } => format!("change to surface {index}"),
        Edit::Insert { index, .. } => format!("insert surface {index}"),
        Edit::Remove { index, .. } => format!("delete surface {index}"),
        Edit::SwapDown { index } => format!("swap surfaces {index} and {}", index + 1),
        Edit::Header { .. } => "header change".into(),
    }
}

/// A file name made from a lens name: lower case, spaces and odd characters as `-`, `.xml`.
fn default_save_name(name: &str) -> String {
    let mut s = crate::output::file_stem(name);
    if s.is_empty() {
        s = "lens".into();
    }
    format!("{s}.xml")
}
