//! The `flarebench` command-line tool.

fn main() -> std::process::ExitCode {
    flarebench::cli::main()
}
