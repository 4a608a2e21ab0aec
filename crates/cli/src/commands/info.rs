//! `sightline info`.

use crate::cli::Command;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let _ = (cmd, quiet);
    anyhow::bail!("`sightline info` is not implemented yet")
}
