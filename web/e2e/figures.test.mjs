// End-to-end tests of what the page shows a researcher (issue 30): critical points
// simplified by persistence, and the rough edges (messages, text boxes, words, layout).
// Run by run.sh (alone: `web/e2e/run.sh web/e2e/figures.test.mjs`).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { decodePng, loadHeat, openPage, writePyramidOff } from './common.mjs';

const BENCH = process.env.SPECTRAL_MESH_WEB_BENCH === '1';
let page;
openPage((p) => { page = p; });

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

// ---------- one figure: the downloaded PNG is the picture on screen ----------

const hexRgb = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
const near = (img, i, c, tol) => Math.abs(img.data[i] - c[0]) <= tol && Math.abs(img.data[i + 1] - c[1]) <= tol
  && Math.abs(img.data[i + 2] - c[2]) <= tol;

// Connected groups (8-neighbours) of pixels within `tol` of `fill` outside the masked
// rectangles, of at least `minArea` pixels, each classified by its shape: a triangle's
// centroid sits towards its base; a diamond is symmetric; a star fills little of its box.
function markerBlobs(img, fill, masked, tol = 14, minArea = 18) {
  const { width: w, height: h } = img;
  const seen = new Uint8Array(w * h);
  const blobs = [];
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const k = y * w + x;
      if (seen[k] || masked(x, y) || !near(img, 4 * k, fill, tol)) continue;
      const stack = [k]; seen[k] = 1;
      let n = 0, sy = 0, x0 = x, x1 = x, y0 = y, y1 = y;
      while (stack.length) {
        const q = stack.pop(); const qx = q % w, qy = (q - qx) / w;
        n++; sy += qy; x0 = Math.min(x0, qx); x1 = Math.max(x1, qx); y0 = Math.min(y0, qy); y1 = Math.max(y1, qy);
        for (let dy = -1; dy <= 1; dy++) for (let dx = -1; dx <= 1; dx++) {
          const nx = qx + dx, ny = qy + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const r = ny * w + nx;
          if (!seen[r] && !masked(nx, ny) && near(img, 4 * r, fill, tol)) { seen[r] = 1; stack.push(r); }
        }
      }
      if (n < minArea) continue;
      const bh = y1 - y0 + 1, bw = x1 - x0 + 1;
      const off = (sy / n - (y0 + y1) / 2) / bh;
      const ratio = n / (bw * bh);
      const shape = ratio > 0.8 ? 'square' : off > 0.07 ? 'triangle-up' : off < -0.07 ? 'triangle-down' : ratio < 0.42 ? 'star' : 'diamond';
      blobs.push({ x: (x0 + x1) / 2, y: (y0 + y1) / 2, n, shape });
    }
  }
  return blobs;
}

test('the PNG download is the picture on screen: camera, colours, marker shapes, legend and colour bar', async () => {
  // A field with minima, maxima and saddles, seen from a camera turned by hand.
  let b = await fieldCount();
  await setValue('experiment', 'eigenfunction');
  await waitField(b);
  b = await fieldCount();
  await setValue('component', 6);
  await waitField(b);
  const box = await page.$eval('#view canvas', (c) => { const r = c.getBoundingClientRect(); return { x: r.left, y: r.top, w: r.width, h: r.height }; });
  await page.mouse.move(box.x + box.w * 0.45, box.y + box.h * 0.4);
  await page.mouse.down();
  await page.mouse.move(box.x + box.w * 0.52, box.y + box.h * 0.46, { steps: 5 });
  await page.mouse.up();
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const fig = await page.evaluate(() => window.__figure);
  assert.ok(fig && fig.stops.length === 256 && fig.colorbar, 'the page shows a figure description');
  // The page's overlays, relative to the canvas: left out of the colour comparison.
  const rects = await page.evaluate(() => {
    const c = document.querySelector('#view canvas').getBoundingClientRect();
    return ['#legend', '#colorbar', '#results', '#stale'].map((s) => document.querySelector(s))
      .filter((e) => e && !e.hidden).map((e) => { const r = e.getBoundingClientRect(); return [r.left - c.left, r.top - c.top, r.right - c.left, r.bottom - c.top]; });
  });
  const shotBytes = await page.screenshot({ clip: { x: box.x, y: box.y, width: box.w, height: box.h } });
  const shot = decodePng(shotBytes);
  await page.evaluate(() => { document.getElementById('dl-scale').value = '1'; document.getElementById('dl-dpi').value = '300'; });
  const [dl] = await Promise.all([
    page.waitForEvent('download', { timeout: 120000 }),
    page.click('#downloads a[data-format="png"]'),
  ]);
  const pngBytes = fs.readFileSync(await dl.path());
  // Both pictures are kept beside the test run for a look (the build folder).
  const keep = path.join(path.dirname(process.env.SPECTRAL_MESH_SCREENSHOT || path.join(os.tmpdir(), 'x.png')), 'figure');
  fs.mkdirSync(keep, { recursive: true });
  fs.writeFileSync(path.join(keep, 'screen.png'), shotBytes);
  fs.writeFileSync(path.join(keep, 'download.png'), pngBytes);
  const png = decodePng(pngBytes);
  assert.deepEqual([png.width, png.height], [shot.width, shot.height], 'the PNG has the size of the canvas');
  assert.deepEqual(png.ppm, [11811, 11811], 'pHYs: 300 dpi');
  const { width: w, height: h } = png;
  // Masked: the page's overlays and the PNG's (the same corners), with a margin.
  const pad = 30;
  const masked = (x, y) => rects.some(([l, t, r, bo]) => x >= l - pad && x <= r + pad && y >= t - pad && y <= bo + pad)
    || (x > w - 330 && y < 260) || (x < 360 && y > h - 150);
  // Colours: where the screenshot is smooth (no line, marker or edge within 3 px) and on
  // the surface, the PNG has the same colour within a small tolerance.
  const smooth = (img, x, y) => {
    const lo = [255, 255, 255], hi = [0, 0, 0];
    for (let dy = -3; dy <= 3; dy++) for (let dx = -3; dx <= 3; dx++) {
      const i = 4 * ((y + dy) * w + (x + dx));
      for (let c = 0; c < 3; c++) { lo[c] = Math.min(lo[c], img.data[i + c]); hi[c] = Math.max(hi[c], img.data[i + c]); }
    }
    return hi.every((v, c) => v - lo[c] <= 24) && !(lo[0] > 245 && lo[1] > 245 && lo[2] > 245);
  };
  const diffs = [];
  for (let y = 4; y < h - 4; y += 6) {
    for (let x = 4; x < w - 4; x += 6) {
      if (masked(x, y) || !smooth(shot, x, y)) continue;
      const i = 4 * (y * w + x);
      diffs.push(Math.max(...[0, 1, 2].map((c) => Math.abs(shot.data[i + c] - png.data[i + c]))));
    }
  }
  diffs.sort((a, b2) => a - b2);
  const q = (f) => diffs[Math.floor(f * (diffs.length - 1))];
  const summary = `${diffs.length} samples, median ${q(0.5)}, 90% ${q(0.9)}, max ${q(1)}`;
  assert.ok(diffs.length >= 300, summary);
  assert.ok(q(0.5) <= 6 && q(0.9) <= 16, `colours differ: ${summary}`);
  // Markers: the same number of each kind, with the same shapes, at the same places.
  const styles = Object.fromEntries(fig.marker_styles.map((s) => [s.kind, s]));
  const drawn = await page.evaluate(() => window.__markers);
  let total = 0;
  for (const kind of ['minimum', 'maximum', 'saddle']) {
    const fill = hexRgb(styles[kind].fill);
    const a = markerBlobs(shot, fill, masked), p = markerBlobs(png, fill, masked);
    assert.equal(p.length, a.length, `${kind}: ${a.length} on screen, ${p.length} in the PNG`);
    for (const m of a) assert.equal(m.shape, styles[kind].shape, `${kind} on screen: ${JSON.stringify(m)}`);
    for (const m of p) {
      assert.equal(m.shape, styles[kind].shape, `${kind} in the PNG: ${JSON.stringify(m)}`);
      assert.ok(a.some((o) => Math.hypot(o.x - m.x, o.y - m.y) <= 4), `${kind} at ${m.x},${m.y} in the PNG only`);
    }
    assert.ok(a.length <= (drawn[kind] || 0));
    total += a.length;
  }
  assert.ok(total >= 3, `only ${total} markers in sight`);
  // Legend (top right) and colour bar (bottom left) in both: the legend's marker icons,
  // the bar's first, middle and last colours.
  const inBox = (img, x0, y0, x1, y1, c, tol = 10) => {
    let n = 0;
    for (let y = Math.max(0, y0); y < Math.min(h, y1); y++) for (let x = Math.max(0, x0); x < Math.min(w, x1); x++) if (near(img, 4 * (y * w + x), c, tol)) n++;
    return n;
  };
  for (const [name, img] of [['screen', shot], ['PNG', png]]) {
    for (const e of fig.legend.filter((x) => styles[x.kind])) {
      assert.ok(inBox(img, w - 330, 0, w, 260, hexRgb(styles[e.kind].fill)) >= 6, `${name}: no ${e.kind} in the legend`);
    }
    for (const c of [fig.stops[0], fig.stops[128], fig.stops[255]]) {
      assert.ok(inBox(img, 0, h - 150, 360, h, hexRgb(c), 6) >= 20, `${name}: colour bar without ${c}`);
    }
  }
  console.log(`PNG vs screen: ${summary}; markers ${total}`);
});

// ---------- what the faster frame leaves out must not change the picture ----------

// Pixels of two RGBA readings that differ by more than `tol` in a channel.
function differing(a, b, tol = 8) {
  let n = 0;
  for (let i = 0; i < a.data.length; i += 4) {
    if ([0, 1, 2].some((c) => Math.abs(a.data[i + c] - b.data[i + c]) > tol)) n++;
  }
  return n;
}

test('a closed surface is drawn from its outer side only, with the same pixels as both sides; an open one from both', async () => {
  let b = await fieldCount();
  await setValue('experiment', 'heat');
  await waitField(b);
  const [one, both] = await page.evaluate(() => {
    const plain = (r) => ({ w: r.w, h: r.h, side: r.side, data: Array.from(r.data) });
    return [plain(window.__viewPixels()), plain(window.__viewPixels(true))];
  });
  assert.notEqual(one.side, 'double', '3torus: the inner side is still drawn');
  assert.equal(both.side, 'double');
  // The view is read in the same task as it is drawn (no drawing buffer is kept): it
  // shows the field, not a cleared canvas.
  let coloured = 0;
  for (let i = 0; i < one.data.length; i += 4) {
    const c = one.data.slice(i, i + 3);
    if (Math.max(...c) - Math.min(...c) > 40) coloured++;
  }
  assert.ok(coloured > 0.05 * one.w * one.h, `${coloured} coloured pixels of ${one.w * one.h}`);
  const d = differing(one, both);
  assert.ok(d <= 0.001 * one.w * one.h, `${d} pixels differ between the outer side and both sides`);
  // An open surface (a pyramid without its base): both sides.
  const file = path.join(os.tmpdir(), 'open-pyramid-e2e.off');
  fs.writeFileSync(file, 'OFF\n5 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0.8\n3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4\n');
  const loaded = await page.evaluate(() => window.__meshLoaded || 0);
  await page.evaluate(() => { document.getElementById('k').value = '3'; });
  await page.setInputFiles('#file-input', file);
  await page.waitForFunction((l) => (window.__meshLoaded || 0) > l, loaded, { timeout: 30000 });
  fs.rmSync(file);
  assert.equal(await page.evaluate(() => window.__viewPixels().side), 'double');
  b = await fieldCount();
  await page.evaluate(() => { document.getElementById('k').value = '100'; document.getElementById('shape-spec').value = '3torus'; document.getElementById('shape-load').click(); });
  await waitField(b);
});

// The view drawn by the full-screen pass and drawn directly, compared in the page (the
// pixel arrays are large to hand over): modes, the pixels that differ by more than 8 in a
// channel, coloured and level-line pixels, and how often the per-pixel buffer was drawn.
const compareModes = () => page.evaluate(() => {
  const fast = window.__viewPixels(), direct = window.__viewPixels(false, true);
  let differ = 0, coloured = 0, lines = 0;
  for (let i = 0; i < fast.data.length; i += 4) {
    let m = 0, lo = 255, hi = 0;
    for (let c = 0; c < 3; c++) {
      m = Math.max(m, Math.abs(fast.data[i + c] - direct.data[i + c]));
      lo = Math.min(lo, fast.data[i + c]); hi = Math.max(hi, fast.data[i + c]);
    }
    if (m > 8) differ++;
    if (hi - lo > 40) coloured++;
    if (hi < 40) lines++;
  }
  return { modes: [fast.mode, direct.mode], pixels: fast.w * fast.h, differ, coloured, lines, draws: window.__gbufferDraws || 0 };
});

test('a new field is drawn by one full-screen pass over the stored triangles, with the pixels of the surface drawn directly', async () => {
  // A field with level lines and markers, then a second one (only the values change).
  let b = await fieldCount();
  await setValue('experiment', 'heat');
  await waitField(b);
  const draws = await page.evaluate(() => window.__gbufferDraws || 0);
  b = await fieldCount();
  await setValue('t-num', '0.05');
  await waitField(b);
  const r = await compareModes();
  // Software GL has float render targets: the page takes the full-screen pass, and the
  // new field did not draw the triangles again (the camera did not move).
  assert.deepEqual(r.modes, ['deferred', 'direct']);
  assert.equal(r.draws, draws, 'the per-pixel buffer was drawn again for a new field');
  assert.ok(r.coloured > 0.05 * r.pixels, JSON.stringify(r));
  assert.ok(r.lines > 200, `level lines: ${JSON.stringify(r)}`);
  assert.ok(r.differ <= 0.001 * r.pixels, `pixels differ between the full-screen pass and the direct draw: ${JSON.stringify(r)}`);
  // Turning the camera draws the buffer again, and the picture still agrees.
  const box = await page.$eval('#view canvas', (c) => { const q = c.getBoundingClientRect(); return { x: q.left, y: q.top, w: q.width, h: q.height }; });
  await page.mouse.move(box.x + box.w * 0.5, box.y + box.h * 0.5);
  await page.mouse.down();
  await page.mouse.move(box.x + box.w * 0.56, box.y + box.h * 0.53, { steps: 3 });
  await page.mouse.up();
  const t = await compareModes();
  assert.ok(t.draws > r.draws, 'the camera moved but the per-pixel buffer was not drawn again');
  assert.ok(t.differ <= 0.001 * t.pixels, `pixels differ after the camera moved: ${JSON.stringify(t)}`);
});

// ---------- latency: from the input event to the frame that shows the new field ----------

const median = (a) => { const s = [...a].sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };

// Moves the t slider `n` times (one move at a time): for each, the time from just before
// the input event is dispatched to the animation frame that shows the new field (the
// second frame after the page drew it: the first one's callbacks run before it is
// composited), measured in the page by this test, with the page's own figure and the
// server's share.
async function tMoves(n) {
  const out = [];
  for (let i = 0; i < n; i++) {
    const r = await page.evaluate(async (v) => {
      const before = window.__fieldCount || 0;
      const t = document.getElementById('t');
      const t0 = performance.now();
      t.value = String(v);
      t.dispatchEvent(new Event('input', { bubbles: true }));
      while ((window.__fieldCount || 0) === before) await new Promise((r) => setTimeout(r, 1));
      return { test_ms: window.__drawnAt - t0, page_ms: window.__lastField.timing.total_ms, server_ms: window.__lastField.timing.server_ms };
    }, -2.2 + 0.04 * (i % 10));
    out.push(r);
  }
  const m = (k) => median(out.map((x) => x[k]));
  return { test_ms: m('test_ms'), page_ms: m('page_ms'), server_ms: m('server_ms'), all: out.map((x) => Math.round(x.test_ms)) };
}

test('latency: input to the frame that shows the new field, 3-torus, k = 200', async () => {
  await page.setViewportSize({ width: 1280, height: 800 });
  await loadHeat(page, '3torus', 200, 600000);
  const n = await page.evaluate(() => window.__lastField.header.n);
  await tMoves(3); // warm
  const r = await tMoves(15);
  console.log(`LATENCY 3torus n=${n} k=200 ${JSON.stringify(r)}`);
  assert.ok(r.test_ms > 0 && Math.abs(r.test_ms - r.page_ms) < 20, JSON.stringify(r));
});

test('latency: input to the frame that shows the new field, ~100k vertices, k = 200', { skip: !BENCH }, async () => {
  await loadHeat(page, 'torus:res=5', 200, 3600000);
  const n = await page.evaluate(() => window.__lastField.header.n);
  await tMoves(3);
  const r = await tMoves(15);
  console.log(`LATENCY torus:res=5 n=${n} k=200 ${JSON.stringify(r)}`);
  assert.ok(r.test_ms > 0);
});
