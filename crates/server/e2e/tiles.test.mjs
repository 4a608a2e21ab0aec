// End-to-end test of the PVS-driven 3D Tiles viewer (/tiles/, 3DTilesRendererJS) in
// headless Chromium. It generates a small city, builds its .pvs (dual-ray), exports the
// tileset with the tile-level PVS, serves both, and walks a few cells: at every step
// the viewer looks round (4 × 90°) and every tile holding a feature that the ground
// truth (`sightline truth`) sees from the cell must be loaded (0 misses); every tile
// the PVS mode requests must be in the cell's tile PVS or its neighbours' (prefetch).
// The plain switch must load at least as many tiles. Screenshots go to e2e/out/.
//
// Environment: SIGHTLINE_BIN (default <repo>/target/debug/sightline), CHROMIUM
// (default /usr/bin/chromium).
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import assert from 'node:assert/strict';
import { chromium } from 'playwright-core';
import { startServer } from './serve.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const repo = resolve(here, '../../..');
const bin = process.env.SIGHTLINE_BIN || join(repo, 'target/debug/sightline');
const outDir = join(here, 'out');
mkdirSync(outDir, { recursive: true });
const work = mkdtempSync(join(tmpdir(), 'sightline-tiles-e2e-'));

function log(...a) { console.log('[tiles-e2e]', ...a); }
function run(...args) { return execFileSync(bin, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] }); }


async function main() {
  const city = join(work, 'city.geojson');
  run('generate', 'city', '--size', '250', '--seed', '3', '-o', city);
  run('cells', city, '--size', '25', '-o', join(work, 'cells.json'));
  run('build', city, '--cells', join(work, 'cells.json'), '--method', 'dual-ray', '-o', join(work, 'city.pvs'));
  const tilesetDir = join(work, 'tileset');
  run('tiles', city, '--pvs', join(work, 'city.pvs'), '--max-features-per-tile', '4', '-o', tilesetDir);
  const sidecar = JSON.parse(readFileSync(join(tilesetDir, 'sightline-pvs.json'), 'utf8'));
  log(`${sidecar.tiles.length} content tiles, ${sidecar.cells.length} cells`);
  // object id → content URI
  const tileOf = new Map();
  sidecar.tiles.forEach((t) => t.objects.forEach((o) => tileOf.set(o, t.uri)));

  const { proc, url } = startServer(bin, ['serve', city, join(work, 'city.pvs'), '--tiles', tilesetDir, '--addr', '127.0.0.1:0'], { log });
  let browser;
  let failed = false;
  try {
    const base = (await url).replace(/\/$/, '');
    // Path traversal through the data route is refused.
    for (const bad of ['/tiles/data/..%2F..%2Fetc%2Fpasswd', '/tiles/data/../city.pvs', '/tiles/data/%2E%2E/city.pvs']) {
      const r = await fetch(base + bad);
      assert.ok(r.status === 404 || r.status === 400, `${bad}: HTTP ${r.status}`);
    }
    browser = await chromium.launch({
      executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
      headless: true,
      args: ['--no-sandbox', '--no-first-run', '--disable-background-networking', '--disable-component-update',
        '--disable-sync', '--disable-quic', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
    });
    const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(String(e)));
    // Console errors, except the browser's own "failed to load resource" lines: failed
    // responses are checked by URL below (the favicon is not ours).
    page.on('console', (m) => { if (m.type() === 'error' && !m.text().startsWith('Failed to load resource')) pageErrors.push(m.text()); });
    page.on('response', (r) => { if (r.status() >= 400 && !r.url().endsWith('/favicon.ico')) pageErrors.push(`HTTP ${r.status()} ${r.url()}`); });
    await page.goto(base + '/tiles/');
    // The viewer starts in the middle of the scene and loads that cell's tile PVS.
    const first = await page.evaluate(() => window.sightlineTiles.ready);
    assert.ok(first && first.tiles, 'the viewer starts in a cell of the tile PVS');
    log(`viewer ready in cell ${first.cell}`);

    // A recorded walk: the centres of a few cells along the middle row, west to east.
    const rows = [...new Set(sidecar.cells.map((c) => c.box[1]))].sort((a, b) => a - b);
    const midRow = rows[Math.floor(rows.length / 2)];
    const steps = sidecar.cells.filter((c) => c.box[1] === midRow).sort((a, b) => a.box[0] - b.box[0]).slice(0, 4);
    assert.ok(steps.length >= 2, 'a walk over at least two cells');
    let totalPvs = 0;
    const everAllowed = new Set([...first.tiles, ...first.neighbours]);
    for (const [k, c] of steps.entries()) {
      const x = (c.box[0] + c.box[3]) / 2;
      const y = (c.box[1] + c.box[4]) / 2;
      const allowed = new Set();
      for (let q = 0; q < 4; q++) {
        const r = await page.evaluate(([px, py, az]) => window.sightlineTiles.lookFrom(px, py, az), [x, y, (q * Math.PI) / 2]);
        assert.equal(r.cell, c.index, `step ${k}: the viewer is in cell ${c.index}`);
        r.tiles.forEach((t) => allowed.add(t));
        r.neighbours.forEach((t) => allowed.add(t));
        allowed.forEach((t) => everAllowed.add(t));
        const stray = r.requested.filter((u) => !allowed.has(u));
        assert.deepEqual(stray, [], `step ${k}: requested tiles outside the tile PVS (+ neighbours)`);
      }
      const loaded = new Set(await page.evaluate(() => window.sightlineTiles.loaded()));
      const truth = JSON.parse(run('truth', city, `--cell=${c.box.join(',')}`, '--json'));
      const truthTiles = [...new Set(truth.visible.map((o) => tileOf.get(o)))].sort();
      const missing = truthTiles.filter((u) => !loaded.has(u));
      log(`step ${k}: cell ${c.index}, truth sees ${truth.visible.length} objects in ${truthTiles.length} tiles; loaded ${loaded.size} of ${sidecar.tiles.length}; missed ${missing.length}`);
      assert.deepEqual(missing, [], `step ${k}: tiles the ground truth sees but the viewer did not load`);
      totalPvs = loaded.size;
      await page.screenshot({ path: join(outDir, `tiles-step-${k}.png`), timeout: 120_000 });
    }
    // Nothing outside the tile PVS was ever requested, not even before the first cell.
    const everRequested = await page.evaluate(() => window.sightlineTiles.requested());
    assert.deepEqual(everRequested.filter((u) => !everAllowed.has(u)), [], 'requests outside every tile PVS of the walk');
    // The plain tileset, for comparison: at least as many tiles.
    await page.evaluate(() => window.sightlineTiles.setPlain(true));
    const last = steps[steps.length - 1];
    const lx = (last.box[0] + last.box[3]) / 2;
    const ly = (last.box[1] + last.box[4]) / 2;
    for (let q = 0; q < 4; q++) await page.evaluate(([px, py, az]) => window.sightlineTiles.lookFrom(px, py, az), [lx, ly, (q * Math.PI) / 2]);
    const plainLoaded = (await page.evaluate(() => window.sightlineTiles.loaded())).length;
    await page.screenshot({ path: join(outDir, 'tiles-plain.png'), timeout: 120_000 });
    log(`plain tileset: ${plainLoaded} tiles loaded (PVS walk: ${totalPvs})`);
    assert.ok(plainLoaded >= totalPvs, 'the plain tileset loads at least what the PVS walk loaded');
    assert.deepEqual(pageErrors, [], 'no page errors');
    log('1 passed, 0 failed');
  } catch (e) {
    failed = true;
    console.error(e);
    log('0 passed, 1 failed');
  } finally {
    if (browser) await browser.close();
    proc.kill('SIGTERM');
    rmSync(work, { recursive: true, force: true });
  }
  process.exit(failed ? 1 : 0);
}

main();
