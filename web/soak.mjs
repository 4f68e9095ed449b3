// Soak test of the web server on 127.0.0.1 (run by web/soak.sh): CLIENTS concurrent
// clients for SECONDS seconds mixing good and broken uploads, oversized and truncated
// ones, eigenbasis jobs (polled, cancelled, abandoned, too large), field requests checked
// against references, malformed JSON, dropped connections and late bodies, after a burst
// of BURST basis requests on as many different meshes at once. Records every status code,
// latency percentiles per kind and the server's memory (VmRSS of PID) over time, then
// waits for the server's idle expiry and records the memory again.
//
// usage: node web/soak.mjs URL PID SECONDS CLIENTS BURST IDLE_SECONDS OUT.json
// Bounded: at most SECONDS of load (plus the setup, the burst and the idle wait), at most
// 200,000 requests, every request at most 60 s. Exits 1 when a good request failed or was
// answered wrongly, a 5xx other than a 503 with a message came back, the server died, or
// its memory did not come back near its start.
import net from 'node:net';
import fs from 'node:fs';

const [URL_ARG, PID, SECONDS = '180', CLIENTS = '16', BURST = '24', IDLE = '20', OUT = ''] =
  process.argv.slice(2);
if (!URL_ARG || !/^http:\/\/127\.0\.0\.1:\d+\/$/.test(URL_ARG) || !PID) {
  console.error('usage: node web/soak.mjs http://127.0.0.1:PORT/ PID [SECONDS CLIENTS BURST IDLE OUT]');
  process.exit(2);
}
const BASE = URL_ARG.replace(/\/$/, '');
const PORT = Number(new URL(URL_ARG).port);
const LOAD_MS = Number(SECONDS) * 1000;
const N_CLIENTS = Number(CLIENTS);
const N_BURST = Number(BURST);
const IDLE_S = Number(IDLE);
const MAX_REQUESTS = 200000;
const TIMEOUT_MS = 60000;
// The options web/soak.sh starts the server with.
const MAX_UPLOAD = 2 << 20;
const MAX_K = 200;
const REQUEST_SECONDS = 10;

// ---------- memory of the server ----------
function procStatus() {
  try {
    const s = fs.readFileSync(`/proc/${PID}/status`, 'utf8');
    const kib = (k) => Number((s.match(new RegExp(`${k}:\\s+(\\d+)`)) || [])[1] || 0);
    return { rss: kib('VmRSS') * 1024, hwm: kib('VmHWM') * 1024 };
  } catch (_) {
    return null;
  }
}
const t0 = Date.now();
const memory = [];
const sample = () => {
  const p = procStatus();
  if (p) memory.push({ t: (Date.now() - t0) / 1000, rss: p.rss });
};
sample();
const startRss = memory[0] ? memory[0].rss : 0;
const sampler = setInterval(sample, 500);

// ---------- records ----------
const kinds = new Map();
const failures = [];
let requests = 0;
function record(kind, status, ms, ok, note) {
  let k = kinds.get(kind);
  if (!k) { k = { n: 0, codes: {}, lat: [], bad: 0 }; kinds.set(kind, k); }
  k.n++;
  k.codes[status] = (k.codes[status] || 0) + 1;
  if (ms !== null) k.lat.push(ms);
  if (!ok) { k.bad++; if (failures.length < 50) failures.push(`${kind}: ${status} ${note || ''}`.slice(0, 300)); }
}
const fiveHundreds = [];

async function call(method, path, { json, body, headers = {}, timeout = TIMEOUT_MS } = {}) {
  requests++;
  const opts = { method, headers: { ...headers }, signal: AbortSignal.timeout(timeout) };
  if (json !== undefined) { opts.body = JSON.stringify(json); opts.headers['Content-Type'] = 'application/json'; }
  else if (body !== undefined) opts.body = body;
  const start = performance.now();
  try {
    const r = await fetch(BASE + path, opts);
    const buf = Buffer.from(await r.arrayBuffer());
    const ms = performance.now() - start;
    let error = '';
    if (r.status >= 400) { try { error = JSON.parse(buf).error || ''; } catch (_) { /* not JSON */ } }
    if (r.status >= 500 && !(r.status === 503 && error)) fiveHundreds.push(`${method} ${path}: ${r.status} ${buf.toString().slice(0, 200)}`);
    return { status: r.status, buf, ms, error, retryAfter: r.headers.get('retry-after') };
  } catch (e) {
    return { status: 0, buf: Buffer.from(String(e)), ms: performance.now() - start, error: String(e) };
  }
}
const json = (r) => { try { return JSON.parse(r.buf); } catch (_) { return null; } };

/// A request over a raw socket: writes `parts` (with `pauseMs` between them), then either
/// destroys the socket (`drop`) or reads the reply (status, or null when none came).
function raw(parts, { drop = false, pauseMs = 0, timeout = TIMEOUT_MS } = {}) {
  requests++;
  return new Promise((resolve) => {
    const start = performance.now();
    const s = net.connect(PORT, '127.0.0.1');
    let buf = Buffer.alloc(0);
    let done = false;
    const finish = (status) => {
      if (done) return;
      done = true;
      clearTimeout(timer);
      s.destroy();
      resolve({ status, ms: performance.now() - start, text: buf.toString('latin1') });
    };
    const timer = setTimeout(() => finish(null), timeout);
    s.on('error', () => finish(null));
    s.on('data', (d) => { buf = Buffer.concat([buf, d]); });
    s.on('end', () => {
      const m = buf.toString('latin1').match(/^HTTP\/1\.1 (\d{3})/);
      finish(m ? Number(m[1]) : null);
    });
    s.on('connect', async () => {
      for (let i = 0; i < parts.length; i++) {
        if (i > 0 && pauseMs) await new Promise((r) => setTimeout(r, pauseMs));
        if (done) return;
        s.write(parts[i]);
      }
      if (drop) setTimeout(() => finish('dropped'), 20);
    });
  });
}
const head = (method, path, len, extra = '') =>
  `${method} ${path} HTTP/1.1\r\nHost: 127.0.0.1:${PORT}\r\nConnection: close\r\nContent-Length: ${len}\r\n${extra}\r\n`;

// ---------- meshes ----------
/// A `side x side` height field as OFF text; `seed` makes its content (and id) unique.
function gridOff(side, seed) {
  const lines = [`OFF\n${side * side} ${2 * (side - 1) * (side - 1)} 0`];
  for (let i = 0; i < side; i++) {
    for (let j = 0; j < side; j++) lines.push(`${i} ${j} ${(0.3 * Math.sin(0.37 * i + seed) * Math.cos(0.23 * j - seed)).toFixed(6)}`);
  }
  for (let i = 0; i < side - 1; i++) {
    for (let j = 0; j < side - 1; j++) {
      const a = i * side + j;
      lines.push(`3 ${a} ${a + side} ${a + 1}`, `3 ${a + 1} ${a + side} ${a + side + 1}`);
    }
  }
  return Buffer.from(lines.join('\n') + '\n');
}
const BROKEN = [
  'OFF\n3 1 0\n0 0 0\nnope\n',
  'OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n',
  'OFF\n3 1 0\n0 0 nan\n1 0 0\n0 1 0\n3 0 1 2\n',
  'ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n',
  'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\nendloop\nendfacet\n',
  '\u0000\u0001\u0002garbage',
];

// ---------- the fixed meshes and the references ----------
// Shapes whose fields every client asks for and checks. k = 64 ends at a gap of the
// sphere's spectrum, so a basis computed again after an eviction gives the same fields.
const FIXED = ['sphere:res=3', 'irregular-sphere:res=3', '3torus'];
const K_FIXED = 64;
const fixed = [];

function parseField(buf) {
  const len = buf.readUInt32LE(0);
  const header = JSON.parse(buf.subarray(4, 4 + len).toString());
  const values = new Float32Array(buf.buffer.slice(buf.byteOffset + 4 + len, buf.byteOffset + 4 + len + 4 * header.n));
  return { header, values };
}

async function ensureBasis(m) {
  const r = await call('POST', `/api/mesh/${m.id}/basis`, { json: { k: K_FIXED } });
  if (r.status !== 200 && r.status !== 202) throw new Error(`basis of ${m.shape}: ${r.status} ${r.buf}`);
  for (let i = 0; i < 2000; i++) {
    const st = json(await call('GET', `/api/mesh/${m.id}/basis/status`));
    if (st && st.state === 'done') return;
    if (st && st.state !== 'running' && st.state !== 'queued') throw new Error(`basis of ${m.shape}: ${JSON.stringify(st)}`);
    await new Promise((r) => setTimeout(r, 150));
  }
  throw new Error(`basis of ${m.shape} did not finish`);
}

async function loadFixed(shape) {
  const r = await call('POST', '/api/mesh', { json: { shape } });
  if (r.status !== 200) throw new Error(`cannot load ${shape}: ${r.status} ${r.buf}`);
  const j = json(r);
  return { shape, id: j.mesh_id, n: j.n };
}

async function setup() {
  for (const shape of FIXED) {
    const m = await loadFixed(shape);
    await ensureBasis(m);
    const v = (x) => Math.floor(x * m.n);
    m.requests = [
      { kind: 'heat', k: K_FIXED, t: 0.01, anchor: v(0.1) },
      { kind: 'distance', k: K_FIXED, distance: 'biharmonic', source: v(0.5) },
      { kind: 'distance', k: K_FIXED, distance: 'diffusion:t=0.05', source: v(0.7) },
      { kind: 'harmonic', constraints: [{ vertex: v(0.2), value: 0 }, { vertex: v(0.9), value: 1 }] },
    ];
    m.refs = [];
    for (const q of m.requests) {
      const r = await call('POST', `/api/mesh/${m.id}/field`, { json: { ...q, levels: 8 } });
      if (r.status !== 200) throw new Error(`reference ${JSON.stringify(q)} on ${shape}: ${r.status} ${r.buf}`);
      m.refs.push(parseField(r.buf).values);
    }
    fixed.push(m);
  }
}

let maxFieldDiff = 0;
/// A field request on a fixed mesh, checked against its reference. A mesh or basis the
/// cache evicted is loaded and computed again, as the page does (recorded apart).
async function goodField(rnd) {
  const m = fixed[Math.floor(rnd() * fixed.length)];
  const i = Math.floor(rnd() * m.requests.length);
  const path = () => `/api/mesh/${m.id}/field`;
  let r = await call('POST', path(), { json: { ...m.requests[i], levels: 8 } });
  if (r.status === 404 || r.status === 409) {
    record('field (evicted: reloaded)', r.status, r.ms, true);
    if (r.status === 404) await loadFixed(m.shape);
    if (m.requests[i].kind !== 'harmonic') await ensureBasis(m);
    r = await call('POST', path(), { json: { ...m.requests[i], levels: 8 } });
  }
  if (r.status !== 200) { record('field', r.status, r.ms, r.status === 503 && r.error, r.error); return; }
  const { values } = parseField(r.buf);
  const ref = m.refs[i];
  let diff = values.length === ref.length ? 0 : Infinity;
  let scale = 1;
  for (let j = 0; j < ref.length && diff < Infinity; j++) {
    scale = Math.max(scale, Math.abs(ref[j]));
    diff = Math.max(diff, Math.abs(values[j] - ref[j]));
  }
  maxFieldDiff = Math.max(maxFieldDiff, diff / scale);
  record('field', r.status, r.ms, diff <= 1e-4 * scale, `differs from its reference by ${diff}`);
}

// ---------- eigenbasis jobs ----------
let uploadSeed = 1000;
async function uploadGrid(kind, side) {
  const r = await call('POST', '/api/mesh', { body: gridOff(side, uploadSeed++), headers: { 'Content-Type': 'application/octet-stream', 'X-Filename': `grid-${side}.off` } });
  const ok = r.status === 200 || (r.status === 503 && r.error);
  record(kind, r.status, r.ms, ok, r.error);
  return r.status === 200 ? json(r) : null;
}

/// Polls like the page (every 150 ms) until the job ends; its final state.
async function poll(id, limitMs = 120000) {
  const start = performance.now();
  while (performance.now() - start < limitMs) {
    const r = await call('GET', `/api/mesh/${id}/basis/status`);
    const st = json(r);
    if (r.status !== 200 || !st) return { state: `status ${r.status}`, message: r.error };
    if (st.state !== 'running' && st.state !== 'queued') return st;
    await new Promise((res) => setTimeout(res, 150));
  }
  return { state: 'timeout' };
}

/// A basis on a fresh upload, polled to the end, then a field from it.
async function basisJob(rnd, side, k, kind = 'basis') {
  const m = await uploadGrid('upload (good)', side);
  if (!m) return;
  const r = await call('POST', `/api/mesh/${m.mesh_id}/basis`, { json: { k } });
  // 503: the queue is full; 422: could never fit: both stated refusals with a message.
  const accepted = r.status === 200 || r.status === 202;
  record(kind, r.status, r.ms, accepted || ((r.status === 503 || r.status === 422) && r.error), r.error);
  if (!accepted) return;
  const t = performance.now();
  const st = await poll(m.mesh_id);
  record(`${kind} job (final state)`, st.state, performance.now() - t, st.state === 'done', st.message);
  if (st.state !== 'done') return;
  const f = await call('POST', `/api/mesh/${m.mesh_id}/field`, { json: { kind: 'heat', k, t: 0.01 } });
  let ok = f.status === 200;
  if (ok) {
    const { header, values } = parseField(f.buf);
    ok = header.n === m.n && values.length === m.n && values.every(Number.isFinite);
  }
  record('field (new basis)', f.status, f.ms, ok || (f.status === 404 && f.error), f.error);
}

// ---------- the mix ----------
const MIX = [
  [30, 'field'], [5, 'geometry'], [4, 'shape'], [6, 'upload (good)'], [5, 'upload (broken)'],
  [3, 'upload (oversized)'], [3, 'upload (truncated)'], [7, 'basis'], [3, 'basis (abandoned)'],
  [3, 'basis (cancelled)'], [2, 'basis (k too large)'], [6, 'malformed JSON'], [3, 'field (no basis)'],
  [5, 'disconnect'], [1, 'late body'], [2, 'path traversal'], [2, 'health'], [2, 'unknown mesh'],
];
const TOTAL = MIX.reduce((a, [w]) => a + w, 0);
function choose(x) {
  let acc = 0;
  for (const [w, k] of MIX) { acc += w; if (x * TOTAL < acc) return k; }
  return MIX[0][1];
}

async function one(kind, rnd) {
  const m = fixed[Math.floor(rnd() * fixed.length)];
  const expect4xx = async (r, codes) => record(kind, r.status, r.ms, codes.includes(r.status) && r.error, r.error || r.buf.toString().slice(0, 100));
  switch (kind) {
    case 'field': return goodField(rnd);
    case 'geometry': {
      const r = await call('GET', `/api/mesh/${m.id}/geometry`);
      const ok = (r.status === 200 && r.buf.readUInt32LE(0) === m.n) || (r.status === 404 && r.error);
      if (r.status === 404) await loadFixed(m.shape);
      return record(kind, r.status, r.ms, ok, r.error);
    }
    case 'shape': {
      const shape = ['sphere:res=2', 'torus:res=1', 'disk:res=2', 'sphere:res=4', 'torus:res=3'][Math.floor(rnd() * 5)];
      const r = await call('POST', '/api/mesh', { json: { shape } });
      return record(kind, r.status, r.ms, r.status === 200 || (r.status === 503 && r.error), r.error);
    }
    case 'upload (good)': return uploadGrid(kind, 10 + Math.floor(rnd() * 110));
    case 'upload (broken)': {
      const body = BROKEN[Math.floor(rnd() * BROKEN.length)];
      const r = await call('POST', '/api/mesh', { body, headers: { 'Content-Type': 'application/octet-stream', 'X-Filename': 'broken.off' } });
      return expect4xx(r, [400, 422]);
    }
    case 'upload (oversized)': {
      const r = await call('POST', '/api/mesh', { body: Buffer.alloc(MAX_UPLOAD + 4096, 48), headers: { 'Content-Type': 'application/octet-stream', 'X-Filename': 'big.off' } });
      return expect4xx(r, [413]);
    }
    case 'upload (truncated)': {
      const body = gridOff(60, uploadSeed++);
      const h = head('POST', '/api/mesh', body.length, 'Content-Type: application/octet-stream\r\nX-Filename: cut.off\r\n');
      const r = await raw([h, body.subarray(0, body.length >> 1)], { drop: true });
      return record(kind, r.status, r.ms, true);
    }
    case 'basis': return basisJob(rnd, 30 + Math.floor(rnd() * 70), 20 + Math.floor(rnd() * 80));
    case 'basis (abandoned)': {
      // The client asks for a basis and goes away without polling: the server cancels
      // the job after --job-idle-seconds.
      const up = await uploadGrid('upload (good)', 80 + Math.floor(rnd() * 40));
      if (!up) return;
      const body = JSON.stringify({ k: 150 });
      const h = head('POST', `/api/mesh/${up.mesh_id}/basis`, body.length, 'Content-Type: application/json\r\n');
      const r = await raw([h + body], { drop: true });
      return record(kind, r.status, r.ms, true);
    }
    case 'basis (cancelled)': {
      const up = await uploadGrid('upload (good)', 80 + Math.floor(rnd() * 40));
      if (!up) return;
      const r = await call('POST', `/api/mesh/${up.mesh_id}/basis`, { json: { k: 120 } });
      const accepted = r.status === 202 || r.status === 200;
      record(kind, r.status, r.ms, accepted || ((r.status === 503 || r.status === 422) && r.error), r.error);
      if (!accepted) return;
      await new Promise((res) => setTimeout(res, 100 + rnd() * 400));
      const d = await call('DELETE', `/api/mesh/${up.mesh_id}/basis`);
      const st = await poll(up.mesh_id);
      return record('basis (cancelled) final state', st.state, d.ms, d.status === 200 && (st.state === 'cancelled' || st.state === 'done'), st.message);
    }
    case 'basis (k too large)': {
      const r = await call('POST', `/api/mesh/${m.id}/basis`, { json: { k: MAX_K + 1 + Math.floor(rnd() * 10000) } });
      return expect4xx(r, [422, 404]);
    }
    case 'malformed JSON': {
      const bodies = ['{"kind":"heat","k":', '{"kind":"heat","t":NaN}', '[1,2', '{"kind":"astrology"}', '{"kind":"heat","k":10,"extra":1}', '\u00ff\u00fe', '{"kind":"heat","levels":-3}', '{"kind":"heat","anchor":1e99}'];
      const body = bodies[Math.floor(rnd() * bodies.length)];
      const r = await call('POST', `/api/mesh/${m.id}/field`, { body, headers: { 'Content-Type': 'application/json' } });
      return expect4xx(r, [400, 404, 422]);
    }
    case 'field (no basis)': {
      const up = await uploadGrid('upload (good)', 10 + Math.floor(rnd() * 30));
      if (!up) return;
      const r = await call('POST', `/api/mesh/${up.mesh_id}/field`, { json: { kind: 'heat', k: 5 } });
      return expect4xx(r, [409, 404]);
    }
    case 'disconnect': {
      // A field request whose client goes away before the reply.
      const q = JSON.stringify({ ...m.requests[Math.floor(rnd() * m.requests.length)], levels: 8 });
      const r = await raw([head('POST', `/api/mesh/${m.id}/field`, q.length, 'Content-Type: application/json\r\n') + q], { drop: true });
      return record(kind, r.status, r.ms, true);
    }
    case 'late body': {
      // 20 of 1000 bytes, then nothing: the server answers 408 at --request-seconds.
      const h = head('POST', '/api/mesh', 1000, 'Content-Type: application/octet-stream\r\nX-Filename: late.off\r\n');
      const r = await raw([h, 'OFF\n3 1 0\n0 0 0\n1 0 '], { timeout: (REQUEST_SECONDS + 10) * 1000 });
      return record(kind, r.status, r.ms, r.status === 408);
    }
    case 'path traversal': {
      const paths = ['/../../../etc/passwd', '/%2e%2e/%2e%2e/etc/passwd', '/vendor/..%2F..%2F..%2Fetc%2Fpasswd', '/api/mesh/..%2F..%2Fetc%2Fpasswd/geometry', '/api/mesh/../../etc/passwd'];
      const r = await call('GET', paths[Math.floor(rnd() * paths.length)]);
      return record(kind, r.status, r.ms, r.status >= 400 && r.status < 500 && !r.buf.toString().includes('root:'));
    }
    case 'health': {
      const r = await call('GET', '/api/health');
      return record(kind, r.status, r.ms, r.status === 200 || (r.status === 503 && r.error));
    }
    case 'unknown mesh': {
      const r = await call('GET', '/api/mesh/0123456789abcdef/geometry');
      return expect4xx(r, [404]);
    }
    default: throw new Error(kind);
  }
}

async function client(c, until) {
  let seed = 9973 + c * 7919;
  const rnd = () => { seed = (seed * 1103515245 + 12345) % 2147483648; return seed / 2147483648; };
  while (Date.now() < until && requests < MAX_REQUESTS) {
    await one(choose(rnd()), rnd);
  }
}

// ---------- run ----------
const phases = {};
const mark = (name) => { const p = procStatus(); phases[name] = { t: (Date.now() - t0) / 1000, rss: p ? p.rss : 0 }; };
mark('start');
await setup();
mark('after setup');
// The burst: BURST basis requests on as many different 20k-vertex meshes at once.
{
  const ups = await Promise.all(Array.from({ length: N_BURST }, () => uploadGrid('upload (good)', 141)));
  await Promise.all(ups.filter(Boolean).map(async (m) => {
    const r = await call('POST', `/api/mesh/${m.mesh_id}/basis`, { json: { k: 100 } });
    const accepted = r.status === 202 || r.status === 200;
    record('burst basis', r.status, r.ms, accepted || (r.status === 503 && r.error), r.error);
    if (!accepted) return;
    const t = performance.now();
    const st = await poll(m.mesh_id, 300000);
    record('burst basis job (final state)', st.state, performance.now() - t, st.state === 'done', st.message);
  }));
}
mark('after burst');
const loadStart = Date.now();
await Promise.all(Array.from({ length: N_CLIENTS }, (_, c) => client(c, loadStart + LOAD_MS)));
const loadSeconds = (Date.now() - loadStart) / 1000;
mark('end of load');
const healthAfter = json(await call('GET', '/api/health'));
// The idle wait: abandoned jobs are cancelled, the cache drops what nobody used.
await new Promise((r) => setTimeout(r, (IDLE_S + 8) * 1000));
mark('after idle wait');
clearInterval(sampler);
const healthFinal = json(await call('GET', '/api/health'));
const alive = procStatus() !== null && healthFinal && healthFinal.ok === true;
const peak = (procStatus() || { hwm: 0 }).hwm;

// ---------- report ----------
const pct = (a, p) => (a.length ? a[Math.min(a.length - 1, Math.floor(p * a.length))] : NaN);
const rows = [...kinds.entries()].sort((a, b) => b[1].n - a[1].n).map(([kind, k]) => {
  const lat = k.lat.sort((a, b) => a - b);
  const codes = Object.entries(k.codes).sort().map(([c, n]) => `${c}: ${n}`).join(', ');
  return { kind, n: k.n, codes, p50: pct(lat, 0.5), p99: pct(lat, 0.99), bad: k.bad };
});
const mib = (b) => (b / 1048576).toFixed(0);
const finalRss = phases['after idle wait'].rss;
const memoryBack = finalRss <= Math.max(startRss * 2, startRss + (160 << 20));
const bad = rows.reduce((a, r) => a + r.bad, 0);
const ok = alive && bad === 0 && fiveHundreds.length === 0 && memoryBack;
console.log(`| kind | requests | status codes | p50 ms | p99 ms | wrong |`);
console.log(`| --- | ---: | --- | ---: | ---: | ---: |`);
for (const r of rows) console.log(`| ${r.kind} | ${r.n} | ${r.codes} | ${r.p50.toFixed(1)} | ${r.p99.toFixed(1)} | ${r.bad} |`);
console.log();
console.log(`clients ${N_CLIENTS}, load ${loadSeconds.toFixed(0)} s, requests ${requests}, burst ${N_BURST}; ` +
  `largest relative field difference from the references ${maxFieldDiff.toExponential(2)}`);
console.log('server memory (VmRSS, MiB): ' + Object.entries(phases).map(([k, v]) => `${k} ${mib(v.rss)}`).join(', ') +
  `; peak (VmHWM) ${mib(peak)}`);
console.log(`health at the end of the load: ${JSON.stringify(healthAfter)}`);
console.log(`health after the idle wait: cache ${healthFinal && healthFinal.cache_entries} entries, ${healthFinal && mib(healthFinal.cache_used)} MiB; jobs running ${healthFinal && healthFinal.jobs_running}, queued ${healthFinal && healthFinal.jobs_queued}`);
for (const f of failures.slice(0, 20)) console.log('WRONG ' + f);
for (const f of fiveHundreds.slice(0, 20)) console.log('5xx ' + f);
if (!memoryBack) console.log(`memory did not come back near its start: ${mib(finalRss)} MiB against ${mib(startRss)} MiB`);
if (!alive) console.log('the server is not answering any more');
if (OUT) {
  fs.writeFileSync(OUT, JSON.stringify({ clients: N_CLIENTS, load_seconds: loadSeconds, requests, burst: N_BURST, rows, phases, peak, memory, healthAfter, healthFinal, failures, fiveHundreds, maxFieldDiff }, null, 1));
}
console.log(`soak: ${ok ? 'passed' : 'FAILED'}`);
process.exit(ok ? 0 : 1);
