//! Errors and warnings at byte offsets of a text, for the line-based readers (Zemax, PBRT):
//! turns offsets into `file:line:column` and collects the warnings.

use super::LensFileError;
use super::text::LineIndex;

/// The file being read: its label, its line index and the warnings so far.
#[derive(Debug)]
pub(crate) struct Reporter<'a> {
    pub file: &'a str,
    lines: LineIndex<'a>,
    pub warnings: Vec<String>,
}

impl<'a> Reporter<'a> {
    pub fn new(file: &'a str, text: &'a str) -> Self {
        Reporter {
            file,
            lines: LineIndex::new(text),
            warnings: Vec::new(),
        }
    }

    /// An error at byte offset `pos`, about `field` (may be empty).
    pub fn error(&self, pos: usize, field: &str, message: impl Into<String>) -> LensFileError {
        let (line, column) = self.lines.line_col(pos);
        LensFileError::at(self.file, line, column, field, message)
    }

    /// A warning at byte offset `pos`, as `file:line:column: message`.
    pub fn warn(&mut self, pos: usize, message: impl AsRef<str>) {
        let (line, column) = self.lines.line_col(pos);
        self.warnings.push(format!(
            "{}:{line}:{column}: {}",
            self.file,
            message.as_ref()
        ));
    }

    /// Several located errors as one: the first, with the others listed in its message.
    pub fn combine(errors: Vec<LensFileError>) -> Option<LensFileError> {
        let mut it = errors.into_iter();
        let mut first = it.next()?;
        let rest: Vec<String> = it
            .map(|e| {
                let field = if e.field.is_empty() {
                    String::new()
                } else {
                    format!("field `{}`: ", e.field)
                };
                format!("{}:{}: {field}{}", e.line, e.column, e.message)
            })
            .collect();
        if !rest.is_empty() {
            first.message = format!(
                "{} (and {} more: {})",
                first.message,
                rest.len(),
                rest.join("; ")
            );
        }
        Some(first)
    }
}
