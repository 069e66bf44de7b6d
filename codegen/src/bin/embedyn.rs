//! The `embedyn` command line; see `embedyn --help` and CONTRACT.md §3.

use clap::Parser;
use embedyn_codegen::cli::{run, Cli};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(serde_json::Value::String(text)) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Ok(json) => {
            println!("{json}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}", e.0);
            ExitCode::FAILURE
        }
    }
}
