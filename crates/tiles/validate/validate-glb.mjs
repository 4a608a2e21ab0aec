// Validates GLB files (e.g. `sightline clusters LEVEL.obj -o L.glb`) with the Khronos
// glTF-Validator (npm gltf-validator), and checks what `clusters` promises: one scene,
// every node named by its index (the cluster id).
// Usage: node validate-glb.mjs FILE.glb…  — prints errors and warnings, exits 1 on an error.
import { readFileSync } from 'node:fs';
import validator from 'gltf-validator';

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate-glb.mjs FILE.glb…');
  process.exit(2);
}
let failed = false;
for (const f of files) {
  const bytes = new Uint8Array(readFileSync(f));
  const report = await validator.validateBytes(bytes, { uri: f, maxIssues: 100 });
  const errors = [];
  for (const m of report.issues.messages) {
    const line = `${f}: ${m.code} ${m.message} (${m.pointer ?? ''})`;
    if (m.severity === 0) errors.push(line);
    else if (m.severity === 1) console.log(`warning: ${line}`);
  }
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const gltf = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + dv.getUint32(12, true))));
  if ((gltf.scenes ?? []).length !== 1) errors.push(`${f}: ${(gltf.scenes ?? []).length} scenes, expected 1`);
  (gltf.nodes ?? []).forEach((n, i) => {
    if (n.name !== String(i)) errors.push(`${f}: node ${i} is named ${JSON.stringify(n.name)}, expected "${i}"`);
  });
  for (const e of errors.slice(0, 50)) console.log(`error: ${e}`);
  console.log(`${f}: ${(gltf.nodes ?? []).length} nodes, ${report.issues.numErrors} validator errors, ${report.issues.numWarnings} warnings, ${report.issues.numInfos} infos`);
  failed ||= errors.length > 0;
}
process.exit(failed ? 1 : 0);
