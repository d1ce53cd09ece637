//! The editor's document model: reversible edits, undo/redo and change notification.
//! Property tests: apply then undo is the identity, undo then redo is the identity, a refused
//! edit changes nothing, and the document always holds a valid system.

use flarebench::document::{Document, Edit, EditError, Header};
use flarebench_sdk::io::read_lens;
use flarebench_sdk::system::curvature_from_radius;
use flarebench_sdk::{LensSystem, Medium, Surface};
use proptest::prelude::*;

fn heliar() -> LensSystem {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../lenses/heliar-tronnier.xml");
    read_lens(std::path::Path::new(path)).unwrap().system
}

/// A random edit description, turned into an `Edit` against the current system.
#[derive(Clone, Debug)]
enum Op {
    Thickness(usize, f64),
    Radius(usize, f64),
    SemiDiameter(usize, f64),
    Glass(usize, f64, f64),
    Insert(usize, f64),
    Duplicate(usize),
    Remove(usize),
    SwapDown(usize),
    FNumber(Option<f64>),
    FilmWidth(f64),
}

fn op() -> impl Strategy<Value = Op> {
    let i = 0usize..14;
    prop_oneof![
        (i.clone(), -1.0f64..30.0).prop_map(|(i, t)| Op::Thickness(i, t)),
        (
            i.clone(),
            prop_oneof![Just(0.0), 5.0f64..300.0, -300.0f64..-5.0]
        )
            .prop_map(|(i, r)| Op::Radius(i, r)),
        (i.clone(), 0.5f64..40.0).prop_map(|(i, h)| Op::SemiDiameter(i, h)),
        (i.clone(), 1.4f64..1.95, 20.0f64..90.0).prop_map(|(i, n, v)| Op::Glass(i, n, v)),
        (i.clone(), 1.0f64..20.0).prop_map(|(i, h)| Op::Insert(i, h)),
        i.clone().prop_map(Op::Duplicate),
        i.clone().prop_map(Op::Remove),
        i.prop_map(Op::SwapDown),
        prop_oneof![Just(None), (1.0f64..32.0).prop_map(Some)].prop_map(Op::FNumber),
        (-5.0f64..60.0).prop_map(Op::FilmWidth),
    ]
}

/// The edit `op` makes on `sys`; `None` when the index is out of range.
fn edit_for(sys: &LensSystem, op: &Op) -> Option<Edit> {
    let n = sys.surfaces.len();
    let replace = |i: usize, f: &dyn Fn(&mut Surface)| {
        let old = sys.surfaces.get(i)?.clone();
        let mut new = old.clone();
        f(&mut new);
        Some(Edit::Replace { index: i, old, new })
    };
    let header = |f: &dyn Fn(&mut Header)| {
        let old = Header::of(sys);
        let mut new = old.clone();
        f(&mut new);
        Some(Edit::Header { old, new })
    };
    match *op {
        Op::Thickness(i, t) => replace(i, &|s| s.thickness = t),
        Op::Radius(i, r) => replace(i, &|s| s.curvature = curvature_from_radius(r)),
        Op::SemiDiameter(i, h) => replace(i, &|s| s.semi_diameter = h),
        Op::Glass(i, nd, vd) => replace(i, &|s| s.medium = Medium::Model { nd, vd: Some(vd) }),
        Op::Insert(i, h) => (i <= n).then(|| Edit::Insert {
            index: i,
            surface: Surface::spherical(0.0, 0.0, Medium::Air, h),
        }),
        Op::Duplicate(i) => sys.surfaces.get(i).map(|s| Edit::Insert {
            index: i + 1,
            surface: s.clone(),
        }),
        Op::Remove(i) => sys.surfaces.get(i).map(|s| Edit::Remove {
            index: i,
            surface: s.clone(),
        }),
        Op::SwapDown(i) => Some(Edit::SwapDown { index: i }),
        Op::FNumber(f) => header(&|h| h.f_number = f),
        Op::FilmWidth(w) => header(&|h| h.film_width_mm = w),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Apply then undo restores the system exactly; redo restores the edited system; a refused
    /// edit leaves the document as it was; the system always validates.
    #[test]
    fn apply_undo_redo_are_inverse(ops in prop::collection::vec(op(), 1..24)) {
        let mut doc = Document::new(heliar()).unwrap();
        let start = doc.system().clone();
        let mut applied = 0;
        for op in &ops {
            let Some(edit) = edit_for(doc.system(), op) else { continue };
            let before = doc.system().clone();
            let rev = doc.revision();
            match doc.apply(edit.clone()) {
                Ok(()) => {
                    applied += 1;
                    let after = doc.system().clone();
                    prop_assert!(after.validate().is_ok());
                    prop_assert_eq!(doc.revision(), rev + 1);
                    // apply ∘ undo = identity
                    prop_assert_eq!(doc.undo().unwrap(), edit.clone());
                    prop_assert_eq!(doc.system(), &before);
                    // undo ∘ redo = identity
                    prop_assert_eq!(doc.redo().unwrap(), edit);
                    prop_assert_eq!(doc.system(), &after);
                }
                Err(_) => {
                    prop_assert_eq!(doc.system(), &before);
                    prop_assert_eq!(doc.revision(), rev);
                }
            }
        }
        // Undoing everything returns to the opened lens; redoing everything comes back.
        let end = doc.system().clone();
        prop_assert_eq!(doc.undo_len(), applied);
        for _ in 0..applied {
            doc.undo().unwrap();
        }
        prop_assert_eq!(doc.system(), &start);
        prop_assert_eq!(doc.undo(), Err(EditError::NothingToUndo));
        for _ in 0..applied {
            doc.redo().unwrap();
        }
        prop_assert_eq!(doc.system(), &end);
        prop_assert_eq!(doc.redo(), Err(EditError::NothingToRedo));
    }

    /// `Edit::inverse` undoes `apply_to` on the raw system, for any edit that fits.
    #[test]
    fn inverse_undoes_apply_to(op in op()) {
        let mut sys = heliar();
        let before = sys.clone();
        if let Some(edit) = edit_for(&sys, &op)
            && edit.apply_to(&mut sys).is_ok()
        {
            edit.inverse().apply_to(&mut sys).unwrap();
        }
        prop_assert_eq!(sys, before);
    }
}

#[test]
fn refused_edits_name_the_problem() {
    let mut doc = Document::new(heliar()).unwrap();
    let stop = doc.system().stop_index().unwrap();
    let surface = doc.system().surfaces[stop].clone();
    let err = doc
        .apply(Edit::Remove {
            index: stop,
            surface,
        })
        .unwrap_err();
    assert!(err.to_string().contains("no aperture stop"), "{err}");
    // A semi-diameter larger than |R| is refused (the sphere does not reach that far).
    let old = doc.system().surfaces[0].clone();
    let mut new = old.clone();
    new.semi_diameter = 40.0; // R = 30.81 mm
    let err = doc.apply(Edit::Replace { index: 0, old, new }).unwrap_err();
    assert!(err.to_string().contains("semi-diameter"), "{err}");
    assert_eq!(doc.revision(), 0);
    assert_eq!(doc.undo_len(), 0);
}

#[test]
fn stale_edits_are_refused() {
    let mut doc = Document::new(heliar()).unwrap();
    let mut wrong = doc.system().surfaces[1].clone();
    wrong.thickness += 1.0;
    let edit = Edit::Replace {
        index: 0,
        old: wrong.clone(),
        new: wrong,
    };
    assert_eq!(doc.apply(edit), Err(EditError::Stale));
}

#[test]
fn subscribers_see_every_change() {
    let mut doc = Document::new(heliar()).unwrap();
    let rx = doc.subscribe();
    let old = doc.system().surfaces[1].clone();
    let mut new = old.clone();
    new.thickness = 2.5;
    doc.apply(Edit::Replace { index: 1, old, new }).unwrap();
    doc.undo().unwrap();
    doc.redo().unwrap();
    let changes: Vec<_> = rx.try_iter().collect();
    assert_eq!(
        changes.iter().map(|c| c.revision).collect::<Vec<_>>(),
        [1, 2, 3]
    );
    assert_eq!(changes[0].system.surfaces[1].thickness, 2.5);
    assert_eq!(
        changes[1].system.surfaces[1].thickness,
        heliar().surfaces[1].thickness
    );
    assert_eq!(changes[2].system.as_ref(), doc.system());
}
