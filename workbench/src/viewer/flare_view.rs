//! The flare view: the newest frame fitted into the panel, a drag to move the first light, the
//! wheel for exposure, a click to select the ghost under the mouse, ghost labels, and the
//! selected ghost's debug view ([`super::debug_view`]).

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Ui, pos2, vec2};
use flarebench_sdk::ghost::GhostPath;

use flarebench_sdk::LensSystem;

use super::debug_view::{DebugState, DebugView};
use super::flare_worker::{FlareFrame, GhostFootprint};

/// What the user did in the flare view this pass.
#[derive(Clone, Debug, PartialEq)]
pub enum FlareAction {
    None,
    /// Drag: the first light moves to the direction imaged at the mouse.
    MoveLight {
        theta: f64,
        phi: f64,
    },
    /// Wheel: exposure offset change (stops).
    Exposure(f32),
    SelectGhost(GhostPath),
}

/// The largest rectangle of aspect `w:h` centred in `area`.
pub fn fit_rect(area: Rect, w: usize, h: usize) -> Rect {
    let aspect = w as f32 / h.max(1) as f32;
    let (mut rw, mut rh) = (area.width(), area.width() / aspect);
    if rh > area.height() {
        rh = area.height();
        rw = rh * aspect;
    }
    Rect::from_center_size(area.center(), vec2(rw, rh))
}

/// Pixel coordinates in the rendered image of screen position `pos` in `image` (drawn at
/// `rect`).
pub fn to_pixel(rect: Rect, width: usize, height: usize, pos: Pos2) -> [f64; 2] {
    [
        ((pos.x - rect.min.x) / rect.width()) as f64 * width as f64,
        ((pos.y - rect.min.y) / rect.height()) as f64 * height as f64,
    ]
}

/// The ghost under pixel `px` of `frame`: of the ghosts whose landing rectangle holds the
/// point, the one with the most energy per area (the brightest there).
pub fn ghost_at(frame: &FlareFrame, film: [f64; 2], px: [f64; 2]) -> Option<&GhostFootprint> {
    let (w, h) = (frame.hdr.width as f64, frame.hdr.height as f64);
    // Photograph orientation (sdk::frame): pixel → sensor millimetres.
    let x = (0.5 - px[0] / w) * film[0];
    let y = (px[1] / h - 0.5) * film[1];
    frame
        .ghosts
        .iter()
        .filter(|g| {
            // Into the ghost's meridional frame (the inverse of its rotation by φ).
            let (s, c) = g.phi.sin_cos();
            let (mx, my) = (x * c + y * s, -x * s + y * c);
            let [x0, y0, x1, y1] = g.rect;
            (x0..=x1).contains(&mx) && (y0..=y1).contains(&my)
        })
        .max_by(|a, b| density(a).total_cmp(&density(b)))
}

fn density(g: &GhostFootprint) -> f64 {
    let [x0, y0, x1, y1] = g.rect;
    g.energy_share / ((x1 - x0) * (y1 - y0)).max(1e-12)
}

/// What the flare view draws.
#[derive(Clone, Copy)]
pub struct FlareViewState<'a> {
    pub system: &'a LensSystem,
    /// The scene's image size (pixels).
    pub width: usize,
    pub height: usize,
    /// The shown frame and its image uploaded (`None` before the first frame).
    pub texture: Option<&'a egui::TextureHandle>,
    pub shown: Option<&'a FlareFrame>,
    pub selected_ghost: Option<GhostPath>,
    /// Label every ghost, not only the selected one.
    pub labels: bool,
    pub debug_view: DebugView,
    pub debug_state: DebugState<'a>,
}

impl std::fmt::Debug for FlareViewState<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FlareViewState")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("selected_ghost", &self.selected_ghost)
            .field("labels", &self.labels)
            .field("debug_view", &self.debug_view)
            .finish_non_exhaustive()
    }
}

/// Draws the flare view; returns where it is (points) and what the user did.
pub fn show(ui: &mut Ui, viewer: FlareViewState<'_>) -> (Rect, FlareAction) {
    let area = ui.available_rect_before_wrap();
    let (w, h) = (viewer.width, viewer.height);
    let rect = fit_rect(area, w, h);
    let response = ui.allocate_rect(rect, Sense::click_and_drag());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::BLACK);
    match (viewer.texture, viewer.shown) {
        (Some(tex), Some(_)) => {
            painter.image(
                tex.id(),
                rect,
                Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        _ => {
            painter.text(
                rect.center(),
                Align2::CENTER_CENTER,
                "rendering…",
                FontId::proportional(16.0),
                Color32::GRAY,
            );
        }
    }
    let system = viewer.system;
    let film = [
        system.film_width_mm,
        system.film_width_mm * h as f64 / w as f64,
    ];
    if let Some(frame) = viewer.shown {
        draw_labels(
            &painter,
            rect,
            frame,
            film,
            viewer.selected_ghost,
            viewer.labels,
        );
    }
    super::debug_view::draw(&painter, rect, viewer.debug_view, viewer.debug_state);

    let mut action = FlareAction::None;
    if response.hovered() {
        let stops = ui.input(|i| i.events.iter().map(wheel_stops).sum::<f32>());
        if stops != 0.0 {
            action = FlareAction::Exposure(stops);
        }
    }
    if (response.dragged() || response.drag_stopped())
        && let Some(pos) = response.interact_pointer_pos()
    {
        let px = to_pixel(rect, w, h, pos);
        let frame = super::flare_worker::view_frame(system, w, h);
        if let Ok((theta, phi)) = crate::sources::direction_of(system, &frame, px[0], px[1]) {
            action = FlareAction::MoveLight { theta, phi };
        }
    } else if response.clicked()
        && let (Some(pos), Some(frame)) = (response.interact_pointer_pos(), viewer.shown)
        && let Some(g) = ghost_at(frame, film, to_pixel(rect, w, h, pos))
    {
        action = FlareAction::SelectGhost(g.path);
    }
    (rect, action)
}

/// Exposure change (stops) of a wheel event: half a stop per notch (a line), two per page,
/// one per 100 points of a touchpad's scroll.
pub fn wheel_stops(e: &egui::Event) -> f32 {
    match e {
        egui::Event::MouseWheel { unit, delta, .. } => match unit {
            egui::MouseWheelUnit::Line => 0.5 * delta.y,
            egui::MouseWheelUnit::Page => 2.0 * delta.y,
            egui::MouseWheelUnit::Point => delta.y / 100.0,
        },
        _ => 0.0,
    }
}

/// Each ghost's name at the centre of where it lands (only the selected one's unless `all`);
/// the selected one outlined.
fn draw_labels(
    painter: &egui::Painter,
    rect: Rect,
    frame: &FlareFrame,
    film: [f64; 2],
    selected: Option<GhostPath>,
    all: bool,
) {
    let (w, h) = (frame.hdr.width as f64, frame.hdr.height as f64);
    let to_screen = |x: f64, y: f64| {
        let px = (0.5 - x / film[0]) * w;
        let py = (0.5 + y / film[1]) * h;
        pos2(
            rect.min.x + (px / w) as f32 * rect.width(),
            rect.min.y + (py / h) as f32 * rect.height(),
        )
    };
    for g in &frame.ghosts {
        let is_selected = Some(g.path) == selected;
        if !all && !is_selected {
            continue;
        }
        let [x0, y0, x1, y1] = g.rect;
        let (s, c) = g.phi.sin_cos();
        let rot = |x: f64, y: f64| to_screen(x * c - y * s, x * s + y * c);
        let centre = rot(0.5 * (x0 + x1), 0.5 * (y0 + y1));
        if is_selected {
            let corners = [
                rot(x0, y0),
                rot(x1, y0),
                rot(x1, y1),
                rot(x0, y1),
                rot(x0, y0),
            ];
            painter.add(egui::Shape::line(
                corners.to_vec(),
                Stroke::new(1.5, Color32::from_rgb(230, 60, 220)),
            ));
        }
        painter.text(
            centre,
            Align2::CENTER_CENTER,
            g.path.to_string(),
            FontId::monospace(11.0),
            if is_selected {
                Color32::from_rgb(255, 120, 240)
            } else {
                Color32::from_rgba_unmultiplied(255, 255, 255, 170)
            },
        );
    }
}
