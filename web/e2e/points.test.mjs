// End-to-end tests of point clouds in the web app, and of the page naming itself to the
// server (X-Client-Id), in headless Chromium (run by run.sh, which starts the server and
// sets SPECTRAL_MESH_URL). The real clouds come from SPECTRAL_MESH_SHARED_POINTS (set by
// run.sh: the points folder beside the shared meshes); a generated one is always used.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launch, pageHelpers } from './common.mjs';

const URL = process.env.SPECTRAL_MESH_URL;
const POINTS = process.env.SPECTRAL_MESH_SHARED_POINTS || '';

let browser, page;
const pageErrors = [];
// Every request of the page to /api: [method, path, X-Client-Id, body].
const sent = [];
let dir;

before(async () => {
  assert.ok(URL, 'SPECTRAL_MESH_URL is not set: run web/e2e/run.sh');
  dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sm-e2e-points-'));
  browser = await launch();
  page = browser.page;
  page.on('pageerror', (e) => pageErrors.push(e.message));
  page.on('request', (r) => {
    const u = new globalThis.URL(r.url());
    if (u.pathname.startsWith('/api/')) sent.push([r.method(), u.pathname, r.headers()['x-client-id'], r.postData()]);
  });
  await page.goto(URL);
  await page.waitForFunction(() => window.__ready, null, { timeout: 30000 });
});

after(async () => {
  await browser?.close();
  if (dir) fs.rmSync(dir, { recursive: true, force: true });
});

const { count, errorCount, waitField, waitError, setValue, pickPoints } =
  pageHelpers(() => page, { fieldTimeout: 300000, errorTimeout: 120000 });




async function uploadFile(file) {
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  const before = await count();
  await page.setInputFiles('#file-input', file);
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 120000 });
  return waitField(before);
}

const health = () => page.evaluate(async () => (await fetch('/api/health')).json());

// Screen points of the canvas that hit the shape, with the vertex (point) each picks.
const shapePoints = pickPoints;

// Pixels of the 3D view that are neither the white background nor grey: the colour map.
// (The page keeps no drawing buffer after a frame is shown: it draws and reads in one task.)
const colouredPixels = () => page.evaluate(() => {
  const { w, h, data: d } = window.__viewPixels();
  let n = 0;
  for (let i = 0; i < d.length; i += 4) {
    const [r, gr, b] = [d[i], d[i + 1], d[i + 2]];
    if (Math.max(r, gr, b) - Math.min(r, gr, b) > 40) n++;
  }
  return n * (320 * 200) / (w * h); // as counted on a 320 x 200 copy before

});

// `n` points on the unit sphere (Fibonacci lattice) as .xyz text.
function writeSphereXyz(file, n) {
  const golden = Math.PI * (3 - Math.sqrt(5));
  const lines = ['# x y z'];
  for (let i = 0; i < n; i++) {
    const y = 1 - (2 * (i + 0.5)) / n, r = Math.sqrt(1 - y * y), th = golden * i;
    lines.push(`${(r * Math.cos(th)).toFixed(9)} ${y.toFixed(9)} ${(r * Math.sin(th)).toFixed(9)}`);
  }
  fs.writeFileSync(file, lines.join('\n') + '\n');
  return file;
}

test('the page names itself: one random X-Client-Id per tab on every request', async () => {
  await page.waitForFunction(() => (window.__fieldCount || 0) >= 1, null, { timeout: 300000 }); // the first screen
  const api = sent.filter(([, p]) => p.startsWith('/api/'));
  assert.ok(api.length >= 4, `${api.length} requests`);
  const ids = new Set(api.map(([, , id]) => id));
  assert.equal(ids.size, 1, `ids: ${[...ids]}`);
  const [id] = ids;
  assert.match(id, /^page-[0-9a-f]{24}$/);
  assert.equal(id, await page.evaluate(() => window.__clientId));
  // Another tab has another id.
  const other = await page.context().newPage();
  await other.goto(URL);
  await other.waitForFunction(() => window.__ready, null, { timeout: 30000 });
  const id2 = await other.evaluate(() => window.__clientId);
  await other.close();
  assert.notEqual(id2, id);
});

test('two quick basis requests for different k: the first is cancelled, the second drawn', async () => {
  const h0 = await health();
  const first = page.waitForRequest((r) => r.url().endsWith('/basis') && r.method() === 'POST'
    && JSON.parse(r.postData() || '{}').k === 420, { timeout: 60000 });
  // Values of k no earlier test file asks for on the default shape (the figures tests hold
  // a k = 200 basis in the server's cache, which answered the first request at once), the
  // second larger than the first (a smaller one is served by the running job).
  const before = await setValue('k', 420);
  await first;
  // As soon as the page has asked for k = 420: ask for k = 480.
  await setValue('k', 480);
  const f = await waitField(before);
  assert.equal(f.header.k, 480);
  const h1 = await health();
  assert.ok(h1.jobs_superseded >= h0.jobs_superseded + 1, `superseded ${h0.jobs_superseded} -> ${h1.jobs_superseded}; before ${JSON.stringify(h0)}; after ${JSON.stringify(h1)}`);
  assert.ok(h1.jobs_cancelled >= h0.jobs_cancelled + 1);
  // Both requests named the same page.
  const posts = sent.filter(([m, p]) => m === 'POST' && p.endsWith('/basis'));
  const ks = posts.map(([, , , b]) => JSON.parse(b).k);
  assert.ok(ks.includes(420) && ks.includes(480), `basis requests: ${ks}`);
  assert.equal(new Set(posts.map(([, , id]) => id)).size, 1);
  const b = await setValue('k', 100);
  await waitField(b);
});

test('a point file is drawn as a coloured cloud and the page says "point cloud"', async () => {
  let before = await setValue('experiment', 'heat');
  await waitField(before);
  const file = writeSphereXyz(path.join(dir, 'sphere2000.xyz'), 2000);
  const f = await uploadFile(file);
  assert.equal(f.header.n, 2000);
  assert.equal(f.header.point_cloud, true);
  assert.equal(f.header.laplacian, 'robust');
  assert.ok(f.header.point_spacing > 0.01 && f.header.point_spacing < 0.2, `${f.header.point_spacing}`);
  assert.match(await page.textContent('#input-kind'), /point cloud/);
  assert.match(await page.textContent('#input-kind'), /robust/);
  assert.match(await page.textContent('#info'), /point cloud: 2000 points/);
  assert.match(await page.textContent('#colorbar-units'), /point cloud/);
  assert.equal(await page.inputValue('#laplacian'), 'robust');
  assert.equal(await page.$eval('#laplacian option[value="fem"]', (o) => o.disabled), true);
  assert.equal(await page.evaluate(() => window.__app.isCloud), true);
  // Drawn: the splats carry the colour map, the level sets are the library's segments.
  assert.ok(await colouredPixels() > 2000, 'the cloud is not drawn in colour');
  assert.ok(await page.evaluate(() => window.__levelSegments) > 10);
  assert.equal(await page.evaluate(() => window.__markers.source), 1);
  // The values are the library's (the full-precision download of the same request).
  const r = await page.evaluate(async () => {
    const res = await fetch(window.__downloadUrl('txt'), { headers: { 'X-Client-Id': window.__clientId } });
    return { ok: res.ok, text: await res.text(), page: Array.from(window.__lastField.values) };
  });
  assert.ok(r.ok, r.text);
  const lib = r.text.trim().split('\n').map(Number);
  assert.equal(lib.length, 2000);
  const scale = Math.max(...lib.map(Math.abs));
  assert.ok(lib.every((v, i) => Math.abs(v - r.page[i]) <= 1e-6 * scale));
  // A click on the cloud moves the anchor to the point under the cursor.
  const pts = await shapePoints();
  assert.ok(pts.length > 5, 'the cloud is on screen');
  const target = pts[Math.floor(pts.length / 2)];
  before = await count();
  await page.mouse.click(target.x, target.y);
  const g = await waitField(before);
  assert.equal(g.header.source, target.v);
  assert.equal(Number(await page.inputValue('#source')), target.v);
  // The levels slider asks the server for that many level sets.
  before = await setValue('levels', 4, 'input');
  const l = await waitField(before);
  assert.equal(l.header.levels.length, 4);
});

test('a real point cloud from the shared folder', async (t) => {
  const file = path.join(POINTS, 'kitten.xyz');
  if (!fs.existsSync(file)) {
    t.skip(`no shared point clouds in ${POINTS} (SPECTRAL_MESH_SHARED_POINTS)`);
    return;
  }
  const f = await uploadFile(file);
  assert.equal(f.header.n, 5210);
  assert.equal(f.header.point_cloud, true);
  assert.match(await page.textContent('#info'), /kitten\.xyz/);
  assert.match(await page.textContent('#input-kind'), /point cloud \(5210 points\)/);
  assert.ok(await colouredPixels() > 2000);
});

test('refused on a cloud: collinear points by the file control, a triangle Laplacian by its control', async () => {
  const line = path.join(dir, 'line.xyz');
  fs.writeFileSync(line, Array.from({ length: 30 }, (_, i) => `${i} 0 0`).join('\n') + '\n');
  let errs = await errorCount();
  await page.setInputFiles('#file-input', line);
  let e = await waitError(errs);
  assert.equal(e.at, 'file-input');
  assert.match(await page.textContent('.ctl-error[data-for="file-input"]'), /line\.xyz.*collinear/s);
  // The cloud still loaded: force fem (the page disables it; a script can still pick it).
  errs = await errorCount();
  await page.evaluate(() => {
    const s = document.getElementById('laplacian');
    s.value = 'fem';
    s.dispatchEvent(new Event('change', { bubbles: true }));
  });
  e = await waitError(errs);
  assert.equal(e.at, 'laplacian');
  const msg = await page.textContent('.ctl-error[data-for="laplacian"]');
  assert.match(msg, /point cloud/);
  assert.match(msg, /needs triangles/);
  assert.equal(await page.isVisible('#stale'), true);
  const before = await setValue('laplacian', 'robust');
  await waitField(before);
  assert.equal(await page.$('.ctl-error'), null);
});

test('back to a mesh: every Laplacian again, the mesh choice restored', async () => {
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  const before = await count();
  await page.evaluate(() => {
    document.getElementById('shape-spec').value = 'sphere:res=3';
    document.getElementById('shape-load').click();
  });
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 60000 });
  const f = await waitField(before);
  assert.equal(f.header.point_cloud, false);
  assert.equal(f.header.laplacian, 'fem');
  assert.equal(await page.inputValue('#laplacian'), 'fem');
  assert.equal(await page.$eval('#laplacian option[value="fem"]', (o) => o.disabled), false);
  assert.match(await page.textContent('#input-kind'), /triangle mesh/);
  assert.deepEqual(pageErrors, []);
});
