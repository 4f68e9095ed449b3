// Bounded load test of the web app on 127.0.0.1: WORKERS concurrent workers x REQUESTS
// requests each, a mix of valid and invalid requests. Fails when a valid request gets an
// error, an invalid one is not a 4xx with a JSON message, or the server stops answering.
// Usage (run by web/load_test.sh): node web/load_test.mjs URL [WORKERS] [REQUESTS]
const URL = process.argv[2];
const WORKERS = Number(process.argv[3] || 8);
const REQUESTS = Number(process.argv[4] || 200);
if (!URL || !/^http:\/\/127\.0\.0\.1:\d+\/$/.test(URL)) {
  console.error('give the server URL on 127.0.0.1, e.g. http://127.0.0.1:8000/');
  process.exit(2);
}

async function call(method, path, body, headers = {}) {
  const opts = { method, headers };
  if (body !== undefined) {
    if (typeof body === 'string' || body instanceof Uint8Array) opts.body = body;
    else { opts.body = JSON.stringify(body); opts.headers['Content-Type'] = 'application/json'; }
  }
  const r = await fetch(URL.replace(/\/$/, '') + path, opts);
  const buf = Buffer.from(await r.arrayBuffer());
  return { status: r.status, buf };
}

const shapes = ['sphere:res=2', 'sphere:res=3', 'torus:res=1', 'torus:res=2', '3torus', 'disk:res=1'];
const stats = { valid: 0, invalid: 0, validFailed: 0, invalidWrong: 0, latencies: [] };
const failures = [];

async function prepare() {
  const ids = [];
  for (const s of shapes) {
    const r = await call('POST', '/api/mesh', { shape: s });
    if (r.status !== 200) throw new Error(`cannot load ${s}: ${r.buf}`);
    const j = JSON.parse(r.buf);
    ids.push({ id: j.mesh_id, n: j.n });
    const b = await call('POST', `/api/mesh/${j.mesh_id}/basis`, { laplacian: 'fem', k: 40 });
    if (b.status >= 300) throw new Error(`basis for ${s}: ${b.buf}`);
  }
  for (const { id } of ids) {
    for (;;) {
      const st = JSON.parse((await call('GET', `/api/mesh/${id}/basis/status`)).buf);
      if (st.state !== 'running') { if (st.state !== 'done') throw new Error(st.message); break; }
      await new Promise((r) => setTimeout(r, 100));
    }
  }
  return ids;
}

function pick(a, r) { return a[Math.floor(r * a.length) % a.length]; }

async function worker(w, ids) {
  let seed = 12345 + w * 7919;
  const rnd = () => { seed = (seed * 1103515245 + 12345) % 2147483648; return seed / 2147483648; };
  for (let i = 0; i < REQUESTS; i++) {
    const m = pick(ids, rnd());
    const kind = Math.floor(rnd() * 12);
    let req, valid = true;
    const field = (p) => ['POST', `/api/mesh/${m.id}/field`, p];
    switch (kind) {
      case 0: req = ['POST', '/api/mesh', { shape: pick(shapes, rnd()) }]; break;
      case 1: req = ['GET', `/api/mesh/${m.id}/geometry`]; break;
      case 2: req = field({ kind: 'heat', k: 40, t: 0.001 + 0.05 * rnd(), anchor: Math.floor(rnd() * m.n), levels: 10 }); break;
      case 3: req = field({ kind: 'distance', k: 40, distance: pick(['diffusion:t=0.01', 'commute', 'biharmonic', 'mix:a=0.5,t=0.01'], rnd()), source: Math.floor(rnd() * m.n) }); break;
      case 4: req = field({ kind: 'harmonic', constraints: pick([2, 4], rnd()) }); break;
      case 5: req = ['GET', `/api/mesh/${m.id}/download?format=txt&body=${encodeURIComponent(JSON.stringify({ kind: 'spectral-function', k: 40, filter: 'diffusion:t=0.1' }))}`]; break;
      case 6: valid = false; req = ['POST', '/api/mesh', { shape: 'no-such-shape' }]; break;
      case 7: valid = false; req = ['POST', `/api/mesh/${m.id}/field`, '{"kind":"heat","k":40,"t":NaN}', { 'Content-Type': 'application/json' }]; break;
      case 8: valid = false; req = field({ kind: 'heat', k: m.n + 1 }); break;
      case 9: valid = false; req = field({ kind: 'distance', k: 40, source: m.n + 3 }); break;
      case 10: valid = false; req = ['POST', '/api/mesh', 'OFF\n3 1 0\n0 0 0\nnope\n', { 'Content-Type': 'application/octet-stream', 'X-Filename': 'bad.off' }]; break;
      default: valid = false; req = ['POST', '/api/mesh', new Uint8Array((1 << 20) + 4096), { 'Content-Type': 'application/octet-stream', 'X-Filename': 'big.off' }]; break;
    }
    const t0 = performance.now();
    let r;
    try { r = await call(...req); } catch (e) { r = { status: 0, buf: Buffer.from(String(e)) }; }
    stats.latencies.push(performance.now() - t0);
    if (valid) {
      stats.valid++;
      if (r.status < 200 || r.status >= 300) { stats.validFailed++; failures.push(`valid ${kind}: ${r.status} ${r.buf.toString().slice(0, 200)}`); }
    } else {
      stats.invalid++;
      let msg = '';
      try { msg = JSON.parse(r.buf).error; } catch (_) { /* not JSON */ }
      if (r.status < 400 || r.status >= 500 || !msg) { stats.invalidWrong++; failures.push(`invalid ${kind}: ${r.status} ${r.buf.toString().slice(0, 200)}`); }
    }
  }
}

const ids = await prepare();
const t0 = performance.now();
await Promise.all(Array.from({ length: WORKERS }, (_, w) => worker(w, ids)));
const secs = (performance.now() - t0) / 1000;
const health = await call('GET', '/api/health');
const lat = stats.latencies.sort((a, b) => a - b);
const q = (p) => lat[Math.min(lat.length - 1, Math.floor(p * lat.length))].toFixed(1);
console.log(JSON.stringify({
  workers: WORKERS, requests: WORKERS * REQUESTS, seconds: +secs.toFixed(2),
  requests_per_second: +(WORKERS * REQUESTS / secs).toFixed(1),
  latency_ms: { p50: q(0.5), p95: q(0.95), max: q(0.999) },
  valid: stats.valid, invalid: stats.invalid, health: JSON.parse(health.buf),
}));
for (const f of failures.slice(0, 10)) console.log('FAIL ' + f);
const ok = health.status === 200 && stats.validFailed === 0 && stats.invalidWrong === 0;
console.log(`load: ${ok ? 1 : 0} passed, ${ok ? 0 : 1} failed`);
process.exit(ok ? 0 : 1);
