// Where a frame's time goes in software GL: opens the page a running server serves
// (SPECTRAL_MESH_URL), loads a mesh with a heat field, then times (1) single draws of the
// scene under variations (canvas size, shader, culling, attribute upload), each draw
// followed by a 1-pixel read that waits for the GL work, and (2) input-to-drawn-frame of
// t-slider moves as the browser test does, with the animation-frame timeline after each.
// Not a test: `node web/e2e/frame_probe.mjs [app.js ...]` with the page files to compare
// (served instead of the server's app.js, taken in turn); default: the server's own.
//   PROBE_SHAPE (default torus:res=5), PROBE_K (200), PROBE_MOVES (10), PROBE_ROUNDS (2),
//   PROBE_MICRO=0 (moves only), PROBE_CONFIGS (the variations timed, comma-separated)
import fs from 'node:fs';
import { launch, loadHeat } from './common.mjs';

const URL = process.env.SPECTRAL_MESH_URL;
if (!URL) { console.error('SPECTRAL_MESH_URL is not set'); process.exit(2); }
const SHAPE = process.env.PROBE_SHAPE || 'torus:res=5';
const K = Number(process.env.PROBE_K || 200);
const MOVES = Number(process.env.PROBE_MOVES || 10);
const ROUNDS = Number(process.env.PROBE_ROUNDS || 2);
const MICRO = process.env.PROBE_MICRO !== '0';
// PROBE_CONFIGS=base,direct,...: only these variations (default all).
const ONLY = (process.env.PROBE_CONFIGS || '').split(',').filter(Boolean);
const files = process.argv.slice(2);
const variants = files.length ? files : [null];

// Appended to the page's module: its scene, for the probe only.
const EXPOSE = `\n;window.__probe = { THREE, renderer, scene, camera, fieldMaterial, mesh: () => meshObj, render, markerObjs,
  deferred: typeof deferred === 'undefined' ? null : deferred,
  resolve: typeof resolveMaterial === 'undefined' ? null : resolveMaterial };\n`;

const median = (a) => { const s = [...a].sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };

async function openVariant(file) {
  const gpuBefore = new Set(procsOfType('gpu-process'));
  const b = await launch();
  b.gpuPid = procsOfType('gpu-process').find((p) => !gpuBefore.has(p));
  const { page } = b;
  page.on('crash', () => console.log('the page crashed'));
  page.on('pageerror', (e) => console.log('page error:', e.message));
  await page.route('**/app.js', async (route) => {
    const r = await route.fetch();
    const body = (file ? fs.readFileSync(file, 'utf8') : await r.text()) + EXPOSE;
    await route.fulfill({ response: r, body, headers: { ...r.headers(), 'content-type': 'text/javascript' } });
  });
  await page.goto(URL);
  await page.waitForFunction(() => (window.__fieldCount || 0) > 0, null, { timeout: 600000 });
  await loadHeat(page, SHAPE, K, 3600000);
  return b;
}

// Chromium's processes of a type (gpu-process, renderer): pids.
function procsOfType(type) {
  const out = [];
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const c = fs.readFileSync(`/proc/${d}/cmdline`, 'utf8');
      if (c.includes('chromium') && c.includes(`--type=${type}`)) out.push(Number(d));
    } catch (_) { /* gone */ }
  }
  return out;
}
// CPU time (user + system, ms) of a process and its threads.
function cpuMs(pid) {
  try {
    const f = fs.readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
    return (Number(f[11]) + Number(f[12])) * 10;
  } catch (_) { return NaN; }
}

// In the page: variations of the scene, each with a set and an undo.
const CONFIGS = `(() => {
  const P = window.__probe;
  const { renderer, THREE, fieldMaterial } = P;
  const gl = renderer.getContext();
  const px = new Uint8Array(4);
  const mesh = P.mesh();
  const g = mesh.geometry;
  const attr = g.getAttribute('scalar');
  const mat = mesh.material;
  const size = new THREE.Vector2(); renderer.getSize(size);
  const simple = new THREE.ShaderMaterial({
    vertexShader: 'void main() { gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }',
    fragmentShader: 'void main() { gl_FragColor = vec4(0.5, 0.5, 0.5, 1.0); }', side: THREE.DoubleSide,
  });
  const basic = new THREE.MeshBasicMaterial({ color: 0x888888, side: THREE.DoubleSide });
  const side = (m, s) => { m.side = s; m.needsUpdate = true; };
  const cam = P.camera; const pos = cam.position.clone();
  const C = {
    base: [() => {}, () => {}],
    upload: [() => {}, () => {}, () => { attr.needsUpdate = true; }],
    front_side: [() => side(fieldMaterial, THREE.FrontSide), () => side(fieldMaterial, THREE.DoubleSide)],
    no_levels: [() => { fieldMaterial.uniforms.showLevels.value = 0; }, () => { fieldMaterial.uniforms.showLevels.value = 1; }],
    simple_double: [() => { mesh.material = simple; }, () => { mesh.material = mat; }],
    simple_front: [() => { mesh.material = simple; side(simple, THREE.FrontSide); }, () => { mesh.material = mat; side(simple, THREE.DoubleSide); }],
    basic_double: [() => { mesh.material = basic; }, () => { mesh.material = mat; }],
    no_mesh: [() => { mesh.visible = false; }, () => { mesh.visible = true; }],
    no_markers: [() => { for (const o of P.markerObjs) o.visible = false; }, () => { for (const o of P.markerObjs) o.visible = true; }],
    half_canvas: [() => renderer.setSize(Math.round(size.x / 2), Math.round(size.y / 2), false), () => renderer.setSize(size.x, size.y, false)],
    canvas_64: [() => renderer.setSize(64, 64, false), () => renderer.setSize(size.x, size.y, false)],
    half_triangles: [() => g.setDrawRange(0, Math.floor(g.index.count / 6) * 3), () => g.setDrawRange(0, Infinity)],
    simple_64: [() => { mesh.material = simple; renderer.setSize(64, 64, false); }, () => { mesh.material = mat; renderer.setSize(size.x, size.y, false); }],
    shuffled: [() => { window.__idx = g.index.array.slice(); const a = g.index.array; const m = a.length / 3; let s = 1; for (let t = m - 1; t > 0; t--) { s = (s * 1103515245 + 12345) % 2147483648; const j = s % (t + 1); for (let c = 0; c < 3; c++) { const x = a[3 * t + c]; a[3 * t + c] = a[3 * j + c]; a[3 * j + c] = x; } } g.index.needsUpdate = true; }, () => { g.index.array.set(window.__idx); g.index.needsUpdate = true; }],
    no_polygon_offset: [() => { fieldMaterial.polygonOffset = false; }, () => { fieldMaterial.polygonOffset = true; }],
    // The page with the full-screen pass (deferred shading): drawn directly instead, and
    // with its per-pixel buffer drawn again before each draw (as after a camera move).
    direct: [() => { if (P.deferred) P.deferred.wanted = false; }, () => { if (P.deferred) P.deferred.wanted = true; }],
    buffer_again: [() => {}, () => {}, () => { if (P.deferred) P.deferred.key = ''; }],
    resolve_min: [() => { const r = P.resolve; P.keepFs = r.fragmentShader; r.fragmentShader = 'uniform highp sampler2D g0; void main() { vec4 a = texelFetch(g0, ivec2(gl_FragCoord.xy), 0); if (a.x < 0.5) discard; gl_FragColor = vec4(a.www, 1.0); }'; r.needsUpdate = true; },
      () => { P.resolve.fragmentShader = P.keepFs; P.resolve.needsUpdate = true; }],
    resolve_no_depth: [() => { const r = P.resolve; P.keepFs = r.fragmentShader; r.fragmentShader = r.fragmentShader.replace(/gl_FragDepth[^;]*;/, ''); r.needsUpdate = true; },
      () => { P.resolve.fragmentShader = P.keepFs; P.resolve.needsUpdate = true; }],
    resolve_bits: [() => { const r = P.resolve; P.keepFs = r.fragmentShader; r.fragmentShader = r.fragmentShader.replace('ivec2(t % texWidth, t / texWidth)', 'ivec2(t & 2047, t >> 11)'); r.needsUpdate = true; },
      () => { P.resolve.fragmentShader = P.keepFs; P.resolve.needsUpdate = true; }],
    resolve_no_vals: [() => { const r = P.resolve; P.keepFs = r.fragmentShader; r.fragmentShader = r.fragmentShader.replace('texelFetch(vals, ivec2(t % texWidth, t / texWidth), 0).xyz', 'a.yzw'); r.needsUpdate = true; },
      () => { P.resolve.fragmentShader = P.keepFs; P.resolve.needsUpdate = true; }],
    resolve_no_cmap: [() => { const r = P.resolve; P.keepFs = r.fragmentShader; r.fragmentShader = r.fragmentShader.replace('texture(cmap, vec2(clamp(u, 0.0, 1.0) * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb', 'vec3(u)'); r.needsUpdate = true; },
      () => { P.resolve.fragmentShader = P.keepFs; P.resolve.needsUpdate = true; }],
    resolve_fetch_only: [() => { const r = P.resolve; P.keepFs = r.fragmentShader; r.fragmentShader = 'uniform highp sampler2D g0, g1, gDepth, vals; void main() { ivec2 p = ivec2(gl_FragCoord.xy); vec4 a = texelFetch(g0, p, 0); if (a.x < 0.5) discard; int t = int(a.x + 0.5) - 1; vec3 s = texelFetch(vals, ivec2(t & 2047, t >> 11), 0).xyz; vec4 d = texelFetch(g1, p, 0); gl_FragColor = vec4(s * a.w + d.xyz, 1.0); gl_FragDepth = texelFetch(gDepth, p, 0).r; }'; r.needsUpdate = true; },
      () => { P.resolve.fragmentShader = P.keepFs; P.resolve.needsUpdate = true; }],
    far_camera: [() => { cam.position.sub(P.mesh().position).multiplyScalar(2); cam.updateMatrixWorld(); }, () => { cam.position.copy(pos); cam.updateMatrixWorld(); }],
  };
  const once = (pre) => { if (pre) pre(); P.render(); gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px); };
  const only = ONLY;
  for (const n of Object.keys(C)) if (only.length && !only.includes(n)) delete C[n];
  window.__cfg = {
    names: Object.keys(C),
    set: (n) => { C[n][0](); once(C[n][2]); },
    unset: (n) => { C[n][1](); once(); },
    time: (n, reps) => { const ts = []; for (let i = 0; i < reps; i++) { const t = performance.now(); once(C[n][2]); ts.push(performance.now() - t); } return ts; },
  };
  return Object.keys(C);
})()`;

// Each variation in turn, `rounds` times, `reps` draws each: the median wall time of a
// draw (with its 1-pixel read) and the CPU time the GPU process spent per draw.
async function micro(page, gpuPid, rounds = 3, reps = 3) {
  const names = await page.evaluate(CONFIGS.replace('ONLY', JSON.stringify(ONLY)));
  const wall = {}, cpu = {};
  for (let r = 0; r < rounds; r++) {
    for (const n of names) {
      await page.evaluate((x) => window.__cfg.set(x), n);
      const c0 = cpuMs(gpuPid);
      const ts = await page.evaluate(([x, k]) => window.__cfg.time(x, k), [n, reps]);
      const c1 = cpuMs(gpuPid);
      await page.evaluate((x) => window.__cfg.unset(x), n);
      (wall[n] ||= []).push(...ts);
      (cpu[n] ||= []).push((c1 - c0) / reps);
    }
  }
  const out = {};
  for (const n of names) out[n] = `${median(wall[n]).toFixed(0)}/${median(cpu[n]).toFixed(0)}`;
  return out;
}

// t moves as the browser test does, with the rAF timeline (ms after the input) of the
// frames until the one that shows the field and 3 after.
async function moves(page, n) {
  const out = [];
  for (let i = 0; i < n; i++) {
    const r = await page.evaluate(async (v) => {
      const frames = [];
      let live = true;
      const tick = (ts) => { frames.push(ts); if (live) requestAnimationFrame(tick); };
      const before = window.__fieldCount || 0;
      const t = document.getElementById('t');
      const t0 = performance.now();
      requestAnimationFrame(tick);
      t.value = String(v);
      t.dispatchEvent(new Event('input', { bubbles: true }));
      while ((window.__fieldCount || 0) === before) await new Promise((r) => setTimeout(r, 1));
      await new Promise((r) => setTimeout(r, 150));
      live = false;
      const f = window.__lastField.timing;
      return { test: window.__drawnAt - t0, fetch: f.fetch_ms, draw: f.draw_ms, server: f.server_ms, frames: frames.map((x) => Math.round(x - t0)) };
    }, -2.2 + 0.04 * (i % 10));
    out.push(r);
  }
  const m = (k) => +median(out.map((x) => x[k])).toFixed(1);
  return { test: m('test'), fetch: m('fetch'), draw: m('draw'), server: m('server'), all: out.map((x) => Math.round(x.test)), frames: out.slice(0, 3).map((x) => x.frames.join(',')) };
}

const load = () => fs.readFileSync('/proc/loadavg', 'utf8').split(' ').slice(0, 3).join(' ');
const browsers = [];
for (const v of variants) browsers.push([v, await openVariant(v)]);
for (let round = 0; round < ROUNDS; round++) {
  for (const [v, b] of browsers) {
    const name = v || 'server app.js';
    if (MICRO) console.log(`MICRO (wall ms / GPU-process CPU ms per draw) ${name} load ${load()} ${JSON.stringify(await micro(b.page, b.gpuPid))}`);
    await moves(b.page, 2);
    console.log(`MOVES ${name} load ${load()} ${JSON.stringify(await moves(b.page, MOVES))}`);
  }
}
for (const [, b] of browsers) await b.close();
