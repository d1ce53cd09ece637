//! The `flarebench` command-line tool.

/// mimalloc keeps freed memory for reuse: a frame's meshes and coarse images (tens of MB,
/// allocated and freed every frame) then cost no page faults and no TLB shootdowns, which
/// with the system allocator were 6–9% of a frame's time.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// mimalloc's `mi_option_purge_delay`: its place in `mi_option_e` (mimalloc.h, v2 and v3),
/// for which the sys crate names no constant.
const MI_OPTION_PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;

/// Keeps freed memory instead of handing it back to the system (mimalloc's purge), unless
/// `MIMALLOC_PURGE_DELAY` is set. By default mimalloc purges memory that has been free for a
/// second, so every so many frames the next frame's meshes and coarse images fault their
/// pages in again and the kernel clears them: the Nikon zoom's frame at 1920 × 1080 made 4 500
/// page faults, and its render was about 10% faster without them. The process keeps its
/// largest frame's memory instead.
fn keep_freed_memory() {
    if std::env::var_os("MIMALLOC_PURGE_DELAY").is_none() {
        // SAFETY: sets one integer option of mimalloc's (-1: never purge); called first thing
        // in `main`, before any other thread exists.
        unsafe { libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DELAY, -1) };
    }
}

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
    keep_freed_memory();
    flarebench::cli::main()
}
