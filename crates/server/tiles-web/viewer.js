// The PVS-driven 3D Tiles viewer of `sightline serve --tiles` (source of
// ../web/tiles/viewer.bundle.js; rebuild with `npm ci && npm run build` here).
//
// 3DTilesRendererJS walks the tileset with its usual screen-space-error refinement; the
// plugin below masks every content tile that the tile-level PVS of the camera's cell
// (GET /tiles/pvs?at=X,Y,Z, plus the neighbouring cells' tiles, prefetched) does not
// list, so such tiles are neither downloaded nor drawn. The "plain" switch turns the
// mask off: the same renderer loads the plain tileset for comparison.
import * as THREE from 'three';
import { TilesRenderer } from '3d-tiles-renderer';

const params = new URLSearchParams(location.search);
const token = params.get('token');
const withToken = (url) => (token ? `${url}${url.includes('?') ? '&' : '?'}token=${encodeURIComponent(token)}` : url);

/** Masks content tiles outside `allowed` (a Set of content URIs); `null` masks nothing. */
class PvsMaskPlugin {
  constructor() {
    this.name = 'SIGHTLINE_PVS_MASK';
    this.allowed = null;
    this.requested = new Set();
  }
  calculateTileViewError(tile, target) {
    const uri = tile.content && tile.content.uri;
    if (!this.allowed || !uri || this.allowed.has(uri)) return false; // no-op
    target.inView = false;
    target.error = 0;
    target.distance = Infinity;
    return true;
  }
  preprocessURL(url, tile) {
    if (tile && tile.content && tile.content.uri) this.requested.add(tile.content.uri);
    return withToken(url);
  }
}

const canvas = document.getElementById('view');
const status = document.getElementById('status');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0xbfd4e6);
scene3.add(new THREE.HemisphereLight(0xffffff, 0x667788, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(0.4, -0.6, 1.0);
scene3.add(sun);
// The ground, a little below z = 0 so that flat street polygons stay on top.
const ground = new THREE.Mesh(new THREE.PlaneGeometry(1e5, 1e5), new THREE.MeshLambertMaterial({ color: 0x9aa58c }));
ground.position.z = -0.05;
scene3.add(ground);
const camera = new THREE.PerspectiveCamera(75, 1, 0.5, 5000);
camera.up.set(0, 0, 1);

const mask = new PvsMaskPlugin();
if (params.get('plain') !== '1') mask.allowed = new Set();
const tiles = new TilesRenderer('/tiles/data/tileset.json');
tiles.registerPlugin(mask);
tiles.errorTarget = 16;
// Keep every loaded tile: the test counts what was loaded along the walk.
tiles.lruCache.minSize = 100000;
tiles.lruCache.maxSize = 100000;
tiles.setCamera(camera);
scene3.add(tiles.group);

let plain = params.get('plain') === '1';
let cell = null;
const state = { eye: new THREE.Vector3(0, 0, 1.7), azimuth: 0 };

function resize() {
  const w = canvas.clientWidth || 1280;
  const h = canvas.clientHeight || 720;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  tiles.setResolutionFromRenderer(camera, renderer);
}
window.addEventListener('resize', resize);

function place() {
  camera.position.copy(state.eye);
  const d = new THREE.Vector3(Math.cos(state.azimuth), Math.sin(state.azimuth), 0);
  camera.lookAt(state.eye.clone().add(d));
  camera.updateMatrixWorld();
}

function frame() {
  place();
  tiles.update();
  renderer.render(scene3, camera);
}

function loadedUris() {
  const out = [];
  tiles.forEachLoadedModel((model, tile) => { if (tile.content && tile.content.uri) out.push(tile.content.uri); });
  return out.sort();
}

/** Render until nothing is queued, downloading or parsing for a few frames. */
async function settle() {
  let quiet = 0;
  // Loading needs only updates; a software renderer would spend most of the time
  // drawing, so the scene is drawn once, at the end.
  for (let i = 0; i < 2000 && quiet < 5; i++) {
    place();
    tiles.update();
    await new Promise((r) => setTimeout(r, 10));
    const s = tiles.stats;
    const busy = (s.queued || 0) + (s.downloading || 0) + (s.parsing || 0);
    quiet = busy === 0 ? quiet + 1 : 0;
  }
  frame();
}

async function fetchCell(p) {
  const r = await fetch(withToken(`/tiles/pvs?at=${p.x},${p.y},${p.z}`));
  if (!r.ok) throw new Error(`/tiles/pvs: HTTP ${r.status} ${await r.text()}`);
  return r.json();
}

function applyMask() {
  // Before the first cell is known the PVS mode loads nothing.
  mask.allowed = plain ? null : new Set(cell ? [...cell.tiles, ...cell.neighbours] : []);
  status.textContent = plain
    ? `plain tileset · loaded ${loadedUris().length} tiles`
    : `cell ${cell ? cell.cell : '-'} · PVS ${cell ? cell.tiles.length : 0} tiles (+${cell ? cell.neighbours.length : 0} prefetched) · loaded ${loadedUris().length}`;
}

/** Stand at (x, y) looking along `azimuthRad`; resolves once the tiles are loaded. */
async function lookFrom(x, y, azimuthRad) {
  state.eye.set(x, y, 1.7);
  state.azimuth = azimuthRad;
  if (!plain) {
    try {
      cell = await fetchCell(state.eye);
    } catch (e) {
      cell = null;
      throw e;
    }
  }
  applyMask();
  const before = new Set(mask.requested);
  await settle();
  applyMask();
  const requestedNow = [...mask.requested].filter((u) => !before.has(u)).sort();
  return { cell: cell && cell.cell, tiles: cell ? cell.tiles : null, neighbours: cell ? cell.neighbours : null, loaded: loadedUris(), requested: requestedNow };
}

document.getElementById('plain').checked = plain;
document.getElementById('plain').addEventListener('change', async (e) => {
  plain = e.target.checked;
  await lookFrom(state.eye.x, state.eye.y, state.azimuth);
});

// Keyboard walking: W/S forward/back, A/D turn.
window.addEventListener('keydown', (e) => {
  const step = e.shiftKey ? 10 : 2;
  const d = new THREE.Vector3(Math.cos(state.azimuth), Math.sin(state.azimuth), 0);
  if (e.key === 'w') state.eye.addScaledVector(d, step);
  if (e.key === 's') state.eye.addScaledVector(d, -step);
  if (e.key === 'a') state.azimuth += 0.1;
  if (e.key === 'd') state.azimuth -= 0.1;
  if ('wsad'.includes(e.key) && e.key.length === 1) lookFrom(state.eye.x, state.eye.y, state.azimuth).catch((err) => { status.textContent = String(err); });
});

let initial = null;
const ready = new Promise((resolve) => {
  tiles.addEventListener('load-root-tileset', () => resolve(), { once: true });
}).then(() => {
  const sphere = new THREE.Sphere();
  tiles.getBoundingSphere(sphere);
  state.eye.set(sphere.center.x, sphere.center.y, 1.7);
  frame();
  // Stand in the middle; a tileset without a tile PVS (or a point outside its cells)
  // says so instead of loading anything.
  initial = lookFrom(state.eye.x, state.eye.y, state.azimuth).catch((err) => { status.textContent = String(err); return null; });
  return initial;
});

// Render on demand (a software-rendered headless browser cannot afford a continuous
// loop): when the renderer reports new tiles, and once now for the first update, which
// starts loading the root tileset.
resize();
let pending = false;
function requestFrame() {
  if (pending) return;
  pending = true;
  requestAnimationFrame(() => { pending = false; frame(); });
}
tiles.addEventListener('needs-update', requestFrame);
tiles.addEventListener('load-model', requestFrame);
window.addEventListener('resize', requestFrame);
requestFrame();

window.sightlineTiles = {
  /** Resolves (with the first lookFrom's result) once the tileset and the first cell are loaded. */
  ready,
  lookFrom,
  setPlain(v) { plain = !!v; document.getElementById('plain').checked = plain; applyMask(); },
  loaded: loadedUris,
  requested: () => [...mask.requested].sort(),
};
