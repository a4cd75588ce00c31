// What the viewer's test and benchmark share (web/README.md): the viewer's
// build (scripts/build-web), headless Chromium, and a
// page served by scripts/view loaded until it is done.
import { spawn, execFileSync } from 'child_process';
import { createRequire } from 'module';
import path from 'path';
import { fileURLToPath } from 'url';

export const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
export const buildDir = process.env.ISOWAVE_WEB_BUILD_DIR || path.join(root, 'build-web');
const chromium = process.env.ISOWAVE_CHROMIUM || '/usr/bin/chromium';

// Headless Chromium (software WebGL), with the viewer built (scripts/build-web
// is incremental: the sources' changes, no download once done).
export async function launch() {
  execFileSync(path.join(root, 'scripts', 'build-web'), { stdio: 'inherit', env: { ...process.env, ISOWAVE_WEB_BUILD_DIR: buildDir } });
  const puppeteer = createRequire(path.join(buildDir, 'npm', 'package.json'))('puppeteer-core');
  return puppeteer.launch({
    executablePath: chromium, headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-quic',
           '--no-first-run', '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
}

// The page's state once it is done loading `file` (served by scripts/view,
// at `rate` bytes per second if not 0):
// window.isowaveViewer's frames, firstFrameMs and error, the error shown,
// the last frame's points (up to a million vertices), and the size of a
// screenshot (a blank canvas compresses to little).
export async function view(browser, file, rate = 0) {
  const server = spawn(path.join(root, 'scripts', 'view'), [file, '--port', '0', '--rate', String(rate)],
                       { env: { ...process.env, ISOWAVE_WEB_BUILD_DIR: buildDir } });
  try {
    const url = await new Promise((resolve, reject) => {
      server.stdout.once('data', (data) => resolve(data.toString().trim()));
      server.once('exit', (code) => reject(new Error(`scripts/view exited with ${code}`)));
    });
    const page = await browser.newPage();
    await page.setViewport({ width: 800, height: 600 });
    await page.goto(url);
    await page.waitForFunction(() => window.isowaveViewer && window.isowaveViewer.done, { timeout: 300000 });
    const state = await page.evaluate(() => {
      const s = window.isowaveViewer;
      return { frames: s.frames, firstFrameMs: s.firstFrameMs, error: s.error,
               shownError: document.getElementById('error').textContent,
               positions: s.positions && s.positions.length <= 3e6 ? Array.from(s.positions) : null };
    });
    const shot = await page.screenshot({ encoding: 'base64', type: 'png' });
    state.screenshotBytes = Buffer.from(shot, 'base64').length;
    await page.close();
    return state;
  } finally {
    server.kill();
  }
}
