// Helpers for swarf's end-to-end browser tests: Debian's Chromium, headless, driven by
// playwright-core (no Playwright-downloaded browsers).
//
//   import { launch, openPage, canvasIsBlank } from './harness.mjs';
//   const browser = await launch();
//   const page = await openPage(browser, 'out/view.html');
//   assert.deepEqual(page.swarfErrors, []);
//   assert.equal(await canvasIsBlank(page, 'canvas'), false);
//   await browser.close();
//
// Environment: SWARF_CHROMIUM overrides the browser executable (default /usr/bin/chromium).

import { existsSync } from 'node:fs';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

export const VIEWPORT = Object.freeze({ width: 1280, height: 800 });

// Flags for a headless Chromium on a CI machine without a GPU or outside network.
export const CHROMIUM_FLAGS = Object.freeze([
  '--headless',
  '--no-sandbox',
  // No GPU: the compositor and canvas run in software.
  '--disable-gpu',
  // Without these, Chromium opens background connections (QUIC, component updates, sync,
  // variations, ...) that a sandboxed CI machine refuses many at a time.
  '--disable-quic',
  '--no-first-run',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  // WebGL: with --disable-gpu, Chromium serves WebGL from ANGLE on SwiftShader (a CPU Vulkan
  // implementation shipped in /usr/lib/chromium/libvk_swiftshader.so). Chromium 156 from
  // bookworm-security still does that on its own (the GPU process gets
  // --use-angle=swiftshader-webgl), but upstream is removing this automatic fallback
  // (https://issues.chromium.org/issues/40277080) and requires --enable-unsafe-swiftshader to
  // opt in; playwright-core passes that flag by default too. Both are stated here so the
  // harness does not depend on either.
  '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader',
]);

/** The Chromium executable: $SWARF_CHROMIUM, or Debian's /usr/bin/chromium. */
export function chromiumPath() {
  return process.env.SWARF_CHROMIUM || '/usr/bin/chromium';
}

/** Launches Debian's Chromium headless (fresh, empty profile) and returns a Playwright Browser. */
export async function launch() {
  const executablePath = chromiumPath();
  if (!existsSync(executablePath)) {
    throw new Error(
      `Chromium not found at ${executablePath} (apt-get install chromium, or set SWARF_CHROMIUM)`,
    );
  }
  return chromium.launch({
    executablePath,
    headless: true,
    args: [...CHROMIUM_FLAGS],
    timeout: 60_000,
  });
}

/**
 * Opens `file://<absolute htmlPath>` in a new page with a 1280x800 viewport and waits for its
 * load event. Console errors, uncaught page errors and renderer crashes are collected, as
 * strings, in `page.swarfErrors`.
 */
export async function openPage(browser, htmlPath) {
  const page = await browser.newPage({ viewport: { ...VIEWPORT } });
  const errors = [];
  page.swarfErrors = errors;
  page.on('console', (msg) => {
    if (msg.type() === 'error') {
      const loc = msg.location();
      const where = loc && loc.url ? ` (${loc.url}:${loc.lineNumber})` : '';
      errors.push(`console.error: ${msg.text()}${where}`);
    }
  });
  page.on('pageerror', (err) => errors.push(`page error: ${err.stack || err.message || err}`));
  page.on('crash', () => errors.push('page crashed'));
  await page.goto(pathToFileURL(resolve(htmlPath)).href, { waitUntil: 'load' });
  return page;
}

/**
 * Pixel statistics of the canvas matched by `selector`: it is drawn into a 2D canvas of the same
 * size (its drawing buffer, not its CSS size) and every pixel is compared with the top-left one.
 * A WebGL canvas reads back only if its context was created with preserveDrawingBuffer: true
 * (otherwise it reads as transparent once the frame has been presented).
 * Returns { width, height, corner: [r, g, b, a], differing, fraction }.
 */
export async function canvasStats(page, selector) {
  return page.evaluate((sel) => {
    const src = document.querySelector(sel);
    if (!(src instanceof HTMLCanvasElement)) throw new Error(`no <canvas> matches ${sel}`);
    const { width, height } = src;
    if (width === 0 || height === 0) return { width, height, corner: null, differing: 0, fraction: 0 };
    const copy = document.createElement('canvas');
    copy.width = width;
    copy.height = height;
    const ctx = copy.getContext('2d', { willReadFrequently: true });
    ctx.drawImage(src, 0, 0);
    const px = new Uint32Array(ctx.getImageData(0, 0, width, height).data.buffer);
    const corner = px[0];
    let differing = 0;
    for (let i = 1; i < px.length; i++) if (px[i] !== corner) differing++;
    const c = new Uint8Array(new Uint32Array([corner]).buffer);
    return { width, height, corner: Array.from(c), differing, fraction: differing / px.length };
  }, selector);
}

/** True if fewer than 1 % of the canvas's pixels differ from its top-left pixel. */
export async function canvasIsBlank(page, selector) {
  const { fraction } = await canvasStats(page, selector);
  return fraction < 0.01;
}
