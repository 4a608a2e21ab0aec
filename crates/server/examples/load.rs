//! Load test against a running `sightline serve`: many concurrent walkers on loopback.
//!
//! Each walker is the load test's client ([`common::walker`], `tests/common/mod.rs`): a
//! random walk inside the scene bounds at `--speed`, a position report `--hz` times a
//! second, every server message checked (deltas apply, sizes match, geometry decodes).
//! Reported: errors (must be 0), ack latency p50/p99/max (time from a position report to
//! its `ack`), cell changes and how many had the PVS in hand on entry, bytes received, and
//! the **server's** resident and peak memory (`/api/stats`, read from the server process's
//! own `/proc/self/status`), sampled every second.
//!
//! ```text
//! target/release/sightline serve /tmp/metro100k.geojson --addr 127.0.0.1:8080 &
//! cargo run --release -p sightline-server --example load -- 127.0.0.1:8080 \
//!     [--clients 200] [--seconds 60] [--speed 1.5] [--hz 10] [--margin 0]
//! ```
//! `--margin M` keeps the walkers M metres inside the scene bounds.

#[path = "../tests/common/mod.rs"]
mod common;

use common::{http_get, summarise, walker, Walk};
use std::net::SocketAddr;
use std::time::{Duration, Instant};

struct Args {
    addr: SocketAddr,
    clients: u64,
    seconds: f64,
    speed: f64,
    hz: f64,
    margin: f64,
}

fn args() -> Result<Args, String> {
    let mut addr = None;
    let mut a = (200u64, 60.0f64, 1.5f64, 10.0f64, 0.0f64);
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or(format!("{k} needs a value"));
        let num = |s: String| s.parse::<f64>().map_err(|e| format!("{k}: {e}"));
        match k.as_str() {
            "--clients" => a.0 = v()?.parse().map_err(|e| format!("{k}: {e}"))?,
            "--seconds" => a.1 = num(v()?)?,
            "--speed" => a.2 = num(v()?)?,
            "--hz" => a.3 = num(v()?)?,
            "--margin" => a.4 = num(v()?)?,
            s if !s.starts_with("--") && addr.is_none() => {
                addr = Some(s.parse().map_err(|e| format!("address {s}: {e}"))?)
            }
            s => return Err(format!("unknown argument {s}")),
        }
    }
    let addr = addr.ok_or(
        "usage: load HOST:PORT [--clients N] [--seconds S] [--speed V] [--hz H] [--margin M]",
    )?;
    Ok(Args {
        addr,
        clients: a.0,
        seconds: a.1,
        speed: a.2,
        hz: a.3,
        margin: a.4,
    })
}

async fn stats(addr: SocketAddr) -> Result<serde_json::Value, String> {
    let (status, _, body) = http_get(addr, "/api/stats").await;
    if status != 200 {
        return Err(format!("/api/stats: HTTP {status}"));
    }
    serde_json::from_slice(&body).map_err(|e| e.to_string())
}

#[tokio::main]
async fn main() {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let (status, _, body) = http_get(a.addr, "/api/scene").await;
    let scene: serde_json::Value = match serde_json::from_slice(&body) {
        Ok(v) if status == 200 => v,
        _ => {
            eprintln!("error: /api/scene: HTTP {status}");
            std::process::exit(1);
        }
    };
    let b: Vec<f64> = scene["bounds"]
        .as_array()
        .map(|v| v.iter().filter_map(|x| x.as_f64()).collect())
        .unwrap_or_default();
    if b.len() != 6 {
        eprintln!("error: /api/scene has no bounds");
        std::process::exit(1);
    }
    let m = a.margin;
    let area = [
        b[0] + m,
        b[1] + m,
        (b[3] - m).max(b[0] + m),
        (b[4] - m).max(b[1] + m),
    ];
    let before = match stats(a.addr).await {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let walk = Walk {
        area,
        speed_m_s: a.speed,
        hz: a.hz,
        until: Instant::now() + Duration::from_secs_f64(a.seconds),
    };
    let t0 = Instant::now();
    let tasks: Vec<_> = (0..a.clients)
        .map(|i| tokio::spawn(walker(a.addr, i + 1, walk)))
        .collect();
    // Sample the server's memory while the walkers run.
    let mut peak_rss = 0u64;
    while tasks.iter().any(|t| !t.is_finished()) {
        if let Ok(s) = stats(a.addr).await {
            peak_rss = peak_rss.max(s["memory_kib"]["rss"].as_u64().unwrap_or(0));
        }
        tokio::time::sleep(Duration::from_secs(1)).await;
    }
    let mut reps = vec![];
    for t in tasks {
        match t.await {
            Ok(r) => reps.push(r),
            Err(e) => {
                eprintln!("error: walker task: {e}");
                std::process::exit(1);
            }
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    let sum = summarise(&reps);
    let after = stats(a.addr).await.unwrap_or_default();
    let d = |k: &str| {
        after[k]
            .as_u64()
            .unwrap_or(0)
            .saturating_sub(before[k].as_u64().unwrap_or(0))
    };
    let silent = reps.iter().filter(|r| r.acks == 0).count();
    println!(
        "load: {} walkers × {} s ({wall:.1} s wall) at {} m/s, {} Hz, on {} ({} objects, {} cells of {} m, method {} {})\n  \
         acks {}, errors {} (walkers without answers {silent}; server ws_errors +{}), ack latency p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms\n  \
         cell changes {} (server: +{}), PVS in hand on entry {} ({:.1} %), received {:.1} MiB\n  \
         server memory: rss {} MiB at the end, peak sampled {} MiB, VmHWM {} MiB\n  \
         cache: {}",
        a.clients,
        a.seconds,
        a.speed,
        a.hz,
        a.addr,
        scene["objects"],
        scene["cells"],
        scene["grid"]["cell_size_m"],
        scene["method"],
        scene["source"],
        sum.acks,
        sum.errors.len(),
        d("ws_errors"),
        sum.p50_ms,
        sum.p99_ms,
        sum.max_ms,
        sum.cell_changes,
        d("cell_changes"),
        sum.in_hand,
        if sum.cell_changes > 0 {
            100.0 * sum.in_hand as f64 / sum.cell_changes as f64
        } else {
            100.0
        },
        sum.bytes as f64 / (1 << 20) as f64,
        after["memory_kib"]["rss"].as_u64().unwrap_or(0) / 1024,
        peak_rss / 1024,
        after["memory_kib"]["peak"].as_u64().unwrap_or(0) / 1024,
        after["cache"],
    );
    for e in sum.errors.iter().take(10) {
        eprintln!("  error: {e}");
    }
    if !sum.errors.is_empty() || silent > 0 {
        std::process::exit(1);
    }
}
