// spectral-mesh web app: the page. Talks to the server's /api (JSON + binary), draws with
// three.js. The per-vertex values go to the GPU once per field (a Float32Array straight from
// the binary reply); the colour map (a 1D texture), the levels and the level-set lines are
// computed in the fragment shader, so changing them costs no request and no per-vertex work.
import * as THREE from 'three';
import { OrbitControls } from '/vendor/OrbitControls.js';

const $ = (id) => document.getElementById(id);
// The page's experiments, each one kind of the library's field request (see fieldRequest).
const USES_FILTER = new Set(['distance', 'signature', 'segmentation', 'embedding']);
const HAS_SOURCE = new Set(['heat', 'diffusion', 'distance', 'geodesic']);
// Kinds computed without an eigenbasis (no basis request first).
const NO_BASIS = new Set(['harmonic', 'geodesic']);
// Stands for +inf (a geodesic distance's unreachable parts) on the GPU: drawn grey.
const UNREACHED = 3e38;

const GUIDANCE = {
  harmonic: 'Harmonic map: the smoothest field that takes the constrained values. Click the surface to add a constraint (values alternate 0, 1); × removes one. Level sets and critical points show its structure.',
  heat: 'Heat kernel: the heat at time t from the anchor (the black-edged star). Click the surface to move the anchor; drag t to let the heat spread.',
  diffusion: 'wFEM diffusion distance from the source (the black-edged star) at time t: small t is local, large t global. Click the surface to move the source.',
  distance: 'Filtered spectral distance from the source (the black-edged star): bi-harmonic by default. Click the surface to move the source; switch the filter to compare distances.',
  signature: 'Spectral signature G(p,p) of every vertex for the filter: a shape descriptor (no source).',
  segmentation: 'Segments: the watershed of a signature, basins whose maxima differ by less than the persistence merged.',
  embedding: 'One coordinate of the spectral embedding for the filter (component 1 is the first non-constant one).',
  eigenfunction: 'One eigenfunction of the Laplacian (component 0 is the constant one); its level sets are nodal-like curves.',
  geodesic: 'Geodesic distance along the surface from the source (the black-edged star), by the heat method, in the mesh\'s units; the level sets are evenly spaced isolines. Click the surface to move the source. Parts the source cannot reach are grey (infinite distance).',
};

const app = {
  meshId: null, n: 0, m: 0, info: null, positions: null, normals: null, triangles: null,
  basisKey: null,        // "laplacian:k" of a basis known to be held
  pending: false,        // an update waiting for the one in flight (coalesced: latest wins)
  inFlight: false,
  inputTime: 0,          // performance.now() of the latest input not yet drawn
  field: null,           // { header, values: Float32Array, params }
  figure: null,          // the figure's description shown (header.figure or /api/figure)
  constraints: null,     // explicit harmonic constraints [{vertex, value}], null: the preset
  lastControl: null,     // id of the control behind the request in flight
  framed: null,          // mesh id the camera was aimed for
  isCloud: false,        // the input is a point cloud (drawn as splats, robust only)
  spacing: 0,            // a cloud's mean point spacing (the library's), sizes the splats
  splatFactor: 0,        // splat radius / spacing (the server's pictures' factor)
  meshLaplacian: null,   // the Laplacian chosen for meshes, restored after a cloud
  defaults: null,        // GET /api/defaults: the library's defaults (the page states none)
};
window.__app = app;
window.__lastField = null;
window.__timings = [];
window.__lastError = null;
window.__markers = {};

// This page's name for the server: a random id made once per tab (on load), sent as
// X-Client-Id on every request, so that the server knows a newer basis request of this
// page supersedes its older one (another mesh's job of the same page is cancelled).
const CLIENT_ID = (() => {
  const b = new Uint8Array(12);
  crypto.getRandomValues(b);
  return 'page-' + Array.from(b, (x) => x.toString(16).padStart(2, '0')).join('');
})();
window.__clientId = CLIENT_ID;

// ---------- three.js scene ----------
const view = $('view');
// No multisampling: in software GL (no GPU) it added 40 % to the time from an input to the
// frame that shows the new field (99 ms against 70 ms, 3-torus, loaded machine); the level
// lines are smoothed in the shader. The drawing buffer is not kept after it is shown (no
// copy per frame): whatever reads the canvas draws it first, in the same task
// (window.__viewPixels); the PNG download is the server's picture.
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: false });
renderer.setPixelRatio(window.devicePixelRatio);
view.prepend(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xffffff);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
scene.add(camera);
let meshObj = null;
const markerObjs = [];
let radius = 1;
const center = new THREE.Vector3();

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  render();
}
window.addEventListener('resize', resize);
// `turning`: drawn for a camera move (OrbitControls): while the camera turns, the surface
// is drawn directly (the per-pixel buffer would be drawn and used once, dearer than one
// direct draw), and the buffer is drawn once the camera has rested for SETTLE_MS.
const SETTLE_MS = 120;
let settleTimer = 0;
function render(turning = false) {
  if (app.isCloud) updateSplatScale();
  else updateSide();
  updateMarkerBias();
  if (turning === true && !app.isCloud && meshObj && deferred.wanted) {
    clearTimeout(settleTimer);
    settleTimer = setTimeout(() => render(), SETTLE_MS);
    renderer.render(scene, camera);
    window.__frameMode = 'direct';
    return;
  }
  if (!app.isCloud && meshObj && deferred.wanted && deferredReady()) {
    // The surface from the per-pixel buffer (one full-screen pass), then the markers.
    meshObj.visible = false; deferred.quad.visible = true;
    renderer.render(scene, camera);
    meshObj.visible = true; deferred.quad.visible = false;
    window.__frameMode = 'deferred';
    return;
  }
  renderer.render(scene, camera);
  window.__frameMode = 'direct';
}
// The 3D view's pixels (RGBA rows, bottom row first), drawn and read in the same task;
// `bothSides` draws every triangle from both sides, as before a closed surface's inner
// side was left out (the tests compare the two).
window.__viewPixels = (bothSides = false, direct = false) => {
  const keep = app.outerSide, keepWanted = deferred.wanted;
  if (bothSides) app.outerSide = null;
  if (direct) deferred.wanted = false;
  render();
  const mode = window.__frameMode;
  const side = fieldMaterial.side;
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(4 * w * h);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  app.outerSide = keep;
  deferred.wanted = keepWanted;
  render();
  return { w, h, mode, side: side === THREE.DoubleSide ? 'double' : side === THREE.BackSide ? 'back' : 'front', data: px };
};
// Markers come towards the viewer by the description's depth bias (f R + s u: R the
// bounding radius, u world units per screen pixel at the target), as the pictures test
// their visibility: a marker at a rim is drawn whole.
const markerBias = { value: 0 };
function updateMarkerBias() {
  const b = app.figure?.marker_depth_bias;
  if (!b) return;
  const h = Math.max(renderer.domElement.clientHeight, 1);
  const ppu = (0.5 * h / Math.tan(THREE.MathUtils.degToRad(camera.fov / 2))) / camera.position.distanceTo(controls.target);
  markerBias.value = b[0] * radius + b[1] / ppu;
}
controls.addEventListener('change', () => render(true));
const nextFrame = () => new Promise((r) => requestAnimationFrame(() => r()));
// The frame that shows what was just rendered: the second animation frame after it (the
// first one's callbacks run before that frame is composited).
const drawnFrame = () => nextFrame().then(nextFrame);

// ---------- the figure: the render crate's description ----------
// Every field reply carries the figure the server's pictures draw (header.figure: colour
// stops, range, level values, lighting, markers, legend, colour bar words); a view-only
// change asks POST /api/figure for the same description with the new options. The page
// draws what the description says and holds no colour, range, number format or marker
// style of its own.
function lut(stops) {
  const data = new Uint8Array(256 * 4);
  const rgb = (stops && stops.length ? stops : ['#cccccc']).map((h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16)));
  for (let i = 0; i < 256; i++) {
    const s = (i / 255) * (rgb.length - 1);
    const j = Math.min(Math.floor(s), Math.max(rgb.length - 2, 0)), f = rgb.length > 1 ? s - j : 0;
    const b = rgb[Math.min(j + 1, rgb.length - 1)];
    for (let c = 0; c < 3; c++) data[4 * i + c] = Math.round(rgb[j][c] + f * (b[c] - rgb[j][c]));
    data[4 * i + 3] = 255;
  }
  return data;
}
const cmapTexture = new THREE.DataTexture(lut(null), 256, 1, THREE.RGBAFormat);
cmapTexture.magFilter = THREE.LinearFilter; cmapTexture.minFilter = THREE.LinearFilter;
cmapTexture.needsUpdate = true;

// The colour of the field at a pixel: the one rule of the direct pass (fieldMaterial) and
// the deferred one (resolveMaterial). The colour map at the value's place in [lo, hi],
// grey for a geodesic distance's unreachable parts (+inf), the shade `vL`, and the
// description's level values lo + (i + 1/2) (hi - lo) / nLevels, i < nLevels, drawn as
// lines lineWidth pixels wide (unshaded, as the pictures draw them); `fw` is the value's
// rate of change per pixel (its fwidth).
const FIELD_COLOUR_GLSL = `
    uniform sampler2D cmap;
    uniform float lo, hi, nLevels, showLevels, hasField, lineWidth;
    uniform vec3 lineColor;
    vec3 fieldColour(float vS, float vL, float fw) {
      if (hasField < 0.5) return vec3(0.8) * vL;
      float u = hi > lo ? (vS - lo) / (hi - lo) : 0.5;
      vec3 c = texture2D(cmap, vec2(clamp(u, 0.0, 1.0) * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb;
      if (vS > 1e38) c = vec3(0.55);
      c *= vL;
      if (showLevels > 0.5 && nLevels > 0.5 && hi > lo) {
        float x = u * nLevels - 0.5;
        float r = floor(x + 0.5);
        float w = max(fw * nLevels / (hi - lo), 1e-6);
        float px = abs(x - r) / w;
        float hw = 0.5 * lineWidth;
        float line = (r >= 0.0 && r <= nLevels - 1.0) ? 1.0 - smoothstep(hw - 0.5, hw + 0.5, px) : 0.0;
        c = mix(c, lineColor, line);
      }
      return c;
    }
`;

const fieldMaterial = new THREE.ShaderMaterial({
  uniforms: {
    cmap: { value: cmapTexture }, lo: { value: 0 }, hi: { value: 1 },
    nLevels: { value: 10 }, showLevels: { value: 1 }, hasField: { value: 0 },
    ambient: { value: 0.35 }, diffuse: { value: 0.65 }, lightDir: { value: new THREE.Vector3(0, 0, 1) },
    lineWidth: { value: 2 }, lineColor: { value: new THREE.Color(0x0f0f0f) },
  },
  // The shade (two-sided Lambert) per vertex, as the server's pictures shade; per fragment
  // only the colour lookup and the level lines. In software GL (no GPU) the fragments of
  // a 100k-vertex mesh are many times its vertices (tiny triangles are shaded in 2 x 2
  // blocks): the normalisation and lighting per fragment cost about a tenth of the frame.
  vertexShader: `
    attribute float scalar;
    uniform float ambient, diffuse;
    uniform vec3 lightDir;
    varying float vS;
    varying float vL;
    void main() {
      vS = scalar;
      vL = ambient + diffuse * abs(dot(normalize(normalMatrix * normal), lightDir));
      gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
    }`,
  fragmentShader: FIELD_COLOUR_GLSL + `
    varying float vS;
    varying float vL;
    void main() {
      gl_FragColor = vec4(fieldColour(vS, vL, fwidth(vS)), 1.0);
    }`,
  side: THREE.DoubleSide,
  polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
});

// ---------- deferred shading: a new field without drawing the triangles again ----------
// In software GL (no GPU) most of a frame at 100k vertices is the geometry: running the
// vertices and setting up the triangles, paid again for every new field although only the
// values change. So when the camera, the mesh, the side drawn or the lighting change, the
// surface is drawn once into an offscreen buffer that keeps, per pixel, its triangle, two
// barycentric coordinates, the shade (interpolated from the vertices', as above) and their
// screen derivatives (for the level lines' width), with the depth. A new field (or colour
// map, range, levels) is then one full-screen pass: it fetches the triangle's three vertex
// values from a data texture (one texel per triangle, filled from the vertex values on
// the CPU for each field: one fetch per pixel instead of four dependent ones), interpolates them and colours the pixel as fieldMaterial's
// fragment shader does; it writes the stored depth, so that the markers drawn after it
// are hidden by the surface as before. Without float render targets (or when the mesh is too
// large for the textures) the surface is drawn directly, as before.
const deferred = {
  wanted: true, failed: false, key: '', target: null, gScene: new THREE.Scene(), gMesh: null,
  vals: null, quad: null, meshId: null, valuesAt: -1, width: 2048,
};
window.__deferred = deferred;
const gMaterial = new THREE.ShaderMaterial({
  glslVersion: THREE.GLSL3,
  uniforms: { ambient: fieldMaterial.uniforms.ambient, diffuse: fieldMaterial.uniforms.diffuse, lightDir: fieldMaterial.uniforms.lightDir },
  // One vertex per triangle corner (no index): the corner is gl_VertexID % 3, the triangle
  // gl_VertexID / 3 (stored + 1: 0 is the background).
  vertexShader: `
    uniform float ambient, diffuse;
    uniform vec3 lightDir;
    out vec2 vB;
    out float vL;
    flat out float vT;
    void main() {
      int c = gl_VertexID % 3;
      vB = vec2(c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0);
      vT = float(gl_VertexID / 3 + 1);
      vL = ambient + diffuse * abs(dot(normalize(normalMatrix * normal), lightDir));
      gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
    }`,
  fragmentShader: `
    in vec2 vB;
    in float vL;
    flat in float vT;
    layout(location = 0) out highp vec4 g0;
    layout(location = 1) out highp vec4 g1;
    void main() {
      g0 = vec4(vT, vB, vL);
      g1 = vec4(dFdx(vB), dFdy(vB));
    }`,
  side: THREE.DoubleSide,
  polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
});
const resolveMaterial = new THREE.ShaderMaterial({
  uniforms: {
    g0: { value: null }, g1: { value: null }, gDepth: { value: null }, vals: { value: null },
    texWidth: { value: deferred.width },
    cmap: fieldMaterial.uniforms.cmap, lo: fieldMaterial.uniforms.lo, hi: fieldMaterial.uniforms.hi,
    nLevels: fieldMaterial.uniforms.nLevels, showLevels: fieldMaterial.uniforms.showLevels,
    hasField: fieldMaterial.uniforms.hasField, lineWidth: fieldMaterial.uniforms.lineWidth,
    lineColor: fieldMaterial.uniforms.lineColor,
  },
  vertexShader: `
    void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }`,
  fragmentShader: FIELD_COLOUR_GLSL + `
    uniform highp sampler2D g0, g1, gDepth, vals;
    uniform int texWidth;
    void main() {
      ivec2 p = ivec2(gl_FragCoord.xy);
      vec4 a = texelFetch(g0, p, 0);
      if (a.x < 0.5) discard;
      int t = int(a.x + 0.5) - 1;
      vec3 s = texelFetch(vals, ivec2(t % texWidth, t / texWidth), 0).xyz;
      float s0 = s.x, s1 = s.y, s2 = s.z;
      float vS = (1.0 - a.y - a.z) * s0 + a.y * s1 + a.z * s2;
      float vL = a.w;
      // The value's change per pixel, as fwidth would take it on the surface: the stored
      // screen derivatives of the barycentric coordinates times the values' differences.
      vec4 d = texelFetch(g1, p, 0);
      float fw = abs((s1 - s0) * d.x + (s2 - s0) * d.y) + abs((s1 - s0) * d.z + (s2 - s0) * d.w);
      vec3 c = fieldColour(vS, vL, fw);
      gl_FragColor = vec4(c, 1.0);
      gl_FragDepth = texelFetch(gDepth, p, 0).r;
    }`,
  depthTest: true, depthWrite: true, depthFunc: THREE.AlwaysDepth,
});
deferred.quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), resolveMaterial);
deferred.quad.frustumCulled = false;
deferred.quad.visible = false;
deferred.quad.renderOrder = -1;
scene.add(deferred.quad);

// A float texture of `data.length / channels` texels, `deferred.width` wide.
function dataTexture(data, channels) {
  const w = deferred.width, h = Math.max(1, Math.ceil(data.length / channels / w));
  const full = new Float32Array(w * h * channels);
  full.set(data);
  const tex = new THREE.DataTexture(full, w, h, channels === 1 ? THREE.RedFormat : THREE.RGBAFormat, THREE.FloatType);
  tex.magFilter = THREE.NearestFilter; tex.minFilter = THREE.NearestFilter;
  tex.needsUpdate = true;
  return tex;
}

// The mesh's per-corner geometry and its per-triangle values texture (once per mesh).
function deferredMesh() {
  if (deferred.meshId === meshObj.id) return;
  const m = app.triangles.length / 3;
  const pos = new Float32Array(9 * m), nrm = new Float32Array(9 * m);
  for (let f = 0; f < m; f++) {
    for (let c = 0; c < 3; c++) {
      const v = app.triangles[3 * f + c];
      for (let j = 0; j < 3; j++) {
        pos[9 * f + 3 * c + j] = app.positions[3 * v + j];
        nrm[9 * f + 3 * c + j] = app.normals[3 * v + j];
      }
    }
  }
  if (deferred.gMesh) { deferred.gScene.remove(deferred.gMesh); deferred.gMesh.geometry.dispose(); }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('normal', new THREE.BufferAttribute(nrm, 3));
  deferred.gMesh = new THREE.Mesh(g, gMaterial);
  deferred.gMesh.frustumCulled = false;
  deferred.gScene.add(deferred.gMesh);
  deferred.vals?.dispose();
  deferred.vals = dataTexture(new Float32Array(4 * m), 4);
  deferred.valuesAt = -1;
  deferred.meshId = meshObj.id;
  deferred.key = '';
}

// The full-screen pass covers only the screen rectangle of the mesh's bounding box (with a
// pixel of margin): the pixels outside it are background.
const corner = new THREE.Vector3();
function fitQuad() {
  const box = meshObj.geometry.boundingBox || (meshObj.geometry.computeBoundingBox(), meshObj.geometry.boundingBox);
  let x0 = 1, y0 = 1, x1 = -1, y1 = -1, whole = false;
  for (let i = 0; i < 8; i++) {
    corner.set(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z);
    corner.applyMatrix4(camera.matrixWorldInverse);
    if (corner.z > -camera.near) { whole = true; break; } // a corner beside or behind the eye
    corner.applyMatrix4(camera.projectionMatrix);
    x0 = Math.min(x0, corner.x); x1 = Math.max(x1, corner.x); y0 = Math.min(y0, corner.y); y1 = Math.max(y1, corner.y);
  }
  const mx = 2 / Math.max(bufferSize.x, 1), my = 2 / Math.max(bufferSize.y, 1);
  if (whole) { x0 = -1; y0 = -1; x1 = 1; y1 = 1; }
  x0 = Math.max(-1, x0 - mx); x1 = Math.min(1, x1 + mx); y0 = Math.max(-1, y0 - my); y1 = Math.min(1, y1 + my);
  const pos = deferred.quad.geometry.getAttribute('position');
  // PlaneGeometry's corners: top left, top right, bottom left, bottom right.
  pos.setXY(0, x0, y1); pos.setXY(1, x1, y1); pos.setXY(2, x0, y0); pos.setXY(3, x1, y0);
  pos.needsUpdate = true;
}

// Whether the full-screen pass can draw the surface now: builds what it needs, draws the
// per-pixel buffer again when the view changed, and uploads the values when they changed.
function deferredReady() {
  if (deferred.failed) return false;
  const caps = renderer.capabilities;
  const w0 = deferred.width;
  const fits = app.triangles.length / 3 < (1 << 24) && Math.ceil(app.triangles.length / 3 / w0) <= caps.maxTextureSize;
  if (!caps.isWebGL2 || !renderer.extensions.has('EXT_color_buffer_float') || !fits) {
    deferred.failed = true;
    return false;
  }
  try {
    deferredMesh();
    renderer.getDrawingBufferSize(bufferSize);
    const w = bufferSize.x, h = bufferSize.y;
    if (!deferred.target) {
      deferred.target = new THREE.WebGLRenderTarget(w, h, {
        count: 2, type: THREE.FloatType, format: THREE.RGBAFormat,
        minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: true,
        depthTexture: new THREE.DepthTexture(w, h, THREE.FloatType),
      });
    } else if (deferred.target.width !== w || deferred.target.height !== h) {
      deferred.target.setSize(w, h);
    }
    const attr = meshObj.geometry.getAttribute('scalar');
    if (deferred.valuesAt !== attr.version) {
      const tv = deferred.vals.image.data, a = attr.array, tri = app.triangles, m = tri.length / 3;
      for (let f = 0; f < m; f++) {
        tv[4 * f] = a[tri[3 * f]]; tv[4 * f + 1] = a[tri[3 * f + 1]]; tv[4 * f + 2] = a[tri[3 * f + 2]];
      }
      deferred.vals.needsUpdate = true;
      deferred.valuesAt = attr.version;
    }
    camera.updateMatrixWorld();
    const u = fieldMaterial.uniforms;
    const key = [...camera.matrixWorldInverse.elements, ...camera.projectionMatrix.elements, w, h, fieldMaterial.side,
      meshObj.id, u.ambient.value, u.diffuse.value, u.lightDir.value.x, u.lightDir.value.y, u.lightDir.value.z].join(',');
    if (key !== deferred.key) {
      if (gMaterial.side !== fieldMaterial.side) { gMaterial.side = fieldMaterial.side; gMaterial.needsUpdate = true; }
      const keepColor = new THREE.Color(); renderer.getClearColor(keepColor);
      const keepAlpha = renderer.getClearAlpha();
      renderer.setClearColor(0x000000, 0);
      renderer.setRenderTarget(deferred.target);
      renderer.render(deferred.gScene, camera);
      renderer.setRenderTarget(null);
      renderer.setClearColor(keepColor, keepAlpha);
      deferred.key = key;
      fitQuad();
      window.__gbufferDraws = (window.__gbufferDraws || 0) + 1;
    }
    const r = resolveMaterial.uniforms;
    r.g0.value = deferred.target.textures[0]; r.g1.value = deferred.target.textures[1];
    r.gDepth.value = deferred.target.depthTexture;
    r.vals.value = deferred.vals;
    return true;
  } catch (e) {
    console.warn('deferred shading off:', e);
    deferred.failed = true;
    return false;
  }
}

// A point cloud: one round splat per point, coloured by the same colour map texture and
// range (the uniforms are shared with the surface's material), a disc of radius
// `point_radius_factor` (the server's, as its pictures) x the library's mean point
// spacing, shaded as a small
// sphere. The splat is pushed back along the view ray by its radius, so that the level
// lines and the markers on the surface stay in front of it. Level sets are not drawn in
// this shader: the page asks the server for the library's level-set segments on the
// triangle union of the cloud's Laplacian and draws them as lines.
const splatMaterial = new THREE.ShaderMaterial({
  uniforms: {
    cmap: fieldMaterial.uniforms.cmap, lo: fieldMaterial.uniforms.lo, hi: fieldMaterial.uniforms.hi,
    hasField: fieldMaterial.uniforms.hasField, radius: { value: 0.01 }, scale: { value: 1 },
  },
  vertexShader: `
    attribute float scalar;
    uniform float radius, scale;
    varying float vS;
    void main() {
      vS = scalar;
      vec4 mv = modelViewMatrix * vec4(position, 1.0);
      mv.xyz += normalize(mv.xyz) * radius;
      gl_Position = projectionMatrix * mv;
      gl_PointSize = max(2.0, 2.0 * radius * scale / max(-mv.z, 1e-6));
    }`,
  fragmentShader: `
    uniform sampler2D cmap;
    uniform float lo, hi, hasField;
    varying float vS;
    void main() {
      vec2 d = gl_PointCoord * 2.0 - 1.0;
      float r2 = dot(d, d);
      if (r2 > 1.0) discard;
      vec3 c = vec3(0.8);
      if (hasField > 0.5) {
        float u = hi > lo ? (vS - lo) / (hi - lo) : 0.5;
        c = texture2D(cmap, vec2(clamp(u, 0.0, 1.0) * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb;
        if (vS > 1e38) c = vec3(0.55);
      }
      gl_FragColor = vec4(c * (0.55 + 0.45 * sqrt(1.0 - r2)), 1.0);
    }`,
});
// Pixels per world unit at distance 1 (the splats' gl_PointSize), from the drawing buffer.
const bufferSize = new THREE.Vector2();
function updateSplatScale() {
  renderer.getDrawingBufferSize(bufferSize);
  splatMaterial.uniforms.scale.value = bufferSize.y * camera.projectionMatrix.elements[5] / 2;
}
// A cloud's level sets: the server's segments, as lines.
let levelObj = null;
const levelMaterial = new THREE.LineBasicMaterial({ color: 0x111111 });
function clearLevelLines() {
  if (levelObj) { scene.remove(levelObj); levelObj.geometry.dispose(); levelObj = null; }
}
function setLevelLines(segments) {
  clearLevelLines();
  window.__levelSegments = segments ? segments.length / 6 : 0;
  if (!segments || !segments.length) return;
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(segments, 3));
  levelObj = new THREE.LineSegments(g, levelMaterial);
  levelObj.renderOrder = 1;
  levelObj.visible = $('show-levels').checked;
  scene.add(levelObj);
}

// ---------- markers: one sprite shape per kind, drawn on the surface ----------
// Shapes, colours and sizes are the description's (marker_styles): the outline polygon in
// the marker's unit box, stroked on the path as the server's pictures draw it.
const MARKER_TEX = {};
let markerStyles = {};
function markerCanvas(st) {
  const c = document.createElement('canvas'); c.width = c.height = 64;
  const g = c.getContext('2d');
  g.beginPath();
  st.outline.forEach(([x, y], i) => g[i ? 'lineTo' : 'moveTo'](64 * x, 64 * y));
  g.closePath();
  g.fillStyle = st.fill; g.fill();
  g.lineWidth = 64 * st.stroke_width; g.strokeStyle = st.stroke; g.stroke();
  return c;
}
function setMarkerStyles(styles) {
  for (const st of styles) {
    const key = JSON.stringify(st);
    if (MARKER_TEX[st.kind]?.key === key) continue;
    const canvas = markerCanvas(st);
    const texture = new THREE.CanvasTexture(canvas); // colours passed through as drawn
    MARKER_TEX[st.kind]?.texture.dispose();
    MARKER_TEX[st.kind] = { texture, url: canvas.toDataURL(), key };
    markerStyles[st.kind] = st;
    const m = MARKER_MAT[st.kind];
    if (m) { m.uniforms.map.value = texture; m.uniforms.size.value = st.size * renderer.getPixelRatio(); }
  }
}
// The legend: the description's rows (the kinds drawn, the level-set line) and its note.
function buildLegend(d) {
  const el = $('legend');
  el.innerHTML = '<div class="lg-title">Legend</div>';
  for (const e of d.legend) {
    const row = document.createElement('div');
    row.dataset.kind = e.kind;
    if (MARKER_TEX[e.kind]) row.innerHTML = `<img alt="" src="${MARKER_TEX[e.kind].url}"><span></span>`;
    else row.innerHTML = `<svg width="16" height="16"><line x1="0" y1="8" x2="16" y2="8" stroke="${d.line_color}" stroke-width="${d.line_width}"/></svg><span></span>`;
    row.querySelector('span').textContent = e.label;
    el.appendChild(row);
  }
  if (d.legend_note) {
    const n = document.createElement('div');
    n.className = 'lg-note'; n.textContent = d.legend_note;
    el.appendChild(n);
  }
  el.hidden = !d.legend.length && !d.legend_note;
}

const MARKER_MAT = {};
function clearMarkers() {
  // The materials stay (one per kind): a new field costs no new material or program.
  for (const o of markerObjs) { scene.remove(o); o.geometry.dispose(); }
  markerObjs.length = 0;
  window.__markers = {};
}
// Points a little above the surface (along the vertex normal), so none is half buried (a
// cloud's splats are pushed back instead).
function addMarkers(kind, vertices) {
  window.__markers[kind] = vertices.length;
  if (!vertices.length) return;
  const pts = new Float32Array(3 * vertices.length);
  vertices.forEach((v, i) => {
    for (let c = 0; c < 3; c++) pts[3 * i + c] = app.positions[3 * v + c];
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pts, 3));
  if (!MARKER_TEX[kind]) return;
  const mat = MARKER_MAT[kind] || (MARKER_MAT[kind] = new THREE.ShaderMaterial({
    uniforms: {
      map: { value: MARKER_TEX[kind].texture }, size: { value: markerStyles[kind].size * renderer.getPixelRatio() },
      bias: markerBias,
    },
    vertexShader: `
      uniform float size, bias;
      void main() {
        vec4 mv = modelViewMatrix * vec4(position, 1.0);
        mv.xyz += normalize(-mv.xyz) * bias;
        gl_Position = projectionMatrix * mv;
        gl_PointSize = size;
      }`,
    fragmentShader: `
      uniform sampler2D map;
      void main() {
        vec4 c = texture2D(map, vec2(gl_PointCoord.x, 1.0 - gl_PointCoord.y));
        if (c.a < 0.3) discard;
        gl_FragColor = c;
      }`,
    transparent: true, depthTest: true,
  }));
  const o = new THREE.Points(g, mat);
  o.renderOrder = kind === 'source' || kind === 'constraint' ? 3 : 2;
  markerObjs.push(o);
  scene.add(o);
}

// ---------- errors: next to the control that caused them ----------
const ERROR_AT = { 'shape-select': 'shape-spec', 'click-value': 'constraint-list', preset: 'constraint-list', 'constraints-clear': 'constraint-list', 'custom-kind': 'custom' };
function clearErrors() {
  document.querySelectorAll('.ctl-error').forEach((e) => e.remove());
  window.__lastError = null;
  $('stale').hidden = true;
  view.classList.remove('stale');
}
function showError(control, msg) {
  const id = ERROR_AT[control] || control || 'experiment';
  const ctl = $(id) || $('experiment');
  const anchor = ctl.closest('.row') || ctl;
  // The page asks for k = n when more than the n vertices are typed: an error about that k
  // names the number typed as well.
  const typed = kWanted();
  if (id === 'k' && app.n && typed > app.n && !msg.includes(String(typed))) {
    msg = `k = ${typed} typed (this ${app.isCloud ? 'point cloud' : 'mesh'} has ${app.n}, so k = ${app.n} was asked): ${msg}`;
  }
  // One error on screen at a time: a later error replaces every earlier one.
  document.querySelectorAll('.ctl-error').forEach((e) => e.remove());
  const div = document.createElement('div');
  div.className = 'ctl-error';
  div.setAttribute('role', 'alert');
  div.dataset.for = id;
  div.textContent = msg;
  anchor.after(div);
  window.__lastError = msg;
  window.__lastErrorFor = id;
  window.__errorCount = (window.__errorCount || 0) + 1;
  if (app.field) {
    $('stale').textContent = 'Stale: this is the last good picture; the new one was refused (see the message in the panel).';
    $('stale').hidden = false;
    view.classList.add('stale');
  }
}

// Every request names this page (X-Client-Id).
function withClient(opts = {}) {
  return { ...opts, headers: { ...(opts.headers || {}), 'X-Client-Id': CLIENT_ID } };
}

async function api(method, url, body, binary = false) {
  const opts = { method, headers: {} };
  if (body !== undefined) {
    opts.body = JSON.stringify(body);
    opts.headers['Content-Type'] = 'application/json';
  }
  return fetchWith(url, opts, binary);
}

async function fetchWith(url, opts, binary) {
  const r = await fetch(url, withClient(opts));
  if (!r.ok) {
    let msg = `${r.status} ${r.statusText}`;
    try { const j = await r.json(); if (j.error) msg = j.error; } catch (_) { /* not JSON */ }
    const err = new Error(msg);
    err.status = r.status;
    throw err;
  }
  return binary ? r.arrayBuffer() : r.json();
}

// ---------- parameters ----------
// t: the slider (log scale), or a value typed in the box beside it (any positive number).
let tTyped = null;
function tValue() { return tTyped ?? Math.pow(10, parseFloat($('t').value)); }
function kWanted() { return parseInt($('k').value, 10); }
// k for this mesh: the request, at most the mesh's vertex count (never carried over).
function kFor(n) { const k = kWanted(); return Number.isFinite(k) && k > n ? n : k; }

function params() {
  const src = $('source').value.trim();
  return {
    experiment: $('experiment').value,
    laplacian: $('laplacian').value,
    k: kFor(app.n),
    t: tValue(),
    a: parseFloat($('a').value),
    filter: $('filter').value,
    custom: $('custom').value,
    custom_kind: $('custom-kind').value,
    source: src === '' ? null : parseInt(src, 10), // null: the library's default (largest x)
    preset: $('preset').value,
    constraints: app.constraints ? app.constraints.map((c) => ({ ...c })) : null,
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

// The body of a field request: the library's FieldRequest (serde form, tagged by kind)
// plus the analysis keys and the picture options the figure is described for (the level
// sets' segments only for a point cloud: the page draws a mesh's in its shader).
function fieldRequest(p) {
  const withSource = (key, r) => (p.source === null ? r : { ...r, [key]: p.source });
  let r;
  switch (p.experiment) {
    case 'harmonic': r = { kind: 'harmonic', constraints: p.constraints ?? parseInt(p.preset, 10) }; break;
    case 'heat': r = withSource('anchor', { kind: 'heat', t: p.t, k: p.k }); break;
    case 'diffusion': r = withSource('source', { kind: 'distance', distance: `wfem-diffusion:t=${p.t}`, k: p.k }); break;
    case 'distance': r = withSource('source', { kind: 'distance', distance: filterText(p), k: p.k }); break;
    case 'signature': r = { kind: 'spectral-function', filter: filterText(p), k: p.k }; break;
    case 'segmentation': r = { kind: 'segmentation', signature: p.filter === 'diffusion' ? `hks:t=${p.t}` : `spectral-function:${filterText(p)}`, persistence: p.persistence, k: p.k }; break;
    case 'embedding': r = { kind: 'embedding', filter: filterText(p), component: p.component, k: p.k }; break;
    case 'geodesic': r = withSource('source', { kind: 'geodesic' }); break;
    default: r = { kind: 'eigenfunction', index: p.component, k: p.k };
  }
  return { ...r, laplacian: p.laplacian, normalize: app.defaults.analysis.normalize, ...figureOptions() };
}

// Why a harmonic request cannot be sent yet (null when it can).
function harmonicMissing(p) {
  if (p.experiment !== 'harmonic' || !p.constraints) return null;
  const values = new Set(p.constraints.map((c) => c.value));
  if (p.constraints.length < 2 || values.size < 2) {
    return `${p.constraints.length} constraint${p.constraints.length === 1 ? '' : 's'}: click ${p.constraints.length ? 'another vertex' : 'two vertices'} on the surface (a harmonic map needs two different values), or pick a preset.`;
  }
  return null;
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
  show('p-source', HAS_SOURCE.has(p.experiment));
  $('guidance').textContent = GUIDANCE[p.experiment] || '';
  if (document.activeElement !== $('t-num')) $('t-num').value = String(Number(tValue().toPrecision(3)));
  $('a-val').textContent = $('a').value;
  $('levels-val').textContent = $('levels').value;
  $('click-value').disabled = $('click-mode').value !== 'fixed';
  renderConstraintList();
}

// ---------- harmonic constraints ----------
function shownConstraints() {
  if (app.constraints) return app.constraints;
  const h = app.field?.header;
  return h && h.kind === 'harmonic' ? h.constraints : [];
}
function renderConstraintList() {
  const ol = $('constraint-list');
  ol.innerHTML = '';
  const list = shownConstraints();
  list.forEach((c, i) => {
    const li = document.createElement('li');
    li.textContent = `vertex ${c.vertex} = ${c.value}`;
    const b = document.createElement('button');
    b.textContent = '×'; b.title = 'remove this constraint';
    b.dataset.index = String(i);
    b.addEventListener('click', () => {
      app.constraints = shownConstraints().map((x) => ({ vertex: x.vertex, value: x.value }));
      app.constraints.splice(i, 1);
      $('preset').value = 'clicks';
      drawMarkers(); // the removed marker goes now, not with the next map
      render();
      onInput({ target: { id: 'constraint-list' } });
    });
    li.appendChild(b);
    ol.appendChild(li);
  });
  const why = harmonicMissing(params());
  if (why) {
    const li = document.createElement('li');
    li.className = 'hint'; li.textContent = why;
    ol.appendChild(li);
  }
}
function addConstraint(v) {
  const cur = shownConstraints().map((x) => ({ vertex: x.vertex, value: x.value }));
  const value = $('click-mode').value === 'fixed' ? Number($('click-value').value) : (cur.length % 2 === 0 ? 0 : 1);
  const at = cur.findIndex((c) => c.vertex === v);
  if (at >= 0) cur[at].value = value; else cur.push({ vertex: v, value });
  app.constraints = cur;
  $('preset').value = 'clicks';
  drawMarkers();
  render();
}

// ---------- mesh ----------
function describeInfo(r) {
  const i = r.info;
  if (r.kind === 'point cloud') {
    return [
      `${r.source}`,
      `point cloud: ${i.points} points, ${i.normals ? `${i.normals} with normals` : 'no normals'}`,
      `point-cloud Laplacian (robust): ${i.neighbors} neighbours`,
      `triangle union ${i.union_triangles} triangles, components ${i.components}`,
      `mean point spacing ${fmt(i.point_spacing)}`,
    ].join('\n');
  }
  const lines = [
    `${r.source}`,
    `vertices ${i.vertices}   triangles ${i.triangles}   edges ${i.edges}`,
    `components ${i.components}   χ ${i.euler_characteristic}   genus ${i.genus ?? '–'}`,
    `boundary loops ${i.boundary_loops}   closed manifold ${i.closed_manifold ? 'yes' : 'no'}`,
    `problems: ${i.problems.length ? i.problems.join('; ') : 'none'}`,
  ];
  return lines.join('\n');
}

// What the input is and which Laplacian is used: a point cloud has only its point-cloud
// Laplacian (robust); the other choices are disabled while it is loaded, and the mesh
// choice comes back with the next mesh.
function applyInputKind(reply) {
  const sel = $('laplacian');
  const cloud = reply.kind === 'point cloud';
  if (cloud && !app.isCloud) app.meshLaplacian = sel.value;
  app.isCloud = cloud;
  app.spacing = cloud ? (reply.point_spacing || 0) : 0;
  app.splatFactor = cloud ? reply.point_radius_factor : 0;
  const allowed = new Set(reply.laplacians || [...sel.options].map((o) => o.value));
  for (const o of sel.options) o.disabled = !allowed.has(o.value);
  if (cloud) sel.value = 'robust';
  else if (app.meshLaplacian) { sel.value = app.meshLaplacian; app.meshLaplacian = null; }
  const el = $('input-kind');
  if (cloud) {
    el.textContent = `Input: point cloud (${reply.n} points), drawn as splats. Laplacian: robust, the point-cloud `
      + `Laplacian of Sharp & Crane (${reply.info.neighbors} neighbours); the others need triangles. Level sets and `
      + `critical points are those of the triangle union it is built on (${reply.info.union_triangles} triangles).`;
  } else {
    el.textContent = `Input: triangle mesh (${reply.n} vertices, ${reply.m} triangles).`;
  }
  el.dataset.kind = reply.kind;
  const level = document.querySelector('#legend [data-kind="level"] span');
  if (level) level.textContent = cloud ? 'level set (on the triangle union)' : 'level set';
}

async function setMesh(reply, fileName = null) {
  app.meshId = reply.mesh_id; app.n = reply.n; app.m = reply.m; app.info = reply.info;
  app.basisKey = null;
  app.field = null;
  app.figure = null;
  app.framed = null;
  app.constraints = null;
  applyInputKind(reply);
  if ($('preset').value === 'clicks') $('preset').value = '2';
  $('info').textContent = describeInfo(reply);
  const sel = $('shape-select');
  sel.querySelectorAll('option.file').forEach((o) => o.remove());
  if (fileName) {
    const o = document.createElement('option');
    o.className = 'file'; o.value = ''; o.textContent = `file: ${fileName}`;
    sel.prepend(o);
    sel.value = '';
    $('shape-spec').value = ''; // not the shape shown before
    $('shape-spec').placeholder = `file: ${fileName} (type a shape spec to load one)`;
  } else {
    const shapeName = String(reply.source).split(':')[0];
    if ([...sel.options].some((o) => o.value === shapeName)) sel.value = shapeName;
  }
  $('source').value = ''; // the library's default source on the new mesh
  const buf = await api('GET', `/api/mesh/${app.meshId}/geometry`, undefined, true);
  const dv = new DataView(buf);
  const n = dv.getUint32(0, true), m = dv.getUint32(4, true);
  app.positions = new Float32Array(buf, 8, 3 * n);
  app.triangles = new Uint32Array(buf, 8 + 12 * n, 3 * m);
  buildMeshObject();
  window.__meshLoaded = (window.__meshLoaded || 0) + 1;
  showK(null);
  await requestUpdate();
}

function buildMeshObject() {
  if (meshObj) { scene.remove(meshObj); meshObj.geometry.dispose(); }
  clearMarkers();
  clearLevelLines();
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(app.positions, 3));
  g.setAttribute('scalar', new THREE.BufferAttribute(new Float32Array(app.n), 1));
  g.computeBoundingSphere();
  const s = g.boundingSphere;
  radius = s.radius; center.copy(s.center);
  app.radius = radius;
  fieldMaterial.uniforms.hasField.value = 0;
  if (app.isCloud) {
    // Splats; the "normals" only aim the camera at the source: outward from the centre.
    const nrm = new Float32Array(3 * app.n);
    for (let v = 0; v < app.n; v++) {
      const d = [0, 1, 2].map((c) => app.positions[3 * v + c] - center.getComponent(c));
      const l = Math.hypot(...d) || 1;
      for (let c = 0; c < 3; c++) nrm[3 * v + c] = d[c] / l;
    }
    app.normals = nrm;
    if (!(app.spacing > 0)) app.spacing = 2 * radius / Math.sqrt(Math.max(app.n, 1)); // a guess
    splatMaterial.uniforms.radius.value = app.splatFactor * app.spacing;
    app.outerSide = null;
    meshObj = new THREE.Points(g, splatMaterial);
  } else {
    g.setIndex(new THREE.BufferAttribute(app.triangles, 1));
    g.computeVertexNormals();
    app.normals = g.getAttribute('normal').array;
    meshObj = new THREE.Mesh(g, fieldMaterial);
    app.outerSide = closedSide(app.triangles, app.positions, app.n);
  }
  scene.add(meshObj);
  aimCamera(new THREE.Vector3(0.4, 0.5, 1).normalize());
}

// The side of a closed surface seen from outside it: FrontSide when every edge is shared by
// two triangles that run through it in opposite directions (a closed surface, one
// orientation) and the enclosed volume is positive (the triangles face outwards),
// BackSide when it is negative, null for any other mesh (both sides drawn). From outside
// the bounding sphere of such a surface that does not cross itself, the other side's
// triangles are always behind this side's: not drawing them changes no pixel and, in
// software GL, saves a quarter to a third of the frame at 100k vertices.
function closedSide(tris, pos, n) {
  const m = tris.length / 3;
  if (!m) return null;
  const open = new Map();
  let vol = 0;
  const edge = (p, q) => {
    const back = q * n + p;
    if (open.has(back)) { open.delete(back); return true; }
    const k = p * n + q;
    if (open.has(k)) return false; // two triangles run through p -> q: not one orientation
    open.set(k, 1);
    return true;
  };
  for (let f = 0; f < m; f++) {
    const a = tris[3 * f], b = tris[3 * f + 1], c = tris[3 * f + 2];
    if (a === b || b === c || c === a) return null; // a degenerate triangle: both sides
    if (!edge(a, b) || !edge(b, c) || !edge(c, a)) return null;
    const ax = pos[3 * a], ay = pos[3 * a + 1], az = pos[3 * a + 2];
    const bx = pos[3 * b], by = pos[3 * b + 1], bz = pos[3 * b + 2];
    const cx = pos[3 * c], cy = pos[3 * c + 1], cz = pos[3 * c + 2];
    vol += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  }
  if (open.size) return null;
  return vol > 0 ? THREE.FrontSide : vol < 0 ? THREE.BackSide : null;
}
// Both sides while the camera is inside the bounding sphere (it may be inside the surface).
function updateSide() {
  const side = app.outerSide !== null && app.outerSide !== undefined && !app.isCloud
    && camera.position.distanceTo(center) > radius * 1.001 ? app.outerSide : THREE.DoubleSide;
  if (fieldMaterial.side !== side) { fieldMaterial.side = side; fieldMaterial.needsUpdate = true; }
}

function aimCamera(dir) {
  controls.target.copy(center);
  camera.position.copy(center).addScaledVector(dir, radius * 3.4);
  camera.near = radius / 100; camera.far = radius * 100;
  camera.updateProjectionMatrix();
  controls.update();
}

// Once per mesh: turn the camera so that the source is in sight (not on the hidden side).
function frameSource(v) {
  if (app.framed === app.meshId || v === null || v === undefined) return;
  app.framed = app.meshId;
  const p = new THREE.Vector3(app.positions[3 * v], app.positions[3 * v + 1], app.positions[3 * v + 2]);
  const nrm = new THREE.Vector3(app.normals[3 * v], app.normals[3 * v + 1], app.normals[3 * v + 2]);
  const base = new THREE.Vector3(0.4, 0.5, 1).normalize();
  const out = p.clone().sub(center).normalize();
  const candidates = [base, base.clone().multiplyScalar(-1), base.clone().add(out).normalize(),
    base.clone().add(nrm).normalize(), nrm.clone(), out.clone()];
  const ray = new THREE.Raycaster();
  ray.params.Points.threshold = app.splatFactor * app.spacing;
  for (const dir of candidates) {
    if (!(dir.lengthSq() > 0.5)) continue;
    aimCamera(dir);
    camera.updateMatrixWorld();
    const toP = p.clone().sub(camera.position);
    const dist = toP.length();
    ray.set(camera.position, toP.normalize());
    const hit = ray.intersectObject(meshObj)[0];
    if (hit && Math.abs(hit.distance - dist) < 0.02 * radius) return;
  }
  aimCamera(base);
}

async function loadShape(spec) {
  clearErrors();
  app.lastControl = 'shape-spec';
  try { await setMesh(await api('POST', '/api/mesh', { shape: spec })); } catch (e) { showError('shape-spec', e.message); }
}

async function loadFile(file) {
  clearErrors();
  app.lastControl = 'file-input';
  try {
    const r = await fetchWith('/api/mesh', {
      method: 'POST', body: file,
      headers: { 'Content-Type': 'application/octet-stream', 'X-Filename': file.name.replace(/[^\x20-\x7e]/g, '_') },
    }, false);
    await setMesh(r, file.name);
  } catch (e) {
    // The server's messages about the file already name it (as it was sent).
    const sent = file.name.replace(/[^\x20-\x7e]/g, '_');
    showError('file-input', e.message.includes(sent) ? e.message : `${file.name}: ${e.message}`);
  }
}

// ---------- basis ----------
// Computes (or finds) the basis the request needs. Returns false, without waiting for
// it, when a newer input arrived meanwhile (or another mesh was loaded): the next update
// asks again with the latest values, so a basis for another k (or mesh) supersedes this
// one on the server, which cancels it.
async function ensureBasis(p) {
  const key = `${p.laplacian}:${p.k}`;
  if (app.basisKey === key) return true;
  const id = app.meshId;
  const normalize = app.defaults.analysis.normalize;
  const want = { laplacian: p.laplacian, normalize, k: p.k };
  const mine = (st) => st.laplacian === p.laplacian && st.normalize === normalize && st.held_k >= p.k;
  const moved = () => app.pending || app.meshId !== id;
  let st = await api('POST', `/api/mesh/${id}/basis`, want);
  // A computation for other parameters (another tab) may cancel this one: ask again, a
  // few times.
  for (let tries = 0; !(st.state === 'done' && mine(st)); ) {
    if (st.state === 'error') throw new Error(`eigenbasis: ${st.message}`);
    setProgress(st);
    await new Promise((r) => setTimeout(r, 150));
    if (moved()) return false;
    st = await api('GET', `/api/mesh/${id}/basis/status`);
    if (!['running', 'queued'].includes(st.state) && !(st.state === 'done' && mine(st))) {
      if (++tries > 3) throw new Error(`eigenbasis: ${st.message}`);
      st = await api('POST', `/api/mesh/${id}/basis`, want);
    }
  }
  setProgress(st);
  if (app.meshId !== id) return false;
  app.basisKey = key;
  return true;
}

function setProgress(st) {
  $('progress-bar').style.width = `${Math.round(100 * (st.progress || 0))}%`;
  $('basis-status').textContent = `${st.laplacian || ''} k=${st.k || ''}: ${st.state} ${st.message || ''}`;
}

function showK(header) {
  const want = kWanted();
  let text = `k requested ${want}`;
  if (header && header.k !== null && header.k !== undefined) {
    text = `k used ${header.k} (of ${header.basis_k} held)`;
    if (header.k < want) text += `: this ${app.isCloud ? 'point cloud' : 'mesh'} has ${app.n} ${app.isCloud ? 'points' : 'vertices'}, ${want} requested`;
  } else if (header) {
    text = 'k: no eigenbasis used';
  } else if (app.n && want > app.n) {
    text = `k ${app.n} on this ${app.isCloud ? 'point cloud' : 'mesh'} (${app.n} ${app.isCloud ? 'points' : 'vertices'}; ${want} requested)`;
  }
  $('k-used').textContent = text;
}

// ---------- field ----------
function parseField(buf) {
  const dv = new DataView(buf);
  const hl = dv.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, hl)));
  const values = new Float32Array(buf, 4 + hl, header.n);
  const nSeg = (header.level_counts || []).reduce((a, b) => a + b, 0);
  const segments = new Float32Array(buf, 4 + hl + 4 * header.n, 6 * nSeg);
  return { header, values, segments };
}

// One request in flight; inputs during it coalesce into one more request with the latest
// values.
async function requestUpdate() {
  if (!app.meshId) return;
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
  const control = app.lastControl;
  const waiting = harmonicMissing(p);
  if (waiting) {
    clearErrors();
    renderConstraintList();
    return;
  }
  try {
    // A mesh's level sets are drawn in the shader; a cloud's are the library's segments.
    const body = { ...fieldRequest(p), segments: app.isCloud };
    const needsBasis = !NO_BASIS.has(body.kind);
    const id = app.meshId;
    if (needsBasis && !(await ensureBasis(p))) return; // superseded by a newer input
    let buf;
    try {
      buf = await api('POST', `/api/mesh/${id}/field`, body, true);
    } catch (e) {
      if (e.status !== 409 || !needsBasis) throw e;
      app.basisKey = null; // evicted: compute again
      if (!(await ensureBasis(p))) return;
      buf = await api('POST', `/api/mesh/${id}/field`, body, true);
    }
    if (app.pending || app.meshId !== id) return; // a newer input: draw that one instead
    const t1 = performance.now();
    app.field = parseField(buf);
    app.field.params = p;
    app.field.body = body;
    clearErrors();
    drawField();
    // The view options changed while the field was computed: describe it for them.
    const sent = { colormap: body.colormap, levels: body.levels, critical_points: body.critical_points };
    if (JSON.stringify(sent) !== JSON.stringify(figureOptions())) {
      api('POST', '/api/figure', { summary: app.figure.summary, options: figureOptions() })
        .then((d) => { applyDescription(d); render(); }).catch((err) => showError('colormap', err.message));
    }
    await drawnFrame();
    const t2 = performance.now();
    window.__drawnAt = t2;
    const h = app.field.header;
    const timing = { total_ms: t2 - t0, fetch_ms: t1 - t0, draw_ms: t2 - t1, server_ms: h.timing_ms.total, experiment: p.experiment, control };
    window.__timings.push(timing);
    window.__lastField = { values: app.field.values, header: h, params: p, body, timing };
    window.__fieldCount = (window.__fieldCount || 0) + 1;
    $('field-stats').textContent = `input to drawn frame ${timing.total_ms.toFixed(0)} ms (server ${timing.server_ms.toFixed(0)} ms)`;
  } catch (e) {
    let at = control;
    if (/\bk\b must|eigenbasis of k|pairs/.test(e.message) && !/constraint/.test(e.message)) at = 'k';
    if (/expression|custom/.test(e.message)) at = 'custom';
    if (/constraint/.test(e.message)) at = 'constraint-list';
    if (/^laplacian:|needs triangles|point-cloud Laplacian/.test(e.message)) at = 'laplacian';
    showError(at, e.message);
  }
}
window.__lastFieldPlain = () => {
  const f = window.__lastField;
  return f && { ...f, values: Array.from(f.values) };
};

function fmt(x) {
  if (!Number.isFinite(x)) return String(x);
  return Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-3 && x !== 0) ? x.toExponential(2) : x.toPrecision(4);
}

// The picture options the description is asked for (the View panel's controls).
function figureOptions() {
  return {
    colormap: $('colormap').value,
    levels: $('show-levels').checked ? parseInt($('levels').value, 10) : 0,
    critical_points: $('show-critical').checked,
  };
}

// The colour bar of the description: its stops, title, tick labels and units line.
function drawColorbar(d) {
  const c = $('colorbar-canvas');
  const g = c.getContext('2d');
  const img = g.createImageData(256, 1);
  img.data.set(lut(d?.stops));
  for (let y = 0; y < c.height; y++) g.putImageData(img, 0, y);
  const cb = d?.colorbar;
  $('colorbar').hidden = !cb;
  if (!cb) return;
  $('colorbar-title').textContent = cb.title;
  const ticks = $('colorbar-ticks');
  ticks.replaceChildren(...cb.ticks.map((t) => { const e = document.createElement('span'); e.textContent = t.label; return e; }));
  $('colorbar-units').textContent = cb.units;
}

// Where the overlays sit: the description's layout (the pictures place theirs the same).
function placeOverlays(lay) {
  const px = (v) => `${v}px`;
  Object.assign($('legend').style, { top: px(lay.legend_inset), right: px(lay.legend_inset) });
  Object.assign($('colorbar').style, { left: px(lay.colorbar_inset), bottom: px(lay.colorbar_inset), width: px(lay.colorbar_width) });
  $('colorbar-canvas').style.height = px(lay.colorbar_height);
}

// Shows a figure description: colour texture, range, levels, line, lighting (uniforms
// only), markers, legend and colour bar.
function applyDescription(d) {
  app.figure = d;
  window.__figure = d;
  const u = fieldMaterial.uniforms;
  // What did not change is not redone: a new field of the same look costs uniforms only
  // (no texture upload, no legend or colour bar repaint in the frames after it).
  const changed = (k, v) => { const j = JSON.stringify(v); if (shown[k] === j) return false; shown[k] = j; return true; };
  if (changed('stops', d.stops)) {
    cmapTexture.image.data.set(lut(d.stops));
    cmapTexture.needsUpdate = true;
  }
  u.lo.value = d.range[0]; u.hi.value = d.range[1];
  u.nLevels.value = d.levels.length;
  u.showLevels.value = d.levels.length ? 1 : 0;
  u.lineWidth.value = d.line_width * renderer.getPixelRatio();
  u.lineColor.value.set(d.line_color);
  u.ambient.value = d.lighting.ambient; u.diffuse.value = d.lighting.diffuse;
  u.lightDir.value.set(...d.lighting.direction);
  if (levelObj) levelObj.visible = d.levels.length > 0;
  levelMaterial.color.set(d.line_color);
  setMarkerStyles(d.marker_styles);
  if (changed('layout', d.layout)) placeOverlays(d.layout);
  if (changed('legend', [d.legend, d.legend_note])) buildLegend(d);
  if (changed('colorbar', [d.stops, d.colorbar])) drawColorbar(d);
  drawMarkers();
}
const shown = {};

function drawField() {
  if (!app.field || !meshObj) return;
  const { header, values } = app.field;
  const attr = meshObj.geometry.getAttribute('scalar');
  attr.array.set(values);
  if (header.unreachable && header.unreachable.length) {
    for (let i = 0; i < attr.array.length; i++) if (!Number.isFinite(attr.array[i])) attr.array[i] = UNREACHED;
  }
  attr.needsUpdate = true;
  fieldMaterial.uniforms.hasField.value = 1;
  if (app.isCloud) setLevelLines(app.field.segments);
  frameSource(header.source);
  applyDescription(header.figure);
  showK(header);
  renderConstraintList();
  const el = $('critical');
  const cp = header.critical;
  if (cp && cp.flat) {
    el.textContent = `constant field: the values agree within ${cp.flat_tolerance} of the largest (one plateau): no critical points`;
    el.className = 'info small';
  } else if (cp) {
    const what = cp.doubled ? '2(m − s + M) inside + (m − s + M) on the boundary' : 'minima − saddles + maxima';
    el.textContent = `minima ${cp.minima}  maxima ${cp.maxima}  saddles ${cp.points.saddles.length} (with multiplicity ${cp.saddles})\n` +
      `${cp.holds ? '✓' : '✗'} ${what} = ${cp.lhs}, ${cp.doubled ? '2χ' : 'χ'} = ${cp.rhs}` +
      hiddenNote(cp);
    el.className = 'info small ' + (cp.holds ? 'ok' : 'bad');
  } else {
    el.textContent = header.categorical ? `${header.max + 1} segments` : '';
    el.className = 'info small';
  }
  const tr = header.truncation;
  const te = $('truncation');
  te.textContent = tr ? tr.message : (header.unreachable_message || '');
  te.className = (tr && tr.warning) || header.unreachable_message ? 'small warn' : 'small';
  render();
}

// How many raw critical points the persistence simplification hides (the library's
// threshold, reported with the field), with the raw counts.
function hiddenNote(cp) {
  const h = cp.hidden;
  if (!h) return '';
  const n = h.minima + h.maxima + h.saddles;
  if (n === 0) return '';
  return `\n${n} hidden: persistence below ${cp.persistence_threshold.toPrecision(3)} ` +
    `(raw: minima ${cp.raw.minima}  maxima ${cp.raw.maxima}  saddles ${cp.raw.saddles})`;
}

// The markers of the field drawn, with the constraints as the page holds them now (a
// constraint removed or added is shown at once, not when the next map arrives).
function drawMarkers() {
  clearMarkers();
  const d = app.figure;
  for (const m of d?.marks || []) {
    if (m.kind === 'constraint') continue;
    addMarkers(m.kind, m.vertices.filter((v) => v < app.n));
  }
  const h = app.field?.header;
  const constraints = $('experiment').value === 'harmonic' ? shownConstraints() : (h?.constraints || []);
  if (app.positions) addMarkers('constraint', constraints.map((c) => c.vertex).filter((v) => v < app.n));
}

// ---------- picking ----------
const raycaster = new THREE.Raycaster();
let downAt = null;
renderer.domElement.addEventListener('pointerdown', (e) => { downAt = [e.clientX, e.clientY]; });
renderer.domElement.addEventListener('pointerup', (e) => {
  if (!downAt || Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]) > 4) return;
  pickAt(e.clientX, e.clientY);
});

function vertexAt(clientX, clientY) {
  if (!meshObj) return null;
  const r = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  if (app.isCloud) {
    // The splat under the cursor: of the points within a splat radius of the ray, the one
    // nearest to the ray among those in the front layer (within two spacings of the first).
    const rad = app.splatFactor * app.spacing;
    raycaster.params.Points.threshold = rad;
    const hits = raycaster.intersectObject(meshObj);
    if (!hits.length) return null;
    const front = hits[0].distance + 2 * app.spacing;
    let best = hits[0];
    for (const h of hits) {
      if (h.distance > front) break;
      if (h.distanceToRay < best.distanceToRay) best = h;
    }
    return best.index;
  }
  const hit = raycaster.intersectObject(meshObj)[0];
  if (!hit) return null;
  const f = hit.face;
  let best = f.a, bd = Infinity;
  for (const v of [f.a, f.b, f.c]) {
    const d = hit.point.distanceToSquared(new THREE.Vector3(app.positions[3 * v], app.positions[3 * v + 1], app.positions[3 * v + 2]));
    if (d < bd) { bd = d; best = v; }
  }
  return best;
}
window.__vertexAt = vertexAt;

function pickAt(clientX, clientY) {
  const v = vertexAt(clientX, clientY);
  if (v === null) return null;
  app.inputTime = performance.now();
  if ($('experiment').value === 'harmonic') {
    addConstraint(v);
    app.lastControl = 'constraint-list';
  } else {
    $('source').value = String(v);
    app.lastControl = 'source';
  }
  requestUpdate();
  return v;
}
window.__pickAt = pickAt;
window.__screenOf = (v) => {
  const p = new THREE.Vector3(app.positions[3 * v], app.positions[3 * v + 1], app.positions[3 * v + 2]).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return [r.left + (p.x + 1) / 2 * r.width, r.top + (1 - p.y) / 2 * r.height];
};

// ---------- downloads ----------
// The camera on screen in the render crate's text form (eye, target, up, vertical field
// of view): the download draws what the page shows.
function cameraText() {
  const n = (v) => [v.x, v.y, v.z].map(String).join(',');
  return `camera:${n(camera.position)},${n(controls.target)},${n(camera.up)},${camera.fov}`;
}
// A download: the field request with the picture options on screen, the camera, and the
// size (the canvas times the chosen scale) and print resolution chosen.
function downloadBody(format) {
  const c = renderer.domElement;
  const scale = Number($('dl-scale').value) || 1;
  const dpi = Math.round(Number($('dl-dpi').value));
  return {
    ...fieldRequest(params()), format, view: cameraText(),
    size: Math.round(c.clientWidth * scale), height: Math.round(c.clientHeight * scale), scale,
    ...(dpi > 0 ? { dpi } : {}),
  };
}
function downloadUrl(format) {
  const body = downloadBody(format);
  const q = new URLSearchParams({ format, body: JSON.stringify(body) });
  return `/api/mesh/${app.meshId}/download?${q}`;
}
window.__downloadBody = downloadBody;
document.querySelectorAll('#downloads a').forEach((a) => {
  a.addEventListener('click', async (e) => {
    e.preventDefault();
    if (!app.meshId) return;
    const url = downloadUrl(a.dataset.format);
    try {
      const r = await fetch(url, withClient());
      if (!r.ok) { let m = r.statusText; try { m = (await r.json()).error; } catch (_) { /* */ } throw new Error(m); }
      const blob = await r.blob();
      const name = (r.headers.get('content-disposition') || '').match(/filename="([^"]+)"/)?.[1] || `field.${a.dataset.format}`;
      const link = document.createElement('a');
      link.href = URL.createObjectURL(blob); link.download = name;
      document.body.appendChild(link); link.click(); link.remove();
      setTimeout(() => URL.revokeObjectURL(link.href), 10000);
    } catch (err) { showError('downloads', `download ${a.dataset.format}: ${err.message}`); }
  });
});
window.__downloadUrl = downloadUrl;

// ---------- wiring ----------
function onInput(e) {
  // Timed from the input event itself (its time stamp), not from when the handler ran.
  app.inputTime = e?.timeStamp > 0 ? Math.min(e.timeStamp, performance.now()) : performance.now();
  app.lastControl = e?.target?.id || null;
  refreshParamVisibility();
  requestUpdate();
}
// View-only changes: no field request; the figure's description for the new options
// (one small request), recoloured on the GPU; timed from the input to the frame.
let viewSeq = 0;
async function onViewInput(e) {
  // A cloud's level sets are the server's segments: a new number of levels is a request.
  if (app.isCloud && (e.target.id === 'levels' || e.target.id === 'show-levels')) { onInput(e); return; }
  const t0 = e?.timeStamp > 0 ? Math.min(e.timeStamp, performance.now()) : performance.now();
  $('levels-val').textContent = $('levels').value;
  const seq = ++viewSeq;
  try {
    if (app.figure) {
      const d = await api('POST', '/api/figure', { summary: app.figure.summary, options: figureOptions() });
      // A newer view change asked meanwhile: its description is the one drawn.
      if (seq === viewSeq) applyDescription(d);
    }
  } catch (err) { showError(e.target.id, err.message); }
  render();
  await drawnFrame();
  window.__timings.push({ total_ms: performance.now() - t0, server_ms: 0, control: e.target.id });
  window.__viewCount = (window.__viewCount || 0) + 1;
}
for (const id of ['experiment', 'laplacian', 'filter', 'custom-kind', 'k', 'source', 'component', 'persistence', 'custom']) $(id).addEventListener('change', onInput);
for (const id of ['t', 'a']) $(id).addEventListener('input', (e) => { if (e.target.id === 't') tTyped = null; onInput(e); });
$('t-num').addEventListener('change', (e) => {
  const v = Number($('t-num').value);
  if (!(v > 0) || !Number.isFinite(v)) { showError('t-num', `t must be a positive number; got '${$('t-num').value}'`); return; }
  tTyped = v;
  $('t').value = String(Math.min(Math.max(Math.log10(v), parseFloat($('t').min)), parseFloat($('t').max)));
  onInput(e);
});
$('preset').addEventListener('change', (e) => {
  if ($('preset').value !== 'clicks') app.constraints = null;
  else if (!app.constraints) app.constraints = shownConstraints().map((c) => ({ vertex: c.vertex, value: c.value }));
  onInput(e);
});
$('constraints-clear').addEventListener('click', (e) => {
  app.constraints = [];
  $('preset').value = 'clicks';
  drawMarkers();
  render();
  onInput(e);
});
$('click-mode').addEventListener('change', () => refreshParamVisibility());
$('levels').addEventListener('input', onViewInput);
$('colormap').addEventListener('change', onViewInput);
$('show-levels').addEventListener('change', onViewInput);
$('show-critical').addEventListener('change', onViewInput);
$('shape-load').addEventListener('click', () => loadShape($('shape-spec').value));
$('shape-select').addEventListener('change', () => {
  if (!$('shape-select').value) return;
  $('shape-spec').value = $('shape-select').value;
  loadShape($('shape-spec').value);
});
$('file-input').addEventListener('change', (e) => { const f = e.target.files[0]; if (f) loadFile(f); });

// The controls' starting values, from the library's defaults (GET /api/defaults).
function applyDefaults(d) {
  app.defaults = d;
  const req = d.requests;
  $('shape-spec').value = d.shape;
  $('laplacian').value = d.default_laplacian.mesh;
  $('k').value = String(d.analysis.k);
  $('k').max = String(d.limits.max_k);
  tTyped = req.heat.t; // exact; the slider shows it on its log scale
  $('t').value = String(Math.log10(req.heat.t));
  $('component').value = String(req.embedding.component);
  $('persistence').value = String(req.segmentation.persistence);
  $('levels').value = String(d.figure.levels);
  $('levels-val').textContent = $('levels').value;
}

async function init() {
  try { applyDefaults(await api('GET', '/api/defaults')); } catch (e) { showError('shape-spec', e.message); return; }
  resize();
  refreshParamVisibility();
  drawColorbar(null);
  try {
    const s = await api('GET', '/api/shapes');
    for (const sh of s.shapes) {
      const o = document.createElement('option');
      o.value = sh.name; o.textContent = sh.name; o.title = sh.description;
      $('shape-select').appendChild(o);
    }
    $('shape-select').value = $('shape-spec').value.split(':')[0];
  } catch (e) { showError('shape-spec', e.message); }
  window.__ready = true;
  await loadShape($('shape-spec').value);
}
init();
