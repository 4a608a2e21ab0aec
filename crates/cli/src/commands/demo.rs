//! `sightline demo`.

use crate::cli::Command;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let _ = (cmd, quiet);
    anyhow::bail!("`sightline demo` is not implemented yet")
}
