//! Load test: many concurrent walk sessions on loopback.
//!
//! Each client walks a random path (random start, heading changes, bouncing off the scene
//! border), reports its position 10 times a second with a sequence number and checks every
//! message it gets (deltas apply to cells it holds, sizes match, geometry decodes). Reported:
//! errors (must be 0), ack latency p50/p99/max, cell changes and how many had the PVS in
//! hand, bytes received and the server's memory.
//!
//! Small in CI (`LOAD_CLIENTS=20`, `LOAD_SECONDS=5`); the report's run:
//! `LOAD_CLIENTS=200 LOAD_SECONDS=60 cargo test --release -p sightline-server --test load -- --nocapture`.

mod common;

use common::*;
use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use sightline_server::ServerConfig;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

#[derive(Default, Debug)]
struct ClientReport {
    acks: u64,
    latencies_us: Vec<u64>,
    cell_changes: u64,
    in_hand: u64,
    bytes: u64,
    errors: Vec<String>,
}

/// xorshift: the paths are random but reproducible per client.
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

async fn client(
    addr: std::net::SocketAddr,
    seed: u64,
    size_m: f64,
    speed_m_s: f64,
    until: Instant,
) -> ClientReport {
    let mut rep = ClientReport::default();
    let ws = match tokio_tungstenite::connect_async(format!("ws://{addr}/api/walk")).await {
        Ok((ws, _)) => ws,
        Err(e) => {
            rep.errors.push(format!("connect: {e}"));
            return rep;
        }
    };
    let (mut tx, mut rx) = ws.split();
    let sent: Arc<Mutex<HashMap<u64, Instant>>> = Arc::default();
    let sent_w = sent.clone();
    let writer = tokio::spawn(async move {
        let mut rng = Rng(seed * 2654435761 + 1);
        let (mut x, mut y) = (rng.f() * size_m, rng.f() * size_m);
        let mut a = rng.f() * std::f64::consts::TAU;
        let mut seq = 0u64;
        let mut tick = tokio::time::interval(Duration::from_millis(100));
        let hello = json!({"type": "hello", "geometry": true}).to_string();
        if tx.send(Message::Text(hello.into())).await.is_err() {
            return;
        }
        while Instant::now() < until {
            tick.tick().await;
            if rng.f() < 0.05 {
                a += (rng.f() - 0.5) * 2.0;
            }
            x += a.cos() * speed_m_s * 0.1;
            y += a.sin() * speed_m_s * 0.1;
            if !(0.0..=size_m).contains(&x) || !(0.0..=size_m).contains(&y) {
                a += std::f64::consts::PI;
                x = x.clamp(0.0, size_m);
                y = y.clamp(0.0, size_m);
            }
            sent_w.lock().unwrap().insert(seq, Instant::now());
            let m = json!({"type": "pos", "x": x, "y": y, "z": 1.7, "seq": seq});
            if tx.send(Message::Text(m.to_string().into())).await.is_err() {
                return;
            }
            seq += 1;
        }
        let _ = tx.send(Message::Close(None)).await;
    });
    let mut state = ClientState::default();
    let mut cell: Option<u64> = None;
    loop {
        let m = match tokio::time::timeout(Duration::from_secs(30), rx.next()).await {
            Ok(Some(Ok(m))) => m,
            Ok(None) | Ok(Some(Err(_))) => break,
            Err(_) => {
                rep.errors.push("no message for 30 s".into());
                break;
            }
        };
        let parsed = match m {
            Message::Text(t) => {
                rep.bytes += t.as_str().len() as u64;
                match serde_json::from_str::<serde_json::Value>(t.as_str()) {
                    Ok(v) => Ok(v),
                    Err(e) => {
                        rep.errors.push(format!("bad JSON from server: {e}"));
                        continue;
                    }
                }
            }
            Message::Binary(b) => {
                rep.bytes += b.len() as u64;
                if let Err(e) = sightline_server::geometry::decode(&b) {
                    rep.errors.push(e.to_string());
                    continue;
                }
                Err(b.to_vec())
            }
            Message::Close(_) => break,
            _ => continue,
        };
        let applied =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| state.apply(&parsed)));
        let t = match applied {
            Ok(t) => t,
            Err(_) => {
                rep.errors.push("inconsistent cell message".into());
                continue;
            }
        };
        if t == "ack" {
            let v = parsed.as_ref().ok().cloned().unwrap_or_default();
            rep.acks += 1;
            if let Some(at) = v["seq"]
                .as_u64()
                .and_then(|s| sent.lock().unwrap().remove(&s))
            {
                rep.latencies_us.push(at.elapsed().as_micros() as u64);
            }
            let c = v["cell"].as_u64();
            if cell.is_some() && c != cell {
                rep.cell_changes += 1;
                if v["held"] == true {
                    rep.in_hand += 1;
                }
            }
            cell = c;
        }
    }
    rep.errors.append(&mut state.errors);
    let _ = writer.await;
    rep
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
    let size_m = blocks as f64 * 40.0 + 20.0;
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
    let until = Instant::now() + Duration::from_secs_f64(seconds);
    let t0 = Instant::now();
    let tasks: Vec<_> = (0..clients)
        .map(|i| tokio::spawn(client(s.addr, i + 1, size_m, speed, until)))
        .collect();
    let mut reps = vec![];
    for t in tasks {
        reps.push(t.await.unwrap());
    }
    let wall = t0.elapsed().as_secs_f64();
    let mut lat: Vec<u64> = reps
        .iter()
        .flat_map(|r| r.latencies_us.iter().copied())
        .collect();
    lat.sort_unstable();
    let q = |p: f64| {
        lat.get(((lat.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(0) as f64
            / 1000.0
    };
    let errors: Vec<&String> = reps.iter().flat_map(|r| &r.errors).collect();
    let changes: u64 = reps.iter().map(|r| r.cell_changes).sum();
    let in_hand: u64 = reps.iter().map(|r| r.in_hand).sum();
    let bytes: u64 = reps.iter().map(|r| r.bytes).sum();
    let (rss, peak) = sightline_server::memory_kib();
    let stats = http_get(s.addr, "/api/stats").await.2;
    let stats: serde_json::Value = serde_json::from_slice(&stats).unwrap();
    println!(
        "load: {clients} clients × {seconds} s ({wall:.1} s wall), {} objects, {cell_m} m cells, {speed} m/s, \
         {delay_ms} ms/cell source\n  messages acked {}, errors {}, ack latency p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms\n  \
         cell changes {changes}, PVS in hand on entry {in_hand} ({:.1} %), received {:.1} MiB\n  \
         process memory (server + clients): rss {} MiB, peak {} MiB; cache {}",
        scene.objects.len(),
        lat.len(),
        errors.len(),
        q(0.5),
        q(0.99),
        q(1.0),
        if changes > 0 { 100.0 * in_hand as f64 / changes as f64 } else { 100.0 },
        bytes as f64 / (1 << 20) as f64,
        rss / 1024,
        peak / 1024,
        stats["cache"],
    );
    assert!(errors.is_empty(), "errors: {errors:?}");
    assert!(reps.iter().all(|r| r.acks > 0), "every client got answers");
    assert_eq!(stats["ws_errors"], 0);
    s.stop().await.unwrap();
}
