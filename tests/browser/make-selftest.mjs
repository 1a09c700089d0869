// Writes tests/browser/selftest.html (gitignored), the page selftest.test.mjs checks the harness
// with: the vendored three.js bundle inlined in a classic <script>, a lit rotating box with
// OrbitControls, and a 5 MB Float32Array as inline base64 gzip that the page decodes with
// DecompressionStream('gzip').
//
//   node make-selftest.mjs            # writes selftest.html next to this file
//
// Importers call makeSelftest(path), which returns what the page must compute.

import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { gzipSync } from 'node:zlib';

const here = dirname(fileURLToPath(import.meta.url));
export const BUNDLE = join(here, '..', '..', 'crates', 'swarf', 'src', 'view', 'three.bundle.js');
export const SELFTEST_HTML = join(here, 'selftest.html');

export const PAYLOAD_FLOATS = (5 * 1024 * 1024) / 4; // 5 MiB of float32

/** FNV-1a over 32-bit words; the page runs the same function on the decoded bytes. */
function fnv1aWords(u32) {
  let h = 0x811c9dc5;
  for (let i = 0; i < u32.length; i++) h = Math.imul(h ^ u32[i], 0x01000193) >>> 0;
  return h >>> 0;
}

/** Deterministic, toolpath-like floats: smooth coordinates with noise, in 1 µm steps. */
function makePayload() {
  const f = new Float32Array(PAYLOAD_FLOATS);
  let s = 0x2545f491;
  for (let i = 0; i < f.length; i++) {
    s ^= s << 13; s ^= s >>> 17; s ^= s << 5; // xorshift32
    const noise = ((s >>> 0) / 4294967296 - 0.5) * 0.2;
    const t = i / 3;
    f[i] = Math.round((50 * Math.sin(t * 0.001) + 10 * Math.cos(t * 0.013 + (i % 3)) + noise) * 1000) / 1000;
  }
  return f;
}

function page(bundle, base64) {
  return `<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>swarf browser harness self-test</title>
<style>html, body { margin: 0; height: 100%; overflow: hidden; background: #1d2026; } canvas { display: block; }</style>
</head>
<body>
<script>
${bundle}
</script>
<script type="application/octet-stream" id="data">${base64}</script>
<script>
'use strict';
const FNV = (u32) => {
  let h = 0x811c9dc5;
  for (let i = 0; i < u32.length; i++) h = Math.imul(h ^ u32[i], 0x01000193) >>> 0;
  return h >>> 0;
};
window.selftest = { frames: 0, decode: null };

// ---- scene ---------------------------------------------------------------------------------
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.domElement.id = 'view';
document.body.appendChild(renderer.domElement);

const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1d2026);
const camera = new THREE.PerspectiveCamera(45, window.innerWidth / window.innerHeight, 0.1, 100);
camera.position.set(3, 2.2, 4);
scene.add(new THREE.AmbientLight(0xffffff, 0.35));
const sun = new THREE.DirectionalLight(0xffffff, 2.5);
sun.position.set(4, 6, 3);
scene.add(sun);
const box = new THREE.Mesh(
  new THREE.BoxGeometry(1.6, 1.6, 1.6),
  new THREE.MeshStandardMaterial({ color: 0xd9822b, roughness: 0.5, metalness: 0.1 }),
);
scene.add(box);
const controls = new THREE.OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, 0);
controls.update();
window.selftest.camera = () => camera.position.toArray();
const gl = renderer.getContext();
const dbg = gl.getExtension('WEBGL_debug_renderer_info');
window.selftest.webgl = {
  version: gl.getParameter(gl.VERSION),
  renderer: dbg ? gl.getParameter(dbg.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER),
  three: THREE.REVISION,
};
renderer.setAnimationLoop(() => {
  box.rotation.x += 0.01;
  box.rotation.y += 0.013;
  controls.update();
  renderer.render(scene, camera);
  window.selftest.frames++;
});

// ---- inline gzip payload -------------------------------------------------------------------
async function decodePayload() {
  const t0 = performance.now();
  const text = document.getElementById('data').textContent;
  const bin = atob(text);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  const t1 = performance.now();
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'));
  const buf = await new Response(stream).arrayBuffer();
  const t2 = performance.now();
  const floats = new Float32Array(buf);
  const checksum = FNV(new Uint32Array(buf));
  const t3 = performance.now();
  return {
    base64Chars: text.length, gzipBytes: bytes.length, bytes: buf.byteLength, floats: floats.length,
    first: floats[0], last: floats[floats.length - 1], checksum,
    ms: { base64: t1 - t0, gunzip: t2 - t1, checksum: t3 - t2, total: t3 - t0 },
  };
}
window.selftest.decodePayload = decodePayload;
decodePayload().then(
  (r) => { window.selftest.decode = r; },
  (e) => { window.selftest.decode = { error: String(e) }; console.error('payload decode failed:', e); },
);
</script>
</body>
</html>
`;
}

/** Writes the self-test page to `out` and returns the payload facts the page must reproduce. */
export function makeSelftest(out = SELFTEST_HTML) {
  const bundle = readFileSync(BUNDLE, 'utf8');
  if (/<\/script/i.test(bundle)) throw new Error(`${BUNDLE} contains '</script'`);
  const floats = makePayload();
  const raw = new Uint8Array(floats.buffer);
  const gz = gzipSync(raw, { level: 6 });
  const base64 = gz.toString('base64');
  writeFileSync(out, page(bundle, base64));
  return {
    path: out,
    bytes: raw.byteLength,
    gzipBytes: gz.length,
    floats: floats.length,
    first: floats[0],
    last: floats[floats.length - 1],
    checksum: fnv1aWords(new Uint32Array(floats.buffer)),
  };
}

if (process.argv[1] && fileURLToPath(import.meta.url) === process.argv[1]) {
  const r = makeSelftest();
  console.log(`wrote ${r.path}: payload ${r.bytes} bytes, gzip ${r.gzipBytes} bytes`);
}
