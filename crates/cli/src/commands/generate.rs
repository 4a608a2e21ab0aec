//! `sightline generate`.

use crate::cli::Command;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let _ = (cmd, quiet);
    anyhow::bail!("`sightline generate` is not implemented yet")
}
