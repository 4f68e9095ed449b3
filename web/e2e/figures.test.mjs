// End-to-end tests of what the page shows a researcher (issue 30): critical points
// simplified by persistence, and the rough edges (messages, text boxes, words, layout).
// Run by run.sh (alone: `web/e2e/run.sh web/e2e/figures.test.mjs`).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launch, writePyramidOff } from './common.mjs';

const URL = process.env.SPECTRAL_MESH_URL;
let browser, page;

before(async () => {
  assert.ok(URL, 'SPECTRAL_MESH_URL is not set: run web/e2e/run.sh');
  browser = await launch();
  page = browser.page;
  await page.goto(URL);
  await page.waitForFunction(() => (window.__fieldCount || 0) > 0, null, { timeout: 180000 });
});

after(async () => { await browser?.close(); });

const errorCount = () => page.evaluate(() => window.__errorCount || 0);
const fieldCount = () => page.evaluate(() => window.__fieldCount || 0);

async function waitError(before, timeout = 60000) {
  await page.waitForFunction((e) => (window.__errorCount || 0) > e && window.__lastError, before, { timeout });
  return page.evaluate(() => ({ msg: window.__lastError, at: window.__lastErrorFor }));
}

async function waitField(before, timeout = 180000) {
  await page.waitForFunction((b) => (window.__fieldCount || 0) > b, before, { timeout });
  return page.evaluate(() => window.__lastField.header);
}

async function setValue(id, value, event = 'change') {
  await page.evaluate(([i, v, e]) => {
    const el = document.getElementById(i);
    el.value = String(v);
    el.dispatchEvent(new Event(e, { bubbles: true }));
  }, [id, value, event]);
}

test('the heat kernel at a small t: the page shows the simplified critical points and says how many are hidden', async () => {
  let b = await fieldCount();
  await setValue('experiment', 'heat');
  await waitField(b);
  b = await fieldCount();
  await setValue('t-num', '0.005');
  const h = await waitField(b);
  const cp = h.critical;
  assert.ok(cp && cp.hidden && cp.raw, JSON.stringify(cp));
  const hidden = cp.hidden.minima + cp.hidden.maxima + cp.hidden.saddles;
  assert.ok(hidden > 0, `raw ${JSON.stringify(cp.raw)}`);
  assert.equal(cp.raw.minima - cp.hidden.minima, cp.minima);
  assert.ok(cp.holds && cp.raw.holds);
  const text = await page.textContent('#critical');
  assert.match(text, new RegExp(`${hidden} hidden: persistence below`));
  // Markers drawn: exactly the points shown.
  const m = await page.evaluate(() => window.__markers);
  assert.deepEqual([m.minimum || 0, m.maximum || 0, m.saddle || 0],
    [cp.points.minima.length, cp.points.maxima.length, cp.points.saddles.length]);
});

test('guidance does not call the source yellow (yellow is also a colour of the maps)', async () => {
  for (const e of ['heat', 'diffusion', 'distance']) {
    const b = await fieldCount();
    await setValue('experiment', e);
    await waitField(b);
    const g = await page.textContent('#guidance');
    assert.doesNotMatch(g, /yellow/i, g);
    assert.match(g, /star/, g);
  }
});

test('a k far above the mesh: the message names the number typed, and the box shows it', async () => {
  const errs = await errorCount();
  await setValue('k', 100000000);
  const e = await waitError(errs);
  assert.equal(e.at, 'k');
  assert.match(e.msg, /100000000/);
  const fits = await page.evaluate(() => { const k = document.getElementById('k'); return k.scrollWidth <= k.clientWidth; });
  assert.ok(fits, 'the k box is too narrow for 100000000');
  const b = await fieldCount();
  await setValue('k', 100);
  await waitField(b);
});

test('one error on screen at a time; a random-bytes PLY names its file once; the shape box after an upload', async () => {
  let errs = await errorCount();
  await setValue('k', 0);
  await waitError(errs);
  const junk = path.join(os.tmpdir(), 'random-e2e.ply');
  const bytes = Buffer.alloc(2000);
  for (let i = 0; i < bytes.length; i++) bytes[i] = (i * 7919 + 13) % 251;
  fs.writeFileSync(junk, bytes);
  errs = await errorCount();
  await page.setInputFiles('#file-input', junk);
  const e = await waitError(errs);
  fs.rmSync(junk);
  assert.equal(e.at, 'file-input');
  assert.equal(e.msg.split('random-e2e.ply').length - 1, 1, e.msg);
  // The k error is gone: only the latest is on screen.
  assert.equal(await page.$$eval('.ctl-error', (l) => l.length), 1);
  // An upload that works (with a valid k again: the k = 0 typed above would be refused on
  // any mesh): the shape box no longer says 3torus, and no error is left on screen.
  await page.evaluate(() => { document.getElementById('k').value = '20'; });
  const file = path.join(os.tmpdir(), 'pyramid-e2e.off');
  writePyramidOff(file);
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  await page.setInputFiles('#file-input', file);
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 30000 });
  fs.rmSync(file);
  assert.notEqual(await page.inputValue('#shape-spec'), '3torus');
  const left = await page.$$eval('.ctl-error', (l) => l.map((e) => `${e.dataset.for}: ${e.textContent}`));
  assert.equal(left.length, 0, left.join(' | '));
  // Back to the built-in shape for the next tests.
  const b = await fieldCount();
  await page.evaluate(() => { document.getElementById('shape-spec').value = '3torus'; document.getElementById('shape-load').click(); });
  await waitField(b);
});

test('at 1280 x 800 the critical-point counts, the timing line and the download buttons are on screen', async () => {
  await page.setViewportSize({ width: 1280, height: 800 });
  for (const sel of ['#critical', '#field-stats', '#downloads a[data-format="png"]', '#downloads a[data-format="toml"]']) {
    const r = await page.$eval(sel, (e) => { const b = e.getBoundingClientRect(); return { top: b.top, bottom: b.bottom, left: b.left, right: b.right, h: b.height }; });
    assert.ok(r.bottom <= 800 && r.top >= 0 && r.right <= 1280 && r.left >= 0, `${sel} at ${JSON.stringify(r)}`);
  }
  assert.match(await page.textContent('#field-stats'), /input to drawn frame \d+ ms/);
  assert.match(await page.textContent('#critical'), /minima \d+/);
});
