//! Panics that are caught where they happen (a render on the viewer's worker thread) must not
//! reach the process's panic hook: the default hook prints over the terminal editor's screen,
//! and ratatui's hook leaves the alternate screen and raw mode — for a panic that the program
//! handles and shows in its status line. A thread marks itself with [`caught_here`]; the hook
//! installed by [`install_hook`] stays silent for such threads and calls the previous hook for
//! all others.

use std::cell::Cell;
use std::sync::Once;

thread_local! {
    static CAUGHT: Cell<bool> = const { Cell::new(false) };
}

/// Panics on this thread are caught and reported by the caller: the hook stays silent.
pub fn caught_here() {
    CAUGHT.with(|c| c.set(true));
}

/// Wraps the current panic hook so that it is skipped on threads marked by [`caught_here`].
/// Call it after any other code installs its hook (the terminal editor's); calling it again
/// wraps again, which changes nothing.
pub fn install_hook() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !CAUGHT.with(Cell::get) {
            previous(info);
        }
    }));
}

/// [`install_hook`] once per process (for code that may run many times).
pub fn install_hook_once() {
    static ONCE: Once = Once::new();
    ONCE.call_once(install_hook);
}
