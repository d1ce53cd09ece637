//! The terminal runner: raw mode and the alternate screen (crossterm), mouse capture, and the
//! loop that reads events, maps them to actions, updates the app and draws it. With a window
//! beside it ([`WindowHost`]), the loop also takes in the window's messages and tells the
//! window what the editor selects; document changes reach the window through
//! `Document::subscribe`.

use std::io::{IsTerminal, stdout};
use std::sync::mpsc::Receiver;
use std::time::Duration;

use anyhow::Context;
use flarebench_sdk::ghost::GhostPath;
use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{
    self, DisableMouseCapture, EnableMouseCapture, Event, KeyEventKind, MouseButton, MouseEventKind,
};
use ratatui::crossterm::execute;

use super::action::Action;
use super::app::App;
use super::{dispatch_with, keymap, view};
use crate::link::{FromEditor, ToEditor};

/// The editor's side of the link with a window in the same process.
pub struct WindowHost {
    /// Opens the window (or says why there is none).
    pub open: Box<dyn Fn() -> Result<(), String> + Send>,
    /// The window's messages.
    pub from_window: Receiver<ToEditor>,
    /// Tells the window what the editor selects (and wakes it).
    pub to_window: Box<dyn Fn(FromEditor) + Send>,
}

impl std::fmt::Debug for WindowHost {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WindowHost").finish_non_exhaustive()
    }
}

/// How often the loop looks at the window's messages while no key arrives.
const WINDOW_POLL: Duration = Duration::from_millis(30);

/// Runs the editor in the terminal until the user quits.
pub fn run(app: App) -> anyhow::Result<()> {
    run_with(app, None)
}

/// Runs the editor in the terminal, linked to a window when `host` is given.
pub fn run_with(app: App, host: Option<WindowHost>) -> anyhow::Result<()> {
    anyhow::ensure!(
        stdout().is_terminal(),
        "`flarebench edit` needs a terminal (standard output is not one)"
    );
    let mut terminal = ratatui::try_init().context("could not set up the terminal")?;
    // ratatui's hook restores the terminal on any panic; not for the viewer's render thread,
    // whose panics are caught and shown in the window's status line.
    crate::panics::install_hook();
    // Mouse selection where the terminal supports it; ignored elsewhere.
    let _ = execute!(stdout(), EnableMouseCapture);
    let result = event_loop(&mut terminal, app, host);
    let _ = execute!(stdout(), DisableMouseCapture);
    ratatui::restore();
    result
}

fn event_loop(
    terminal: &mut DefaultTerminal,
    mut app: App,
    host: Option<WindowHost>,
) -> anyhow::Result<()> {
    let size = terminal.size()?;
    app.update(Action::Resize {
        width: size.width,
        height: size.height,
    });
    let mut told = (None, None);
    loop {
        if let Some(h) = &host {
            tell_window(h, &app, &mut told);
        }
        terminal.draw(|f| view::draw(f, &app))?;
        let mut actions = Vec::new();
        if let Some(h) = &host {
            actions.extend(h.from_window.try_iter().map(|m| match m {
                ToEditor::SelectRow(r) => Action::SelectRow(r),
                ToEditor::SelectGhost(g) => Action::SelectGhost(g),
                ToEditor::Note(n) => Action::Note(n),
            }));
            if actions.is_empty() && !event::poll(WINDOW_POLL)? {
                continue;
            }
        }
        if actions.is_empty() {
            let action = match event::read()? {
                Event::Key(k) if k.kind != KeyEventKind::Release => {
                    keymap::action_for(app.key_mode(), k)
                }
                Event::Mouse(m) if m.kind == MouseEventKind::Down(MouseButton::Left) => {
                    Some(Action::Click {
                        x: m.column,
                        y: m.row,
                    })
                }
                Event::Resize(width, height) => Some(Action::Resize { width, height }),
                _ => None,
            };
            actions.extend(action);
        }
        for a in actions {
            if dispatch_with(&mut app, a, host.as_ref()) {
                return Ok(());
            }
        }
    }
}

/// Sends the window the editor's selection when it changed.
fn tell_window(h: &WindowHost, app: &App, told: &mut (Option<usize>, Option<GhostPath>)) {
    let now = (app.selected_row(), app.selected_ghost());
    if now.0 != told.0 {
        (h.to_window)(FromEditor::Row(now.0));
    }
    if now.1 != told.1 {
        (h.to_window)(FromEditor::Ghost(now.1));
    }
    *told = now;
}
