//! The browser viewer, compiled into the binary (`crates/server/web/`).
//!
//! three.js is vendored as its built file (`web/vendor/three.module.min.js`, r170, MIT,
//! see `web/vendor/README.md`), so building the server needs no npm. The viewer is served
//! without a token (it holds no scene data); it passes the page's `?token=` to the API.

use crate::AppState;
use axum::http::header;
use axum::response::IntoResponse;
use axum::routing::get;
use axum::Router;
use std::sync::Arc;

const INDEX_HTML: &str = include_str!("../web/index.html");
const APP_JS: &str = include_str!("../web/app.js");
const THREE_JS: &[u8] = include_bytes!("../web/vendor/three.module.min.js");
const THREE_LICENSE: &str = include_str!("../web/vendor/three.LICENSE");

/// `GET /`, `/app.js`, `/vendor/three.module.min.js`, `/vendor/three.LICENSE`.
pub fn router() -> Router<Arc<AppState>> {
    let html = "text/html; charset=utf-8";
    let js = "text/javascript; charset=utf-8";
    let txt = "text/plain; charset=utf-8";
    Router::new()
        .route(
            "/",
            get(move || async move { ([(header::CONTENT_TYPE, html)], INDEX_HTML).into_response() }),
        )
        .route(
            "/app.js",
            get(move || async move { ([(header::CONTENT_TYPE, js)], APP_JS).into_response() }),
        )
        .route(
            "/vendor/three.module.min.js",
            get(move || async move {
                (
                    [
                        (header::CONTENT_TYPE, js),
                        (header::CACHE_CONTROL, "public, max-age=86400"),
                    ],
                    THREE_JS,
                )
                    .into_response()
            }),
        )
        .route(
            "/vendor/three.LICENSE",
            get(move || async move { ([(header::CONTENT_TYPE, txt)], THREE_LICENSE).into_response() }),
        )
}
