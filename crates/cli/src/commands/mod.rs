//! One module per command (or family of commands).

mod pvs;

use crate::cli::{Cli, Command};

pub fn run(cli: Cli) -> anyhow::Result<()> {
    let quiet = cli.quiet;
    let _ = quiet;
    match cli.command {
        Command::Pvs {
            scene,
            cell,
            method,
            resolution,
            sweep,
            json,
        } => pvs::pvs(&scene, &cell, &method, resolution, sweep, json),
        other => anyhow::bail!("{} is not implemented yet", command_name(&other)),
    }
}

fn command_name(c: &Command) -> &'static str {
    match c {
        Command::Demo { .. } => "demo",
        Command::Generate { .. } => "generate",
        Command::Info { .. } => "info",
        Command::Cells { .. } => "cells",
        Command::Pvs { .. } => "pvs",
        Command::Truth { .. } => "truth",
        Command::Build { .. } => "build",
        Command::Merge { .. } => "merge",
        Command::Query { .. } => "query",
        Command::Check { .. } => "check",
        Command::Map { .. } => "map",
        Command::Bench { .. } => "bench",
        Command::Serve { .. } => "serve",
    }
}
