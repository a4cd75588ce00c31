// The browser viewer in headless Chromium (issue #50, item 2; web/README.md),
// against the native decoder: a page served by scripts/view at 8 kB/s shows
// the base mesh first, before half the file is in (level 0, as many
// vertices as `isowave decode --level 0 --triangulate`), later frames decode
// more bytes and have more triangles, and the last one has
// the native decode's vertices and triangles at the same float32 points;
// the canvas is not blank; a truncated and a corrupt file show an error on
// the page. Prints the time to the first frame and the full decode's time
// in the page, and the native decode's.
//
// usage: node web/tests/viewer_test.mjs   (ISOWAVE_CLI: the isowave binary;
// ISOWAVE_WEB_BUILD_DIR: the viewer's build, made or updated by
// scripts/build-web; ISOWAVE_CHROMIUM: the browser, default /usr/bin/chromium)
import { execFileSync } from 'child_process';
import { mkdtempSync, readFileSync, writeFileSync } from 'fs';
import { tmpdir } from 'os';
import path from 'path';
import { launch, view } from './viewer_page.mjs';

const cli = process.env.ISOWAVE_CLI;
if (!cli) throw new Error('ISOWAVE_CLI must name the isowave binary');

const failures = [];
function check(condition, message) {
  if (!condition) {
    failures.push(message);
    console.log('FAIL:', message);
  }
}

// Vertices (float32, as the PLY holds them) and face count of `isowave decode ARGS --triangulate`.
function nativeDecode(file, args, work) {
  const ply = path.join(work, 'native.ply');
  const started = performance.now();
  execFileSync(cli, ['decode', file, ...args, '--triangulate', '--force', '--quiet', '-o', ply]);
  const seconds = (performance.now() - started) / 1000;
  const bytes = readFileSync(ply);
  const headerEnd = bytes.indexOf('end_header\n') + 'end_header\n'.length;
  const header = bytes.subarray(0, headerEnd).toString();
  const vertices = Number(/element vertex (\d+)/.exec(header)[1]);
  const faces = Number(/element face (\d+)/.exec(header)[1]);
  check(/property float x/.test(header) && /binary_little_endian/.test(header), 'native PLY: float32 binary');
  const positions = new Float32Array(bytes.buffer.slice(bytes.byteOffset + headerEnd, bytes.byteOffset + headerEnd + 12 * vertices));
  return { vertices, faces, positions, seconds };
}

const work = mkdtempSync(path.join(tmpdir(), 'isowave-viewer-'));
const file = path.join(work, 'surface.isw');
execFileSync(cli, ['convert', 'builtin:sphere:48', '--levels', '3', '-o', file, '--quiet']);
const browser = await launch();
try {
  const base = nativeDecode(file, ['--level', '0'], work);
  const whole = nativeDecode(file, [], work);
  // Served at 8 kB/s, as a slow network would: the page refines as the bytes arrive.
  const size = readFileSync(file).length;
  const state = await view(browser, file, 8000);
  const frames = state.frames;
  check(!state.error, `an error on the page: ${state.error}`);
  check(frames.length >= 3, `${frames.length} frames`);
  check(frames.length > 0 && frames[0].bytes < size / 2, 'the base mesh is shown before half the file is in');
  check(frames.every((f, k) => k === 0 || f.bytes > frames[k - 1].bytes || k === frames.length - 1),
        'each frame decodes more bytes');
  if (frames.length >= 2) {
    const first = frames[0], last = frames[frames.length - 1];
    check(first.level === 0 && first.vertices === base.vertices, `first frame: level ${first.level}, ${first.vertices} vertices; the base mesh has ${base.vertices}`);
    check(frames.slice(1).every((f) => f.triangles > first.triangles), 'later frames have more triangles');
    check(last.vertices === whole.vertices && last.triangles === whole.faces,
          `last frame: ${last.vertices} vertices, ${last.triangles} triangles; native ${whole.vertices}, ${whole.faces}`);
    let differ = 0;
    for (let i = 0; state.positions && i < whole.positions.length; ++i) differ += state.positions[i] !== whole.positions[i];
    check(state.positions && differ === 0, `${differ} coordinates differ from the native decode's float32`);
    console.log(`frames: ${frames.map((f) => `${f.bytes} bytes level ${f.level} ${f.triangles} triangles ${f.ms.toFixed(0)} ms`).join('; ')}`);
    console.log(`first frame ${state.firstFrameMs.toFixed(0)} ms after the request; whole decode in the page ` +
                `${last.ms.toFixed(0)} ms, native decode and PLY ${(whole.seconds * 1000).toFixed(0)} ms`);
  }
  check(state.screenshotBytes > 5000, `the page's screenshot holds ${state.screenshotBytes} bytes (a blank canvas?)`);

  const bytes = readFileSync(file);
  const truncated = path.join(work, 'truncated.isw'), corrupt = path.join(work, 'corrupt.isw');
  writeFileSync(truncated, bytes.subarray(0, 100));
  const damaged = Buffer.from(bytes);
  damaged[Math.floor(damaged.length / 2)] ^= 0x5a;
  writeFileSync(corrupt, damaged);
  for (const bad of [truncated, corrupt]) {
    const s = await view(browser, bad);
    check(s.error && s.shownError.includes('file.isw'), `${path.basename(bad)}: no error on the page (${s.shownError})`);
    console.log(`${path.basename(bad)}: "${s.shownError}"`);
  }
} finally {
  await browser.close();
}
if (failures.length) {
  console.log(`${failures.length} failures`);
  process.exit(1);
}
console.log('viewer: all checks passed');
