// Validates a tileset folder written by `sightline tiles`:
//  * every GLB content with the Khronos glTF-Validator (npm `gltf-validator`);
//  * tileset.json against the 3D Tiles 1.1 rules a client relies on: asset.version,
//    geometricError present, non-negative and never larger than the parent's, box
//    bounding volumes of 12 finite numbers that enclose the children's boxes and the
//    content's positions, content URIs relative and present, EXT_mesh_features /
//    EXT_structural_metadata feature ids in range of their property table.
// Usage: node validate.mjs TILESET_DIR  — prints errors and warnings, exits 1 on an error.
import { readFileSync, existsSync } from 'node:fs';
import { join, normalize, isAbsolute } from 'node:path';
import validator from 'gltf-validator';

const dir = process.argv[2];
if (!dir) {
  console.error('usage: node validate.mjs TILESET_DIR');
  process.exit(2);
}
const errors = [];
const warnings = [];
const EPS = 1e-3;

const tileset = JSON.parse(readFileSync(join(dir, 'tileset.json'), 'utf8'));
if (tileset?.asset?.version !== '1.1') errors.push(`asset.version is ${tileset?.asset?.version}, expected 1.1`);
if (!(tileset.geometricError >= 0)) errors.push('tileset geometricError missing or negative');

const boxRange = (b) => {
  // Axis-aligned boxes only (what sightline writes): centre ± half-axes.
  const [cx, cy, cz, hx, , , , hy, , , , hz] = b;
  return [cx - Math.abs(hx), cy - Math.abs(hy), cz - Math.abs(hz), cx + Math.abs(hx), cy + Math.abs(hy), cz + Math.abs(hz)];
};
const inside = (a, b) => a[0] >= b[0] - EPS && a[1] >= b[1] - EPS && a[2] >= b[2] - EPS
  && a[3] <= b[3] + EPS && a[4] <= b[4] + EPS && a[5] <= b[5] + EPS;

const contents = [];
function visit(tile, path, parent) {
  const bv = tile.boundingVolume?.box;
  if (!Array.isArray(bv) || bv.length !== 12 || !bv.every(Number.isFinite)) {
    errors.push(`${path}: boundingVolume.box is not 12 finite numbers`);
    return;
  }
  const r = boxRange(bv);
  if (!(tile.geometricError >= 0)) errors.push(`${path}: geometricError missing or negative`);
  if (parent) {
    if (tile.geometricError > parent.geometricError + EPS) errors.push(`${path}: geometricError above its parent's`);
    if (!inside(r, parent.range)) errors.push(`${path}: box not enclosed by the parent's`);
  } else if (tile.geometricError > tileset.geometricError + EPS) {
    errors.push('root geometricError above the tileset geometricError');
  }
  if (tile.content) {
    const uri = tile.content.uri;
    if (typeof uri !== 'string' || isAbsolute(uri) || uri.includes(':') || normalize(uri).startsWith('..')) {
      errors.push(`${path}: content uri ${uri} is not a relative path inside the tileset`);
    } else if (!existsSync(join(dir, uri))) {
      errors.push(`${path}: content ${uri} is missing`);
    } else {
      contents.push({ path, uri, range: r });
    }
  }
  (tile.children ?? []).forEach((c, k) => visit(c, `${path}.children[${k}]`, { geometricError: tile.geometricError, range: r }));
}
visit(tileset.root, 'root', null);

// The feature ids and positions of our GLBs (one node with a translation, y-up).
function checkFeatures(uri, bytes, range) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const jsonLen = dv.getUint32(12, true);
  const gltf = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLen)));
  const binStart = 20 + jsonLen + 8;
  const tables = gltf.extensions?.EXT_structural_metadata?.propertyTables ?? [];
  const t = gltf.nodes?.[0]?.translation ?? [0, 0, 0];
  for (const mesh of gltf.meshes ?? []) {
    for (const prim of mesh.primitives) {
      const ids = prim.extensions?.EXT_mesh_features?.featureIds ?? [];
      if (ids.length === 0) errors.push(`${uri}: primitive without EXT_mesh_features feature ids`);
      for (const f of ids) {
        const table = tables[f.propertyTable];
        if (!table) { errors.push(`${uri}: feature ids name no property table`); continue; }
        if (table.count !== f.featureCount) errors.push(`${uri}: featureCount ${f.featureCount} ≠ property table count ${table.count}`);
        const acc = gltf.accessors[prim.attributes[`_FEATURE_ID_${f.attribute}`]];
        const view = gltf.bufferViews[acc.bufferView];
        const start = binStart + (view.byteOffset ?? 0) + (acc.byteOffset ?? 0);
        for (let i = 0; i < acc.count; i++) {
          const v = acc.componentType === 5123 ? dv.getUint16(start + 2 * i, true) : dv.getFloat32(start + 4 * i, true);
          if (v >= f.featureCount) { errors.push(`${uri}: feature id ${v} ≥ featureCount ${f.featureCount}`); break; }
        }
      }
      // POSITION min/max, back to the tileset's z-up frame, inside the tile's box.
      const p = gltf.accessors[prim.attributes.POSITION];
      const lo = [p.min[0] + t[0], -(p.max[2] + t[2]), p.min[1] + t[1]];
      const hi = [p.max[0] + t[0], -(p.min[2] + t[2]), p.max[1] + t[1]];
      if (!inside([...lo, ...hi], range)) errors.push(`${uri}: positions outside the tile's bounding box`);
    }
  }
}

for (const c of contents) {
  const bytes = new Uint8Array(readFileSync(join(dir, c.uri)));
  const report = await validator.validateBytes(bytes, { uri: c.uri, maxIssues: 100 });
  for (const m of report.issues.messages) {
    const line = `${c.uri}: ${m.code} ${m.message} (${m.pointer ?? ''})`;
    if (m.severity === 0) errors.push(line);
    else if (m.severity === 1) warnings.push(line);
  }
  checkFeatures(c.uri, bytes, c.range);
}

for (const w of warnings.slice(0, 20)) console.log(`warning: ${w}`);
for (const e of errors.slice(0, 50)) console.log(`error: ${e}`);
console.log(`tileset ${dir}: ${contents.length} content tiles, ${errors.length} errors, ${warnings.length} warnings`);
process.exit(errors.length ? 1 : 0);
