//! The `flarebench` command-line tool.

fn main() -> std::process::ExitCode {
    // Rust ignores SIGPIPE, so printing into a pipe whose reader has gone (`flarebench plugins
    // list | head -1`) would fail and `println!` would panic. Restore the default: the process
    // ends quietly, as Unix tools do.
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any other thread exists; `signal` with
    // SIG_DFL only resets the disposition of SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    flarebench::cli::main()
}
