//! Helpers shared by the commands: scene loading, progress bars, JSON output.
#![allow(dead_code)] // used by the commands as they land

use crate::cli::{CrsArg, SceneArg};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use sightline_scene::import::{Crs, ImportOptions};
use sightline_scene::Scene;
use sightline_world::{OpenOptions, Standing, World};
use std::io::IsTerminal;

/// Load the scene named on the command line.
pub fn load_scene(arg: &SceneArg) -> anyhow::Result<Scene> {
    sightline_scene::import::load(&arg.scene, &import_options(arg))
        .with_context(|| format!("cannot load {}", arg.scene.display()))
}

/// The importer's options of a scene argument.
pub fn import_options(arg: &SceneArg) -> ImportOptions {
    let crs = match arg.crs {
        CrsArg::Auto => Crs::Auto,
        CrsArg::Projected => Crs::Projected,
        CrsArg::Wgs84 => Crs::Wgs84,
    };
    ImportOptions {
        crs,
        strict: arg.strict,
    }
}

/// Open the scene of `arg` as a [`World`] (any kind), with a mesh level's smallest hole
/// and standing.
pub fn open_world(
    arg: &SceneArg,
    smallest_hole: Option<f64>,
    standing: Standing,
) -> anyhow::Result<World> {
    let opts = OpenOptions {
        import: import_options(arg),
        smallest_hole,
        standing,
    };
    World::open(&arg.scene, &opts)
}

/// Print a mesh level's warnings (a raised hole, skipped triangles, a leak) unless quiet.
pub fn print_warnings(warnings: &[String], quiet: bool) {
    if !quiet {
        for w in warnings {
            eprintln!("warning: {w}");
        }
    }
}

/// A progress bar over `len` items, hidden when quiet or not on a terminal.
pub fn progress(len: u64, quiet: bool, what: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({per_sec}, eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// Print a value as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(v: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(v)?);
    Ok(())
}

/// Write `bytes` to `path` atomically: a temporary file in the same folder, then rename.
pub fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> anyhow::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(d) = dir {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    let tmp = path.with_extension(format!(
        "{}.tmp{}",
        path.extension().and_then(|e| e.to_str()).unwrap_or(""),
        std::process::id()
    ));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// Method options from the shared flags (`--resolution`, `--sweep`, `--planes`); the
/// sweep flags belong to `ext-proj` only and are refused for any other method rather
/// than silently ignored.
pub fn method_options(
    method: &str,
    resolution: Option<u32>,
    sweep: bool,
    planes: Option<u32>,
    set: &[String],
) -> anyhow::Result<sightline_methods::MethodOptions> {
    if sweep && method != "ext-proj" {
        anyhow::bail!("--sweep only applies to --method ext-proj (got '{method}')");
    }
    if let Some(k) = planes {
        if !sweep {
            anyhow::bail!("--planes sets the number of sweep planes: it needs --sweep");
        }
        if !(1..=256).contains(&k) {
            anyhow::bail!("--planes must be between 1 and 256, got {k}");
        }
    }
    let set = set
        .iter()
        .map(|kv| match kv.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() => {
                Ok((k.trim().to_string(), v.trim().to_string()))
            }
            _ => anyhow::bail!("--set takes KEY=VALUE, got '{kv}'"),
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let opts = sightline_methods::MethodOptions {
        resolution_px: resolution,
        sweep,
        planes,
        set,
        ..Default::default()
    };
    // The registry validates every knob by key (an unknown method is reported later,
    // where the method is prepared, with the list of names).
    if let Ok(m) = method.parse::<sightline_methods::Method>() {
        m.options(&opts)?;
    }
    Ok(opts)
}

#[cfg(test)]
mod tests {
    use super::method_options;

    #[test]
    fn sweep_options_reach_ext_proj_and_only_it() {
        let o = method_options("ext-proj", Some(128), true, Some(5), &[]).unwrap();
        assert!(o.sweep);
        assert_eq!(o.planes, Some(5));
        assert_eq!(o.resolution_px, Some(128));
        let p = sightline_methods::ext_proj::Params::from_options(&o);
        assert!(p.sweep);
        assert_eq!(p.sweep_planes, 5);
        // Refused rather than silently ignored.
        let e = method_options("erosion", None, true, None, &[]).unwrap_err();
        assert!(e.to_string().contains("ext-proj"), "{e}");
        let e = method_options("ext-proj", None, false, Some(5), &[]).unwrap_err();
        assert!(e.to_string().contains("--sweep"), "{e}");
        assert!(method_options("ext-proj", None, true, Some(0), &[]).is_err());
        assert!(
            !method_options("erosion", None, false, None, &[])
                .unwrap()
                .sweep
        );
    }
}
