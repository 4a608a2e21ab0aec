// sightline walkthrough viewer: a thin client of the remote-walkthrough scenario
// (dual ray space paper, §1 and §6). It knows nothing of the city beforehand; the server
// sends the PVS of the viewcell it stands in and of the cells around it (as deltas), and
// the geometry of each object once. Protocol: docs/api.md.
//
// Two kinds of scene (`/api/scene`'s `kind`): a city, walked at eye height above the
// ground z = 0 on a regular grid of cells the page locates itself; and a level (a BSP or
// mesh level), whose cells are free shapes the server locates (the `ack` of each position
// names the cell), walked on its floors: the eye stands `eye_height` above the highest
// surface below it (a ray cast down against the geometry the page holds), and a move
// into a wall (a ray cast along the move) is refused.
import * as THREE from 'three';

const WALK_SPEED = 1.5; // m/s, at an eye height of 1.7 m (speeds scale with the eye)
const DRIVE_SPEED = 14; // m/s (50 km/h)
const EYE = 1.7; // m, a city's default (the server says: `eye_height`)
const POS_INTERVAL_MS = 100;
const HIDDEN_LIMIT = 4000;

const params = new URLSearchParams(location.search);
const token = params.get('token');

function apiUrl(path, query = {}) {
  const q = new URLSearchParams(query);
  if (token) q.set('token', token);
  const s = q.toString();
  return `/api/${path}${s ? '?' + s : ''}`;
}

async function getJson(path, query) {
  const r = await fetch(apiUrl(path, query));
  const body = await r.json();
  if (!r.ok) throw new Error(body.error || `HTTP ${r.status}`);
  return body;
}

// ---- SLG1 geometry (crates/server/src/geometry.rs) ----
function decodeGeometry(buf) {
  const dv = new DataView(buf);
  const magic = String.fromCharCode(dv.getUint8(0), dv.getUint8(1), dv.getUint8(2), dv.getUint8(3));
  if (magic !== 'SLG1') throw new Error('not SLG1 geometry');
  const count = dv.getUint32(4, true);
  let at = 8;
  const out = [];
  for (let k = 0; k < count; k++) {
    const id = dv.getUint32(at, true);
    const kind = dv.getUint32(at + 4, true);
    const nv = dv.getUint32(at + 8, true);
    const ni = dv.getUint32(at + 12, true);
    at += 16;
    const positions = new Float32Array(buf, at, nv * 3);
    at += nv * 12;
    const indices = new Uint32Array(buf, at, ni);
    at += ni * 4;
    out.push({ id, kind, positions, indices });
  }
  return out;
}

// ---- state ----
const S = {
  scene: null, // /api/scene
  grid: null,
  level: false, // a level: cells located by the server, floors followed
  eye: EYE, // eye height above the ground or floor (scene units)
  scale: 100, // a typical cell width (scene units)
  cellBoxes: new Map(), // cell id -> [x0,y0,z0,x1,y1,z1] (levels, from `cell` messages)
  seq: 0, // last position sequence number sent (levels)
  acked: 0, // last position sequence number acknowledged
  lastGood: null, // last position the server located in a cell (levels)
  origin: null,
  ws: null,
  open: false,
  geometry: new Map(), // id -> BufferGeometry
  kinds: new Map(), // id -> kind
  meshes: new Map(), // id -> Mesh (PVS objects)
  hiddenMeshes: new Map(), // id -> Mesh (red)
  cells: new Map(), // cell id -> Set of object ids (full PVS)
  displayCell: null,
  displaySet: new Set(),
  currentCell: null,
  entered: false,
  cellChangeAt: 0,
  waiting: false,
  pos: new THREE.Vector3(), // local (relative to origin)
  yaw: 0,
  pitch: -0.05,
  showHidden: false,
  boxes: null, // Float32Array, 6 per object
  stats: {
    objectsReceived: 0, bytesReceived: 0, cellChanges: 0, prefetchHits: 0,
    lastInHandMs: null, worstInHandMs: 0, errors: 0, lastError: null, outside: 0,
  },
  sentAt: new Map(), // seq -> position sent (levels)
  lastSent: 0,
  lastSentPos: null,
  waiters: [],
};

// ---- three.js scene ----
const canvas = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0xaac8e8);
scene3.fog = new THREE.Fog(0xaac8e8, 400, 2500);
const camera = new THREE.PerspectiveCamera(70, 1, 0.3, 6000);
camera.up.set(0, 0, 1);
scene3.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.4);
sun.position.set(0.4, -0.6, 1);
scene3.add(sun);
const pvsGroup = new THREE.Group();
const hiddenGroup = new THREE.Group();
scene3.add(pvsGroup, hiddenGroup);
const matBlocks = new THREE.MeshLambertMaterial({ color: 0xd8d2c4, flatShading: true });
const matFlat = new THREE.MeshLambertMaterial({ color: 0x8a8f96, polygonOffset: true, polygonOffsetFactor: -1, polygonOffsetUnits: -4 });
const matMesh = new THREE.MeshLambertMaterial({ color: 0x7fae6a, flatShading: true, side: THREE.DoubleSide });
const matHidden = new THREE.MeshBasicMaterial({ color: 0xd9453b, transparent: true, opacity: 0.55, depthWrite: false });
let ground = null;
let cellOutline = null;

function resize() {
  const w = window.innerWidth, h = window.innerHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

// A level's faces: stone, both sides (a BSP face is one-sided, seen from its front).
const matLevel = new THREE.MeshLambertMaterial({ color: 0xb8aa94, flatShading: true, side: THREE.DoubleSide });

function materialFor(kind) {
  if (S.level) return matLevel;
  return kind === 1 ? matFlat : kind === 2 ? matMesh : matBlocks;
}

function addGeometry(buf) {
  const objs = decodeGeometry(buf);
  for (const o of objs) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(o.positions, 3));
    g.setIndex(new THREE.BufferAttribute(o.indices, 1));
    g.computeVertexNormals();
    g.computeBoundingSphere();
    S.geometry.set(o.id, g);
    S.kinds.set(o.id, o.kind);
  }
  S.stats.objectsReceived += objs.length;
  S.stats.bytesReceived += buf.byteLength;
}

// ---- cells ----
function cellOf(local) {
  if (S.level) return S.currentCell; // the server locates (see onAck)
  const g = S.grid;
  const wx = local.x + S.origin[0], wy = local.y + S.origin[1];
  const maxX = g.origin[0] + g.nx * g.cell_size_m, maxY = g.origin[1] + g.ny * g.cell_size_m;
  if (wx < g.origin[0] || wy < g.origin[1] || wx > maxX || wy > maxY) return null;
  const ix = Math.min(g.nx - 1, Math.floor((wx - g.origin[0]) / g.cell_size_m));
  const iy = Math.min(g.ny - 1, Math.floor((wy - g.origin[1]) / g.cell_size_m));
  return iy * g.nx + ix;
}

function cellRect(cell) {
  // local coordinates
  if (S.level) {
    const b = S.cellBoxes.get(cell) || [0, 0, 0, 0, 0, 0];
    return [b[0] - S.origin[0], b[1] - S.origin[1], b[3] - S.origin[0], b[4] - S.origin[1]];
  }
  const g = S.grid;
  const ix = cell % g.nx, iy = Math.floor(cell / g.nx);
  const x0 = g.origin[0] + ix * g.cell_size_m - S.origin[0];
  const y0 = g.origin[1] + iy * g.cell_size_m - S.origin[1];
  return [x0, y0, x0 + g.cell_size_m, y0 + g.cell_size_m];
}

function display(cell) {
  const set = S.cells.get(cell);
  if (!set) return;
  S.displayCell = cell;
  S.displaySet = set;
  for (const [id, m] of S.meshes) {
    if (!set.has(id)) { pvsGroup.remove(m); S.meshes.delete(id); }
  }
  for (const id of set) {
    if (S.meshes.has(id)) continue;
    const g = S.geometry.get(id);
    if (!g) continue; // not received yet: drawn when it arrives (see onBinary)
    const m = new THREE.Mesh(g, materialFor(S.kinds.get(id)));
    m.userData.id = id;
    S.meshes.set(id, m);
    pvsGroup.add(m);
  }
  // The viewcell, outlined like the papers' figures (a tall wireframe box).
  if (cellOutline) { scene3.remove(cellOutline); cellOutline.geometry.dispose(); }
  const [x0, y0, x1, y1] = cellRect(cell);
  let z0 = 0, z1 = Math.max(S.grid ? S.grid.z_range_m[1] : 0, 30);
  if (S.level) {
    const b = S.cellBoxes.get(cell) || [0, 0, 0, 0, 0, 0];
    z0 = b[2] - S.origin[2]; z1 = b[5] - S.origin[2];
  }
  const box = new THREE.BoxGeometry(x1 - x0, y1 - y0, z1 - z0);
  cellOutline = new THREE.LineSegments(new THREE.EdgesGeometry(box), new THREE.LineBasicMaterial({ color: 0x2ecc71 }));
  box.dispose();
  cellOutline.position.set((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2);
  scene3.add(cellOutline);
  if (S.showHidden) refreshHidden();
  // A level's start may be in mid-air (a cell's centre): stand on the first floor seen.
  if (S.level && !S.onFloor) S.onFloor = standOnFloor();
  wakeWaiters();
}

function enterCell(cell) {
  const first = !S.entered;
  S.currentCell = cell;
  if (cell === null) return;
  S.entered = true;
  if (!first) S.stats.cellChanges += 1;
  S.cellChangeAt = performance.now();
  if (S.cells.has(cell)) {
    if (!first) S.stats.prefetchHits += 1;
    S.stats.lastInHandMs = 0;
    S.waiting = false;
    display(cell);
  } else {
    S.waiting = true;
  }
  sendPos(true);
}

function onCellMessage(m) {
  let set;
  if (m.base !== null && m.base !== undefined) {
    const base = S.cells.get(m.base);
    if (!base) { noteError(`cell ${m.cell}: base ${m.base} not held`); return; }
    set = new Set(base);
  } else {
    set = new Set();
  }
  for (const id of m.added) set.add(id);
  for (const id of m.removed) set.delete(id);
  if (set.size !== m.size) noteError(`cell ${m.cell}: size ${set.size} != ${m.size}`);
  S.cells.set(m.cell, set);
  if (m.box) S.cellBoxes.set(m.cell, m.box);
  if (m.cell === S.currentCell && S.displayCell !== m.cell) {
    if (S.waiting) {
      const dt = performance.now() - S.cellChangeAt;
      S.stats.lastInHandMs = dt;
      S.stats.worstInHandMs = Math.max(S.stats.worstInHandMs, dt);
      S.waiting = false;
    }
    display(m.cell);
  }
}

function noteError(e) {
  S.stats.errors += 1;
  S.stats.lastError = String(e);
  console.warn('sightline:', e);
}

// ---- hidden objects in red (debug view, like the papers' figures) ----
let hiddenToken = 0;
async function refreshHidden() {
  const my = ++hiddenToken;
  for (const m of S.hiddenMeshes.values()) hiddenGroup.remove(m);
  S.hiddenMeshes.clear();
  if (!S.showHidden || S.displayCell === null || !S.boxes) return;
  // Hidden objects near the viewer: within two cells.
  const r = S.scale * 2;
  const want = [];
  const n = S.boxes.length / 6;
  for (let id = 0; id < n && want.length < HIDDEN_LIMIT; id++) {
    if (S.displaySet.has(id)) continue;
    const b = id * 6;
    const cx = (S.boxes[b] + S.boxes[b + 3]) / 2, cy = (S.boxes[b + 1] + S.boxes[b + 4]) / 2;
    if (Math.abs(cx - S.pos.x) < r && Math.abs(cy - S.pos.y) < r) want.push(id);
  }
  const missing = want.filter((id) => !S.geometry.has(id));
  for (let i = 0; i < missing.length; i += 2000) {
    const r2 = await fetch(apiUrl('objects', { ids: missing.slice(i, i + 2000).join(',') }));
    if (!r2.ok) { noteError(`objects: HTTP ${r2.status}`); return; }
    addGeometry(await r2.arrayBuffer());
  }
  if (my !== hiddenToken || !S.showHidden) return;
  for (const id of want) {
    if (S.displaySet.has(id)) continue;
    const g = S.geometry.get(id);
    if (!g) continue;
    const m = new THREE.Mesh(g, matHidden);
    S.hiddenMeshes.set(id, m);
    hiddenGroup.add(m);
  }
}

function setShowHidden(on) {
  S.showHidden = !!on;
  document.getElementById('hidden-toggle').checked = S.showHidden;
  return refreshHidden();
}
document.getElementById('hidden-toggle').addEventListener('change', (e) => setShowHidden(e.target.checked));

// ---- network ----
function sendPos(force) {
  if (!S.open) return;
  const now = performance.now();
  const moved = !S.lastSentPos || S.lastSentPos.distanceToSquared(S.pos) > 1e-6;
  if (!force && (!moved || now - S.lastSent < POS_INTERVAL_MS)) return;
  S.lastSent = now;
  S.lastSentPos = S.pos.clone();
  const m = { type: 'pos', x: S.pos.x + S.origin[0], y: S.pos.y + S.origin[1], z: S.pos.z + S.origin[2] };
  // In a level the server locates the eye: every position asks for an `ack` naming its cell.
  if (S.level) { m.seq = ++S.seq; S.sentAt.set(m.seq, S.pos.clone()); }
  S.ws.send(JSON.stringify(m));
}

// A level's position was located: its cell is the current cell.
function onAck(m) {
  const at = S.sentAt.get(m.seq);
  for (const k of S.sentAt.keys()) if (k <= m.seq) S.sentAt.delete(k);
  S.acked = Math.max(S.acked, m.seq);
  if (at) S.lastGood = at;
  if (m.cell !== S.currentCell) enterCell(m.cell);
}

// A level's position was in no cell (inside a wall, outside the level): step back to
// the last position that was.
function onOutside(m) {
  S.sentAt.delete(m.seq);
  S.acked = Math.max(S.acked, m.seq);
  S.stats.outside += 1;
  if (S.lastGood) { S.pos.copy(S.lastGood); S.lastSentPos = null; }
}

function connect() {
  return new Promise((resolve, reject) => {
    const proto = location.protocol === 'https:' ? 'wss' : 'ws';
    const q = token ? `?token=${encodeURIComponent(token)}` : '';
    const ws = new WebSocket(`${proto}://${location.host}/api/walk${q}`);
    ws.binaryType = 'arraybuffer';
    S.ws = ws;
    ws.onopen = () => {
      S.open = true;
      ws.send(JSON.stringify({ type: 'hello', geometry: true }));
      setStatus('connected');
      resolve();
    };
    ws.onerror = () => reject(new Error('WebSocket failed'));
    ws.onclose = (e) => { S.open = false; setStatus(`disconnected (${e.code} ${e.reason || ''})`, true); };
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') {
        try { addGeometry(e.data); } catch (err) { noteError(err); }
        for (const id of S.displaySet) if (!S.meshes.has(id) && S.geometry.has(id)) display(S.displayCell);
        return;
      }
      S.stats.bytesReceived += e.data.length;
      const m = JSON.parse(e.data);
      if (m.type === 'cell') onCellMessage(m);
      else if (m.type === 'ack') { if (S.level) onAck(m); }
      else if (m.type === 'forget') for (const c of m.cells) S.cells.delete(c);
      else if (m.type === 'error' && S.level && m.seq !== undefined && m.seq !== null) onOutside(m);
      else if (m.type === 'error') noteError(m.error);
      wakeWaiters();
    };
  });
}

function setStatus(t, err) {
  const el = document.getElementById('status');
  el.textContent = t;
  el.className = err ? 'err' : '';
}

// ---- input ----
const keys = new Set();
window.addEventListener('keydown', (e) => {
  keys.add(e.code);
  if (e.code === 'KeyH') setShowHidden(!S.showHidden);
});
window.addEventListener('keyup', (e) => keys.delete(e.code));
window.addEventListener('blur', () => keys.clear());
canvas.addEventListener('click', () => { if (canvas.requestPointerLock) canvas.requestPointerLock(); });
document.addEventListener('mousemove', (e) => {
  if (document.pointerLockElement !== canvas) return;
  S.yaw -= e.movementX * 0.0025;
  S.pitch = Math.max(-1.4, Math.min(1.4, S.pitch - e.movementY * 0.0025));
});

// ---- floors and walls (levels) ----
const ray = new THREE.Raycaster();
const DOWN = new THREE.Vector3(0, 0, -1);
// The eye may climb a step this high (Quake: 18 units of 46) in one move.
const STEP_UP = 0.45;
// Walls are kept this far from the eye (Quake: a player is 32 units wide).
const RADIUS = 0.35;

/** The highest surface below `p` (local, at most a step above the feet), or null. */
function floorBelow(p) {
  if (pvsGroup.children.length === 0) return null;
  const from = new THREE.Vector3(p.x, p.y, p.z - S.eye + STEP_UP * S.eye);
  ray.set(from, DOWN);
  ray.far = 200 * S.eye;
  const hit = ray.intersectObjects(pvsGroup.children, false)[0];
  return hit ? hit.point.z : null;
}

/** Whether a wall stands within `len` (plus the radius) of `p` along `dir` (unit, xy). */
function blocked(p, dir, len) {
  if (pvsGroup.children.length === 0) return false;
  // Above a climbable step, below the eye.
  const from = new THREE.Vector3(p.x, p.y, p.z - S.eye + 1.5 * STEP_UP * S.eye);
  ray.set(from, new THREE.Vector3(dir.x, dir.y, 0));
  ray.far = len + RADIUS * S.eye;
  return ray.intersectObjects(pvsGroup.children, false).length > 0;
}

/** Put the eye `eye` above the floor below it, if there is one. */
function standOnFloor() {
  const f = floorBelow(S.pos);
  if (f !== null) S.pos.z = f + S.eye;
  return f !== null;
}

function step(dt) {
  const k = S.eye / EYE; // speeds are given at a person's eye height in metres
  const speed = k * (keys.has('ShiftLeft') || keys.has('ShiftRight') ? DRIVE_SPEED : WALK_SPEED);
  if (keys.has('ArrowLeft')) S.yaw += dt * 1.2;
  if (keys.has('ArrowRight')) S.yaw -= dt * 1.2;
  const f = new THREE.Vector2(Math.cos(S.yaw), Math.sin(S.yaw));
  const r = new THREE.Vector2(Math.sin(S.yaw), -Math.cos(S.yaw));
  const v = new THREE.Vector2();
  if (keys.has('KeyW') || keys.has('ArrowUp')) v.add(f);
  if (keys.has('KeyS') || keys.has('ArrowDown')) v.sub(f);
  if (keys.has('KeyD')) v.add(r);
  if (keys.has('KeyA')) v.sub(r);
  if (v.lengthSq() > 0) {
    v.normalize().multiplyScalar(speed * dt);
    const next = S.pos.clone();
    next.x += v.x; next.y += v.y;
    if (S.level) {
      const len = v.length();
      if (blocked(S.pos, v.clone().divideScalar(len), len)) return;
      const f = floorBelow(next);
      if (f === null && pvsGroup.children.length > 0) return; // no floor: not a place to stand
      if (f !== null) next.z = f + S.eye;
      S.pos.copy(next);
    } else if (cellOf(next) !== null) S.pos.copy(next);
  }
}

function updateCamera() {
  camera.position.copy(S.pos);
  const d = new THREE.Vector3(Math.cos(S.yaw) * Math.cos(S.pitch), Math.sin(S.yaw) * Math.cos(S.pitch), Math.sin(S.pitch));
  camera.lookAt(S.pos.clone().add(d));
}

// ---- mini-map ----
const mapCanvas = document.getElementById('minimap');
const mapCtx = mapCanvas.getContext('2d');
function drawMap() {
  if (!S.scene || !S.boxes) return;
  const W = mapCanvas.width, H = mapCanvas.height;
  const span = S.scale * 3.2; // metres (scene units) across
  const k = W / span;
  const tx = (x) => W / 2 + (x - S.pos.x) * k;
  const ty = (y) => H / 2 - (y - S.pos.y) * k;
  mapCtx.fillStyle = '#20252b';
  mapCtx.fillRect(0, 0, W, H);
  const n = S.boxes.length / 6;
  const half = span / 2 + S.scale / 2;
  // In a level, a plan at the walker's height: what crosses the band from the feet to the
  // eye (walls), not the floors below nor the ceilings above.
  const feet = S.pos.z - S.eye;
  for (let id = 0; id < n; id++) {
    const b = id * 6;
    if (S.level && (S.boxes[b + 5] < feet + 0.25 * S.eye || S.boxes[b + 2] > S.pos.z)) continue;
    if (S.boxes[b + 3] < S.pos.x - half || S.boxes[b] > S.pos.x + half || S.boxes[b + 4] < S.pos.y - half || S.boxes[b + 1] > S.pos.y + half) continue;
    const x0 = tx(S.boxes[b]), y0 = ty(S.boxes[b + 4]);
    const w = Math.max(1, (S.boxes[b + 3] - S.boxes[b]) * k), h = Math.max(1, (S.boxes[b + 4] - S.boxes[b + 1]) * k);
    if (S.level) {
      // A level's faces overlap in plan: outlines.
      mapCtx.strokeStyle = S.displaySet.has(id) ? '#4f8cff' : '#d9453b';
      mapCtx.strokeRect(x0, y0, w, h);
    } else {
      mapCtx.fillStyle = S.displaySet.has(id) ? '#4f8cff' : '#d9453b';
      mapCtx.fillRect(x0, y0, w, h);
    }
  }
  // Held cells dashed, the current viewcell in green.
  mapCtx.setLineDash([3, 3]);
  mapCtx.strokeStyle = '#8aa';
  for (const c of S.cells.keys()) {
    const [x0, y0, x1, y1] = cellRect(c);
    mapCtx.strokeRect(tx(x0), ty(y1), (x1 - x0) * k, (y1 - y0) * k);
  }
  mapCtx.setLineDash([]);
  if (S.currentCell !== null) {
    const [x0, y0, x1, y1] = cellRect(S.currentCell);
    mapCtx.strokeStyle = '#2ecc71';
    mapCtx.lineWidth = 2;
    mapCtx.strokeRect(tx(x0), ty(y1), (x1 - x0) * k, (y1 - y0) * k);
    mapCtx.lineWidth = 1;
  }
  mapCtx.fillStyle = '#fff';
  mapCtx.beginPath();
  mapCtx.arc(W / 2, H / 2, 4, 0, Math.PI * 2);
  mapCtx.fill();
  mapCtx.strokeStyle = '#fff';
  mapCtx.beginPath();
  mapCtx.moveTo(W / 2, H / 2);
  mapCtx.lineTo(W / 2 + Math.cos(S.yaw) * 14, H / 2 - Math.sin(S.yaw) * 14);
  mapCtx.stroke();
}

// ---- stats ----
function fmtBytes(b) {
  return b > 1 << 20 ? (b / (1 << 20)).toFixed(1) + ' MiB' : b > 1024 ? (b / 1024).toFixed(1) + ' KiB' : b + ' B';
}
function setText(id, t) { document.getElementById(id).textContent = t; }
function drawStats() {
  const st = S.stats;
  setText('s-method', S.scene ? `${S.scene.method}${S.scene.conservative ? '' : ' (NOT conservative)'} · ${S.scene.source}` : '–');
  setText('s-pos', `${(S.pos.x + S.origin[0]).toFixed(1)}, ${(S.pos.y + S.origin[1]).toFixed(1)}`);
  setText('s-cell', S.currentCell === null ? 'outside' : `${S.currentCell}${S.waiting ? ' (waiting)' : ''}`);
  setText('s-pvs', `${S.displaySet.size} / ${S.scene ? S.scene.objects : '–'}`);
  setText('s-drawn', String(S.meshes.size));
  setText('s-objs', String(st.objectsReceived));
  setText('s-bytes', fmtBytes(st.bytesReceived));
  setText('s-held', String(S.cells.size));
  setText('s-changes', String(st.cellChanges));
  setText('s-hits', st.cellChanges ? `${st.prefetchHits} (${(100 * st.prefetchHits / st.cellChanges).toFixed(0)} %)` : '–');
  setText('s-lat', st.lastInHandMs === null ? '–' : `${st.lastInHandMs.toFixed(0)} ms`);
  setText('s-worst', `${st.worstInHandMs.toFixed(0)} ms`);
  if (st.lastError) setStatus(`${S.open ? 'connected' : 'disconnected'} · ${st.errors} error(s): ${st.lastError}`, true);
}

// ---- main loop ----
let lastT = performance.now();
let frame = 0;
function loop(t) {
  const dt = Math.min(0.1, (t - lastT) / 1000);
  lastT = t;
  if (S.scene && S.origin) {
    step(dt);
    const c = cellOf(S.pos);
    if (c !== S.currentCell) enterCell(c);
    sendPos(false);
    updateCamera();
    renderer.render(scene3, camera);
    if (frame % 6 === 0) { drawMap(); drawStats(); }
  }
  frame++;
  requestAnimationFrame(loop);
}

// ---- test hooks (crates/server/e2e) ----
function wakeWaiters() {
  const still = [];
  for (const w of S.waiters) (w.test() ? w.resolve() : still.push(w));
  S.waiters = still;
}
function until(test, timeoutMs = 30000) {
  if (test()) return Promise.resolve();
  return new Promise((resolve, reject) => {
    const w = { test, resolve };
    S.waiters.push(w);
    setTimeout(() => { S.waiters = S.waiters.filter((x) => x !== w); reject(new Error('timeout')); }, timeoutMs);
  });
}
function drawnIds() { return [...S.meshes.keys()].filter((id) => S.meshes.get(id).parent === pvsGroup).sort((a, b) => a - b); }
function inHand() {
  return S.currentCell !== null && S.displayCell === S.currentCell && [...S.displaySet].every((id) => S.meshes.has(id));
}

window.sightline = {
  ready: null,
  /** Move to world (x, y) at eye height (in a level: to (x, y, z), or on the floor below
   * the current eye height when z is not given); resolves once the new cell's PVS is drawn. */
  async walkTo(x, y, z) {
    if (S.level) {
      S.pos.set(x - S.origin[0], y - S.origin[1], z === undefined ? S.pos.z : z - S.origin[2]);
      if (z === undefined) standOnFloor();
      sendPos(true);
      const mine = S.seq;
      await until(() => S.acked >= mine && inHand());
    } else {
      S.pos.set(x - S.origin[0], y - S.origin[1], S.eye);
      const c = cellOf(S.pos);
      if (c !== S.currentCell) enterCell(c);
      sendPos(true);
      await until(inHand);
    }
    updateCamera();
    renderer.render(scene3, camera);
    return { cell: S.currentCell, drawn: drawnIds() };
  },
  look(yawDeg, pitchDeg = -3) { S.yaw = (yawDeg * Math.PI) / 180; S.pitch = (pitchDeg * Math.PI) / 180; updateCamera(); renderer.render(scene3, camera); },
  drawnIds,
  pvsIds: () => [...S.displaySet].sort((a, b) => a - b),
  hiddenIds: () => [...S.hiddenMeshes.keys()].sort((a, b) => a - b),
  setShowHidden,
  position: () => [S.pos.x + S.origin[0], S.pos.y + S.origin[1], S.pos.z + S.origin[2]],
  /** The floor below the eye (world z), from the geometry held; null if none. */
  floor: () => { const f = floorBelow(S.pos); return f === null ? null : f + S.origin[2]; },
  eyeHeight: () => S.eye,
  cell: () => S.currentCell,
  stats: () => ({ ...S.stats, pvsSize: S.displaySet.size, drawn: S.meshes.size, cellsHeld: S.cells.size }),
  render: () => { drawMap(); drawStats(); renderer.render(scene3, camera); },
};

// A free starting point: the scene centre, or the nearest point not inside a building.
function startPoint() {
  const at = (params.get('at') || '').split(',').map(Number);
  if (at.length >= 2 && at.every(Number.isFinite)) return [at[0] - S.origin[0], at[1] - S.origin[1]];
  const g = S.grid;
  const cx = g.nx * g.cell_size_m / 2, cy = g.ny * g.cell_size_m / 2;
  const inside = (x, y) => {
    for (let b = 0; b < S.boxes.length; b += 6) {
      if (S.boxes[b + 5] > 0.5 && x >= S.boxes[b] && x <= S.boxes[b + 3] && y >= S.boxes[b + 1] && y <= S.boxes[b + 4]) return true;
    }
    return false;
  };
  for (let r = 0; r < g.cell_size_m * 2; r += 3) {
    for (let a = 0; a < 16; a++) {
      const x = cx + r * Math.cos((a * Math.PI) / 8), y = cy + r * Math.sin((a * Math.PI) / 8);
      if (!inside(x, y)) return [x, y];
      if (r === 0) break;
    }
  }
  return [cx, cy];
}

async function main() {
  const scene = await getJson('scene');
  S.grid = scene.grid;
  S.origin = scene.origin;
  S.level = scene.kind === 'level';
  S.eye = scene.eye_height || EYE;
  S.scale = scene.cell_scale || (S.grid ? S.grid.cell_size_m : 100);
  const rb = await fetch(apiUrl('boxes'));
  if (!rb.ok) throw new Error(`boxes: HTTP ${rb.status}`);
  const bb = await rb.arrayBuffer();
  S.boxes = new Float32Array(bb, 8, new DataView(bb).getUint32(4, true) * 6);
  if (S.level) {
    // Indoors: no ground, no sky; near and far planes at the level's scale.
    const k = S.eye / EYE;
    camera.near = 0.1 * k;
    camera.far = 6000 * k;
    camera.updateProjectionMatrix();
    scene3.fog = null;
    scene3.background = new THREE.Color(0x1c2026);
    const b = scene.bounds;
    const st = scene.start || [(b[0] + b[3]) / 2, (b[1] + b[4]) / 2, (b[2] + b[5]) / 2];
    S.pos.set(st[0] - S.origin[0], st[1] - S.origin[1], st[2] - S.origin[2]);
    S.lastGood = S.pos.clone();
    S.scene = scene;
    await connect();
    sendPos(true);
    requestAnimationFrame(loop);
    return;
  }
  S.scene = scene;
  const [w, h] = [S.grid.nx * S.grid.cell_size_m, S.grid.ny * S.grid.cell_size_m];
  ground = new THREE.Mesh(new THREE.PlaneGeometry(w + 2000, h + 2000), new THREE.MeshLambertMaterial({ color: 0x55604f }));
  ground.position.set(w / 2, h / 2, -0.05);
  scene3.add(ground);
  const [sx, sy] = startPoint();
  S.pos.set(sx, sy, S.eye);
  await connect();
  requestAnimationFrame(loop);
}

window.sightline.ready = main().catch((e) => { setStatus(`error: ${e.message}`, true); throw e; });
