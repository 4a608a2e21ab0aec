//! `sightline bench`: see [`crate::bench`].

use crate::bench::{run as run_bench, Suite};
use crate::cli::Command;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Bench {
        suite,
        scene,
        methods,
        out,
        only,
    } = cmd
    else {
        unreachable!("dispatched by commands::run")
    };
    let mut suite = Suite::named(&suite)?;
    suite.only = only.map(|o| {
        o.split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    });
    let methods = methods.map(|m| {
        m.split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    });
    run_bench(suite, &scene, methods, &out, quiet)?;
    if !quiet {
        eprintln!("report written to {}", out.join("README.md").display());
    }
    Ok(())
}
