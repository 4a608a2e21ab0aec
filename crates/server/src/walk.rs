//! WebSocket walk sessions (`/api/walk`) with PVS prefetch.
//!
//! The protocol of the dual ray space paper's remote walkthrough (§6, Fig. 5):
//! * when the walk begins, the server sends the PVS of the client's cell and of the
//!   **eight adjacent cells** (on a free cell set, the cells whose boxes touch its box:
//!   [`crate::layout`]);
//! * each time the client enters a new cell, the server starts on the adjacent cells it
//!   has not sent yet — those **ahead along the motion first** (at most five for a move
//!   to a side or corner neighbour: the three behind were already sent), and, at driving
//!   speed, the cell two steps ahead — so that the PVS of the next cell is in the client's
//!   hands before it gets there;
//! * beyond Fig. 5, on every position report the cell the client's direction of motion
//!   leads into ([`crate::source::PvsSource::next_cell`]) is requested at
//!   [`Priority::Ahead`], ahead of every other prefetch, and on a cell change the requests
//!   for cells no longer adjacent are withdrawn (the cache skips jobs nobody waits for), so
//!   that at driving speed the workers spend their time on the cell the client reaches next;
//! * each cell's PVS travels as a **delta** (added / removed ids) against the PVS the
//!   client is displaying, and the geometry of objects the client has never received
//!   goes along in binary `SLG1` frames ([`crate::geometry`]), sent *before* the message
//!   that refers to them.
//!
//! Messages are JSON text frames with a `type`; see `docs/api.md` for the full list.
//! A malformed message gets an `error` frame and is otherwise ignored; only a client that
//! keeps sending them (more than [`crate::ServerConfig::max_session_errors`]) is
//! disconnected. Messages are rate-limited per session.

use crate::cache::{CacheError, Priority, Pvs};
use crate::grid::CellId;
use crate::limits::{json_error, TokenBucket};
use crate::AppState;
use axum::extract::ws::{CloseFrame, Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::Response;
use serde::Deserialize;
use serde_json::json;
use sightline_geom::{DVec2, DVec3};
use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::mpsc;

/// Objects per binary geometry frame.
const GEOMETRY_CHUNK: usize = 2048;

/// Speed above which the cell two steps ahead is prefetched too, in cells per second
/// × this factor: at 100 m cells, above 5 m/s (18 km/h).
const FAST_CELLS_PER_S: f64 = 0.05;

/// A message from the client.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ClientMsg {
    /// Session options. `geometry: false`: do not push geometry (the client fetches
    /// `/api/objects` itself).
    Hello {
        #[serde(default = "yes")]
        geometry: bool,
    },
    /// The viewer's position in scene coordinates; `seq` asks for an `ack`.
    Pos {
        x: f64,
        y: f64,
        z: f64,
        #[serde(default)]
        seq: Option<u64>,
    },
}

fn yes() -> bool {
    true
}

/// `GET /api/walk`: upgrade to a walk session.
pub async fn upgrade(State(s): State<Arc<AppState>>, ws: WebSocketUpgrade) -> Response {
    let n = s.counters.sessions.fetch_add(1, Ordering::SeqCst);
    if n >= s.config.max_sessions {
        s.counters.sessions.fetch_sub(1, Ordering::SeqCst);
        return json_error(StatusCode::SERVICE_UNAVAILABLE, "too many walk sessions");
    }
    s.counters.sessions_total.fetch_add(1, Ordering::Relaxed);
    let max = s.config.ws_max_message_bytes;
    ws.max_message_size(max)
        .max_frame_size(max)
        .on_failed_upgrade({
            let s = s.clone();
            move |_| {
                s.counters.sessions.fetch_sub(1, Ordering::SeqCst);
            }
        })
        .on_upgrade(move |socket| async move {
            let st = s.clone();
            let (session, rx) = Session::new(st);
            session.run(socket, rx).await;
            s.counters.sessions.fetch_sub(1, Ordering::SeqCst);
        })
}

/// Dense set of object ids.
struct BitSet(Vec<u64>);
impl BitSet {
    fn new(n: usize) -> Self {
        BitSet(vec![0; n.div_ceil(64)])
    }
    fn insert(&mut self, i: u32) -> bool {
        let (w, b) = ((i / 64) as usize, i % 64);
        let Some(word) = self.0.get_mut(w) else {
            return false;
        };
        let new = *word & (1 << b) == 0;
        *word |= 1 << b;
        new
    }
}

/// `a \ b` for sorted slices.
pub fn difference(a: &[u32], b: &[u32]) -> Vec<u32> {
    let (mut i, mut j, mut out) = (0, 0, Vec::new());
    while i < a.len() {
        if j >= b.len() || a[i] < b[j] {
            out.push(a[i]);
            i += 1;
        } else if a[i] > b[j] {
            j += 1;
        } else {
            i += 1;
            j += 1;
        }
    }
    out
}

type Done = (CellId, Result<Pvs, CacheError>);

struct Session {
    s: Arc<AppState>,
    push_geometry: bool,
    geometry_held: BitSet,
    /// Cells whose PVS the client holds, oldest first.
    held: HashMap<CellId, Pvs>,
    held_order: VecDeque<CellId>,
    /// Cells requested from the cache and not answered yet, with the tasks waiting for them
    /// (aborted to withdraw the request).
    pending: HashMap<CellId, (Priority, Vec<tokio::task::AbortHandle>)>,
    /// The cell the client is heading into, as last requested at [`Priority::Ahead`].
    heading_into: Option<CellId>,
    current: Option<CellId>,
    /// The cell whose PVS the client displays (deltas are against it).
    display: Option<CellId>,
    last: Option<(DVec3, Instant)>,
    heading: DVec2,
    speed_m_s: f64,
    bucket: TokenBucket,
    errors: u32,
    tx: mpsc::UnboundedSender<Done>,
}

enum Flow {
    Continue,
    Close(u16, &'static str),
}

impl Session {
    fn new(s: Arc<AppState>) -> (Self, mpsc::UnboundedReceiver<Done>) {
        let (tx, rx) = mpsc::unbounded_channel();
        let n = s.scene.objects.len();
        let bucket = TokenBucket::new(s.config.ws_rate_per_s, s.config.ws_burst);
        let session = Session {
            s,
            push_geometry: true,
            geometry_held: BitSet::new(n),
            held: HashMap::new(),
            held_order: VecDeque::new(),
            pending: HashMap::new(),
            heading_into: None,
            current: None,
            display: None,
            last: None,
            heading: DVec2::ZERO,
            speed_m_s: 0.0,
            bucket,
            errors: 0,
            tx,
        };
        (session, rx)
    }

    async fn send(&self, ws: &mut WebSocket, m: Message) -> bool {
        let len = match &m {
            Message::Text(t) => t.as_str().len(),
            Message::Binary(b) => b.len(),
            _ => 0,
        };
        self.s
            .counters
            .bytes_sent
            .fetch_add(len as u64, Ordering::Relaxed);
        ws.send(m).await.is_ok()
    }

    async fn send_json(&self, ws: &mut WebSocket, v: serde_json::Value) -> bool {
        self.send(ws, Message::Text(Utf8Bytes::from(v.to_string())))
            .await
    }

    async fn run(mut self, mut ws: WebSocket, mut rx: mpsc::UnboundedReceiver<Done>) {
        let mut shutdown = self.s.shutdown_signal();
        let src = self.s.source().clone();
        let info = src.info();
        let welcome = json!({
            "type": "welcome",
            "objects": self.s.scene.objects.len(),
            "origin": [self.s.origin.x, self.s.origin.y, self.s.origin.z],
            "grid": src.layout().grid(),
            "layout": src.layout().kind(),
            "cells": src.layout().len(),
            "method": info.method,
            "conservative": info.conservative,
            "source": info.kind,
        });
        if !self.send_json(&mut ws, welcome).await {
            return;
        }
        loop {
            tokio::select! {
                m = ws.recv() => {
                    let Some(Ok(m)) = m else { return };
                    match self.on_message(&mut ws, m).await {
                        Ok(Flow::Continue) => {}
                        Ok(Flow::Close(code, why)) => {
                            let _ = ws.send(Message::Close(Some(CloseFrame {
                                code,
                                reason: Utf8Bytes::from_static(why),
                            }))).await;
                            return;
                        }
                        Err(()) => return,
                    }
                }
                Some((cell, result)) = rx.recv() => {
                    if self.on_done(&mut ws, cell, result).await.is_err() {
                        return;
                    }
                }
                _ = shutdown.changed() => {
                    let _ = ws.send(Message::Close(Some(CloseFrame {
                        code: 1001,
                        reason: Utf8Bytes::from_static("server shutting down"),
                    }))).await;
                    return;
                }
            }
        }
    }

    /// Count a client error; send it; close when there were too many.
    async fn client_error(&mut self, ws: &mut WebSocket, msg: String) -> Result<Flow, ()> {
        self.client_error_seq(ws, msg, None).await
    }

    /// [`Session::client_error`] about the position message `seq`, if it has one.
    async fn client_error_seq(
        &mut self,
        ws: &mut WebSocket,
        msg: String,
        seq: Option<u64>,
    ) -> Result<Flow, ()> {
        self.errors += 1;
        self.s.counters.ws_errors.fetch_add(1, Ordering::Relaxed);
        let mut m = json!({"type": "error", "error": msg});
        if let Some(seq) = seq {
            m["seq"] = json!(seq);
        }
        if !self.send_json(ws, m).await {
            return Err(());
        }
        if self.errors > self.s.config.max_session_errors {
            return Ok(Flow::Close(1008, "too many malformed messages"));
        }
        Ok(Flow::Continue)
    }

    async fn on_message(&mut self, ws: &mut WebSocket, m: Message) -> Result<Flow, ()> {
        let text = match m {
            Message::Text(t) => t,
            Message::Binary(_) => {
                return self
                    .client_error(ws, "binary messages are not accepted".into())
                    .await
            }
            Message::Close(_) => return Err(()),
            Message::Ping(_) | Message::Pong(_) => return Ok(Flow::Continue),
        };
        self.s.counters.ws_messages.fetch_add(1, Ordering::Relaxed);
        if !self.bucket.try_take() {
            return self
                .client_error(ws, "rate limit exceeded: message dropped".into())
                .await;
        }
        let msg: ClientMsg = match serde_json::from_str(text.as_str()) {
            Ok(m) => m,
            Err(e) => return self.client_error(ws, format!("bad message: {e}")).await,
        };
        match msg {
            ClientMsg::Hello { geometry } => {
                self.push_geometry = geometry;
                Ok(Flow::Continue)
            }
            ClientMsg::Pos { x, y, z, seq } => self.on_pos(ws, DVec3::new(x, y, z), seq).await,
        }
    }

    async fn on_pos(&mut self, ws: &mut WebSocket, p: DVec3, seq: Option<u64>) -> Result<Flow, ()> {
        let src = self.s.source().clone();
        let cell = match src.locate(p) {
            Ok(c) => c,
            // The `seq` tells the client which position had no cell (it steps back).
            Err(e) => return self.client_error_seq(ws, e.to_string(), seq).await,
        };
        let now = Instant::now();
        if let Some((q, t)) = self.last {
            let d = (p - q).truncate();
            let dt = now.duration_since(t).as_secs_f64();
            if d.length() > 1e-6 {
                self.heading = d;
                if dt > 1e-3 {
                    // Smoothed: positions arrive at the client's pace, with jitter.
                    self.speed_m_s = 0.7 * self.speed_m_s + 0.3 * d.length() / dt;
                }
            }
        }
        self.last = Some((p, now));
        if self.current != Some(cell) {
            let first = self.current.is_none();
            self.current = Some(cell);
            if !first {
                self.s.counters.cell_changes.fetch_add(1, Ordering::Relaxed);
                if self.held.contains_key(&cell) {
                    self.s
                        .counters
                        .prefetch_hits
                        .fetch_add(1, Ordering::Relaxed);
                }
            }
            if self.held.contains_key(&cell) {
                self.display = Some(cell);
            } else if let Some(v) = self.s.cache.peek(cell) {
                // Computed for someone else already: answer at once.
                self.withdraw(cell);
                if !self.send_cell(ws, cell, v).await {
                    return Err(());
                }
            } else {
                self.request(cell, Priority::Demand);
            }
            // Fig. 5: the adjacent cells, those ahead first; at speed, two steps ahead.
            let mut next = src.neighbours(cell, self.heading);
            let fast = self.speed_m_s > FAST_CELLS_PER_S * src.layout().scale_m();
            if fast {
                if let Some(a) = src.ahead(cell, self.heading, 2) {
                    next.insert(1.min(next.len()), a);
                }
            }
            // Withdraw what is no longer adjacent: stale work for the workers.
            let stale: Vec<CellId> = self
                .pending
                .keys()
                .copied()
                .filter(|c| *c != cell && !next.contains(c))
                .collect();
            for c in stale {
                self.withdraw(c);
            }
            self.heading_into = None;
            for n in next {
                if !self.held.contains_key(&n) {
                    self.request(n, Priority::Prefetch);
                }
            }
            self.forget_old(ws).await?;
        }
        // The cell the motion leads into goes before the other prefetches.
        let into = src.next_cell(p, self.heading);
        if into != self.heading_into {
            self.heading_into = into;
            if let Some(n) = into {
                if !self.held.contains_key(&n) {
                    self.request(n, Priority::Ahead);
                }
            }
        }
        if let Some(seq) = seq {
            let ack = json!({
                "type": "ack",
                "seq": seq,
                "cell": cell,
                "held": self.held.contains_key(&cell),
            });
            if !self.send_json(ws, ack).await {
                return Err(());
            }
        }
        Ok(Flow::Continue)
    }

    /// Ask the cache for a cell; the answer arrives on `self.rx`.
    /// A better priority than a pending request's asks again (the cache promotes the job).
    fn request(&mut self, cell: CellId, prio: Priority) {
        match self.pending.get(&cell) {
            Some((p, _)) if *p <= prio => return,
            _ => {}
        }
        let cache = self.s.cache.clone();
        let tx = self.tx.clone();
        let task = tokio::spawn(async move {
            let r = cache.get(cell, prio).await;
            let _ = tx.send((cell, r));
        });
        let e = self.pending.entry(cell).or_insert((prio, vec![]));
        e.0 = prio;
        e.1.push(task.abort_handle());
    }

    /// Withdraw the requests for a cell (if the cache has not started on it, and nobody
    /// else asked, it is not computed).
    fn withdraw(&mut self, cell: CellId) {
        if let Some((_, tasks)) = self.pending.remove(&cell) {
            for t in tasks {
                t.abort();
            }
        }
    }

    async fn on_done(
        &mut self,
        ws: &mut WebSocket,
        cell: CellId,
        result: Result<Pvs, CacheError>,
    ) -> Result<(), ()> {
        let was = self.pending.remove(&cell);
        if self.held.contains_key(&cell) {
            return Ok(()); // a duplicate (promoted request)
        }
        match result {
            Ok(v) => {
                if !self.send_cell(ws, cell, v).await {
                    return Err(());
                }
                self.forget_old(ws).await
            }
            // A refused prefetch is requested again, as a demand, if the client gets there.
            Err(CacheError::Busy) => Ok(()),
            Err(e) => {
                if was.is_some() && self.current == Some(cell) {
                    let m = json!({"type": "error", "cell": cell, "error": e.to_string()});
                    if !self.send_json(ws, m).await {
                        return Err(());
                    }
                }
                Ok(())
            }
        }
    }

    /// Send one cell's PVS: geometry of new objects first, then the delta.
    async fn send_cell(&mut self, ws: &mut WebSocket, cell: CellId, pvs: Pvs) -> bool {
        let src = self.s.source().clone();
        let Some(bx) = src.cell(cell) else {
            return true;
        };
        if self.push_geometry {
            let fresh: Vec<u32> = pvs
                .iter()
                .copied()
                .filter(|&i| self.geometry_held.insert(i))
                .collect();
            for chunk in fresh.chunks(GEOMETRY_CHUNK) {
                let bytes = self.s.geometry.encode(chunk);
                if !self.send(ws, Message::Binary(bytes.into())).await {
                    return false;
                }
            }
        }
        let base = self.display.and_then(|d| self.held.get(&d).map(|v| (d, v)));
        let (base_id, added, removed) = match base {
            Some((d, b)) => (Some(d), difference(&pvs, b), difference(b, &pvs)),
            None => (None, pvs.to_vec(), vec![]),
        };
        let current = self.current == Some(cell);
        let m = json!({
            "type": "cell",
            "cell": cell,
            "box": bx,
            "base": base_id,
            "added": added,
            "removed": removed,
            "size": pvs.len(),
            "current": current,
        });
        if !self.send_json(ws, m).await {
            return false;
        }
        self.held.insert(cell, pvs);
        self.held_order.push_back(cell);
        if current {
            self.display = Some(cell);
        }
        true
    }

    /// Keep at most `max_held_cells` on the client: forget the oldest that are neither the
    /// displayed cell nor adjacent to the current one.
    async fn forget_old(&mut self, ws: &mut WebSocket) -> Result<(), ()> {
        let max = self.s.config.max_held_cells.max(10);
        if self.held.len() <= max {
            return Ok(());
        }
        let keep: Vec<CellId> = match self.current {
            Some(c) => {
                let mut k = self.s.source().neighbours(c, DVec2::ZERO);
                k.push(c);
                k
            }
            None => vec![],
        };
        let mut forgotten = vec![];
        let mut rest = VecDeque::new();
        while let Some(c) = self.held_order.pop_front() {
            if self.held.len() > max
                && Some(c) != self.display
                && !keep.contains(&c)
                && self.held.remove(&c).is_some()
            {
                forgotten.push(c);
            } else if self.held.contains_key(&c) {
                rest.push_back(c);
            }
        }
        self.held_order = rest;
        if forgotten.is_empty() {
            return Ok(());
        }
        let m = json!({"type": "forget", "cells": forgotten});
        if self.send_json(ws, m).await {
            Ok(())
        } else {
            Err(())
        }
    }
}

impl Drop for Session {
    /// A closed session withdraws everything it still waits for: the workers must not
    /// spend minutes on cells for a client that has gone.
    fn drop(&mut self) {
        for (_, (_, tasks)) in self.pending.drain() {
            for t in tasks {
                t.abort();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorted_difference() {
        assert_eq!(difference(&[1, 2, 5, 7], &[2, 3, 7]), vec![1, 5]);
        assert_eq!(difference(&[], &[1]), Vec::<u32>::new());
        assert_eq!(difference(&[4], &[]), vec![4]);
    }

    #[test]
    fn client_messages_parse_strictly() {
        let m: ClientMsg = serde_json::from_str(r#"{"type":"pos","x":1,"y":2,"z":1.7}"#).unwrap();
        assert!(matches!(m, ClientMsg::Pos { seq: None, .. }));
        assert!(serde_json::from_str::<ClientMsg>(r#"{"type":"pos","x":1}"#).is_err());
        assert!(serde_json::from_str::<ClientMsg>(r#"{"type":"fly"}"#).is_err());
        assert!(
            serde_json::from_str::<ClientMsg>(r#"{"type":"pos","x":1,"y":2,"z":3,"w":4}"#).is_err()
        );
        let h: ClientMsg = serde_json::from_str(r#"{"type":"hello"}"#).unwrap();
        assert!(matches!(h, ClientMsg::Hello { geometry: true }));
    }
}
