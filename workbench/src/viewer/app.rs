//! The viewer's state and its UI, one egui pass at a time: the lens view beside the flare
//! view, a status line below. The same [`Viewer::frame`] runs in the window and offscreen
//! (tests, screenshots). State flows one way: document change → view model → drawing;
//! input → action → a new render job (or a message to the editor).

use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender};
use std::time::Duration;

use egui::{Key, Ui};
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};
use ghost_raytrace::scene::{LightSpec, Quality};

use super::debug_view::{DebugState, DebugView};
use super::flare_view;
use super::flare_worker::{FlareFrame, FlareJob, FlareScene, FlareWorker, Stage, WorkerEvent};
use super::lens_picker::LensPicker;
use super::lens_view::{self, LensCamera, LensOverlay};
use super::plugins::{PluginWatcher, SharedWaker, ViewerAlgo, WatchEvent};
use super::status;
use crate::algo_spec::Algo;
use crate::document::Change;
use crate::flare::{BackendChoice, StarburstMode};
use crate::lens_drawing::{self, LensDrawing, RayFan};
use crate::link::{FromEditor, ToEditor};

/// Rays per drawn fan.
const FAN_RAYS: usize = 7;
/// The F, d and C lines, for fans per wavelength.
const FAN_WAVELENGTHS_NM: [f64; 3] = [486.13, 587.56, 656.27];

/// The window's side of the link with the editor.
#[derive(Debug)]
pub struct EditorLink {
    pub changes: Receiver<Change>,
    pub selection: Receiver<FromEditor>,
    pub to_editor: Sender<ToEditor>,
}

/// How the viewer starts.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    pub backend: BackendChoice,
    /// The flare's render size (pixels).
    pub size: (usize, usize),
    pub lights: Vec<LightSpec>,
    pub quality: Quality,
    pub starburst: StarburstMode,
    /// Iris blades (0: a circular stop).
    pub blades: u32,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        ViewerOptions {
            backend: BackendChoice::Auto,
            size: (960, 540),
            lights: vec![LightSpec::parse("8,30").expect("a valid light")],
            quality: Quality::Default,
            starburst: StarburstMode::On,
            blades: 0,
        }
    }
}

/// Where the viewer's log lines go.
pub type LogSink = Box<dyn FnMut(&str) + Send>;

/// The viewer: the lens being shown, its drawing, the flare scene and the latest frame.
pub struct Viewer {
    system: Arc<LensSystem>,
    revision: u64,
    drawing: LensDrawing,
    fans: Vec<RayFan>,
    ghost_fan: Option<RayFan>,
    ghosts: Vec<GhostPath>,
    pub(super) selected_ghost: Option<GhostPath>,
    selected_row: Option<usize>,
    hovered_row: Option<usize>,
    pub(super) scene: FlareScene,
    blades: u32,
    per_wavelength: bool,
    pub(super) labels: bool,
    /// The debug view shown for the selected ghost (`D`).
    debug_view: DebugView,
    /// The ghost the last job submitted traces for the debug views.
    submitted_debug: Option<GhostPath>,
    want_reference: bool,
    worker: FlareWorker,
    next_id: u64,
    /// A scene or lens change not yet sent to the worker.
    dirty: bool,
    pub(super) shown: Option<FlareFrame>,
    pub(super) texture: Option<egui::TextureHandle>,
    /// Exposure offset the texture was toned with.
    texture_offset_ev: f32,
    camera: Option<LensCamera>,
    /// The last error, panic or note, for the status line.
    pub(super) message: Option<String>,
    /// Why the newest job failed or panicked, if it did.
    failed: Option<String>,
    link: Option<EditorLink>,
    saved: usize,
    /// Where `--log` lines go (frames shown, selections, layout), if anywhere.
    log: Option<LogSink>,
    /// The lens and flare views' rectangles (points) last logged.
    logged_rects: [Option<egui::Rect>; 2],
    /// The ghost plugins (`--algo`), and which renders the preview (none: the built-in
    /// renderer; `A` cycles).
    algos: Vec<ViewerAlgo>,
    active_algo: Option<usize>,
    /// Watches the plugins' libraries and loads rebuilt ones.
    plugin_watch: Option<PluginWatcher>,
    /// Wakes the window's event loop (from the render and watch threads).
    waker: SharedWaker,
    /// The bundled library to open another lens from (`O`; not while an editor owns the lens).
    picker: LensPicker,
    /// The other lens of an A/B comparison (`--compare`; `C` swaps it with the one shown),
    /// and whether the one shown is the compared one (B).
    compare: Option<Arc<LensSystem>>,
    showing_b: bool,
}

/// What the debug views say for a plugin's frame.
const DEBUG_NOT_FOR_PLUGINS: &str =
    "the debug views trace the built-in renderer: not available for a plugin (A switches)";

impl std::fmt::Debug for Viewer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Viewer")
            .field("lens", &self.system.name)
            .field("revision", &self.revision)
            .finish_non_exhaustive()
    }
}

impl Viewer {
    /// A viewer of `system`; `waker` is called from the render thread when a frame is ready.
    pub fn new(
        system: LensSystem,
        options: ViewerOptions,
        waker: Box<dyn Fn() + Send + Sync>,
    ) -> Viewer {
        let waker: SharedWaker = Arc::from(waker);
        let w = Arc::clone(&waker);
        let worker = FlareWorker::start(options.backend, Box::new(move || w()));
        let scene = FlareScene {
            lights: options.lights,
            width: options.size.0,
            height: options.size.1,
            aperture: aperture_of(options.blades),
            starburst: options.starburst,
            quality: options.quality,
            solo: None,
            exposure_offset_ev: 0.0,
        };
        let system = Arc::new(system);
        let mut v = Viewer {
            drawing: LensDrawing::new(&system),
            system,
            revision: 0,
            fans: Vec::new(),
            ghost_fan: None,
            ghosts: Vec::new(),
            selected_ghost: None,
            selected_row: None,
            hovered_row: None,
            scene,
            blades: options.blades,
            per_wavelength: false,
            labels: false,
            debug_view: DebugView::Off,
            submitted_debug: None,
            want_reference: false,
            worker,
            next_id: 0,
            dirty: true,
            shown: None,
            texture: None,
            texture_offset_ev: 0.0,
            camera: None,
            message: None,
            failed: None,
            link: None,
            saved: 0,
            log: None,
            logged_rects: [None; 2],
            algos: Vec::new(),
            active_algo: None,
            plugin_watch: None,
            waker,
            picker: LensPicker::default(),
            compare: None,
            showing_b: false,
        };
        v.rebuild_lens();
        v
    }

    /// Gives the viewer a second lens to compare the first with (A/B): `C` shows one, then
    /// the other, with the same lights, aperture and exposure (a fitted or re-coated lens
    /// against the original, say).
    pub fn with_compare(mut self, other: LensSystem) -> Viewer {
        self.compare = Some(Arc::new(other));
        self
    }

    /// Whether the lens shown is the compared one (B of an A/B comparison).
    pub fn showing_compared(&self) -> bool {
        self.showing_b
    }

    /// Gives the viewer ghost plugins (resolved `--algo` arguments, each loaded with its
    /// parameters, else an error): the first renders the preview (`A` cycles through the
    /// built-in renderer and them), and their libraries are watched and reloaded when rebuilt.
    pub fn with_algos(mut self, algos: Vec<Algo>) -> anyhow::Result<Viewer> {
        let (algos, watch) = super::plugins::from_algos(algos, Arc::clone(&self.waker))?;
        self.active_algo = (!algos.is_empty()).then_some(0);
        self.algos = algos;
        self.plugin_watch = watch;
        self.dirty = true;
        Ok(self)
    }

    /// The plugins given (`--algo`).
    pub fn algos(&self) -> &[ViewerAlgo] {
        &self.algos
    }

    /// The plugin rendering the preview (none: the built-in renderer).
    pub fn active_algo(&self) -> Option<&ViewerAlgo> {
        self.active_algo.and_then(|i| self.algos.get(i))
    }

    /// Renders the preview with plugin `index` of [`Viewer::algos`], or the built-in renderer.
    pub fn select_algo(&mut self, index: Option<usize>) {
        let index = index.filter(|&i| i < self.algos.len());
        if index != self.active_algo {
            self.active_algo = index;
            self.dirty = true;
        }
        let name = self
            .active_algo()
            .map_or("built-in".to_string(), |a| format!("plugin {}", a.spec));
        self.log(format!("renderer {name}"));
    }

    /// Takes what the plugin watch found: a reloaded library replaces the plugin of every spec
    /// using it (the preview renders again if one of them is shown); a failed one is kept as
    /// the error, the previous plugin still in use. Both are told in the status line, the log
    /// and the editor.
    fn on_plugin_watch(&mut self, event: WatchEvent) {
        let message = match event {
            WatchEvent::Reloaded {
                library,
                plugin,
                noticed,
            } => {
                let mut taken = Vec::new();
                let mut refused = None;
                for (i, a) in self.algos.iter_mut().enumerate() {
                    if a.library != library {
                        continue;
                    }
                    match a.take(plugin) {
                        Ok(()) => taken.push((i, a.reloads)),
                        Err(e) => {
                            a.reload_error = Some(e.clone());
                            refused = Some(e);
                        }
                    }
                }
                if taken.iter().any(|&(i, _)| Some(i) == self.active_algo) {
                    self.dirty = true;
                }
                match refused {
                    Some(e) => format!(
                        "plugin reload failed, the previous one stays in use: {}: {e}",
                        library.display()
                    ),
                    None => format!(
                        "reloaded plugin `{}` {} from {} (reload {}, loaded in {:.0} ms)",
                        plugin.name,
                        plugin.version,
                        library.display(),
                        taken.iter().map(|&(_, n)| n).max().unwrap_or(0),
                        noticed.elapsed().as_secs_f64() * 1e3
                    ),
                }
            }
            WatchEvent::Failed { library, error } => {
                for a in self.algos.iter_mut().filter(|a| a.library == library) {
                    a.reload_error = Some(error.clone());
                }
                format!(
                    "plugin reload failed, the previous one stays in use: {}: {error}",
                    library.display()
                )
            }
        };
        self.log(message.clone());
        if let Some(link) = &self.link {
            let _ = link
                .to_editor
                .send(ToEditor::Note(format!("window: {message}")));
        }
        self.message = Some(message);
    }

    /// Connects the viewer to an editor: its document changes and selection drive the view.
    pub fn with_link(mut self, link: EditorLink) -> Viewer {
        self.link = Some(link);
        self
    }

    /// Writes a line for every frame shown, lens change, selection and layout change to
    /// `log` (`flarebench view --log`; scripts and tests follow the window with it).
    pub fn with_log(mut self, log: LogSink) -> Viewer {
        self.log = Some(log);
        self
    }

    fn log(&mut self, line: String) {
        if let Some(l) = &mut self.log {
            l(&line);
        }
    }

    /// The lens shown.
    pub fn system(&self) -> &LensSystem {
        &self.system
    }

    /// The document revision shown (0 without an editor).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// The newest frame shown, if any.
    pub fn frame_shown(&self) -> Option<&FlareFrame> {
        self.shown.as_ref()
    }

    /// The flare scene.
    pub fn scene(&self) -> &FlareScene {
        &self.scene
    }

    /// The status line's message (an error, a panic, a save), if any.
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    /// The selected ghost.
    pub fn selected_ghost(&self) -> Option<GhostPath> {
        self.selected_ghost
    }

    /// The debug view shown (`D`).
    pub fn debug_view(&self) -> DebugView {
        self.debug_view
    }

    /// The ghost the debug views want traced: the selected one, while a view is on and the
    /// built-in renderer draws the preview.
    fn wanted_debug(&self) -> Option<GhostPath> {
        self.selected_ghost
            .filter(|_| self.debug_view != DebugView::Off && self.active_algo.is_none())
    }

    /// What the debug view has to draw: the shown frame's trace of the selected ghost, or why
    /// there is none.
    pub(super) fn debug_state(&self) -> DebugState<'_> {
        if self.active_algo.is_some() {
            return DebugState::Note(DEBUG_NOT_FOR_PLUGINS);
        }
        let Some(g) = self.selected_ghost else {
            return DebugState::Note("select a ghost (click it, or N)");
        };
        let Some(f) = &self.shown else {
            return DebugState::Note("tracing the ghost…");
        };
        // The newest job's answer is the selection's (an older one's may be another ghost's).
        let newest = f.id == self.next_id && self.submitted_debug == Some(g);
        match &f.debug {
            Some(Ok(d)) if d.path == g => DebugState::Ready(d),
            Some(Err(why)) if newest => DebugState::Note(why),
            _ => DebugState::Note("tracing the ghost…"),
        }
    }

    /// True when the newest job has been rendered to its last stage and nothing waits.
    pub fn settled(&self) -> bool {
        let last = if self.want_reference {
            Stage::Reference
        } else if self.active_algo.is_some() {
            // A plugin's only frame.
            Stage::Settled
        } else if self.scene.quality == Quality::Fast {
            Stage::Fast
        } else {
            Stage::Settled
        };
        !self.dirty
            && self
                .shown
                .as_ref()
                .is_some_and(|f| f.id == self.next_id && f.stage >= last)
    }

    /// True when the render thread has finished the bounds table of the newest lens
    /// (`bounds_table`), so fast frames of a moved light are planned by lookup.
    pub fn bounds_table_complete(&self) -> bool {
        self.worker.bounds_table_complete()
    }

    /// Why the newest render failed or panicked, if it did (nothing more will come of it).
    pub fn render_failure(&self) -> Option<&str> {
        self.failed.as_deref()
    }

    /// Waits up to `timeout` for the render thread's next event (headless use: the window
    /// waits in its event loop instead). True when one arrived; it is handled by the next
    /// [`Viewer::frame`].
    pub fn wait_for_render(&mut self, timeout: Duration) -> bool {
        match self.worker.wait(timeout) {
            Some(e) => {
                self.on_worker(e);
                true
            }
            None => false,
        }
    }

    /// Shows a new version of the lens (an edit in the editor).
    pub fn set_system(&mut self, system: Arc<LensSystem>, revision: u64) {
        self.system = system;
        self.revision = revision;
        self.rebuild_lens();
        self.log(format!("lens revision {revision}"));
    }

    /// Moves light `index` to `(theta, phi)` degrees.
    pub fn move_light(&mut self, index: usize, theta_deg: f64, phi_deg: f64) {
        if let Some(l) = self.scene.lights.get_mut(index) {
            l.theta_deg = theta_deg.clamp(0.0, 89.0);
            l.phi_deg = phi_deg;
            self.dirty = true;
            self.rebuild_ghost_fan();
        }
    }

    /// Selects a ghost (its path shows in the lens view; the editor is told).
    pub fn select_ghost(&mut self, ghost: Option<GhostPath>, tell_editor: bool) {
        self.selected_ghost = ghost;
        if self.scene.solo.is_some() {
            self.scene.solo = ghost;
            self.dirty = true;
        }
        if let (Some(g), true, Some(link)) = (ghost, tell_editor, &self.link) {
            let _ = link.to_editor.send(ToEditor::SelectGhost(g));
        }
        if let Some(g) = ghost {
            self.log(format!("ghost {g}"));
        }
        self.rebuild_ghost_fan();
    }

    fn rebuild_lens(&mut self) {
        self.drawing = LensDrawing::new(&self.system);
        self.ghosts = enumerate_ghosts(&self.system);
        if self
            .selected_ghost
            .is_some_and(|g| !self.ghosts.contains(&g))
        {
            self.selected_ghost = None;
            self.scene.solo = None;
        }
        if self
            .selected_row
            .is_some_and(|r| r >= self.system.surfaces.len())
        {
            self.selected_row = None;
        }
        self.rebuild_fans();
        self.rebuild_ghost_fan();
        self.dirty = true;
    }

    fn rebuild_fans(&mut self) {
        let fields = lens_drawing::standard_fields(&self.system);
        self.fans = match fields {
            Some(f) => {
                let waves = if self.per_wavelength {
                    FAN_WAVELENGTHS_NM.to_vec()
                } else {
                    vec![self.system.default_wavelength_nm()]
                };
                lens_drawing::ray_fans(&self.system, &f, &waves, FAN_RAYS)
            }
            None => Vec::new(),
        };
    }

    fn rebuild_ghost_fan(&mut self) {
        let theta = self.scene.lights.first().map_or(0.0, |l| l.theta_deg);
        self.ghost_fan = self.selected_ghost.map(|g| {
            lens_drawing::ghost_fan(
                &self.system,
                g,
                theta,
                self.system.default_wavelength_nm(),
                FAN_RAYS,
            )
        });
    }

    fn on_worker(&mut self, event: WorkerEvent) {
        match event {
            WorkerEvent::Frame(f) => {
                if self.shown.as_ref().is_none_or(|s| f.id >= s.id) {
                    let light = self.scene.lights.first().map_or(String::new(), |l| {
                        format!(" light {:.3},{:.3}", l.theta_deg, l.phi_deg)
                    });
                    self.log(format!(
                        "frame {} {:?} {} {:.1} ms{light}",
                        f.id,
                        f.stage,
                        f.quality.name(),
                        f.stats.total_ms
                    ));
                    // Toned at the offset of its job; re-toned if the wheel moved since.
                    self.texture_offset_ev = f.exposure_offset_ev;
                    self.shown = Some(*f);
                    self.texture = None;
                    if self
                        .message
                        .as_deref()
                        .is_some_and(|m| m.starts_with("render"))
                    {
                        self.message = None;
                    }
                }
            }
            WorkerEvent::Failed { id, message } => {
                let m = format!("render failed: {message}");
                self.log(m.clone());
                self.failed = (id == self.next_id).then(|| m.clone());
                self.message = Some(m);
            }
            WorkerEvent::Panicked { id, message } => {
                let m = format!("render worker panicked (a bug; edits are safe): {message}");
                self.log(m.clone());
                self.failed = (id == self.next_id).then(|| m.clone());
                self.message = Some(m);
            }
        }
    }

    fn submit(&mut self) {
        self.next_id += 1;
        self.failed = None;
        self.worker.submit(FlareJob {
            id: self.next_id,
            system: Arc::clone(&self.system),
            scene: self.scene.clone(),
            reference: self.want_reference,
            debug: self.wanted_debug(),
            plugin: self.active_algo().map(ViewerAlgo::job),
        });
        self.submitted_debug = self.wanted_debug();
        self.dirty = false;
    }

    /// Takes in what arrived (document changes, selections, frames), then sends a render job
    /// if the scene changed. Called at the start of every pass.
    fn take_inputs(&mut self) {
        let mut newest: Option<Change> = None;
        let mut selections = Vec::new();
        if let Some(link) = &self.link {
            newest = link.changes.try_iter().last();
            selections = link.selection.try_iter().collect();
        }
        if let Some(c) = newest {
            self.set_system(c.system, c.revision);
        }
        for s in selections {
            match s {
                FromEditor::Row(r) => self.selected_row = r,
                FromEditor::Ghost(g) => self.select_ghost(g, false),
            }
        }
        for e in self.worker.poll() {
            self.on_worker(e);
        }
        let found = self
            .plugin_watch
            .as_ref()
            .map(PluginWatcher::poll)
            .unwrap_or_default();
        for e in found {
            self.on_plugin_watch(e);
        }
        // A debug view needs the selected ghost traced: a new job when the last did not.
        if self.wanted_debug().is_some() && self.wanted_debug() != self.submitted_debug {
            self.dirty = true;
        }
        if self.dirty {
            self.submit();
        }
    }

    /// One UI pass: inputs, keys, then the panels.
    pub fn frame(&mut self, ui: &mut Ui) {
        self.take_inputs();
        self.keys(ui.ctx());
        self.take_inputs();
        self.ensure_texture(ui.ctx());

        if let Some(path) = self.picker.show(ui) {
            self.open_lens(&path);
        }
        egui::Panel::top("viewer-help").show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                if self.compare.is_some() {
                    ui.strong(if self.showing_b { "B" } else { "A" });
                }
                ui.strong(&self.system.name);
                ui.label(status::help_line());
            });
        });
        let hovered = self.hovered_description();
        egui::Panel::bottom("viewer-status").show(ui, |ui| {
            status::show(
                ui,
                status::StatusState {
                    message: self.message.as_deref(),
                    frame: self.shown.as_ref(),
                    selected_ghost: self.selected_ghost,
                    solo: self.scene.solo.is_some(),
                    debug_view: self.debug_view,
                    algos: self.algos(),
                    active_algo: self.active_algo(),
                    hovered: hovered.as_deref(),
                },
            );
        });
        let half = (ui.available_width() * 0.42).max(120.0);
        egui::Panel::left("viewer-lens")
            .default_size(half)
            .show(ui, |ui| {
                let overlay = LensOverlay {
                    fans: &self.fans,
                    ghost: self.ghost_fan.as_ref(),
                    selected_row: self.selected_row,
                };
                let r = lens_view::show(ui, &self.drawing, &overlay, &mut self.camera);
                self.log_rect(0, "lens", r.rect);
                self.hovered_row = r.hovered_row;
                if let Some(row) = r.clicked_row {
                    self.selected_row = Some(row);
                    self.log(format!("row {row}"));
                    if let Some(link) = &self.link {
                        let _ = link.to_editor.send(ToEditor::SelectRow(row));
                    }
                }
            });
        egui::CentralPanel::default().show(ui, |ui| {
            let state = flare_view::FlareViewState {
                system: &self.system,
                width: self.scene.width,
                height: self.scene.height,
                texture: self.texture.as_ref(),
                shown: self.shown.as_ref(),
                selected_ghost: self.selected_ghost,
                labels: self.labels,
                debug_view: self.debug_view,
                debug_state: self.debug_state(),
            };
            let (rect, action) = flare_view::show(ui, state);
            self.log_rect(1, "flare", rect);
            self.apply(action);
        });
        self.take_inputs();
    }

    /// Logs where view `k` (`name`) is when it moved.
    fn log_rect(&mut self, k: usize, name: &str, rect: egui::Rect) {
        if self.log.is_some() && self.logged_rects[k] != Some(rect) {
            self.logged_rects[k] = Some(rect);
            self.log(format!(
                "{name} view at {:.0},{:.0} size {:.0}x{:.0}",
                rect.min.x,
                rect.min.y,
                rect.width(),
                rect.height()
            ));
        }
    }

    /// The row under the mouse in the lens view, with its data, for the status line.
    pub(super) fn hovered_description(&self) -> Option<String> {
        let row = self.hovered_row?;
        let s = self.system.surfaces.get(row)?;
        let radius = if s.curvature == 0.0 {
            "flat".to_string()
        } else {
            format!("R {:.3} mm", 1.0 / s.curvature)
        };
        let coating = if s.kind == flarebench_sdk::system::SurfaceKind::Refracting {
            format!(", {}", status::coating_text(&s.coating))
        } else {
            String::new()
        };
        Some(format!(
            "row {row}: {radius}, thickness {:.3} mm, semi-diameter {:.3} mm{coating}",
            s.thickness, s.semi_diameter
        ))
    }

    fn apply(&mut self, action: flare_view::FlareAction) {
        use flare_view::FlareAction as A;
        match action {
            A::None => {}
            A::MoveLight { theta, phi } => self.move_light(0, theta, phi),
            A::Exposure(d) => {
                self.scene.exposure_offset_ev += d;
            }
            A::SelectGhost(g) => self.select_ghost(Some(g), true),
        }
    }

    /// The texture of the shown frame, re-toned when only the exposure offset changed.
    fn ensure_texture(&mut self, ctx: &egui::Context) {
        let Some(f) = &self.shown else { return };
        if self.texture.is_some() && self.texture_offset_ev == self.scene.exposure_offset_ev {
            return;
        }
        let rgba = if f.exposure_offset_ev == self.scene.exposure_offset_ev {
            f.rgba.clone()
        } else {
            super::flare_worker::tone_rgba(
                &f.hdr,
                f.stats.auto_exposure_ev + self.scene.exposure_offset_ev,
            )
        };
        let image = egui::ColorImage::from_rgba_unmultiplied([f.hdr.width, f.hdr.height], &rgba);
        self.texture = Some(ctx.load_texture("flare", image, egui::TextureOptions::LINEAR));
        self.texture_offset_ev = self.scene.exposure_offset_ev;
    }

    /// Whether the lens picker is open.
    pub fn picker_open(&self) -> bool {
        self.picker.is_open()
    }

    /// Shows the lens in `path` instead of the current one (from the lens picker).
    fn open_lens(&mut self, path: &std::path::Path) {
        match flarebench_sdk::io::read_lens(path) {
            Ok(loaded) => {
                self.set_system(Arc::new(loaded.system), 0);
                self.camera = None;
                self.message = Some(format!("opened {}", path.display()));
            }
            Err(e) => self.message = Some(format!("could not open the lens: {e}")),
        }
    }

    /// Shows the other lens of the A/B comparison (`C`), keeping the view's camera.
    fn swap_compared(&mut self) {
        if self.link.is_some() {
            self.message = Some(
                "C compares lenses in `flarebench view`; here the editor owns the lens".into(),
            );
            return;
        }
        let Some(other) = self.compare.take() else {
            self.message =
                Some("C compares with another lens: give one with --compare LENS".into());
            return;
        };
        self.compare = Some(Arc::clone(&self.system));
        self.showing_b = !self.showing_b;
        let side = if self.showing_b { "B" } else { "A" };
        self.message = Some(format!("{side}: {} (C swaps)", other.name));
        self.log(format!("compare {side} {}", other.name));
        self.set_system(other, 0);
    }

    fn keys(&mut self, ctx: &egui::Context) {
        // Keys typed into a text box (the lens picker's) are not shortcuts.
        if ctx.egui_wants_keyboard_input() || self.picker.is_open() {
            return;
        }
        let pressed = |k: Key| ctx.input(|i| i.key_pressed(k));
        if pressed(Key::O) {
            if self.link.is_some() {
                self.message = Some(
                    "O opens another lens in `flarebench view`; here the editor owns the lens"
                        .into(),
                );
            } else {
                self.picker.toggle();
                return;
            }
        }
        if pressed(Key::C) {
            self.swap_compared();
        }
        if pressed(Key::S) {
            self.scene.starburst = match self.scene.starburst {
                StarburstMode::On => StarburstMode::Off,
                StarburstMode::Off => StarburstMode::Only,
                StarburstMode::Only => StarburstMode::On,
            };
            self.dirty = true;
        }
        if pressed(Key::Q) {
            self.scene.quality = match self.scene.quality {
                Quality::Fast => Quality::Default,
                Quality::Default => Quality::High,
                Quality::High => Quality::Fast,
            };
            self.dirty = true;
        }
        if pressed(Key::B) {
            self.blades = match self.blades {
                0 => 5,
                b if b >= 9 => 0,
                b => b + 1,
            };
            self.scene.aperture = aperture_of(self.blades);
            self.dirty = true;
        }
        if pressed(Key::G) && self.active_algo.is_some() {
            self.message = Some(
                "G draws the selected ghost alone with the built-in renderer only (A switches)"
                    .into(),
            );
        } else if pressed(Key::G) {
            self.scene.solo = match self.scene.solo {
                Some(_) => None,
                None => self.selected_ghost,
            };
            if self.scene.solo.is_none() && self.selected_ghost.is_none() {
                self.message = Some("G draws the selected ghost alone: click a ghost first".into());
            }
            self.dirty = true;
        }
        if pressed(Key::N) {
            let back = ctx.input(|i| i.modifiers.shift);
            self.step_ghost(if back { -1 } else { 1 });
        }
        if pressed(Key::L) {
            self.labels = !self.labels;
        }
        if pressed(Key::D) {
            self.debug_view = self.debug_view.next();
            self.log(format!("debug view {}", self.debug_view.name()));
        }
        if pressed(Key::W) {
            self.per_wavelength = !self.per_wavelength;
            self.rebuild_fans();
        }
        if pressed(Key::A) {
            if self.algos.is_empty() {
                self.message =
                    Some("A switches to a ghost plugin: give one with --algo NAME".into());
            } else {
                let next = match self.active_algo {
                    None => Some(0),
                    Some(i) if i + 1 < self.algos.len() => Some(i + 1),
                    Some(_) => None,
                };
                self.select_algo(next);
            }
        }
        if pressed(Key::E) {
            self.want_reference = !self.want_reference;
            self.dirty = true;
        }
        if pressed(Key::F) {
            self.camera = None;
        }
        if pressed(Key::P) {
            self.save(false);
        }
        if pressed(Key::X) {
            self.save(true);
        }
    }

    /// Selects the next (`+1`) or previous ghost of the lens.
    fn step_ghost(&mut self, step: isize) {
        if self.ghosts.is_empty() {
            return;
        }
        let n = self.ghosts.len() as isize;
        let k = match self
            .selected_ghost
            .and_then(|g| self.ghosts.iter().position(|x| *x == g))
        {
            Some(k) => (k as isize + step).rem_euclid(n),
            None => 0,
        };
        self.select_ghost(Some(self.ghosts[k as usize]), true);
    }

    /// Writes the shown frame: PNG as shown, or EXR (linear).
    fn save(&mut self, exr: bool) {
        let Some(f) = &self.shown else {
            self.message = Some("nothing to save yet".into());
            return;
        };
        self.saved += 1;
        let stem: String = self
            .system
            .name
            .chars()
            .map(|c| if c.is_alphanumeric() { c } else { '-' })
            .collect();
        let path = std::path::PathBuf::from(format!(
            "{stem}-flare-{}.{}",
            self.saved,
            if exr { "exr" } else { "png" }
        ));
        let result = if exr {
            crate::output::save_image_as(
                &f.hdr,
                &path,
                &crate::output::ToneMap::default(),
                crate::output::ExrPrecision::Float,
            )
        } else {
            let rgba = super::flare_worker::tone_rgba(
                &f.hdr,
                f.stats.auto_exposure_ev + self.scene.exposure_offset_ev,
            );
            let rgb = rgba
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            crate::output::save_png_rgb8(rgb, f.hdr.width, f.hdr.height, &path)
        };
        self.message = Some(match result {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => format!("could not save: {e:#}"),
        });
    }
}

/// The aperture for `blades` iris blades (0: circular).
fn aperture_of(blades: u32) -> Aperture {
    if blades == 0 {
        Aperture::Circular
    } else {
        Aperture::Iris {
            blades,
            rotation_rad: 0.0,
            roundness: 0.0,
        }
    }
}
