//! Rust errors into Python exceptions: the whole `anyhow` chain as the message (as the CLI
//! prints it after `error:`), so a lens file's error keeps its `file:line:column: field`.

use pyo3::PyErr;
use pyo3::exceptions::{PyFileNotFoundError, PyRuntimeError, PyValueError};

/// Bad input (a lens file's content, an option's value): `ValueError`.
pub fn value_error(e: &anyhow::Error) -> PyErr {
    PyValueError::new_err(format!("{e:#}"))
}

/// A lens that is neither a file nor a bundled lens's name: `FileNotFoundError`.
pub fn not_found(e: &anyhow::Error) -> PyErr {
    PyFileNotFoundError::new_err(format!("{e:#}"))
}

/// A frame that could not be drawn (the GPU backend failing, say): `RuntimeError`.
pub fn runtime_error(e: &anyhow::Error) -> PyErr {
    PyRuntimeError::new_err(format!("{e:#}"))
}
