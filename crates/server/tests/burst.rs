//! Bursts and hostile clients on loopback: the server holds 2,000 simultaneous
//! connections next to half-open and slowloris clients, answers every admitted request
//! correctly, refuses what is over capacity with `503` and a JSON error, and stays alive.
//!
//! Bounded in count and time: a few thousand connections on loopback, a stand-in PVS
//! source (the server is what is tested here, not a method). Reported: p50/p99/max
//! latency, failures and the process's peak memory (server and clients share it).

mod common;

use common::*;
use sightline_server::cache::CacheConfig;
use sightline_server::ServerConfig;
use sightline_stats::quantile_sorted as quantile;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

/// One `GET` on its own connection: status, headers, body, or why it failed.
async fn get(addr: SocketAddr, path: &str) -> Result<(u16, String, Vec<u8>), String> {
    let io = async {
        let mut s = TcpStream::connect(addr).await?;
        let req = format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
        s.write_all(req.as_bytes()).await?;
        let mut buf = vec![];
        s.read_to_end(&mut buf).await?;
        Ok::<_, std::io::Error>(buf)
    };
    let buf = tokio::time::timeout(Duration::from_secs(60), io)
        .await
        .map_err(|_| "no answer within 60 s".to_string())?
        .map_err(|e| format!("i/o: {e}"))?;
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .ok_or_else(|| format!("incomplete response ({} bytes)", buf.len()))?;
    let head = String::from_utf8_lossy(&buf[..split]).to_string();
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .ok_or_else(|| format!("bad status line in {head:?}"))?;
    Ok((status, head, buf[split + 4..].to_vec()))
}

/// Seconds until the server closes connection `s` (opened at `t0`) that sends `prefix`
/// and then, every `drip`, one more byte of a header that never ends (`None`: sends
/// nothing at all).
async fn held_open(
    mut s: TcpStream,
    t0: Instant,
    prefix: &'static [u8],
    drip: Option<Duration>,
) -> f64 {
    let _ = s.write_all(prefix).await;
    let mut buf = [0u8; 256];
    loop {
        let wait = drip.unwrap_or(Duration::from_secs(120));
        match tokio::time::timeout(wait, s.read(&mut buf)).await {
            Ok(Ok(0)) | Ok(Err(_)) => return t0.elapsed().as_secs_f64(),
            Ok(Ok(_)) => {} // a 408 or similar before the close
            Err(_) => {
                if s.write_all(b"x").await.is_err() {
                    return t0.elapsed().as_secs_f64();
                }
            }
        }
        if t0.elapsed() > Duration::from_secs(60) {
            return f64::INFINITY;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn burst_of_2000_connections_beside_slow_and_half_open_clients() {
    let limit = sightline_server::conn::raise_fd_limit().unwrap_or(u64::MAX);
    const BURST: usize = 2000;
    const HALF_OPEN: usize = 200;
    const SLOW: usize = 100;
    // Each connection is two descriptors in this process (client and server side).
    assert!(
        limit >= 2 * (BURST + HALF_OPEN + SLOW) as u64 + 200,
        "open-file limit {limit} is too low for this test"
    );
    let scene = Arc::new(block_city(25));
    let b = scene.bounds;
    let src = near_source(scene.clone(), 50.0, 80.0, 2);
    let header_timeout = Duration::from_secs(2);
    let s = TestServer::start(
        scene.clone(),
        src.clone(),
        ServerConfig {
            header_read_timeout: header_timeout,
            ..Default::default()
        },
    )
    .await;
    let addr = s.addr;

    // The slow and half-open clients are connected (and accepted) before the burst: a
    // connection the server has not accepted yet is not one it can time out.
    let mut half_open = vec![];
    for _ in 0..HALF_OPEN {
        let c = TcpStream::connect(addr).await.expect("connect");
        half_open.push(tokio::spawn(held_open(c, Instant::now(), b"", None)));
    }
    let mut slow = vec![];
    for _ in 0..SLOW {
        let c = TcpStream::connect(addr).await.expect("connect");
        slow.push(tokio::spawn(held_open(
            c,
            Instant::now(),
            b"GET /api/scene HTTP/1.1\r\nHost: x\r\nX-Slow: ",
            Some(Duration::from_millis(300)),
        )));
    }
    tokio::time::sleep(Duration::from_millis(200)).await;

    // The burst: every client connects at the same moment.
    let start = Arc::new(tokio::sync::Barrier::new(BURST));
    let t0 = Instant::now();
    let burst: Vec<_> = (0..BURST)
        .map(|i| {
            let start = start.clone();
            let src = src.clone();
            tokio::spawn(async move {
                let k = i as f64;
                let p = [
                    b.min.x + (k * 37.3) % (b.max.x - b.min.x),
                    b.min.y + (k * 61.7) % (b.max.y - b.min.y),
                    1.7,
                ];
                start.wait().await;
                let t = Instant::now();
                let r = get(addr, &format!("/api/pvs?at={},{},{}", p[0], p[1], p[2])).await;
                let ms = t.elapsed().as_secs_f64() * 1e3;
                let check = r.and_then(|(code, _, body)| {
                    if code != 200 {
                        return Err(format!("status {code}: {}", String::from_utf8_lossy(&body)));
                    }
                    let v: serde_json::Value =
                        serde_json::from_slice(&body).map_err(|e| format!("bad JSON: {e}"))?;
                    let id = src
                        .locate(sightline_geom::DVec3::from_array(p))
                        .map_err(|e| e.to_string())?;
                    let want = src.pvs(id).map_err(|e| e.to_string())?;
                    let got: Vec<u32> = serde_json::from_value(v["visible"].clone())
                        .map_err(|e| format!("bad visible: {e}"))?;
                    if v["cell_id"] != id || got != want {
                        return Err(format!("wrong answer for {p:?}: cell {}", v["cell_id"]));
                    }
                    Ok(())
                });
                (ms, check)
            })
        })
        .collect();
    let mut ms = vec![];
    let mut failures = vec![];
    for h in burst {
        let (t, r) = h.await.unwrap();
        ms.push(t);
        if let Err(e) = r {
            failures.push(e);
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    ms.sort_by(f64::total_cmp);

    let mut held = vec![];
    for h in half_open.into_iter().chain(slow) {
        held.push(h.await.unwrap());
    }

    // Still alive and still right.
    let (code, _, _) = get(addr, "/api/scene")
        .await
        .expect("server alive after the burst");
    let stats = get(addr, "/api/stats").await.unwrap().2;
    let stats: serde_json::Value = serde_json::from_slice(&stats).unwrap();
    let (_, peak_kib) = sightline_server::memory_kib();
    println!(
        "burst: {BURST} concurrent GET /api/pvs beside {HALF_OPEN} half-open and {SLOW} slowloris \
         clients, {wall:.2} s wall\n  failed {}, latency p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms\n  \
         half-open clients closed after {:.2} s at most, slowloris after {:.2} s (header timeout {} s)\n  \
         peak memory of the process (server + clients) {} MiB; server refused {} (503), queued now {}",
        failures.len(),
        quantile(&ms, 0.5),
        quantile(&ms, 0.99),
        ms[ms.len() - 1],
        held[..HALF_OPEN].iter().fold(0.0f64, |a, &b| a.max(b)),
        held[HALF_OPEN..].iter().fold(0.0f64, |a, &b| a.max(b)),
        header_timeout.as_secs_f64(),
        peak_kib / 1024,
        stats["http_over_capacity"],
        stats["http_queued"],
    );
    assert!(
        failures.is_empty(),
        "{} failed, first: {:?}",
        failures.len(),
        &failures[..failures.len().min(5)]
    );
    assert_eq!(code, 200);
    let longest = held.iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(
        longest < header_timeout.as_secs_f64() + 10.0,
        "a slow or half-open client was kept for {longest:.1} s"
    );
    // Bounded memory: thousands of connections, not thousands of megabytes.
    assert!(peak_kib < 1024 * 1024, "peak {peak_kib} KiB");
    s.stop().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn over_capacity_is_503_with_a_json_error_then_recovers() {
    let scene = Arc::new(block_city(10));
    // Slow cells (100 ms each, one worker), few slots, a short queue.
    let src = near_source(scene.clone(), 20.0, 60.0, 100);
    let s = TestServer::start(
        scene.clone(),
        src,
        ServerConfig {
            max_inflight: 4,
            max_queued: 8,
            queue_timeout: Duration::from_millis(300),
            cache: CacheConfig {
                workers: 1,
                ..CacheConfig::default()
            },
            ..Default::default()
        },
    )
    .await;
    let addr = s.addr;
    let tasks: Vec<_> = (0..100)
        .map(|i| {
            let (x, y) = ((i % 10) as f64 * 41.0 + 5.0, (i / 10) as f64 * 41.0 + 5.0);
            tokio::spawn(async move { get(addr, &format!("/api/pvs?at={x},{y},1.7")).await })
        })
        .collect();
    let (mut ok, mut refused) = (0, 0);
    for t in tasks {
        let (code, head, body) = t.await.unwrap().expect("every request is answered");
        match code {
            200 => ok += 1,
            503 => {
                refused += 1;
                let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
                assert!(
                    v["error"].as_str().unwrap().contains("over capacity"),
                    "{v}"
                );
                assert!(
                    head.to_ascii_lowercase().contains("retry-after: 1"),
                    "{head}"
                );
            }
            c => panic!("unexpected status {c}: {}", String::from_utf8_lossy(&body)),
        }
    }
    println!("over capacity: {ok} answered, {refused} refused with 503");
    assert!(ok >= 4 && refused > 0, "{ok} answered, {refused} refused");
    // Once the burst is over, requests are served again.
    let (code, _, _) = get(addr, "/api/pvs?at=205,15,1.7").await.unwrap();
    assert_eq!(code, 200);
    s.stop().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn connections_over_the_cap_get_503_and_the_server_goes_on() {
    let scene = Arc::new(block_city(5));
    let src = near_source(scene.clone(), 50.0, 60.0, 0);
    let s = TestServer::start(
        scene.clone(),
        src,
        ServerConfig {
            max_connections: 20,
            header_read_timeout: Duration::from_secs(30),
            ..Default::default()
        },
    )
    .await;
    let addr = s.addr;
    let mut idle = vec![];
    for _ in 0..20 {
        idle.push(TcpStream::connect(addr).await.unwrap());
    }
    // Let the server accept them all before the one too many.
    tokio::time::sleep(Duration::from_millis(200)).await;
    let (code, _, body) = get(addr, "/api/scene").await.unwrap();
    assert_eq!(code, 503, "{}", String::from_utf8_lossy(&body));
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert!(v["error"]
        .as_str()
        .unwrap()
        .contains("too many connections"));
    drop(idle);
    tokio::time::sleep(Duration::from_millis(200)).await;
    assert_eq!(get(addr, "/api/scene").await.unwrap().0, 200);
    s.stop().await.unwrap();
}
