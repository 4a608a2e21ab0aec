//! `sightline serve`: the walkthrough server on a scene (dual ray space paper, §6).
//!
//! A city is served on a regular grid of cells, answering from a `.pvs` file or
//! computing PVS on-line with `--method`. A level (a BSP or a mesh) is served on its own
//! cells — BSP leaves, automatic cells — from a `.pvs` of the level or from one built
//! in memory at start-up with a portal method ([`level`]).

mod level;

use crate::cli::{Command, SceneArg};
use crate::common::load_scene;
use anyhow::{bail, Context};
use sightline_core::Method;
use sightline_methods::MethodOptions;
use sightline_scene::Scene;
use sightline_server::cache::CacheConfig;
use sightline_server::grid::CellGrid;
use sightline_server::source::{FileSource, OnlineSource, PvsSource, SharedSource};
use sightline_server::{Server, ServerConfig, ViewSettings};
use sightline_world::SceneKind;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Serve {
        scene: scene_arg,
        pvs,
        pvs_flag,
        addr,
        cell_size,
        method,
        eye_height,
        smallest_hole,
        token,
        resolution,
        workers,
        tiles,
    } = cmd
    else {
        unreachable!("dispatched by commands::run")
    };
    if let Some(t) = &token {
        if t.is_empty() {
            bail!("--token must not be empty");
        }
    }
    if workers == Some(0) {
        bail!("--workers must be at least 1");
    }
    if let Some(e) = eye_height {
        if !(e.is_finite() && e > 0.0) {
            bail!("--eye-height must be a positive number of scene units, got {e}");
        }
    }
    if let Some(m) = &method {
        m.parse::<Method>()?;
    }
    let pvs = pvs.or(pvs_flag);
    let path = &scene_arg.scene;
    let kind = sightline_world::kind_of(path);
    let is_level = kind != SceneKind::City;
    // A level is served on its own cells unless a city method is asked for explicitly.
    let level_mode = match method.as_deref() {
        None => is_level,
        Some(m) => {
            let on_cells = m.parse().is_ok_and(sightline_world::on_level_cells);
            is_level && (on_cells || pvs.is_some())
        }
    };
    let default = sightline_world::serving_method(kind).name();
    let served = if level_mode {
        let method = method.as_deref().unwrap_or(default);
        level::prepare(
            &scene_arg,
            pvs.as_deref(),
            method,
            smallest_hole,
            eye_height,
            quiet,
        )?
    } else {
        city(
            &scene_arg,
            pvs.as_deref(),
            cell_size,
            method.as_deref().unwrap_or(default),
            resolution,
        )?
    };
    let Served {
        scene,
        source,
        mut view,
    } = served;
    if let Some(e) = eye_height {
        view.eye_height = e;
    }
    let mut config = ServerConfig {
        token,
        view,
        ..Default::default()
    };
    if let Some(w) = workers {
        config.cache = CacheConfig {
            workers: w,
            ..config.cache
        };
    }
    let info = source.info();
    let cells = source.layout().len();
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    rt.block_on(async move {
        let listener = sightline_server::conn::listen(&addr)
            .await
            .with_context(|| format!("cannot listen on {addr}"))?;
        let local = listener.local_addr()?;
        let mut server = Server::new(scene.clone(), source, config);
        if let Some(dir) = &tiles {
            let t = sightline_server::tiles::TilesState::open(dir, scene.fingerprint())
                .map_err(|e| anyhow::anyhow!("--tiles: {e}"))?;
            let routes = sightline_server::tiles::router(server.state().clone(), Arc::new(t));
            server.merge_routes(routes);
            eprintln!("sightline: tileset {} at /tiles/", dir.display());
        }
        // The e2e test reads this line to find the port of `--addr 127.0.0.1:0`.
        println!(
            "sightline: serving {} objects, {cells} cells, method {} ({}{}) on http://{local}/",
            scene.len(),
            info.method,
            info.kind,
            if info.conservative {
                ", conservative"
            } else {
                ", NOT conservative"
            },
        );
        std::io::stdout().flush().ok();
        server.run(listener, shutdown_signal()).await?;
        eprintln!("sightline: shut down");
        Ok(())
    })
}

/// What is served: the scene (its objects are what the PVS lists), the PVS source and
/// how the viewer walks.
pub(crate) struct Served {
    pub scene: Arc<Scene>,
    pub source: SharedSource,
    pub view: ViewSettings,
}

/// A city: a regular grid of cells at eye height, from a `.pvs` or an on-line method.
fn city(
    scene_arg: &SceneArg,
    pvs: Option<&Path>,
    cell_size: f64,
    method: &str,
    resolution: Option<u32>,
) -> anyhow::Result<Served> {
    let scene = Arc::new(load_scene(scene_arg)?);
    if scene.is_empty() {
        bail!("{}: the scene has no objects", scene_arg.scene.display());
    }
    let source: SharedSource = match pvs {
        Some(path) => {
            let file = sightline_pvs::PvsFile::open(path)
                .with_context(|| format!("cannot open {}", path.display()))?;
            let src = FileSource::new(file, &scene)
                .with_context(|| format!("cannot serve {}", path.display()))?;
            let g = src.layout();
            eprintln!(
                "serving {}: {} grid cells of {} m (--method, --cell-size and --resolution come from the file)",
                path.display(),
                g.len(),
                g.scale_m()
            );
            Arc::new(src)
        }
        None => {
            let grid = CellGrid::cover(&scene.bounds, cell_size).context("--cell-size")?;
            eprintln!(
                "preparing method '{method}' for {} objects ({} cells of {cell_size} m)…",
                scene.len(),
                grid.len()
            );
            let opts = MethodOptions {
                resolution_px: resolution,
                ..Default::default()
            };
            let m = sightline_methods::create(method, scene.clone(), &opts)
                .with_context(|| format!("cannot prepare method '{method}'"))?;
            if method == "all" {
                eprintln!("note: method 'all' does no culling: every PVS is the whole scene");
            } else if !m.is_conservative() {
                eprintln!(
                    "warning: method '{method}' is NOT conservative: clients may miss visible objects"
                );
            }
            Arc::new(OnlineSource::new(m, grid))
        }
    };
    Ok(Served {
        scene,
        source,
        view: ViewSettings::default(),
    })
}

/// Ctrl-C or SIGTERM.
async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
}
