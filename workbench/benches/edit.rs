//! The editor's reaction to one edit on the Nikon zoom (`lenses/nikon-zoom-long.xml`, 23
//! surfaces, 210 ghost paths): the cell edit committed through `App::update` (cell parsing,
//! whole-system validation, the edit applied, paraxial analysis, outline, two ray fans, ghost
//! list, the selected ghost's ray path) and the frame redrawn into a 120 × 40 `TestBackend`.
//!
//! - `commit_and_draw`: the whole reaction (target ≤ 16 ms, one frame at 60 Hz);
//! - `commit`: `App::update` only; `draw`: the redraw only;
//! - `recovery_write`: the recovery file written after the edit (atomic write + fsync).
//!
//! Run: `cargo bench -p flarebench --bench edit`.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use flarebench::edit::action::{Action, Effect};
use flarebench::edit::app::App;
use flarebench::edit::{files, view};
use ratatui::Terminal;
use ratatui::backend::TestBackend;

fn nikon() -> App {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/nikon-zoom-long.xml");
    let mut app = App::new(files::open(path.to_str().unwrap(), false).unwrap()).unwrap();
    // Surface 10's thickness, with a ghost selected so its path is traced too.
    for _ in 0..10 {
        app.update(Action::Move(flarebench::edit::action::Move::Down));
    }
    app.update(Action::Move(flarebench::edit::action::Move::Right));
    app.update(Action::NextGhost);
    app
}

/// Types `value` into the selected cell and commits it; returns the effects (not performed).
fn commit(app: &mut App, value: &str) -> Vec<Effect> {
    app.update(Action::Edit);
    app.update(Action::ClearInput);
    for c in value.chars() {
        app.update(Action::Input(c));
    }
    let fx = app.update(Action::Commit);
    // Writing the recovery file, or removing it when the edit returns to the saved lens.
    assert!(
        matches!(
            fx.first(),
            Some(Effect::WriteRecovery { .. } | Effect::RemoveRecovery(_))
        ),
        "{:?}",
        app.message
    );
    fx
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("edit_nikon_zoom");
    let mut terminal = Terminal::new(TestBackend::new(120, 40)).unwrap();
    let mut app = nikon();
    // Alternate between the thickness of the file and 0.5 mm more, so every commit changes it.
    let t = app.doc.system().surfaces[10].thickness;
    let values = [format!("{}", t + 0.5), format!("{t}")];
    let mut flip = true;
    g.bench_function("commit_and_draw", |b| {
        b.iter(|| {
            flip = !flip;
            black_box(commit(&mut app, &values[flip as usize]));
            terminal.draw(|f| view::draw(f, &app)).unwrap();
        })
    });
    g.bench_function("commit", |b| {
        b.iter(|| {
            flip = !flip;
            black_box(commit(&mut app, &values[flip as usize]));
        })
    });
    g.bench_function("draw", |b| {
        b.iter(|| terminal.draw(|f| view::draw(f, &app)).unwrap().area)
    });
    let dir = tempfile::Builder::new()
        .prefix("flarebench-bench-edit-")
        .tempdir()
        .unwrap();
    let target = dir.path().join(".nikon-zoom-long.xml.recover");
    g.bench_function("recovery_write", |b| {
        b.iter(|| files::write_recovery(&target, app.doc.system()).unwrap())
    });
    g.finish();
    drop(dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
