//! The analysis panel (paraxial data) and the ghost list.

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, List, ListItem, ListState, Paragraph};

use crate::edit::app::App;
use crate::edit::cell::fmt_num;

pub(super) fn draw_analysis(frame: &mut Frame, app: &App, area: Rect) {
    let lines: Vec<Line> = match &app.analysis.paraxial {
        Ok(p) => {
            let open = if (p.f_number - p.open_f_number).abs() > 1e-9 {
                format!(" (open {:.2})", p.open_f_number)
            } else {
                String::new()
            };
            vec![
                Line::from(format!("EFL      {:>10} mm", fmt2(p.efl_mm))),
                Line::from(format!("BFL      {:>10} mm", fmt2(p.bfl_mm))),
                Line::from(format!(
                    "f-number {:>10}{open}",
                    format!("{:.2}", p.f_number)
                )),
                Line::from(format!(
                    "EP       {:>10} mm ⌀",
                    fmt2(p.entrance_pupil_diameter_mm)
                )),
                Line::from(format!("EP at    {:>10} mm", fmt2(p.entrance_pupil_z_mm))),
                Line::from(format!("track    {:>10} mm", fmt2(p.total_track_mm))),
                Line::from(format!("defocus  {:>10} mm", fmt2(p.focus_error_mm))),
                Line::from(format!("λ {} nm", fmt_num(p.wavelength_nm))),
            ]
        }
        Err(e) => vec![Line::styled(e.clone(), Style::new().fg(Color::Red))],
    };
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(" paraxial ")),
        area,
    );
}

fn fmt2(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "inf".into()
    }
}

pub(super) fn draw_ghosts(frame: &mut Frame, app: &App, area: Rect) {
    let ghosts = &app.analysis.ghosts;
    let items: Vec<ListItem> = ghosts
        .iter()
        .enumerate()
        .map(|(i, g)| ListItem::new(format!("{i:>3}  {g}")))
        .collect();
    let mut state = ListState::default().with_selected(app.ghost);
    let title = match app.ghost {
        Some(i) => format!(" ghosts {}/{} ", i + 1, ghosts.len()),
        None => format!(" ghosts ({}) ] [ ", ghosts.len()),
    };
    frame.render_stateful_widget(
        List::new(items)
            .block(Block::bordered().title(title))
            .highlight_style(
                Style::new()
                    .fg(Color::Magenta)
                    .add_modifier(Modifier::REVERSED),
            ),
        area,
        &mut state,
    );
}
