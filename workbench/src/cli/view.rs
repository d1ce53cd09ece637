//! `flarebench view`: the viewer window on a lens (lens section, ray fans, live flare), or the
//! same views drawn offscreen into a PNG (`--screenshot`); `--algo` renders the flare through
//! ghost plugins, reloaded when their libraries are rebuilt ([`AlgoArgs`], shared with
//! `edit --window`).

use std::path::PathBuf;
use std::time::Duration;

use crate::algo_spec::Algo;

use anyhow::Context;
use clap::Args;
use ghost_raytrace::scene::{LightSpec, Quality};

use super::render::parse_size;
use crate::flare::{BackendChoice, StarburstMode};
use crate::lens_library;
use crate::viewer::offscreen::Offscreen;
use crate::viewer::window::{self, OnClose, WindowApp};
use crate::viewer::{Viewer, ViewerOptions};

#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Lens file or the name of a bundled lens.
    pub lens: String,
    /// A light at infinity, THETA,PHI[,INTENSITY[,COLOUR]] as for `render` (repeat for
    /// several; the first one follows a drag in the flare view). Default 8,30.
    #[arg(long = "light", value_parser = LightSpec::parse)]
    pub lights: Vec<LightSpec>,
    /// The flare preview's render size, WxH.
    #[arg(long, value_parser = parse_size, default_value = "960x540")]
    pub size: (usize, usize),
    /// The preset the preview settles on (a fast frame always comes first).
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    /// Diffraction starburst: on, off or only.
    #[arg(long, value_enum, default_value_t = StarburstMode::On)]
    pub starburst: StarburstMode,
    /// Iris blade count (0: a circular stop).
    #[arg(long, default_value_t = 0)]
    pub iris_blades: u32,
    /// Where the flare is drawn: auto (a hardware GPU if there is one, else the CPU), cpu or gpu.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// Draw the window's views offscreen into this PNG once the flare has settled, instead of
    /// opening a window (needs no display).
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// Print a line to standard output for every frame shown, light move, selection and
    /// layout change (for scripts and tests that drive the window).
    #[arg(long)]
    pub log: bool,
    /// The window's size (logical pixels), WxH; with --screenshot, the offscreen image's.
    #[arg(long, value_parser = parse_size, default_value = "1500x820")]
    pub window_size: (usize, usize),
    /// A second lens to compare with (file or bundled name): `C` in the window swaps the
    /// two (A/B), with the same lights, aperture and exposure — a lens from `flarebench fit`
    /// or `flarebench coatings` against the original, say.
    #[arg(long)]
    pub compare: Option<String>,
    #[command(flatten)]
    pub algos: AlgoArgs,
}

/// The flare preview's ghost plugins (`view`, `edit --window`).
#[derive(Clone, Debug, Default, Args)]
pub struct AlgoArgs {
    /// Render the flare preview's ghosts with this plugin instead of the built-in renderer: a
    /// plugin name or library path, optionally with parameters, NAME:key=value,… (as for
    /// `compare --algo`). Repeat for several; `A` in the window cycles through the built-in
    /// renderer and them. Their libraries are watched: a rebuilt one is loaded afresh (beside
    /// the old, which stays loaded) and the preview renders again; one that fails to load
    /// leaves the previous in use, with the error in the status line.
    #[arg(long = "algo", value_name = "NAME[:k=v,…]")]
    pub algos: Vec<String>,
    /// Also load this plugin library (repeatable), as for `compare --plugin`.
    #[arg(long = "plugin", value_name = "PATH")]
    pub plugins: Vec<PathBuf>,
}

impl AlgoArgs {
    /// Each `--algo` resolved to its plugin (as `compare --watch` resolves them: a library
    /// given by path is loaded as a fresh copy, every library watched from now on); an error
    /// names the first that did not load or does not take its parameters.
    pub fn resolve(&self) -> anyhow::Result<Vec<Algo>> {
        let algos: Vec<Algo> = self
            .algos
            .iter()
            .map(|spec| Algo::resolve(spec, &self.plugins, true))
            .collect();
        for a in &algos {
            match &a.plugin {
                Err(e) => anyhow::bail!("--algo {}: {e}", a.spec),
                Ok(p) => {
                    flarebench_sdk::abi::params::parse_values(&p.params, a.split().1)
                        .with_context(|| format!("--algo {}", a.spec))?;
                }
            }
        }
        Ok(algos)
    }
}

impl ViewArgs {
    fn options(&self) -> anyhow::Result<ViewerOptions> {
        let mut o = ViewerOptions {
            backend: self.backend,
            size: self.size,
            quality: self.quality,
            starburst: self.starburst,
            blades: self.iris_blades,
            ..ViewerOptions::default()
        };
        if self.iris_blades > 0 {
            flarebench_sdk::aperture::Aperture::Iris {
                blades: self.iris_blades,
                rotation_rad: 0.0,
                roundness: 0.0,
            }
            .validate()
            .context("--iris-blades")?;
        }
        if !self.lights.is_empty() {
            o.lights = self.lights.clone();
        }
        Ok(o)
    }
}

pub fn run(args: &ViewArgs, quiet: bool) -> anyhow::Result<()> {
    let loaded = lens_library::load(&args.lens, quiet)?;
    let compared = args
        .compare
        .as_deref()
        .map(|c| lens_library::load(c, quiet))
        .transpose()?;
    let options = args.options()?;
    let algos = args.algos.resolve()?;
    if let Some(path) = &args.screenshot {
        let mut viewer = Viewer::new(loaded.system, options, Box::new(|| {})).with_algos(algos)?;
        if let Some(c) = compared {
            viewer = viewer.with_compare(c.system);
        }
        let (w, h) = args.window_size;
        let mut target = Offscreen::new(w as u32, h as u32)?;
        let settled = target.settle(&mut viewer, Duration::from_secs(600));
        // Written also when the render failed: the status line in it says why.
        target
            .read()?
            .save(path)
            .with_context(|| format!("could not write `{}`", path.display()))?;
        if !quiet {
            eprintln!("wrote {}", path.display());
        }
        if let Some(why) = viewer.render_failure() {
            anyhow::bail!("{why}");
        }
        anyhow::ensure!(settled, "the flare did not settle within 10 minutes");
        return Ok(());
    }
    let event_loop = window::event_loop()?;
    let mut viewer = Viewer::new(
        loaded.system,
        options,
        window::waker(event_loop.create_proxy()),
    )
    .with_algos(algos)?;
    if let Some(c) = compared {
        viewer = viewer.with_compare(c.system);
    }
    if args.log {
        viewer = viewer.with_log(Box::new(|line| {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        }));
    }
    let mut app = WindowApp::new(&event_loop, viewer, true, OnClose::Exit)
        .with_size(args.window_size.0 as f64, args.window_size.1 as f64);
    window::run(event_loop, &mut app)
}
