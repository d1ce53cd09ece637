//! The lens picker (`O`): the bundled library in a window, filtered as you type (every word
//! must be part of a lens's `maker/name`); Enter or a click opens a lens, Escape closes.

use std::path::PathBuf;

use egui::{Key, Ui};

use crate::lens_library::{self, BundledLens};

/// Names listed at most (the count says how many match).
const MAX_LISTED: usize = 200;

/// The picker's state while the viewer runs.
#[derive(Debug, Default)]
pub struct LensPicker {
    open: bool,
    /// Set when the picker opens, so the text box takes the keyboard.
    focus: bool,
    query: String,
    /// The bundled library, read when the picker first opens.
    library: Option<Vec<BundledLens>>,
}

/// The lenses of `library` whose `maker/name` holds every word of `query` (case-insensitive),
/// in the library's order.
pub fn matching<'a>(library: &'a [BundledLens], query: &str) -> Vec<&'a BundledLens> {
    let words: Vec<String> = query.split_whitespace().map(str::to_lowercase).collect();
    library
        .iter()
        .filter(|l| {
            let name = l.qualified.to_lowercase();
            words.iter().all(|w| name.contains(w.as_str()))
        })
        .collect()
}

impl LensPicker {
    pub fn is_open(&self) -> bool {
        self.open
    }

    /// Opens the picker (reading the library the first time), or closes it.
    pub fn toggle(&mut self) {
        self.open = !self.open;
        if self.open {
            self.focus = true;
            self.library.get_or_insert_with(lens_library::bundled);
        }
    }

    /// Draws the picker when open; the file of the lens chosen in this pass, if any.
    pub fn show(&mut self, ui: &mut Ui) -> Option<PathBuf> {
        if !self.open {
            return None;
        }
        let library = self.library.get_or_insert_with(lens_library::bundled);
        let mut chosen = None;
        let mut close = false;
        egui::Window::new("Open a bundled lens")
            .collapsible(false)
            .default_width(420.0)
            .show(ui.ctx(), |ui| {
                // The pass that opens the picker may carry the `O` typed as text.
                let opening = self.focus;
                let before = self.query.clone();
                let edit = ui.add(
                    egui::TextEdit::singleline(&mut self.query)
                        .hint_text("words of the name: nikon 135, summilux, fisheye")
                        .desired_width(f32::INFINITY),
                );
                if std::mem::take(&mut self.focus) {
                    edit.request_focus();
                }
                if opening {
                    self.query = before;
                }
                let found = matching(library, &self.query);
                ui.label(format!(
                    "{} of {} lenses · Enter opens the first · Esc closes",
                    found.len(),
                    library.len()
                ));
                let (enter, escape) =
                    ui.input(|i| (i.key_pressed(Key::Enter), i.key_pressed(Key::Escape)));
                if enter && let Some(first) = found.first() {
                    chosen = Some(first.path.clone());
                }
                close |= escape;
                egui::ScrollArea::vertical()
                    .max_height(360.0)
                    .show(ui, |ui| {
                        for l in found.iter().take(MAX_LISTED) {
                            if ui.selectable_label(false, &l.qualified).clicked() {
                                chosen = Some(l.path.clone());
                            }
                        }
                    });
            });
        if chosen.is_some() || close {
            self.open = false;
        }
        chosen
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(qualified: &str) -> BundledLens {
        let name = qualified.rsplit('/').next().unwrap().to_string();
        BundledLens {
            name,
            qualified: qualified.to_string(),
            folder: qualified.split_once('/').map(|(f, _)| f.to_string()),
            path: PathBuf::from(format!("{qualified}.xml")),
        }
    }

    #[test]
    fn every_word_must_be_part_of_the_name() {
        let lib = [
            lens("nikon/ai-nikkor-135mm-f2"),
            lens("canon/canon-ef135mm-f2l-usm"),
            lens("heliar-tronnier"),
        ];
        let names = |q: &str| -> Vec<String> {
            matching(&lib, q)
                .iter()
                .map(|l| l.qualified.clone())
                .collect()
        };
        assert_eq!(names("").len(), 3);
        assert_eq!(
            names("135"),
            ["nikon/ai-nikkor-135mm-f2", "canon/canon-ef135mm-f2l-usm"]
        );
        assert_eq!(names("NIKON 135"), ["nikon/ai-nikkor-135mm-f2"]);
        assert_eq!(names("  heliar  "), ["heliar-tronnier"]);
        assert!(names("nikon canon").is_empty());
    }
}
