// Self-test of the browser harness: the vendored three.js bundle renders a lit box with
// OrbitControls in Debian's Chromium from a file:// page, and a 5 MB inline base64 gzip payload
// decodes with DecompressionStream.
//
//   cd tests/browser && npm ci && node --test
//
// The screenshot goes to $SWARF_BROWSER_OUT (default: a fresh temporary folder).

import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';

import { canvasIsBlank, canvasStats, launch, openPage } from './harness.mjs';
import { makeSelftest } from './make-selftest.mjs';

const outDir = process.env.SWARF_BROWSER_OUT || mkdtempSync(join(tmpdir(), 'swarf-browser-'));
mkdirSync(outDir, { recursive: true });

let browser;
let page;
let expected;

before(async () => {
  expected = makeSelftest();
  browser = await launch();
  page = await openPage(browser, expected.path);
  // A few frames, so that the box has been drawn.
  await page.waitForFunction(() => window.selftest && window.selftest.frames >= 3, null, { timeout: 30_000 });
});

after(async () => {
  await browser?.close();
});

test('three.js bundle renders a lit box with WebGL', async (t) => {
  const webgl = await page.evaluate(() => window.selftest.webgl);
  t.diagnostic(`three r${webgl.three}, ${webgl.version}, ${webgl.renderer}`);
  const stats = await canvasStats(page, '#view');
  t.diagnostic(`canvas ${stats.width}x${stats.height}, ${(stats.fraction * 100).toFixed(1)} % of pixels differ from the corner`);
  assert.equal(stats.width, 1280);
  assert.equal(stats.height, 800);
  assert.equal(await canvasIsBlank(page, '#view'), false, 'the canvas shows nothing');
  // The box is orange on a dark background: the centre pixel is mostly red.
  const centre = await page.evaluate(() => {
    const c = document.getElementById('view');
    const copy = document.createElement('canvas');
    copy.width = c.width; copy.height = c.height;
    const ctx = copy.getContext('2d');
    ctx.drawImage(c, 0, 0);
    return Array.from(ctx.getImageData(c.width / 2, c.height / 2, 1, 1).data);
  });
  t.diagnostic(`centre pixel rgba(${centre.join(', ')})`);
  assert.ok(centre[0] > 100 && centre[0] > centre[2] + 40, `centre pixel is not the box: ${centre}`);

  const png = join(outDir, 'selftest.png');
  writeFileSync(png, await page.screenshot());
  t.diagnostic(`screenshot: ${png}`);
  assert.deepEqual(page.swarfErrors, []);
});

test('canvasIsBlank reports a blank canvas', async () => {
  await page.evaluate(() => {
    const c = document.createElement('canvas');
    c.id = 'blank';
    c.width = 200; c.height = 100;
    const ctx = c.getContext('2d');
    ctx.fillStyle = '#336699';
    ctx.fillRect(0, 0, 200, 100);
    ctx.fillRect(0, 0, 1, 1);
    document.body.appendChild(c);
  });
  assert.equal(await canvasIsBlank(page, '#blank'), true);
  await page.evaluate(() => {
    const ctx = document.getElementById('blank').getContext('2d');
    ctx.fillStyle = '#ffffff';
    ctx.fillRect(50, 20, 40, 40); // 8 % of the pixels
  });
  assert.equal(await canvasIsBlank(page, '#blank'), false);
  await page.evaluate(() => document.getElementById('blank').remove());
});

test('OrbitControls moves the camera on a mouse drag', async () => {
  const before = await page.evaluate(() => window.selftest.camera());
  await page.mouse.move(640, 400);
  await page.mouse.down();
  await page.mouse.move(760, 430, { steps: 8 });
  await page.mouse.up();
  await page.waitForFunction(() => window.selftest.frames > 0);
  const afterDrag = await page.evaluate(() => window.selftest.camera());
  assert.notDeepEqual(afterDrag, before, 'camera did not move');
  const dist = (p) => Math.hypot(...p);
  assert.ok(Math.abs(dist(afterDrag) - dist(before)) < 1e-3, 'a rotation keeps the distance');
});

test('inline base64 gzip payload decodes with DecompressionStream from file://', async (t) => {
  await page.waitForFunction(() => window.selftest.decode !== null, null, { timeout: 30_000 });
  const first = await page.evaluate(() => window.selftest.decode);
  assert.equal(first.error, undefined, first.error);
  // Once more, now that the page is idle, for a steadier timing.
  const r = await page.evaluate(() => window.selftest.decodePayload());
  for (const [label, d] of [['on load', first], ['idle', r]]) {
    t.diagnostic(
      `decode ${label}: ${d.gzipBytes} gzip bytes (${d.base64Chars} base64 chars) -> ${d.bytes} bytes in ` +
        `${d.ms.total.toFixed(1)} ms (atob+copy ${d.ms.base64.toFixed(1)}, gunzip ${d.ms.gunzip.toFixed(1)}, ` +
        `checksum ${d.ms.checksum.toFixed(1)})`,
    );
  }
  for (const d of [first, r]) {
    assert.equal(d.bytes, expected.bytes);
    assert.equal(d.gzipBytes, expected.gzipBytes);
    assert.equal(d.floats, expected.floats);
    assert.equal(d.first, expected.first);
    assert.equal(d.last, expected.last);
    assert.equal(d.checksum, expected.checksum);
  }
  assert.deepEqual(page.swarfErrors, []);
});
