//! The side view: the lens in its meridional section (surfaces, element edges, stop, sensor)
//! with the axial and field ray fans, and the selected ghost's ray path in another colour.

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::widgets::Block;
use ratatui::widgets::canvas::{Canvas, Context, Line as CanvasLine};

use crate::edit::app::App;

pub(super) fn draw(frame: &mut Frame, app: &App, area: Rect) {
    let a = &app.analysis;
    let (z0, z1) = a.z_range;
    let h = a.half_height;
    let title = match app.ghost {
        Some(g) => format!(
            " side view — rays: axial (yellow), {:.1}° (cyan), ghost {} (magenta) ",
            a.field_deg, a.ghosts[g]
        ),
        None => format!(
            " side view — rays: axial (yellow), {:.1}° (cyan) ",
            a.field_deg
        ),
    };
    let canvas = Canvas::default()
        .block(Block::bordered().title(title))
        .marker(Marker::Braille)
        .x_bounds([z0, z1])
        .y_bounds([-h, h])
        .paint(|ctx| {
            polyline(ctx, &[(z0, 0.0), (z1, 0.0)], Color::DarkGray);
            for l in &a.edges {
                polyline(ctx, l, Color::Gray);
            }
            for l in &a.surfaces {
                polyline(ctx, l, Color::White);
            }
            ctx.layer();
            for l in &a.axial_rays {
                polyline(ctx, l, Color::Yellow);
            }
            for l in &a.field_rays {
                polyline(ctx, l, Color::Cyan);
            }
            ctx.layer();
            for l in &app.ghost_rays {
                polyline(ctx, l, Color::Magenta);
            }
        });
    frame.render_widget(canvas, area);
}

fn polyline(ctx: &mut Context, points: &[(f64, f64)], color: Color) {
    for w in points.windows(2) {
        ctx.draw(&CanvasLine {
            x1: w[0].0,
            y1: w[0].1,
            x2: w[1].0,
            y2: w[1].1,
            color,
        });
    }
}
