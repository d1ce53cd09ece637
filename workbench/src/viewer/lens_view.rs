//! The lens view: the meridional section at true scale (glass filled and tinted by index,
//! profiles, stop and sensor), ray fans, the selected ghost's path, pan and zoom, and the
//! surface under the mouse. Geometry comes from [`crate::lens_drawing`]; this module only maps
//! millimetres to the screen and paints.

use egui::{Color32, Mesh, Pos2, Rect, Sense, Shape, Stroke, Ui, Vec2, pos2};

use crate::lens_drawing::{LensDrawing, RayEnd, RayFan};

/// The view's camera: which point (mm) is at the centre and how many mm a point spans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensCamera {
    pub center: [f64; 2],
    pub mm_per_point: f64,
}

impl LensCamera {
    /// The camera that shows `bounds` whole in `rect` with a margin.
    pub fn fit(drawing: &LensDrawing, rect: Rect) -> LensCamera {
        let b = &drawing.bounds;
        let w = (b.max[0] - b.min[0]).max(1e-3);
        let h = (b.max[1] - b.min[1]).max(1e-3);
        let s = (w / rect.width().max(1.0) as f64).max(h / rect.height().max(1.0) as f64) * 1.08;
        LensCamera {
            center: [0.5 * (b.min[0] + b.max[0]), 0.5 * (b.min[1] + b.max[1])],
            mm_per_point: s,
        }
    }

    /// Screen position of (z, y) mm in `rect` (y up on screen).
    pub fn to_screen(&self, rect: Rect, p: [f64; 2]) -> Pos2 {
        let c = rect.center();
        pos2(
            c.x + ((p[0] - self.center[0]) / self.mm_per_point) as f32,
            c.y - ((p[1] - self.center[1]) / self.mm_per_point) as f32,
        )
    }

    /// The point (z, y) mm at screen position `pos`.
    pub fn to_mm(&self, rect: Rect, pos: Pos2) -> [f64; 2] {
        let c = rect.center();
        [
            self.center[0] + (pos.x - c.x) as f64 * self.mm_per_point,
            self.center[1] - (pos.y - c.y) as f64 * self.mm_per_point,
        ]
    }

    /// Zooms by `factor` (> 1 zooms in) keeping the point under `pos` in place.
    pub fn zoom_about(&mut self, rect: Rect, pos: Pos2, factor: f64) {
        let before = self.to_mm(rect, pos);
        self.mm_per_point /= factor.clamp(0.01, 100.0);
        let after = self.to_mm(rect, pos);
        self.center[0] += before[0] - after[0];
        self.center[1] += before[1] - after[1];
    }

    /// Moves the view by a screen drag `delta` (points).
    pub fn pan(&mut self, delta: Vec2) {
        self.center[0] -= delta.x as f64 * self.mm_per_point;
        self.center[1] += delta.y as f64 * self.mm_per_point;
    }
}

/// What to draw besides the lens itself.
#[derive(Debug)]
pub struct LensOverlay<'a> {
    pub fans: &'a [RayFan],
    pub ghost: Option<&'a RayFan>,
    /// The editor's selected row (highlighted).
    pub selected_row: Option<usize>,
}

/// The result of drawing the lens view for one frame.
#[derive(Debug)]
pub struct LensViewResponse {
    /// Where the view is (points).
    pub rect: Rect,
    /// The row under the mouse, if any.
    pub hovered_row: Option<usize>,
    /// The row clicked.
    pub clicked_row: Option<usize>,
}

/// Colour of glass of index `n_d`: denser glass a deeper blue.
pub fn glass_tint(n_d: f64) -> Color32 {
    let t = ((n_d - 1.45) / 0.5).clamp(0.0, 1.0) as f32;
    let lerp = |a: f32, b: f32| (a + (b - a) * t).round() as u8;
    Color32::from_rgba_unmultiplied(
        lerp(170.0, 40.0),
        lerp(205.0, 90.0),
        lerp(235.0, 200.0),
        150,
    )
}

/// The colour of light of wavelength `nm` (a rough visible-spectrum ramp for drawing rays).
pub fn wavelength_colour(nm: f64) -> Color32 {
    let (r, g, b) = match nm {
        x if x < 440.0 => ((440.0 - x) / 60.0, 0.0, 1.0),
        x if x < 490.0 => (0.0, (x - 440.0) / 50.0, 1.0),
        x if x < 510.0 => (0.0, 1.0, (510.0 - x) / 20.0),
        x if x < 580.0 => ((x - 510.0) / 70.0, 1.0, 0.0),
        x if x < 645.0 => (1.0, (645.0 - x) / 65.0, 0.0),
        _ => (1.0, 0.0, 0.0),
    };
    let c = |v: f64| (v.clamp(0.0, 1.0) * 230.0) as u8;
    Color32::from_rgb(c(r), c(g), c(b))
}

const FIELD_COLOURS: [Color32; 3] = [
    Color32::from_rgb(240, 200, 40),
    Color32::from_rgb(60, 200, 90),
    Color32::from_rgb(230, 90, 60),
];
const GHOST_COLOUR: Color32 = Color32::from_rgb(230, 60, 220);
const LINE: Color32 = Color32::from_rgb(30, 30, 40);
const HIGHLIGHT: Color32 = Color32::from_rgb(255, 140, 0);

/// Draws the lens view into the space `ui` has, handling pan (drag), zoom (wheel) and the
/// surface under the mouse. `camera` is `None` until the first fit.
pub fn show(
    ui: &mut Ui,
    drawing: &LensDrawing,
    overlay: &LensOverlay<'_>,
    camera: &mut Option<LensCamera>,
) -> LensViewResponse {
    let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
    let cam = camera.get_or_insert_with(|| LensCamera::fit(drawing, rect));
    if response.dragged() {
        cam.pan(response.drag_delta());
    }
    if response.double_clicked() {
        *cam = LensCamera::fit(drawing, rect);
    }
    if let Some(pos) = response.hover_pos() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            cam.zoom_about(rect, pos, (scroll as f64 / 200.0).exp());
        }
    }
    let cam = *cam;
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::from_rgb(248, 248, 244));
    let to = |p: [f64; 2]| cam.to_screen(rect, p);

    // The axis.
    let b = &drawing.bounds;
    painter.line_segment(
        [to([b.min[0], 0.0]), to([b.max[0], 0.0])],
        Stroke::new(1.0, Color32::from_gray(170)),
    );

    // Glass.
    for e in &drawing.elements {
        let mut mesh = Mesh::default();
        let tint = glass_tint(e.n_d);
        for p in &e.outline {
            mesh.colored_vertex(to(*p), tint);
        }
        for t in &e.triangles {
            mesh.add_triangle(t[0], t[1], t[2]);
        }
        painter.add(Shape::mesh(mesh));
        let mut closed: Vec<Pos2> = e.outline.iter().map(|p| to(*p)).collect();
        if let Some(&first) = closed.first() {
            closed.push(first);
        }
        painter.add(Shape::line(closed, Stroke::new(1.0, LINE)));
    }

    let hovered_row = response.hover_pos().and_then(|pos| {
        let [z, y] = cam.to_mm(rect, pos);
        drawing.surface_at(z, y, 6.0 * cam.mm_per_point)
    });
    let emphasis = |row: usize| {
        if Some(row) == overlay.selected_row {
            Stroke::new(3.0, HIGHLIGHT)
        } else if Some(row) == hovered_row {
            Stroke::new(2.5, Color32::from_rgb(0, 120, 220))
        } else {
            Stroke::new(1.2, LINE)
        }
    };
    // Stop and sensor rows are drawn by their marks below.
    for s in drawing
        .surfaces
        .iter()
        .filter(|s| s.kind == flarebench_sdk::SurfaceKind::Refracting)
    {
        let pts: Vec<Pos2> = s.points.iter().map(|p| to(*p)).collect();
        painter.add(Shape::line(pts, emphasis(s.row)));
    }
    if let Some(stop) = &drawing.stop {
        let st = emphasis(stop.row);
        let st = Stroke::new(st.width + 1.0, st.color);
        for sign in [1.0, -1.0] {
            painter.line_segment(
                [
                    to([stop.z, sign * stop.opening]),
                    to([stop.z, sign * stop.outer]),
                ],
                st,
            );
        }
    }
    let sensor = &drawing.sensor;
    let st = emphasis(sensor.row);
    painter.line_segment(
        [
            to([sensor.z, -sensor.half_height]),
            to([sensor.z, sensor.half_height]),
        ],
        Stroke::new(st.width + 1.5, st.color),
    );

    // Rays: per field a colour, or per wavelength when fans of several wavelengths are shown.
    let several_wavelengths = overlay
        .fans
        .windows(2)
        .any(|w| w[0].wavelength_nm != w[1].wavelength_nm);
    let mut fields: Vec<f64> = Vec::new();
    for fan in overlay.fans {
        let k = fields
            .iter()
            .position(|f| *f == fan.field_deg)
            .unwrap_or_else(|| {
                fields.push(fan.field_deg);
                fields.len() - 1
            });
        let colour = if several_wavelengths {
            wavelength_colour(fan.wavelength_nm)
        } else {
            FIELD_COLOURS[k % FIELD_COLOURS.len()]
        };
        draw_fan(&painter, fan, colour, &to);
    }
    if let Some(g) = overlay.ghost {
        draw_fan(&painter, g, GHOST_COLOUR, &to);
    }

    if let Some(row) = hovered_row {
        response
            .clone()
            .on_hover_text_at_pointer(format!("surface row {row}"));
    }
    LensViewResponse {
        rect,
        hovered_row,
        clicked_row: if response.clicked() {
            hovered_row
        } else {
            None
        },
    }
}

fn draw_fan(painter: &egui::Painter, fan: &RayFan, colour: Color32, to: &dyn Fn([f64; 2]) -> Pos2) {
    for ray in &fan.rays {
        let pts: Vec<Pos2> = ray.points.iter().map(|p| to(*p)).collect();
        let Some(&end) = pts.last() else { continue };
        painter.add(Shape::line(pts, Stroke::new(1.0, colour)));
        // Where a ray is stopped: a cross (vignetted, missed) or a ring (totally reflected).
        match ray.end {
            RayEnd::Sensor => {}
            RayEnd::Vignetted { .. } | RayEnd::Missed { .. } => {
                let d = 3.0;
                let s = Stroke::new(1.2, colour);
                painter.line_segment([end + egui::vec2(-d, -d), end + egui::vec2(d, d)], s);
                painter.line_segment([end + egui::vec2(-d, d), end + egui::vec2(d, -d)], s);
            }
            RayEnd::TotalInternalReflection { .. } => {
                painter.circle_stroke(end, 3.5, Stroke::new(1.2, colour));
            }
        }
    }
}
