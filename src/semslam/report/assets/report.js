// The HTML report's script (embedded into report.html at build time): sortable tables and the 3D view.
// See html_report_assets.h.
(function () {
  'use strict';
  const errorBox = document.getElementById('js-errors');
  function reportError(message) {
    if (!errorBox) return;
    errorBox.hidden = false;
    const p = document.createElement('p');
    p.textContent = 'JavaScript error: ' + message;
    errorBox.appendChild(p);
    document.body.setAttribute('data-js-errors', String(errorBox.children.length));
  }
  window.addEventListener('error', function (e) {
    reportError(e.message + (e.lineno ? ' (line ' + e.lineno + ')' : ''));
  });

  // ---- Tables: a click on a column header sorts by it (numbers by their data-v value).
  function cellValue(cell) {
    if (!cell) return '';
    const v = cell.getAttribute('data-v');
    return v === null ? cell.textContent.trim().toLowerCase() : parseFloat(v);
  }
  document.querySelectorAll('table.sortable').forEach(function (table) {
    const headers = table.querySelectorAll('thead th');
    headers.forEach(function (th, column) {
      th.classList.add('sort-key');
      th.title = 'sort by this column';
      th.addEventListener('click', function () {
        const body = table.tBodies[0];
        const rows = Array.prototype.slice.call(body.rows);
        const ascending = th.getAttribute('data-order') !== 'asc';
        headers.forEach(function (h) { h.removeAttribute('data-order'); });
        th.setAttribute('data-order', ascending ? 'asc' : 'desc');
        rows.sort(function (a, b) {
          const x = cellValue(a.cells[column]), y = cellValue(b.cells[column]);
          const c = (typeof x === 'number' && typeof y === 'number') ? x - y : String(x).localeCompare(String(y));
          return ascending ? c : -c;
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
  });
  document.querySelectorAll('.plots img').forEach(function (img) {
    img.addEventListener('click', function () { img.parentNode.classList.toggle('wide'); });
  });

  // ---- The 3D view.
  const dataElement = document.getElementById('semslam-data');
  const canvas = document.getElementById('view-canvas');
  if (!dataElement || !canvas) {
    document.body.setAttribute('data-viewer', 'none');
    return;
  }
  const data = JSON.parse(dataElement.textContent);

  function bytesFromBase64(text) {
    const s = atob(text || '');
    const bytes = new Uint8Array(s.length);
    for (let i = 0; i < s.length; ++i) bytes[i] = s.charCodeAt(i);
    return bytes;
  }
  function float32FromBase64(text) {
    const bytes = bytesFromBase64(text);
    const view = new DataView(bytes.buffer);
    const out = new Float32Array(bytes.length >> 2);
    for (let i = 0; i < out.length; ++i) out[i] = view.getFloat32(4 * i, true);
    return out;
  }
  // Positions come in the display frame: x east (or right), y north (or forward), z up.
  function geometry(entry) {
    return entry ? float32FromBase64(entry.positions_b64) : new Float32Array(0);
  }

  const points = geometry(data.points);
  const labels = data.points ? bytesFromBase64(data.points.labels_b64) : new Uint8Array(0);
  const ranges = data.points ? data.points.class_ranges : [];
  const trajectory = geometry(data.trajectory);
  const keyframes = geometry(data.keyframes);
  const landmarks = (data.landmarks || []).map(function (l) {
    return { name: l.name, p: [l.position[0], l.position[1], l.position[2]] };
  });
  const landmarkPositions = new Float32Array(landmarks.length * 3);
  landmarks.forEach(function (l, i) { landmarkPositions.set(l.p, 3 * i); });
  const classes = data.classes || [];
  const classById = {};
  const visible = {};
  classes.forEach(function (c) { classById[c.id] = c; visible[c.id] = true; });
  const colors = new Uint8Array(labels.length * 3);
  for (let i = 0; i < labels.length; ++i) {
    const c = classById[labels[i]] ? classById[labels[i]].color : [150, 150, 150];
    colors[3 * i] = c[0]; colors[3 * i + 1] = c[1]; colors[3 * i + 2] = c[2];
  }

  const TRAJECTORY_COLOR = [10, 88, 202], KEYFRAME_COLOR = [255, 140, 0], LANDMARK_COLOR = [214, 0, 143];
  const GRID_COLOR_LIGHT = [184, 192, 200], GRID_COLOR_DARK = [70, 76, 86];
  const FOV = 50 * Math.PI / 180;
  const center = data.view ? data.view.center.slice() : [0, 0, 0];
  const radius = data.view && data.view.radius > 0 ? data.view.radius : 1;
  const units = data.units || 'map units';
  const northUp = data.frame === 'enu';
  // Home: straight down, north (or the first camera's forward) up the screen.
  const TOP_PITCH = 1.5533, TOP_YAW = -Math.PI / 2;
  const home = { target: center, distance: 1.25 * radius / Math.tan(FOV / 2), yaw: TOP_YAW, pitch: TOP_PITCH };
  const camera = { target: home.target.slice(), distance: home.distance, yaw: home.yaw, pitch: home.pitch };
  const settings = { pointSize: labels.length < 20000 ? 3 : 2, trajectory: true, keyframes: true, landmarks: true,
                     grid: true, light: true };

  // A ground grid at the cameras' height: round spacing, about ten lines across the scene.
  function niceStep(limit) {
    const p = Math.pow(10, Math.floor(Math.log10(limit)));
    const steps = [5, 2, 1];
    for (let i = 0; i < steps.length; ++i) if (steps[i] * p <= limit) return steps[i] * p;
    return p;
  }
  const gridStep = niceStep(radius / 5);
  const grid = (function () {
    const z = data.view && typeof data.view.grid_z === 'number' ? data.view.grid_z : center[2];
    const lines = [];
    const x0 = Math.floor((center[0] - 1.5 * radius) / gridStep) * gridStep;
    const x1 = Math.ceil((center[0] + 1.5 * radius) / gridStep) * gridStep;
    const y0 = Math.floor((center[1] - 1.5 * radius) / gridStep) * gridStep;
    const y1 = Math.ceil((center[1] + 1.5 * radius) / gridStep) * gridStep;
    for (let x = x0; x <= x1 + 1e-9; x += gridStep) lines.push(x, y0, z, x, y1, z);
    for (let y = y0; y <= y1 + 1e-9; y += gridStep) lines.push(x0, y, z, x1, y, z);
    return new Float32Array(lines);
  })();
  function gridLabel() {
    const value = gridStep >= 1000 && units === 'm' ? (gridStep / 1000) + ' km' : gridStep + ' ' + units;
    return 'grid ' + value;
  }

  // ---- Column-major 4x4 matrices.
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function normalize(a) { const n = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
  function multiply(a, b) {
    const out = new Float32Array(16);
    for (let c = 0; c < 4; ++c) {
      for (let r = 0; r < 4; ++r) {
        let s = 0;
        for (let k = 0; k < 4; ++k) s += a[k * 4 + r] * b[c * 4 + k];
        out[c * 4 + r] = s;
      }
    }
    return out;
  }
  function eye() {
    const cp = Math.cos(camera.pitch);
    return [camera.target[0] + camera.distance * cp * Math.cos(camera.yaw),
            camera.target[1] + camera.distance * cp * Math.sin(camera.yaw),
            camera.target[2] + camera.distance * Math.sin(camera.pitch)];
  }
  function basis() {  // camera right, up and backward axes in the display frame
    const z = normalize(sub(eye(), camera.target));
    const x = normalize(cross([0, 0, 1], z));
    return { x: x, y: cross(z, x), z: z };
  }
  function clipRange() {
    const near = Math.max(camera.distance * 0.005, radius * 1e-5);
    return { near: near, far: camera.distance + 60 * radius };
  }
  function viewProjection(aspect) {
    const e = eye(), b = basis();
    const view = [b.x[0], b.y[0], b.z[0], 0, b.x[1], b.y[1], b.z[1], 0, b.x[2], b.y[2], b.z[2], 0,
                  -dot(b.x, e), -dot(b.y, e), -dot(b.z, e), 1];
    const range = clipRange();
    const f = 1 / Math.tan(FOV / 2), nf = 1 / (range.near - range.far);
    const projection = [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (range.far + range.near) * nf, -1,
                        0, 0, 2 * range.far * range.near * nf, 0];
    return multiply(projection, view);
  }
  function project(m, p, w, h) {  // -> [x px, y px, depth] or null behind the camera
    const cw = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    if (cw <= 1e-9) return null;
    const cx = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    const cy = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    return [(cx / cw * 0.5 + 0.5) * w, (0.5 - cy / cw * 0.5) * h, cw];
  }

  // ---- Renderers.
  const wrap = document.getElementById('view-wrap');
  const overlay = document.getElementById('view-overlay');
  const overlayContext = overlay.getContext('2d');
  const status = document.getElementById('view-status');
  function background() { return settings.light ? [0.957, 0.965, 0.973] : [0.114, 0.125, 0.149]; }
  function gridColor() { return settings.light ? GRID_COLOR_LIGHT : GRID_COLOR_DARK; }

  function makeWebGl() {
    if (location.hash.indexOf('canvas2d') >= 0) return null;
    let gl = null;
    try {
      gl = canvas.getContext('webgl', { antialias: true }) || canvas.getContext('experimental-webgl');
    } catch (e) {
      gl = null;
    }
    if (!gl) return null;
    const vertexSource =
        'attribute vec3 aPos; attribute vec3 aColor; uniform mat4 uMvp; uniform float uSize; varying vec3 vColor;' +
        'void main() { gl_Position = uMvp * vec4(aPos, 1.0); gl_PointSize = uSize; vColor = aColor; }';
    const fragmentSource =
        'precision mediump float; varying vec3 vColor; uniform float uRound;' +
        'void main() { vec2 d = gl_PointCoord - vec2(0.5);' +
        '  if (uRound > 0.5 && dot(d, d) > 0.25) discard; gl_FragColor = vec4(vColor, 1.0); }';
    function shader(type, source) {
      const s = gl.createShader(type);
      gl.shaderSource(s, source);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
      return s;
    }
    const program = gl.createProgram();
    gl.attachShader(program, shader(gl.VERTEX_SHADER, vertexSource));
    gl.attachShader(program, shader(gl.FRAGMENT_SHADER, fragmentSource));
    gl.bindAttribLocation(program, 0, 'aPos');
    gl.bindAttribLocation(program, 1, 'aColor');
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(program));
    const uMvp = gl.getUniformLocation(program, 'uMvp');
    const uSize = gl.getUniformLocation(program, 'uSize');
    const uRound = gl.getUniformLocation(program, 'uRound');
    function buffer(array) {
      const b = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.bufferData(gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
      return b;
    }
    const buffers = { points: buffer(points), colors: buffer(colors), trajectory: buffer(trajectory),
                      keyframes: buffer(keyframes), landmarks: buffer(landmarkPositions), grid: buffer(grid) };
    const sizeRange = gl.getParameter(gl.ALIASED_POINT_SIZE_RANGE);
    const maxSize = sizeRange ? sizeRange[1] : 64;
    function positions(b) {
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.enableVertexAttribArray(0);
      gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    }
    function uniformColor(c) {
      gl.disableVertexAttribArray(1);
      gl.vertexAttrib3f(1, c[0] / 255, c[1] / 255, c[2] / 255);
    }
    return {
      name: 'webgl',
      draw: function (m, w, h, dpr) {
        gl.viewport(0, 0, w, h);
        const bg = background();
        gl.clearColor(bg[0], bg[1], bg[2], 1);
        gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        gl.enable(gl.DEPTH_TEST);
        gl.useProgram(program);
        gl.uniformMatrix4fv(uMvp, false, m);
        if (settings.grid && grid.length > 0) {
          gl.uniform1f(uRound, 0);
          positions(buffers.grid);
          uniformColor(gridColor());
          gl.drawArrays(gl.LINES, 0, grid.length / 3);
        }
        if (labels.length > 0) {
          positions(buffers.points);
          gl.bindBuffer(gl.ARRAY_BUFFER, buffers.colors);
          gl.enableVertexAttribArray(1);
          gl.vertexAttribPointer(1, 3, gl.UNSIGNED_BYTE, true, 0, 0);
          gl.uniform1f(uSize, Math.min(maxSize, settings.pointSize * dpr));
          gl.uniform1f(uRound, settings.pointSize * dpr >= 3 ? 1 : 0);
          ranges.forEach(function (r) { if (visible[r[0]]) gl.drawArrays(gl.POINTS, r[1], r[2]); });
        }
        // Keyframes under the trajectory, so that many of them do not hide it.
        gl.uniform1f(uRound, 1);
        if (settings.keyframes && keyframes.length > 0) {
          positions(buffers.keyframes);
          uniformColor(KEYFRAME_COLOR);
          gl.uniform1f(uSize, Math.min(maxSize, (settings.pointSize + 1) * dpr));
          gl.drawArrays(gl.POINTS, 0, keyframes.length / 3);
        }
        gl.uniform1f(uRound, 0);
        if (settings.trajectory && trajectory.length >= 6) {
          gl.disable(gl.DEPTH_TEST);
          positions(buffers.trajectory);
          uniformColor(TRAJECTORY_COLOR);
          gl.drawArrays(gl.LINE_STRIP, 0, trajectory.length / 3);
          gl.enable(gl.DEPTH_TEST);
        }
        gl.uniform1f(uRound, 1);
        if (settings.landmarks && landmarks.length > 0) {
          positions(buffers.landmarks);
          uniformColor(LANDMARK_COLOR);
          gl.uniform1f(uSize, Math.min(maxSize, 11 * dpr));
          gl.drawArrays(gl.POINTS, 0, landmarks.length);
        }
      }
    };
  }

  function makeCanvas2d() {
    const context = canvas.getContext('2d');
    if (!context) return null;
    let image = null, pixels = null, depth = null;
    function packed(c) { return ((255 << 24) | (c[2] << 16) | (c[1] << 8) | c[0]) >>> 0; }
    function css(c) { return 'rgb(' + c[0] + ',' + c[1] + ',' + c[2] + ')'; }
    return {
      name: 'canvas2d',
      draw: function (m, w, h, dpr) {
        if (!image || image.width !== w || image.height !== h) {
          image = context.createImageData(w, h);
          pixels = new Uint32Array(image.data.buffer);
          depth = new Float32Array(w * h);
        }
        const bg = background();
        pixels.fill(packed([Math.round(bg[0] * 255), Math.round(bg[1] * 255), Math.round(bg[2] * 255)]));
        depth.fill(Infinity);
        const size = Math.max(1, Math.round(settings.pointSize * dpr));
        const half = size >> 1;
        const near = clipRange().near;
        ranges.forEach(function (r) {
          if (!visible[r[0]]) return;
          const color = packed(classById[r[0]] ? classById[r[0]].color : [150, 150, 150]);
          for (let i = r[1]; i < r[1] + r[2]; ++i) {
            const x = points[3 * i], y = points[3 * i + 1], z = points[3 * i + 2];
            const cw = m[3] * x + m[7] * y + m[11] * z + m[15];
            if (cw <= near) continue;
            const px = Math.round(((m[0] * x + m[4] * y + m[8] * z + m[12]) / cw * 0.5 + 0.5) * w) - half;
            const py = Math.round((0.5 - (m[1] * x + m[5] * y + m[9] * z + m[13]) / cw * 0.5) * h) - half;
            if (px <= -size || py <= -size || px >= w || py >= h) continue;
            for (let dy = Math.max(0, -py); dy < size && py + dy < h; ++dy) {
              let k = (py + dy) * w + Math.max(0, px);
              for (let dx = Math.max(0, -px); dx < size && px + dx < w; ++dx, ++k) {
                if (cw < depth[k]) { depth[k] = cw; pixels[k] = color; }
              }
            }
          }
        });
        context.putImageData(image, 0, 0);
        if (settings.grid) {
          context.strokeStyle = css(gridColor());
          context.lineWidth = dpr;
          context.beginPath();
          for (let i = 0; i + 5 < grid.length; i += 6) {
            const a = project(m, [grid[i], grid[i + 1], grid[i + 2]], w, h);
            const b = project(m, [grid[i + 3], grid[i + 4], grid[i + 5]], w, h);
            if (!a || !b || a[2] <= near || b[2] <= near) continue;
            context.moveTo(a[0], a[1]);
            context.lineTo(b[0], b[1]);
          }
          context.stroke();
        }
        function markers(array, color, markerSize) {
          context.fillStyle = css(color);
          for (let i = 0; i + 2 < array.length; i += 3) {
            const p = project(m, [array[i], array[i + 1], array[i + 2]], w, h);
            if (p && p[2] > near) context.fillRect(p[0] - markerSize / 2, p[1] - markerSize / 2, markerSize, markerSize);
          }
        }
        if (settings.keyframes) markers(keyframes, KEYFRAME_COLOR, (settings.pointSize + 1) * dpr);
        if (settings.trajectory && trajectory.length >= 6) {
          context.strokeStyle = css(TRAJECTORY_COLOR);
          context.lineWidth = dpr;
          context.beginPath();
          let drawing = false;
          for (let i = 0; i + 2 < trajectory.length; i += 3) {
            const p = project(m, [trajectory[i], trajectory[i + 1], trajectory[i + 2]], w, h);
            if (!p || p[2] <= near) { drawing = false; continue; }
            if (drawing) context.lineTo(p[0], p[1]); else context.moveTo(p[0], p[1]);
            drawing = true;
          }
          context.stroke();
        }
        if (settings.landmarks) markers(landmarkPositions, LANDMARK_COLOR, 10 * dpr);
      }
    };
  }

  let renderer = null;
  try {
    renderer = makeWebGl();
  } catch (e) {
    reportError('WebGL unusable, drawing on a 2D canvas instead: ' + e.message);
    renderer = null;
  }
  if (!renderer) renderer = makeCanvas2d();
  document.body.setAttribute('data-viewer', renderer ? renderer.name : 'none');
  document.body.setAttribute('data-points-shown', String(labels.length));

  function shownCount() {
    let n = 0;
    ranges.forEach(function (r) { if (visible[r[0]]) n += r[2]; });
    return n;
  }
  function draw() {
    if (!renderer) return;
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(wrap.clientWidth * dpr)), h = Math.max(1, Math.round(wrap.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    if (overlay.width !== w || overlay.height !== h) { overlay.width = w; overlay.height = h; }
    const m = viewProjection(w / h);
    renderer.draw(m, w, h, dpr);
    overlayContext.clearRect(0, 0, w, h);
    drawNorthArrow(m, w, h, dpr);
    if (settings.landmarks && landmarks.length > 0) {
      overlayContext.font = Math.round(12 * dpr) + 'px system-ui, sans-serif';
      overlayContext.lineWidth = 3 * dpr;
      overlayContext.strokeStyle = settings.light ? 'rgba(255,255,255,0.9)' : 'rgba(0,0,0,0.8)';
      overlayContext.fillStyle = settings.light ? '#000' : '#fff';
      const near = clipRange().near;
      // Names next to their markers without overlapping each other: the first free of eight spots, else none.
      const placed = [];
      const lineHeight = 14 * dpr, gap = 7 * dpr;
      function free(r) {
        return placed.every(function (q) {
          return r.x + r.w <= q.x || q.x + q.w <= r.x || r.y + r.h <= q.y || q.y + q.h <= r.y;
        });
      }
      landmarks.forEach(function (l) {
        const p = project(m, l.p, w, h);
        if (!p || p[2] <= near || p[0] < 0 || p[1] < 0 || p[0] > w || p[1] > h) return;
        const tw = overlayContext.measureText(l.name).width;
        const spots = [[gap, -gap - lineHeight], [gap, gap], [-gap - tw, -gap - lineHeight], [-gap - tw, gap],
                       [-tw / 2, -2 * gap - lineHeight], [-tw / 2, 2 * gap], [gap, -lineHeight / 2],
                       [-gap - tw, -lineHeight / 2]];
        for (let i = 0; i < spots.length; ++i) {
          const r = { x: p[0] + spots[i][0], y: p[1] + spots[i][1], w: tw, h: lineHeight };
          if (!free(r)) continue;
          placed.push(r);
          overlayContext.strokeText(l.name, r.x, r.y + lineHeight - 3 * dpr);
          overlayContext.fillText(l.name, r.x, r.y + lineHeight - 3 * dpr);
          return;
        }
      });
    }
    status.textContent = (settings.grid ? gridLabel() + ' \u00b7 ' : '') + shownCount().toLocaleString() + ' of ' + labels.length.toLocaleString() + ' points, ' +
        (trajectory.length / 3) + ' poses, ' + (keyframes.length / 3) + ' keyframes, ' +
        landmarks.length + ' landmarks \u00b7 ' + (renderer.name === 'webgl' ? 'WebGL' : '2D canvas');
  }
  // North (ENU) or the first camera's forward direction (level map frame), as it points on the screen now.
  function drawNorthArrow(m, w, h, dpr) {
    const a = project(m, camera.target, w, h);
    const b = project(m, [camera.target[0], camera.target[1] + 0.1 * radius, camera.target[2]], w, h);
    if (!a || !b) return;
    const dx = b[0] - a[0], dy = b[1] - a[1], n = Math.hypot(dx, dy);
    if (n < 1e-6) return;
    const ux = dx / n, uy = dy / n, c = [28 * dpr, 36 * dpr], len = 16 * dpr;
    const ctx = overlayContext;
    ctx.strokeStyle = settings.light ? '#222' : '#eee';
    ctx.fillStyle = ctx.strokeStyle;
    ctx.lineWidth = 2 * dpr;
    ctx.beginPath();
    ctx.moveTo(c[0] - ux * len, c[1] - uy * len);
    ctx.lineTo(c[0] + ux * len, c[1] + uy * len);
    ctx.stroke();
    ctx.beginPath();
    ctx.moveTo(c[0] + ux * (len + 6 * dpr), c[1] + uy * (len + 6 * dpr));
    ctx.lineTo(c[0] + ux * len - uy * 5 * dpr, c[1] + uy * len + ux * 5 * dpr);
    ctx.lineTo(c[0] + ux * len + uy * 5 * dpr, c[1] + uy * len - ux * 5 * dpr);
    ctx.fill();
    ctx.font = Math.round(12 * dpr) + 'px system-ui, sans-serif';
    ctx.fillText(northUp ? 'N' : 'fwd', c[0] + ux * (len + 10 * dpr) - 4 * dpr, c[1] + uy * (len + 10 * dpr) + 4 * dpr);
  }
  let pending = false;
  function requestDraw() {
    if (pending) return;
    pending = true;
    window.requestAnimationFrame(function () { pending = false; draw(); });
  }

  // ---- Mouse, touch and wheel.
  function rotate(dx, dy) {
    camera.yaw -= dx * 0.008;
    camera.pitch = Math.max(-1.55, Math.min(1.55, camera.pitch + dy * 0.008));
  }
  function pan(dx, dy) {
    const b = basis();
    const scale = 2 * camera.distance * Math.tan(FOV / 2) / Math.max(1, wrap.clientHeight);
    for (let i = 0; i < 3; ++i) camera.target[i] += (-dx * b.x[i] + dy * b.y[i]) * scale;
  }
  function zoom(factor) {
    camera.distance = Math.max(radius * 1e-4, Math.min(radius * 1e3, camera.distance * factor));
  }
  const pointers = new Map();
  let mode = 'rotate';
  canvas.addEventListener('pointerdown', function (e) {
    try {
      canvas.setPointerCapture(e.pointerId);
    } catch (error) {
      // not an active pointer (a synthetic event): dragging still works inside the canvas
    }
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    mode = (e.button === 1 || e.button === 2 || e.shiftKey) ? 'pan' : 'rotate';
    e.preventDefault();
  });
  canvas.addEventListener('pointermove', function (e) {
    const previous = pointers.get(e.pointerId);
    if (!previous) return;
    const dx = e.clientX - previous.x, dy = e.clientY - previous.y;
    if (pointers.size >= 2) {
      let other = null;
      pointers.forEach(function (p, id) { if (id !== e.pointerId && !other) other = p; });
      const before = Math.hypot(previous.x - other.x, previous.y - other.y);
      const after = Math.hypot(e.clientX - other.x, e.clientY - other.y);
      if (before > 0 && after > 0) zoom(before / after);
      pan(dx / 2, dy / 2);
    } else if (mode === 'pan' || e.shiftKey) {
      pan(dx, dy);
    } else {
      rotate(dx, dy);
    }
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    requestDraw();
  });
  function release(e) { pointers.delete(e.pointerId); }
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    zoom(Math.exp(e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015)));
    requestDraw();
  }, { passive: false });

  // ---- Controls and legend.
  function on(id, event, handler) {
    const element = document.getElementById(id);
    if (element) element.addEventListener(event, handler);
  }
  on('view-reset', 'click', function () {
    camera.target = home.target.slice();
    camera.distance = home.distance;
    camera.yaw = home.yaw;
    camera.pitch = home.pitch;
    requestDraw();
  });
  on('view-top', 'click', function () {
    camera.pitch = TOP_PITCH;
    camera.yaw = TOP_YAW;
    requestDraw();
  });
  on('view-oblique', 'click', function () {
    camera.pitch = 0.75;
    camera.yaw = TOP_YAW - 0.6;
    requestDraw();
  });
  function applyBackground() {
    wrap.classList.toggle('light', settings.light);
    wrap.style.background = settings.light ? '#f4f6f8' : '';
  }
  applyBackground();
  on('view-background', 'click', function () {
    settings.light = !settings.light;
    applyBackground();
    requestDraw();
  });
  const sizeSlider = document.getElementById('view-point-size');
  if (sizeSlider) sizeSlider.value = String(settings.pointSize);
  on('view-point-size', 'input', function (e) { settings.pointSize = parseFloat(e.target.value) || 2; requestDraw(); });
  ['trajectory', 'keyframes', 'landmarks', 'grid'].forEach(function (what) {
    on('show-' + what, 'change', function (e) { settings[what] = e.target.checked; requestDraw(); });
  });
  const legend = document.querySelector('#legend tbody');
  const legendRows = {};
  classes.forEach(function (c) {
    if (!(c.map_count > 0) && !(c.shown > 0)) return;
    const row = document.createElement('tr');
    const name = document.createElement('td');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = true;
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = 'rgb(' + c.color.join(',') + ')';
    name.appendChild(box);
    name.appendChild(document.createTextNode(' '));
    name.appendChild(swatch);
    name.appendChild(document.createTextNode(c.name));
    row.appendChild(name);
    [c.map_count, c.shown].forEach(function (n) {
      const td = document.createElement('td');
      td.className = 'num';
      td.textContent = Number(n).toLocaleString();
      row.appendChild(td);
    });
    row.addEventListener('click', function (e) {
      if (e.target !== box) box.checked = !box.checked;
      visible[c.id] = box.checked;
      row.classList.toggle('hidden-class', !box.checked);
      requestDraw();
    });
    legendRows[c.id] = { row: row, box: box };
    legend.appendChild(row);
  });
  function showAll(show) {
    classes.forEach(function (c) {
      visible[c.id] = show;
      const entry = legendRows[c.id];
      if (entry) { entry.box.checked = show; entry.row.classList.toggle('hidden-class', !show); }
    });
    requestDraw();
  }
  on('classes-all', 'click', function () { showAll(true); });
  on('classes-none', 'click', function () { showAll(false); });
  window.addEventListener('resize', requestDraw);
  // For scripted checks and the browser console.
  window.semslamViewer = { camera: camera, settings: settings, visible: visible, redraw: draw,
                           shown: shownCount };
  draw();
})();
