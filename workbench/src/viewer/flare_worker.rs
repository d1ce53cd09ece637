//! The flare preview's render worker: one thread that renders the newest scene it was given,
//! progressively (a fast frame at once, then the default preset while the scene holds still,
//! then on request the error against the dense reference). A job that arrives while one renders
//! replaces the waiting one (the newest edit wins; a stale job is dropped, never queued), and
//! the frames of a superseded job are not sent. A panic in a render is caught and reported;
//! the worker keeps serving. Each frame is drawn by one [`Flare`] kept on the thread (the
//! backend, the starburst patterns, the lens's tables and the last frame's ghost rectangles
//! kept with it), as every command draws its frames.
//!
//! A job may name a ghost plugin ([`PluginJob`], `view --algo`) instead of the built-in
//! renderer: the plugin has no presets, so it is rendered once per job (the settled stage) with
//! its parameters, its mesh drawn by the backend as `compare` draws it
//! (`Flare::render_plugin`), the starbursts added as for the built-in renderer. Its
//! instance is kept from job to job (prepared again when the lens changes, made anew for
//! another plugin or a reloaded library).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::host::{LoadedPlugin, PluginInstance};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::{GhostPath, ReflectionOrder};
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::{LightSpec, Quality};
use rayon::prelude::*;

use crate::flare::{
    BackendChoice, BackendReport, Flare, GhostBackend, Preset, Scene, StarburstMode, frame_for,
};
use crate::output::{ToneMap, ToneOperator, ToneTable};
use crate::report::ErrorReport;

use super::bounds_table::BoundsTabulation;
use super::ghost_debug::{self, GhostDebug};

/// What the flare view shows: everything a render depends on besides the lens.
#[derive(Clone, Debug, PartialEq)]
pub struct FlareScene {
    pub lights: Vec<LightSpec>,
    /// Image size in pixels.
    pub width: usize,
    pub height: usize,
    pub aperture: Aperture,
    pub starburst: StarburstMode,
    /// The preset rendered once the scene holds still (the fast preset comes first).
    pub quality: Quality,
    /// Draw this ghost alone.
    pub solo: Option<GhostPath>,
    /// Stops added to the automatic exposure.
    pub exposure_offset_ev: f32,
}

/// One render request: a lens and a scene, numbered so results can be matched to requests.
#[derive(Clone, Debug)]
pub struct FlareJob {
    pub id: u64,
    pub system: Arc<LensSystem>,
    pub scene: FlareScene,
    /// Also render the dense reference and report the error against it (slow).
    pub reference: bool,
    /// Trace this ghost alone for the first light for the debug views ([`GhostDebug`]);
    /// built-in renderer only.
    pub debug: Option<GhostPath>,
    /// Render the ghosts with this plugin instead of the built-in renderer.
    pub plugin: Option<PluginJob>,
}

/// A ghost plugin to render a job with (`view --algo`).
#[derive(Clone, Debug)]
pub struct PluginJob {
    /// The plugin, loaded for the life of the process: its library is never unloaded
    /// (`crate::algo_spec`), so its descriptor is kept as long (`viewer::plugins`), and the
    /// render thread's instance can borrow it from job to job.
    pub plugin: &'static LoadedPlugin,
    /// Its parameter values, one per [`LoadedPlugin::params`].
    pub values: Vec<f64>,
    /// The `--algo` argument.
    pub spec: String,
    /// How many times its library has been reloaded (0: as loaded at the start).
    pub reloads: u32,
}

/// What a plugin's frame reports besides the image.
#[derive(Clone, Debug)]
pub struct PluginFrame {
    pub name: String,
    pub version: String,
    pub spec: String,
    pub reloads: u32,
    /// Items the plugin reports drawn (ghosts, sprites).
    pub items_drawn: u32,
    /// Triangles of its mesh.
    pub mesh_triangles: usize,
    /// Time of the plugin's `prepare` when this frame called it (a new instance or lens).
    pub prepare_ms: Option<f64>,
}

/// The stages of a job, in the order they are rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// The fast preset: the first frame after a change.
    Fast,
    /// The scene's own preset, once nothing newer is waiting.
    Settled,
    /// The settled frame with its error against the dense reference.
    Reference,
}

/// Where a drawn ghost lands, to find the ghost under the mouse.
#[derive(Clone, Debug)]
pub struct GhostFootprint {
    pub path: GhostPath,
    /// Index of the light it belongs to.
    pub light: usize,
    /// Its landing rectangle in its light's meridional frame (mm) and that frame's azimuth.
    pub rect: [f64; 4],
    pub phi: f64,
    pub energy_share: f64,
}

/// Figures of one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    pub ghosts_drawn: usize,
    pub ghosts_dropped: usize,
    /// The share of the ghost energy left out by planning, over all lights.
    pub dropped_energy_fraction: f64,
    /// The largest share of a light's on-frame ghost energy that culling left out
    /// (`LightPlan::culled_share`).
    pub culled_energy_fraction: f64,
    pub triangles: usize,
    pub plan_ms: f64,
    /// The plan looked its bounds up in the lens's table (`bounds_table`) instead of tracing
    /// them.
    pub bounds_from_table: bool,
    /// The plan traced its bounds starting from the last frame's rectangles.
    pub warm_started: bool,
    /// The table the plan looked its bounds up in was the lens's before the last edit (a
    /// fast frame before the edited lens is tabulated).
    pub bounds_from_previous_lens: bool,
    pub ghosts_ms: f64,
    pub starburst_ms: f64,
    pub tone_ms: f64,
    pub total_ms: f64,
    /// Time to render the dense reference (the reference stage only).
    pub reference_ms: Option<f64>,
    /// Time to trace the debug views' ghost (when asked for).
    pub debug_ms: Option<f64>,
    /// The automatic exposure of the frame (stops, before the scene's offset).
    pub auto_exposure_ev: f32,
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct FlareFrame {
    pub id: u64,
    pub stage: Stage,
    pub quality: Quality,
    /// The linear image (ghosts and starbursts).
    pub hdr: Arc<HdrImage>,
    /// Tone mapped, 8-bit sRGB with opaque alpha, rows top to bottom, at the automatic
    /// exposure plus `exposure_offset_ev`.
    pub rgba: Vec<u8>,
    pub exposure_offset_ev: f32,
    pub stats: FrameStats,
    pub ghosts: Vec<GhostFootprint>,
    pub backend: BackendReport,
    pub error: Option<ErrorReport>,
    /// The debug views' ghost ([`FlareJob::debug`]) traced alone, or why it could not be.
    pub debug: Option<Result<Arc<GhostDebug>, String>>,
    /// The plugin that drew the ghosts (none: the built-in renderer).
    pub plugin: Option<PluginFrame>,
}

/// What the worker sends back.
#[derive(Debug)]
pub enum WorkerEvent {
    Frame(Box<FlareFrame>),
    /// The job could not be rendered (an error, not a bug).
    Failed {
        id: u64,
        message: String,
    },
    /// A render panicked: a bug, shown in the status line; the worker goes on.
    Panicked {
        id: u64,
        message: String,
    },
}

type Waker = Box<dyn Fn() + Send + Sync>;

#[derive(Default)]
struct Pending {
    job: Option<FlareJob>,
    quit: bool,
}

struct Shared {
    pending: Mutex<Pending>,
    wake: Condvar,
    /// The bounds table of the newest job's lens is finished.
    tabulated: AtomicBool,
}

impl Shared {
    /// True when a newer job waits (the current one is stale).
    fn superseded(&self) -> bool {
        let p = self.pending.lock().unwrap_or_else(|e| e.into_inner());
        p.job.is_some() || p.quit
    }
}

/// The worker thread and its channels.
pub struct FlareWorker {
    shared: Arc<Shared>,
    events: Receiver<WorkerEvent>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for FlareWorker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FlareWorker").finish_non_exhaustive()
    }
}

impl FlareWorker {
    /// Starts the worker with `backend` (opened on the worker thread: a failure to open the
    /// GPU falls back to the CPU and says so in every frame's report). `waker` is called after
    /// every event sent (e.g. to wake the window's event loop).
    pub fn start(backend: BackendChoice, waker: Waker) -> FlareWorker {
        let shared = Arc::new(Shared {
            pending: Mutex::new(Pending::default()),
            wake: Condvar::new(),
            tabulated: AtomicBool::new(false),
        });
        let (tx, events) = channel();
        let s = Arc::clone(&shared);
        crate::panics::install_hook_once();
        let thread = std::thread::Builder::new()
            .name("flare-render".into())
            .spawn(move || {
                // A render's panic is caught and shown in the status line, not printed.
                crate::panics::caught_here();
                serve(&s, backend, &tx, &waker)
            })
            .expect("spawning the render thread");
        FlareWorker {
            shared,
            events,
            thread: Some(thread),
        }
    }

    /// Asks for `job`, replacing any job still waiting.
    pub fn submit(&self, job: FlareJob) {
        let mut p = self
            .shared
            .pending
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        p.job = Some(job);
        self.shared.wake.notify_one();
    }

    /// The events that have arrived, oldest first, without waiting.
    /// True when the bounds table of the newest job's lens is finished (`bounds_table`): its
    /// fast frames are then planned by lookup.
    pub fn bounds_table_complete(&self) -> bool {
        self.shared.tabulated.load(Ordering::Relaxed)
    }

    pub fn poll(&self) -> Vec<WorkerEvent> {
        self.events.try_iter().collect()
    }

    /// Waits for the next event (tests and headless use).
    pub fn wait(&self, timeout: Duration) -> Option<WorkerEvent> {
        self.events.recv_timeout(timeout).ok()
    }
}

impl Drop for FlareWorker {
    fn drop(&mut self) {
        {
            let mut p = self
                .shared
                .pending
                .lock()
                .unwrap_or_else(|e| e.into_inner());
            p.quit = true;
            p.job = None;
            self.shared.wake.notify_one();
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// How long the render thread must have been idle before it works on the bounds table: edits
/// and drags in quick succession are not slowed by it.
const IDLE_DELAY: Duration = Duration::from_millis(500);

fn serve(shared: &Shared, choice: BackendChoice, tx: &Sender<WorkerEvent>, waker: &Waker) {
    let mut renderer: Option<Renderer> = None;
    let mut idle_since = Instant::now();
    loop {
        let job = {
            let mut p = shared.pending.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                if p.quit {
                    return;
                }
                if let Some(job) = p.job.take() {
                    break Some(job);
                }
                if renderer.as_ref().is_some_and(Renderer::has_idle_work) {
                    let waited = idle_since.elapsed();
                    if waited >= IDLE_DELAY {
                        break None;
                    }
                    p = shared
                        .wake
                        .wait_timeout(p, IDLE_DELAY - waited)
                        .unwrap_or_else(|e| e.into_inner())
                        .0;
                } else {
                    p = shared.wake.wait(p).unwrap_or_else(|e| e.into_inner());
                }
            }
        };
        let Some(job) = job else {
            // Nothing to render: tabulate a few more angles of the lens's bounds.
            if let Some(r) = renderer.as_mut() {
                r.idle_step();
                shared
                    .tabulated
                    .store(!r.has_idle_work(), Ordering::Relaxed);
            }
            continue;
        };
        // A plugin has no presets: one frame, the settled one.
        let mut stages = Vec::new();
        if job.plugin.is_none() {
            stages.push(Stage::Fast);
        }
        if job.plugin.is_some() || job.scene.quality != Quality::Fast || job.reference {
            stages.push(Stage::Settled);
        }
        if job.reference {
            stages.push(Stage::Reference);
        }
        let mut last: Option<FlareFrame> = None;
        for stage in stages {
            if shared.superseded() {
                break;
            }
            let r = renderer.get_or_insert_with(|| Renderer::open(choice));
            let outcome = catch_unwind(AssertUnwindSafe(|| match (stage, &last) {
                (Stage::Reference, Some(settled)) => Renderer::with_error(&job, settled),
                _ => r.render(&job, stage),
            }));
            let event = match outcome {
                Ok(Ok(frame)) => {
                    last = Some(frame.clone());
                    // A job replaced while it rendered: its frame is stale.
                    if shared.superseded() {
                        break;
                    }
                    WorkerEvent::Frame(Box::new(frame))
                }
                Ok(Err(e)) => WorkerEvent::Failed {
                    id: job.id,
                    message: format!("{e:#}"),
                },
                Err(panic) => {
                    // The backend's state may be broken: open a new one for the next job.
                    renderer = None;
                    WorkerEvent::Panicked {
                        id: job.id,
                        message: panic_message(panic.as_ref()),
                    }
                }
            };
            if let Some(r) = &renderer {
                shared
                    .tabulated
                    .store(!r.has_idle_work(), Ordering::Relaxed);
            }
            let stop = !matches!(event, WorkerEvent::Frame(_));
            if tx.send(event).is_err() {
                return;
            }
            waker();
            if stop {
                break;
            }
        }
        idle_since = Instant::now();
    }
}

/// The text of a panic's payload.
pub fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a render panicked".into()
    }
}

/// The flare renderer (backend, starburst patterns, lens tables, warm starts) and the bounds
/// tables, kept from frame to frame.
struct Renderer {
    flare: Flare,
    /// The lens's ghost bounds over the light's angles, built while idle.
    tabulation: Option<BoundsTabulation>,
    /// The tabulation of the lens before the last edit: the fast frames of the edited lens
    /// look its bounds up there (when its ghosts are the same) until the edited lens's own
    /// table covers the lights.
    previous_tabulation: Option<BoundsTabulation>,
    /// Why the backend asked for could not be opened (the CPU is used instead).
    fallback: Option<String>,
    /// The instance of the last job's plugin.
    plugin: Option<PluginState>,
}

/// A plugin's instance kept between jobs.
struct PluginState {
    plugin: &'static LoadedPlugin,
    instance: PluginInstance<'static>,
    /// The lens it was last prepared for.
    lens: Option<Arc<LensSystem>>,
}

impl Renderer {
    fn open(choice: BackendChoice) -> Renderer {
        let (backend, fallback) = match GhostBackend::open(choice) {
            Ok(backend) => (backend, None),
            Err(e) => (
                GhostBackend::open(BackendChoice::Cpu).expect("the CPU backend opens"),
                Some(format!("{e:#}; drawing on the CPU")),
            ),
        };
        Renderer {
            flare: Flare::on(backend),
            tabulation: None,
            previous_tabulation: None,
            fallback,
            plugin: None,
        }
    }

    /// True when the lens's bounds table is not finished.
    fn has_idle_work(&self) -> bool {
        self.tabulation.as_ref().is_some_and(|t| !t.complete())
    }

    /// One chunk of the bounds table. A panic in it ends the tabulation (the plan then traces
    /// bounds, as without a table); it is not reported, since no frame depends on it.
    fn idle_step(&mut self) {
        if let Some(t) = self.tabulation.as_mut()
            && catch_unwind(AssertUnwindSafe(|| t.step())).is_err()
        {
            t.abandon();
        }
    }

    /// `settled` with its error against the dense reference of its scene.
    fn with_error(job: &FlareJob, settled: &FlareFrame) -> anyhow::Result<FlareFrame> {
        let t = Instant::now();
        let scene = &job.scene;
        let frame = frame_for(&job.system, (scene.width, scene.height));
        let (reference, _) = crate::reference_file::reference_for(
            &job.system,
            &scene.aperture,
            frame,
            &scene.lights,
            None,
            ReflectionOrder::Two,
        )?;
        let mut f = settled.clone();
        f.stage = Stage::Reference;
        f.stats.reference_ms = Some(ms(t));
        f.error = Some(ErrorReport::between(&settled.hdr, &reference)?);
        Ok(f)
    }

    fn render(&mut self, job: &FlareJob, stage: Stage) -> anyhow::Result<FlareFrame> {
        // Fault injection for the tests of what a render bug does to the window and editor.
        if std::env::var_os("FLAREBENCH_FAULT").is_some_and(|v| v == "render-panic") {
            panic!("injected render panic (FLAREBENCH_FAULT=render-panic)");
        }
        if let Some(p) = &job.plugin {
            return self.render_plugin(job, p, stage);
        }
        let t0 = Instant::now();
        let sys = job.system.as_ref();
        let scene = &job.scene;
        let quality = match stage {
            Stage::Fast => Quality::Fast,
            Stage::Settled | Stage::Reference => scene.quality,
        };
        let frame = frame_for(sys, (scene.width, scene.height));
        let mut stats = FrameStats::default();

        let t = Instant::now();
        if self
            .tabulation
            .as_ref()
            .is_none_or(|b| !b.is_for(&job.system))
        {
            let old = std::mem::replace(
                &mut self.tabulation,
                BoundsTabulation::new(Arc::clone(&job.system)),
            );
            // Keep the last table that holds anything (edits faster than tabulation keep
            // the one before them).
            if old.as_ref().is_some_and(|t| t.angles_done() > 0) {
                self.previous_tabulation = old;
            }
        }
        // Fast frames look bounds up once the table covers the lights; until the edited
        // lens's does, in the table of the lens before the edit (same ghosts: its rectangles
        // are where the edited lens's ghosts are searched for anyway). The settled frame
        // traces them.
        let (table, previous) = match stage {
            Stage::Fast => {
                let own = self
                    .tabulation
                    .as_ref()
                    .and_then(|b| b.table_for(&scene.lights));
                match own {
                    Some(t) => (Some(t), false),
                    None => {
                        let prev = self
                            .previous_tabulation
                            .as_ref()
                            .filter(|b| b.same_ghosts(sys))
                            .and_then(|b| b.table_for(&scene.lights));
                        (prev, prev.is_some())
                    }
                }
            }
            Stage::Settled | Stage::Reference => (None, false),
        };
        stats.bounds_from_table = table.is_some();
        stats.bounds_from_previous_lens = previous;
        // Without a table, a fast frame's search starts from the last frame's rectangles (the
        // lens before an edit, the light before a move); the settled frame searches afresh.
        let preset = Preset {
            lens_tables: true,
            warm_start: stage == Stage::Fast,
            solo: scene.solo,
            exposure: true,
            ..Preset::new(PlanOptions::for_quality(quality, table))
        };
        let tables_ms = ms(t);
        let r = self
            .flare
            .render(&flare_scene(sys, scene, frame), &preset)?;
        stats.plan_ms = tables_ms + r.timings.plan_ms;
        stats.warm_started = r.warm_started && table.is_none();
        stats.ghosts_ms = r.timings.ghosts_ms;
        stats.starburst_ms = r.timings.starburst_ms;
        stats.auto_exposure_ev = r.exposure_ev.unwrap_or(0.0);

        let t = Instant::now();
        let debug = job.debug.map(
            |path| match r.planned.as_ref().unwrap_or(&r.plans).first() {
                Some(p) => ghost_debug::compute(sys, &scene.aperture, frame, p, path).map(Arc::new),
                None => Err("no ghosts are drawn (starburst only)".to_string()),
            },
        );
        if debug.is_some() {
            stats.debug_ms = Some(ms(t));
        }
        let (mut total, mut dropped) = (0.0, 0.0);
        let mut ghosts = Vec::new();
        for (l, (p, s)) in r.plans.iter().zip(&r.ghost_stats).enumerate() {
            let (t, d) = p.energy();
            total += t;
            dropped += d;
            stats.ghosts_drawn += p.ghosts.len();
            stats.ghosts_dropped += p.dropped.len();
            stats.triangles += s.iter().map(|g| g.triangles).sum::<usize>();
            ghosts.extend(p.ghosts.iter().map(|g| {
                let r = g.bounds.sensor;
                GhostFootprint {
                    path: g.path,
                    light: l,
                    rect: [r.x0, r.y0, r.x1, r.y1],
                    phi: p.light.phi_deg.to_radians(),
                    energy_share: g.energy_share,
                }
            }));
        }
        stats.dropped_energy_fraction = if total > 0.0 { dropped / total } else { 0.0 };
        stats.culled_energy_fraction = r.plans.iter().map(|p| p.culled_share).fold(0.0, f64::max);
        let img = self.flare.take_image();

        Ok(self.finish(
            job,
            img,
            stats,
            t0,
            FrameExtras {
                stage,
                quality,
                ghosts,
                debug,
                plugin: None,
            },
        ))
    }

    /// The job's ghosts rendered by its plugin (`compare`'s way: `GhostBackend::render_plugin`),
    /// then the starbursts, tone mapped. A failed `prepare` or render drops the instance: the
    /// next job makes a new one (a plugin that panicked is poisoned).
    fn render_plugin(
        &mut self,
        job: &FlareJob,
        p: &PluginJob,
        stage: Stage,
    ) -> anyhow::Result<FlareFrame> {
        let t0 = Instant::now();
        let sys = job.system.as_ref();
        let scene = &job.scene;
        let frame = frame_for(sys, (scene.width, scene.height));
        let mut stats = FrameStats::default();
        let mut info = PluginFrame {
            name: p.plugin.name.clone(),
            version: p.plugin.version.clone(),
            spec: p.spec.clone(),
            reloads: p.reloads,
            items_drawn: 0,
            mesh_triangles: 0,
            prepare_ms: None,
        };
        let drawing = scene.starburst.ghosts();
        if drawing {
            if !self
                .plugin
                .as_ref()
                .is_some_and(|s| std::ptr::eq(s.plugin, p.plugin))
            {
                self.plugin = None;
                let instance = p
                    .plugin
                    .instantiate()
                    .map_err(|e| anyhow::anyhow!("plugin `{}`: {e}", p.spec))?;
                self.plugin = Some(PluginState {
                    plugin: p.plugin,
                    instance,
                    lens: None,
                });
            }
            let state = self.plugin.as_mut().expect("an instance was just ensured");
            if !state
                .lens
                .as_ref()
                .is_some_and(|l| Arc::ptr_eq(l, &job.system))
            {
                let t = Instant::now();
                if let Err(e) = state.instance.prepare(sys) {
                    self.plugin = None;
                    anyhow::bail!("plugin `{}`: {e}", p.spec);
                }
                state.lens = Some(Arc::clone(&job.system));
                info.prepare_ms = Some(ms(t));
                stats.plan_ms = ms(t);
            }
        }
        let instance = self
            .plugin
            .as_mut()
            .filter(|_| drawing)
            .map(|s| (&mut s.instance, p.values.as_slice()));
        let (r, drawn) =
            match self
                .flare
                .render_plugin(&flare_scene(sys, scene, frame), instance, true)
            {
                Ok(r) => r,
                Err(e) => {
                    self.plugin = None;
                    return Err(e.context(format!("plugin `{}`", p.spec)));
                }
            };
        if let Some(out) = drawn {
            info.items_drawn = out.items_drawn;
            info.mesh_triangles = out.mesh_triangles;
            stats.ghosts_drawn = info.items_drawn as usize;
            stats.triangles = info.mesh_triangles;
        }
        stats.ghosts_ms = r.timings.ghosts_ms;
        stats.starburst_ms = r.timings.starburst_ms;
        stats.auto_exposure_ev = r.exposure_ev.unwrap_or(0.0);
        let img = self.flare.take_image();

        Ok(self.finish(
            job,
            img,
            stats,
            t0,
            FrameExtras {
                stage,
                quality: scene.quality,
                ghosts: Vec::new(),
                debug: None,
                plugin: Some(info),
            },
        ))
    }

    /// The frame of `job` from its linear image: tone mapped at the automatic exposure plus
    /// the scene's offset, with the backend's report and the total time since `t0`.
    fn finish(
        &self,
        job: &FlareJob,
        img: HdrImage,
        mut stats: FrameStats,
        t0: Instant,
        extras: FrameExtras,
    ) -> FlareFrame {
        let offset = job.scene.exposure_offset_ev;
        let t = Instant::now();
        let rgba = tone_rgba(&img, stats.auto_exposure_ev + offset);
        stats.tone_ms = ms(t);
        stats.total_ms = ms(t0);
        let mut backend = self.flare.backend().report().clone();
        if let Some(why) = &self.fallback {
            backend.note = Some(why.clone());
        }
        FlareFrame {
            id: job.id,
            stage: extras.stage,
            quality: extras.quality,
            hdr: Arc::new(img),
            rgba,
            exposure_offset_ev: offset,
            stats,
            ghosts: extras.ghosts,
            backend,
            error: None,
            debug: extras.debug,
            plugin: extras.plugin,
        }
    }
}

/// What a frame carries besides its image: its stage and preset, and the built-in renderer's
/// footprints and debug trace, or the plugin that drew it.
struct FrameExtras {
    stage: Stage,
    quality: Quality,
    ghosts: Vec<GhostFootprint>,
    debug: Option<Result<Arc<GhostDebug>, String>>,
    plugin: Option<PluginFrame>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// `img` tone mapped as the PNG writer maps it (ACES, sRGB) at `exposure_ev`, as RGBA8.
pub fn tone_rgba(img: &HdrImage, exposure_ev: f32) -> Vec<u8> {
    let tone = ToneTable::new(&ToneMap {
        exposure_ev,
        operator: ToneOperator::Aces,
    });
    let mut out = vec![0u8; img.pixels.len() * 4];
    out.par_chunks_mut(4 * 4096)
        .zip(img.pixels.par_chunks(4096))
        .for_each(|(o, px)| {
            for (o, p) in o.chunks_exact_mut(4).zip(px) {
                o[0] = tone.map(p[0]);
                o[1] = tone.map(p[1]);
                o[2] = tone.map(p[2]);
                o[3] = 255;
            }
        });
    out
}

/// The flare layer's scene of a view's scene on `frame`: its lights, aperture and starburst
/// mode, the starbursts by the default settings.
fn flare_scene<'a>(system: &'a LensSystem, scene: &'a FlareScene, frame: Frame) -> Scene<'a> {
    Scene {
        starburst: scene.starburst,
        ..Scene::new(system, &scene.lights, &scene.aperture, frame)
    }
}

/// The frame of the flare view for `system` at `width × height` (the film's width across).
pub fn view_frame(system: &LensSystem, width: usize, height: usize) -> Frame {
    frame_for(system, (width, height))
}
