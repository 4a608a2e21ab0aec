//! A small city and a test server on loopback, shared by the integration tests.
#![allow(dead_code)]

use futures_util::{SinkExt, StreamExt};
use sightline_geom::{DVec2, Polygon};
use sightline_scene::{Object, Scene};
use sightline_server::grid::{CellGrid, CellId};
use sightline_server::layout::Layout;
use sightline_server::source::{PvsSource, SharedSource, SourceError, SourceInfo};
use sightline_server::{Server, ServerConfig};
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::oneshot;
use tokio_tungstenite::tungstenite::Message;

/// `n × n` blocks of 20 × 20 m on a 40 m pitch (20 m streets), 10–40 m tall, plus one flat
/// street polygon.
pub fn block_city(n: usize) -> Scene {
    let mut objects = vec![];
    for j in 0..n {
        for i in 0..n {
            let x = i as f64 * 40.0 + 10.0;
            let y = j as f64 * 40.0 + 10.0;
            let h = 10.0 + ((i * 7 + j * 13) % 4) as f64 * 10.0;
            objects.push(Object::block(
                Some(format!("b{i}_{j}")),
                Polygon::rect(DVec2::new(x, y), DVec2::new(x + 20.0, y + 20.0)),
                0.0,
                h,
            ));
        }
    }
    let w = n as f64 * 40.0 + 20.0;
    objects.push(Object::flat(
        Some("street".into()),
        vec![Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(w, 10.0))],
    ));
    Scene::from_objects(objects)
}

/// A deterministic stand-in for a method whose PVS changes from cell to cell: the objects
/// whose bounds come within `radius_m` of the cell. (The server does not care which
/// method answers; the methods have their own conservativeness tests.)
pub struct NearSource {
    pub scene: Arc<Scene>,
    pub grid: CellGrid,
    pub radius_m: f64,
    pub delay_ms: u64,
}

impl PvsSource for NearSource {
    fn info(&self) -> SourceInfo {
        SourceInfo {
            kind: "online",
            method: "near-test".into(),
            conservative: false,
            params: vec![format!("radius={}", self.radius_m)],
        }
    }
    fn layout(&self) -> Layout<'_> {
        Layout::Grid(&self.grid)
    }
    fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError> {
        if self.delay_ms > 0 {
            std::thread::sleep(std::time::Duration::from_millis(self.delay_ms));
        }
        let c = self.grid.cell(id).ok_or(SourceError::NoCell(id))?;
        let (lo, hi) = (c.min.truncate(), c.max.truncate());
        Ok(self
            .scene
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| {
                let b = o.bounds.xy();
                b.min.x <= hi.x + self.radius_m
                    && b.max.x >= lo.x - self.radius_m
                    && b.min.y <= hi.y + self.radius_m
                    && b.max.y >= lo.y - self.radius_m
            })
            .map(|(i, _)| i as u32)
            .collect())
    }
}

pub fn near_source(scene: Arc<Scene>, cell_m: f64, radius_m: f64, delay_ms: u64) -> SharedSource {
    let grid = CellGrid::cover(&scene.bounds, cell_m).unwrap();
    Arc::new(NearSource {
        scene,
        grid,
        radius_m,
        delay_ms,
    })
}

/// A running test server; dropped → shut down.
pub struct TestServer {
    pub addr: SocketAddr,
    pub state: Arc<sightline_server::AppState>,
    stop: Option<oneshot::Sender<()>>,
    handle: Option<tokio::task::JoinHandle<std::io::Result<()>>>,
}

impl TestServer {
    pub async fn start(scene: Arc<Scene>, source: SharedSource, config: ServerConfig) -> Self {
        let listener = sightline_server::conn::listen("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let server = Server::new(scene, source, config);
        let state = server.state().clone();
        let (tx, rx) = oneshot::channel::<()>();
        let handle = tokio::spawn(server.run(listener, async move {
            let _ = rx.await;
        }));
        TestServer {
            addr,
            state,
            stop: Some(tx),
            handle: Some(handle),
        }
    }

    pub fn url(&self, path: &str) -> String {
        format!("http://{}{}", self.addr, path)
    }

    /// Stop gracefully and wait until the server has finished.
    pub async fn stop(mut self) -> std::io::Result<()> {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        match self.handle.take() {
            Some(h) => h.await.unwrap(),
            None => Ok(()),
        }
    }
}

/// A raw HTTP/1.1 GET on loopback (no HTTP client crate needed): (status, headers, body).
pub async fn http_get(addr: SocketAddr, path_and_query: &str) -> (u16, String, Vec<u8>) {
    http_request(
        addr,
        &format!("GET {path_and_query} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"),
    )
    .await
}

pub async fn http_request(addr: SocketAddr, raw: &str) -> (u16, String, Vec<u8>) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    s.write_all(raw.as_bytes()).await.unwrap();
    let mut buf = vec![];
    s.read_to_end(&mut buf).await.unwrap();
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a complete response");
    let head = String::from_utf8_lossy(&buf[..split]).to_string();
    let mut body = buf[split + 4..].to_vec();
    let status: u16 = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    if head
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        body = dechunk(&body);
    }
    (status, head, body)
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = vec![];
    loop {
        let Some(eol) = b.windows(2).position(|w| w == b"\r\n") else {
            return out;
        };
        let n = usize::from_str_radix(std::str::from_utf8(&b[..eol]).unwrap().trim(), 16).unwrap();
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[eol + 2..eol + 2 + n]);
        b = &b[eol + 2 + n + 2..];
    }
}

pub type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

pub async fn ws_connect(addr: SocketAddr, query: &str) -> Ws {
    let (ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/walk{query}"))
        .await
        .unwrap();
    ws
}

pub async fn ws_send(ws: &mut Ws, v: serde_json::Value) {
    ws.send(Message::Text(v.to_string().into())).await.unwrap();
}

/// The next message: Ok(json) for text, Err(bytes) for binary; None when closed.
pub async fn ws_next(ws: &mut Ws) -> Option<Result<serde_json::Value, Vec<u8>>> {
    loop {
        match tokio::time::timeout(std::time::Duration::from_secs(20), ws.next()).await {
            Ok(Some(Ok(Message::Text(t)))) => {
                return Some(Ok(serde_json::from_str(t.as_str()).unwrap()))
            }
            Ok(Some(Ok(Message::Binary(b)))) => return Some(Err(b.to_vec())),
            Ok(Some(Ok(Message::Close(_)))) | Ok(None) | Ok(Some(Err(_))) => return None,
            Ok(Some(Ok(_))) => continue,
            Err(_) => panic!("no message from the server within 20 s"),
        }
    }
}

/// What a client holds: the mirror of the protocol's state (as the viewer keeps it).
#[derive(Default)]
pub struct ClientState {
    pub cells: std::collections::HashMap<u32, std::collections::BTreeSet<u32>>,
    pub geometry: std::collections::HashSet<u32>,
    pub errors: Vec<String>,
}

impl ClientState {
    /// Apply one server message; returns its type.
    pub fn apply(&mut self, m: &Result<serde_json::Value, Vec<u8>>) -> String {
        match m {
            Err(bytes) => {
                let objs = sightline_server::geometry::decode(bytes).expect("valid SLG1");
                for o in objs {
                    self.geometry.insert(o.id);
                }
                "geometry".into()
            }
            Ok(v) => {
                let t = v["type"].as_str().unwrap_or("").to_string();
                match t.as_str() {
                    "cell" => {
                        let mut set = match v["base"].as_u64() {
                            Some(b) => self.cells.get(&(b as u32)).expect("base held").clone(),
                            None => Default::default(),
                        };
                        for a in v["added"].as_array().unwrap() {
                            set.insert(a.as_u64().unwrap() as u32);
                        }
                        for r in v["removed"].as_array().unwrap() {
                            set.remove(&(r.as_u64().unwrap() as u32));
                        }
                        assert_eq!(set.len() as u64, v["size"].as_u64().unwrap());
                        self.cells.insert(v["cell"].as_u64().unwrap() as u32, set);
                    }
                    "forget" => {
                        for c in v["cells"].as_array().unwrap() {
                            self.cells.remove(&(c.as_u64().unwrap() as u32));
                        }
                    }
                    "error" => self.errors.push(v["error"].to_string()),
                    _ => {}
                }
                t
            }
        }
    }
}

/// What one load-test walker saw.
#[derive(Default, Debug)]
pub struct ClientReport {
    pub acks: u64,
    pub latencies_us: Vec<u64>,
    pub cell_changes: u64,
    pub in_hand: u64,
    pub bytes: u64,
    pub errors: Vec<String>,
}

/// How a load-test walker moves.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    /// The rectangle it walks in (scene coordinates): `[x0, y0, x1, y1]`.
    pub area: [f64; 4],
    pub speed_m_s: f64,
    /// Position reports per second.
    pub hz: f64,
    pub until: Instant,
}

/// One walker: a random path (random start, heading changes, bouncing off the area's
/// border), a position report with a sequence number `hz` times a second, and a check of
/// every message it gets (deltas apply to cells it holds, sizes match, geometry decodes).
/// The ack latency is the time from sending a position to its `ack`; a cell change is
/// "in hand" when the ack of the first position in the new cell says the PVS was held.
pub async fn walker(addr: SocketAddr, seed: u64, walk: Walk) -> ClientReport {
    let mut rep = ClientReport::default();
    let ws = match tokio_tungstenite::connect_async(format!("ws://{addr}/api/walk")).await {
        Ok((ws, _)) => ws,
        Err(e) => {
            rep.errors.push(format!("connect: {e}"));
            return rep;
        }
    };
    let (mut tx, mut rx) = ws.split();
    let sent: Arc<std::sync::Mutex<std::collections::HashMap<u64, Instant>>> = Arc::default();
    let sent_w = sent.clone();
    let [x0, y0, x1, y1] = walk.area;
    let writer = tokio::spawn(async move {
        let mut rng = sightline_stats::Rng::new(seed);
        let (mut x, mut y) = (x0 + rng.f64() * (x1 - x0), y0 + rng.f64() * (y1 - y0));
        let mut a = rng.f64() * std::f64::consts::TAU;
        let mut seq = 0u64;
        let step_s = 1.0 / walk.hz.max(0.1);
        let mut tick = tokio::time::interval(std::time::Duration::from_secs_f64(step_s));
        let hello = serde_json::json!({"type": "hello", "geometry": true}).to_string();
        if tx.send(Message::Text(hello.into())).await.is_err() {
            return;
        }
        while Instant::now() < walk.until {
            tick.tick().await;
            if rng.f64() < 0.5 * step_s {
                a += (rng.f64() - 0.5) * 2.0;
            }
            x += a.cos() * walk.speed_m_s * step_s;
            y += a.sin() * walk.speed_m_s * step_s;
            if !(x0..=x1).contains(&x) || !(y0..=y1).contains(&y) {
                a += std::f64::consts::PI;
                x = x.clamp(x0, x1);
                y = y.clamp(y0, y1);
            }
            sent_w
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .insert(seq, Instant::now());
            let m = serde_json::json!({"type": "pos", "x": x, "y": y, "z": 1.7, "seq": seq});
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
        let m = match tokio::time::timeout(std::time::Duration::from_secs(30), rx.next()).await {
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
                .and_then(|s| sent.lock().unwrap_or_else(|p| p.into_inner()).remove(&s))
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

/// Totals over walkers.
#[derive(Debug)]
pub struct LoadSummary {
    pub acks: usize,
    pub errors: Vec<String>,
    /// Ack latency p50, p99, max (ms).
    pub p50_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
    pub cell_changes: u64,
    pub in_hand: u64,
    pub bytes: u64,
}

pub fn summarise(reps: &[ClientReport]) -> LoadSummary {
    let mut lat: Vec<u64> = reps
        .iter()
        .flat_map(|r| r.latencies_us.iter().copied())
        .collect();
    lat.sort_unstable();
    let q = |p: f64| {
        lat.get(((lat.len() as f64 - 1.0).max(0.0) * p).round() as usize)
            .copied()
            .unwrap_or(0) as f64
            / 1000.0
    };
    LoadSummary {
        acks: lat.len(),
        errors: reps.iter().flat_map(|r| r.errors.iter().cloned()).collect(),
        p50_ms: q(0.5),
        p99_ms: q(0.99),
        max_ms: q(1.0),
        cell_changes: reps.iter().map(|r| r.cell_changes).sum(),
        in_hand: reps.iter().map(|r| r.in_hand).sum(),
        bytes: reps.iter().map(|r| r.bytes).sum(),
    }
}
