//! The terminal runner: raw mode and the alternate screen (crossterm), mouse capture, and the
//! loop that reads events, maps them to actions, updates the app and draws it.

use std::io::{IsTerminal, stdout};

use anyhow::Context;
use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{
    self, DisableMouseCapture, EnableMouseCapture, Event, KeyEventKind, MouseButton, MouseEventKind,
};
use ratatui::crossterm::execute;

use super::action::Action;
use super::app::App;
use super::{dispatch, keymap, view};

/// Runs the editor in the terminal until the user quits.
pub fn run(app: App) -> anyhow::Result<()> {
    anyhow::ensure!(
        stdout().is_terminal(),
        "`flarebench edit` needs a terminal (standard output is not one)"
    );
    let mut terminal = ratatui::try_init().context("could not set up the terminal")?;
    // Mouse selection where the terminal supports it; ignored elsewhere.
    let _ = execute!(stdout(), EnableMouseCapture);
    let result = event_loop(&mut terminal, app);
    let _ = execute!(stdout(), DisableMouseCapture);
    ratatui::restore();
    result
}

fn event_loop(terminal: &mut DefaultTerminal, mut app: App) -> anyhow::Result<()> {
    let size = terminal.size()?;
    app.update(Action::Resize {
        width: size.width,
        height: size.height,
    });
    loop {
        terminal.draw(|f| view::draw(f, &app))?;
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
        if let Some(a) = action
            && dispatch(&mut app, a)
        {
            return Ok(());
        }
    }
}
