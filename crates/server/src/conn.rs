//! Connections: the accept loop, the connection cap and the timeouts that keep the
//! server alive under bursts and hostile clients.
//!
//! `axum::serve` accepts every connection and waits for its headers forever (hyper's
//! header timeout needs a timer that `axum::serve` does not install): a few thousand
//! half-open or slow clients take every file descriptor, and the server stops answering.
//! Here:
//!
//! * at most [`ServerConfig::max_connections`] connections are open at once; one more is
//!   answered `503` with a JSON error and closed (back-pressure the client can read,
//!   instead of a reset or a hang);
//! * a client must send a request's headers within [`ServerConfig::header_read_timeout`]
//!   (slowloris, half-open and idle keep-alive connections are closed);
//! * the process's open-file limit is raised to its hard limit at start (many systems
//!   start programs at 1,024, fewer than a burst of 2,000 clients needs), and the cap is
//!   kept below it;
//! * an accept error (out of descriptors despite all this) waits a moment and goes on;
//!   it never ends the server.
//!
//! Requests are then admitted by [`crate::limits::Admission`] (bounded in-flight and
//! queued requests, `503` beyond) before they reach a handler.

use crate::ServerConfig;
use axum::extract::ConnectInfo;
use axum::Router;
use hyper::body::Incoming;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use std::future::Future;
use std::sync::Arc;
use std::time::Duration;
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{watch, Semaphore};
use tower::ServiceExt;

/// What a connection over the cap gets before it is closed.
const BUSY: &[u8] = b"HTTP/1.1 503 Service Unavailable\r\ncontent-type: application/json\r\n\
retry-after: 1\r\nconnection: close\r\ncontent-length: 61\r\n\r\n\
{\"error\":\"server over capacity: too many connections, retry\"}";

/// File descriptors kept free for everything that is not a client connection (the
/// scene and `.pvs` files, the worker pool, logs).
const RESERVED_FDS: u64 = 64;

/// Raise the soft open-file limit to the hard limit; returns the limit now in force
/// (`None` where the platform has no such limit).
pub fn raise_fd_limit() -> Option<u64> {
    #[cfg(unix)]
    {
        let (soft, hard) = rlimit::Resource::NOFILE.get().ok()?;
        if soft < hard && rlimit::Resource::NOFILE.set(hard, hard).is_ok() {
            return Some(hard);
        }
        Some(soft)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Pending connections the kernel keeps for the accept loop (Linux caps it at
/// `net.core.somaxconn`, 4,096 by default): a burst of a few thousand simultaneous
/// connects fits, instead of overflowing the 1,024 of `TcpListener::bind` and leaving
/// clients that the server never sees.
pub const LISTEN_BACKLOG: u32 = 8192;

/// Listen on `addr` (`host:port`; port 0 picks one) with [`LISTEN_BACKLOG`].
pub async fn listen(addr: &str) -> std::io::Result<TcpListener> {
    let mut last = None;
    for a in tokio::net::lookup_host(addr).await? {
        let socket = if a.is_ipv4() {
            tokio::net::TcpSocket::new_v4()?
        } else {
            tokio::net::TcpSocket::new_v6()?
        };
        socket.set_reuseaddr(true)?;
        match socket.bind(a).and_then(|()| socket.listen(LISTEN_BACKLOG)) {
            Ok(l) => return Ok(l),
            Err(e) => last = Some(e),
        }
    }
    Err(last.unwrap_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::AddrNotAvailable,
            format!("{addr}: no address"),
        )
    }))
}

/// The connection cap for `config` under an open-file limit of `fd_limit`: what the
/// limit leaves once the reserved descriptors and the walk sessions (whose upgraded
/// connections no longer count against the cap) are set aside.
pub fn connection_cap(config: &ServerConfig, fd_limit: Option<u64>) -> usize {
    match fd_limit {
        Some(l) => {
            let spare = l.saturating_sub(RESERVED_FDS + config.max_sessions as u64);
            config.max_connections.min(spare.max(16) as usize)
        }
        None => config.max_connections,
    }
}

/// Serve `router` on `listener` until `shutdown` resolves; then stop accepting, let
/// every open connection finish its request (walk sessions are told by the server's own
/// shutdown signal) and return once all have closed or `grace` has passed.
pub async fn serve(
    listener: TcpListener,
    router: Router,
    config: &ServerConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
    grace: Duration,
) -> std::io::Result<()> {
    let cap = connection_cap(config, raise_fd_limit());
    let slots = Arc::new(Semaphore::new(cap));
    let header_timeout = config.header_read_timeout;
    // Dropped to tell the connections to shut down gracefully.
    let (stop_tx, stop_rx) = watch::channel(());
    let mut shutdown = std::pin::pin!(shutdown);
    loop {
        let (stream, addr) = tokio::select! {
            _ = &mut shutdown => break,
            r = listener.accept() => match r {
                Ok(c) => c,
                Err(e) => {
                    if !is_connection_error(&e) {
                        // Out of descriptors (EMFILE/ENFILE) or another transient error:
                        // let connections close, then accept again.
                        tokio::time::sleep(Duration::from_millis(50)).await;
                    }
                    continue;
                }
            },
        };
        let _ = stream.set_nodelay(true);
        let Ok(slot) = slots.clone().try_acquire_owned() else {
            tokio::spawn(refuse(stream));
            continue;
        };
        let router = router.clone();
        let mut stop_rx = stop_rx.clone();
        tokio::spawn(async move {
            let _slot = slot;
            let service = TowerToHyperService::new(router.map_request(
                move |mut req: axum::http::Request<Incoming>| {
                    req.extensions_mut().insert(ConnectInfo(addr));
                    req.map(axum::body::Body::new)
                },
            ));
            // HTTP/1.1 only: browsers speak HTTP/2 only over TLS, which a proxy in front
            // terminates; and a version sniffer would wait for a first byte forever.
            let mut builder = http1::Builder::new();
            builder
                .timer(TokioTimer::new())
                .header_read_timeout(header_timeout)
                .max_buf_size(64 * 1024);
            let conn = builder
                .serve_connection(TokioIo::new(stream), service)
                .with_upgrades();
            let mut conn = std::pin::pin!(conn);
            tokio::select! {
                _ = conn.as_mut() => return,
                _ = stop_rx.changed() => {}
            }
            conn.as_mut().graceful_shutdown();
            let _ = conn.await;
        });
    }
    drop(listener);
    drop(stop_tx);
    // Wait for the connections to give their slots back.
    let all = u32::try_from(cap).unwrap_or(u32::MAX);
    let _ = tokio::time::timeout(grace, slots.acquire_many(all)).await;
    Ok(())
}

/// Tell a connection over the cap why it is closed (best effort, bounded in time).
async fn refuse(mut stream: TcpStream) {
    let _ = tokio::time::timeout(Duration::from_secs(1), async {
        stream.write_all(BUSY).await?;
        stream.shutdown().await
    })
    .await;
}

fn is_connection_error(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::ConnectionRefused
            | std::io::ErrorKind::ConnectionAborted
            | std::io::ErrorKind::ConnectionReset
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn busy_response_is_well_formed() {
        let text = std::str::from_utf8(BUSY).unwrap();
        let (head, body) = text.split_once("\r\n\r\n").unwrap();
        let len: usize = head
            .lines()
            .find_map(|l| l.strip_prefix("content-length: "))
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(body.len(), len);
        let v: serde_json::Value = serde_json::from_str(body).unwrap();
        assert!(v["error"].as_str().unwrap().contains("over capacity"));
    }

    #[test]
    fn cap_stays_below_the_descriptor_limit() {
        let c = ServerConfig::default();
        assert_eq!(connection_cap(&c, None), c.max_connections);
        let spare = 20_000 - RESERVED_FDS as usize - c.max_sessions;
        assert_eq!(
            connection_cap(&c, Some(20_000)),
            spare.min(c.max_connections)
        );
        assert_eq!(connection_cap(&c, Some(10)), 16);
        assert_eq!(connection_cap(&c, Some(1 << 20)), c.max_connections);
    }
}
