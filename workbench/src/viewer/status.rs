//! The status line: frame time by stage, ghosts drawn and left out with the dropped energy
//! share (or, for a plugin's frame, the plugin, its version and reloads, items and triangles),
//! backend and adapter, the error when known, the renderer in use and the last failed reload
//! of its library, and the last message (a failed or panicked render, a reload, a save).

use egui::{Color32, RichText, Ui};

use flarebench_sdk::ghost::GhostPath;

use super::debug_view::DebugView;
use super::flare_worker::{FlareFrame, Stage};
use super::plugins::ViewerAlgo;

/// The controls, for the help line.
pub fn help_line() -> &'static str {
    "lens: drag pan · wheel zoom · F fit · W wavelengths | flare: drag light · wheel exposure · \
     click ghost · N / Shift-N next/previous ghost · G ghost alone · S starburst on/off/only · \
     Q quality · B blades · L labels · D debug view (grid/stop/radius/irradiance) · E error · \
     A renderer (built-in / --algo plugins) · O open a bundled lens · C A/B (--compare) · \
     P save PNG · X save EXR"
}

/// The error part of a frame's line.
fn error_text(f: &FlareFrame) -> String {
    let mut line = String::new();
    if let Some(e) = &f.error {
        line += &format!(
            " · error {:.2}% RMSE, energy {:+.2}%",
            100.0 * e.relative_rmse,
            100.0 * e.energy_error
        );
        if let Some(t) = f.stats.reference_ms {
            line += &format!(" (reference {:.1} s)", t / 1e3);
        }
    }
    line
}

/// A plugin's frame as one line of text: the plugin, its version and reloads, the times,
/// what it drew.
fn plugin_frame_line(f: &FlareFrame, p: &super::flare_worker::PluginFrame) -> String {
    let s = &f.stats;
    let prepare = p
        .prepare_ms
        .map_or(String::new(), |t| format!("prepare {t:.1}, "));
    let mut line = format!(
        "frame by plugin `{}` {} (reload {}) {:.0} ms: {prepare}render {:.1}, starburst {:.1}, \
         tone {:.1} ms · {} drawn · {} triangles",
        p.name,
        p.version,
        p.reloads,
        s.total_ms,
        s.ghosts_ms,
        s.starburst_ms,
        s.tone_ms,
        p.items_drawn,
        p.mesh_triangles
    );
    line += &error_text(f);
    line
}

/// The frame's figures as one line of text.
pub fn frame_line(f: &FlareFrame) -> String {
    if let Some(p) = &f.plugin {
        return plugin_frame_line(f, p);
    }
    let s = &f.stats;
    let stage = match f.stage {
        Stage::Fast => "fast",
        Stage::Settled => "settled",
        Stage::Reference => "with error",
    };
    let mut line = format!(
        "{stage} frame ({}) {:.0} ms: plan {:.1}{}, ghosts {:.1}, starburst {:.1}, tone {:.1} ms · \
         {} ghosts drawn, {} left out ({:.2}% of the ghost energy, {:.2}% of the frame's culled) · {} triangles",
        f.quality.name(),
        s.total_ms,
        s.plan_ms,
        if s.bounds_from_previous_lens {
            " (table of the lens before the edit)"
        } else if s.bounds_from_table {
            " (table)"
        } else if s.warm_started {
            " (warm)"
        } else {
            ""
        },
        s.ghosts_ms,
        s.starburst_ms,
        s.tone_ms,
        s.ghosts_drawn,
        s.ghosts_dropped,
        100.0 * s.dropped_energy_fraction,
        100.0 * s.culled_energy_fraction,
        s.triangles
    );
    if let Some(t) = s.debug_ms {
        line += &format!(" · debug trace {t:.1} ms");
    }
    line += &error_text(f);
    line
}

/// The renderer in use, when plugins were given (`algos`): the built-in one, or the plugin
/// `active` with its library and reloads; and the last failed reload of that library, if any.
pub fn renderer_line(
    algos: &[ViewerAlgo],
    active: Option<&ViewerAlgo>,
) -> Option<(String, Option<String>)> {
    if algos.is_empty() {
        return None;
    }
    Some(match active {
        None => (
            format!(
                "renderer: built-in (A: {})",
                algos
                    .iter()
                    .map(|a| a.spec.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None,
        ),
        Some(a) => (
            format!(
                "renderer: plugin {} — `{}` {} from {}, reload {}",
                a.spec,
                a.plugin.name,
                a.plugin.version,
                a.library.display(),
                a.reloads
            ),
            a.reload_error
                .as_ref()
                .map(|e| format!("last reload failed (the previous plugin stays in use): {e}")),
        ),
    })
}

/// The backend as one line of text.
pub fn backend_line(f: &FlareFrame) -> String {
    let b = &f.backend;
    let mut s = format!("backend {}", b.backend);
    if let Some(a) = &b.adapter {
        s += &format!(" on {a}");
        if let Some(api) = &b.api {
            s += &format!(" ({api})");
        }
        if b.software_adapter {
            s += ", software";
        }
    }
    if let Some(n) = &b.note {
        s += &format!(" — {n}");
    }
    s
}

/// What the status lines show.
#[derive(Clone, Copy, Debug)]
pub struct StatusState<'a> {
    /// The last message (a failed or panicked render, a reload, a save).
    pub message: Option<&'a str>,
    pub frame: Option<&'a FlareFrame>,
    pub selected_ghost: Option<GhostPath>,
    /// The selected ghost is drawn alone.
    pub solo: bool,
    pub debug_view: DebugView,
    /// The plugins given, and the one in use.
    pub algos: &'a [ViewerAlgo],
    pub active_algo: Option<&'a ViewerAlgo>,
    /// What is under the mouse in the lens view.
    pub hovered: Option<&'a str>,
}

/// Draws the status lines.
pub fn show(ui: &mut Ui, v: StatusState<'_>) {
    if let Some(m) = v.message {
        let colour = if m.contains("panicked") || m.contains("failed") {
            Color32::from_rgb(220, 60, 60)
        } else {
            ui.visuals().text_color()
        };
        ui.label(RichText::new(m).color(colour));
    }
    match v.frame {
        Some(f) => {
            ui.label(frame_line(f));
            let mut extra = backend_line(f);
            if let Some(g) = v.selected_ghost {
                extra += &format!(" · ghost {g}");
                if v.solo {
                    extra += " alone";
                }
                if v.debug_view != DebugView::Off {
                    extra += &format!(" · debug view {}", v.debug_view.name());
                }
            }
            ui.label(extra);
        }
        None => {
            ui.label("rendering the first frame…");
        }
    }
    if let Some((line, error)) = renderer_line(v.algos, v.active_algo) {
        ui.horizontal_wrapped(|ui| {
            ui.label(line);
            if let Some(e) = error {
                ui.label(RichText::new(e).color(Color32::from_rgb(220, 60, 60)));
            }
        });
    }
    if let Some(d) = v.hovered {
        ui.label(d);
    }
}

/// A surface's coating in words: `uncoated`, a quarter-wave layer, or a stack's layers as
/// index/thickness (nm) from the object side.
pub fn coating_text(coating: &flarebench_sdk::Coating) -> String {
    use flarebench_sdk::Coating;
    match coating {
        Coating::None => "uncoated".to_string(),
        Coating::SingleLayer {
            design_wavelength_nm,
            index,
        } => format!("coated λ/4 n={index:.3} at {design_wavelength_nm:.0} nm"),
        Coating::Stack(layers) => format!(
            "coated {} layers {}",
            layers.len(),
            layers
                .iter()
                .map(|l| format!("{:.2}/{:.0}", l.index, l.thickness_nm))
                .collect::<Vec<_>>()
                .join(" ")
        ),
    }
}
