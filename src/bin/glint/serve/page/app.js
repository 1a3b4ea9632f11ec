// glint serve: the page. No libraries: the image is the server's PNG, the
// overlays are segments the server projected with the renderer's camera, and
// the 3-D view is a canvas-2D projection with its own orbit.
'use strict';

const $ = (id) => document.getElementById(id);
const KIND_COLOR = {
  eye: 'rgb(178,178,178)', shadow: 'rgb(25,229,25)', reflected: 'rgb(229,25,25)',
  transmitted: 'rgb(25,25,229)', occlusion: 'rgb(229,204,25)',
};

// The camera's frustum in the 3-D view: magenta, a colour no ray kind, walk
// or grid cell uses (docs/serve.md says so).
const FRUSTUM = 'rgb(230,60,230)';

const S = {
  sid: 's' + Math.random().toString(36).slice(2, 12),
  gen: 0,            // render generation: a newer one stops the older loop
  cam: null,         // the camera the page renders through (null: the scene's)
  sceneCam: null,
  scene: null,       // /api/scene
  version: -1,
  generation: -1,
  pick: null,        // {x, y, query}: the clicked pixel and the query it was traced with
  tree: null, treeOverlay: null,
  walk: null, grid: null,
  spp: 0, target: 0, passes: 0, done: false, rendering: false,
  renders: 0, started: false, imageVersion: -1,
};
window.glint = S;

const v3 = {
  add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
  sub: (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
  mul: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
  dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
  cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
  len: (a) => Math.hypot(a[0], a[1], a[2]),
  norm: (a) => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; },
  // Rodrigues: a rotated by angle t around unit axis k.
  rot: (a, k, t) => {
    const c = Math.cos(t), s = Math.sin(t);
    return v3.add(v3.add(v3.mul(a, c), v3.mul(v3.cross(k, a), s)), v3.mul(k, v3.dot(k, a) * (1 - c)));
  },
};
const fmt = (a) => a ? '(' + a.map((x) => (+x).toFixed(3)).join(', ') + ')' : '-';

// ---- parameters ---------------------------------------------------------

function form() { return $('controls'); }

function params() {
  const f = form();
  const [w, h] = f.size.value.split('x');
  const p = new URLSearchParams({
    w, h, integrator: f.integrator.value, accel: f.accel.value,
    shadows: f.shadows.checked ? 1 : 0, shade_back: f.shade_back.checked ? 1 : 0,
    bounces: f.bounces.value, spp: f.spp.value, sampler: f.sampler.value, filter: f.filter.value,
  });
  if (S.cam) {
    p.set('eye', S.cam.eye.join(','));
    p.set('dir', S.cam.dir.join(','));
    p.set('up', S.cam.up.join(','));
    if (S.cam.kind === 'perspective') p.set('fov', S.cam.fov); else p.set('span', S.cam.span);
  }
  return p;
}

function size() {
  const [w, h] = form().size.value.split('x').map(Number);
  return [w, h];
}

function setOption(sel, value) {
  if (![...sel.options].some((o) => o.value === String(value))) {
    const o = document.createElement('option');
    o.textContent = String(value);
    sel.appendChild(o);
  }
  sel.value = String(value);
}

// ---- progressive render ---------------------------------------------------

async function refine() {
  const gen = ++S.gen;
  const q = params().toString();
  S.rendering = true; S.done = false; S.spp = 0;
  let pass = 0;
  pollProgress(gen);
  while (gen === S.gen) {
    let r;
    try {
      r = await fetch(`/api/render?${q}&session=${S.sid}&seq=${gen}&pass=${pass}`);
    } catch (e) { if (gen === S.gen) status('server unreachable'); break; }
    if (gen !== S.gen) return;
    if (!r.ok) {
      const t = await r.text();
      if (!t.startsWith('superseded')) status(t);
      break;
    }
    const bmp = await createImageBitmap(await r.blob());
    if (gen !== S.gen) return;
    const c = $('image');
    if (c.width !== bmp.width || c.height !== bmp.height) {
      c.width = bmp.width; c.height = bmp.height;
      $('overlay').width = bmp.width; $('overlay').height = bmp.height;
      drawOverlay();
    }
    c.getContext('2d').drawImage(bmp, 0, 0);
    S.spp = +r.headers.get('x-glint-spp');
    S.target = +r.headers.get('x-glint-target');
    S.passes = +r.headers.get('x-glint-pass');
    S.imageVersion = +r.headers.get('x-glint-version');
    S.renders++;
    pass = S.passes;
    status('');
    showProgress(S.spp, 0, 0);
    if ($('show-cost').checked) loadCost();
    if (r.headers.get('x-glint-done') === 'true') { S.done = true; break; }
  }
  if (gen === S.gen) S.rendering = false;
}

function showProgress(spp, done, total) {
  const next = Math.max(1, Math.min(spp, S.target - spp));
  const frac = S.target ? Math.min(1, (spp + (total ? next * done / total : 0)) / S.target) : 0;
  $('bar').style.width = (100 * frac).toFixed(1) + '%';
  $('spp-text').textContent = `${spp} of ${S.target} samples per pixel` + (S.done ? ' (done)' : '');
}

async function pollProgress(gen) {
  while (gen === S.gen && !S.done) {
    await new Promise((res) => setTimeout(res, 250));
    if (gen !== S.gen || S.done) return;
    try {
      const p = await (await fetch(`/api/progress?session=${S.sid}`)).json();
      if (gen === S.gen && !S.done) showProgress(p.spp, p.pass_done, p.pass_total);
    } catch (e) { /* the next render answer says what went wrong */ }
  }
}

function status(t) { $('status').textContent = t; }

async function loadCost() {
  const r = await fetch(`/api/cost?session=${S.sid}`);
  if (!r.ok) return;
  const url = URL.createObjectURL(await r.blob());
  const img = $('cost');
  img.onload = () => URL.revokeObjectURL(url);
  img.src = url;
  $('cost-totals').textContent = `Totals: ${r.headers.get('x-glint-tests')} tests, ${r.headers.get('x-glint-nodes')} nodes.`;
  $('cost-box').hidden = false;
}

// ---- the clicked pixel: ray tree and accelerator walk ---------------------

async function pick(x, y) {
  S.pick = { x, y };
  await refreshPick();
}

async function refreshPick() {
  if (!S.pick) return;
  const q = params();
  q.set('x', S.pick.x); q.set('y', S.pick.y);
  const tq = new URLSearchParams(q); tq.set('overlay', 1);
  const r = await fetch('/api/raytree?' + tq);
  if (!r.ok) { status(await r.text()); return; }
  const j = await r.json();
  S.tree = j.tree; S.treeOverlay = j.overlay;
  S.pick.query = q.toString();
  await loadWalk();
  drawOverlay(); draw3d(); listRays();
}

async function loadWalk() {
  S.walk = null;
  $('walk-text').textContent = '';
  if (!S.pick || form().accel.value === 'none') {
    if (S.pick) $('walk-text').textContent = 'Brute force (accel none) walks no structure.';
    return;
  }
  const q = params();
  q.set('x', S.pick.x); q.set('y', S.pick.y);
  const r = await fetch('/api/traversal?' + q);
  if (!r.ok) { $('walk-text').textContent = await r.text(); return; }
  S.walk = await r.json();
  $('walk-text').textContent = `${S.walk.accel}: the eye ray's search looked at ${S.walk.visits} boxes, entered ${S.walk.entered}` +
    (S.walk.faces ? `, ${S.walk.faces} entry faces` : '') + (S.walk.hit_t == null ? ', no hit.' : `, hit at t = ${S.walk.hit_t.toFixed(3)}.`);
}

async function loadGrid() {
  S.grid = null;
  if ($('show-grid').checked) {
    const r = await fetch('/api/grid?' + params());
    if (r.ok) S.grid = await r.json(); else status(await r.text());
  }
  drawOverlay(); draw3d();
}

function rgb(c) { return `rgb(${Math.round(c[0] * 255)},${Math.round(c[1] * 255)},${Math.round(c[2] * 255)})`; }

function drawOverlay() {
  const c = $('overlay');
  const g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  g.lineCap = 'round';
  if (S.grid && $('show-grid').checked) {
    g.lineWidth = 1; g.globalAlpha = 0.7;
    S.grid.overlay.forEach((s, i) => {
      if (!s) return;
      const k = S.grid.segments[i];
      g.strokeStyle = rgb(k.slice(6));
      line(g, s);
    });
    g.globalAlpha = 1;
  }
  if (!S.pick || S.pick.stale) return;
  if (S.walk && $('show-walk').checked) {
    g.lineWidth = 1;
    S.walk.overlay.forEach((s, i) => {
      if (!s) return;
      g.strokeStyle = rgb(S.walk.segments[i].slice(6));
      line(g, s);
    });
  }
  if (S.tree && $('show-tree').checked) {
    g.lineWidth = 2;
    S.tree.rays.forEach((ray, i) => {
      const s = S.treeOverlay[i];
      if (!s) return;
      g.strokeStyle = KIND_COLOR[ray.kind];
      g.setLineDash(ray.occluded ? [4, 4] : []);
      line(g, s);
      g.setLineDash([]);
      if (ray.hit) cross(g, s[2], s[3], 3);
    });
  }
  // The clicked pixel.
  g.strokeStyle = '#fff'; g.lineWidth = 1;
  g.strokeRect(S.pick.x - 3.5, S.pick.y - 3.5, 8, 8);
}

function line(g, s) { g.beginPath(); g.moveTo(s[0], s[1]); g.lineTo(s[2], s[3]); g.stroke(); }
function cross(g, x, y, r) {
  g.beginPath(); g.moveTo(x - r, y - r); g.lineTo(x + r, y + r); g.moveTo(x - r, y + r); g.lineTo(x + r, y - r); g.stroke();
}

function listRays() {
  const tb = $('rays').tBodies[0];
  tb.innerHTML = '';
  if (!S.tree) return;
  const t = S.tree;
  $('tree-text').textContent = `Pixel (${t.pixel[0]}, ${t.pixel[1]}): ${t.rays.length} rays (` +
    Object.entries(t.counts).map(([k, n]) => `${n} ${k}`).join(', ') + `), colour ${fmt(t.color)}.` +
    (form().integrator.value === 'whitted' ? '' : ' (The Whitted ray tree of this pixel, with these bounces and shadows: '
      + 'the image is the ' + form().integrator.value + ' integrator\'s.)');
  t.rays.forEach((r, i) => {
    const tr = tb.insertRow();
    const note = r.kind === 'shadow' ? (r.occluded ? ' (blocked)' : ' (reaches the light)') : (r.hit ? '' : ' (escapes)');
    const cells = [i, null, r.depth, fmt(r.origin), fmt(r.end) + note, fmt(r.normal), (+r.weight).toFixed(3)];
    cells.forEach((v, k) => {
      const td = tr.insertCell();
      if (k === 1) {
        const sw = document.createElement('span');
        sw.className = 'sw'; sw.style.background = KIND_COLOR[r.kind];
        td.append(sw, r.kind);
      } else td.textContent = String(v);
    });
  });
}

// ---- the camera: orbit, pan, zoom -------------------------------------------

function currentCam() {
  return S.cam || JSON.parse(JSON.stringify(S.sceneCam));
}

function pivotDistance(cam) {
  const b = S.scene && S.scene.bounds;
  if (!b) return 10;
  const c = v3.mul(v3.add(b.min, b.max), 0.5);
  const d = v3.dot(v3.sub(c, cam.eye), v3.norm(cam.dir));
  return d > 1e-3 ? d : Math.max(1, v3.len(v3.sub(c, cam.eye)));
}

function moveCamera(fn) {
  const cam = currentCam();
  fn(cam);
  S.cam = cam;
  if (S.pick) S.pick.stale = true;  // the tree stays in the 3-D view, not over a new image
  drawOverlay(); draw3d();
  scheduleRender();
}

function orbit(cam, yaw, pitch) {
  const d = pivotDistance(cam);
  const f = v3.norm(cam.dir);
  const target = v3.add(cam.eye, v3.mul(f, d));
  const up = v3.norm(cam.up);
  let off = v3.sub(cam.eye, target);
  let dir = f;
  off = v3.rot(off, up, yaw); dir = v3.rot(dir, up, yaw);
  const right = v3.norm(v3.cross(dir, up));
  const off2 = v3.rot(off, right, pitch), dir2 = v3.rot(dir, right, pitch);
  if (Math.abs(v3.dot(v3.norm(dir2), up)) < 0.98) { off = off2; dir = dir2; }
  cam.eye = v3.add(target, off);
  cam.dir = v3.norm(dir);
}

function pan(cam, dx, dy) {
  const d = pivotDistance(cam);
  const f = v3.norm(cam.dir);
  const right = v3.norm(v3.cross(f, cam.up));
  const up = v3.cross(right, f);
  const k = d * 0.002 * (cam.kind === 'perspective' ? Math.tan(cam.fov * Math.PI / 360) * 2 : 1);
  cam.eye = v3.add(cam.eye, v3.add(v3.mul(right, -dx * k * 2), v3.mul(up, dy * k * 2)));
}

function zoom(cam, factor) {
  if (cam.kind === 'perspective') {
    const d = pivotDistance(cam);
    cam.eye = v3.add(cam.eye, v3.mul(v3.norm(cam.dir), d * (1 - factor)));
  } else cam.span *= factor;
}

let renderTimer = null;
function scheduleRender() {
  clearTimeout(renderTimer);
  renderTimer = setTimeout(() => { refine(); loadGrid(); }, 80);
}

function setupImage() {
  const c = $('image');
  let down = null;
  c.addEventListener('contextmenu', (e) => e.preventDefault());
  c.addEventListener('mousedown', (e) => {
    down = { x: e.offsetX, y: e.offsetY, moved: false, pan: e.shiftKey || e.button === 2 };
    c.focus();
  });
  window.addEventListener('mousemove', (e) => {
    if (!down) return;
    const dx = e.offsetX - down.x, dy = e.offsetY - down.y;
    if (!down.moved && Math.hypot(dx, dy) < 4) return;
    down.moved = true;
    if (e.target !== c) return;
    const p = down.pan;
    moveCamera((cam) => p ? pan(cam, dx, dy) : orbit(cam, -dx * 0.01, -dy * 0.01));
    down.x = e.offsetX; down.y = e.offsetY;
  });
  window.addEventListener('mouseup', (e) => {
    if (down && !down.moved && e.target === c) {
      const x = Math.floor(e.offsetX * c.width / c.clientWidth);
      const y = Math.floor(e.offsetY * c.height / c.clientHeight);
      if (x >= 0 && y >= 0 && x < c.width && y < c.height) pick(x, y);
    }
    down = null;
  });
  c.addEventListener('wheel', (e) => {
    e.preventDefault();
    moveCamera((cam) => zoom(cam, e.deltaY > 0 ? 1.1 : 1 / 1.1));
  }, { passive: false });
  c.addEventListener('keydown', (e) => {
    const step = 0.08;
    const keys = {
      ArrowLeft: (cam) => e.shiftKey ? pan(cam, -20, 0) : orbit(cam, step, 0),
      ArrowRight: (cam) => e.shiftKey ? pan(cam, 20, 0) : orbit(cam, -step, 0),
      ArrowUp: (cam) => e.shiftKey ? pan(cam, 0, -20) : orbit(cam, 0, step),
      ArrowDown: (cam) => e.shiftKey ? pan(cam, 0, 20) : orbit(cam, 0, -step),
      '+': (cam) => zoom(cam, 1 / 1.1), '=': (cam) => zoom(cam, 1 / 1.1), '-': (cam) => zoom(cam, 1.1),
    };
    if (keys[e.key]) { e.preventDefault(); moveCamera(keys[e.key]); }
    if (e.key === 'r') { S.cam = null; if (S.pick) S.pick.stale = true; drawOverlay(); scheduleRender(); }
  });
}

// ---- the 3-D view -----------------------------------------------------------

const V = { yaw: 0.6, pitch: 0.35, dist: 0, center: [0, 0, 0], radius: 1 };

function setup3d() {
  const c = $('view3d');
  let down = null;
  c.addEventListener('mousedown', (e) => { down = { x: e.clientX, y: e.clientY }; });
  window.addEventListener('mouseup', () => { down = null; });
  window.addEventListener('mousemove', (e) => {
    if (!down) return;
    V.yaw += (e.clientX - down.x) * 0.01;
    V.pitch = Math.max(-1.5, Math.min(1.5, V.pitch + (e.clientY - down.y) * 0.01));
    down = { x: e.clientX, y: e.clientY };
    draw3d();
  });
  c.addEventListener('wheel', (e) => { e.preventDefault(); V.dist *= e.deltaY > 0 ? 1.1 : 1 / 1.1; draw3d(); }, { passive: false });
}

function frame3d() {
  const s = S.scene;
  const cam = currentCam();
  const b = s.bounds || { min: v3.sub(cam.eye, [1, 1, 1]), max: v3.add(cam.eye, [1, 1, 1]) };
  V.center = v3.mul(v3.add(b.min, b.max), 0.5);
  V.radius = Math.max(v3.len(v3.sub(b.max, b.min)) / 2, v3.len(v3.sub(S.sceneCam.eye, V.center)), 1e-3);
  V.dist = 1.6 * V.radius;
}

// The 3-D view's camera: yaw and pitch around the scene camera's up.
function viewBasis() {
  const u = v3.norm(S.sceneCam.up);
  let a = v3.sub(S.sceneCam.dir, v3.mul(u, v3.dot(S.sceneCam.dir, u)));
  a = v3.len(a) < 1e-6 ? v3.norm(v3.cross(u, [1, 0, 0])) : v3.norm(a);
  const bb = v3.cross(a, u);
  const horiz = v3.add(v3.mul(a, Math.cos(V.yaw)), v3.mul(bb, Math.sin(V.yaw)));
  const fwd = v3.norm(v3.sub(v3.mul(horiz, Math.cos(V.pitch)), v3.mul(u, Math.sin(V.pitch))));
  const right = v3.norm(v3.cross(fwd, u));
  const up = v3.cross(right, fwd);
  const pos = v3.sub(V.center, v3.mul(fwd, V.dist));
  return { fwd, right, up, pos };
}

function projector(c) {
  const B = viewBasis();
  const f = (c.height / 2) / Math.tan(22.5 * Math.PI / 180);
  const near = V.dist * 1e-3;
  const cam = (p) => { const q = v3.sub(p, B.pos); return [v3.dot(q, B.right), v3.dot(q, B.up), v3.dot(q, B.fwd)]; };
  const scr = (q) => [c.width / 2 + f * q[0] / q[2], c.height / 2 - f * q[1] / q[2]];
  // A segment, clipped at the near plane: screen end points or null.
  const seg = (a, b) => {
    let qa = cam(a), qb = cam(b);
    if (qa[2] < near && qb[2] < near) return null;
    if (qa[2] < near || qb[2] < near) {
      const t = (near - qa[2]) / (qb[2] - qa[2]);
      const m = [qa[0] + (qb[0] - qa[0]) * t, qa[1] + (qb[1] - qa[1]) * t, near];
      if (qa[2] < near) qa = m; else qb = m;
    }
    return [...scr(qa), ...scr(qb)];
  };
  return { seg };
}

function boxEdges(min, max) {
  const c = (i) => [i & 1 ? max[0] : min[0], i & 2 ? max[1] : min[1], i & 4 ? max[2] : min[2]];
  const e = [];
  for (let i = 0; i < 8; i++) for (const bit of [1, 2, 4]) if (!(i & bit)) e.push([c(i), c(i | bit)]);
  return e;
}

function draw3d() {
  const c = $('view3d');
  const g = c.getContext('2d');
  g.fillStyle = '#111318'; g.fillRect(0, 0, c.width, c.height);
  if (!S.scene) return;
  const P = projector(c);
  const stroke = (a, b) => { const s = P.seg(a, b); if (s) { g.moveTo(s[0], s[1]); g.lineTo(s[2], s[3]); } };
  const s = S.scene;
  // Scene geometry, as wire frames.
  g.strokeStyle = 'rgba(170,180,200,0.35)'; g.lineWidth = 1;
  g.beginPath();
  const t = s.triangles;
  for (let i = 0; i + 8 < t.length; i += 9) {
    const a = [t[i], t[i + 1], t[i + 2]], b = [t[i + 3], t[i + 4], t[i + 5]], d = [t[i + 6], t[i + 7], t[i + 8]];
    stroke(a, b); stroke(b, d); stroke(d, a);
  }
  for (const [x, y, z, r] of s.spheres) {
    const ring = (k, n, m) => {
      for (let i = 0; i < 24; i++) {
        const p = (j) => { const a = j * Math.PI / 12; return v3.add([x, y, z], v3.add(v3.mul(n, r * Math.cos(a) * k), v3.add(v3.mul(m, r * Math.sin(a) * k), [0, 0, 0]))); };
        stroke(p(i), p(i + 1));
      }
    };
    for (let l = -2; l <= 2; l++) {
      const h = r * Math.sin(l * Math.PI / 6), k = Math.cos(l * Math.PI / 6);
      const ringAt = (i) => { const a = i * Math.PI / 12; return [x + r * k * Math.cos(a), y + h, z + r * k * Math.sin(a)]; };
      for (let i = 0; i < 24; i++) stroke(ringAt(i), ringAt(i + 1));
    }
    for (let m = 0; m < 6; m++) {
      const ph = m * Math.PI / 6;
      const mer = (i) => { const a = i * Math.PI / 12; return [x + r * Math.cos(a) * Math.cos(ph), y + r * Math.sin(a), z + r * Math.cos(a) * Math.sin(ph)]; };
      for (let i = 0; i < 24; i++) stroke(mer(i), mer(i + 1));
    }
    void ring;
  }
  for (const [mn, mx] of s.boxes) for (const [a, b] of boxEdges(mn, mx)) stroke(a, b);
  for (const [nx, ny, nz, d] of s.planes) {
    // A square of the plane around the point nearest the scene's centre.
    const n = v3.norm([nx, ny, nz]);
    const p0 = v3.sub(V.center, v3.mul(n, v3.dot(V.center, n) - d / v3.len([nx, ny, nz])));
    const e1 = v3.norm(Math.abs(n[0]) < 0.9 ? v3.cross(n, [1, 0, 0]) : v3.cross(n, [0, 1, 0]));
    const e2 = v3.cross(n, e1);
    const R = V.radius * 1.2;
    for (let k = -4; k <= 4; k++) {
      stroke(v3.add(p0, v3.add(v3.mul(e1, R * k / 4), v3.mul(e2, -R))), v3.add(p0, v3.add(v3.mul(e1, R * k / 4), v3.mul(e2, R))));
      stroke(v3.add(p0, v3.add(v3.mul(e2, R * k / 4), v3.mul(e1, -R))), v3.add(p0, v3.add(v3.mul(e2, R * k / 4), v3.mul(e1, R))));
    }
  }
  g.stroke();
  // The camera's frustum, to the pivot distance.
  const cam = currentCam();
  const [w, h] = size();
  const f = v3.norm(cam.dir);
  const right = v3.norm(v3.cross(f, cam.up));
  const up = v3.cross(right, f);
  const dist = pivotDistance(cam);
  const half = cam.kind === 'perspective' ? dist * Math.tan(cam.fov * Math.PI / 360) : cam.span / 2;
  const [hx, hy] = w >= h ? [half, half * h / w] : [half * w / h, half];
  const apex = cam.eye;
  const corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(([sx, sy]) =>
    v3.add(v3.add(v3.add(apex, v3.mul(f, dist)), v3.mul(right, sx * hx)), v3.mul(up, sy * hy)));
  g.strokeStyle = FRUSTUM; g.lineWidth = 1;
  g.beginPath();
  for (let i = 0; i < 4; i++) {
    stroke(cam.kind === 'perspective' ? apex : v3.sub(corners[i], v3.mul(f, dist)), corners[i]);
    stroke(corners[i], corners[(i + 1) % 4]);
  }
  g.stroke();
  // Grid cells and the walk.
  const segs = (list, alpha) => {
    g.globalAlpha = alpha;
    for (const k of list) {
      g.strokeStyle = rgb(k.slice(6));
      g.beginPath(); stroke(k.slice(0, 3), k.slice(3, 6)); g.stroke();
    }
    g.globalAlpha = 1;
  };
  if (S.grid && $('show-grid').checked) segs(S.grid.segments, 0.5);
  if (S.walk && $('show-walk').checked) segs(S.walk.segments, 0.9);
  // The ray tree, the eye ray last.
  S.eye3d = null;
  if (S.tree && $('show-tree').checked) {
    const order = S.tree.rays.map((r, i) => i).sort((a, b) => (S.tree.rays[a].kind === 'eye') - (S.tree.rays[b].kind === 'eye'));
    for (const i of order) {
      const r = S.tree.rays[i];
      const sg = P.seg(r.origin, r.end);
      if (!sg) continue;
      g.strokeStyle = KIND_COLOR[r.kind]; g.lineWidth = r.kind === 'eye' ? 3 : 2;
      g.setLineDash(r.occluded ? [5, 4] : []);
      g.beginPath(); g.moveTo(sg[0], sg[1]); g.lineTo(sg[2], sg[3]); g.stroke();
      g.setLineDash([]);
      if (r.kind === 'eye' && !S.eye3d) S.eye3d = sg;
    }
  }
}

// ---- scene, status, watching ------------------------------------------------

async function loadScene() {
  const r = await fetch('/api/scene?' + params());
  if (!r.ok) { status(await r.text()); return; }
  S.scene = await r.json();
  S.sceneCam = S.scene.camera;
  if (V.dist === 0) frame3d();
  draw3d();
}

async function poll() {
  try {
    const st = await (await fetch('/api/status')).json();
    if (st.generation !== S.generation) {
      S.generation = st.generation;
      if (st.error) {
        $('error').hidden = false;
        const e = st.error;
        $('error-where').textContent = e.line ? `${e.file}, line ${e.line}, column ${e.column}` : e.file;
        $('error-text').textContent = e.text;
      } else $('error').hidden = true;
      if (st.loaded && st.version !== S.version) {
        S.version = st.version;
        await loadScene();
        // Before start() has run, it starts the first render itself.
        if (S.started) { refine(); loadGrid(); if (S.pick && !S.pick.stale) refreshPick(); }
      }
    }
  } catch (e) { status('server unreachable'); }
  setTimeout(poll, 400);
}

async function start() {
  const st = await (await fetch('/api/status')).json();
  $('scene-name').textContent = st.scene;
  document.title = 'glint serve: ' + st.scene;
  const d = st.defaults, f = form();
  // The menus the server offers: the command line's names, its default first.
  const fill = (sel, names) => { sel.innerHTML = ''; names.forEach((n) => setOption(sel, n)); };
  fill(f.integrator, d.integrators);
  f.integrator.value = d.integrators[0];
  fill(f.accel, d.accels);
  setOption(f.size, `${d.w}x${d.h}`);
  setOption(f.accel, d.accel);
  setOption(f.spp, d.spp);
  f.bounces.value = d.bounces;
  f.shadows.checked = d.shadows;
  f.shade_back.checked = d.shade_back;
  setupImage(); setup3d();
  // As `glint render`: the path tracer's bounces default to its own; a
  // bounce count left at one integrator's default follows the switch.
  let integ = f.integrator.value;
  f.integrator.addEventListener('change', () => {
    const def = (i) => (i === 'path' ? d.path_bounces : d.bounces);
    if (+f.bounces.value === def(integ)) f.bounces.value = def(f.integrator.value);
    integ = f.integrator.value;
  });
  f.addEventListener('change', () => {
    if (S.pick && !S.pick.stale) refreshPick(); else { S.walk = null; drawOverlay(); }
    refine(); loadGrid();
  });
  $('show-tree').addEventListener('change', () => { drawOverlay(); draw3d(); });
  $('show-walk').addEventListener('change', () => { drawOverlay(); draw3d(); });
  $('show-grid').addEventListener('change', loadGrid);
  $('show-cost').addEventListener('change', () => { if ($('show-cost').checked) loadCost(); else $('cost-box').hidden = true; });
  await poll();
  S.started = true;
  if (S.version >= 0) refine();
}

start();
