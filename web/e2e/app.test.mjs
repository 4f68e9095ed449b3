// End-to-end tests of the spectral-mesh web app in headless Chromium (run by run.sh, which
// starts the server and sets SPECTRAL_MESH_URL).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { chromium } from 'playwright-core';

const URL = process.env.SPECTRAL_MESH_URL;
const SHARED = process.env.SPECTRAL_MESH_SHARED_MESHES || '';
const SHOT = process.env.SPECTRAL_MESH_SCREENSHOT || '';
const BENCH = process.env.SPECTRAL_MESH_WEB_BENCH === '1';

let context, page, userDir;
const pageErrors = [];

before(async () => {
  assert.ok(URL, 'SPECTRAL_MESH_URL is not set: run web/e2e/run.sh');
  userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'sm-chromium-'));
  // A fresh profile folder every run (playwright passes it as --user-data-dir).
  context = await chromium.launchPersistentContext(userDir, {
    executablePath: '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
    viewport: { width: 1280, height: 800 },
    acceptDownloads: true,
  });
  page = context.pages()[0] || await context.newPage();
  page.on('pageerror', (e) => pageErrors.push(e.message));
  await page.goto(URL);
});

after(async () => {
  await context?.close();
  if (userDir) fs.rmSync(userDir, { recursive: true, force: true });
});

const count = () => page.evaluate(() => window.__fieldCount || 0);
const lastError = () => page.evaluate(() => window.__lastError);

async function waitField(before, timeout = 120000) {
  await page.waitForFunction((b) => (window.__fieldCount || 0) > b || ((window.__errorCount || 0) > 0 && window.__lastError),
    before, { timeout });
  const err = await lastError();
  assert.equal(err, null, `page shows an error: ${err}`);
  return page.evaluate(() => window.__lastField);
}

async function setValue(id, value, event = 'change') {
  const before = await count();
  await page.evaluate(([i, v, e]) => {
    const el = document.getElementById(i);
    el.value = String(v);
    el.dispatchEvent(new Event(e, { bubbles: true }));
  }, [id, value, event]);
  return before;
}

// The values the page shows, against the server's own f64 computation for the same
// parameters (the txt download goes through the library's code path, not the page's).
async function checkAgainstLibrary() {
  const r = await page.evaluate(async () => {
    const res = await fetch(window.__downloadUrl('txt'));
    return { ok: res.ok, text: await res.text(), page: window.__lastField.values };
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

test('loads the default built-in shape and shows a field', async () => {
  await page.waitForFunction(() => window.__ready, null, { timeout: 30000 });
  const f = await waitField(0);
  assert.equal(f.header.kind, 'heat');
  // Nothing clicked yet: the library's default anchor (the vertex of largest x).
  assert.equal(await page.inputValue('#source'), '');
  assert.equal(typeof f.header.source, 'number');
  assert.equal(f.header.normalized, true);
  assert.equal(f.values.length, f.header.n);
  assert.ok(f.values.every(Number.isFinite));
  const info = await page.textContent('#info');
  assert.match(info, /vertices 642/);
  assert.match(await page.textContent('#critical'), /✓/);
  await checkAgainstLibrary();
});

test('clicking the surface moves the source and the heat peak follows', async () => {
  const box = await page.locator('#view canvas').boundingBox();
  const before = await count();
  await page.mouse.click(box.x + box.width / 2 + 40, box.y + box.height / 2 - 30);
  const f = await waitField(before);
  const src = Number(await page.inputValue('#source'));
  assert.equal(f.header.source, src);
  assert.equal(f.header.request.anchor, src);
  let argmax = 0;
  f.values.forEach((v, i) => { if (v > f.values[argmax]) argmax = i; });
  assert.equal(argmax, src, 'the heat kernel peaks at the clicked anchor');
});

test('changing t changes the field (the kernel spreads)', async () => {
  const f0 = await page.evaluate(() => window.__lastField);
  const before = await setValue('t', -1.5, 'input');
  const f1 = await waitField(before);
  assert.ok(f1.params.t > f0.params.t);
  assert.ok(f1.header.max < f0.header.max, 'a longer time lowers the peak');
  await checkAgainstLibrary();
});

test('switching experiment, filter and Laplacian recomputes from the right basis', async () => {
  let before = await setValue('experiment', 'distance');
  let f = await waitField(before);
  assert.equal(f.header.kind, 'distance');
  assert.equal(f.values[f.header.source], 0);
  before = await setValue('filter', 'commute');
  f = await waitField(before);
  assert.equal(f.params.filter, 'commute');
  before = await setValue('laplacian', 'voronoi-cot');
  f = await waitField(before);
  assert.equal(f.header.laplacian, 'voronoi-cot');
  await checkAgainstLibrary();
  // A custom expression that does not parse: the page shows the server's message.
  await page.evaluate(() => { document.getElementById('filter').value = 'custom'; });
  const errs = await page.evaluate(() => window.__errorCount || 0);
  await setValue('custom', 'exp(-t*');
  await page.waitForFunction((e) => (window.__errorCount || 0) > e, errs, { timeout: 30000 });
  assert.match(await page.textContent('#error'), /expression error/);
  before = await setValue('custom', '1/s');
  f = await waitField(before);
  assert.equal(f.params.custom, '1/s');
});

test('uploads a shared mesh, then a broken file shows its error', async (t) => {
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
  assert.match(await page.textContent('#info'), /sphere966\.off/);
  assert.match(await page.textContent("#info"), /vertices 926/);

  const broken = path.join(os.tmpdir(), 'broken-e2e.off');
  fs.writeFileSync(broken, 'OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n');
  await page.setInputFiles('#file-input', broken);
  await page.waitForFunction(() => document.getElementById('error').classList.contains('shown'), null, { timeout: 30000 });
  const msg = await page.textContent('#error');
  assert.match(msg, /broken-e2e\.off/);
  fs.rmSync(broken);
  // The app still works afterwards.
  const b2 = await setValue('t', -1, 'input');
  await waitField(b2);
});

test('downloads the picture, the field and the experiment file', async () => {
  for (const [format, check] of [
    ['png', (b) => b.subarray(0, 4).equals(Buffer.from([0x89, 0x50, 0x4e, 0x47]))],
    ['wrl', (b) => b.toString('utf8', 0, 15) === '#VRML V2.0 utf8'],
    ['txt', (b) => b.toString().trim().split('\n').every((l) => Number.isFinite(Number(l)))],
    ['toml', (b) => /experiment = "field"/.test(b.toString()) && /kind = "distance"/.test(b.toString())
      && /laplacian = "voronoi-cot"/.test(b.toString()) && /mesh_hash = "[0-9a-f]{64}"/.test(b.toString())],
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
});

test('harmonic map on the 3-torus: Euler check holds; screenshot', async () => {
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  await page.evaluate(() => {
    document.getElementById('experiment').value = 'harmonic';
    document.getElementById('constraints').value = '6';
    document.getElementById('levels').value = '16';
    document.getElementById('colormap').value = 'hue';
    document.getElementById('shape-spec').value = '3torus';
    document.getElementById('shape-load').click();
  });
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 60000 });
  await page.waitForFunction(() => window.__lastField && window.__lastField.header.kind === 'harmonic'
    && window.__lastField.params.constraints === '6', null, { timeout: 60000 });
  const f = await page.evaluate(() => window.__lastField);
  assert.equal(f.header.critical.holds, true);
  assert.equal(f.header.critical.chi, -4);
  assert.equal(f.header.levels.length, 16);
  await checkAgainstLibrary();
  if (SHOT) {
    fs.mkdirSync(path.dirname(SHOT), { recursive: true });
    await page.screenshot({ path: SHOT });
  }
  assert.deepEqual(pageErrors, []);
});

test('benchmark: input-to-picture on a ~100k-vertex mesh with k = 200', { skip: !BENCH }, async () => {
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  const t0 = Date.now();
  await page.evaluate(() => {
    document.getElementById('experiment').value = 'heat';
    document.getElementById('laplacian').value = 'fem';
    document.getElementById('k').value = '200';
    document.getElementById('levels').value = '10';
    document.getElementById('shape-spec').value = 'torus:res=5';
    document.getElementById('shape-load').click();
  });
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 60000 });
  await page.waitForFunction(() => window.__lastField && window.__lastField.header.k === 200
    && window.__lastField.header.n > 90000, null, { timeout: 1800000 });
  const basisSeconds = (Date.now() - t0) / 1000;
  const n = await page.evaluate(() => window.__lastField.header.n);
  const times = { t: [], source: [], filter: [] };
  for (let i = 0; i < 8; i++) {
    let b = await setValue('t', -2 + 0.2 * i, 'input');
    times.t.push((await waitField(b)).timing);
    b = await setValue('source', 1000 * (i + 1));
    times.source.push((await waitField(b)).timing);
  }
  await setValue('experiment', 'distance');
  for (const filter of ['biharmonic', 'commute', 'diffusion', 'mix', 'biharmonic', 'commute', 'diffusion', 'mix']) {
    const b = await setValue('filter', filter);
    times.filter.push((await waitField(b)).timing);
  }
  const cm = await page.evaluate(() => {
    const t0 = performance.now();
    const el = document.getElementById('colormap');
    el.value = 'viridis'; el.dispatchEvent(new Event('change'));
    return performance.now() - t0;
  });
  const med = (a) => { const s = a.map((x) => x.total_ms).sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };
  const medServer = (a) => { const s = a.map((x) => x.server_ms).sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };
  const report = {
    n, k: 200, basis_seconds_incl_load: basisSeconds,
    t_slider_median_ms: med(times.t), t_slider_server_ms: medServer(times.t),
    source_click_median_ms: med(times.source), source_server_ms: medServer(times.source),
    filter_switch_median_ms: med(times.filter), filter_server_ms: medServer(times.filter),
    colormap_switch_ms: cm,
  };
  console.log('BENCH ' + JSON.stringify(report));
});
