//! The editor driven by key scripts through the real keymap, `App::update` and the file
//! effects, drawn into ratatui's `TestBackend` (insta snapshots of the screen) with the
//! results checked against the optics: the analysis after an edit equals a fresh paraxial
//! analysis of the edited prescription, saves write the file, recovery files come and go.

use crate::common;

use std::path::{Path, PathBuf};

use flarebench::edit::action::Action;
use flarebench::edit::app::{App, Focus, Mode, Prompt};
use flarebench::edit::keymap::{KEY_HELP, action_for};
use flarebench::edit::{dispatch, files, view};
use flarebench_sdk::Medium;
use flarebench_sdk::io::{parse_olf_xml, read_lens};
use flarebench_sdk::paraxial::analyse;
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

/// A fresh directory for one test, holding a copy of the bundled lens `name`: the directory
/// (removed when it is dropped, so the test keeps it) and the copy's path.
fn lens_copy(test: &str, name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = common::temp_dir(&format!("edit-app-{test}"));
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../lenses/{name}.xml"));
    let dst = dir.path().join(format!("{name}.xml"));
    std::fs::copy(src, &dst).unwrap();
    (dir, dst)
}

fn open(path: &Path) -> App {
    App::new(files::open(path.to_str().unwrap(), false).unwrap()).unwrap()
}

/// Presses one key; true when the editor quits.
fn press(app: &mut App, code: KeyCode, modifiers: KeyModifiers) -> bool {
    match action_for(app.key_mode(), KeyEvent::new(code, modifiers)) {
        Some(a) => dispatch(app, a),
        None => false,
    }
}

fn key(app: &mut App, code: KeyCode) -> bool {
    press(app, code, KeyModifiers::NONE)
}

fn ctrl(app: &mut App, c: char) -> bool {
    press(app, KeyCode::Char(c), KeyModifiers::CONTROL)
}

/// Types `text`, one key per character.
fn keys(app: &mut App, text: &str) {
    for c in text.chars() {
        assert!(!key(app, KeyCode::Char(c)), "quit while typing {text}");
    }
}

fn screen(app: &App) -> String {
    let mut t = Terminal::new(TestBackend::new(app.size.0, app.size.1)).unwrap();
    t.draw(|f| view::draw(f, app)).unwrap();
    t.backend().to_string()
}

fn efl(app: &App) -> f64 {
    app.analysis.paraxial.as_ref().unwrap().efl_mm
}

#[test]
fn opening_screen() {
    let (_dir, path) = lens_copy("opening", "heliar-tronnier");
    let app = open(&path);
    insta::assert_snapshot!("opening", screen(&app));
}

#[test]
fn editing_a_thickness_updates_the_analysis() {
    let (_dir, path) = lens_copy("thickness", "heliar-tronnier");
    let mut app = open(&path);
    let before = efl(&app);
    // Down to surface 1, right to the thickness column, edit, clear, type, accept.
    key(&mut app, KeyCode::Char('j'));
    key(&mut app, KeyCode::Char('l'));
    key(&mut app, KeyCode::Enter);
    ctrl(&mut app, 'u');
    keys(&mut app, "5");
    key(&mut app, KeyCode::Enter);
    assert_eq!(app.mode, Mode::Normal);
    assert_eq!(app.doc.system().surfaces[1].thickness, 5.0);
    let expected = analyse(app.doc.system(), app.doc.system().default_wavelength_nm()).unwrap();
    assert_eq!(efl(&app), expected.efl_mm);
    assert!((efl(&app) - before).abs() > 0.1, "{before} → {}", efl(&app));
    assert!(app.dirty());
    insta::assert_snapshot!("thickness_edited", screen(&app));
    // Undo (u) restores the analysis; redo (Ctrl-r) brings the edit back.
    key(&mut app, KeyCode::Char('u'));
    assert_eq!(efl(&app), before);
    assert!(!app.dirty());
    ctrl(&mut app, 'r');
    assert_eq!(efl(&app), expected.efl_mm);
    ctrl(&mut app, 'z');
    ctrl(&mut app, 'y');
    assert_eq!(app.doc.system().surfaces[1].thickness, 5.0);
}

#[test]
fn invalid_input_is_shown_and_refused() {
    let (_dir, path) = lens_copy("invalid", "heliar-tronnier");
    let mut app = open(&path);
    let original = app.doc.system().clone();
    // Radius of surface 0: a typo.
    key(&mut app, KeyCode::F(2));
    ctrl(&mut app, 'u');
    keys(&mut app, "3x");
    assert!(matches!(app.edit_status, Some(Err(ref e)) if e.contains("not a number")));
    insta::assert_snapshot!("invalid_radius", screen(&app));
    key(&mut app, KeyCode::Enter);
    assert!(matches!(app.mode, Mode::Cell(_)), "stays in the editor");
    assert_eq!(app.doc.system(), &original);
    // A number, but the surface cannot be that steep for its semi-diameter (14.5 mm).
    key(&mut app, KeyCode::Backspace);
    key(&mut app, KeyCode::Backspace);
    keys(&mut app, "10");
    assert!(matches!(app.edit_status, Some(Err(ref e)) if e.contains("semi-diameter")));
    key(&mut app, KeyCode::Tab);
    assert_eq!(app.doc.system(), &original);
    key(&mut app, KeyCode::Esc);
    assert_eq!(app.mode, Mode::Normal);
    assert_eq!(app.doc.system(), &original);
    assert_eq!(app.doc.undo_len(), 0);
}

#[test]
fn glass_names_complete_from_the_catalogue() {
    let (_dir, path) = lens_copy("glass", "heliar-tronnier");
    let mut app = open(&path);
    for _ in 0..2 {
        key(&mut app, KeyCode::Char('l'));
    }
    key(&mut app, KeyCode::Enter);
    ctrl(&mut app, 'u');
    keys(&mut app, "n-bk");
    assert!(app.completions().contains(&"SCHOTT:N-BK7".to_string()));
    ctrl(&mut app, 'n');
    let Mode::Cell(ed) = &app.mode else { panic!() };
    let first = ed.text.clone();
    assert!(first.contains(":N-BK"), "{first}");
    insta::assert_snapshot!("glass_completion", screen(&app));
    // Tab accepts and moves to the nd column, which now shows the glass's index.
    key(&mut app, KeyCode::Tab);
    let Medium::Glass { name, .. } = &app.doc.system().surfaces[0].medium else {
        panic!("{:?}", app.doc.system().surfaces[0].medium)
    };
    assert_eq!(name, &first);
    assert_eq!(app.focus, Focus::Cell { row: 0, col: 4 });
}

#[test]
fn rows_insert_duplicate_delete_and_move_with_undo() {
    let (_dir, path) = lens_copy("rows", "heliar-tronnier");
    let mut app = open(&path);
    let original = app.doc.system().clone();
    let n = original.surfaces.len();
    key(&mut app, KeyCode::Char('O'));
    assert_eq!(app.doc.system().surfaces.len(), n + 1);
    let blank = &app.doc.system().surfaces[0];
    assert!(blank.curvature == 0.0 && blank.medium.is_air() && blank.thickness == 0.0);
    key(&mut app, KeyCode::Char('d'));
    assert_eq!(app.doc.system(), &original);
    key(&mut app, KeyCode::Char('y'));
    assert_eq!(app.doc.system().surfaces[1], original.surfaces[0]);
    assert!(
        matches!(app.focus, Focus::Cell { row: 1, .. }),
        "on the copy"
    );
    key(&mut app, KeyCode::Char('u'));
    assert_eq!(app.doc.system(), &original);
    // Move surface 1 down: it swaps with surface 2 and the selection follows.
    key(&mut app, KeyCode::Char('g'));
    key(&mut app, KeyCode::Char('j'));
    key(&mut app, KeyCode::Char('J'));
    assert_eq!(app.doc.system().surfaces[2], original.surfaces[1]);
    assert!(matches!(app.focus, Focus::Cell { row: 2, .. }));
    key(&mut app, KeyCode::Char('K'));
    assert_eq!(app.doc.system(), &original);
    // The sensor cannot be deleted, nor anything inserted after it.
    key(&mut app, KeyCode::Char('G'));
    key(&mut app, KeyCode::Delete);
    assert!(app.message.as_ref().unwrap().error);
    key(&mut app, KeyCode::Char('o'));
    assert!(app.message.as_ref().unwrap().text.contains("sensor"));
    assert_eq!(app.doc.system(), &original);
    // Undo everything that was applied.
    while app.doc.undo_len() > 0 {
        key(&mut app, KeyCode::Char('u'));
    }
    assert_eq!(app.doc.system(), &original);
}

#[test]
fn help_shows_the_key_map() {
    let (_dir, path) = lens_copy("help", "heliar-tronnier");
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('?'));
    assert_eq!(app.mode, Mode::Help);
    insta::assert_snapshot!("help", screen(&app));
    key(&mut app, KeyCode::Esc);
    assert_eq!(app.mode, Mode::Normal);
}

#[test]
fn the_selected_ghost_path_is_traced() {
    let (_dir, path) = lens_copy("ghost", "heliar-tronnier");
    let mut app = open(&path);
    key(&mut app, KeyCode::Char(']'));
    assert_eq!(app.ghost, Some(0));
    let g = app.analysis.ghosts[0];
    assert_eq!((g.first(), g.second()), (1, 0));
    assert!(!app.ghost_rays.is_empty());
    // The path goes back toward the object after the first reflection (z decreases).
    let reverses = app
        .ghost_rays
        .iter()
        .any(|l| l.windows(2).any(|w| w[1].0 < w[0].0));
    assert!(reverses);
    insta::assert_snapshot!("ghost_1_0", screen(&app));
    key(&mut app, KeyCode::Char('['));
    assert_eq!(app.ghost, None);
    assert!(app.ghost_rays.is_empty());
    key(&mut app, KeyCode::Char('['));
    assert_eq!(app.ghost, Some(app.analysis.ghosts.len() - 1));
}

#[test]
fn save_writes_the_file_and_removes_the_recovery_file() {
    let (_dir, path) = lens_copy("save", "heliar-tronnier");
    let recovery = files::recovery_path(&path);
    assert_eq!(
        recovery.file_name().unwrap(),
        ".heliar-tronnier.xml.recover"
    );
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('j'));
    key(&mut app, KeyCode::Char('l'));
    keys(&mut app, "2.5"); // a digit starts a new value
    key(&mut app, KeyCode::Enter);
    // Every committed edit is in the recovery file at once.
    let text = std::fs::read_to_string(&recovery).unwrap();
    let rec = parse_olf_xml(&text, "recovery").unwrap().system;
    assert_eq!(rec.surfaces[1].thickness, 2.5);
    assert_eq!(&rec, app.doc.system());
    ctrl(&mut app, 's');
    assert!(!app.dirty());
    assert!(!recovery.exists());
    let saved = read_lens(&path).unwrap().system;
    assert_eq!(&saved, app.doc.system());
    assert!(app.message.as_ref().unwrap().text.starts_with("saved"));
    // `:w PATH` saves a copy elsewhere and continues there.
    let other = path.with_file_name("copy.xml");
    key(&mut app, KeyCode::Char(':'));
    keys(&mut app, &format!("w {}", other.display()));
    key(&mut app, KeyCode::Enter);
    assert_eq!(read_lens(&other).unwrap().system, saved);
    assert_eq!(app.path.as_deref(), Some(other.as_path()));
    // Not an XML name: refused.
    key(&mut app, KeyCode::Char(':'));
    keys(&mut app, "w x.zmx");
    key(&mut app, KeyCode::Enter);
    assert!(app.message.as_ref().unwrap().error);
}

#[test]
fn reopening_offers_recovery() {
    let (_dir, path) = lens_copy("recover", "heliar-tronnier");
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('j'));
    key(&mut app, KeyCode::Char('l'));
    keys(&mut app, "3");
    key(&mut app, KeyCode::Enter);
    let edited = app.doc.system().clone();
    drop(app); // the terminal was killed: nothing saved
    let mut app = open(&path);
    assert!(matches!(app.mode, Mode::Prompt(Prompt::Recover(_))));
    insta::assert_snapshot!("recover_prompt", screen(&app));
    key(&mut app, KeyCode::Char('r'));
    assert_eq!(app.doc.system(), &edited);
    assert!(app.dirty(), "recovered edits are not saved yet");
    // Discarding removes the recovery file.
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('d'));
    assert_eq!(app.doc.system(), &read_lens(&path).unwrap().system);
    assert!(!files::recovery_path(&path).exists());
    assert_eq!(open(&path).mode, Mode::Normal);
}

#[test]
fn quitting_with_unsaved_changes_asks() {
    let (_dir, path) = lens_copy("quit", "heliar-tronnier");
    let mut app = open(&path);
    assert!(key(&mut app, KeyCode::Char('q')), "nothing to save: quits");
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('O'));
    assert!(!key(&mut app, KeyCode::Char('q')));
    assert_eq!(app.mode, Mode::Prompt(Prompt::QuitUnsaved));
    insta::assert_snapshot!("quit_prompt", screen(&app));
    assert!(!key(&mut app, KeyCode::Char('c')));
    assert_eq!(app.mode, Mode::Normal);
    assert!(!ctrl(&mut app, 'c'));
    assert!(key(&mut app, KeyCode::Char('d')), "discard and quit");
    assert!(!files::recovery_path(&path).exists());
    assert_eq!(
        read_lens(&path).unwrap().system,
        open(&path).doc.system().clone()
    );
    // Save and quit.
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('O'));
    key(&mut app, KeyCode::Char('q'));
    assert!(key(&mut app, KeyCode::Char('s')));
    assert_eq!(read_lens(&path).unwrap().system, *app.doc.system());
}

#[test]
fn untitled_lenses_ask_where_to_save() {
    let (dir, _) = lens_copy("untitled", "heliar-tronnier");
    let mut app = App::new(files::open("heliar-tronnier", true).unwrap()).unwrap();
    assert_eq!(app.path, None);
    ctrl(&mut app, 's');
    assert!(matches!(app.mode, Mode::Line { .. }));
    ctrl(&mut app, 'u');
    let target = dir.path().join("mine.xml");
    keys(&mut app, &target.display().to_string());
    key(&mut app, KeyCode::Enter);
    assert_eq!(app.path.as_deref(), Some(target.as_path()));
    assert_eq!(read_lens(&target).unwrap().system, *app.doc.system());
}

/// The paraxial f-number against the f/8 typed into the header.
const F_NUMBER_TOL: f64 = 0.05;

#[test]
fn header_fields_are_edited_in_the_form() {
    let (_dir, path) = lens_copy("header", "heliar-tronnier");
    let mut app = open(&path);
    key(&mut app, KeyCode::Char('k')); // from the table up into the form (f-number)
    assert_eq!(app.focus, Focus::Header(1));
    key(&mut app, KeyCode::Enter);
    ctrl(&mut app, 'u');
    keys(&mut app, "8");
    key(&mut app, KeyCode::Enter);
    assert_eq!(app.doc.system().f_number, Some(8.0));
    let p = app.analysis.paraxial.as_ref().unwrap();
    assert!((p.f_number - 8.0).abs() < F_NUMBER_TOL, "{}", p.f_number);
}

#[test]
fn mouse_clicks_select_cells() {
    let (_dir, path) = lens_copy("mouse", "heliar-tronnier");
    let mut app = open(&path);
    // Table at x 0, y 2; first surface row at y 4; cells start at x 5
    // (border, 3-wide row number, space); thickness is the third column (7 + 1 + 9 + 1).
    dispatch(
        &mut app,
        Action::Click {
            x: 5 + 18,
            y: 4 + 3,
        },
    );
    assert_eq!(app.focus, Focus::Cell { row: 3, col: 2 });
    dispatch(&mut app, Action::Click { x: 2, y: 1 });
    assert_eq!(app.focus, Focus::Header(0));
    dispatch(&mut app, Action::Click { x: 200, y: 39 });
    assert_eq!(app.focus, Focus::Header(0), "outside every cell: unchanged");
}

#[test]
fn long_lenses_scroll() {
    let (_dir, path) = lens_copy("scroll", "nikon-zoom-mid");
    let mut app = open(&path);
    dispatch(
        &mut app,
        Action::Resize {
            width: 120,
            height: 30,
        },
    );
    key(&mut app, KeyCode::Char('G'));
    let rows = view::table_rows(app.size);
    assert_eq!(app.scroll, app.doc.system().surfaces.len() - rows);
    assert!(screen(&app).contains("sensor"));
    key(&mut app, KeyCode::Char('g'));
    assert_eq!(app.scroll, 0);
}

#[test]
fn the_key_map_is_documented() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/editor.md")).unwrap();
    for (keys, what) in KEY_HELP {
        let row = format!("| {keys} | {what} |");
        assert!(doc.contains(&row), "docs/editor.md lacks `{row}`");
    }
}
