//! Drawing the editor: a pure function of the `App` state into a ratatui `Frame`, in the
//! areas of `super::layout`.

mod panels;
mod side_view;
mod table;

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph};

use super::app::{App, LinePurpose, Mode, Prompt};
use super::cell::{HeaderField, show_header};
use super::document::Header;
use super::keymap::KEY_HELP;
pub use super::layout::{Areas, hit_test, table_rows};
use super::layout::{Focus, HEADER_WIDTHS, ROW_LABEL, layout};

/// Draws the whole editor.
pub fn draw(frame: &mut Frame, app: &App) {
    let a = layout(frame.area());
    draw_title(frame, app, a.title);
    draw_header(frame, app, a.header);
    table::draw(frame, app, a.table);
    panels::draw_analysis(frame, app, a.analysis);
    panels::draw_ghosts(frame, app, a.ghosts);
    side_view::draw(frame, app, a.side);
    draw_status(frame, app, a.status);
    if app.mode == Mode::Help {
        draw_help(frame, frame.area());
    }
}

fn draw_title(frame: &mut Frame, app: &App, area: Rect) {
    let file = std::path::Path::new(&app.label)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| app.label.clone());
    let target = match &app.path {
        Some(_) => String::new(),
        None => " (not saved to a file yet)".into(),
    };
    let modified = if app.dirty() { " [modified]" } else { "" };
    let text = format!(
        " flarebench edit — {file}{target}{modified}   undo {} · redo {}   ? keys",
        app.doc.undo_len(),
        app.doc.redo_len()
    );
    frame.render_widget(
        Paragraph::new(text).style(Style::new().add_modifier(Modifier::REVERSED)),
        area,
    );
}

fn draw_header(frame: &mut Frame, app: &App, area: Rect) {
    let header = Header::of(app.doc.system());
    let mut spans = Vec::new();
    for (i, f) in HeaderField::ALL.iter().enumerate() {
        let selected = app.focus == Focus::Header(i);
        let value = match (&app.mode, selected) {
            (Mode::Cell(ed), true) => ed.text.clone(),
            _ => show_header(&header, *f),
        };
        let label = format!(" {}: ", f.title());
        let w = HEADER_WIDTHS[i] as usize;
        let room = w.saturating_sub(label.chars().count());
        let value: String = format!("{value:<room$}").chars().take(room).collect();
        spans.push(Span::styled(label, Style::new().fg(Color::DarkGray)));
        spans.push(Span::styled(value, cell_style(app, selected)));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), area);
    if let (Mode::Cell(ed), Focus::Header(i)) = (&app.mode, app.focus) {
        let left: u16 = HEADER_WIDTHS[..i].iter().sum();
        let label = HeaderField::ALL[i].title().chars().count() as u16 + 3;
        frame.set_cursor_position((area.x + left + label + ed.caret as u16, area.y));
    }
}

/// The style of a cell: reversed when selected (yellow while editing).
fn cell_style(app: &App, selected: bool) -> Style {
    match (selected, &app.mode) {
        (true, Mode::Cell(_)) => Style::new().fg(Color::Black).bg(Color::Yellow),
        (true, _) => Style::new().add_modifier(Modifier::REVERSED),
        _ => Style::new(),
    }
}

fn draw_status(frame: &mut Frame, app: &App, area: Rect) {
    let line = match &app.mode {
        Mode::Line { purpose, editor } => {
            let prefix = match purpose {
                LinePurpose::Command => ":",
                LinePurpose::SaveAs => "save as: ",
                LinePurpose::Open => "open: ",
            };
            frame.set_cursor_position((
                area.x + prefix.chars().count() as u16 + editor.caret as u16,
                area.y,
            ));
            Line::from(format!("{prefix}{}", editor.text))
        }
        Mode::Prompt(Prompt::QuitUnsaved) => Line::styled(
            "unsaved changes — (s)ave and quit, (d)iscard and quit, (c)ancel",
            Style::new().fg(Color::Yellow),
        ),
        Mode::Prompt(Prompt::Recover(_)) => Line::styled(
            "a recovery file holds unsaved edits of this lens — (r)ecover them or (d)iscard the file",
            Style::new().fg(Color::Yellow),
        ),
        Mode::Cell(_) => {
            let mut spans = match &app.edit_status {
                Some(Err(e)) => vec![Span::styled(format!("✗ {e}"), Style::new().fg(Color::Red))],
                _ => vec![Span::styled("✓ ", Style::new().fg(Color::Green))],
            };
            let completions = app.completions();
            if !completions.is_empty() {
                spans.push(Span::styled(
                    format!("  Ctrl-n: {}", completions.join(" ")),
                    Style::new().fg(Color::DarkGray),
                ));
            } else if matches!(app.edit_status, Some(Ok(()))) {
                spans.push(Span::styled(
                    "Enter accept · Tab accept and move · Esc cancel",
                    Style::new().fg(Color::DarkGray),
                ));
            }
            Line::from(spans)
        }
        _ => match &app.message {
            Some(m) if m.error => Line::styled(m.text.clone(), Style::new().fg(Color::Red)),
            Some(m) => Line::from(m.text.clone()),
            None => Line::styled(
                "Enter edit · o/O insert · y dup · d delete · u undo · ] ghost · Ctrl-s save · q quit · ? keys",
                Style::new().fg(Color::DarkGray),
            ),
        },
    };
    frame.render_widget(Paragraph::new(line), area);
}

fn draw_help(frame: &mut Frame, area: Rect) {
    let w = 78.min(area.width);
    let h = (KEY_HELP.len() as u16 + 2).min(area.height);
    let popup = Rect::new(
        area.x + (area.width - w) / 2,
        area.y + (area.height - h) / 2,
        w,
        h,
    );
    let lines: Vec<Line> = KEY_HELP
        .iter()
        .map(|(k, what)| {
            Line::from(vec![
                Span::styled(format!(" {k:<28}"), Style::new().fg(Color::Yellow)),
                Span::raw(*what),
            ])
        })
        .collect();
    frame.render_widget(Clear, popup);
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(" keys (Esc closes) ")),
        popup,
    );
}
