// swarf's program viewer. Reads the page's head (JSON) and packed arrays (gzip, base64), draws
// the path, the stock field and the solids with three.js, plays the program back while cutting
// the stock field with a flat end mill, and links the engagement chart to the path. The page's
// state is exposed as `window.swarf` for scripts and tests. See docs/viewer.md.
(function () {
  'use strict';
  const S = (window.swarf = { ready: false, error: null, t0: performance.now() });
  const $ = (id) => document.getElementById(id);
  const head = JSON.parse($('swarf-head').textContent);
  const KIND = ['rapid', 'cut', 'entry', 'plunge', 'link', 'descend', 'finish'];
  const ARC = 0x10, CCW = 0x20;
  const PALETTE = [0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf, 0xbcbd22, 0x7f7f7f];

  function status(t) { $('status').textContent = t; }
  function fail(e) {
    S.error = String(e && e.stack || e);
    status('error: ' + (e && e.message || e));
    throw e;
  }

  async function decode() {
    const text = $('swarf-data').textContent.trim();
    const bin = atob(text);
    const u8 = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
    const stream = new Blob([u8]).stream().pipeThrough(new DecompressionStream('gzip'));
    return new Response(stream).arrayBuffer();
  }

  function views(buf) {
    const A = {};
    const T = { f32: Float32Array, u32: Uint32Array, u16: Uint16Array, u8: Uint8Array };
    for (const [name, [t, off, len]] of Object.entries(head.arrays)) A[name] = new T[t](buf, off, len);
    return A;
  }

  // ---- data ------------------------------------------------------------------------------
  let A, runs, field;
  function model() {
    runs = head.runs.map((r, ri) => {
      let before = 0, sBefore = 0;
      const programs = r.programs.map((p, pi) => {
        const k = p.key;
        const prog = {
          index: pi, name: p.name, tool: p.tool, start: p.start, n: p.moves, levels: p.levels, ref: p.ref,
          figures: p.figures, gouges: p.gouges, plunges: p.plunges, rapidCollisions: p.rapidCollisions,
          to: A[k + '.to'], ctr: A[k + '.ctr'], flags: A[k + '.flags'], feed: A[k + '.feed'], level: A[k + '.level'],
          line: A[k + '.line'] || null, s: A[k + '.s'], tea: A[k + '.tea'], cs: A[k + '.cs'] || new Float32Array(0),
          cmax: A[k + '.cmax'] || new Float32Array(0), cmean: A[k + '.cmean'] || new Float32Array(0),
          cmi: A[k + '.cmi'] || new Uint32Array(0), rest: A[k + '.rest'] || null, axis: A[k + '.axis'] || null,
          gcodeBytes: A[k + '.gcode'] || null, gcodeLines: null,
          before, sBefore, cutLength: p.cutLength,
        };
        before += p.moves;
        sBefore += p.cutLength;
        return prog;
      });
      // the run's levels: every program's heights, highest first (a tool sequence's programs
      // share some and not others); each program's level numbers mapped onto them
      const zs = [...new Set(programs.flatMap((p) => p.levels.map((z) => Math.round(z * 1000))))].sort((a, b) => b - a);
      for (const p of programs) {
        const map = p.levels.map((z) => zs.indexOf(Math.round(z * 1000)));
        p.lv = new Uint16Array(p.n);
        for (let i = 0; i < p.n; i++) p.lv[i] = map.length ? map[p.level[i]] : 0;
      }
      const levels = zs.map((z, index) => ({ index, z: z / 1000 }));
      return { index: ri, name: r.name, programs, levels, n: before, cutLength: sBefore, removal: r.removal, end: r.end ? A['r' + ri + '.end'] : null };
    });
    if (head.field) {
      const f = head.field;
      field = Object.assign({}, f, { start: A['field.start'], part: A['field.part'] });
    }
  }

  // the program and its move of a run's move index
  function locate(run, g) {
    const ps = run.programs;
    let lo = 0;
    for (let i = 0; i < ps.length; i++) if (ps[i].before <= g) lo = i;
    return [ps[lo], g - ps[lo].before];
  }
  function startOf(p, i) {
    if (i === 0) return p.start;
    return [p.to[3 * i - 3], p.to[3 * i - 2], p.to[3 * i - 1]];
  }
  // points along move i of p (its start excluded), `step` radians on arcs
  function movePoints(p, i, step, out) {
    const a = startOf(p, i);
    const bx = p.to[3 * i], by = p.to[3 * i + 1], bz = p.to[3 * i + 2];
    const f = p.flags[i];
    if (f & ARC) {
      const cx = p.ctr[2 * i], cy = p.ctr[2 * i + 1];
      const r = Math.hypot(a[0] - cx, a[1] - cy);
      const a0 = Math.atan2(a[1] - cy, a[0] - cx);
      let d = Math.atan2(by - cy, bx - cx) - a0;
      if (f & CCW) { while (d <= 1e-12) d += 2 * Math.PI; } else { while (d >= -1e-12) d -= 2 * Math.PI; }
      if (Math.abs(d) > 2 * Math.PI - 1e-9 && Math.hypot(bx - a[0], by - a[1]) > 1e-9) d = d % (2 * Math.PI);
      const n = Math.max(2, Math.ceil(Math.abs(d) / step));
      for (let k = 1; k <= n; k++) {
        const t = k / n, ang = a0 + d * t;
        if (k === n) out.push(bx, by, bz); else out.push(cx + r * Math.cos(ang), cy + r * Math.sin(ang), a[2] + (bz - a[2]) * t);
      }
    } else out.push(bx, by, bz);
  }
  // the point a share t along move i of p
  function pointAlong(p, i, t) {
    const pts = [];
    movePoints(p, i, Math.PI / 90, pts);
    const a = startOf(p, i);
    const all = [a[0], a[1], a[2]].concat(pts);
    const m = all.length / 3 - 1;
    const x = Math.min(Math.max(t, 0), 1) * m, k = Math.min(Math.floor(x), m - 1), u = x - k;
    return [0, 1, 2].map((c) => all[3 * k + c] + (all[3 * k + 3 + c] - all[3 * k + c]) * u);
  }

  // ---- colours ---------------------------------------------------------------------------
  const col = new THREE.Color();
  function engagementColour(t, ref) {
    if (!(t >= 0)) return [0.62, 0.64, 0.67];
    const stops = [[0, [0.16, 0.35, 0.95]], [ref, [0.1, 0.72, 0.25]], [ref + 20, [1.0, 0.8, 0.0]], [ref + 60, [0.88, 0.1, 0.1]]];
    if (t >= stops[3][0]) return stops[3][1];
    for (let k = 0; k < 3; k++) {
      const [x0, c0] = stops[k], [x1, c1] = stops[k + 1];
      if (t <= x1) { const u = (t - x0) / Math.max(x1 - x0, 1e-9); return [0, 1, 2].map((c) => c0[c] + (c1[c] - c0[c]) * u); }
    }
    return stops[3][1];
  }
  function feedColour(u) {
    // dark blue → teal → yellow
    const c0 = [0.15, 0.1, 0.45], c1 = [0.1, 0.6, 0.6], c2 = [0.98, 0.85, 0.1];
    u = Math.min(Math.max(u, 0), 1);
    const [a, b, v] = u < 0.5 ? [c0, c1, u * 2] : [c1, c2, u * 2 - 1];
    return [0, 1, 2].map((c) => a[c] + (b[c] - a[c]) * v);
  }
  // (the colours here are sRGB, as the legend's CSS shows them; `lin` turns one into the
  // linear values three.js expects of vertex colours, so that the lines match the legend)
  function paletteColour(k) { const h = PALETTE[k % PALETTE.length]; return [(h >> 16 & 255) / 255, (h >> 8 & 255) / 255, (h & 255) / 255]; }
  function lin(c) { col.setRGB(c[0], c[1], c[2], THREE.SRGBColorSpace); return [col.r, col.g, col.b]; }

  // ---- three.js scene --------------------------------------------------------------------
  let renderer, scene, camera, controls, pathRoot, markRoot, restRoot, solidRoot, tool, highlight;
  let needsRender = true;
  const box = new THREE.Box3();

  function initThree() {
    const canvas = $('gl');
    renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    renderer.setClearColor(0xf7f8fa, 1);
    scene = new THREE.Scene();
    camera = new THREE.PerspectiveCamera(35, 1, 0.1, 1e6);
    camera.up.set(0, 0, 1);
    controls = new THREE.OrbitControls(camera, canvas);
    controls.enableDamping = false;
    controls.addEventListener('change', () => { needsRender = true; });
    scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(-0.4, -0.7, 1.0);
    scene.add(sun);
    pathRoot = new THREE.Group(); markRoot = new THREE.Group(); restRoot = new THREE.Group(); solidRoot = new THREE.Group();
    scene.add(pathRoot, markRoot, restRoot, solidRoot);
    new ResizeObserver(resize).observe($('view'));
    new ResizeObserver(() => drawChart()).observe($('chartbox'));
    resize();
    const loop = () => {
      if (needsRender) {
        needsRender = false;
        renderer.render(scene, camera);
        if (side && side.on) side.renderer.render(side.scene, camera);
        S.frames = (S.frames || 0) + 1;
      }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }
  function resize() {
    const v = $('view');
    const w = Math.max(v.clientWidth, 10), h = Math.max(v.clientHeight, 10);
    renderer.setSize(w, h, false);
    if (side && side.renderer) side.renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    needsRender = true;
  }

  // ---- the stock field --------------------------------------------------------------------
  let F = null; // { mesh, h, pos, colour, vol, dirty }
  const C_STOCK = [0.86, 0.76, 0.58], C_CUT = [0.93, 0.58, 0.3], C_PART = [0.47, 0.58, 0.72];
  function buildField() {
    if (!field) return;
    F = makeField(field.start);
    scene.add(F.mesh);
    F.mesh.geometry.computeBoundingBox();
    box.union(F.mesh.geometry.boundingBox);
  }
  // a mesh of the field at `heights` (its cells' centres, walls down to the bottom at its edges)
  function makeField(heights) {
    const { nx, ny, x0, y0, res, bottom } = field;
    const n = nx * ny;
    const start = field.start, part = field.part;
    const stock = (i, j) => i >= 0 && j >= 0 && i < nx && j < ny && !Number.isNaN(start[j * nx + i]);
    // quads between the centres of four stock cells, and walls where a quad has no neighbour
    const quad = (i, j) => stock(i, j) && stock(i + 1, j) && stock(i, j + 1) && stock(i + 1, j + 1);
    const idx = [];
    const bottomOf = new Int32Array(n).fill(-1);
    let extra = 0;
    const low = (v) => { if (bottomOf[v] < 0) bottomOf[v] = n + extra++; return bottomOf[v]; };
    const wall = (a, b) => { const a2 = low(a), b2 = low(b); idx.push(a, a2, b, b, a2, b2); };
    for (let j = 0; j + 1 < ny; j++) for (let i = 0; i + 1 < nx; i++) {
      if (!quad(i, j)) continue;
      const a = j * nx + i, b = a + 1, c = a + nx + 1, d = a + nx;
      idx.push(a, b, c, a, c, d);
      if (!quad(i, j - 1)) wall(b, a);
      if (!quad(i + 1, j)) wall(c, b);
      if (!quad(i, j + 1)) wall(d, c);
      if (!quad(i - 1, j)) wall(a, d);
    }
    const pos = new Float32Array((n + extra) * 3);
    const colour = new Float32Array((n + extra) * 3);
    for (let j = 0; j < ny; j++) for (let i = 0; i < nx; i++) {
      const v = j * nx + i;
      pos[3 * v] = x0 + (i + 0.5) * res; pos[3 * v + 1] = y0 + (j + 0.5) * res;
      pos[3 * v + 2] = Number.isNaN(start[v]) ? bottom : start[v];
      const w = bottomOf[v];
      if (w >= 0) { pos[3 * w] = pos[3 * v]; pos[3 * w + 1] = pos[3 * v + 1]; pos[3 * w + 2] = bottom; }
    }
    const g = new THREE.BufferGeometry();
    const pa = new THREE.BufferAttribute(pos, 3), ca = new THREE.BufferAttribute(colour, 3);
    pa.setUsage(THREE.DynamicDrawUsage); ca.setUsage(THREE.DynamicDrawUsage);
    g.setAttribute('position', pa); g.setAttribute('color', ca);
    g.setIndex(new THREE.BufferAttribute(n + extra > 65535 ? new Uint32Array(idx) : new Uint16Array(idx), 1));
    const mat = new THREE.MeshPhongMaterial({ vertexColors: true, flatShading: true, shininess: 8, side: THREE.DoubleSide });
    const mesh = new THREE.Mesh(g, mat);
    const f = { mesh, pos, colour, pa, ca, h: new Float32Array(heights), bottomOf, vol: 0, dirty: null, n };
    paintField(0, ny - 1, f);
    return f;
  }
  function paintField(j0, j1, F) {
    const { nx } = field, start = field.start, part = field.part, h = F.h;
    for (let v = j0 * nx; v < (j1 + 1) * nx; v++) {
      if (Number.isNaN(start[v])) continue;
      F.pos[3 * v + 2] = h[v];
      const c = h[v] <= (Number.isNaN(part[v]) ? -Infinity : part[v]) + 0.05 ? C_PART : h[v] < start[v] - 1e-3 ? C_CUT : C_STOCK;
      F.colour[3 * v] = c[0]; F.colour[3 * v + 1] = c[1]; F.colour[3 * v + 2] = c[2];
      const w = F.bottomOf[v];
      if (w >= 0) { F.colour[3 * w] = c[0] * 0.8; F.colour[3 * w + 1] = c[1] * 0.8; F.colour[3 * w + 2] = c[2] * 0.8; }
    }
  }
  // uploads the rows changed since the last upload (the rest of the buffers stays on the GPU)
  function uploadField() {
    if (!F || !F.dirty) return;
    const [j0, j1] = F.dirty; F.dirty = null;
    paintField(j0, j1, F);
    const nx = field.nx;
    for (const attr of [F.pa, F.ca]) {
      attr.clearUpdateRanges();
      attr.addUpdateRange(j0 * nx * 3, (j1 - j0 + 1) * nx * 3);
      // (wall vertices beyond the grid copy their colour from the rows above)
      attr.addUpdateRange(F.n * 3, attr.array.length - F.n * 3);
      attr.needsUpdate = true;
    }
    needsRender = true;
  }
  function markDirty(j0, j1) {
    if (!F.dirty) F.dirty = [j0, j1]; else { F.dirty[0] = Math.min(F.dirty[0], j0); F.dirty[1] = Math.max(F.dirty[1], j1); }
  }
  // a flat end mill of radius R from a to b: each cell whose centre the disk passes over is
  // lowered to the lowest the tool's tip is while it does (exact for a flat end mill)
  function cutSegment(R, ax, ay, az, bx, by, bz) {
    const { nx, ny, x0, y0, res } = field, start = field.start, h = F.h;
    const dx = bx - ax, dy = by - ay, L2 = dx * dx + dy * dy, L = Math.sqrt(L2);
    const i0 = Math.max(0, Math.ceil((Math.min(ax, bx) - R - x0) / res - 0.5));
    const i1 = Math.min(nx - 1, Math.floor((Math.max(ax, bx) + R - x0) / res - 0.5));
    const j0 = Math.max(0, Math.ceil((Math.min(ay, by) - R - y0) / res - 0.5));
    const j1 = Math.min(ny - 1, Math.floor((Math.max(ay, by) + R - y0) / res - 0.5));
    if (i0 > i1 || j0 > j1) return;
    const R2 = R * R, cell = res * res;
    let touched = false;
    for (let j = j0; j <= j1; j++) {
      const cy = y0 + (j + 0.5) * res;
      for (let i = i0; i <= i1; i++) {
        const v = j * nx + i;
        const hv = h[v];
        if (Number.isNaN(hv)) continue;
        const cx = x0 + (i + 0.5) * res;
        let z;
        if (L < 1e-9) {
          if ((cx - ax) * (cx - ax) + (cy - ay) * (cy - ay) > R2) continue;
          z = Math.min(az, bz);
        } else {
          const ux = cx - ax, uy = cy - ay;
          const along = (ux * dx + uy * dy) / L2;
          const perp = (ux * dy - uy * dx) / L;
          if (perp * perp > R2) continue;
          const w = Math.sqrt(R2 - perp * perp) / L;
          const t0 = Math.max(0, along - w), t1 = Math.min(1, along + w);
          if (t0 > t1) continue;
          z = Math.min(az + (bz - az) * t0, az + (bz - az) * t1);
        }
        if (z < hv) { F.vol += (hv - z) * cell; h[v] = z; touched = true; }
      }
    }
    if (touched) markDirty(j0, j1);
  }
  const ptsBuf = [];
  function cutMove(p, i) {
    const R = p.tool.d / 2;
    const a = startOf(p, i);
    ptsBuf.length = 0;
    // arcs in chords whose sagitta is under a quarter cell
    const step = (p.flags[i] & ARC) ? Math.max(0.02, Math.min(Math.PI / 18, 2 * Math.acos(Math.max(-1, 1 - field.res / 4 / Math.max(Math.hypot(a[0] - p.ctr[2 * i], a[1] - p.ctr[2 * i + 1]), 1e-6))))) : 1;
    movePoints(p, i, step, ptsBuf);
    let ax = a[0], ay = a[1], az = a[2];
    for (let k = 0; k < ptsBuf.length; k += 3) {
      const bx = ptsBuf[k], by = ptsBuf[k + 1], bz = ptsBuf[k + 2];
      // long pieces in parts of at most two radii, so that the cell windows stay small
      const parts = Math.max(1, Math.ceil(Math.hypot(bx - ax, by - ay) / (2 * R)));
      for (let q = 0; q < parts; q++) {
        const u0 = q / parts, u1 = (q + 1) / parts;
        cutSegment(R, ax + (bx - ax) * u0, ay + (by - ay) * u0, az + (bz - az) * u0, ax + (bx - ax) * u1, ay + (by - ay) * u1, az + (bz - az) * u1);
      }
      ax = bx; ay = by; az = bz;
    }
  }

  // ---- playback state: k moves of the current run done ------------------------------------
  let run = null, K = 0, checkpoints = [], cpEvery = 1;
  function resetStock() {
    if (!F) return;
    F.h.set(field.start);
    F.vol = 0;
    markDirty(0, field.ny - 1);
  }
  // moves the stock to k moves done: from the nearest checkpoint at or before k (or from where
  // it is when that is nearer), cutting in the page; checkpoints are kept as it passes them
  function seekStock(k) {
    if (!F) return;
    if (k < F.k || F.k === undefined) {
      let best = null;
      for (const c of checkpoints) if (c.k <= k && (!best || c.k > best.k)) best = c;
      if (best) { F.h.set(best.h); F.vol = best.vol; F.k = best.k; markDirty(0, field.ny - 1); }
      else { resetStock(); F.k = 0; }
    }
    while (F.k < k) {
      const [p, i] = locate(run, F.k);
      cutMove(p, i);
      F.k++;
      if (F.k % cpEvery === 0 && !checkpoints.some((c) => c.k === F.k)) checkpoints.push({ k: F.k, h: new Float32Array(F.h), vol: F.vol });
    }
  }
  function seek(k) {
    k = Math.max(0, Math.min(run.n, Math.round(k)));
    K = k;
    seekStock(k);
    uploadField();
    updatePathRange();
    placeTool(k);
    $('slider').value = String(k);
    readout();
    drawChart();
    needsRender = true;
  }
  function simulatorVolume(k) {
    const r = run.removal;
    if (!r.length) return NaN;
    for (let q = 0; q < r.length; q++) {
      if (r[q][0] === k) return r[q][1];
      if (r[q][0] > k) {
        if (q === 0) return r[0][1];
        const [ka, va] = r[q - 1], [kb, vb] = r[q];
        return va + (vb - va) * (k - ka) / (kb - ka);
      }
    }
    return r[r.length - 1][1];
  }

  // ---- the path ---------------------------------------------------------------------------
  let groups = [];
  function buildPath() {
    for (const g of groups) { g.obj.geometry.dispose(); pathRoot.remove(g.obj); }
    groups = makeGroups(run);
    for (const g of groups) {
      g.obj.geometry.computeBoundingBox();
      box.union(g.obj.geometry.boundingBox);
      pathRoot.add(g.obj);
    }
    colourPath();
    applyFilters();
  }
  // the path of run `run` as line segments, one object per program, level and rapid or feed
  function makeGroups(run) {
    const groups = [];
    const byKey = new Map();
    const step = Math.PI / 24;
    const tmp = [];
    // first pass: count each group's segments
    for (const p of run.programs) {
      for (let i = 0; i < p.n; i++) {
        const rapid = (p.flags[i] & 15) === 0;
        const key = p.index + ':' + p.lv[i] + ':' + (rapid ? 'r' : 'f');
        let g = byKey.get(key);
        if (!g) { g = { key, prog: p, level: p.lv[i], rapid, segs: 0, moves: 0 }; byKey.set(key, g); groups.push(g); }
        tmp.length = 0;
        movePoints(p, i, step, tmp);
        g.segs += tmp.length / 3;
        g.moves++;
      }
    }
    for (const g of groups) {
      g.pos = new Float32Array(g.segs * 6); g.colour = new Float32Array(g.segs * 6);
      g.segMove = new Uint32Array(g.segs); g.moveG = new Uint32Array(g.moves); g.moveEnd = new Uint32Array(g.moves);
      g.fill = 0; g.mfill = 0;
    }
    for (const p of run.programs) {
      for (let i = 0; i < p.n; i++) {
        const g = byKey.get(p.index + ':' + p.lv[i] + ':' + ((p.flags[i] & 15) === 0 ? 'r' : 'f'));
        tmp.length = 0;
        movePoints(p, i, step, tmp);
        let a = startOf(p, i);
        for (let k = 0; k < tmp.length; k += 3) {
          const o = g.fill * 6;
          g.pos[o] = a[0]; g.pos[o + 1] = a[1]; g.pos[o + 2] = a[2];
          g.pos[o + 3] = tmp[k]; g.pos[o + 4] = tmp[k + 1]; g.pos[o + 5] = tmp[k + 2];
          g.segMove[g.fill] = p.before + i;
          g.fill++;
          a = [tmp[k], tmp[k + 1], tmp[k + 2]];
        }
        g.moveG[g.mfill] = p.before + i;
        g.moveEnd[g.mfill] = g.fill * 2;
        g.mfill++;
      }
    }
    for (const g of groups) {
      const geo = new THREE.BufferGeometry();
      geo.setAttribute('position', new THREE.BufferAttribute(g.pos, 3));
      geo.setAttribute('color', new THREE.BufferAttribute(g.colour, 3));
      const mat = g.rapid
        ? new THREE.LineDashedMaterial({ color: 0x5a6472, dashSize: 1.5, gapSize: 1.2, transparent: true, opacity: 0.75 })
        : new THREE.LineBasicMaterial({ vertexColors: true });
      g.obj = new THREE.LineSegments(geo, mat);
      if (g.rapid) g.obj.computeLineDistances();
      g.obj.userData.group = g;
    }
    return groups;
  }
  function colourOfMove(mode, p, i) {
    switch (mode) {
      case 'feed': return feedColour(p.feed[i] / (p.maxFeed || 1));
      case 'level': return paletteColour(p.lv[i]);
      case 'tool': return paletteColour(p.index);
      default: {
        return engagementColour(p.tea[i], p.ref || 60);
      }
    }
  }
  function colourPath() {
    const mode = $('colourby').value;
    colourGroups(groups, run, mode);
    if (side) colourGroups(side.groups, side.run, mode);
    legend(mode);
    needsRender = true;
  }
  function colourGroups(groups, run, mode) {
    run.maxFeed = 0;
    for (const p of run.programs) for (let i = 0; i < p.n; i++) run.maxFeed = Math.max(run.maxFeed, p.feed[i]);
    for (const p of run.programs) p.maxFeed = run.maxFeed;
    for (const g of groups) {
      if (g.rapid) continue;
      let last = -1, c = null;
      for (let s = 0; s < g.segs; s++) {
        const gm = g.segMove[s];
        if (gm !== last) { last = gm; c = lin(colourOfMove(mode, g.prog, gm - g.prog.before)); }
        g.colour.set(c, s * 6); g.colour.set(c, s * 6 + 3);
      }
      g.obj.geometry.attributes.color.needsUpdate = true;
    }
  }
  function updatePathRange() {
    const all = $('show-ahead').checked;
    for (const g of groups) {
      let count = g.pos.length / 3;
      if (!all) {
        // vertices of the moves before K
        let lo = 0, hi = g.moves;
        while (lo < hi) { const m = (lo + hi) >> 1; if (g.moveG[m] < K) lo = m + 1; else hi = m; }
        count = lo === 0 ? 0 : g.moveEnd[lo - 1];
      }
      g.obj.geometry.setDrawRange(0, count);
    }
  }
  let levelOn = [], toolOn = [];
  function applyFilters() {
    const rapids = $('show-rapids').checked;
    if (side && side.on) for (const g of side.groups) g.obj.visible = !g.rapid || rapids;
    for (const g of groups) g.obj.visible = levelOn[g.level] !== false && toolOn[g.prog.index] !== false && (!g.rapid || rapids);
    markRoot.visible = $('show-marks').checked;
    restRoot.visible = $('show-rest').checked;
    solidRoot.visible = $('show-solids').checked;
    if (F) F.mesh.visible = $('show-stock').checked;
    needsRender = true;
  }

  // ---- marks, rest, solids, the tool ------------------------------------------------------
  function points(xyz, colour, size) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(xyz), 3));
    return new THREE.Points(g, new THREE.PointsMaterial({ color: colour, size, sizeAttenuation: false, depthTest: false, transparent: true }));
  }
  function buildMarks() {
    markRoot.clear(); restRoot.clear();
    const m = makeMarks(run);
    for (const o of m.marks.children.slice()) markRoot.add(o);
    for (const o of m.rest.children.slice()) restRoot.add(o);
    S.marks = m.counts;
  }
  function makeMarks(run) {
    const markRoot = new THREE.Group(), restRoot = new THREE.Group();
    const entries = [], plunges = [], gouges = [], collisions = [], rest = [];
    for (const p of run.programs) {
      for (let i = 0; i < p.n; i++) {
        const kind = p.flags[i] & 15;
        if (kind === 2 && (i === 0 || (p.flags[i - 1] & 15) !== 2)) entries.push(...startOf(p, i));
      }
      for (const e of p.plunges) plunges.push(e[1], e[2], e[3]);
      for (const e of p.gouges) gouges.push(e[1], e[2], e[3]);
      for (const e of p.rapidCollisions) collisions.push(e[1], e[2], e[3]);
      if (p.rest) {
        for (let k = 0; k < p.rest.length; k += 2) {
          const x = p.rest[k], y = p.rest[k + 1];
          rest.push(x, y, heightAt(x, y, run.end));
        }
      }
    }
    // the tool axis along a 5-axis path, at about 600 of its moves
    for (const p of run.programs) {
      if (!p.axis) continue;
      const every = Math.max(1, Math.floor(p.n / 600)), L = 2 * p.tool.d, seg = [];
      for (let i = 0; i < p.n; i += every) {
        if ((p.flags[i] & 15) === 0) continue;
        const x = p.to[3 * i], y = p.to[3 * i + 1], z = p.to[3 * i + 2];
        seg.push(x, y, z, x + L * p.axis[3 * i], y + L * p.axis[3 * i + 1], z + L * p.axis[3 * i + 2]);
      }
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(seg), 3));
      markRoot.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0x8a3ffc, transparent: true, opacity: 0.6 })));
    }
    if (entries.length) markRoot.add(points(entries, 0x1a9e3a, 6));
    if (plunges.length) markRoot.add(points(plunges, 0xc01890, 8));
    if (collisions.length) markRoot.add(points(collisions, 0xff6a00, 9));
    if (gouges.length) markRoot.add(points(gouges, 0xe00000, 7));
    if (rest.length) restRoot.add(points(rest, 0xff8c1a, 2));
    const counts = { entries: entries.length / 3, plunges: plunges.length / 3, gouges: gouges.length / 3, rapidCollisions: collisions.length / 3, rest: rest.length / 3 };
    return { marks: markRoot, rest: restRoot, counts };
  }
  function heightAt(x, y, h) {
    if (!field) return 0;
    const i = Math.floor((x - field.x0) / field.res), j = Math.floor((y - field.y0) / field.res);
    if (i < 0 || j < 0 || i >= field.nx || j >= field.ny) return field.bottom;
    const v = (h || field.start)[j * field.nx + i];
    return Number.isNaN(v) ? field.bottom : v + 0.01;
  }
  function buildSolids() {
    head.solids.forEach((s, si) => {
      const colour = s.kind === 'fixture' ? 0xa33b3b : 0x7d8fa6;
      let geo;
      if (s.type === 'mesh') {
        geo = new THREE.BufferGeometry();
        geo.setAttribute('position', new THREE.BufferAttribute(A['s' + si + '.tris'], 3));
        geo.computeVertexNormals();
      } else {
        const xy = A['s' + si + '.xy'];
        const ring = ([at, n]) => { const v = []; for (let k = 0; k < n; k++) v.push(new THREE.Vector2(xy[2 * (at + k)], xy[2 * (at + k) + 1])); return v; };
        const shapes = s.polys.map((rings) => {
          const sh = new THREE.Shape(ring(rings[0]));
          for (const h of rings.slice(1)) sh.holes.push(new THREE.Path(ring(h)));
          return sh;
        });
        geo = new THREE.ExtrudeGeometry(shapes, { depth: s.z1 - s.z0, bevelEnabled: false });
        geo.translate(0, 0, s.z0);
      }
      // (a part's faces that the stock field covers stay behind it: no z-fighting where they meet)
      const mesh = new THREE.Mesh(geo, new THREE.MeshPhongMaterial({ color: colour, flatShading: s.type !== 'mesh', shininess: 20, side: THREE.DoubleSide,
        transparent: s.type === 'mesh', opacity: s.type === 'mesh' ? 0.45 : 1, depthWrite: s.type !== 'mesh',
        polygonOffset: true, polygonOffsetFactor: 2, polygonOffsetUnits: 8 }));
      geo.computeBoundingBox();
      box.union(geo.boundingBox);
      solidRoot.add(mesh);
    });
  }
  function buildTool() {
    if (tool) scene.remove(tool);
    const p = run.programs[0];
    const R = p.tool.d / 2, H = Math.max(2.5 * R, 8);
    const g = new THREE.CylinderGeometry(R, R, H, 32, 1);
    g.rotateX(Math.PI / 2); g.translate(0, 0, H / 2);
    tool = new THREE.Mesh(g, new THREE.MeshPhongMaterial({ color: 0x3d4a5c, transparent: true, opacity: 0.7, shininess: 60 }));
    const axis = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(0, 0, 0), new THREE.Vector3(0, 0, H * 1.6)]), new THREE.LineBasicMaterial({ color: 0x111111 }));
    tool.add(axis);
    scene.add(tool);
  }
  const Z = new THREE.Vector3(0, 0, 1);
  function placeToolAt(p, i, xyz) {
    tool.position.set(xyz[0], xyz[1], xyz[2]);
    if (p.axis && i >= 0) tool.quaternion.setFromUnitVectors(Z, new THREE.Vector3(p.axis[3 * i], p.axis[3 * i + 1], p.axis[3 * i + 2]).normalize());
    else tool.quaternion.identity();
    // (the marker is built for the run's first tool; a later tool's is as wide as it is)
    const s = p.tool.d / run.programs[0].tool.d;
    tool.scale.set(s, s, 1);
    S.marker = xyz.slice();
    needsRender = true;
  }
  function placeTool(k) {
    if (k === 0) { const p = run.programs[0]; placeToolAt(p, -1, p.start); return; }
    const [p, i] = locate(run, k - 1);
    placeToolAt(p, i, [p.to[3 * i], p.to[3 * i + 1], p.to[3 * i + 2]]);
  }

  // ---- side by side: another run beside the one playing --------------------------------------
  // The other run (the next one) as it ends: its path, the simulator's stock after it, its
  // marks and the solids, seen through the same camera; turning either view turns both.
  let side = null;
  function lights(sc) {
    sc.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(-0.4, -0.7, 1.0);
    sc.add(sun);
  }
  function buildSide() {
    const on = runs.length > 1 && $('side').checked;
    $('view2').style.display = on ? '' : 'none';
    if (side) {
      side.scene.traverse((o) => { if (o.userData.group) o.geometry.dispose(); });
      if (side.field) side.field.mesh.geometry.dispose();
      side.on = false;
    }
    if (!on) { resize(); needsRender = true; return; }
    if (!side) {
      const r2 = new THREE.WebGLRenderer({ canvas: $('gl2'), antialias: true, preserveDrawingBuffer: true });
      r2.setPixelRatio(renderer.getPixelRatio());
      r2.setClearColor(0xf5f3ee, 1);
      const c2 = new THREE.OrbitControls(camera, $('gl2'));
      c2.target = controls.target;
      c2.addEventListener('change', () => { needsRender = true; });
      side = { renderer: r2, controls: c2 };
    }
    const other = runs[(run.index + 1) % runs.length];
    const sc = new THREE.Scene();
    lights(sc);
    side.scene = sc; side.run = other; side.field = null;
    if (field) {
      side.field = makeField(other.end || field.start);
      sc.add(side.field.mesh);
    }
    side.groups = makeGroups(other);
    for (const g of side.groups) { g.obj.visible = !g.rapid || $('show-rapids').checked; sc.add(g.obj); }
    colourGroups(side.groups, other, $('colourby').value);
    const m = makeMarks(other);
    sc.add(m.marks, m.rest);
    for (const o of solidRoot.children) sc.add(new THREE.Mesh(o.geometry, o.material));
    side.on = true;
    let removed = '';
    if (field && other.end) {
      let v = 0;
      const st = field.start, cell = field.res * field.res;
      for (let q = 0; q < st.length; q++) if (!Number.isNaN(st[q]) && !Number.isNaN(other.end[q])) v += (st[q] - other.end[q]) * cell;
      removed = ` · removed ${(v / 1000).toFixed(2)} cm³`;
    }
    $('hud2').textContent = `${other.name}: as it ends${removed} · ${m.counts.gouges} gouges`;
    S.side = { run: other.index, marks: m.counts };
    resize();
    needsRender = true;
  }

  // ---- camera -----------------------------------------------------------------------------
  function view(kind) {
    const c = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    const r = Math.max(size.length() / 2, 1);
    const d = (0.8 * r) / Math.tan((camera.fov * Math.PI) / 360) / Math.min(1, camera.aspect);
    let dir;
    if (kind === 'top') dir = new THREE.Vector3(0, -0.0001, 1);
    else if (kind === 'front') dir = new THREE.Vector3(0, -1, 0.0001);
    else if (kind === 'iso') dir = new THREE.Vector3(-0.55, -0.8, 0.75);
    else dir = camera.position.clone().sub(controls.target);
    dir.normalize();
    camera.position.copy(c).addScaledVector(dir, d);
    camera.near = d / 100; camera.far = d * 100;
    camera.updateProjectionMatrix();
    controls.target.copy(c);
    controls.update();
    needsRender = true;
  }

  // ---- chart ------------------------------------------------------------------------------
  let chartHover = null;
  function chartGeom() {
    const cv = $('chart');
    const w = cv.clientWidth, h = cv.clientHeight;
    return { cv, w, h, l: 40, r: 10, t: 8, b: 20 };
  }
  function drawChart() {
    if (!run) return;
    const G = chartGeom(), dpr = window.devicePixelRatio || 1;
    G.cv.width = Math.max(1, G.w * dpr); G.cv.height = Math.max(1, G.h * dpr);
    const c = G.cv.getContext('2d');
    c.setTransform(dpr, 0, 0, dpr, 0, 0);
    c.clearRect(0, 0, G.w, G.h);
    const total = Math.max(run.cutLength, 1e-9);
    const ymax = 180;
    const X = (s) => G.l + (s / total) * (G.w - G.l - G.r);
    const Y = (t) => G.t + (1 - t / ymax) * (G.h - G.t - G.b);
    c.font = '10px sans-serif'; c.fillStyle = '#52606d'; c.strokeStyle = '#e4e7eb'; c.lineWidth = 1;
    for (const t of [0, 45, 90, 135, 180]) { c.beginPath(); c.moveTo(G.l, Y(t)); c.lineTo(G.w - G.r, Y(t)); c.stroke(); c.fillText(t + '°', 4, Y(t) + 3); }
    const metres = total / 1000;
    c.fillText('cut length ' + (metres >= 1 ? metres.toFixed(2) + ' m' : total.toFixed(0) + ' mm'), G.w - 130, G.h - 5);
    for (const p of run.programs) {
      if (toolOn[p.index] === false) continue;
      const colour = run.programs.length > 1 ? '#' + PALETTE[p.index % PALETTE.length].toString(16).padStart(6, '0') : '#2f6fd6';
      c.strokeStyle = colour; c.globalAlpha = 0.9; c.beginPath();
      for (let b = 0; b < p.cs.length; b++) { const x = X(p.sBefore + p.cs[b]), y = Y(p.cmax[b]); if (b) c.lineTo(x, y); else c.moveTo(x, y); }
      c.stroke();
      c.globalAlpha = 0.5; c.strokeStyle = run.programs.length > 1 ? colour : '#0b3b8c'; c.beginPath();
      for (let b = 0; b < p.cs.length; b++) { const x = X(p.sBefore + p.cs[b]), y = Y(p.cmean[b]); if (b) c.lineTo(x, y); else c.moveTo(x, y); }
      c.stroke(); c.globalAlpha = 1;
      if (p.ref) {
        c.setLineDash([5, 4]); c.strokeStyle = '#c62828';
        for (const t of [p.ref, p.ref + 20]) { c.beginPath(); c.moveTo(X(p.sBefore), Y(t)); c.lineTo(X(p.sBefore + p.cutLength), Y(t)); c.stroke(); }
        c.setLineDash([]);
      }
    }
    // where the playback is, and the hovered or selected point
    const sNow = sAtMoves(K);
    c.strokeStyle = '#1f2933'; c.lineWidth = 1.5; c.beginPath(); c.moveTo(X(sNow), G.t); c.lineTo(X(sNow), G.h - G.b); c.stroke();
    const mark = chartHover || selected;
    if (mark && mark.s !== undefined) { c.strokeStyle = '#f0a000'; c.beginPath(); c.moveTo(X(mark.s), G.t); c.lineTo(X(mark.s), G.h - G.b); c.stroke(); }
    c.lineWidth = 1;
    if (!run.programs.some((p) => p.cs.length)) {
      c.fillStyle = '#52606d'; c.font = '12px sans-serif';
      c.fillText('no engagement measured for this program', G.l + 12, G.t + 20);
    }
  }
  // cutting length of the run after k moves
  function sAtMoves(k) {
    if (k <= 0) return 0;
    const [p, i] = locate(run, k - 1);
    return p.sBefore + p.s[i];
  }
  function chartPick(ev) {
    const G = chartGeom();
    const rect = G.cv.getBoundingClientRect();
    const x = ev.clientX - rect.left;
    const s = Math.min(Math.max((x - G.l) / (G.w - G.l - G.r), 0), 1) * run.cutLength;
    // the program and its bucket nearest s
    let best = null;
    for (const p of run.programs) {
      if (!p.cs.length || toolOn[p.index] === false) continue;
      const local = s - p.sBefore;
      let lo = 0, hi = p.cs.length - 1;
      while (lo < hi) { const m = (lo + hi) >> 1; if (p.cs[m] < local) lo = m + 1; else hi = m; }
      for (const b of [lo - 1, lo]) {
        if (b < 0 || b >= p.cs.length) continue;
        const d = Math.abs(p.sBefore + p.cs[b] - s);
        if (!best || d < best.d) best = { d, p, b };
      }
    }
    if (!best) return null;
    const { p, b } = best;
    const i = p.cmi[b];
    const sIn = p.cs[b], s0 = i > 0 ? p.s[i - 1] : 0, s1 = p.s[i];
    return { p, i, g: p.before + i, s: p.sBefore + sIn, tea: p.cmax[b], at: pointAlong(p, i, s1 > s0 ? (sIn - s0) / (s1 - s0) : 1) };
  }
  function chartEvents() {
    const cv = $('chart');
    cv.addEventListener('mousemove', (ev) => {
      const h = chartPick(ev);
      chartHover = h;
      if (h) {
        placeToolAt(h.p, h.i, h.at);
        $('charttip').textContent = `${(h.s / 1000).toFixed(3)} m · ${h.tea.toFixed(0)}° · move ${h.g + 1}` + (h.p.line ? ` · line ${h.p.line[h.i]}` : '');
      }
      drawChart();
    });
    cv.addEventListener('mouseleave', () => { chartHover = null; $('charttip').textContent = ''; placeTool(K); drawChart(); });
    cv.addEventListener('click', (ev) => { const h = chartPick(ev); if (h) { select(h.p, h.i); seek(h.g + 1); } });
  }

  // ---- selection --------------------------------------------------------------------------
  let selected = null;
  function select(p, i) {
    if (highlight) { scene.remove(highlight); highlight.geometry.dispose(); }
    const pts = [...startOf(p, i)];
    movePoints(p, i, Math.PI / 48, pts);
    const v = [];
    for (let k = 0; k < pts.length; k += 3) v.push(new THREE.Vector3(pts[k], pts[k + 1], pts[k + 2]));
    highlight = new THREE.Line(new THREE.BufferGeometry().setFromPoints(v), new THREE.LineBasicMaterial({ color: 0xff00aa, depthTest: false }));
    highlight.renderOrder = 10;
    scene.add(highlight);
    selected = { p, i, g: p.before + i, s: p.sBefore + p.s[i] };
    const kind = KIND[p.flags[i] & 15];
    const tea = p.tea[i];
    $('moveinfo').textContent = `move ${p.before + i + 1} of ${run.n} (${p.name}): ${kind}${(p.flags[i] & ARC) ? ' arc' : ''}, ` +
      `feed ${p.feed[i].toFixed(0)} mm/min, z ${p.to[3 * i + 2].toFixed(3)}` + (Number.isNaN(tea) ? '' : `, engagement up to ${tea.toFixed(0)}°`) +
      (p.line ? `, G-code line ${p.line[i]}` : '');
    showGcode(p, p.line ? p.line[i] : 0);
    S.selected = { move: p.before + i, line: p.line ? p.line[i] : null, s: selected.s };
    drawChart();
    needsRender = true;
  }
  function showGcode(p, line) {
    const pre = $('gcode');
    pre.textContent = '';
    if (!p.gcodeBytes || !line) return;
    if (!p.gcodeLines) p.gcodeLines = new TextDecoder().decode(p.gcodeBytes).split('\n');
    for (let l = Math.max(1, line - 6); l <= Math.min(p.gcodeLines.length, line + 6); l++) {
      const span = document.createElement('span');
      span.textContent = String(l).padStart(6) + '  ' + p.gcodeLines[l - 1] + '\n';
      if (l === line) span.className = 'hl';
      pre.appendChild(span);
    }
  }
  function pickEvents() {
    const cv = $('gl');
    const ray = new THREE.Raycaster();
    let down = null;
    cv.addEventListener('pointerdown', (e) => { down = [e.clientX, e.clientY]; });
    cv.addEventListener('pointerup', (e) => {
      if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
      const rect = cv.getBoundingClientRect();
      const ndc = new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
      ray.setFromCamera(ndc, camera);
      ray.params.Line.threshold = Math.max(run.programs[0].tool.d / 8, box.getSize(new THREE.Vector3()).length() / 800);
      const hits = ray.intersectObjects(groups.filter((g) => g.obj.visible).map((g) => g.obj), false);
      if (!hits.length) return;
      const g = hits[0].object.userData.group;
      const gm = g.segMove[Math.floor(hits[0].index / 2)];
      const [p, i] = locate(run, gm);
      select(p, i);
    });
  }

  // ---- panel ------------------------------------------------------------------------------
  function legend(mode) {
    const L = $('legend');
    L.innerHTML = '';
    if (mode === 'engagement') {
      const ref = run.programs[0].ref || 60;
      const grad = [];
      for (let t = 0; t <= 180; t += 10) { const c = engagementColour(t, ref); grad.push(`rgb(${c.map((x) => Math.round(x * 255)).join(',')}) ${(t / 180 * 100).toFixed(1)}%`); }
      L.innerHTML = `<div class="bar" style="background:linear-gradient(90deg,${grad.join(',')})"></div><div class="ticks"><span>0°</span><span>ref ${ref.toFixed(0)}°</span><span>180°</span></div>` +
        `<div><span class="sw" style="background:#9ea3ab"></span>no engagement (air, links)</div>` +
        `<div><span class="sw" style="background:#1a9e3a"></span>entry <span class="sw" style="background:#c01890"></span>plunge into material <span class="sw" style="background:#e00000"></span>gouge <span class="sw" style="background:#ff6a00"></span>rapid through material <span class="sw" style="background:#ff8c1a"></span>rest</div>`;
    } else if (mode === 'feed') {
      const grad = [0, 0.25, 0.5, 0.75, 1].map((u) => { const c = feedColour(u); return `rgb(${c.map((x) => Math.round(x * 255)).join(',')})`; });
      L.innerHTML = `<div class="bar" style="background:linear-gradient(90deg,${grad.join(',')})"></div><div class="ticks"><span>0</span><span>${run.maxFeed.toFixed(0)} mm/min</span></div>`;
    } else {
      const items = mode === 'tool' ? run.programs.map((p) => [p.index, `${p.name} (Ø${p.tool.d})`]) : allLevels().slice(0, 30).map((l) => [l.index, 'z ' + l.z.toFixed(3)]);
      L.innerHTML = items.map(([k, t]) => { const c = paletteColour(k); return `<div><span class="sw" style="background:rgb(${c.map((x) => Math.round(x * 255)).join(',')})"></span>${t}</div>`; }).join('') +
        (mode === 'level' && allLevels().length > 30 ? '<div>…</div>' : '');
    }
  }
  function allLevels() { return run.levels; }
  function buildPanel() {
    const lv = $('levels');
    lv.innerHTML = '';
    levelOn = [];
    for (const l of allLevels()) {
      levelOn[l.index] = true;
      const lab = document.createElement('label');
      lab.innerHTML = `<input type="checkbox" data-level="${l.index}" checked> level ${l.index + 1}: z ${l.z.toFixed(3)}`;
      lv.appendChild(lab);
    }
    lv.onchange = (e) => { const k = e.target.dataset.level; if (k !== undefined) { levelOn[+k] = e.target.checked; applyFilters(); } };
    const tl = $('tools');
    tl.innerHTML = '';
    toolOn = [];
    for (const p of run.programs) {
      toolOn[p.index] = true;
      const c = paletteColour(p.index);
      const lab = document.createElement('label');
      lab.innerHTML = `<input type="checkbox" data-tool="${p.index}" checked> <span class="sw" style="background:rgb(${c.map((x) => Math.round(x * 255)).join(',')})"></span>T${p.tool.number} Ø${p.tool.d} mm — ${esc(p.name)} ` +
        `<button class="mini" data-after="${p.index}" title="Play to the end of this tool: the stock it leaves">after</button>`;
      tl.appendChild(lab);
    }
    tl.onchange = (e) => { const k = e.target.dataset.tool; if (k !== undefined) { toolOn[+k] = e.target.checked; applyFilters(); drawChart(); } };
    tl.onclick = (e) => {
      const k = e.target.dataset.after;
      if (k !== undefined) { e.preventDefault(); play(false); const p = run.programs[+k]; seek(p.before + p.n); }
    };
    $('slider').max = String(run.n);
  }
  function figures() {
    // one column per program of every run: programs side by side
    const cols = [];
    for (const r of runs) for (const p of r.programs) cols.push(p);
    const labels = [];
    for (const p of cols) for (const [k] of p.figures) if (!labels.includes(k)) labels.push(k);
    const t = $('figures');
    let html = cols.length > 1 ? '<tr><th></th>' + cols.map((p) => `<th>${esc(p.name)}</th>`).join('') + '</tr>' : '';
    for (const k of labels) html += `<tr><th>${esc(k)}</th>` + cols.map((p) => { const f = p.figures.find((x) => x[0] === k); return `<td class="v">${f ? esc(f[1]) : ''}</td>`; }).join('') + '</tr>';
    t.innerHTML = html;
  }
  function esc(s) { return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]); }
  function readout() {
    const r = F ? `removed ${(F.vol / 1000).toFixed(2)} cm³ (simulator ${(simulatorVolume(K) / 1000).toFixed(2)} cm³)` : '';
    let line = '';
    if (K > 0) { const [p, i] = locate(run, K - 1); if (p.line) line = ` · line ${p.line[i]}`; }
    $('readout').textContent = `move ${K} / ${run.n}${line}`;
    $('hud').textContent = r;
  }

  // ---- run selection and playback ---------------------------------------------------------
  function useRun(ri) {
    run = runs[ri];
    checkpoints = [];
    cpEvery = Math.max(1, Math.ceil(run.n / 24));
    selected = null; chartHover = null;
    if (highlight) { scene.remove(highlight); highlight = null; }
    buildPanel();
    buildPath();
    buildMarks();
    buildTool();
    if (F) {
      // the stock after the whole run as the simulator left it; earlier states are cut here
      checkpoints.push({ k: 0, h: new Float32Array(field.start), vol: 0 });
      if (run.end) {
        F.h.set(run.end);
        let v = 0;
        const s = field.start, cell = field.res * field.res;
        for (let q = 0; q < s.length; q++) if (!Number.isNaN(s[q]) && !Number.isNaN(run.end[q])) v += (s[q] - run.end[q]) * cell;
        F.vol = v; F.k = run.n;
        markDirty(0, field.ny - 1);
      } else { resetStock(); F.k = 0; }
    }
    seek(run.n);
    if (runs.length > 1) buildSide();
  }
  let playing = false, lastT = 0;
  function play(on) {
    playing = on;
    $('play').textContent = on ? '❚❚' : '▶';
    if (on && K >= run.n) seek(0);
    lastT = performance.now();
    if (on) requestAnimationFrame(tick);
  }
  function tick(t) {
    if (!playing) return;
    // a program plays in about 60 s at 1×
    const rate = run.n / 60 * (+$('speed').value);
    const dk = Math.max(1, Math.round(rate * (t - lastT) / 1000));
    lastT = t;
    seek(Math.min(run.n, K + dk));
    if (K >= run.n) { play(false); return; }
    requestAnimationFrame(tick);
  }

  async function main() {
    try {
      $('title').textContent = head.title;
      document.title = 'swarf — ' + head.title;
      $('notes').textContent = (head.notes || []).join(' · ');
      const buf = await decode();
      A = views(buf);
      model();
      initThree();
      buildField();
      buildSolids();
      const sel = $('run');
      runs.forEach((r, i) => { const o = document.createElement('option'); o.value = i; o.textContent = r.name; sel.appendChild(o); });
      $('runbox').style.display = runs.length > 1 ? '' : 'none';
      sel.onchange = () => { useRun(+sel.value); view('fit'); };
      figures();
      // (a program with no engagement samples, a 5-axis one, is coloured by tool)
      if (!runs.some((r) => r.programs.some((p) => p.cs.length))) $('colourby').value = 'tool';
      if (!field) $('hud').style.display = 'none';
      useRun(0);
      $('toolbox').style.display = run.programs.length > 1 ? '' : 'none';
      view('iso');
      for (const b of document.querySelectorAll('#views button')) b.onclick = () => view(b.dataset.view);
      $('colourby').onchange = colourPath;
      for (const id of ['show-rapids', 'show-stock', 'show-solids', 'show-marks', 'show-rest']) $(id).onchange = applyFilters;
      $('side').onchange = buildSide;
      $('show-ahead').onchange = () => { updatePathRange(); needsRender = true; };
      $('levels-all').onclick = () => { for (const c of $('levels').querySelectorAll('input')) { c.checked = true; levelOn[+c.dataset.level] = true; } applyFilters(); };
      $('levels-none').onclick = () => { for (const c of $('levels').querySelectorAll('input')) { c.checked = false; levelOn[+c.dataset.level] = false; } applyFilters(); };
      $('slider').addEventListener('input', () => { play(false); seek(+$('slider').value); });
      $('play').onclick = () => play(!playing);
      window.addEventListener('keydown', (e) => { if (e.code === 'Space' && e.target.tagName !== 'INPUT' && e.target.tagName !== 'SELECT') { e.preventDefault(); play(!playing); } });
      chartEvents();
      pickEvents();
      status(`${runs.reduce((a, r) => a + r.n, 0)} moves`);
      // (the first frame is drawn before the page says it is ready)
      renderer.render(scene, camera);
      // (from the start of the page's navigation)
      S.readyMs = performance.now();
      S.ready = true;
    } catch (e) { fail(e); }
  }

  // ---- for scripts and tests ---------------------------------------------------------------
  Object.assign(S, {
    moves: () => run.n,
    runs: () => runs.length,
    useRun: (i) => { $('run').value = String(i); useRun(i); },
    seek: (k) => seek(k),
    position: () => K,
    removedVolume: () => (F ? F.vol : NaN),
    simulatorVolume: (k) => simulatorVolume(k === undefined ? K : k),
    removalMarks: () => run.removal.map((r) => r[0]),
    markerPosition: () => S.marker,
    levels: () => allLevels().map((l) => ({ index: l.index, z: l.z, on: levelOn[l.index] !== false })),
    visibleLevels: () => [...new Set(groups.filter((g) => g.obj.visible && !g.rapid).map((g) => g.level))].sort((a, b) => a - b),
    drawnSegments: () => groups.filter((g) => g.obj.visible).reduce((a, g) => a + g.obj.geometry.drawRange.count, 0),
    // where the end of move g of the run is on the page, in CSS pixels
    screenOf: (g) => {
      const [p, i] = locate(run, g);
      const v = new THREE.Vector3(p.to[3 * i], p.to[3 * i + 1], p.to[3 * i + 2]).project(camera);
      const r = $('gl').getBoundingClientRect();
      return { x: r.left + (v.x + 1) / 2 * r.width, y: r.top + (1 - v.y) / 2 * r.height };
    },
    stockCut: () => { if (!F) return 0; let c = 0; for (let q = 0; q < F.h.length; q++) if (F.h[q] < field.start[q] - 1e-3) c++; return c; },
  });
  main();
})();
