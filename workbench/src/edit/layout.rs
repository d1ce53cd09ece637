//! The editor's screen layout: its areas, how many table rows fit, and which header field or
//! table cell a screen position falls on ([`Focus`]). Shared by drawing (`view`) and by the
//! state's handling of clicks and scrolling (`app`), and depending on neither.

use ratatui::layout::{Constraint, Layout, Rect};

use super::cell::Column;

/// Where the selection is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Focus {
    /// A field of the header form (index into `HeaderField::ALL`).
    Header(usize),
    /// A cell of the surface table (surface, index into `Column::ALL`).
    Cell { row: usize, col: usize },
}

/// Width of the row-number column of the table.
pub(super) const ROW_LABEL: u16 = 3;
/// Width of each header field: name, then the numeric fields.
pub(super) const HEADER_WIDTHS: [u16; 4] = [40, 18, 16, 16];

/// The screen areas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Areas {
    pub title: Rect,
    pub header: Rect,
    pub table: Rect,
    pub analysis: Rect,
    pub ghosts: Rect,
    pub side: Rect,
    pub status: Rect,
}

/// Total width of the table with its borders.
fn table_width() -> u16 {
    let cols: u16 = Column::ALL.iter().map(|c| c.width() + 1).sum();
    ROW_LABEL + cols + 2
}

/// Splits the terminal area.
pub fn layout(area: Rect) -> Areas {
    let [title, header, body, status] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Length(1),
        Constraint::Min(0),
        Constraint::Length(1),
    ])
    .areas(area);
    let side_h = (body.height * 2 / 5).max(6).min(body.height);
    let [top, side] =
        Layout::vertical([Constraint::Min(0), Constraint::Length(side_h)]).areas(body);
    let [table, right] =
        Layout::horizontal([Constraint::Length(table_width()), Constraint::Min(0)]).areas(top);
    let [analysis, ghosts] =
        Layout::vertical([Constraint::Length(10), Constraint::Min(0)]).areas(right);
    Areas {
        title,
        header,
        table,
        analysis,
        ghosts,
        side,
        status,
    }
}

/// How many surface rows the table shows in a terminal of `size` (columns, rows).
pub fn table_rows(size: (u16, u16)) -> usize {
    let a = layout(Rect::new(0, 0, size.0, size.1));
    a.table.height.saturating_sub(3) as usize
}

/// The cell or header field at screen position (`x`, `y`) of a terminal of `size`, its table
/// scrolled by `scroll` rows and holding `surfaces` rows, if any.
pub fn hit_test(size: (u16, u16), scroll: usize, surfaces: usize, x: u16, y: u16) -> Option<Focus> {
    let a = layout(Rect::new(0, 0, size.0, size.1));
    if y == a.header.y {
        let mut left = a.header.x;
        for (i, w) in HEADER_WIDTHS.iter().enumerate() {
            if x >= left && x < left + w {
                return Some(Focus::Header(i));
            }
            left += w;
        }
        return None;
    }
    let first_row_y = a.table.y + 2;
    let rows = table_rows(size);
    if y < first_row_y || y >= first_row_y + rows as u16 {
        return None;
    }
    let row = scroll + (y - first_row_y) as usize;
    if row >= surfaces {
        return None;
    }
    let mut left = a.table.x + 1 + ROW_LABEL + 1;
    for (col, c) in Column::ALL.iter().enumerate() {
        if x >= left && x < left + c.width() {
            return Some(Focus::Cell { row, col });
        }
        left += c.width() + 1;
    }
    None
}
