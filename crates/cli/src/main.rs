//! `sightline`: conservative potentially visible sets for cities (SPEC §5).

mod bench;
mod cli;
mod commands;
mod common;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    if let Err(e) = commands::run(args) {
        // One line, never a panic trace (SPEC §5).
        let msg = format!("{e:#}").replace('\n', " ");
        eprintln!("error: {msg}");
        std::process::exit(1);
    }
}
