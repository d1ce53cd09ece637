//! The lens document being edited: a valid `LensSystem`, reversible edits, undo/redo history
//! and change notification. No terminal types: a window can drive and observe the same model.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};

use flarebench_sdk::{LensSystem, Surface};

/// The system-wide fields shown in the editor's header form.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub name: String,
    /// Aperture setting (f-number); `None` = the stop wide open.
    pub f_number: Option<f64>,
    /// Film (sensor) width and height (mm).
    pub film_width_mm: f64,
    pub film_height_mm: f64,
}

impl Header {
    /// The header fields of `system`.
    pub fn of(system: &LensSystem) -> Header {
        Header {
            name: system.name.clone(),
            f_number: system.f_number,
            film_width_mm: system.film_width_mm,
            film_height_mm: system.film_height_mm,
        }
    }

    fn store(&self, system: &mut LensSystem) {
        system.name = self.name.clone();
        system.f_number = self.f_number;
        system.film_width_mm = self.film_width_mm;
        system.film_height_mm = self.film_height_mm;
    }
}

/// One reversible change to a prescription. Each edit carries what it needs to undo itself.
#[derive(Clone, Debug, PartialEq)]
#[allow(
    clippy::large_enum_variant,
    reason = "a history holds at most thousands of edits; boxing surfaces would only add noise"
)]
pub enum Edit {
    /// Replace surface `index` (`old` → `new`).
    Replace {
        index: usize,
        old: Surface,
        new: Surface,
    },
    /// Insert `surface` so that it becomes surface `index`.
    Insert { index: usize, surface: Surface },
    /// Remove surface `index` (which is `surface`).
    Remove { index: usize, surface: Surface },
    /// Swap surfaces `index` and `index + 1`.
    SwapDown { index: usize },
    /// Replace the header fields.
    Header { old: Header, new: Header },
}

impl Edit {
    /// The edit that undoes this one.
    pub fn inverse(&self) -> Edit {
        match self.clone() {
            Edit::Replace { index, old, new } => Edit::Replace {
                index,
                old: new,
                new: old,
            },
            Edit::Insert { index, surface } => Edit::Remove { index, surface },
            Edit::Remove { index, surface } => Edit::Insert { index, surface },
            Edit::SwapDown { index } => Edit::SwapDown { index },
            Edit::Header { old, new } => Edit::Header { old: new, new: old },
        }
    }

    /// Applies the edit to `system`; an edit that does not fit the system (index out of range,
    /// `old` not what is there) is refused and leaves `system` untouched.
    pub fn apply_to(&self, system: &mut LensSystem) -> Result<(), EditError> {
        let n = system.surfaces.len();
        match self {
            Edit::Replace { index, old, new } => {
                let s = system
                    .surfaces
                    .get_mut(*index)
                    .ok_or(EditError::NoSurface(*index))?;
                if s != old {
                    return Err(EditError::Stale);
                }
                *s = new.clone();
            }
            Edit::Insert { index, surface } => {
                if *index > n {
                    return Err(EditError::NoSurface(*index));
                }
                system.surfaces.insert(*index, surface.clone());
            }
            Edit::Remove { index, surface } => {
                if system.surfaces.get(*index) != Some(surface) {
                    return Err(if *index >= n {
                        EditError::NoSurface(*index)
                    } else {
                        EditError::Stale
                    });
                }
                system.surfaces.remove(*index);
            }
            Edit::SwapDown { index } => {
                if index + 1 >= n {
                    return Err(EditError::NoSurface(index + 1));
                }
                system.surfaces.swap(*index, index + 1);
            }
            Edit::Header { old, new } => {
                if Header::of(system) != *old {
                    return Err(EditError::Stale);
                }
                new.store(system);
            }
        }
        Ok(())
    }

    /// The surface row the edit concerns (where the cursor goes after it), if any.
    pub fn row(&self) -> Option<usize> {
        match self {
            Edit::Replace { index, .. }
            | Edit::Insert { index, .. }
            | Edit::Remove { index, .. }
            | Edit::SwapDown { index } => Some(*index),
            Edit::Header { .. } => None,
        }
    }
}

/// Why an edit was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum EditError {
    /// No surface at this index.
    NoSurface(usize),
    /// The edit was made for a different state of the document.
    Stale,
    /// The edited system would not be valid (the first issue's text).
    Invalid(String),
    /// Nothing to undo or redo.
    NothingToUndo,
    NothingToRedo,
}

impl std::fmt::Display for EditError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EditError::NoSurface(i) => write!(f, "there is no surface {i}"),
            EditError::Stale => write!(f, "the edit does not match the document"),
            EditError::Invalid(m) => write!(f, "refused: {m}"),
            EditError::NothingToUndo => write!(f, "nothing to undo"),
            EditError::NothingToRedo => write!(f, "nothing to redo"),
        }
    }
}

impl std::error::Error for EditError {}

/// A change notification: the document's new revision and a snapshot of the system.
#[derive(Clone, Debug)]
pub struct Change {
    /// Increases by one with every applied edit, undo or redo.
    pub revision: u64,
    pub system: Arc<LensSystem>,
}

/// The document: a lens system that always passes `LensSystem::validate`, with history.
#[derive(Debug)]
pub struct Document {
    system: LensSystem,
    undo: Vec<Edit>,
    redo: Vec<Edit>,
    revision: u64,
    subscribers: Vec<Sender<Change>>,
}

impl Document {
    /// A document holding `system`; refused when the system is not valid.
    pub fn new(system: LensSystem) -> Result<Document, EditError> {
        validated(&system)?;
        Ok(Document {
            system,
            undo: Vec::new(),
            redo: Vec::new(),
            revision: 0,
            subscribers: Vec::new(),
        })
    }

    /// The current system (always valid).
    pub fn system(&self) -> &LensSystem {
        &self.system
    }

    /// The revision: 0 when opened, +1 for every applied edit, undo or redo.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Number of edits that can be undone / redone.
    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }
    pub fn redo_len(&self) -> usize {
        self.redo.len()
    }

    /// A channel that receives a [`Change`] after every applied edit, undo and redo (for a
    /// window or any other observer; a dropped receiver is forgotten).
    pub fn subscribe(&mut self) -> Receiver<Change> {
        let (tx, rx) = channel();
        self.subscribers.push(tx);
        rx
    }

    /// Applies `edit` when the result is a valid system, records it for undo and clears the
    /// redo list. A refused edit leaves the document unchanged.
    pub fn apply(&mut self, edit: Edit) -> Result<(), EditError> {
        self.try_apply(&edit)?;
        self.undo.push(edit);
        self.redo.clear();
        self.changed();
        Ok(())
    }

    /// Undoes the last edit; returns it.
    pub fn undo(&mut self) -> Result<Edit, EditError> {
        let edit = self.undo.pop().ok_or(EditError::NothingToUndo)?;
        if let Err(e) = self.try_apply(&edit.inverse()) {
            self.undo.push(edit);
            return Err(e);
        }
        self.redo.push(edit.clone());
        self.changed();
        Ok(edit)
    }

    /// Redoes the last undone edit; returns it.
    pub fn redo(&mut self) -> Result<Edit, EditError> {
        let edit = self.redo.pop().ok_or(EditError::NothingToRedo)?;
        if let Err(e) = self.try_apply(&edit) {
            self.redo.push(edit);
            return Err(e);
        }
        self.undo.push(edit.clone());
        self.changed();
        Ok(edit)
    }

    /// Takes over `previous`'s subscribers (a new lens opened or recovered in the same editor):
    /// the revision goes on from `previous`'s and every subscriber is sent this document.
    pub fn take_subscribers(&mut self, previous: &mut Document) {
        self.subscribers.append(&mut previous.subscribers);
        self.revision = self.revision.max(previous.revision);
        self.changed();
    }

    /// Checks `edit` without applying it: `Ok` when it fits and leaves a valid system.
    pub fn check(&self, edit: &Edit) -> Result<(), EditError> {
        let mut next = self.system.clone();
        edit.apply_to(&mut next)?;
        validated(&next)
    }

    fn try_apply(&mut self, edit: &Edit) -> Result<(), EditError> {
        let mut next = self.system.clone();
        edit.apply_to(&mut next)?;
        validated(&next)?;
        self.system = next;
        Ok(())
    }

    fn changed(&mut self) {
        self.revision += 1;
        if self.subscribers.is_empty() {
            return;
        }
        let change = Change {
            revision: self.revision,
            system: Arc::new(self.system.clone()),
        };
        self.subscribers.retain(|s| s.send(change.clone()).is_ok());
    }
}

/// `Ok` when `system` validates, else the first issue as an error.
fn validated(system: &LensSystem) -> Result<(), EditError> {
    system.validate().map_err(|issues| {
        let first = &issues[0];
        let msg = match first.surface {
            Some(s) => format!("surface {s}: {} ({})", first.message, first.field),
            None => format!("{} ({})", first.message, first.field),
        };
        EditError::Invalid(msg)
    })
}
