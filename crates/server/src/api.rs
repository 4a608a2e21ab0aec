//! HTTP endpoints (documented in `docs/api.md`).
//!
//! No endpoint takes a path or file name: the viewer's assets are compiled into the binary
//! ([`crate::web`]) and everything else is computed from the loaded scene, so the API
//! cannot be used to read the server's file system.

use crate::cache::{CacheError, Priority};
use crate::limits::{guard, json_error, over_capacity, percent_decode};
use crate::{memory_kib, walk, web, AppState};
use axum::extract::{DefaultBodyLimit, RawQuery, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::{Json, Router};
use serde_json::json;
use sightline_geom::DVec3;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// The whole route table.
pub fn router(state: Arc<AppState>) -> Router {
    let api = Router::new()
        .route("/scene", get(scene))
        .route("/pvs", get(pvs))
        .route("/objects", get(objects))
        .route("/boxes", get(boxes))
        .route("/stats", get(stats))
        .route("/walk", get(walk::upgrade))
        .fallback(|| async { json_error(StatusCode::NOT_FOUND, "no such endpoint") })
        .layer(axum::middleware::from_fn_with_state(state.clone(), guard));
    Router::new()
        .nest("/api", api)
        .merge(web::router())
        .fallback(|| async { json_error(StatusCode::NOT_FOUND, "not found") })
        // Every endpoint is a GET: no request needs a body.
        .layer(DefaultBodyLimit::max(1024))
        .with_state(state)
}

/// The value of `key` in a query string.
pub fn query_param(q: Option<&str>, key: &str) -> Option<String> {
    q?.split('&').find_map(|kv| {
        let (k, v) = kv.split_once('=').unwrap_or((kv, ""));
        (k == key).then(|| percent_decode(v))
    })
}

/// `GET /api/scene`: what a client needs before walking.
async fn scene(State(s): State<Arc<AppState>>) -> Response {
    let src = s.source();
    let info = src.info();
    let b = s.scene.bounds;
    let layout = src.layout();
    let view = &s.config.view;
    Json(json!({
        "objects": s.scene.objects.len(),
        "bounds": [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
        "origin": [s.origin.x, s.origin.y, s.origin.z],
        "grid": layout.grid(),
        "cells": layout.len(),
        "layout": layout.kind(),
        "cell_scale": layout.scale_m(),
        "kind": view.kind,
        "eye_height": view.eye_height,
        "start": view.start,
        "method": info.method,
        "conservative": info.conservative,
        "source": info.kind,
        "params": info.params,
        "geometry_format": "SLG1",
        "token_required": s.config.token.is_some(),
    }))
    .into_response()
}

/// Parse `X,Y,Z`.
fn parse_point(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "'at' must be X,Y,Z (3 comma-separated numbers), got {} part(s)",
            parts.len()
        ));
    }
    let mut v = [0.0; 3];
    for (o, p) in v.iter_mut().zip(&parts) {
        *o = p
            .parse::<f64>()
            .map_err(|_| format!("'{p}' is not a number"))?;
    }
    Ok(DVec3::from_array(v))
}

/// `GET /api/pvs?at=X,Y,Z`: the `query` JSON of the cell containing the point.
async fn pvs(State(s): State<Arc<AppState>>, RawQuery(q): RawQuery) -> Response {
    let Some(at) = query_param(q.as_deref(), "at") else {
        return json_error(StatusCode::BAD_REQUEST, "missing parameter 'at=X,Y,Z'");
    };
    let p = match parse_point(&at) {
        Ok(p) => p,
        Err(e) => return json_error(StatusCode::BAD_REQUEST, e),
    };
    let cell_id = match s.source().locate(p) {
        Ok(c) => c,
        Err(e) => return json_error(StatusCode::BAD_REQUEST, e.to_string()),
    };
    let Some(cell) = s.source().cell(cell_id) else {
        return json_error(StatusCode::INTERNAL_SERVER_ERROR, "cell lookup failed");
    };
    // A request that has waited too long gives up (`503`); if nobody else waits for
    // the cell, the cache drops the queued job.
    let got = tokio::time::timeout(s.config.pvs_timeout, s.cache.get(cell_id, Priority::Demand));
    let Ok(got) = got.await else {
        s.counters.http_refused.fetch_add(1, Ordering::Relaxed);
        return over_capacity(format!(
            "server over capacity: the PVS of cell {cell_id} was not ready within {} s, retry",
            s.config.pvs_timeout.as_secs_f64()
        ));
    };
    match got {
        Ok(v) => Json(json!({
            "cell": cell,
            "cell_id": cell_id,
            "method": s.source().info().method,
            "visible": &*v,
        }))
        .into_response(),
        Err(CacheError::Shutdown) => {
            json_error(StatusCode::SERVICE_UNAVAILABLE, "server shutting down")
        }
        Err(e) => json_error(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("cannot compute the PVS of cell {cell_id}: {e}"),
        ),
    }
}

/// Parse `ids=1,2,3` (each a valid object id, at most `max`).
pub fn parse_ids(s: &str, objects: usize, max: usize) -> Result<Vec<u32>, String> {
    if s.is_empty() {
        return Ok(vec![]);
    }
    let mut ids = Vec::new();
    for p in s.split(',') {
        if ids.len() >= max {
            return Err(format!("too many ids (at most {max} per request)"));
        }
        let id: u32 = p
            .trim()
            .parse()
            .map_err(|_| format!("'{p}' is not an object id"))?;
        if id as usize >= objects {
            return Err(format!("no object {id} (the scene has {objects} objects)"));
        }
        ids.push(id);
    }
    Ok(ids)
}

/// `GET /api/objects?ids=1,2,3`: `SLG1` binary geometry (see [`crate::geometry`]).
async fn objects(State(s): State<Arc<AppState>>, RawQuery(q): RawQuery) -> Response {
    let Some(raw) = query_param(q.as_deref(), "ids") else {
        return json_error(StatusCode::BAD_REQUEST, "missing parameter 'ids=1,2,3'");
    };
    let ids = match parse_ids(&raw, s.scene.objects.len(), s.config.max_ids_per_request) {
        Ok(v) => v,
        Err(e) => return json_error(StatusCode::BAD_REQUEST, e),
    };
    // Triangulating a few thousand objects the first time takes milliseconds: keep it off
    // the async threads.
    let st = s.clone();
    let Ok(bytes) = tokio::task::spawn_blocking(move || st.geometry.encode(&ids)).await else {
        return json_error(StatusCode::INTERNAL_SERVER_ERROR, "encoding failed");
    };
    s.counters
        .bytes_sent
        .fetch_add(bytes.len() as u64, Ordering::Relaxed);
    ([(header::CONTENT_TYPE, "application/octet-stream")], bytes).into_response()
}

/// `GET /api/boxes`: `SLB1` bounds of all objects (the mini-map).
async fn boxes(State(s): State<Arc<AppState>>) -> Response {
    (
        [(header::CONTENT_TYPE, "application/octet-stream")],
        s.boxes.clone(),
    )
        .into_response()
}

/// `GET /api/stats`: server counters, cache and memory.
async fn stats(State(s): State<Arc<AppState>>) -> Response {
    let c = &s.counters;
    let (rss, peak) = memory_kib();
    Json(json!({
        "sessions": c.sessions.load(Ordering::Relaxed),
        "sessions_total": c.sessions_total.load(Ordering::Relaxed),
        "ws_messages": c.ws_messages.load(Ordering::Relaxed),
        "ws_errors": c.ws_errors.load(Ordering::Relaxed),
        "cell_changes": c.cell_changes.load(Ordering::Relaxed),
        "prefetch_hits": c.prefetch_hits.load(Ordering::Relaxed),
        "bytes_sent": c.bytes_sent.load(Ordering::Relaxed),
        "http_rate_limited": c.http_limited.load(Ordering::Relaxed),
        "http_over_capacity": c.http_refused.load(Ordering::Relaxed),
        "http_queued": s.admission.queued(),
        "cache": s.cache.stats(),
        "memory_kib": { "rss": rss, "peak": peak },
    }))
    .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_points_and_ids() {
        assert_eq!(
            parse_point("-5, 2.5,1.7").unwrap(),
            DVec3::new(-5.0, 2.5, 1.7)
        );
        assert!(parse_point("1,2").is_err());
        assert!(parse_point("1,2,x").is_err());
        assert_eq!(parse_ids("0,2, 1", 3, 10).unwrap(), vec![0, 2, 1]);
        assert!(parse_ids("3", 3, 10).is_err());
        assert!(parse_ids("-1", 3, 10).is_err());
        assert!(parse_ids("0,1,2", 3, 2).is_err());
        assert_eq!(parse_ids("", 3, 2).unwrap(), Vec::<u32>::new());
        assert_eq!(
            query_param(Some("a=1&at=1%2C2%2C3&b"), "at").as_deref(),
            Some("1,2,3")
        );
        assert_eq!(query_param(Some("b"), "b").as_deref(), Some(""));
        assert_eq!(query_param(None, "b"), None);
    }
}
