// spectral-mesh web app: the page. Talks to the server's /api (JSON + binary), draws with
// three.js. Per-vertex colours are computed here from the Float32 field values, so
// switching the colour map needs no request.
import * as THREE from 'three';
import { OrbitControls } from '/vendor/OrbitControls.js';

const $ = (id) => document.getElementById(id);
// The page's experiments, each one kind of the library's field request (see fieldRequest).
const USES_FILTER = new Set(['distance', 'signature', 'segmentation', 'embedding']);

const app = {
  meshId: null, n: 0, m: 0, info: null, positions: null, triangles: null,
  basisKey: null,        // "laplacian:k" of a basis known to be held
  pending: null,         // an update waiting for the one in flight
  inFlight: false,
  inputTime: 0,          // performance.now() of the input that started the update
  field: null,
};
window.__app = app;
window.__lastField = null;
window.__timings = [];

// ---------- three.js scene ----------
const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xffffff);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
scene.add(new THREE.AmbientLight(0xffffff, 0.55));
const light = new THREE.DirectionalLight(0xffffff, 1.6);
camera.add(light);
light.position.set(1, 2, 3);
scene.add(camera);
let meshObj = null, levelObj = null, critObj = null, markerObj = null;
let bboxDiag = 1;

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  render();
}
window.addEventListener('resize', resize);
function render() { renderer.render(scene, camera); }
controls.addEventListener('change', render);

// ---------- helpers ----------
function showError(msg) {
  const e = $('error');
  e.textContent = msg || '';
  e.classList.toggle('shown', !!msg);
  window.__lastError = msg || null;
}

async function api(method, url, body, binary = false) {
  const opts = { method, headers: {} };
  if (body instanceof ArrayBuffer || body instanceof Uint8Array || body instanceof Blob) {
    opts.body = body;
    opts.headers['Content-Type'] = 'application/octet-stream';
  } else if (body !== undefined) {
    opts.body = JSON.stringify(body);
    opts.headers['Content-Type'] = 'application/json';
  }
  return fetchWith(url, opts, binary);
}

async function fetchWith(url, opts, binary) {
  const r = await fetch(url, opts);
  if (!r.ok) {
    let msg = `${r.status} ${r.statusText}`;
    try { const j = await r.json(); if (j.error) msg = j.error; } catch (_) { /* not JSON */ }
    const err = new Error(msg);
    err.status = r.status;
    throw err;
  }
  return binary ? r.arrayBuffer() : r.json();
}

// ---------- colour maps ----------
const STOPS = {
  viridis: ['440154', '482878', '3e4989', '31688e', '26828e', '1f9e89', '35b779', '6ece58', 'b5de2b', 'fde725'],
  turbo: ['30123b', '4145ab', '4675ed', '39a2fc', '1bcfd4', '24eca6', '61fc6c', 'a4fc3b', 'd1e834', 'f3c63a', 'fe9b2d', 'f36315', 'd93806', 'b11901', '7a0403'],
  diverging: ['3b4cc0', '7092f3', 'aac7fd', 'dddddd', 'f7b89c', 'e7755b', 'b40426'],
};
const STOP_RGB = Object.fromEntries(Object.entries(STOPS).map(([k, v]) =>
  [k, v.map((h) => [parseInt(h.slice(0, 2), 16) / 255, parseInt(h.slice(2, 4), 16) / 255, parseInt(h.slice(4, 6), 16) / 255])]));

function hue(u, out, o) {
  // HSV hue from red through yellow, green, cyan, blue to magenta (as the server's files).
  const h = Math.min(Math.max(u, 0), 1) * 5;
  const x = 1 - Math.abs((h % 2) - 1);
  let r = 0, g = 0, b = 0;
  switch (Math.min(Math.floor(h), 4)) {
    case 0: r = 1; g = x; break;
    case 1: r = x; g = 1; break;
    case 2: g = 1; b = x; break;
    case 3: g = x; b = 1; break;
    default: r = x; b = 1;
  }
  out[o] = r; out[o + 1] = g; out[o + 2] = b;
}

function colorize(values, lo, hi, map) {
  const n = values.length;
  const out = new Float32Array(3 * n);
  let a = lo, d = hi - lo;
  if (map === 'diverging' && lo < 0 && hi > 0) { const m = Math.max(-lo, hi); a = -m; d = 2 * m; }
  if (!(d > 0)) d = 1;
  const stops = STOP_RGB[map];
  for (let i = 0; i < n; i++) {
    const u = (values[i] - a) / d;
    if (!stops) { hue(u, out, 3 * i); continue; }
    const s = Math.min(Math.max(u, 0), 1) * (stops.length - 1);
    const j = Math.min(Math.floor(s), stops.length - 2), f = s - j;
    const c0 = stops[j], c1 = stops[j + 1];
    out[3 * i] = c0[0] + f * (c1[0] - c0[0]);
    out[3 * i + 1] = c0[1] + f * (c1[1] - c0[1]);
    out[3 * i + 2] = c0[2] + f * (c1[2] - c0[2]);
  }
  return out;
}

// ---------- parameters ----------
function tValue() { return Math.pow(10, parseFloat($('t').value)); }

function params() {
  const src = $('source').value.trim();
  return {
    experiment: $('experiment').value,
    laplacian: $('laplacian').value,
    k: parseInt($('k').value, 10),
    t: tValue(),
    a: parseFloat($('a').value),
    filter: $('filter').value,
    custom: $('custom').value,
    custom_kind: $('custom-kind').value,
    source: src === '' ? null : parseInt(src, 10), // null: the library's default (largest x)
    constraints: $('constraints').value,
    levels: parseInt($('levels').value, 10),
    component: parseInt($('component').value, 10),
    persistence: parseFloat($('persistence').value),
  };
}

// The filter in the library's text form (spectral_mesh::spectral::filters).
function filterText(p) {
  switch (p.filter) {
    case 'diffusion': return `diffusion:t=${p.t}`;
    case 'mix': return `mix:a=${p.a},t=${p.t}`;
    case 'custom': return `custom-${p.custom_kind === 'phi' ? 'phi' : 'w'}:${p.custom};t=${p.t},a=${p.a}`;
    default: return p.filter; // commute, biharmonic
  }
}

// Harmonic constraints: a preset count (2, 4, 6) or "vertex=value,..." pairs.
function constraintsOf(text) {
  const t = text.trim();
  if (/^[246]$/.test(t)) return parseInt(t, 10);
  return t.split(',').map((item) => {
    const m = item.trim().match(/^(\d+)\s*=\s*(\S+)$/);
    if (!m || !Number.isFinite(Number(m[2]))) throw new Error(`constraints: '${item.trim()}' should be vertex=value (or use 2, 4 or 6)`);
    return { vertex: parseInt(m[1], 10), value: Number(m[2]) };
  });
}

// The body of a field request: the library's FieldRequest (serde form, tagged by kind)
// plus the analysis keys and the number of level sets.
function fieldRequest(p) {
  const withSource = (key, r) => (p.source === null ? r : { ...r, [key]: p.source });
  let r;
  switch (p.experiment) {
    case 'harmonic': r = { kind: 'harmonic', constraints: constraintsOf(p.constraints) }; break;
    case 'heat': r = withSource('anchor', { kind: 'heat', t: p.t, k: p.k }); break;
    case 'diffusion': r = withSource('source', { kind: 'distance', distance: `wfem-diffusion:t=${p.t}`, k: p.k }); break;
    case 'distance': r = withSource('source', { kind: 'distance', distance: filterText(p), k: p.k }); break;
    case 'signature': r = { kind: 'spectral-function', filter: filterText(p), k: p.k }; break;
    case 'segmentation': r = { kind: 'segmentation', signature: p.filter === 'diffusion' ? `hks:t=${p.t}` : `spectral-function:${filterText(p)}`, persistence: p.persistence, k: p.k }; break;
    case 'embedding': r = { kind: 'embedding', filter: filterText(p), component: p.component, k: p.k }; break;
    default: r = { kind: 'eigenfunction', index: p.component, k: p.k };
  }
  return { ...r, laplacian: p.laplacian, normalize: true, levels: p.levels };
}

function refreshParamVisibility() {
  const p = params();
  const show = (cls, on) => document.querySelectorAll('.' + cls).forEach((e) => e.classList.toggle('shown', on));
  const usesFilter = USES_FILTER.has(p.experiment);
  show('p-filter', usesFilter);
  show('p-custom', usesFilter && p.filter === 'custom');
  show('p-t', p.experiment === 'heat' || p.experiment === 'diffusion' || (usesFilter && ['diffusion', 'mix', 'custom'].includes(p.filter)));
  show('p-a', usesFilter && (p.filter === 'mix' || p.filter === 'custom'));
  show('p-component', p.experiment === 'embedding' || p.experiment === 'eigenfunction');
  show('p-persistence', p.experiment === 'segmentation');
  show('p-constraints', p.experiment === 'harmonic');
  $('click-hint').textContent = p.experiment === 'harmonic'
    ? 'click the surface to add a constraint (vertex = click value)'
    : 'click the surface to set the source / anchor';
  $('t-val').textContent = tValue().toPrecision(3);
  $('a-val').textContent = $('a').value;
  $('levels-val').textContent = $('levels').value;
}

// ---------- mesh ----------
function describeInfo(r) {
  const i = r.info;
  const lines = [
    `${r.source}`,
    `vertices ${i.vertices}   triangles ${i.triangles}   edges ${i.edges}`,
    `components ${i.components}   χ ${i.euler_characteristic}   genus ${i.genus ?? '–'}`,
    `boundary loops ${i.boundary_loops}   closed manifold ${i.closed_manifold ? 'yes' : 'no'}`,
    `problems: ${i.problems.length ? i.problems.join('; ') : 'none'}`,
  ];
  return lines.join('\n');
}

async function setMesh(reply) {
  app.meshId = reply.mesh_id; app.n = reply.n; app.m = reply.m; app.info = reply.info;
  app.basisKey = null;
  $('info').textContent = describeInfo(reply);
  const shapeName = String(reply.source).split(':')[0];
  if ([...$('shape-select').options].some((o) => o.value === shapeName)) $('shape-select').value = shapeName;
  $('k').max = String(reply.n);
  if (parseInt($('k').value, 10) > reply.n) $('k').value = String(Math.min(reply.n, 100));
  $('source').value = ''; // the library's default source on the new mesh
  const buf = await api('GET', `/api/mesh/${app.meshId}/geometry`, undefined, true);
  const dv = new DataView(buf);
  const n = dv.getUint32(0, true), m = dv.getUint32(4, true);
  app.positions = new Float32Array(buf, 8, 3 * n);
  app.triangles = new Uint32Array(buf, 8 + 12 * n, 3 * m);
  buildMeshObject();
  window.__meshLoaded = (window.__meshLoaded || 0) + 1;
  await requestUpdate();
}

function buildMeshObject() {
  for (const o of [meshObj, levelObj, critObj, markerObj]) if (o) { scene.remove(o); o.geometry.dispose(); }
  levelObj = critObj = markerObj = null;
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(app.positions, 3));
  g.setIndex(new THREE.BufferAttribute(app.triangles, 1));
  g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(app.positions.length).fill(0.8), 3));
  g.computeVertexNormals();
  g.computeBoundingSphere();
  const mat = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
  meshObj = new THREE.Mesh(g, mat);
  scene.add(meshObj);
  const s = g.boundingSphere;
  bboxDiag = 2 * s.radius;
  controls.target.copy(s.center);
  camera.position.copy(s.center).add(new THREE.Vector3(0.4, 0.5, 1).normalize().multiplyScalar(s.radius * 4.2));
  camera.near = s.radius / 100; camera.far = s.radius * 100;
  camera.updateProjectionMatrix();
  controls.update();
  render();
}

async function loadShape(spec) {
  showError(null);
  try { await setMesh(await api('POST', '/api/mesh', { shape: spec })); } catch (e) { showError(e.message); }
}

async function loadFile(file) {
  showError(null);
  try {
    const r = await fetchWith('/api/mesh', {
      method: 'POST', body: file,
      headers: { 'Content-Type': 'application/octet-stream', 'X-Filename': file.name.replace(/[^\x20-\x7e]/g, '_') },
    }, false);
    await setMesh(r);
  } catch (e) { showError(`${file.name}: ${e.message}`); }
}

// ---------- basis ----------
async function ensureBasis(p) {
  const key = `${p.laplacian}:${p.k}`;
  if (app.basisKey === key) return true;
  const want = { laplacian: p.laplacian, normalize: true, k: p.k };
  const mine = (st) => st.laplacian === p.laplacian && st.normalize === true && st.held_k >= p.k;
  let st = await api('POST', `/api/mesh/${app.meshId}/basis`, want);
  // A computation for other parameters (another tab) may cancel this one: ask again, a
  // few times.
  for (let tries = 0; !(st.state === 'done' && mine(st)); ) {
    if (st.state === 'error') throw new Error(`eigenbasis: ${st.message}`);
    setProgress(st);
    await new Promise((r) => setTimeout(r, 150));
    st = await api('GET', `/api/mesh/${app.meshId}/basis/status`);
    if (st.state !== 'running' && !(st.state === 'done' && mine(st))) {
      if (++tries > 3) throw new Error(`eigenbasis: ${st.message}`);
      st = await api('POST', `/api/mesh/${app.meshId}/basis`, want);
    }
  }
  setProgress(st);
  app.basisKey = key;
  return true;
}

function setProgress(st) {
  $('progress-bar').style.width = `${Math.round(100 * (st.progress || 0))}%`;
  $('basis-status').textContent = `${st.laplacian || ''} k=${st.k || ''}: ${st.state} ${st.message || ''}`;
}

// ---------- field ----------
function parseField(buf) {
  const dv = new DataView(buf);
  const hl = dv.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, hl)));
  const n = header.n;
  const values = new Float32Array(buf, 4 + hl, n);
  const segs = new Float32Array(buf, 4 + hl + 4 * n, (buf.byteLength - 4 - hl - 4 * n) / 4);
  return { header, values, segs };
}

async function requestUpdate() {
  if (!app.meshId) return;
  app.inputTime = app.inputTime || performance.now();
  if (app.inFlight) { app.pending = true; return; }
  app.inFlight = true;
  try {
    do {
      app.pending = false;
      await updateOnce();
    } while (app.pending);
  } finally {
    app.inFlight = false;
  }
}

async function updateOnce() {
  refreshParamVisibility();
  const p = params();
  const t0 = app.inputTime || performance.now();
  app.inputTime = 0;
  showError(null);
  try {
    const body = fieldRequest(p);
    const needsBasis = body.kind !== 'harmonic';
    if (needsBasis) await ensureBasis(p);
    let buf;
    try {
      buf = await api('POST', `/api/mesh/${app.meshId}/field`, body, true);
    } catch (e) {
      if (e.status !== 409 || !needsBasis) throw e;
      app.basisKey = null; // evicted: compute again
      await ensureBasis(p);
      buf = await api('POST', `/api/mesh/${app.meshId}/field`, body, true);
    }
    const t1 = performance.now();
    app.field = parseField(buf);
    app.field.params = p;
    drawField();
    await new Promise((r) => requestAnimationFrame(() => r()));
    const t2 = performance.now();
    const timing = { total_ms: t2 - t0, fetch_ms: t1 - t0, draw_ms: t2 - t1, server_ms: app.field.header.timing_ms.total, experiment: p.experiment };
    window.__timings.push(timing);
    window.__lastField = { values: Array.from(app.field.values), header: app.field.header, params: p, body, timing };
    window.__fieldCount = (window.__fieldCount || 0) + 1;
    $('field-stats').textContent = `min ${fmt(app.field.header.min)}  max ${fmt(app.field.header.max)}  ·  ${timing.total_ms.toFixed(0)} ms (server ${timing.server_ms.toFixed(0)} ms)`;
  } catch (e) {
    showError(e.message);
    window.__errorCount = (window.__errorCount || 0) + 1;
  }
}

function fmt(x) { return Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-3 && x !== 0) ? x.toExponential(3) : x.toFixed(4); }

function drawField() {
  if (!app.field || !meshObj) return;
  const { header, values, segs } = app.field;
  meshObj.geometry.setAttribute('color', new THREE.BufferAttribute(colorize(values, header.min, header.max, $('colormap').value), 3));
  for (const o of [levelObj, critObj, markerObj]) if (o) { scene.remove(o); o.geometry.dispose(); }
  levelObj = critObj = markerObj = null;
  if ($('show-levels').checked && segs.length) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(segs, 3));
    levelObj = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0x111111 }));
    scene.add(levelObj);
  }
  const cp = header.critical;
  if ($('show-critical').checked && cp) {
    const pts = [], cols = [];
    const add = (v, c) => { pts.push(app.positions[3 * v], app.positions[3 * v + 1], app.positions[3 * v + 2]); cols.push(...c); };
    cp.points.minima.forEach((v) => add(v, [0.1, 0.2, 1]));
    cp.points.maxima.forEach((v) => add(v, [1, 0.1, 0.1]));
    cp.points.saddles.forEach(([v]) => add(v, [0, 0.7, 0.1]));
    if (pts.length) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
      g.setAttribute('color', new THREE.Float32BufferAttribute(cols, 3));
      critObj = new THREE.Points(g, new THREE.PointsMaterial({ size: 9, sizeAttenuation: false, vertexColors: true, depthTest: true }));
      scene.add(critObj);
    }
  }
  if (header.source !== null && header.source !== undefined) {
    const s = header.source;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute([app.positions[3 * s], app.positions[3 * s + 1], app.positions[3 * s + 2]], 3));
    markerObj = new THREE.Points(g, new THREE.PointsMaterial({ size: 14, sizeAttenuation: false, color: 0x000000 }));
    scene.add(markerObj);
  }
  const el = $('critical');
  if (cp) {
    const what = cp.doubled ? '2(m − s + M) inside + (m − s + M) on the boundary' : 'minima − saddles + maxima';
    el.textContent = `minima ${cp.minima}  maxima ${cp.maxima}  saddles ${cp.points.saddles.length} (with multiplicity ${cp.saddles})\n` +
      `${cp.holds ? '✓' : '✗'} ${what} = ${cp.lhs}, ${cp.doubled ? '2χ' : 'χ'} = ${cp.rhs}`;
    el.className = 'info small ' + (cp.holds ? 'ok' : 'bad');
  } else {
    el.textContent = header.categorical ? `${header.max + 1} segments` : '';
    el.className = 'info small';
  }
  render();
}

// ---------- picking ----------
const raycaster = new THREE.Raycaster();
let downAt = null;
renderer.domElement.addEventListener('pointerdown', (e) => { downAt = [e.clientX, e.clientY]; });
renderer.domElement.addEventListener('pointerup', (e) => {
  if (!downAt || Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]) > 4) return;
  pickAt(e.clientX, e.clientY);
});

function pickAt(clientX, clientY) {
  if (!meshObj) return null;
  const r = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  const hit = raycaster.intersectObject(meshObj)[0];
  if (!hit) return null;
  const f = hit.face;
  let best = f.a, bd = Infinity;
  for (const v of [f.a, f.b, f.c]) {
    const d = hit.point.distanceToSquared(new THREE.Vector3(app.positions[3 * v], app.positions[3 * v + 1], app.positions[3 * v + 2]));
    if (d < bd) { bd = d; best = v; }
  }
  app.inputTime = performance.now();
  if ($('experiment').value === 'harmonic') {
    const cur = $('constraints').value.trim();
    const item = `${best}=${$('click-value').value}`;
    $('constraints').value = /^[246]$/.test(cur) || cur === '' ? item : `${cur},${item}`;
  } else {
    $('source').value = String(best);
  }
  requestUpdate();
  return best;
}
window.__pickAt = pickAt;
window.__screenOf = (v) => {
  const p = new THREE.Vector3(app.positions[3 * v], app.positions[3 * v + 1], app.positions[3 * v + 2]).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return [r.left + (p.x + 1) / 2 * r.width, r.top + (1 - p.y) / 2 * r.height];
};

// ---------- downloads ----------
function downloadUrl(format) {
  const body = { ...fieldRequest(params()), colormap: $('colormap').value };
  const q = new URLSearchParams({ format, body: JSON.stringify(body) });
  return `/api/mesh/${app.meshId}/download?${q}`;
}
document.querySelectorAll('#downloads a').forEach((a) => {
  a.addEventListener('click', async (e) => {
    e.preventDefault();
    if (!app.meshId) return;
    const url = downloadUrl(a.dataset.format);
    try {
      const r = await fetch(url);
      if (!r.ok) { let m = r.statusText; try { m = (await r.json()).error; } catch (_) { /* */ } throw new Error(m); }
      const blob = await r.blob();
      const name = (r.headers.get('content-disposition') || '').match(/filename="([^"]+)"/)?.[1] || `field.${a.dataset.format}`;
      const link = document.createElement('a');
      link.href = URL.createObjectURL(blob); link.download = name;
      document.body.appendChild(link); link.click(); link.remove();
      setTimeout(() => URL.revokeObjectURL(link.href), 10000);
    } catch (err) { showError(`download ${a.dataset.format}: ${err.message}`); }
  });
});
window.__downloadUrl = downloadUrl;

// ---------- wiring ----------
function onInput() { app.inputTime = performance.now(); refreshParamVisibility(); requestUpdate(); }
for (const id of ['experiment', 'laplacian', 'filter', 'custom-kind', 'k', 'source', 'constraints', 'component', 'persistence', 'custom']) $(id).addEventListener('change', onInput);
for (const id of ['t', 'a', 'levels']) $(id).addEventListener('input', onInput);
$('colormap').addEventListener('change', () => { drawField(); });
$('show-levels').addEventListener('change', () => drawField());
$('show-critical').addEventListener('change', () => drawField());
$('shape-load').addEventListener('click', () => loadShape($('shape-spec').value));
$('shape-select').addEventListener('change', () => { $('shape-spec').value = $('shape-select').value; loadShape($('shape-spec').value); });
$('file-input').addEventListener('change', (e) => { const f = e.target.files[0]; if (f) loadFile(f); });

async function init() {
  resize();
  refreshParamVisibility();
  try {
    const s = await api('GET', '/api/shapes');
    for (const sh of s.shapes) {
      const o = document.createElement('option');
      o.value = sh.name; o.textContent = sh.name; o.title = sh.description;
      $('shape-select').appendChild(o);
    }
    $('shape-select').value = $('shape-spec').value.split(':')[0];
  } catch (e) { showError(e.message); }
  window.__ready = true;
  await loadShape($('shape-spec').value);
}
init();
