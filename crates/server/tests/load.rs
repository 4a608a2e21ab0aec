//! Load test: many concurrent walk sessions on loopback.
//!
//! Each client walks a random path (random start, heading changes, bouncing off the scene
//! border), reports its position 10 times a second with a sequence number and checks every
//! message it gets (deltas apply to cells it holds, sizes match, geometry decodes). Reported:
//! errors (must be 0), ack latency p50/p99/max, cell changes and how many had the PVS in
//! hand, bytes received and the server's memory.
//!
//! Small in CI (`LOAD_CLIENTS=20`, `LOAD_SECONDS=5`, a stand-in source on a small block
//! city). The report's run — 200 walkers for 60 s against a real `sightline serve` on the
//! metropolis, server memory from its own `/api/stats` — is the release example
//! `crates/server/examples/load.rs`, which drives the same walkers ([`common::walker`]).

mod common;

use common::*;
use sightline_server::ServerConfig;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_walkers_on_loopback() {
    let clients: u64 = env("LOAD_CLIENTS", 20);
    let seconds: f64 = env("LOAD_SECONDS", 5.0);
    let blocks: usize = env("LOAD_CITY", 25);
    let cell_m: f64 = env("LOAD_CELL", 50.0);
    let speed: f64 = env("LOAD_SPEED", 14.0);
    let delay_ms: u64 = env("LOAD_DELAY_MS", 5);
    let scene = Arc::new(block_city(blocks));
    let src = near_source(scene.clone(), cell_m, 80.0, delay_ms);
    let s = TestServer::start(
        scene.clone(),
        src,
        ServerConfig {
            max_sessions: clients as usize + 10,
            ..Default::default()
        },
    )
    .await;
    let walk = Walk {
        // Inside the scene's bounds (the city is not square: its last row has no street
        // beyond it).
        area: [
            scene.bounds.min.x,
            scene.bounds.min.y,
            scene.bounds.max.x,
            scene.bounds.max.y,
        ],
        speed_m_s: speed,
        hz: 10.0,
        until: Instant::now() + Duration::from_secs_f64(seconds),
    };
    let t0 = Instant::now();
    let tasks: Vec<_> = (0..clients)
        .map(|i| tokio::spawn(walker(s.addr, i + 1, walk)))
        .collect();
    let mut reps = vec![];
    for t in tasks {
        reps.push(t.await.unwrap());
    }
    let wall = t0.elapsed().as_secs_f64();
    let sum = summarise(&reps);
    let (rss, peak) = sightline_server::memory_kib();
    let stats = http_get(s.addr, "/api/stats").await.2;
    let stats: serde_json::Value = serde_json::from_slice(&stats).unwrap();
    println!(
        "load: {clients} clients × {seconds} s ({wall:.1} s wall), {} objects, {cell_m} m cells, {speed} m/s, \
         {delay_ms} ms/cell source\n  messages acked {}, errors {}, ack latency p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms\n  \
         cell changes {}, PVS in hand on entry {} ({:.1} %), received {:.1} MiB\n  \
         process memory (server + clients): rss {} MiB, peak {} MiB; cache {}",
        scene.objects.len(),
        sum.acks,
        sum.errors.len(),
        sum.p50_ms,
        sum.p99_ms,
        sum.max_ms,
        sum.cell_changes,
        sum.in_hand,
        if sum.cell_changes > 0 { 100.0 * sum.in_hand as f64 / sum.cell_changes as f64 } else { 100.0 },
        sum.bytes as f64 / (1 << 20) as f64,
        rss / 1024,
        peak / 1024,
        stats["cache"],
    );
    assert!(sum.errors.is_empty(), "errors: {:?}", sum.errors);
    assert!(reps.iter().all(|r| r.acks > 0), "every client got answers");
    assert!(sum.acks > 0);
    assert_eq!(stats["ws_errors"], 0);
    s.stop().await.unwrap();
}
