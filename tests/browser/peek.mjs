// Opens a page, waits for the viewer, prints its state and saves a screenshot (a development aid,
// and how docs/viewer.md's figures were measured):
//   node tests/browser/peek.mjs PAGE.html OUT.png [MOVE|mid]
// MOVE moves the slider there first; `mid` to the simulator's reading nearest the middle.
import { launch, openPage } from './harness.mjs';
const [html, png, move] = process.argv.slice(2);
const browser = await launch();
try {
  const page = await openPage(browser, html);
  await page.waitForFunction(() => window.swarf && (window.swarf.ready || window.swarf.error), null, { timeout: 60_000 });
  const st = await page.evaluate((move) => {
    const s = window.swarf;
    if (s.error) return { error: s.error };
    if (move === 'mid') { const n = s.moves(); const m = s.removalMarks(); s.seek(m.length ? m.reduce((a, b) => (Math.abs(b - n / 2) < Math.abs(a - n / 2) ? b : a)) : n / 2); } else if (move !== undefined) s.seek(+move);
    return { readyMs: s.readyMs, moves: s.moves(), k: s.position(), removed: s.removedVolume(), sim: s.simulatorVolume(), levels: s.levels().length, marks: s.marks };
  }, move);
  await page.waitForTimeout(300);
  await page.screenshot({ path: png });
  console.log(JSON.stringify(st), page.swarfErrors);
} finally {
  await browser.close();
}
