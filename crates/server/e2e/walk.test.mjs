// End-to-end test of the walkthrough viewer in real headless Chromium (Debian `chromium`,
// driven by playwright-core). It starts `sightline serve`, opens the viewer, walks a
// scripted path across several viewcells and checks at every step that the objects the
// page draws are exactly the server's PVS for that cell (`/api/pvs`), so no potentially
// visible object is missing and no hidden one is drawn. Screenshots go to e2e/out/.
//
// Environment:
//   SIGHTLINE_BIN   the binary (default: <repo>/target/debug/sightline)
//   E2E_SCENE       scene file (default: <repo>/data/lyon1_bdtopo.geojson; '' skips the city)
//   E2E_METHOD      on-line method (default: dual-ray, the fastest conservative one)
//   E2E_CELL_SIZE   viewcell size in metres (default: 100)
//   E2E_LEVEL       a level walked after the city (default: <repo>/data/quake/dm1.bsp,
//                   served with its PVS built in memory by portals-fast; '' skips it)
//   CHROMIUM        browser executable (default: /usr/bin/chromium)
import { mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import assert from 'node:assert/strict';
import { chromium } from 'playwright-core';
import { startServer } from './serve.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const repo = resolve(here, '../../..');
const bin = process.env.SIGHTLINE_BIN || join(repo, 'target/debug/sightline');
const sceneFile = process.env.E2E_SCENE ?? join(repo, 'data/lyon1_bdtopo.geojson');
const method = process.env.E2E_METHOD || 'dual-ray';
const cellSize = Number(process.env.E2E_CELL_SIZE || 100);
const levelFile = process.env.E2E_LEVEL ?? join(repo, 'data/quake/dm1.bsp');
const outDir = join(here, 'out');
mkdirSync(outDir, { recursive: true });

function log(...a) { console.log('[e2e]', ...a); }

function startWalkServer() {
  const args = ['serve', sceneFile, '--method', method, '--cell-size', String(cellSize), '--addr', '127.0.0.1:0'];
  return startServer(bin, args, { log, timeoutMs: 600_000, echoStderr: true });
}

async function getJson(base, path) {
  const r = await fetch(base + path);
  const body = await r.json();
  assert.ok(r.ok, `${path}: HTTP ${r.status} ${JSON.stringify(body)}`);
  return body;
}

function launchBrowser() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: [
      '--no-sandbox', '--no-first-run', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--disable-quic', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--ignore-gpu-blocklist',
    ],
  });
}

/** Stop a server with SIGTERM; its exit status ('killed' if it would not stop). */
function stopServer(proc) {
  return new Promise((res) => {
    if (proc.exitCode !== null) return res(proc.exitCode);
    proc.on('exit', (c) => res(c));
    proc.kill('SIGTERM');
    setTimeout(() => { proc.kill('SIGKILL'); res('killed'); }, 20_000);
  });
}

/** A headless page on the viewer, ready, with its errors collected. */
async function openViewer(base) {
  const browser = await launchBrowser();
  const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(m.text()); });
  await page.goto(base + '/');
  await page.evaluate(() => window.sightline.ready);
  return { browser, page, pageErrors };
}

async function main() {
  let failed = sceneFile ? await cityWalk() : false;
  if (!failed && levelFile) failed = await levelWalk();
  process.exit(failed ? 1 : 0);
}

async function cityWalk() {
  const { proc, url } = startWalkServer();
  let browser;
  let failed = false;
  try {
    const base = (await url).replace(/\/$/, '');
    log('server at', base);
    const scene = await getJson(base, '/api/scene');
    log(`scene: ${scene.objects} objects, ${scene.cells} cells (${scene.grid.nx}×${scene.grid.ny} of ${scene.grid.cell_size_m} m), method ${scene.method}`);
    assert.equal(scene.method, method);

    const viewer = await openViewer(base);
    browser = viewer.browser;
    const { page, pageErrors } = viewer;
    log('viewer ready');

    // A scripted path: along the middle row of cells, west to east, over up to 5 cells,
    // in 12 m steps (a walker's position updates), then one step north into the next row.
    const g = scene.grid;
    const row = Math.floor(g.ny / 2);
    const y = g.origin[1] + (row + 0.5) * g.cell_size_m;
    const cols = Math.min(g.nx, 5);
    const x0 = g.origin[0] + 0.3 * g.cell_size_m;
    const x1 = g.origin[0] + (cols - 0.3) * g.cell_size_m;
    const path = [];
    for (let x = x0; x <= x1; x += 12) path.push([x, y]);
    if (row + 1 < g.ny) path.push([x1, y + g.cell_size_m]);

    const cells = new Set();
    let best = null; // the step with the largest PVS: the "around" screenshots go there
    let step = 0;
    for (const [x, yy] of path) {
      const r = await page.evaluate(([px, py]) => window.sightline.walkTo(px, py), [x, yy]);
      const truth = await getJson(base, `/api/pvs?at=${x},${yy},1.7`);
      // What the page draws is exactly the server's PVS of the cell it stands in.
      assert.deepEqual(r.drawn, truth.visible, `step ${step} at (${x.toFixed(1)}, ${yy.toFixed(1)}): drawn != PVS`);
      const missing = truth.visible.filter((id) => !r.drawn.includes(id));
      assert.equal(missing.length, 0, `missing objects ${missing.slice(0, 10)}`);
      if (!best || r.drawn.length > best.n) best = { x, y: yy, n: r.drawn.length };
      if (!cells.has(r.cell)) {
        cells.add(r.cell);
        await page.evaluate(([px]) => window.sightline.look(px), [step % 2 ? 60 : 0]);
        await page.evaluate(() => window.sightline.render());
        await page.screenshot({ path: join(outDir, `cell-${String(cells.size).padStart(2, '0')}-${r.cell}.png`) });
        log(`cell ${r.cell}: ${r.drawn.length} objects drawn = PVS (of ${scene.objects})`);
      }
      step++;
    }
    assert.ok(cells.size >= Math.min(3, g.nx), `walked across ${cells.size} cells only`);

    // Hidden objects in red: none of them is drawn as a PVS object.
    await page.evaluate(() => window.sightline.setShowHidden(true));
    const hidden = await page.evaluate(() => window.sightline.hiddenIds());
    const drawn = await page.evaluate(() => window.sightline.drawnIds());
    assert.ok(hidden.every((id) => !drawn.includes(id)), 'a hidden object is also drawn');
    await page.evaluate(() => window.sightline.look(30, -8));
    await page.evaluate(() => window.sightline.render());
    await page.screenshot({ path: join(outDir, 'hidden-red.png') });
    log(`hidden view: ${hidden.length} hidden objects near the viewer in red`);

    // Around the largest PVS of the path, hidden objects shown: 8 headings (docs/img/viewer.png
    // is one of them).
    const rb = await page.evaluate(([px, py]) => window.sightline.walkTo(px, py), [best.x, best.y]);
    const truthB = await getJson(base, `/api/pvs?at=${best.x},${best.y},1.7`);
    assert.deepEqual(rb.drawn, truthB.visible, 'back at the largest PVS: drawn != PVS');
    await page.evaluate(() => window.sightline.setShowHidden(true));
    for (let yaw = 0; yaw < 360; yaw += 45) {
      await page.evaluate(([a]) => window.sightline.look(a, 2), [yaw]);
      await page.evaluate(() => window.sightline.render());
      await page.screenshot({ path: join(outDir, `around-${String(yaw).padStart(3, '0')}.png`) });
    }
    log(`around (${best.x.toFixed(1)}, ${best.y.toFixed(1)}): ${rb.drawn.length} objects drawn, 8 headings`);
    await page.evaluate(() => window.sightline.setShowHidden(false));

    // The keyboard walks: hold W (with Shift: 14 m/s) for a second.
    const before = await page.evaluate(() => window.sightline.position());
    await page.keyboard.down('Shift');
    await page.keyboard.down('KeyW');
    await page.waitForTimeout(1000);
    await page.keyboard.up('KeyW');
    await page.keyboard.up('Shift');
    const after = await page.evaluate(() => window.sightline.position());
    const moved = Math.hypot(after[0] - before[0], after[1] - before[1]);
    assert.ok(moved > 2, `W did not move the viewer (moved ${moved} m)`);
    const r = await page.evaluate(([px, py]) => window.sightline.walkTo(px, py), [after[0], after[1]]);
    const truth = await getJson(base, `/api/pvs?at=${after[0]},${after[1]},1.7`);
    assert.deepEqual(r.drawn, truth.visible, 'after walking with the keyboard');

    const stats = await page.evaluate(() => window.sightline.stats());
    log('viewer stats', JSON.stringify(stats));
    assert.equal(stats.errors, 0, `viewer errors: ${stats.lastError}`);
    assert.deepEqual(pageErrors, [], 'page errors');
    await page.screenshot({ path: join(outDir, 'final.png') });
    log(`OK: ${path.length} steps over ${cells.size} cells, drawn == PVS at every step; ${stats.cellChanges} cell changes, ${stats.prefetchHits} prefetched; screenshots in ${outDir}`);
  } catch (e) {
    failed = true;
    console.error('[e2e] FAILED:', e && e.stack ? e.stack : e);
  } finally {
    if (browser) await browser.close();
    // Graceful shutdown on SIGTERM: the server must exit 0.
    const code = await stopServer(proc);
    if (code !== 0) {
      console.error(`[e2e] FAILED: server exit status ${code} after SIGTERM`);
      failed = true;
    }
  }
  return failed;
}

// A level (dm1): the viewer starts at the level's start, walks to points of open space
// around it (each drawn set must be the server's PVS of the leaf there), then walks with
// the keyboard on the floors, the eye at the level's eye height above them.
async function levelWalk() {
  const { proc, url } = startServer(bin, ['serve', levelFile, '--addr', '127.0.0.1:0'], { log, timeoutMs: 600_000, echoStderr: true });
  let browser;
  let failed = false;
  try {
    const base = (await url).replace(/\/$/, '');
    const scene = await getJson(base, '/api/scene');
    log(`level: ${scene.objects} objects, ${scene.cells} cells (${scene.layout}), method ${scene.method} (${scene.source}), eye ${scene.eye_height}, start ${scene.start}`);
    assert.equal(scene.kind, 'level');
    assert.equal(scene.layout, 'cells');
    assert.ok(Array.isArray(scene.start), 'a start position');
    const viewer = await openViewer(base);
    browser = viewer.browser;
    const { page, pageErrors } = viewer;
    const [sx, sy, sz] = scene.start;
    // Points of open space around the start, 40 units apart along x and y (those the
    // server locates in a cell).
    const path = [[sx, sy, sz]];
    for (const [dx, dy] of [[1, 0], [-1, 0], [0, 1], [0, -1]]) {
      for (let k = 1; k <= 4; k++) {
        const p = [sx + 40 * k * dx, sy + 40 * k * dy, sz];
        const r = await fetch(`${base}/api/pvs?at=${p.join(',')}`);
        if (!r.ok) break; // a wall: the next points of this line are beyond it
        path.push(p);
      }
    }
    const cells = new Set();
    for (const [x, y, z] of path) {
      const r = await page.evaluate(([px, py, pz]) => window.sightline.walkTo(px, py, pz), [x, y, z]);
      const at = await page.evaluate(() => window.sightline.position());
      const truth = await getJson(base, `/api/pvs?at=${at.join(',')}`);
      assert.equal(r.cell, truth.cell_id, `at (${at}): the page's cell`);
      assert.deepEqual(r.drawn, truth.visible, `at (${at}): drawn != PVS`);
      if (!cells.has(r.cell)) {
        cells.add(r.cell);
        await page.evaluate(() => window.sightline.render());
        await page.screenshot({ path: join(outDir, `level-cell-${String(cells.size).padStart(2, '0')}-${r.cell}.png`) });
        log(`level cell ${r.cell}: ${r.drawn.length} faces drawn = PVS (of ${scene.objects})`);
      }
    }
    assert.ok(cells.size >= 3, `walked across ${cells.size} level cells only`);

    // The keyboard walks on the floors: from the start, Shift+W for half a second in four
    // headings (a wall may stop some of them).
    // Back to the start, standing on the floor below it.
    await page.evaluate(([x, y, z]) => window.sightline.walkTo(x, y, z), scene.start);
    await page.evaluate(([x, y]) => window.sightline.walkTo(x, y), scene.start);
    let moved = 0;
    for (const yaw of [0, 90, 180, 270]) {
      await page.evaluate(([a]) => window.sightline.look(a, 0), [yaw]);
      const before = await page.evaluate(() => window.sightline.position());
      await page.keyboard.down('Shift');
      await page.keyboard.down('KeyW');
      await page.waitForTimeout(500);
      await page.keyboard.up('KeyW');
      await page.keyboard.up('Shift');
      const after = await page.evaluate(() => window.sightline.position());
      moved += Math.hypot(after[0] - before[0], after[1] - before[1]);
      const floor = await page.evaluate(() => window.sightline.floor());
      assert.ok(floor !== null, `no floor under (${after})`);
      assert.ok(Math.abs(after[2] - floor - scene.eye_height) < 1e-3 * scene.eye_height + 0.01,
        `eye at ${after[2]}, floor ${floor}: not ${scene.eye_height} above it`);
    }
    assert.ok(moved > scene.eye_height / 2, `W did not move the viewer (moved ${moved})`);
    const at = await page.evaluate(() => window.sightline.position());
    const r = await page.evaluate(([x, y, z]) => window.sightline.walkTo(x, y, z), at);
    const truth = await getJson(base, `/api/pvs?at=${at.join(',')}`);
    assert.deepEqual(r.drawn, truth.visible, 'after walking with the keyboard');
    await page.evaluate(() => window.sightline.look(0, -5));
    await page.evaluate(() => window.sightline.render());
    await page.screenshot({ path: join(outDir, 'level-final.png') });
    const stats = await page.evaluate(() => window.sightline.stats());
    log('level viewer stats', JSON.stringify(stats));
    assert.equal(stats.errors, 0, `viewer errors: ${stats.lastError}`);
    assert.deepEqual(pageErrors, [], 'page errors');
    log(`OK: level walk over ${cells.size} cells, drawn == PVS at every step; moved ${moved.toFixed(0)} units with the keyboard`);
  } catch (e) {
    failed = true;
    console.error('[e2e] FAILED (level):', e && e.stack ? e.stack : e);
  } finally {
    if (browser) await browser.close();
    const code = await stopServer(proc);
    if (code !== 0) {
      console.error(`[e2e] FAILED: level server exit status ${code} after SIGTERM`);
      failed = true;
    }
  }
  return failed;
}

main();
