//! Access token, rate limits and admission.
//!
//! * `--token T`: every `/api` request must carry `T`, as `?token=T` (browsers cannot set
//!   headers on a WebSocket) or `Authorization: Bearer T`. Compared in constant time.
//! * HTTP requests are rate-limited per client address by a token bucket; WebSocket
//!   messages per session by another (see [`crate::walk`]). Over the limit a request gets
//!   `429` with a JSON error, a message gets an error frame. Loopback addresses are not
//!   limited unless [`crate::ServerConfig::rate_limit_loopback`] is set: behind a reverse
//!   proxy on the same host every client comes from 127.0.0.1, and one bucket for all
//!   of them would turn a crowd into errors.
//! * [`Admission`]: at most `max_inflight` requests are handled at once and at most
//!   `max_queued` wait for a turn, each for at most `queue_timeout`; beyond that a request
//!   gets `503` with a JSON error and `retry-after` at once. This bounds the memory and
//!   the work of a burst, whatever its size, and lets every admitted request finish.

use crate::AppState;
use axum::extract::{ConnectInfo, Request, State};
use axum::http::{header, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

/// A token bucket: `rate` tokens per second up to `burst`.
#[derive(Clone, Debug)]
pub struct TokenBucket {
    rate: f64,
    burst: f64,
    tokens: f64,
    last: Instant,
}

impl TokenBucket {
    pub fn new(rate: f64, burst: f64) -> Self {
        TokenBucket {
            rate,
            burst,
            tokens: burst,
            last: Instant::now(),
        }
    }

    /// Take one token if there is one.
    pub fn try_take(&mut self) -> bool {
        let now = Instant::now();
        let dt = now.duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.rate).min(self.burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

/// Per-address token buckets.
pub struct RateLimiter {
    rate: f64,
    burst: f64,
    buckets: Mutex<HashMap<IpAddr, TokenBucket>>,
}

/// Addresses tracked before idle buckets are pruned.
const MAX_TRACKED: usize = 10_000;

impl RateLimiter {
    pub fn new(rate: f64, burst: f64) -> Self {
        RateLimiter {
            rate,
            burst,
            buckets: Mutex::new(HashMap::new()),
        }
    }

    pub fn allow(&self, ip: IpAddr) -> bool {
        let mut m = self.buckets.lock().unwrap_or_else(|p| p.into_inner());
        if m.len() >= MAX_TRACKED && !m.contains_key(&ip) {
            // Forget buckets that have refilled: they carry no information.
            let now = Instant::now();
            let (rate, burst) = (self.rate, self.burst);
            m.retain(|_, b| b.tokens + now.duration_since(b.last).as_secs_f64() * rate < burst);
        }
        m.entry(ip)
            .or_insert_with(|| TokenBucket::new(self.rate, self.burst))
            .try_take()
    }
}

/// Bounded in-flight and queued requests (see the module doc).
pub struct Admission {
    inflight: Arc<Semaphore>,
    waiting: AtomicUsize,
    max_queued: usize,
    queue_timeout: Duration,
}

/// Why a request was not admitted.
#[derive(Debug, PartialEq, Eq)]
pub enum Refusal {
    /// Every in-flight slot is taken and the queue is full.
    QueueFull,
    /// No slot came free within the queue timeout.
    Timeout,
}

impl Admission {
    pub fn new(max_inflight: usize, max_queued: usize, queue_timeout: Duration) -> Self {
        Admission {
            inflight: Arc::new(Semaphore::new(max_inflight.max(1))),
            waiting: AtomicUsize::new(0),
            max_queued,
            queue_timeout,
        }
    }

    /// A slot to handle one request, held until the permit is dropped.
    pub async fn admit(&self) -> Result<OwnedSemaphorePermit, Refusal> {
        if let Ok(p) = self.inflight.clone().try_acquire_owned() {
            return Ok(p);
        }
        if self.waiting.fetch_add(1, Ordering::AcqRel) >= self.max_queued {
            self.waiting.fetch_sub(1, Ordering::AcqRel);
            return Err(Refusal::QueueFull);
        }
        let r =
            tokio::time::timeout(self.queue_timeout, self.inflight.clone().acquire_owned()).await;
        self.waiting.fetch_sub(1, Ordering::AcqRel);
        match r {
            Ok(Ok(p)) => Ok(p),
            _ => Err(Refusal::Timeout),
        }
    }

    /// Requests waiting for a slot now.
    pub fn queued(&self) -> usize {
        self.waiting.load(Ordering::Relaxed)
    }
}

/// `503` with a JSON error and `retry-after: 1`.
pub fn over_capacity(msg: impl Into<String>) -> Response {
    let mut r = json_error(StatusCode::SERVICE_UNAVAILABLE, msg);
    r.headers_mut()
        .insert(header::RETRY_AFTER, header::HeaderValue::from_static("1"));
    r
}

/// A JSON error response `{"error": "..."}`.
pub fn json_error(status: StatusCode, msg: impl Into<String>) -> Response {
    (
        status,
        axum::Json(serde_json::json!({ "error": msg.into() })),
    )
        .into_response()
}

/// Constant-time equality (the time does not tell how much of a guess was right).
pub fn same_secret(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// The token a request carries, if any.
fn request_token(req: &Request) -> Option<String> {
    if let Some(h) = req.headers().get(header::AUTHORIZATION) {
        if let Some(t) = h.to_str().ok().and_then(|s| s.strip_prefix("Bearer ")) {
            return Some(t.trim().to_string());
        }
    }
    let q = req.uri().query()?;
    q.split('&')
        .find_map(|kv| kv.strip_prefix("token="))
        .map(percent_decode)
}

/// Minimal `%XX` / `+` decoding for query values.
pub fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < b.len() => {
                let hex = std::str::from_utf8(&b[i + 1..i + 3])
                    .ok()
                    .and_then(|h| u8::from_str_radix(h, 16).ok());
                match hex {
                    Some(v) => {
                        out.push(v);
                        i += 2;
                    }
                    None => out.push(b'%'),
                }
            }
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Middleware of `/api`: rate limit by address, then the token, then admission.
pub async fn guard(
    State(state): State<Arc<AppState>>,
    ConnectInfo(addr): ConnectInfo<SocketAddr>,
    req: Request,
    next: Next,
) -> Response {
    let limited = state.config.rate_limit_loopback || !addr.ip().is_loopback();
    if limited && !state.limiter.allow(addr.ip()) {
        state.counters.http_limited.fetch_add(1, Ordering::Relaxed);
        return json_error(StatusCode::TOO_MANY_REQUESTS, "rate limit exceeded");
    }
    if let Some(expected) = &state.config.token {
        let ok = request_token(&req)
            .map(|t| same_secret(t.as_bytes(), expected.as_bytes()))
            .unwrap_or(false);
        if !ok {
            return json_error(
                StatusCode::UNAUTHORIZED,
                "missing or wrong token (use ?token= or Authorization: Bearer)",
            );
        }
    }
    let _slot = match state.admission.admit().await {
        Ok(p) => p,
        Err(why) => {
            state.counters.http_refused.fetch_add(1, Ordering::Relaxed);
            return over_capacity(match why {
                Refusal::QueueFull => "server over capacity: request queue full, retry",
                Refusal::Timeout => "server over capacity: no slot within the queue timeout, retry",
            });
        }
    };
    next.run(req).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bucket_allows_the_burst_then_refuses() {
        let mut b = TokenBucket::new(0.0, 3.0);
        assert!(b.try_take() && b.try_take() && b.try_take());
        assert!(!b.try_take());
    }

    #[test]
    fn limiter_is_per_address() {
        let l = RateLimiter::new(0.0, 1.0);
        let a: IpAddr = "127.0.0.1".parse().unwrap();
        let b: IpAddr = "127.0.0.2".parse().unwrap();
        assert!(l.allow(a));
        assert!(!l.allow(a));
        assert!(l.allow(b));
    }

    #[tokio::test]
    async fn admission_bounds_inflight_and_queue() {
        let a = Arc::new(Admission::new(2, 1, Duration::from_millis(50)));
        let p1 = a.admit().await.unwrap();
        let _p2 = a.admit().await.unwrap();
        // The third waits in the queue; a fourth finds the queue full.
        let waiter = {
            let a = a.clone();
            tokio::spawn(async move { a.admit().await.map(drop) })
        };
        while a.queued() == 0 {
            tokio::task::yield_now().await;
        }
        assert_eq!(a.admit().await.err(), Some(Refusal::QueueFull));
        drop(p1);
        assert_eq!(waiter.await.unwrap(), Ok(()));
        // Nothing frees a slot now: a waiter times out.
        let _p3 = a.admit().await.unwrap();
        assert_eq!(a.admit().await.err(), Some(Refusal::Timeout));
        assert_eq!(a.queued(), 0);
    }

    #[test]
    fn secrets_and_decoding() {
        assert!(same_secret(b"abc", b"abc"));
        assert!(!same_secret(b"abc", b"abd"));
        assert!(!same_secret(b"abc", b"ab"));
        assert_eq!(percent_decode("a%20b+c%2"), "a b c%2");
        assert_eq!(percent_decode("%zz"), "%zz");
    }
}
