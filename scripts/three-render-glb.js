#!/usr/bin/env node
// Renders a .glb written by `cellbake export` with three.js in headless
// Chromium (driven by playwright-core), from an eye looking at a point given
// in the model's world coordinates, as `cellbake render --eye --look` takes
// them: the file's root node holds the origin and up axis in its extras
// (pipeline/export/cell_gltf_export.h), which map world points into the scene.
//
//   node scripts/three-render-glb.js --glb F.glb --eye X,Y,Z --look X,Y,Z
//        [--size WxH] [--fov DEG] [--near N] --out F.png
//
// Needs the npm packages `three` and `playwright-core` (scripts/install-node-tools.sh)
// on NODE_PATH or in CELLBAKE_NODE_TOOLS/node_modules, and Chromium
// (Debian package `chromium`; CHROMIUM=path overrides /usr/bin/chromium).
// Exit 0 with the PNG written; 1 with a message on any failure (load errors
// and console errors of the page included); 2 for bad arguments.
'use strict';
const fs = require('fs');
const http = require('http');
const path = require('path');

const { package_root: find_package } = require('./node-packages.js');

// The folder of npm package `name`; throws naming it when absent.
function package_root(name) {
  const root = find_package(name);
  if (root) return root;
  throw new Error(`npm package ${name} not found (scripts/install-node-tools.sh installs it; set CELLBAKE_NODE_TOOLS)`);
}

function parse_args(argv) {
  const a = { size: '512x512', fov: 60, near: 0.05 };
  for (let i = 2; i < argv.length; i += 2) {
    const key = argv[i].replace(/^--/, '');
    if (i + 1 >= argv.length) throw new Error('missing value for ' + argv[i]);
    a[key] = argv[i + 1];
  }
  for (const k of ['glb', 'eye', 'look', 'out']) if (!a[k]) throw new Error('--' + k + ' is required');
  const point = (s, name) => {
    const v = s.split(',').map(Number);
    if (v.length !== 3 || v.some((x) => !Number.isFinite(x))) throw new Error(name + ' must be X,Y,Z');
    return v;
  };
  const [w, h] = a.size.split('x').map(Number);
  if (!(w > 0 && h > 0)) throw new Error('--size must be WxH');
  return { glb: a.glb, eye: point(a.eye, '--eye'), look: point(a.look, '--look'), width: w, height: h,
           fov: Number(a.fov), near: Number(a.near), out: a.out };
}

const page_html = `<!doctype html><html><head><meta charset="utf-8">
<script type="importmap">{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}</script>
</head><body style="margin:0;background:#000">
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
window.renderGlb = async (p) => {
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(p.width, p.height);
  document.body.appendChild(renderer.domElement);
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.loadAsync('/model.glb');
  const json = gltf.parser.json;
  const root = json.nodes[json.scenes[json.scene || 0].nodes[0]];
  const info = root.extras && root.extras.cellbake;
  if (!info) throw new Error('the file has no cellbake extras on its root node');
  const o = info.origin;
  // World -> scene: relative to the origin, then the root's turn of the up axis onto +Y.
  const to_scene = (v) => info.up === 'z' ? new THREE.Vector3(v[0] - o[0], v[2] - o[2], -(v[1] - o[1]))
                                          : new THREE.Vector3(v[0] - o[0], v[1] - o[1], v[2] - o[2]);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0, 0, 0);
  scene.add(gltf.scene);
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const eye = to_scene(p.eye);
  const far = Math.max(box.distanceToPoint(eye) + box.getSize(new THREE.Vector3()).length(), 1) * 1.5;
  const camera = new THREE.PerspectiveCamera(p.fov, p.width / p.height, p.near, far);
  camera.up.set(0, 1, 0);
  camera.position.copy(eye);
  camera.lookAt(to_scene(p.look));
  renderer.render(scene, camera);
  let triangles = 0;
  gltf.scene.traverse((m) => { if (m.isMesh) triangles += m.geometry.index ? m.geometry.index.count / 3 : 0; });
  return { png: renderer.domElement.toDataURL('image/png'), triangles, calls: renderer.info.render.calls };
};
window.pageReady = true;
</script></body></html>`;

async function main() {
  let args;
  try {
    args = parse_args(process.argv);
  } catch (e) {
    console.error('three-render-glb: ' + e.message);
    process.exit(2);
  }
  const glb = fs.readFileSync(args.glb);
  const three_root = path.resolve(package_root('three'));
  const { chromium } = require(package_root('playwright-core'));

  const missing = [];  // URLs the page asked for that are not there
  const server = http.createServer((req, res) => {
    const url = decodeURIComponent(req.url.split('?')[0]);
    let body = null, type = 'application/octet-stream';
    if (url === '/' || url === '/index.html') { body = page_html; type = 'text/html'; }
    else if (url === '/model.glb') { body = glb; type = 'model/gltf-binary'; }
    else if (url.startsWith('/three/')) {
      const file = path.normalize(path.join(three_root, url.slice('/three/'.length)));
      if (file.startsWith(three_root + path.sep) && fs.existsSync(file)) {
        body = fs.readFileSync(file);
        if (file.endsWith('.js')) type = 'text/javascript';
      }
    }
    if (url === '/favicon.ico') { res.writeHead(204); res.end(); return; }
    if (body === null) { missing.push(url); res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'Content-Type': type });
    res.end(body);
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  const port = server.address().port;
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-sandbox'],
  });
  const errors = [];
  try {
    const page = await browser.newPage({ viewport: { width: args.width, height: args.height } });
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.goto(`http://127.0.0.1:${port}/index.html`);
    await page.waitForFunction(() => window.pageReady === true, null, { timeout: 60000 });
    const result = await page.evaluate((p) => window.renderGlb(p), args);
    if (errors.length) throw new Error('page errors: ' + errors.join('; ') + (missing.length ? ' (not found: ' + missing.join(', ') + ')' : ''));
    fs.writeFileSync(args.out, Buffer.from(result.png.split(',')[1], 'base64'));
    console.log(JSON.stringify({ out: args.out, triangles: result.triangles, draw_calls: result.calls }));
  } finally {
    await browser.close();
    server.close();
  }
}

main().catch((e) => {
  console.error('three-render-glb: ' + (e && e.message ? e.message : e));
  process.exit(1);
});
