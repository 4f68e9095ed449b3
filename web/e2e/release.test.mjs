// The release binary travels alone: copied to an empty folder, with no source tree beside
// it and no node_modules, `serve` gives a page with its 3D library and draws a field.
// run.sh sets SPECTRAL_MESH_RELEASE_BIN (the `spectral-mesh` CLI built with --release).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { spawn } from 'node:child_process';
import { launch } from './common.mjs';

const BIN = process.env.SPECTRAL_MESH_RELEASE_BIN || '';

test('a copied release binary serves the page and a field from an empty folder', { skip: !BIN && 'SPECTRAL_MESH_RELEASE_BIN is not set' }, async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sm-release-'));
  const bin = path.join(dir, 'spectral-mesh');
  fs.copyFileSync(BIN, bin);
  fs.chmodSync(bin, 0o755);
  assert.deepEqual(fs.readdirSync(dir), ['spectral-mesh']);
  const env = { ...process.env };
  delete env.SPECTRAL_MESH_WEB_NODE_MODULES;
  const server = spawn(bin, ['serve', '--host', '127.0.0.1', '--port', '0', '--cache-mib', '256'], { cwd: dir, env, stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  server.stdout.on('data', (d) => { out += d; });
  server.stderr.on('data', (d) => { out += d; });
  let browser;
  try {
    const url = await new Promise((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error(`no URL from serve: ${out}`)), 30000);
      const look = () => {
        const m = out.match(/http:\/\/[^\s]+/);
        if (m) { clearTimeout(timer); resolve(m[0]); } else setTimeout(look, 50);
      };
      server.on('exit', (c) => reject(new Error(`serve exited with ${c}: ${out}`)));
      look();
    });
    const three = await fetch(new URL('vendor/three.module.js', url));
    assert.equal(three.status, 200);
    assert.equal(three.headers.get('x-spectral-mesh-asset'), 'embedded');
    assert.ok((await three.text()).length > 100000);
    browser = await launch();
    const page = browser.page;
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    // Nothing but this server: any other request would fail the page.
    const external = [];
    page.on('request', (r) => { if (!r.url().startsWith(url) && !r.url().startsWith('data:')) external.push(r.url()); });
    await page.goto(url);
    await page.waitForFunction(() => (window.__fieldCount || 0) > 0 || window.__lastError, null, { timeout: 180000 });
    assert.equal(await page.evaluate(() => window.__lastError), null);
    const f = await page.evaluate(() => ({ n: window.__lastField.header.n, kind: window.__lastField.header.kind }));
    assert.equal(f.kind, 'distance');
    assert.ok(f.n > 100);
    assert.equal(await page.isVisible('#lib-missing'), false);
    assert.deepEqual(external, []);
    assert.deepEqual(errors, []);
  } finally {
    await browser?.close();
    server.kill();
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
