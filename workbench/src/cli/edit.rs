//! `flarebench edit`: open the terminal prescription editor on a lens, with the viewer window
//! beside it (`--window`, or `W` / `:window` later).
//!
//! With a display, the winit event loop owns the main thread and the terminal editor runs on
//! a thread of its own; the window follows the editor's document (`Document::subscribe`) and
//! selection, and sends its clicks back. Without a display, the editor runs alone and says why
//! there is no window.

use anyhow::Context;
use clap::Args;

use crate::edit::{app::App, files, runner};

/// The bundled lens opened when no lens is given.
const DEFAULT_LENS: &str = "heliar-tronnier";

#[derive(Debug, Args)]
pub struct EditArgs {
    /// Lens file (`.xml`; `.zmx`, `.dat` and `.lens` are saved as `.xml` beside them) or the
    /// name of a bundled lens. Without one, a copy of the bundled Heliar-Tronnier (saving asks
    /// for a path).
    pub lens: Option<String>,
    /// Open the viewer window beside the editor: the lens section and a live flare preview
    /// that follow every edit (docs/window.md). `W` or `:window` opens it later.
    #[cfg(feature = "window")]
    #[arg(long)]
    pub window: bool,
    /// The window's ghost plugins (`--algo`, `--plugin`), as for `view`.
    #[cfg(feature = "window")]
    #[command(flatten)]
    pub algos: super::view::AlgoArgs,
}

pub fn run(args: &EditArgs, _quiet: bool) -> anyhow::Result<()> {
    let spec = args.lens.as_deref().unwrap_or(DEFAULT_LENS);
    let opened = files::open(spec, args.lens.is_none())
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("could not open lens `{spec}`"))?;
    let app = App::new(opened).with_context(|| format!("cannot edit `{spec}`"))?;
    #[cfg(feature = "window")]
    {
        // Resolved before the terminal is taken over, so an error is printed plainly.
        let algos = args.algos.resolve()?;
        with_window(app, args.window, algos)
    }
    #[cfg(not(feature = "window"))]
    {
        runner::run(app)
    }
}

/// The editor on a thread of its own beside the window's event loop on this (the main)
/// thread; the editor alone when there can be no window.
#[cfg(feature = "window")]
fn with_window(
    mut app: App,
    open_now: bool,
    algos: Vec<crate::algo_spec::Algo>,
) -> anyhow::Result<()> {
    use std::panic::{AssertUnwindSafe, catch_unwind};
    use std::sync::mpsc::channel;

    use crate::edit::action::Action;
    use crate::link::{FromEditor, ToEditor};
    use crate::viewer::flare_worker::panic_message;
    use crate::viewer::window::{self, OnClose, UserEvent, WindowApp};
    use crate::viewer::{EditorLink, Viewer, ViewerOptions};

    anyhow::ensure!(
        std::io::IsTerminal::is_terminal(&std::io::stdout()),
        "`flarebench edit` needs a terminal (standard output is not one)"
    );
    let event_loop = match window::event_loop() {
        Ok(l) => l,
        Err(e) => {
            if open_now {
                app.update(Action::Failed(format!("no window: {e:#}")));
            }
            return runner::run(app);
        }
    };
    let proxy = event_loop.create_proxy();

    // Document changes → the window (woken for each).
    let changes = app.doc.subscribe();
    let (change_tx, change_rx) = channel();
    let p = proxy.clone();
    std::thread::Builder::new()
        .name("edit-changes".into())
        .spawn(move || {
            for c in changes {
                if change_tx.send(c).is_err() {
                    break;
                }
                let _ = p.send_event(UserEvent::Wake);
            }
        })
        .context("could not start the change forwarder")?;
    let (selection_tx, selection_rx) = channel::<FromEditor>();
    let (to_editor, from_window) = channel::<ToEditor>();

    let p = proxy.clone();
    let p2 = proxy.clone();
    let host = runner::WindowHost {
        open: Box::new(move || {
            p.send_event(UserEvent::Open)
                .map_err(|_| "the window's event loop has ended".to_string())
        }),
        from_window,
        to_window: Box::new(move |m| {
            let _ = selection_tx.send(m);
            let _ = p2.send_event(UserEvent::Wake);
        }),
    };
    let system = app.doc.system().clone();
    let quit = proxy.clone();
    let editor = std::thread::Builder::new()
        .name("editor".into())
        .spawn(move || {
            let r = catch_unwind(AssertUnwindSafe(|| runner::run_with(app, Some(host))));
            let _ = quit.send_event(UserEvent::Quit);
            match r {
                Ok(r) => r,
                Err(p) => Err(anyhow::anyhow!(
                    "the editor panicked: {}",
                    panic_message(&*p)
                )),
            }
        })
        .context("could not start the editor thread")?;

    let link = EditorLink {
        changes: change_rx,
        selection: selection_rx,
        to_editor: to_editor.clone(),
    };
    let viewer = Viewer::new(system, ViewerOptions::default(), window::waker(proxy))
        .with_link(link)
        .with_algos(algos)?;
    let notes = to_editor.clone();
    let mut wapp =
        WindowApp::new(&event_loop, viewer, open_now, OnClose::Wait).on_error(Box::new(move |e| {
            let _ = notes.send(ToEditor::Note(format!("window: {e}")));
        }));
    // Whatever happens to the window, the editor keeps running and keeps its edits.
    let ended = catch_unwind(AssertUnwindSafe(|| window::run(event_loop, &mut wapp)));
    let note = match ended {
        Ok(Ok(())) => None,
        Ok(Err(e)) => Some(format!("the window ended: {e:#}")),
        Err(p) => Some(format!("the window panicked: {}", panic_message(&*p))),
    };
    if let Some(n) = note {
        let _ = to_editor.send(ToEditor::Note(n));
    }
    drop(wapp);
    editor
        .join()
        .map_err(|_| anyhow::anyhow!("the editor thread ended abnormally"))?
}
