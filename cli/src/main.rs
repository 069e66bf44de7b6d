//! The `embedyn` command line; see `embedyn --help` and docs/command-line.md.

fn main() -> std::process::ExitCode {
    embedyn_cli::main()
}
