//! One module per command (or family of commands). Each `run` receives its own
//! `Command` variant.

mod bench;
mod bsp_map;
mod build;
mod cells;
mod check;
mod clusters;
mod demo;
mod frames;
mod gameplay;
mod generate;
mod info;
mod map;
mod pvs;
mod serve;
mod tiles;
mod truth;
pub mod vis;

use crate::cli::{Cli, Command};

pub fn run(cli: Cli) -> anyhow::Result<()> {
    let quiet = cli.quiet;
    match cli.command {
        c @ Command::Demo { .. } => demo::run(c, quiet),
        c @ Command::Generate { .. } => generate::run(c, quiet),
        c @ Command::Info { .. } => info::run(c, quiet),
        c @ Command::Cells { .. } => cells::run(c, quiet),
        c @ Command::Clusters { .. } => clusters::run(c, quiet),
        c @ Command::Pvs { .. } => pvs::run(c, quiet),
        c @ Command::Truth { .. } => truth::run(c, quiet),
        // build, merge and query share the store's code.
        c @ (Command::Build { .. } | Command::Merge { .. } | Command::Query { .. }) => {
            build::run(c, quiet)
        }
        c @ Command::Check { .. } => check::run(c, quiet),
        c @ Command::Map { .. } => map::run(c, quiet),
        c @ Command::Bench { .. } => bench::run(c, quiet),
        c @ Command::Serve { .. } => serve::run(c, quiet),
        c @ Command::Tiles { .. } => tiles::run(c, quiet),
        c @ Command::Frames { .. } => frames::run(c, quiet),
        Command::Vis(args) => vis::run(args, quiet),
    }
}
