// Issue #50's browser targets: a file served by scripts/view on localhost
// and loaded by the viewer in headless Chromium (software WebGL): the time
// from the request to the first frame (the base mesh), each frame's decode
// and whole time (normals, upload, rendering), and the last decode against
// the native decoder's in the same run (the
// Python module's decode(triangulate=True): decode and triangulation, no
// file written; best of 3).
//
// usage: node bench/viewer_time.mjs FILE.isw [FILE.isw ...]   (PYTHONPATH:
// the module's directory; ISOWAVE_WEB_BUILD_DIR as for web/tests)
import { execFileSync } from 'child_process';
import { launch, view } from '../web/tests/viewer_page.mjs';

function nativeSeconds(file) {
  const script = 'import sys, time, isowave\nbest = 1e9\nfor _ in range(3):\n    t = time.perf_counter()\n' +
                 '    isowave.decode(sys.argv[1], triangulate=True)\n    best = min(best, time.perf_counter() - t)\nprint(best)';
  return Number(execFileSync('/usr/bin/python3', ['-c', script, file]).toString());
}

const browser = await launch();
try {
  for (const file of process.argv.slice(2)) {
    const state = await view(browser, file);
    if (state.error) {
      console.log(`${file}: ${state.error}`);
      continue;
    }
    const last = state.frames[state.frames.length - 1];
    const native = nativeSeconds(file);
    console.log(`${file}: first frame ${state.firstFrameMs.toFixed(0)} ms after the request (level ` +
                `${state.frames[0].level}, ${state.frames[0].triangles} triangles); frames ` +
                `${state.frames.map((f) => `${f.bytes}:${f.decodeMs.toFixed(0)}/${f.ms.toFixed(0)}ms`).join(' ')} ` +
                `(decode/frame); the last decode ${last.decodeMs.toFixed(0)} ms (${last.triangles} triangles) ` +
                `against the native decode's ${(native * 1000).toFixed(0)} ms: ${(last.decodeMs / 1000 / native).toFixed(2)}x; ` +
                `its frame ${last.ms.toFixed(0)} ms`);
  }
} finally {
  await browser.close();
}
