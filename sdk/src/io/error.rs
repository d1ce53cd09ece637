//! The one error type of lens file reading: it always names the file, and where the problem
//! is inside it, the line, column and field.

use std::fmt;

/// Why a lens file could not be read. `line` and `column` are 1-based; `line == 0` means the
/// error concerns the whole file (it could not be read, or its format is not supported).
///
/// Displayed as `path/to/file.xml:12:9: field `radius`: must be finite, got NaN`, or
/// `path/to/file.xml: cannot read the file: …` for file-level errors.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", Located(self))]
pub struct LensFileError {
    /// The file as the caller named it (a path or a label such as `<editor>`).
    pub file: String,
    /// 1-based line; 0 for errors about the whole file.
    pub line: usize,
    /// 1-based column in characters; 0 for errors about the whole file.
    pub column: usize,
    /// The XML tag (or model field) concerned, e.g. `radius`; empty for file-level errors.
    pub field: String,
    pub message: String,
}

impl LensFileError {
    /// An error at a position inside the file.
    pub fn at(
        file: impl Into<String>,
        line: usize,
        column: usize,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        LensFileError {
            file: file.into(),
            line,
            column,
            field: field.into(),
            message: message.into(),
        }
    }

    /// An error about the whole file (unsupported format, unreadable encoding, …).
    pub fn whole_file(file: impl Into<String>, message: impl Into<String>) -> Self {
        LensFileError::at(file, 0, 0, "", message)
    }

    /// The file could not be read at all.
    pub fn io(file: impl Into<String>, err: &std::io::Error) -> Self {
        LensFileError::whole_file(file, format!("cannot read the file: {err}"))
    }

    /// True when the error concerns the whole file rather than a place in it.
    pub fn is_whole_file(&self) -> bool {
        self.line == 0
    }
}

/// Formats the error as `file:line:column: field `f`: message`.
struct Located<'a>(&'a LensFileError);

impl fmt::Display for Located<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = self.0;
        if e.line == 0 {
            return write!(f, "{}: {}", e.file, e.message);
        }
        write!(f, "{}:{}:{}: ", e.file, e.line, e.column)?;
        if !e.field.is_empty() {
            write!(f, "field `{}`: ", e.field)?;
        }
        f.write_str(&e.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_line_column_and_field() {
        let e = LensFileError::at(
            "path/to/file.xml",
            12,
            9,
            "radius",
            "must be finite, got NaN",
        );
        assert_eq!(
            e.to_string(),
            "path/to/file.xml:12:9: field `radius`: must be finite, got NaN"
        );
    }

    #[test]
    fn io_errors_name_the_file() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory");
        let e = LensFileError::io("lenses/missing.xml", &io);
        assert!(e.is_whole_file());
        assert_eq!(
            e.to_string(),
            "lenses/missing.xml: cannot read the file: No such file or directory"
        );
    }
}
