//! The surface table: one row per surface, the selected cell highlighted, the cell being
//! edited shown with its caret.

use ratatui::Frame;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::widgets::{Block, Cell, Row, Table};

use super::{ROW_LABEL, cell_style};
use crate::edit::app::{App, Mode};
use crate::edit::cell::{Column, show};
use crate::edit::layout::Focus;
use flarebench_sdk::SurfaceKind;

pub(super) fn draw(frame: &mut Frame, app: &App, area: Rect) {
    let sys = app.doc.system();
    let visible = area.height.saturating_sub(3) as usize;
    let header = Row::new(
        std::iter::once(Cell::from("#"))
            .chain(Column::ALL.iter().map(|c| Cell::from(c.title())))
            .collect::<Vec<_>>(),
    )
    .style(Style::new().fg(Color::Cyan).add_modifier(Modifier::BOLD));
    let rows = sys
        .surfaces
        .iter()
        .enumerate()
        .skip(app.scroll)
        .take(visible)
        .map(|(i, s)| {
            let cells = std::iter::once(Cell::from(format!("{i:>2}"))).chain(
                Column::ALL.iter().enumerate().map(|(c, col)| {
                    let selected = app.focus == Focus::Cell { row: i, col: c };
                    let text = match (&app.mode, selected) {
                        (Mode::Cell(ed), true) => ed.text.clone(),
                        _ => show(s, *col),
                    };
                    Cell::from(text).style(cell_style(app, selected))
                }),
            );
            let style = match s.kind {
                SurfaceKind::ApertureStop => Style::new().fg(Color::LightBlue),
                SurfaceKind::Sensor => Style::new().fg(Color::DarkGray),
                SurfaceKind::Refracting => Style::new(),
            };
            Row::new(cells.collect::<Vec<_>>()).style(style)
        });
    let widths = std::iter::once(Constraint::Length(ROW_LABEL))
        .chain(Column::ALL.iter().map(|c| Constraint::Length(c.width())));
    let title = format!(
        " surfaces {}–{} of {} ",
        app.scroll,
        (app.scroll + visible)
            .min(sys.surfaces.len())
            .saturating_sub(1),
        sys.surfaces.len()
    );
    frame.render_widget(
        Table::new(rows, widths)
            .header(header)
            .column_spacing(1)
            .block(Block::bordered().title(title)),
        area,
    );
    if let (Mode::Cell(ed), Focus::Cell { row, col }) = (&app.mode, app.focus)
        && row >= app.scroll
        && row < app.scroll + visible
    {
        let left: u16 = Column::ALL[..col].iter().map(|c| c.width() + 1).sum();
        let x = area.x + 1 + ROW_LABEL + 1 + left + ed.caret as u16;
        let y = area.y + 2 + (row - app.scroll) as u16;
        frame.set_cursor_position((x, y));
    }
}
