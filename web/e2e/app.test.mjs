// End-to-end tests of the spectral-mesh web app in headless Chromium (run by run.sh, which
// starts the server and sets SPECTRAL_MESH_URL).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openPage, pageHelpers, writeTorusOff, writePyramidOff } from './common.mjs';

const SHARED = process.env.SPECTRAL_MESH_SHARED_MESHES || '';
const SHOT = process.env.SPECTRAL_MESH_SCREENSHOT || '';
const BENCH = process.env.SPECTRAL_MESH_WEB_BENCH === '1';

let page;
const pageErrors = [];

openPage((p) => {
  page = p;
  page.on('pageerror', (e) => pageErrors.push(e.message));
}, { firstField: false });

// Fields drawn so far; also notes the errors shown so far, so that waitField sees only
// the new ones.
const { count, errorCount, waitField, waitError, setValue, pickPoints, clickSource } =
  pageHelpers(() => page, { fieldTimeout: 180000, errorTimeout: 60000 });
const lastError = () => page.evaluate(() => window.__lastError);
const lastField = () => page.evaluate(() => window.__lastFieldPlain());




// The values the page shows, against the server's own f64 computation for the same
// parameters (the txt download goes through the library's code path, not the page's).
async function checkAgainstLibrary() {
  const r = await page.evaluate(async () => {
    const res = await fetch(window.__downloadUrl('txt'));
    return { ok: res.ok, text: await res.text(), page: Array.from(window.__lastField.values) };
  });
  assert.ok(r.ok, r.text);
  const lib = r.text.trim().split('\n').map(Number);
  assert.equal(lib.length, r.page.length);
  const scale = Math.max(...lib.map(Math.abs), 1e-300);
  let worst = 0;
  for (let i = 0; i < lib.length; i++) worst = Math.max(worst, Math.abs(lib[i] - r.page[i]) / scale);
  assert.ok(worst < 1e-6, `page values differ from the library's by ${worst} (relative to max)`);
  return lib;
}

// Screen points of the canvas that hit the surface, with the vertex each picks.
const surfacePoints = pickPoints;

test('the first screen explains itself: field, colour bar, legend, guidance, visible source', async () => {
  await page.waitForFunction(() => window.__ready, null, { timeout: 30000 });
  const f = await waitField(0);
  assert.equal(f.header.kind, 'distance');
  assert.equal(f.header.request.distance, 'biharmonic');
  assert.match(await page.textContent('#info'), /3torus/);
  assert.match(await page.textContent('#guidance'), /click the surface/i);
  assert.match(await page.textContent('#intro'), /click the surface/i);
  // Colour bar: the quantity, the values (min at the source: 0), the units.
  assert.match(await page.textContent('#colorbar-title'), /distance/);
  const ticks = await page.$$eval('#colorbar-ticks span', (s) => s.map((e) => e.textContent));
  assert.equal(ticks.length, 3);
  assert.equal(Number(ticks[0]), 0);
  assert.ok(Math.abs(Number(ticks[2]) - f.header.max) <= 1e-3 * f.header.max, `${ticks} vs ${f.header.max}`);
  assert.match(await page.textContent('#colorbar-units'), /unit area/);
  // Legend: the marker kinds drawn (the figure's description) and the level-set line.
  const legend = await page.textContent('#legend');
  for (const w of ['source', 'maximum', 'minimum', 'level set']) assert.match(legend, new RegExp(w));
  assert.doesNotMatch(legend, /constraint/);
  // The source marker is drawn and the source is on the visible side: the surface point
  // under its marker is the source itself (or right beside it).
  assert.equal(await page.evaluate(() => window.__markers.source), 1);
  const seen = await page.evaluate((s) => {
    const [x, y] = window.__screenOf(s);
    const v = window.__vertexAt(x, y);
    if (v === null) return Infinity;
    const p = window.__app.positions;
    return Math.hypot(p[3 * v] - p[3 * s], p[3 * v + 1] - p[3 * s + 1], p[3 * v + 2] - p[3 * s + 2]) / window.__app.radius;
  }, f.header.source);
  assert.ok(seen < 0.03, `the source is hidden (the visible point is ${seen} radii away)`);
  assert.match(await page.textContent('#critical'), /✓/);
  assert.match(await page.textContent('#k-used'), /k used 100/);
  await checkAgainstLibrary();
  if (SHOT) {
    fs.mkdirSync(path.dirname(SHOT), { recursive: true });
    await page.screenshot({ path: SHOT });
  }
});

test('colour map and level changes are drawn without a request', async () => {
  const before = await count();
  const views = await page.evaluate(() => window.__viewCount || 0);
  await page.selectOption('#colormap', 'turbo');
  await page.evaluate(() => { const l = document.getElementById('levels'); l.value = '20'; l.dispatchEvent(new Event('input')); });
  await page.waitForFunction((v) => (window.__viewCount || 0) >= v + 2, views);
  assert.equal(await count(), before, 'a view change sent a field request');
  assert.match(await page.textContent('#colorbar-units'), /20 level sets/);
  await page.selectOption('#colormap', 'viridis');
});

test('clicking the surface moves the heat anchor and the peak follows; t spreads it', async () => {
  let before = await setValue('experiment', 'heat');
  let f = await waitField(before);
  assert.ok(f.header.truncation, 'heat fields carry the truncation hint');
  // t = 1e-4 with k = 100 on the 3-torus: truncation dominates, and the page says so.
  before = await setValue('t-num', '1e-4');
  f = await waitField(before);
  assert.equal(f.header.truncation.warning, true);
  assert.match(await page.textContent('#truncation'), /truncation dominates/);
  assert.match(await page.getAttribute('#truncation', 'class'), /warn/);
  // t = 0.01: the first omitted pair weighs little.
  before = await setValue('t', -2, 'input');
  f = await waitField(before);
  assert.equal(f.header.truncation.warning, false);
  assert.match(await page.textContent('#truncation'), /first omitted pair/);
  const clicked = await clickSource(1 / 3);
  f = clicked.f;
  const { src } = clicked;
  // The heat is concentrated around the clicked anchor (on a shape of varying curvature
  // the kernel's largest value need not be at the anchor itself).
  assert.ok(f.values[src] >= 0.5 * f.header.max, `k_t(a, a) = ${f.values[src]}, max ${f.header.max}`);
  assert.ok(f.values[src] > 20 * Math.max(f.header.min, 1e-300), 'the anchor is far above the coldest point');
  before = await setValue('t', -0.5, 'input');
  const f1 = await waitField(before);
  assert.ok(f1.params.t > f.params.t);
  assert.ok(f1.header.max < f.header.max, 'a longer time lowers the peak');
  await checkAgainstLibrary();
});

test('t = 1e12: a constant field, no critical points reported', async () => {
  const before = await setValue('t-num', '1e12');
  const f = await waitField(before);
  assert.equal(f.params.t, 1e12);
  const cp = f.header.critical;
  assert.equal(cp.flat, true);
  assert.deepEqual([cp.minima, cp.maxima, cp.saddles], [0, 0, 0]);
  assert.equal(await page.evaluate(() => (window.__markers.minimum || 0) + (window.__markers.maximum || 0) + (window.__markers.saddle || 0)), 0);
  assert.match(await page.textContent('#critical'), /constant field/);
  const b = await setValue('t', -2, 'input');
  await waitField(b);
});

test('a refused request: the message sits next to its control, the picture is marked stale', async () => {
  let errs = await errorCount();
  await setValue('k', 0);
  let e = await waitError(errs);
  assert.equal(e.at, 'k');
  assert.match(await page.textContent('.ctl-error[data-for="k"]'), /k must be/);
  assert.equal(await page.isVisible('.ctl-error[data-for="k"]'), true);
  assert.equal(await page.isVisible('#stale'), true);
  // The error box is right below the k control's row.
  const near = await page.evaluate(() => document.getElementById('k').closest('.row').nextElementSibling.dataset.for);
  assert.equal(near, 'k');
  let before = await setValue('k', 100);
  await waitField(before);
  assert.equal(await page.isVisible('#stale'), false);
  assert.equal(await page.$('.ctl-error'), null);
  // A custom filter expression that does not parse: next to the expression.
  before = await setValue('experiment', 'distance');
  await waitField(before);
  await page.evaluate(() => { document.getElementById('filter').value = 'custom'; });
  errs = await errorCount();
  await setValue('custom', 'exp(-t*');
  e = await waitError(errs);
  assert.equal(e.at, 'custom');
  assert.match(await page.textContent('.ctl-error[data-for="custom"]'), /expression/);
  before = await setValue('custom', '1/s');
  const f = await waitField(before);
  assert.equal(f.params.custom, '1/s');
  before = await setValue('filter', 'biharmonic');
  await waitField(before);
});

test('harmonic mode: two clicks make two removable constraints and a correct map', async () => {
  let before = await setValue('experiment', 'harmonic');
  let f = await waitField(before);
  assert.equal(f.header.constraints.length, 2, 'the preset: 2 constraints');
  assert.equal(await page.evaluate(() => window.__markers.constraint), 2);
  assert.equal(await page.$$eval('#constraint-list li:not(.hint)', (l) => l.length), 2);
  await page.click('#constraints-clear');
  await page.waitForFunction(() => /click two vertices/.test(document.getElementById('constraint-list').textContent));
  const pts = await surfacePoints();
  // Two far-apart visible vertices.
  const a = pts[0];
  const b = pts.reduce((best, p) => (Math.hypot(p.x - a.x, p.y - a.y) > Math.hypot(best.x - a.x, best.y - a.y) ? p : best), pts[1]);
  assert.notEqual(a.v, b.v);
  await page.mouse.click(a.x, a.y);
  await page.waitForFunction(() => /another vertex/.test(document.getElementById('constraint-list').textContent));
  before = await count();
  await page.mouse.click(b.x, b.y);
  f = await waitField(before);
  assert.deepEqual(f.header.constraints.map((c) => [c.vertex, c.value]), [[a.v, 0], [b.v, 1]]);
  assert.equal(await page.evaluate(() => window.__markers.constraint), 2);
  // The map: the constrained values, and between them (maximum principle).
  assert.ok(Math.abs(f.values[a.v]) < 1e-6 && Math.abs(f.values[b.v] - 1) < 1e-6);
  assert.ok(f.values.every((v) => v > -1e-6 && v < 1 + 1e-6));
  assert.equal(f.header.critical.holds, true);
  assert.equal(f.header.critical.chi, -4);
  await checkAgainstLibrary();
  // Remove the first: one left, the page asks for another click and sends nothing.
  const n = await count();
  await page.click('#constraint-list li button[data-index="0"]');
  // Its marker goes at once, not with the next map (there is none: one constraint left).
  assert.equal(await page.evaluate(() => window.__markers.constraint), 1);
  await page.waitForFunction(() => /another vertex/.test(document.getElementById('constraint-list').textContent));
  assert.equal(await page.$$eval('#constraint-list li:not(.hint)', (l) => l.length), 1);
  assert.equal(await count(), n);
});

test('k per mesh: a 5-vertex upload, then a 10k-vertex one computed with the requested k', async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sm-e2e-'));
  try {
    let before = await setValue('experiment', 'heat');
    await waitField(before);
    const small = writePyramidOff(path.join(dir, 'pyramid.off'));
    let loaded = await page.evaluate(() => window.__meshLoaded || 0);
    before = await count();
    await page.setInputFiles('#file-input', small);
    await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 30000 });
    let f = await waitField(before);
    assert.equal(f.header.n, 5);
    assert.equal(f.header.k, 5);
    assert.match(await page.textContent('#k-used'), /k used 5 .*5 vertices, 100 requested/);
    assert.equal(await page.inputValue('#k'), '100', 'the request is kept');
    assert.match(await page.$eval('#shape-select', (s) => s.selectedOptions[0].textContent), /pyramid\.off/);
    const big = writeTorusOff(path.join(dir, 'torus10k.off'), 100, 100);
    loaded = await page.evaluate(() => window.__meshLoaded || 0);
    before = await count();
    await page.setInputFiles('#file-input', big);
    await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 30000 });
    f = await waitField(before);
    assert.equal(f.header.n, 10000);
    assert.equal(f.header.k, 100);
    assert.match(await page.textContent('#k-used'), /^k used 100/);
    assert.match(await page.textContent('#info'), /torus10k\.off/);
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('uploads a shared mesh, then a broken file shows its error by the file control', async (t) => {
  const file = path.join(SHARED, 'sphere966.off');
  if (!SHARED || !fs.existsSync(file)) {
    t.skip(`no shared meshes (SPECTRAL_MESH_SHARED_MESHES=${SHARED})`);
    return;
  }
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  const before = await count();
  await page.setInputFiles('#file-input', file);
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 30000 });
  const f = await waitField(before);
  assert.equal(f.values.length, 926); // the file has 926 vertices despite its name
  assert.match(await page.textContent('#info'), /vertices 926/);

  const broken = path.join(os.tmpdir(), 'broken-e2e.off');
  fs.writeFileSync(broken, 'OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n');
  const errs = await errorCount();
  await page.setInputFiles('#file-input', broken);
  const e = await waitError(errs);
  assert.equal(e.at, 'file-input');
  assert.match(await page.textContent('.ctl-error[data-for="file-input"]'), /broken-e2e\.off/);
  fs.rmSync(broken);
  // The app still works afterwards.
  const b2 = await setValue('t', -1, 'input');
  await waitField(b2);
});

test('downloads the picture, the field and the experiment file', async () => {
  const before = await setValue('experiment', 'distance');
  await waitField(before);
  for (const [format, check] of [
    ['png', (b) => b.subarray(0, 4).equals(Buffer.from([0x89, 0x50, 0x4e, 0x47]))],
    ['wrl', (b) => b.toString('utf8', 0, 15) === '#VRML V2.0 utf8'],
    ['txt', (b) => b.toString().trim().split('\n').every((l) => Number.isFinite(Number(l)))],
    ['toml', (b) => /experiment = "field"/.test(b.toString()) && /kind = "distance"/.test(b.toString())
      && /mesh_hash = "[0-9a-f]{64}"/.test(b.toString())],
  ]) {
    const [dl] = await Promise.all([
      page.waitForEvent('download', { timeout: 60000 }),
      page.click(`#downloads a[data-format="${format}"]`),
    ]);
    assert.ok(dl.suggestedFilename().endsWith(`.${format}`), dl.suggestedFilename());
    const p = await dl.path();
    const buf = fs.readFileSync(p);
    assert.ok(buf.length > 0 && check(buf), `bad ${format} download`);
  }
  assert.deepEqual(pageErrors, []);
});

const median = (a) => { const s = [...a].sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };

test('benchmark: input-to-frame latency on a ~100k-vertex mesh with k = 200', { skip: !BENCH }, async () => {
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  const t0 = Date.now();
  await page.evaluate(() => {
    document.getElementById('experiment').value = 'heat';
    document.getElementById('laplacian').value = 'fem';
    document.getElementById('k').value = '200';
    document.getElementById('shape-spec').value = 'torus:res=5';
    document.getElementById('shape-load').click();
  });
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 60000 });
  await page.waitForFunction(() => window.__lastField && window.__lastField.header.k === 200
    && window.__lastField.header.n > 90000, null, { timeout: 3600000 });
  const basisSeconds = (Date.now() - t0) / 1000;
  const n = await page.evaluate(() => window.__lastField.header.n);
  const N = 20;
  const times = { t: [], source: [], filter: [], colormap: [], levels: [] };
  const timing = () => page.evaluate(() => window.__lastField.timing);
  const lastView = () => page.evaluate(() => window.__timings[window.__timings.length - 1]);
  for (let i = 0; i < N; i++) {
    const b = await setValue('t', -2 + 0.05 * i, 'input');
    await waitField(b);
    times.t.push(await timing());
  }
  const pts = await surfacePoints();
  for (let i = 0; i < N; i++) {
    const p = pts[(i * 7) % pts.length];
    const b = await count();
    await page.mouse.click(p.x, p.y);
    await waitField(b);
    times.source.push(await timing());
  }
  let b = await setValue('experiment', 'distance');
  await waitField(b);
  const filters = ['commute', 'biharmonic', 'diffusion', 'mix'];
  for (let i = 0; i < N; i++) {
    b = await setValue('filter', filters[i % 4]);
    await waitField(b);
    times.filter.push(await timing());
  }
  const maps = ['turbo', 'viridis', 'diverging', 'hue'];
  for (let i = 0; i < N; i++) {
    const v = await page.evaluate(() => window.__viewCount || 0);
    await page.selectOption('#colormap', maps[i % 4]);
    await page.waitForFunction((c) => (window.__viewCount || 0) > c, v);
    times.colormap.push(await lastView());
  }
  for (let i = 0; i < N; i++) {
    const v = await page.evaluate(() => window.__viewCount || 0);
    await page.evaluate((x) => { const l = document.getElementById('levels'); l.value = String(x); l.dispatchEvent(new Event('input')); }, 5 + i);
    await page.waitForFunction((c) => (window.__viewCount || 0) > c, v);
    times.levels.push(await lastView());
  }
  // 20 quick slider moves: the time until the last value is drawn.
  b = await setValue('experiment', 'heat');
  await waitField(b);
  const settle = await page.evaluate(async () => {
    const t = document.getElementById('t');
    const start = performance.now();
    for (let i = 0; i < 20; i++) { t.value = String(-2 + 0.03 * i); t.dispatchEvent(new Event('input')); await new Promise((r) => setTimeout(r, 10)); }
    const want = Math.pow(10, -2 + 0.03 * 19);
    while (!(window.__lastField && Math.abs(window.__lastField.params.t - want) < 1e-12 * want)) await new Promise((r) => setTimeout(r, 5));
    return performance.now() - start;
  });
  const report = { n, k: 200, moves: N, basis_seconds_incl_load: basisSeconds, settle_20_quick_moves_ms: settle };
  for (const [k, v] of Object.entries(times)) {
    report[`${k}_input_to_frame_median_ms`] = median(v.map((x) => x.total_ms));
    report[`${k}_server_median_ms`] = median(v.map((x) => x.server_ms));
  }
  console.log('BENCH ' + JSON.stringify(report));
});
