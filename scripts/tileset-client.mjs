// Loads a lodstudio tileset in a real 3D Tiles client (issue 47, by hand):
// three.js' 3d-tiles-renderer, headless in Node (no WebGL: its traversal,
// screen-space error, downloads and GLB parsing are the library's own, only
// drawing is left out). The tileset's folder is served over HTTP on
// localhost; the camera looks at the model from a few distances, and at
// each the client's visible tiles, their levels and triangles are reported.
// Exit 1 when a tile fails to load or nothing is shown.
//
//   npm install three 3d-tiles-renderer     (in any folder, once)
//   NODE_PATH=... node scripts/tileset-client.mjs DIR/tileset.json
//
// Run from the folder holding node_modules (or copy the script there).

import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { TilesRenderer } from '3d-tiles-renderer';
import { PerspectiveCamera, Box3, Vector3, Sphere } from 'three';

const file = path.resolve(process.argv[2] ?? '');
if (!fs.existsSync(file)) {
  console.error(`error: ${file}: no tileset`);
  process.exit(2);
}
const root = path.dirname(file);
const server = http.createServer((req, res) => {
  const target = path.resolve(root, '.' + decodeURIComponent(req.url.split('?')[0]));
  if (!target.startsWith(root + path.sep) || !fs.existsSync(target)) {
    res.writeHead(404).end();
    return;
  }
  res.writeHead(200).end(fs.readFileSync(target));
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const url = `http://127.0.0.1:${server.address().port}/${path.basename(file)}`;

// The page the client would run in: it resolves relative URIs against it.
globalThis.window ??= { location: { href: url }, devicePixelRatio: 1, performance };
globalThis.requestAnimationFrame ??= (f) => setTimeout(() => f(performance.now()), 0);
globalThis.cancelAnimationFrame ??= (id) => clearTimeout(id);
const tiles = new TilesRenderer(url);
const failures = [];
tiles.addEventListener('load-error', (e) => failures.push(String(e.error ?? e.url)));
const camera = new PerspectiveCamera(60, 1280 / 800, 1e-4, 1e6);
tiles.setCamera(camera);
tiles.setResolution(camera, 1280, 800);

const idle = () => {
  const s = tiles.stats;
  return s.queued + s.downloading + s.parsing === 0;
};
async function settle() {
  for (let i = 0; i < 2000; i++) {
    camera.updateMatrixWorld();
    tiles.update();
    await new Promise((ok) => setTimeout(ok, 5));
    if (i > 3 && idle() && tiles.root) {
      tiles.update();
      if (idle()) return;
    }
  }
}

await settle();
const sphere = new Sphere();
tiles.getBoundingSphere(sphere);
const report = { url, failures, views: [] };
for (const distance of [64, 4, 1.5, 0.6, 0.3]) {
  camera.position.copy(sphere.center).add(new Vector3(0, 0, distance * sphere.radius));
  camera.lookAt(sphere.center);
  await settle();
  let triangles = 0;
  const levels = {};
  for (const tile of tiles.visibleTiles) {
    levels[tile.internal.depth] = (levels[tile.internal.depth] ?? 0) + 1;
    tile.engineData.scene?.traverse((o) => {
      const g = o.geometry;
      if (g) triangles += (g.index ? g.index.count : g.attributes.position.count) / 3;
    });
  }
  report.views.push({
    distance_in_radii: distance,
    visible_tiles: tiles.visibleTiles.size,
    tiles_by_depth: levels,
    triangles,
    loaded: tiles.stats.loaded,
  });
}
server.close();
tiles.dispose();
console.log(JSON.stringify(report));
process.exit(failures.length || report.views.some((v) => v.visible_tiles === 0) ? 1 : 0);
