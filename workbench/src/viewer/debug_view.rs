//! The debug views of the selected ghost (`D` cycles them), drawn over the flare view from the
//! frame's [`GhostDebug`]:
//!
//! - **grid**: an inset plot of the entrance plane — the ghost's entrance rectangle, its grid
//!   of rays coloured by their fate, the front element's rim;
//! - **stop**: an inset plot of the aperture stop — where each ray crosses it, with the stop's
//!   outline (circle or iris) at its working radius;
//! - **relative radius**: the ghost's triangles over the flare, each corner coloured by its
//!   ray's relative radius (0 on the axis, 1 at the edge that clips, > 1 clipped: grey);
//! - **irradiance**: the triangles coloured by their irradiance relative to the ghost's
//!   brightest, on a log scale.
//!
//! Colours come from one false-colour ramp ([`false_colour`], viridis: dark to light, its
//! lightness rising evenly), with a legend giving the range and units.

use egui::{
    Align2, Color32, FontId, Mesh, Painter, Pos2, Rect, Shape, Stroke, StrokeKind, pos2, vec2,
};

use super::ghost_debug::{GhostDebug, RayFate};

/// The debug view shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DebugView {
    #[default]
    Off,
    /// The entrance plane: rectangle and ray grid.
    Grid,
    /// The aperture stop: where the rays cross it.
    Stop,
    /// The triangles coloured by relative radius.
    RelativeRadius,
    /// The triangles coloured by irradiance.
    Irradiance,
}

impl DebugView {
    /// The next view in `D`'s cycle: off → grid → stop → relative radius → irradiance → off.
    pub fn next(self) -> DebugView {
        match self {
            DebugView::Off => DebugView::Grid,
            DebugView::Grid => DebugView::Stop,
            DebugView::Stop => DebugView::RelativeRadius,
            DebugView::RelativeRadius => DebugView::Irradiance,
            DebugView::Irradiance => DebugView::Off,
        }
    }

    /// The view's name, for the status line and the log.
    pub fn name(self) -> &'static str {
        match self {
            DebugView::Off => "off",
            DebugView::Grid => "grid",
            DebugView::Stop => "stop",
            DebugView::RelativeRadius => "relative radius",
            DebugView::Irradiance => "irradiance",
        }
    }
}

/// Viridis (matplotlib's) at 0, 1/8, …, 1.
const VIRIDIS: [[u8; 3]; 9] = [
    [68, 1, 84],
    [72, 40, 120],
    [62, 73, 137],
    [49, 104, 142],
    [38, 130, 142],
    [31, 158, 137],
    [53, 183, 121],
    [110, 206, 88],
    [253, 231, 37],
];

/// The colour of a relative radius beyond 1 (clipped): grey, not on the ramp.
pub const CLIPPED: Color32 = Color32::from_rgb(128, 128, 128);

/// The false colour of `t` in 0..=1 (viridis, interpolated linearly between its control
/// points); values outside are clamped to the ends, NaN takes the low end.
pub fn false_colour(t: f32) -> Color32 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |c: usize| (a[c] as f32 + (b[c] as f32 - a[c] as f32) * f).round() as u8;
    Color32::from_rgb(mix(0), mix(1), mix(2))
}

/// The irradiance view's scale: logarithmic, from `max / 10^decades` (the ramp's low end,
/// and everything dimmer) to `max` (its high end).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceScale {
    pub max: f32,
    pub decades: f32,
}

impl IrradianceScale {
    /// Fewest decades a scale spans (a factor of 2): a ghost of nearly even irradiance is not
    /// stretched over the whole ramp.
    pub const MIN_DECADES: f32 = std::f32::consts::LOG10_2;
    /// Most decades a scale spans: dimmer triangles take the low end.
    pub const MAX_DECADES: f32 = 4.0;
    /// The share of the dimmest values the low end may leave below it (a few stretched edge
    /// triangles do not flatten the rest).
    pub const LOW_PERCENTILE: f64 = 0.02;

    /// The scale of `values` (the lit triangles' irradiances): up to the largest, down to the
    /// [`Self::LOW_PERCENTILE`] one, within [`Self::MIN_DECADES`] and [`Self::MAX_DECADES`];
    /// `None` without a positive finite value.
    pub fn of(values: impl Iterator<Item = f32>) -> Option<IrradianceScale> {
        let mut v: Vec<f32> = values.filter(|v| v.is_finite() && *v > 0.0).collect();
        v.sort_by(f32::total_cmp);
        let max = *v.last()?;
        let low = v[(Self::LOW_PERCENTILE * (v.len() - 1) as f64) as usize];
        let decades = (max / low)
            .log10()
            .clamp(Self::MIN_DECADES, Self::MAX_DECADES);
        Some(IrradianceScale { max, decades })
    }

    /// Where `value` falls on the ramp: 1 at `max`, 0 at `max / 10^decades` and below (and for
    /// values that are not positive).
    pub fn position(&self, value: f32) -> f32 {
        if !(value > 0.0 && self.max > 0.0) {
            return 0.0;
        }
        (1.0 + (value / self.max).log10() / self.decades).clamp(0.0, 1.0)
    }

    /// The value over `max` at ramp position `t` (the inverse of [`Self::position`]).
    pub fn ratio_at(&self, t: f32) -> f32 {
        10f32.powf(-self.decades * (1.0 - t))
    }
}

/// The colour of relative radius `r`: the ramp over 0..=1, [`CLIPPED`] beyond.
pub fn relative_radius_colour(r: f32) -> Color32 {
    if r > 1.0 { CLIPPED } else { false_colour(r) }
}

const PANEL_FILL: Color32 = Color32::from_rgba_premultiplied(10, 10, 14, 225);
const FRAME_STROKE: Color32 = Color32::from_gray(150);
const AXIS: Color32 = Color32::from_gray(90);
const TEXT: Color32 = Color32::from_gray(220);

/// The colour of a ray of this fate in the inset plots.
pub fn fate_colour(f: RayFate) -> Color32 {
    match f {
        RayFate::Passes => Color32::from_rgb(90, 210, 120),
        RayFate::ClippedAtStop => Color32::from_rgb(245, 160, 40),
        RayFate::ClippedElsewhere => Color32::from_rgb(110, 150, 255),
        RayFate::Stopped => Color32::from_rgb(215, 60, 60),
    }
}

/// What to draw when the view is on: the debug data for the selected ghost, or why there is
/// none (yet).
#[derive(Clone, Copy, Debug)]
pub enum DebugState<'a> {
    Ready(&'a GhostDebug),
    /// A note: no ghost selected, still tracing, or the ghost is not drawn.
    Note(&'a str),
}

/// Draws `view` of `state` over the flare image drawn at `rect` (the image is
/// `debug.image_size` pixels).
pub fn draw(painter: &Painter, rect: Rect, view: DebugView, state: DebugState<'_>) {
    if view == DebugView::Off {
        return;
    }
    let d = match state {
        DebugState::Ready(d) => d,
        DebugState::Note(note) => {
            caption(
                painter,
                rect,
                &format!("debug view {}: {note}", view.name()),
            );
            return;
        }
    };
    match view {
        DebugView::Off => {}
        DebugView::Grid => entrance_plot(painter, inset_rect(rect), d),
        DebugView::Stop => stop_plot(painter, inset_rect(rect), d),
        DebugView::RelativeRadius => {
            triangles(painter, rect, d, false);
            legend_relative_radius(painter, legend_rect(rect));
        }
        DebugView::Irradiance => {
            triangles(painter, rect, d, true);
            legend_irradiance(painter, legend_rect(rect), d);
        }
    }
    caption(
        painter,
        rect,
        &format!(
            "debug view {}: ghost {} at {:.1}°,{:.1}°, {:.0} nm, {}×{} grid{}",
            view.name(),
            d.path,
            d.theta_deg,
            d.phi_deg,
            d.lambda_nm,
            d.n,
            d.n,
            if d.downscale > 1 {
                format!(", drawn at 1/{} resolution", d.downscale)
            } else {
                String::new()
            }
        ),
    );
}

/// A line of text at the top left of the flare view, on a dark band.
fn caption(painter: &Painter, rect: Rect, text: &str) {
    let galley = painter.layout_no_wrap(text.to_string(), FontId::proportional(12.0), TEXT);
    let at = rect.min + vec2(6.0, 6.0);
    let bg = Rect::from_min_size(at, galley.size()).expand(3.0);
    painter.rect_filled(bg, 2.0, PANEL_FILL);
    painter.galley(at, galley, TEXT);
}

/// The inset plots' square in the flare view's bottom-left corner.
fn inset_rect(rect: Rect) -> Rect {
    let side = (rect.height() * 0.62)
        .min(rect.width() * 0.45)
        .clamp(120.0, 300.0);
    Rect::from_min_size(
        pos2(rect.min.x + 8.0, rect.max.y - side - 8.0),
        vec2(side, side),
    )
}

/// The legend's strip in the flare view's bottom-right corner.
fn legend_rect(rect: Rect) -> Rect {
    let w = (rect.width() * 0.45).clamp(200.0, 320.0);
    Rect::from_min_size(pos2(rect.max.x - w - 8.0, rect.max.y - 70.0), vec2(w, 62.0))
}

/// Two lines of a legend's title at the top of `area`.
fn legend_title(painter: &Painter, area: Rect, lines: [&str; 2]) {
    for (k, line) in lines.iter().enumerate() {
        painter.text(
            area.min + vec2(6.0, 3.0 + 11.0 * k as f32),
            Align2::LEFT_TOP,
            *line,
            FontId::proportional(9.5),
            TEXT,
        );
    }
}

/// The colour bar's place in a legend.
fn legend_bar(area: Rect, right_margin: f32) -> Rect {
    Rect::from_min_max(
        area.min + vec2(8.0, 28.0),
        pos2(area.max.x - right_margin, area.min.y + 42.0),
    )
}

/// An inset plot: a square of millimetres `[x0, x1] × [y0, y1]` (equal scales, y up) in
/// `area` below a title, with axes through 0 and the extents labelled. Returns the map from
/// millimetres to the screen and the plot's rectangle.
fn plot_frame(
    painter: &Painter,
    area: Rect,
    title: &str,
    centre: [f64; 2],
    half: f64,
) -> (impl Fn([f64; 2]) -> Pos2 + use<>, Rect) {
    painter.rect_filled(area, 3.0, PANEL_FILL);
    painter.text(
        area.min + vec2(6.0, 4.0),
        Align2::LEFT_TOP,
        title,
        FontId::proportional(10.0),
        TEXT,
    );
    let plot = Rect::from_min_max(area.min + vec2(34.0, 20.0), area.max - vec2(8.0, 46.0));
    let side = plot.width().min(plot.height());
    let plot = Rect::from_center_size(plot.center(), vec2(side, side));
    let scale = side as f64 / (2.0 * half);
    let c = plot.center();
    let to = move |[x, y]: [f64; 2]| {
        pos2(
            c.x + ((x - centre[0]) * scale) as f32,
            c.y - ((y - centre[1]) * scale) as f32,
        )
    };
    painter.rect_stroke(
        plot,
        0.0,
        Stroke::new(1.0, FRAME_STROKE),
        StrokeKind::Outside,
    );
    let inner = painter.with_clip_rect(plot);
    let (x0, x1) = (centre[0] - half, centre[0] + half);
    let (y0, y1) = (centre[1] - half, centre[1] + half);
    if (x0..=x1).contains(&0.0) {
        inner.line_segment([to([0.0, y0]), to([0.0, y1])], Stroke::new(1.0, AXIS));
    }
    if (y0..=y1).contains(&0.0) {
        inner.line_segment([to([x0, 0.0]), to([x1, 0.0])], Stroke::new(1.0, AXIS));
    }
    let font = FontId::monospace(9.0);
    let label = |at: Pos2, align: Align2, v: f64| {
        painter.text(at, align, format!("{v:.2}"), font.clone(), TEXT);
    };
    label(plot.left_bottom() + vec2(0.0, 2.0), Align2::LEFT_TOP, x0);
    label(plot.right_bottom() + vec2(0.0, 2.0), Align2::RIGHT_TOP, x1);
    label(
        plot.left_bottom() - vec2(3.0, 0.0),
        Align2::RIGHT_BOTTOM,
        y0,
    );
    label(plot.left_top() - vec2(3.0, 0.0), Align2::RIGHT_TOP, y1);
    painter.text(
        plot.center_bottom() + vec2(0.0, 2.0),
        Align2::CENTER_TOP,
        "x mm",
        font.clone(),
        TEXT,
    );
    painter.text(
        plot.left_center() - vec2(3.0, 0.0),
        Align2::RIGHT_CENTER,
        "y mm",
        font,
        TEXT,
    );
    (to, plot)
}

/// Square markers of side `size` at `points` in `colour`, as one mesh.
fn markers(painter: &Painter, points: impl Iterator<Item = (Pos2, Color32)>, size: f32) {
    let mut mesh = Mesh::default();
    for (p, colour) in points {
        mesh.add_colored_rect(Rect::from_center_size(p, vec2(size, size)), colour);
    }
    painter.add(Shape::mesh(mesh));
}

/// The counts of each fate as a legend under the plot, two to a row.
fn fate_legend(painter: &Painter, area: Rect, d: &GhostDebug, fates: &[RayFate]) {
    let counts = d.fate_counts();
    for (k, &f) in fates.iter().enumerate() {
        let name = match f {
            RayFate::Passes => "pass",
            RayFate::ClippedAtStop => "clipped at stop",
            RayFate::ClippedElsewhere => "clipped elsewhere",
            RayFate::Stopped => "stopped",
        };
        let x = area.min.x + 6.0 + (k % 2) as f32 * 0.5 * area.width();
        let y = area.max.y - 20.0 + (k / 2) as f32 * 12.0;
        painter.rect_filled(
            Rect::from_center_size(pos2(x + 3.0, y), vec2(6.0, 6.0)),
            0.0,
            fate_colour(f),
        );
        painter.text(
            pos2(x + 9.0, y),
            Align2::LEFT_CENTER,
            format!("{} {name}", counts[f as usize]),
            FontId::proportional(9.0),
            TEXT,
        );
    }
}

/// (a) The entrance plane: the ghost's rectangle, its grid rays by fate, the front rim.
fn entrance_plot(painter: &Painter, area: Rect, d: &GhostDebug) {
    let e = d.entrance;
    let half = 0.5 * e.width().max(e.height()) * 1.15;
    let centre = [0.5 * (e.x0 + e.x1), 0.5 * (e.y0 + e.y1)];
    let (to, plot) = plot_frame(
        painter,
        area,
        "entrance plane (light's meridional frame)",
        centre,
        half.max(1e-6),
    );
    let inner = painter.with_clip_rect(plot);
    let scale = plot.width() as f64 / (2.0 * half);
    inner.circle_stroke(
        to([0.0, 0.0]),
        (d.front_semi_diameter * scale) as f32,
        Stroke::new(1.0, Color32::from_rgb(120, 170, 220)),
    );
    inner.rect_stroke(
        Rect::from_two_pos(to([e.x0, e.y0]), to([e.x1, e.y1])),
        0.0,
        Stroke::new(1.0, Color32::WHITE),
        StrokeKind::Middle,
    );
    let size = (plot.width() / d.n as f32 * 0.55).clamp(1.0, 4.0);
    markers(
        &inner,
        d.rays.iter().map(|r| (to(r.entrance), fate_colour(r.fate))),
        size,
    );
    fate_legend(
        painter,
        area,
        d,
        &[
            RayFate::Passes,
            RayFate::ClippedAtStop,
            RayFate::ClippedElsewhere,
            RayFate::Stopped,
        ],
    );
}

/// The aperture's outline (unit circle = the working radius), found along 360 directions
/// by bisecting its signed distance.
fn aperture_outline(d: &GhostDebug) -> Vec<[f64; 2]> {
    let sampler = d.aperture.sampler();
    (0..360)
        .map(|k| {
            let a = (k as f64).to_radians();
            let (s, c) = a.sin_cos();
            let inside = |r: f64| sampler.signed_distance((r * c) as f32, (r * s) as f32) <= 0.0;
            let (mut lo, mut hi) = (0.0, 1.5);
            if inside(hi) {
                lo = hi;
            }
            for _ in 0..30 {
                let m = 0.5 * (lo + hi);
                if inside(m) {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            [lo * c * d.stop_radius, lo * s * d.stop_radius]
        })
        .collect()
}

/// (b) The aperture stop: where the rays that reach it cross it, and its outline.
fn stop_plot(painter: &Painter, area: Rect, d: &GhostDebug) {
    let reached: Vec<_> = d
        .rays
        .iter()
        .filter(|r| r.fate != RayFate::Stopped)
        .collect();
    let far = reached
        .iter()
        .map(|r| r.stop[0].abs().max(r.stop[1].abs()))
        .fold(0.0, f64::max);
    let half = (far * 1.05).clamp(1.2 * d.stop_radius, 2.5 * d.stop_radius);
    let (to, plot) = plot_frame(
        painter,
        area,
        &format!("stop crossings (lens frame), r = {:.2} mm", d.stop_radius),
        [0.0, 0.0],
        half.max(1e-6),
    );
    let inner = painter.with_clip_rect(plot);
    let size = (plot.width() / d.n as f32 * 0.55).clamp(1.0, 4.0);
    markers(
        &inner,
        reached.iter().map(|r| (to(r.stop), fate_colour(r.fate))),
        size,
    );
    let mut outline: Vec<Pos2> = aperture_outline(d).into_iter().map(&to).collect();
    outline.push(outline[0]);
    inner.add(Shape::line(outline, Stroke::new(1.5, Color32::WHITE)));
    let beyond = reached
        .iter()
        .filter(|r| r.stop[0].abs().max(r.stop[1].abs()) > half)
        .count();
    if beyond > 0 {
        painter.text(
            plot.right_top() + vec2(-3.0, 3.0),
            Align2::RIGHT_TOP,
            format!("{beyond} beyond the plot"),
            FontId::proportional(9.5),
            TEXT,
        );
    }
    fate_legend(
        painter,
        area,
        d,
        &[
            RayFate::Passes,
            RayFate::ClippedAtStop,
            RayFate::ClippedElsewhere,
        ],
    );
}

/// The irradiance view's scale for `d`'s lit triangles.
pub fn irradiance_scale(d: &GhostDebug) -> Option<IrradianceScale> {
    IrradianceScale::of(d.triangles.iter().filter(|t| t.lit()).map(|t| t.irradiance))
}

/// (c), (d) The ghost's triangles over the image at `rect`, each in one colour: by irradiance
/// (lit triangles only, the brightest drawn last) or by relative radius (its corners' largest:
/// ≤ 1 when all of it is inside every aperture).
fn triangles(painter: &Painter, rect: Rect, d: &GhostDebug, irradiance: bool) {
    let (w, h) = (d.image_size.0 as f32, d.image_size.1 as f32);
    let to = |p: [f32; 2]| {
        pos2(
            rect.min.x + p[0] / w * rect.width(),
            rect.min.y + p[1] / h * rect.height(),
        )
    };
    let mut mesh = Mesh::default();
    let mut add = |t: &super::ghost_debug::DebugTriangle, colours: [Color32; 3]| {
        let base = mesh.vertices.len() as u32;
        for (p, c) in t.pixels.iter().zip(colours) {
            mesh.colored_vertex(to(*p), c);
        }
        mesh.add_triangle(base, base + 1, base + 2);
    };
    if irradiance {
        let Some(scale) = irradiance_scale(d) else {
            return;
        };
        let mut lit: Vec<_> = d.triangles.iter().filter(|t| t.lit()).collect();
        lit.sort_by(|a, b| a.irradiance.total_cmp(&b.irradiance));
        for t in lit {
            add(t, [false_colour(scale.position(t.irradiance)); 3]);
        }
    } else {
        for t in &d.triangles {
            add(t, [relative_radius_colour(t.max_relative_radius()); 3]);
        }
    }
    painter.add(Shape::mesh(mesh));
}

/// A horizontal colour bar in `bar` of the ramp.
fn colour_bar(painter: &Painter, bar: Rect) {
    let mut mesh = Mesh::default();
    let steps = 64;
    for k in 0..steps {
        let (t0, t1) = (k as f32 / steps as f32, (k + 1) as f32 / steps as f32);
        let r = Rect::from_min_max(
            pos2(bar.min.x + t0 * bar.width(), bar.min.y),
            pos2(bar.min.x + t1 * bar.width(), bar.max.y),
        );
        mesh.add_colored_rect(r, false_colour(0.5 * (t0 + t1)));
    }
    painter.add(Shape::mesh(mesh));
    painter.rect_stroke(
        bar,
        0.0,
        Stroke::new(1.0, FRAME_STROKE),
        StrokeKind::Outside,
    );
}

/// The legend of the relative-radius view: 0 … 1 on the ramp, > 1 grey.
fn legend_relative_radius(painter: &Painter, area: Rect) {
    painter.rect_filled(area, 3.0, PANEL_FILL);
    legend_title(
        painter,
        area,
        [
            "relative radius: r / clear radius, largest on the path",
            "0 on the axis, 1 at the edge that clips",
        ],
    );
    let bar = legend_bar(area, 70.0);
    colour_bar(painter, bar);
    let font = FontId::monospace(9.0);
    for v in [0.0f32, 0.5, 1.0] {
        let x = bar.min.x + v * bar.width();
        painter.text(
            pos2(x, bar.max.y + 2.0),
            Align2::CENTER_TOP,
            format!("{v:.1}"),
            font.clone(),
            TEXT,
        );
    }
    let swatch = Rect::from_min_size(pos2(bar.max.x + 8.0, bar.min.y), vec2(14.0, bar.height()));
    painter.rect_filled(swatch, 0.0, CLIPPED);
    painter.text(
        pos2(swatch.max.x + 3.0, swatch.center().y),
        Align2::LEFT_CENTER,
        "> 1\nclipped",
        FontId::proportional(9.0),
        TEXT,
    );
}

/// A ratio to the maximum for a tick label: two decimals down to 0.1, then in powers of ten.
fn ratio_label(r: f32) -> String {
    if r >= 0.095 {
        format!("{r:.2}")
    } else {
        format!("{r:.0e}")
    }
}

/// The legend of the irradiance view: the log ramp from the scale's low end to the ghost's
/// brightest triangle, ticks as ratios to it, and its value in the image's units.
fn legend_irradiance(painter: &Painter, area: Rect, d: &GhostDebug) {
    let Some(scale) = irradiance_scale(d) else {
        return;
    };
    painter.rect_filled(area, 3.0, PANEL_FILL);
    legend_title(
        painter,
        area,
        [
            &format!(
                "irradiance / the ghost's brightest triangle, log ({:.1} decades)",
                scale.decades
            ),
            &format!(
                "max {:.3e} image units/px² (unit light, before colour)",
                scale.max
            ),
        ],
    );
    let bar = legend_bar(area, 8.0);
    colour_bar(painter, bar);
    let font = FontId::monospace(9.0);
    for k in 0..=4 {
        let t = k as f32 / 4.0;
        let x = bar.min.x + t * bar.width();
        let text = match k {
            0 => format!("≤{}", ratio_label(scale.ratio_at(t))),
            4 => "1".to_string(),
            _ => ratio_label(scale.ratio_at(t)),
        };
        let align = match k {
            0 => Align2::LEFT_TOP,
            4 => Align2::RIGHT_TOP,
            _ => Align2::CENTER_TOP,
        };
        painter.text(pos2(x, bar.max.y + 2.0), align, text, font.clone(), TEXT);
    }
}
