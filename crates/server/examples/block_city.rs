//! Serve a synthetic block city (no scene file, no importer needed): a quick way to try the
//! viewer and to run the browser test against a known scene.
//!
//! ```text
//! cargo run -p sightline-server --example block_city -- [--blocks 12] [--method erosion] [--cell-size 100] [--addr 127.0.0.1:8080]
//! ```
//! Prints the same `… on http://ADDR/` line as `sightline serve`.

use sightline_geom::{DVec2, Polygon};
use sightline_scene::{Object, Scene};
use sightline_server::grid::CellGrid;
use sightline_server::source::OnlineSource;
use sightline_server::{Server, ServerConfig};
use std::io::Write;
use std::sync::Arc;

fn main() {
    let mut blocks = 12usize;
    let mut method = "erosion".to_string();
    let mut cell = 100.0;
    let mut addr = "127.0.0.1:8080".to_string();
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let v = it.next().unwrap_or_default();
        match k.as_str() {
            "--blocks" => blocks = v.parse().unwrap_or(blocks),
            "--method" => method = v,
            "--cell-size" => cell = v.parse().unwrap_or(cell),
            "--addr" => addr = v,
            _ => {
                eprintln!("error: unknown argument {k}");
                std::process::exit(2);
            }
        }
    }
    // Blocks of 30 × 30 m on a 50 m pitch, 8–44 m tall, streets 20 m wide.
    let mut objects = vec![];
    for j in 0..blocks {
        for i in 0..blocks {
            let (x, y) = (i as f64 * 50.0 + 10.0, j as f64 * 50.0 + 10.0);
            let h = 8.0 + ((i * 7 + j * 13) % 10) as f64 * 4.0;
            objects.push(Object::block(
                Some(format!("b{i}_{j}")),
                Polygon::rect(DVec2::new(x, y), DVec2::new(x + 30.0, y + 30.0)),
                0.0,
                h,
            ));
        }
    }
    let scene = Arc::new(Scene::from_objects(objects));
    let m = match sightline_methods::create(&method, scene.clone(), &Default::default()) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: cannot prepare method '{method}': {e}");
            std::process::exit(1);
        }
    };
    let grid = match CellGrid::cover(&scene.bounds, cell) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let rt = match tokio::runtime::Runtime::new() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let result = rt.block_on(async move {
        let listener = tokio::net::TcpListener::bind(&addr).await?;
        let server = Server::new(
            scene.clone(),
            Arc::new(OnlineSource::new(m, grid)),
            ServerConfig::default(),
        );
        println!(
            "block_city: serving {} objects, method {method} on http://{}/",
            scene.len(),
            listener.local_addr()?
        );
        std::io::stdout().flush().ok();
        server
            .run(listener, async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await
    });
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
