//! The `flarebench` command-line tool.

/// mimalloc keeps freed memory for reuse: a frame's meshes and coarse images (tens of MB,
/// allocated and freed every frame) then cost no page faults and no TLB shootdowns, which
/// with the system allocator were 6–9% of a frame's time.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

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
