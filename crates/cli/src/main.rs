//! `sightline`: conservative potentially visible sets for cities.

mod bench;
mod cli;
mod commands;
mod common;

use clap::Parser;

fn main() {
    quiet_broken_pipe();
    let args = cli::Cli::parse();
    if let Err(e) = commands::run(args) {
        // One line, never a panic trace.
        let msg = format!("{e:#}").replace('\n', " ");
        eprintln!("error: {msg}");
        std::process::exit(1);
    }
}

/// `sightline … | head` closes stdout early: end quietly, as Unix tools do, instead of
/// the panic `println!` raises on a broken pipe (never a panic trace). Every
/// other panic keeps the default report.
fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let p = info.payload();
        let msg = p
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| p.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info);
    }));
}
