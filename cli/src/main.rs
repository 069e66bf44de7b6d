//! The `embedyn` command line; see `embedyn --help` and CONTRACT.md §3.

fn main() -> std::process::ExitCode {
    embedyn_cli::main()
}
