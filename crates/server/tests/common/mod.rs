//! A small city and a test server on loopback, shared by the integration tests.
#![allow(dead_code)]

use futures_util::{SinkExt, StreamExt};
use sightline_geom::{DVec2, Polygon};
use sightline_scene::{Object, Scene};
use sightline_server::grid::{CellGrid, CellId};
use sightline_server::source::{PvsSource, SharedSource, SourceError, SourceInfo};
use sightline_server::{Server, ServerConfig};
use std::net::SocketAddr;
use std::sync::Arc;
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
    fn grid(&self) -> &CellGrid {
        &self.grid
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
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
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
