// The isowave browser viewer (web/README.md): fetches an .isw file as a
// stream, shows the base mesh as soon as its bytes are in (the end of BPTS;
// decoded from those bytes alone, without the hierarchy), and decodes again
// at the finest level each time the bytes read double and at the end, with the WebAssembly decoder (isowave_decoder.mjs). The page's
// state is in window.isowaveViewer for tests: one entry per frame (bytes
// read, level, vertices, triangles, the file's recorded D, the frame's time),
// the time to the first frame, `done`, and `error` (also shown on the page).
import * as THREE from 'three';
import { OrbitControls } from './OrbitControls.js';
import createIsowaveDecoder from './isowave_decoder.mjs';

const state = (window.isowaveViewer = { frames: [], firstFrameMs: null, done: false, error: null, positions: null });
const statusBox = document.getElementById('status');
const errorBox = document.getElementById('error');
const canvas = document.getElementById('view');

const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
const controls = new OrbitControls(camera, canvas);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 2.0));
const light = new THREE.DirectionalLight(0xffffff, 1.5);
scene.add(light);
const material = new THREE.MeshStandardMaterial({ color: 0xc8b090, roughness: 0.6, side: THREE.DoubleSide });
const mesh = new THREE.Mesh(new THREE.BufferGeometry(), material);
scene.add(mesh);

function resize() {
  renderer.setSize(window.innerWidth, window.innerHeight, false);
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
}
function render() {
  light.position.copy(camera.position);
  renderer.render(scene, camera);
}
window.addEventListener('resize', () => { resize(); render(); });
controls.addEventListener('change', render);
resize();

function showError(message) {
  state.error = message;
  errorBox.textContent = message;
}

// Where the base mesh's bytes end: after BPTS (docs/FORMAT.md: a 16-byte
// header, then sections of tag, u64 payload size and u32 CRC, the payload,
// and a u32 CRC). Infinity while unknown.
function baseEnd(bytes, length) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, length);
  for (let at = 16; at + 16 <= length;) {
    const tag = String.fromCharCode(bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]);
    const end = at + 16 + Number(view.getBigUint64(at + 4, true)) + 4;
    if (tag === 'BPTS') return end;
    at = end;
  }
  return Infinity;
}

// Decodes the first `length` bytes at `level` (-1: the finest; -2: the base
// mesh from the headers) and shows
// them; returns the decoder's error message (headed by `name`), or null.
function decodeAndShow(decoder, bytes, length, level, started, name) {
  const t0 = performance.now();
  const at = decoder._malloc(length);
  decoder.HEAPU8.set(bytes.subarray(0, length), at);
  const nameBytes = decoder.lengthBytesUTF8(name) + 1, nameAt = decoder._malloc(nameBytes);
  decoder.stringToUTF8(name, nameAt, nameBytes);
  const failed = decoder._isw_decode(at, length, level, nameAt);
  const decodeMs = performance.now() - t0;
  decoder._free(nameAt);
  decoder._free(at);
  if (failed) return decoder.UTF8ToString(decoder._isw_error());
  const vertices = decoder._isw_vertex_count(), triangles = decoder._isw_triangle_count();
  const positions = new Float32Array(decoder.HEAPF32.buffer, decoder._isw_positions(), 3 * vertices).slice();
  const index = new Uint32Array(decoder.HEAPU32.buffer, decoder._isw_triangles(), 3 * triangles).slice();
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setIndex(new THREE.BufferAttribute(index, 1));
  geometry.computeVertexNormals();
  geometry.computeBoundingSphere();
  const first = state.frames.length === 0;
  mesh.geometry.dispose();
  mesh.geometry = geometry;
  if (first) {
    const { center, radius } = geometry.boundingSphere;
    controls.target.copy(center);
    camera.position.copy(center).add(new THREE.Vector3(0, -radius * 2.5, radius * 1.2));
    camera.near = radius / 100;
    camera.far = radius * 20;
    camera.updateProjectionMatrix();
    controls.update();
  }
  render();
  const now = performance.now();
  if (first) state.firstFrameMs = now - started;
  const frame = {
    bytes: length, level: decoder._isw_level(), vertices, triangles, errorCells: decoder._isw_error_cells(),
    ms: now - t0, decodeMs, truncated: decoder._isw_truncated() === 1,
  };
  state.frames.push(frame);
  state.positions = positions;
  const d = frame.errorCells >= 0 ? `, D ${frame.errorCells.toFixed(3)} cells` : '';
  statusBox.textContent = `${length.toLocaleString()} bytes read, level ${frame.level}: ` +
    `${vertices.toLocaleString()} vertices, ${triangles.toLocaleString()} triangles${d}; ` +
    `frame ${frame.ms.toFixed(0)} ms`;
  return null;
}

// Reads `stream` (of `total` bytes if known), decoding as described above.
async function load(stream, total, name) {
  const started = performance.now();
  state.frames = [];
  state.done = false;
  state.error = null;
  errorBox.textContent = '';
  const decoder = await decoderReady;
  let bytes = new Uint8Array(Math.max(total || 0, 1 << 16));
  let length = 0, next = Infinity, base = Infinity, baseShown = false;
  const reader = stream.getReader();
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    if (length + value.length > bytes.length) {
      const grown = new Uint8Array(Math.max(2 * bytes.length, length + value.length));
      grown.set(bytes.subarray(0, length));
      bytes = grown;
    }
    bytes.set(value, length);
    length += value.length;
    if (base === Infinity) base = baseEnd(bytes, length);
    if (!baseShown && base <= length) {
      decodeAndShow(decoder, bytes, base, -2, started, name);  // the base mesh, from its own bytes
      baseShown = true;
      next = 2 * length;
    } else if (length >= next) {
      decodeAndShow(decoder, bytes, length, -1, started, name);
      next = 2 * length;
    }
  }
  const message = decodeAndShow(decoder, bytes, length, -1, started, name);
  if (message) showError(message);
  else if (state.frames[state.frames.length - 1].truncated)
    showError(`${name}: the file ends before its last section: showing what it holds`);
  state.done = true;
}

const decoderReady = createIsowaveDecoder().then((decoder) => {
  statusBox.textContent = 'decoder ready';
  return decoder;
});

document.getElementById('file').addEventListener('change', (event) => {
  const file = event.target.files[0];
  if (file) load(file.stream(), file.size, file.name).catch((e) => showError(`${file.name}: ${e.message || e}`));
});

const url = new URLSearchParams(location.search).get('file');
if (url) {
  fetch(url)
    .then((response) => {
      if (!response.ok) throw new Error(`HTTP ${response.status}`);
      return load(response.body, Number(response.headers.get('Content-Length')) || 0, url);
    })
    .catch((e) => {
      showError(`${url}: ${e.message || e}`);
      state.done = true;
    });
} else {
  statusBox.textContent = 'choose an .isw file';
}
