//! `capp`: the CAPP host simulator's command line. Everything it does lives in
//! the `capp_sim` library ([`capp_sim::cli`]); this file only hands it the
//! arguments.

use std::process::ExitCode;

fn main() -> ExitCode {
    capp_sim::cli::main(std::env::args_os())
}
