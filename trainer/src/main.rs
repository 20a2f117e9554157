//! The `aprt` command line: a thin layer over the `aprt_trainer` library.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = aprt_trainer::cli::Cli::parse();
    match aprt_trainer::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("aprt: {}", aprt_trainer::cli::error_line(&err));
            ExitCode::FAILURE
        }
    }
}
