//! The `multires` command-line tool. Run without arguments for the demo.

use std::process::ExitCode;

use clap::Parser;

mod cli;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // One clear line; no backtrace for user mistakes.
            eprintln!("multires: {error}");
            ExitCode::FAILURE
        }
    }
}
