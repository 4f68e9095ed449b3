// Shared by the end-to-end tests: Debian's Chromium driven by playwright-core, and small
// mesh files written on the fly.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import assert from 'node:assert/strict';
import zlib from 'node:zlib';
import { before, after } from 'node:test';
import { chromium } from 'playwright-core';

// Headless Chromium with a fresh profile (the flags that work on a closed network; see
// the machine notes). Rendering is in software (SwiftShader): no GPU.
export async function launch() {
  const userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'sm-chromium-'));
  const context = await chromium.launchPersistentContext(userDir, {
    executablePath: process.env.SPECTRAL_MESH_CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
    viewport: { width: 1280, height: 800 },
    acceptDownloads: true,
  });
  const page = context.pages()[0] || await context.newPage();
  return {
    page,
    async close() {
      await context.close();
      fs.rmSync(userDir, { recursive: true, force: true });
    },
  };
}

// Opens the page run.sh serves (SPECTRAL_MESH_URL) in a fresh browser before the calling
// file's tests and closes it after them: `onOpen(page)` is called before the page loads
// (to keep the page, listen to it); with `firstField`, the page's first field is waited
// for (at most 180 s).
export function openPage(onOpen, { firstField = true } = {}) {
  let browser;
  before(async () => {
    const url = process.env.SPECTRAL_MESH_URL;
    assert.ok(url, 'SPECTRAL_MESH_URL is not set: run web/e2e/run.sh');
    browser = await launch();
    await onOpen(browser.page);
    await browser.page.goto(url);
    if (firstField) {
      await browser.page.waitForFunction(() => (window.__fieldCount || 0) > 0, null, { timeout: 180000 });
    }
  });
  after(async () => { await browser?.close(); });
}

// A square pyramid: 5 vertices, 6 triangles, closed.
export function writePyramidOff(file) {
  fs.writeFileSync(file, 'OFF\n5 6 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0.8\n'
    + '3 0 2 1\n3 0 3 2\n3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4\n');
  return file;
}

// A torus of nu x nv vertices (radii 1 and 0.35), as an OFF file.
export function writeTorusOff(file, nu, nv) {
  const lines = [`OFF\n${nu * nv} ${2 * nu * nv} 0`];
  for (let i = 0; i < nu; i++) {
    const u = (2 * Math.PI * i) / nu;
    for (let j = 0; j < nv; j++) {
      const v = (2 * Math.PI * j) / nv;
      const r = 1 + 0.35 * Math.cos(v);
      lines.push(`${(r * Math.cos(u)).toFixed(7)} ${(r * Math.sin(u)).toFixed(7)} ${(0.35 * Math.sin(v)).toFixed(7)}`);
    }
  }
  const id = (i, j) => ((i + nu) % nu) * nv + ((j + nv) % nv);
  for (let i = 0; i < nu; i++) {
    for (let j = 0; j < nv; j++) {
      lines.push(`3 ${id(i, j)} ${id(i + 1, j)} ${id(i + 1, j + 1)}`);
      lines.push(`3 ${id(i, j)} ${id(i + 1, j + 1)} ${id(i, j + 1)}`);
    }
  }
  fs.writeFileSync(file, lines.join('\n') + '\n');
  return file;
}

// Loads the built-in shape `shape` (its spec) in `page` with the heat experiment at `k`
// pairs and waits (at most `timeout` ms) for that field to be drawn.
export async function loadHeat(page, shape, k, timeout) {
  const before = await page.evaluate(() => window.__fieldCount || 0);
  await page.evaluate(([s, kk]) => {
    document.getElementById('experiment').value = 'heat';
    document.getElementById('k').value = String(kk);
    document.getElementById('shape-spec').value = s;
    document.getElementById('shape-load').click();
  }, [shape, k]);
  await page.waitForFunction(([bb, kk]) => (window.__fieldCount || 0) > bb && window.__lastField.header.k === kk
    && window.__lastField.header.kind === 'heat', [before, k], { timeout });
}

// What the page tests ask of the page, for the page `getPage()` returns (set in `before`):
// counts of fields and errors, waiting for the next field or error (at most
// `fieldTimeout` / `errorTimeout` ms), setting a control's value, and the screen points
// of the canvas that hit the shape with the vertex (point) each picks.
export function pageHelpers(getPage, { fieldTimeout, errorTimeout }) {
  let errorsBefore = 0;
  const count = () => getPage().evaluate(() => [window.__fieldCount || 0, window.__errorCount || 0])
    .then(([f, e]) => { errorsBefore = e; return f; });
  const errorCount = () => getPage().evaluate(() => window.__errorCount || 0);

  async function waitField(before, timeout = fieldTimeout) {
    const page = getPage();
    await page.waitForFunction(([b, e]) => (window.__fieldCount || 0) > b || (window.__errorCount || 0) > e,
      [before, errorsBefore], { timeout });
    const [errors, err] = await page.evaluate(() => [window.__errorCount || 0, window.__lastError]);
    assert.ok(errors === errorsBefore, `page shows an error: ${err}`);
    return page.evaluate(() => window.__lastFieldPlain());
  }

  async function waitError(before, timeout = errorTimeout) {
    const page = getPage();
    await page.waitForFunction((e) => (window.__errorCount || 0) > e && window.__lastError, before, { timeout });
    return page.evaluate(() => ({ msg: window.__lastError, at: window.__lastErrorFor }));
  }

  async function setValue(id, value, event = 'change') {
    const before = await count();
    await getPage().evaluate(([i, v, e]) => {
      const el = document.getElementById(i);
      el.value = String(v);
      el.dispatchEvent(new Event(e, { bubbles: true }));
    }, [id, value, event]);
    return before;
  }

  function pickPoints() {
    return getPage().evaluate(() => {
      const c = document.querySelector('#view canvas').getBoundingClientRect();
      const out = [];
      for (let i = 1; i < 16; i++) {
        for (let j = 1; j < 12; j++) {
          const x = c.left + (c.width * i) / 16, y = c.top + (c.height * j) / 12;
          const v = window.__vertexAt(x, y);
          if (v !== null) out.push({ x, y, v });
        }
      }
      return out;
    });
  }

  // Clicks the surface at the point a `fraction` of the way through `pickPoints()` and
  // waits for the field: it and its source (or anchor), checked to be the clicked vertex
  // in the source box and in the field's header.
  async function clickSource(fraction) {
    const page = getPage();
    const pts = await pickPoints();
    assert.ok(pts.length > 5, 'the surface is on screen');
    const target = pts[Math.floor(fraction * pts.length)];
    const before = await count();
    await page.mouse.click(target.x, target.y);
    const f = await waitField(before);
    const src = Number(await page.inputValue('#source'));
    assert.equal(src, target.v);
    assert.equal(f.header.source, src);
    return { f, src, pts };
  }

  return { count, errorCount, waitField, waitError, setValue, pickPoints, clickSource };
}

// A PNG file's pixels: 8-bit RGB or RGBA (colour types 2 and 6), not interlaced, as the
// server and Chromium write them. Returns { width, height, data (RGBA bytes), ppm } with
// `ppm` the pHYs chunk's pixels per metre (null without one).
export function decodePng(buf) {
  assert.equal(buf.subarray(1, 4).toString('latin1'), 'PNG', 'not a PNG');
  let off = 8, width = 0, height = 0, type = 0, ppm = null;
  const idat = [];
  while (off < buf.length) {
    const len = buf.readUInt32BE(off);
    const name = buf.subarray(off + 4, off + 8).toString('latin1');
    const data = buf.subarray(off + 8, off + 8 + len);
    if (name === 'IHDR') {
      width = data.readUInt32BE(0); height = data.readUInt32BE(4);
      assert.equal(data[8], 8, 'bit depth'); type = data[9];
      assert.ok(type === 2 || type === 6, `colour type ${type}`); assert.equal(data[12], 0, 'interlaced');
    } else if (name === 'pHYs' && data[8] === 1) {
      ppm = [data.readUInt32BE(0), data.readUInt32BE(4)];
    } else if (name === 'IDAT') idat.push(data);
    off += 12 + len;
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const bpp = type === 6 ? 4 : 3, stride = width * bpp;
  const cur = new Uint8Array(stride), prev = new Uint8Array(stride);
  const out = new Uint8Array(width * height * 4);
  for (let y = 0; y < height; y++) {
    const f = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let i = 0; i < stride; i++) {
      const a = i >= bpp ? cur[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      let p = 0;
      if (f === 1) p = a; else if (f === 2) p = b; else if (f === 3) p = (a + b) >> 1;
      else if (f === 4) { const q = a + b - c, pa = Math.abs(q - a), pb = Math.abs(q - b), pc = Math.abs(q - c); p = pa <= pb && pa <= pc ? a : pb <= pc ? b : c; }
      cur[i] = (line[i] + p) & 255;
    }
    for (let x = 0; x < width; x++) {
      for (let k = 0; k < 3; k++) out[4 * (y * width + x) + k] = cur[x * bpp + k];
      out[4 * (y * width + x) + 3] = bpp === 4 ? cur[x * bpp + 3] : 255;
    }
    prev.set(cur);
  }
  return { width, height, data: out, ppm };
}
