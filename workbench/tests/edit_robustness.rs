//! Random key scripts never crash the editor or corrupt the document: every key of the key
//! map (and random typing) goes through `App::update`, each state is drawn at several terminal
//! sizes down to 1 × 1, and the document always holds a valid lens whose analysis matches it.
//! Effects (saves, recovery files) are not performed here: `edit_app.rs` covers them.

use flarebench::edit::action::Action;
use flarebench::edit::app::App;
use flarebench::edit::keymap::action_for;
use flarebench::edit::{files, view};
use proptest::prelude::*;
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

fn heliar() -> App {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../lenses/heliar-tronnier.xml");
    App::new(files::open(path, false).unwrap()).unwrap()
}

fn key() -> impl Strategy<Value = KeyEvent> {
    let plain = prop_oneof![
        prop::sample::select(vec![
            KeyCode::Up,
            KeyCode::Down,
            KeyCode::Left,
            KeyCode::Right,
            KeyCode::Tab,
            KeyCode::BackTab,
            KeyCode::Enter,
            KeyCode::Esc,
            KeyCode::Backspace,
            KeyCode::Delete,
            KeyCode::Insert,
            KeyCode::Home,
            KeyCode::End,
            KeyCode::F(2),
        ]),
        // Keys of the key map and text: digits, signs, letters, glass-name characters.
        prop::sample::select(
            "hjklgGoOydKJu][?:0123456789.-eE/@ nN-BKairstopflatqwx!"
                .chars()
                .collect::<Vec<_>>()
        )
        .prop_map(KeyCode::Char),
        any::<char>().prop_map(KeyCode::Char),
    ];
    let ctrl = prop::sample::select(vec!['z', 'r', 'y', 'n', 'p', 'u', 'a', 'e', 'o', 'w', 's']);
    prop_oneof![
        8 => plain.prop_map(|c| KeyEvent::new(c, KeyModifiers::NONE)),
        1 => ctrl.prop_map(|c| KeyEvent::new(KeyCode::Char(c), KeyModifiers::CONTROL)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_keys_never_break_the_editor(
        keys in prop::collection::vec(key(), 1..120),
        clicks in prop::collection::vec((0u16..130, 0u16..45), 0..6),
    ) {
        let mut app = heliar();
        let mut terminals: Vec<Terminal<TestBackend>> = [(120, 40), (60, 16), (7, 3), (1, 1)]
            .into_iter()
            .map(|(w, h)| Terminal::new(TestBackend::new(w, h)).unwrap())
            .collect();
        let mut clicks = clicks.into_iter();
        for (i, k) in keys.into_iter().enumerate() {
            if let Some(a) = action_for(app.key_mode(), k) {
                app.update(a);
            }
            if i % 7 == 0 && let Some((x, y)) = clicks.next() {
                app.update(Action::Click { x, y });
            }
            prop_assert!(app.doc.system().validate().is_ok());
            for t in &mut terminals {
                t.draw(|f| view::draw(f, &app)).unwrap();
            }
        }
        // The analysis shown is the analysis of the document.
        let fresh = flarebench::edit::analysis::Analysis::compute(app.doc.system());
        prop_assert_eq!(
            format!("{:?}", app.analysis.paraxial),
            format!("{:?}", fresh.paraxial)
        );
        prop_assert_eq!(&app.analysis.ghosts, &fresh.ghosts);
        // Undoing everything gives back the opened lens.
        while app.doc.undo_len() > 0 {
            app.doc.undo().unwrap();
        }
        let opened = heliar();
        prop_assert_eq!(app.doc.system(), opened.doc.system());
    }
}
