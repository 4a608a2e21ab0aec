//! The HTTP API and the walk protocol against a server on loopback.

mod common;

use common::*;
use serde_json::json;
use sightline_server::grid::CellGrid;
use sightline_server::source::OnlineSource;
use sightline_server::ServerConfig;
use std::sync::Arc;

async fn near_server(config: ServerConfig) -> (Arc<sightline_scene::Scene>, TestServer) {
    let scene = Arc::new(block_city(6)); // 260 × 260 m, 37 objects
    let src = near_source(scene.clone(), 50.0, 30.0, 0);
    let s = TestServer::start(scene.clone(), src, config).await;
    (scene, s)
}

#[tokio::test]
async fn scene_pvs_and_objects_endpoints() {
    let (scene, s) = near_server(ServerConfig::default()).await;
    let (st, _, body) = http_get(s.addr, "/api/scene").await;
    assert_eq!(st, 200);
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(v["objects"], 37);
    assert_eq!(v["method"], "near-test");
    assert_eq!(v["grid"]["nx"], 6);
    assert_eq!(v["grid"]["ny"], 5);
    assert_eq!(v["cells"], 30);

    // The PVS of the cell containing a point: the `query` JSON.
    let (st, _, body) = http_get(s.addr, "/api/pvs?at=5,5,1.7").await;
    assert_eq!(st, 200);
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(v["cell"], json!([0.0, 0.0, 1.5, 50.0, 50.0, 2.0]));
    let visible: Vec<u32> = serde_json::from_value(v["visible"].clone()).unwrap();
    assert!(visible.windows(2).all(|w| w[0] < w[1]));
    assert!(visible.contains(&0) && visible.contains(&36));

    // Geometry of those objects, SLG1.
    let ids: Vec<String> = visible.iter().map(|i| i.to_string()).collect();
    let (st, head, body) = http_get(s.addr, &format!("/api/objects?ids={}", ids.join(","))).await;
    assert_eq!(st, 200);
    assert!(head.contains("application/octet-stream"));
    let objs = sightline_server::geometry::decode(&body).unwrap();
    assert_eq!(objs.iter().map(|o| o.id).collect::<Vec<_>>(), visible);
    assert!(objs.iter().all(|o| !o.indices.is_empty()));

    let (st, _, body) = http_get(s.addr, "/api/boxes").await;
    assert_eq!(st, 200);
    assert_eq!(body.len(), 8 + 24 * scene.objects.len());

    let (st, _, body) = http_get(s.addr, "/api/stats").await;
    assert_eq!(st, 200);
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert!(v["cache"]["computed"].as_u64().unwrap() >= 1);
    s.stop().await.unwrap();
}

#[tokio::test]
async fn bad_requests_get_json_errors() {
    let (_scene, s) = near_server(ServerConfig::default()).await;
    for (path, status) in [
        ("/api/pvs", 400),
        ("/api/pvs?at=1,2", 400),
        ("/api/pvs?at=a,b,c", 400),
        ("/api/pvs?at=NaN,1,1", 400),
        ("/api/pvs?at=-1000,5,1.7", 400),
        ("/api/pvs?at=5,5,1e9", 400),
        ("/api/objects", 400),
        ("/api/objects?ids=1,x", 400),
        ("/api/objects?ids=37", 400),
        ("/api/objects?ids=-3", 400),
        ("/api/nothing", 404),
        ("/api/../../etc/passwd", 404),
    ] {
        let (st, _, body) = http_get(s.addr, path).await;
        assert_eq!(st, status, "{path}");
        let v: serde_json::Value = serde_json::from_slice(&body)
            .unwrap_or_else(|_| panic!("{path}: not JSON: {}", String::from_utf8_lossy(&body)));
        assert!(v["error"].as_str().is_some_and(|e| !e.is_empty()), "{path}");
    }
    // Too many ids in one request.
    let many: Vec<String> = (0..9000).map(|i| (i % 37).to_string()).collect();
    let (st, _, _) = http_get(s.addr, &format!("/api/objects?ids={}", many.join(","))).await;
    assert!(st == 400 || st == 431 || st == 414, "status {st}");
    // A request with a body is refused, the server stays up.
    let big = "x".repeat(10_000);
    let (st, _, _) = http_request(
        s.addr,
        &format!("POST /api/scene HTTP/1.1\r\nHost: x\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{big}", big.len()),
    )
    .await;
    assert!(st >= 400, "status {st}");
    let (st, _, _) = http_get(s.addr, "/api/scene").await;
    assert_eq!(st, 200);
    s.stop().await.unwrap();
}

#[tokio::test]
async fn token_is_required_when_set() {
    let (_scene, s) = near_server(ServerConfig {
        token: Some("s3cret".into()),
        ..Default::default()
    })
    .await;
    assert_eq!(http_get(s.addr, "/api/scene").await.0, 401);
    assert_eq!(http_get(s.addr, "/api/scene?token=wrong").await.0, 401);
    assert_eq!(http_get(s.addr, "/api/scene?token=s3cret").await.0, 200);
    let (st, _, _) = http_request(
        s.addr,
        "GET /api/scene HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer s3cret\r\nConnection: close\r\n\r\n",
    )
    .await;
    assert_eq!(st, 200);
    // The viewer itself needs no token; the walk does.
    assert_eq!(http_get(s.addr, "/").await.0, 200);
    assert!(
        tokio_tungstenite::connect_async(format!("ws://{}/api/walk", s.addr))
            .await
            .is_err()
    );
    let mut ws = ws_connect(s.addr, "?token=s3cret").await;
    let w = ws_next(&mut ws).await.unwrap().unwrap();
    assert_eq!(w["type"], "welcome");
    s.stop().await.unwrap();
}

#[tokio::test]
async fn http_rate_limit_answers_429() {
    let (_scene, s) = near_server(ServerConfig {
        http_rate_per_s: 0.001,
        http_burst: 5.0,
        // The test client is on loopback, which is not limited by default.
        rate_limit_loopback: true,
        ..Default::default()
    })
    .await;
    let mut codes = vec![];
    for _ in 0..8 {
        codes.push(http_get(s.addr, "/api/scene").await.0);
    }
    assert_eq!(&codes[..5], &[200; 5]);
    assert!(codes[5..].iter().all(|&c| c == 429), "{codes:?}");
    s.stop().await.unwrap();
}

#[tokio::test]
async fn viewer_assets_are_embedded() {
    let (_scene, s) = near_server(ServerConfig::default()).await;
    let (st, head, body) = http_get(s.addr, "/").await;
    assert_eq!(st, 200);
    assert!(head.contains("text/html"));
    assert!(String::from_utf8_lossy(&body).contains("app.js"));
    let (st, _, body) = http_get(s.addr, "/vendor/three.module.min.js").await;
    assert_eq!(st, 200);
    assert!(body.len() > 100_000);
    assert_eq!(http_get(s.addr, "/app.js").await.0, 200);
    assert_eq!(http_get(s.addr, "/vendor/three.LICENSE").await.0, 200);
    assert_eq!(http_get(s.addr, "/Cargo.toml").await.0, 404);
    s.stop().await.unwrap();
}

/// Walk east across several cells: at start the cell and its 8 neighbours arrive; every
/// cell entered afterwards was already held; each PVS equals `/api/pvs` there; geometry
/// arrives before the cells that refer to it.
#[tokio::test]
async fn walk_prefetches_neighbours_and_sends_deltas() {
    let (_scene, s) = near_server(ServerConfig::default()).await;
    let mut ws = ws_connect(s.addr, "").await;
    let mut c = ClientState::default();
    assert_eq!(c.apply(&ws_next(&mut ws).await.unwrap()), "welcome");
    ws_send(&mut ws, json!({"type": "hello", "geometry": true})).await;
    // Start in cell (1,1) of the 6 × 6 grid of 50 m cells.
    let y = 75.0;
    let mut x = 70.0;
    ws_send(
        &mut ws,
        json!({"type": "pos", "x": x, "y": y, "z": 1.7, "seq": 0}),
    )
    .await;
    let grid = CellGrid::cover(&s.state.scene.bounds, 50.0).unwrap();
    let start = grid.locate(sightline_geom::DVec3::new(x, y, 1.7)).unwrap();
    let mut want: std::collections::BTreeSet<u32> = grid
        .neighbours(start, sightline_geom::DVec2::ZERO)
        .into_iter()
        .collect();
    want.insert(start);
    while !want.iter().all(|k| c.cells.contains_key(k)) {
        let m = ws_next(&mut ws).await.expect("open");
        if let Ok(v) = &m {
            if v["type"] == "cell" {
                for id in v["added"].as_array().unwrap() {
                    assert!(
                        c.geometry.contains(&(id.as_u64().unwrap() as u32)),
                        "geometry first"
                    );
                }
            }
        }
        c.apply(&m);
    }
    assert_eq!(c.cells.len(), 9, "the cell and its 8 neighbours");
    let mut seq = 1;
    let mut entered = 0;
    while x < 240.0 {
        x += 10.0;
        ws_send(
            &mut ws,
            json!({"type": "pos", "x": x, "y": y, "z": 1.7, "seq": seq}),
        )
        .await;
        // Read until the ack of this position.
        let ack = loop {
            let m = ws_next(&mut ws).await.expect("open");
            c.apply(&m);
            if let Ok(v) = &m {
                if v["type"] == "ack" && v["seq"] == seq {
                    break v.clone();
                }
            }
        };
        seq += 1;
        let cell = ack["cell"].as_u64().unwrap() as u32;
        assert_eq!(
            ack["held"], true,
            "cell {cell} prefetched before entering it"
        );
        let held = c.cells.get(&cell).expect("client holds the PVS");
        let (_, _, body) = http_get(s.addr, &format!("/api/pvs?at={x},{y},1.7")).await;
        let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
        let truth: std::collections::BTreeSet<u32> =
            serde_json::from_value(v["visible"].clone()).unwrap();
        assert_eq!(held, &truth, "cell {cell}");
        assert!(truth.iter().all(|id| c.geometry.contains(id)));
        if (x as u32).is_multiple_of(50) {
            entered += 1;
        }
        // Give the prefetch of the next cells time, as walking does.
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        while let Ok(Some(m)) =
            tokio::time::timeout(std::time::Duration::from_millis(30), ws_next(&mut ws)).await
        {
            c.apply(&m);
        }
    }
    assert!(entered >= 3);
    assert!(c.errors.is_empty(), "{:?}", c.errors);
    let stats = http_get(s.addr, "/api/stats").await.2;
    let v: serde_json::Value = serde_json::from_slice(&stats).unwrap();
    assert!(v["cell_changes"].as_u64().unwrap() >= 3);
    assert_eq!(v["cell_changes"], v["prefetch_hits"]);
    s.stop().await.unwrap();
}

/// A server over a 6 × 6 block city with a single (slow) worker computing the PVS.
async fn one_slow_worker_server() -> (TestServer, Arc<sightline_scene::Scene>) {
    let scene = Arc::new(block_city(6));
    let src = near_source(scene.clone(), 50.0, 30.0, 100);
    let config = ServerConfig {
        cache: sightline_server::cache::CacheConfig {
            workers: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    (TestServer::start(scene.clone(), src, config).await, scene)
}

#[tokio::test]
async fn a_closed_session_withdraws_what_it_waited_for() {
    let (s, _) = one_slow_worker_server().await;
    let mut ws = ws_connect(s.addr, "").await;
    assert_eq!(ws_next(&mut ws).await.unwrap().unwrap()["type"], "welcome");
    ws_send(
        &mut ws,
        json!({"type": "pos", "x": 75.0, "y": 75.0, "z": 1.7, "seq": 0}),
    )
    .await;
    // The ack: the session has queued its 9 cells.
    while ws_next(&mut ws)
        .await
        .unwrap()
        .map_or(true, |v| v["type"] != "ack")
    {}
    drop(ws);
    let mut cache = serde_json::Value::Null;
    for _ in 0..100 {
        let v: serde_json::Value =
            serde_json::from_slice(&http_get(s.addr, "/api/stats").await.2).unwrap();
        cache = v["cache"].clone();
        if cache["cancelled"].as_u64().unwrap() >= 7 && cache["queued"] == 0 {
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    assert!(cache["cancelled"].as_u64().unwrap() >= 7, "{cache}");
    assert!(cache["computed"].as_u64().unwrap() <= 2, "{cache}");
    s.stop().await.unwrap();
}

#[tokio::test]
async fn a_jump_withdraws_the_prefetches_left_behind() {
    // One slow worker: the old neighbourhood's prefetches are still queued at the jump.
    let (s, scene) = one_slow_worker_server().await;
    let mut ws = ws_connect(s.addr, "").await;
    let mut c = ClientState::default();
    assert_eq!(c.apply(&ws_next(&mut ws).await.unwrap()), "welcome");
    ws_send(
        &mut ws,
        json!({"type": "pos", "x": 75.0, "y": 75.0, "z": 1.7}),
    )
    .await;
    // Cell (4, 4): no neighbour in common with (1, 1).
    ws_send(
        &mut ws,
        json!({"type": "pos", "x": 225.0, "y": 225.0, "z": 1.7, "seq": 1}),
    )
    .await;
    let grid = CellGrid::cover(&scene.bounds, 50.0).unwrap();
    let far = grid
        .locate(sightline_geom::DVec3::new(225.0, 225.0, 1.7))
        .unwrap();
    while !c.cells.contains_key(&far) {
        c.apply(&ws_next(&mut ws).await.expect("open"));
    }
    // Of the 8 prefetches of (1, 1), at most one had started when the client jumped; the
    // worker drops the others when it comes to them.
    let mut cache = serde_json::Value::Null;
    for _ in 0..100 {
        let stats = http_get(s.addr, "/api/stats").await.2;
        let v: serde_json::Value = serde_json::from_slice(&stats).unwrap();
        cache = v["cache"].clone();
        if cache["cancelled"].as_u64().unwrap() >= 7 {
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    assert!(cache["cancelled"].as_u64().unwrap() >= 7, "{cache}");
    assert!(
        cache["computed"].as_u64().unwrap() <= 1 + 1 + 8 + 1,
        "{cache}"
    );
    assert!(c.errors.is_empty(), "{:?}", c.errors);
    s.stop().await.unwrap();
}

#[tokio::test]
async fn malformed_messages_get_error_frames_and_never_crash() {
    let (_scene, s) = near_server(ServerConfig {
        max_session_errors: 10,
        ..Default::default()
    })
    .await;
    let mut ws = ws_connect(s.addr, "").await;
    assert_eq!(ws_next(&mut ws).await.unwrap().unwrap()["type"], "welcome");
    use futures_util::SinkExt;
    use tokio_tungstenite::tungstenite::Message;
    let bad: Vec<Message> = vec![
        Message::Text("not json".into()),
        Message::Text("{}".into()),
        Message::Text(r#"{"type":"pos","x":"a","y":1,"z":1}"#.into()),
        Message::Text(r#"{"type":"pos","x":1e300,"y":1e300,"z":1}"#.into()),
        Message::Text(r#"{"type":"teleport"}"#.into()),
        Message::Binary(vec![0u8; 10].into()),
    ];
    for m in bad {
        ws.send(m).await.unwrap();
        let e = ws_next(&mut ws).await.unwrap().unwrap();
        assert_eq!(e["type"], "error", "{e}");
    }
    // Still answering.
    ws_send(
        &mut ws,
        json!({"type": "pos", "x": 5.0, "y": 5.0, "z": 1.7, "seq": 1}),
    )
    .await;
    loop {
        let m = ws_next(&mut ws).await.unwrap();
        if let Ok(v) = m {
            if v["type"] == "ack" {
                break;
            }
        }
    }
    // An oversized message closes only this connection.
    let _ = ws.send(Message::Text("x".repeat(100_000).into())).await;
    let mut closed = false;
    for _ in 0..100 {
        match ws_next(&mut ws).await {
            None => {
                closed = true;
                break;
            }
            Some(_) => continue,
        }
    }
    assert!(closed);
    // Too many errors close the session with a close frame.
    let mut ws = ws_connect(s.addr, "").await;
    ws_next(&mut ws).await;
    let mut n = 0;
    loop {
        if ws.send(Message::Text("garbage".into())).await.is_err() {
            break;
        }
        match ws_next(&mut ws).await {
            Some(_) => n += 1,
            None => break,
        }
        assert!(n < 100, "never closed");
    }
    assert_eq!(http_get(s.addr, "/api/scene").await.0, 200);
    s.stop().await.unwrap();
}

#[tokio::test]
async fn graceful_shutdown_closes_walk_sessions() {
    let (_scene, s) = near_server(ServerConfig::default()).await;
    let mut ws = ws_connect(s.addr, "").await;
    ws_next(&mut ws).await;
    let addr = s.addr;
    let stop = tokio::spawn(s.stop());
    // The session gets a close frame, the server returns.
    let mut closed = false;
    for _ in 0..50 {
        if ws_next(&mut ws).await.is_none() {
            closed = true;
            break;
        }
    }
    assert!(closed);
    tokio::time::timeout(std::time::Duration::from_secs(10), stop)
        .await
        .expect("shut down in time")
        .unwrap()
        .unwrap();
    assert!(tokio::net::TcpStream::connect(addr).await.is_err());
}

/// The on-line source with a real method from `sightline_methods`.
#[tokio::test]
async fn online_source_with_a_method() {
    let scene = Arc::new(block_city(3));
    let method = sightline_methods::create("all", scene.clone(), &Default::default()).unwrap();
    let grid = CellGrid::cover(&scene.bounds, 100.0).unwrap();
    let s = TestServer::start(
        scene.clone(),
        Arc::new(OnlineSource::new(method, grid)),
        ServerConfig::default(),
    )
    .await;
    let (st, _, body) = http_get(s.addr, "/api/pvs?at=5,5,1.7").await;
    assert_eq!(st, 200);
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(v["method"], "all");
    assert_eq!(v["visible"].as_array().unwrap().len(), scene.objects.len());
    s.stop().await.unwrap();
}
