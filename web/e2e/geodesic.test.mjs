// End-to-end test of the geodesic distance on the page (issue 28): pick the experiment,
// click the surface, and find the distance from the clicked vertex with its isolines.
// Run by run.sh (alone: `web/e2e/run.sh web/e2e/geodesic.test.mjs`).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { openPage, pageHelpers } from './common.mjs';

let page;
openPage((p) => { page = p; });
const { count, waitField, setValue, clickSource } = pageHelpers(() => page, { fieldTimeout: 180000, errorTimeout: 60000 });

test('geodesic distance: a click sets the source, the distance is 0 there, evenly spaced isolines', async () => {
  let before = await setValue('experiment', 'geodesic');
  let f = await waitField(before);
  assert.equal(f.header.kind, 'geodesic');
  assert.equal(f.header.k, null, 'no eigenbasis');
  assert.equal(f.header.normalized, false);
  assert.match(await page.textContent('#guidance'), /heat method/);
  const clicked = await clickSource(2 / 3);
  f = clicked.f;
  const { src, pts } = clicked;
  assert.equal(f.values[src], 0, 'the distance at the source is 0');
  assert.equal(f.header.min, 0);
  assert.ok(f.header.max > 0 && Number.isFinite(f.header.max), `max ${f.header.max}`);
  assert.ok(f.values.every((v) => v >= 0 && Number.isFinite(v)));
  assert.equal(f.header.unreachable_message, null);
  // The source marker is drawn; the colour bar names the quantity and the isolines.
  const markers = await page.evaluate(() => window.__markers);
  assert.equal(markers.source, 1);
  assert.match(await page.textContent('#colorbar-title'), /geodesic distance/);
  const levels = Number(await page.inputValue('#levels'));
  assert.ok(levels > 1);
  const units = await page.textContent('#colorbar-units');
  assert.match(units, /original size/);
  const spacing = units.match(/(\d+) level sets, spacing ([^ ]+)/);
  assert.ok(spacing, units);
  assert.equal(Number(spacing[1]), levels);
  const want = f.header.max / levels;
  assert.ok(Math.abs(Number(spacing[2]) - want) <= 1e-3 * want, `${spacing[2]} against ${want}`);
  // The same request with the server's isolines: as many as asked, evenly spaced, each
  // one a curve on the surface; the text download is the page's field.
  const server = await page.evaluate(async ([body, l]) => {
    const id = new URL(window.__downloadUrl('txt'), location.href).pathname.split('/')[3];
    const res = await fetch(`/api/mesh/${id}/field`, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify({ ...body, levels: l, segments: true }) });
    const buf = await res.arrayBuffer();
    const hl = new DataView(buf).getUint32(0, true);
    const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, hl)));
    const txt = await (await fetch(window.__downloadUrl('txt'))).text();
    return { header, txt: txt.trim().split('\n').map(Number) };
  }, [f.body, levels]);
  assert.equal(server.header.levels.length, levels);
  const step = server.header.levels[1] - server.header.levels[0];
  for (let i = 1; i < levels; i++) {
    assert.ok(Math.abs(server.header.levels[i] - server.header.levels[i - 1] - step) <= 1e-9 * step);
  }
  assert.ok(Math.abs(step - want) <= 1e-9 * want);
  assert.ok(server.header.level_counts.every((c) => c > 0), JSON.stringify(server.header.level_counts));
  assert.equal(server.txt.length, f.values.length);
  assert.equal(server.txt[src], 0);
  server.txt.forEach((v, i) => assert.equal(Math.fround(v), f.values[i]));
  // Another click: another source, the distance follows it.
  const other = pts.find((p) => p.v !== src);
  before = await count();
  await page.mouse.click(other.x, other.y);
  const g = await waitField(before);
  assert.equal(g.header.source, other.v);
  assert.equal(g.values[other.v], 0);
  assert.ok(g.values[src] > 0);
});
