//! Walkthrough server of sightline: HTTP API, WebSocket walk sessions with
//! PVS prefetch, and the embedded browser viewer.
//!
//! This is the remote-walkthrough scenario of the dual ray space paper (Koltun et al.
//! 2001, §1 and §6, Fig. 5): a large city lives on the server; a thin client walks
//! through it; the server keeps the client supplied with the PVS of the viewcell it is in
//! and of the cells it may enter next — ahead of time, so that the client never waits —
//! and sends the geometry of each object the first time it becomes potentially visible.
//!
//! * [`grid`] — the regular grid of viewcells; [`layout`] — a grid, or the free cells of
//!   a `.pvs` file (a BSP level's leaves, a mesh level's automatic cells);
//! * [`source`] — where a cell's PVS comes from (a method on-line, or a `.pvs` file);
//! * [`cache`] — LRU cache and bounded worker pool in front of the source;
//! * [`geometry`] — the compact binary object geometry (`SLG1`);
//! * [`api`] — HTTP endpoints; [`walk`] — WebSocket sessions; [`limits`] — token, rate
//!   limits and admission; [`conn`] — the accept loop, connection cap and timeouts;
//!   [`web`] — the embedded viewer.
//!
//! ```no_run
//! # async fn demo() -> std::io::Result<()> {
//! use std::sync::Arc;
//! use sightline_server::{Server, ServerConfig, grid::CellGrid, source::OnlineSource};
//! use sightline_scene::Scene;
//! let scene = Arc::new(Scene::from_objects(vec![]));
//! let grid = CellGrid::cover(&scene.bounds, 100.0).unwrap();
//! let method = sightline_methods::create("erosion", scene.clone(), &Default::default()).unwrap();
//! let server = Server::new(scene, Arc::new(OnlineSource::new(method, grid)), ServerConfig::default());
//! let listener = sightline_server::conn::listen("127.0.0.1:8080").await?;
//! server.run(listener, async { let _ = tokio::signal::ctrl_c().await; }).await
//! # }
//! ```

pub mod api;
pub mod cache;
pub mod conn;
pub mod geometry;
pub mod grid;
pub mod layout;
pub mod limits;
pub mod source;
pub mod tiles;
pub mod walk;
pub mod web;

use cache::{CacheConfig, PvsCache};
use geometry::GeometryStore;
use sightline_geom::DVec3;
use sightline_scene::Scene;
use source::SharedSource;
use std::future::Future;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::watch;

/// Limits and options of a server.
#[derive(Clone, Debug)]
pub struct ServerConfig {
    /// When set, every `/api` request must carry it (`?token=` or `Authorization: Bearer`).
    pub token: Option<String>,
    /// Cache and worker pool sizes.
    pub cache: CacheConfig,
    /// Most simultaneous walk sessions.
    pub max_sessions: usize,
    /// HTTP requests per second and burst allowed per client address.
    pub http_rate_per_s: f64,
    pub http_burst: f64,
    /// WebSocket messages per second and burst allowed per session.
    pub ws_rate_per_s: f64,
    pub ws_burst: f64,
    /// Largest WebSocket message a client may send (bytes).
    pub ws_max_message_bytes: usize,
    /// Most ids in one `/api/objects` request.
    pub max_ids_per_request: usize,
    /// Most cell PVS a session keeps on the client (older ones are forgotten).
    pub max_held_cells: usize,
    /// Malformed messages tolerated before a session is closed.
    pub max_session_errors: u32,
    /// Per-address HTTP rate limits apply to loopback clients too (off by default: a
    /// reverse proxy on the same host sends every client from 127.0.0.1).
    pub rate_limit_loopback: bool,
    /// Most open client connections (kept below the open-file limit; see [`conn`]).
    pub max_connections: usize,
    /// A client must send a request's headers within this time, or is disconnected.
    pub header_read_timeout: Duration,
    /// Most `/api` requests handled at once, most waiting for a turn, and how long one
    /// may wait (see [`limits::Admission`]); beyond, `503` with a JSON error.
    pub max_inflight: usize,
    pub max_queued: usize,
    pub queue_timeout: Duration,
    /// Longest a `/api/pvs` request waits for its cell's PVS before `503`.
    pub pvs_timeout: Duration,
    /// What the viewer is told about walking in the scene (`/api/scene`).
    pub view: ViewSettings,
}

/// How the viewer walks in the scene, sent in `/api/scene` (the server itself does not
/// use it: a session accepts any position and locates it).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ViewSettings {
    /// `"city"`: the walker stays at eye height above the ground z = 0; `"level"`: it
    /// stands on the highest floor below it (a ray cast down against the geometry it holds).
    pub kind: &'static str,
    /// Eye height above the ground or floor, in scene units.
    pub eye_height: f64,
    /// Where the viewer starts, in scene coordinates (`None`: the viewer chooses, e.g. a
    /// free point near a city's centre).
    pub start: Option<[f64; 3]>,
}

impl Default for ViewSettings {
    /// A city: 1.7 m above the ground, start chosen by the viewer.
    fn default() -> Self {
        ViewSettings {
            kind: "city",
            eye_height: 1.7,
            start: None,
        }
    }
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            token: None,
            cache: CacheConfig::default(),
            max_sessions: 1024,
            http_rate_per_s: 100.0,
            http_burst: 400.0,
            ws_rate_per_s: 30.0,
            ws_burst: 60.0,
            ws_max_message_bytes: 4096,
            max_ids_per_request: 8192,
            max_held_cells: 32,
            max_session_errors: 64,
            rate_limit_loopback: false,
            max_connections: 16_384,
            header_read_timeout: Duration::from_secs(10),
            max_inflight: 1024,
            max_queued: 16_384,
            queue_timeout: Duration::from_secs(10),
            pvs_timeout: Duration::from_secs(30),
            view: ViewSettings::default(),
        }
    }
}

/// Counters of the whole server.
#[derive(Default)]
pub struct Counters {
    pub sessions: AtomicUsize,
    pub sessions_total: AtomicU64,
    pub ws_messages: AtomicU64,
    pub ws_errors: AtomicU64,
    pub cell_changes: AtomicU64,
    pub prefetch_hits: AtomicU64,
    pub bytes_sent: AtomicU64,
    pub http_limited: AtomicU64,
    /// Requests answered `503` by admission control.
    pub http_refused: AtomicU64,
}

/// Everything the handlers share.
pub struct AppState {
    pub scene: Arc<Scene>,
    pub cache: Arc<PvsCache>,
    pub geometry: GeometryStore,
    /// Coordinates sent to clients are relative to this point (see [`geometry`]).
    pub origin: DVec3,
    pub config: ServerConfig,
    pub counters: Counters,
    pub limiter: limits::RateLimiter,
    pub admission: limits::Admission,
    pub boxes: axum::body::Bytes,
    shutdown: watch::Receiver<bool>,
}

impl AppState {
    pub fn source(&self) -> &SharedSource {
        self.cache.source()
    }

    /// Resolves when the server starts shutting down.
    pub fn shutdown_signal(&self) -> watch::Receiver<bool> {
        self.shutdown.clone()
    }

    pub fn counter(c: &AtomicU64) -> u64 {
        c.load(Ordering::Relaxed)
    }
}

/// A walkthrough server for one scene and one PVS source.
pub struct Server {
    state: Arc<AppState>,
    shutdown_tx: watch::Sender<bool>,
    /// Routes added by [`Server::merge_routes`] (the 3D Tiles viewer).
    extra: Option<axum::Router>,
}

impl Server {
    pub fn new(scene: Arc<Scene>, source: SharedSource, config: ServerConfig) -> Self {
        let origin = source.layout().origin();
        let geometry = GeometryStore::new(scene.clone(), origin);
        let boxes = axum::body::Bytes::from(geometry.boxes());
        let cache = PvsCache::new(source, config.cache.clone());
        let (shutdown_tx, shutdown) = watch::channel(false);
        let limiter = limits::RateLimiter::new(config.http_rate_per_s, config.http_burst);
        let admission =
            limits::Admission::new(config.max_inflight, config.max_queued, config.queue_timeout);
        Server {
            state: Arc::new(AppState {
                scene,
                cache,
                geometry,
                origin,
                config,
                counters: Counters::default(),
                limiter,
                admission,
                boxes,
                shutdown,
            }),
            shutdown_tx,
            extra: None,
        }
    }

    /// Serve `routes` too (e.g. [`tiles::router`]); their paths must not clash.
    pub fn merge_routes(&mut self, routes: axum::Router) {
        self.extra = Some(match self.extra.take() {
            Some(r) => r.merge(routes),
            None => routes,
        });
    }

    pub fn state(&self) -> &Arc<AppState> {
        &self.state
    }

    /// The HTTP routes (viewer, API, walk sessions).
    pub fn router(&self) -> axum::Router {
        let r = api::router(self.state.clone());
        match &self.extra {
            Some(extra) => r.merge(extra.clone()),
            None => r,
        }
    }

    /// Serve on `listener` until `shutdown` resolves, then close every walk session with a
    /// close frame, let running requests finish and stop the worker pool.
    pub async fn run(
        self,
        listener: tokio::net::TcpListener,
        shutdown: impl Future<Output = ()> + Send + 'static,
    ) -> std::io::Result<()> {
        let router = self.router();
        let tx = self.shutdown_tx;
        let shutdown = async move {
            shutdown.await;
            let _ = tx.send(true);
        };
        let result = conn::serve(
            listener,
            router,
            &self.state.config,
            shutdown,
            Duration::from_secs(30),
        )
        .await;
        let cache = self.state.cache.clone();
        let _ = tokio::task::spawn_blocking(move || cache.shutdown()).await;
        result
    }
}

/// Resident and peak memory of this process in KiB, read by `/api/stats` only (the path
/// is fixed, never taken from a request).
pub use sightline_stats::memory_kib;
