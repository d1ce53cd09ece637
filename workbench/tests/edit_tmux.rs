//! End to end: the built `flarebench edit` runs in a real terminal (a detached tmux session),
//! receives keys, edits a cell, saves with Ctrl-s and quits; the file on disk must hold the
//! edit. Skipped with a message when tmux is not installed locally; under CI (`CI` set) a
//! missing tmux is a failure, since `.ci/run` installs it.

use crate::common;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use flarebench_sdk::io::read_lens;

/// A tmux server of this test alone (its own socket name), killed when dropped.
struct Tmux {
    socket: String,
}

impl Tmux {
    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .args(["-L", &self.socket, "-f", "/dev/null"])
            .args(args)
            .output()
            .expect("tmux runs")
    }

    fn pane(&self) -> String {
        String::from_utf8_lossy(&self.run(&["capture-pane", "-p", "-t", "e2e"]).stdout).into()
    }

    /// Waits until the pane shows `text`; panics with the pane after 20 s.
    fn wait_for(&self, text: &str) -> String {
        let start = Instant::now();
        loop {
            let pane = self.pane();
            if pane.contains(text) {
                return pane;
            }
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "the editor never showed `{text}`; the pane:\n{pane}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn keys(&self, keys: &[&str]) {
        for k in keys {
            let out = self.run(&["send-keys", "-t", "e2e", k]);
            assert!(out.status.success(), "send-keys {k}: {out:?}");
        }
    }

    /// Waits until the editor has quit (its session ended); panics with the pane after 20 s.
    fn wait_until_ended(&self) {
        let start = Instant::now();
        while self.session_alive() {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "the editor did not quit: {}",
                self.pane()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn session_alive(&self) -> bool {
        self.run(&["has-session", "-t", "e2e"]).status.success()
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

fn tmux_available() -> bool {
    Command::new("tmux")
        .arg("-V")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn edit_a_cell_save_and_quit_in_a_real_terminal() {
    if !tmux_available() {
        assert!(
            std::env::var_os("CI").is_none(),
            "tmux is missing under CI: .ci/run should install it"
        );
        eprintln!("skipped: tmux is not installed (CI installs it; apt-get install tmux)");
        return;
    }
    // Declared before `tmux`, so the directory outlives the tmux server (dropped first, in
    // reverse order) and the editor it runs.
    let tmp = common::temp_dir("edit-tmux");
    let dir = tmp.path();
    let path = heliar_copy(dir);
    let original = read_lens(&path).unwrap().system;
    assert_ne!(original.surfaces[1].thickness, 7.5);

    let command = format!(
        "'{}' edit '{}'",
        env!("CARGO_BIN_EXE_flarebench"),
        path.display()
    );
    let tmux = session("edit", 120, &command);
    tmux.wait_for("flarebench edit — heliar-tronnier.xml");

    // Surface 1, thickness column: edit, clear, type 7.5, accept.
    tmux.keys(&["j", "l", "Enter", "C-u", "7", ".", "5", "Enter"]);
    let pane = tmux.wait_for("[modified]");
    assert!(
        pane.lines()
            .any(|l| l.contains("│ 1  refract") && l.contains(" 7.5 ")),
        "{pane}"
    );
    // The recovery file already holds the edit.
    let recovery = dir.join(".heliar-tronnier.xml.recover");
    assert!(recovery.exists());

    tmux.keys(&["C-s"]);
    tmux.wait_for("saved ");
    tmux.keys(&["q"]);
    tmux.wait_until_ended();

    let saved = read_lens(&path).unwrap().system;
    assert_eq!(saved.surfaces[1].thickness, 7.5);
    let mut expected = original;
    expected.surfaces[1].thickness = 7.5;
    assert_eq!(saved, expected, "only that cell changed");
    assert!(!recovery.exists(), "saving removes the recovery file");
}

#[test]
fn without_a_terminal_or_a_lens_the_errors_are_clear() {
    // Standard output is a pipe here, not a terminal.
    let out = common::flarebench(&["edit", "heliar-tronnier"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("needs a terminal"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let out = common::flarebench(&["edit", "no-such-lens"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("could not open lens `no-such-lens`")
            && err.contains("`flarebench lenses` lists"),
        "points to the listing of the bundled lenses: {err}"
    );
}

/// A copy of the bundled Heliar-Tronnier in `dir`, to edit and save.
fn heliar_copy(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("heliar-tronnier.xml");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/heliar-tronnier.xml"),
        &path,
    )
    .unwrap();
    path
}

/// A detached tmux session `e2e` (`cols` × 40) of a server named after `tag`, running the
/// shell `command`.
fn session(tag: &str, cols: u16, command: &str) -> Tmux {
    let tmux = Tmux {
        socket: format!("flarebench-e2e-{tag}-{}", std::process::id()),
    };
    let cols = cols.to_string();
    let out = tmux.run(&[
        "new-session",
        "-d",
        "-s",
        "e2e",
        "-x",
        &cols,
        "-y",
        "40",
        command,
    ]);
    assert!(out.status.success(), "tmux new-session: {out:?}");
    tmux
}

/// The share of pixels in `rect` (x, y, w, h) that differ between two screenshots.
fn changed(a: &image::RgbImage, b: &image::RgbImage, rect: [u32; 4]) -> f64 {
    let [x0, y0, w, h] = rect;
    let mut n = 0;
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            if a.get_pixel(x, y) != b.get_pixel(x, y) {
                n += 1;
            }
        }
    }
    n as f64 / (w * h) as f64
}

#[test]
#[cfg(feature = "window")]
fn edit_with_a_window_shows_each_edit_in_the_window() {
    use common::x11::{Xvfb, x_tools};
    if !tmux_available() || !x_tools() {
        assert!(
            std::env::var_os("CI").is_none(),
            "tmux or X tools missing under CI"
        );
        eprintln!("skipped: tmux or the X tools are not installed");
        return;
    }
    let tmp = common::temp_dir("edit-window");
    let path = heliar_copy(tmp.path());
    let x = Xvfb::start();
    let command = format!(
        "env DISPLAY={} '{}' edit --window '{}'",
        x.display,
        env!("CARGO_BIN_EXE_flarebench"),
        path.display()
    );
    let tmux = session("window", 120, &command);
    tmux.wait_for("flarebench edit — heliar-tronnier.xml");

    // The window (at the screen's top-left corner: Xvfb has no window manager) settles: two
    // screenshots a second apart alike, the flare drawn.
    let lens_area = [20, 60, 500, 500];
    let flare_area = [700, 100, 500, 400];
    let settle = |what: &str| -> image::RgbImage {
        let start = Instant::now();
        let mut last = x.screenshot();
        loop {
            std::thread::sleep(Duration::from_millis(1000));
            let now = x.screenshot();
            if changed(&last, &now, [0, 0, 1280, 720]) == 0.0
                && changed(&now, &image::RgbImage::new(1280, 720), flare_area) > 0.01
            {
                return now;
            }
            assert!(
                start.elapsed() < Duration::from_secs(240),
                "the window never settled {what}; the editor:\n{}",
                tmux.pane()
            );
            last = now;
        }
    };
    let before = settle("after opening");

    // Surface 0's radius (30.81 mm) made 24 mm in the terminal: the lens and the flare change.
    tmux.keys(&["Enter", "C-u", "2", "4", "Enter"]);
    tmux.wait_for("[modified]");
    let after = settle("after the edit");
    assert!(
        changed(&before, &after, lens_area) > 0.001,
        "the lens view did not change"
    );
    assert!(
        changed(&before, &after, flare_area) > 0.001,
        "the flare did not change"
    );

    // Quitting the editor closes the window and ends the process.
    tmux.keys(&[":", "q", "!", "Enter"]);
    tmux.wait_until_ended();
}

#[test]
#[cfg(feature = "window")]
fn edit_with_a_window_but_no_display_runs_the_editor_with_a_note() {
    if !tmux_available() {
        assert!(std::env::var_os("CI").is_none(), "tmux missing under CI");
        return;
    }
    // A copy: an edit writes the recovery file beside the lens, and other tests open the
    // bundled one at the same time.
    let tmp = common::temp_dir("edit-nodisplay");
    let path = heliar_copy(tmp.path());
    let command = format!(
        "env -u DISPLAY -u WAYLAND_DISPLAY '{}' edit --window '{}'",
        env!("CARGO_BIN_EXE_flarebench"),
        path.display()
    );
    let tmux = session("nodisplay", 160, &command);
    tmux.wait_for("no window: cannot open a window");
    // The editor works: an edit goes in.
    tmux.keys(&["j", "l", "Enter", "C-u", "7", ".", "5", "Enter"]);
    tmux.wait_for("[modified]");
    tmux.keys(&[":", "q", "!", "Enter"]);
}

#[test]
#[cfg(feature = "window")]
fn a_render_panic_beside_the_editor_loses_no_edit() {
    use common::x11::{Xvfb, x_tools};
    if !tmux_available() || !x_tools() {
        assert!(
            std::env::var_os("CI").is_none(),
            "tmux or X tools missing under CI"
        );
        return;
    }
    let tmp = common::temp_dir("edit-window-panic");
    let path = heliar_copy(tmp.path());
    let x = Xvfb::start();
    // Every render panics (fault injection): the window says so, the editor goes on.
    let command = format!(
        "env DISPLAY={} FLAREBENCH_FAULT=render-panic '{}' edit --window '{}'",
        x.display,
        env!("CARGO_BIN_EXE_flarebench"),
        path.display()
    );
    let tmux = session("panic", 120, &command);
    tmux.wait_for("flarebench edit — heliar-tronnier.xml");
    std::thread::sleep(Duration::from_millis(2000));
    tmux.keys(&["j", "l", "Enter", "C-u", "7", ".", "5", "Enter"]);
    tmux.wait_for("[modified]");
    tmux.keys(&["C-s"]);
    tmux.wait_for("saved ");
    tmux.keys(&["q"]);
    tmux.wait_until_ended();
    let saved = read_lens(&path).unwrap().system;
    assert_eq!(saved.surfaces[1].thickness, 7.5);
}
