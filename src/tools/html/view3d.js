// The run page's 3-D view (src/tools/html/view3d.rs writes its data): the vehicle flying its trace in WebGL, with
// a time slider. Written by hand, without a library: it draws a few boxes, prisms, discs and lines, which a 3-D
// library would do in some 600 KB more of page (docs/src/explanations/architecture.md, "Written by hand").
// Frames: world east-north-up (m), body forward-left-up, as Foxglove's (src/recording/foxglove.rs); the aircraft is
// the model Foxglove's 3D panel draws, its surfaces hinged the same way.
(function () {
  'use strict';
  // Column-major 4x4 matrices, as WebGL takes them.
  function mul(a, b) {
    var o = new Float32Array(16);
    for (var c = 0; c < 4; c++)
      for (var r = 0; r < 4; r++) {
        var s = 0;
        for (var k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
        o[c * 4 + r] = s;
      }
    return o;
  }
  // The rotation of quaternion (x, y, z, w) as a 3x3, rows.
  function quatMatrix(q) {
    var x = q[0], y = q[1], z = q[2], w = q[3];
    return [
      [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]
    ];
  }
  // Translation, then rotation q, then scale s.
  function pose(t, q, s) {
    var m = quatMatrix(q);
    s = s || [1, 1, 1];
    return new Float32Array([
      m[0][0] * s[0], m[1][0] * s[0], m[2][0] * s[0], 0,
      m[0][1] * s[1], m[1][1] * s[1], m[2][1] * s[1], 0,
      m[0][2] * s[2], m[1][2] * s[2], m[2][2] * s[2], 0,
      t[0], t[1], t[2], 1
    ]);
  }
  function perspective(fovy, aspect, near, far) {
    var f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function unit(a) { var n = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function lookAt(eye, target, up) {
    var z = unit(sub(eye, target)), x = unit(cross(up, z)), y = cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
      -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
  }
  // A moving surface's box in the body: hinged on a line through `hinge` along body y (axis 0) or z (axis 1), its
  // centre `aft` behind the hinge, turned by sign x its surface's position: Foxglove's model, the same arithmetic.
  function surfacePose(s, surfacesRad) {
    var a = s.sign * surfacesRad[s.surface], c = Math.cos(a), sn = Math.sin(a), aft = -s.aft, h = s.hinge;
    var half = [Math.sin(a / 2), Math.cos(a / 2)];
    return s.axis === 0
      ? { center: [h[0] + aft * c, h[1], h[2] - aft * sn], q: [0, half[0], 0, half[1]] }
      : { center: [h[0] + aft * c, h[1] + aft * sn, h[2]], q: [0, 0, half[0], half[1]] };
  }
  window.silrigView3d = { quatMatrix: quatMatrix, surfacePose: surfacePose };

  var root = document.getElementById('view3d');
  if (!root) return;
  var data = JSON.parse(document.getElementById('view3d-data').textContent);
  var canvas = root.querySelector('canvas'), status = root.querySelector('.view3d-status');
  var gl = canvas.getContext('webgl', { antialias: true });
  var frames = data.t.length;
  if (!gl) {
    status.textContent = 'This browser gives the page no WebGL: the 3-D view cannot be drawn (the figures show the same flight).';
    root.setAttribute('data-view3d-frames', '0');
    return;
  }
  var VS = 'attribute vec3 a_p;attribute vec3 a_n;uniform mat4 u_mvp;uniform mat4 u_model;uniform vec3 u_col;' +
    'uniform float u_lit;varying vec3 v_c;void main(){gl_Position=u_mvp*vec4(a_p,1.0);' +
    'vec3 n=normalize((u_model*vec4(a_n,0.0)).xyz+vec3(1e-6));' +
    'float l=u_lit>0.5?0.45+0.55*abs(dot(n,normalize(vec3(0.35,0.25,0.9)))):1.0;v_c=u_col*l;}';
  var FS = 'precision mediump float;varying vec3 v_c;void main(){gl_FragColor=vec4(v_c,1.0);}';
  function shader(type, text) {
    var s = gl.createShader(type);
    gl.shaderSource(s, text);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  var prog = gl.createProgram();
  gl.attachShader(prog, shader(gl.VERTEX_SHADER, VS));
  gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, FS));
  gl.linkProgram(prog);
  gl.useProgram(prog);
  var at = { p: gl.getAttribLocation(prog, 'a_p'), n: gl.getAttribLocation(prog, 'a_n') };
  var un = {};
  ['u_mvp', 'u_model', 'u_col', 'u_lit'].forEach(function (u) { un[u] = gl.getUniformLocation(prog, u); });
  gl.enableVertexAttribArray(at.p);
  gl.enableVertexAttribArray(at.n);
  gl.enable(gl.DEPTH_TEST);

  // Meshes: interleaved position and normal, 6 floats a vertex.
  function mesh(vertices, mode) {
    var b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(vertices), gl.STATIC_DRAW);
    return { buffer: b, count: vertices.length / 6, mode: mode };
  }
  function quadFace(v, a, b, c, d, n) { [a, b, c, a, c, d].forEach(function (p) { v.push(p[0], p[1], p[2], n[0], n[1], n[2]); }); }
  function boxMesh() {
    var v = [], h = 0.5;
    [[0, 1, 2], [1, 2, 0], [2, 0, 1]].forEach(function (ax) {
      [-1, 1].forEach(function (sg) {
        function p(u, w) { var o = [0, 0, 0]; o[ax[0]] = sg * h; o[ax[1]] = u * h; o[ax[2]] = w * h; return o; }
        var n = [0, 0, 0]; n[ax[0]] = sg;
        quadFace(v, p(-1, -1), p(1, -1), p(1, 1), p(-1, 1), n);
      });
    });
    return mesh(v, gl.TRIANGLES);
  }
  // A prism along x from -0.5 to 0.5, radius 0.5 at its back and 0.5 x top at its front (0: a cone).
  function ring(a, r, x) { return [x, r * Math.cos(a), r * Math.sin(a)]; }
  function prismMesh(sides, top) {
    var v = [];
    for (var k = 0; k < sides; k++) {
      var a0 = 2 * Math.PI * k / sides, a1 = 2 * Math.PI * (k + 1) / sides, am = (a0 + a1) / 2;
      quadFace(v, ring(a0, 0.5, -0.5), ring(a1, 0.5, -0.5), ring(a1, 0.5 * top, 0.5), ring(a0, 0.5 * top, 0.5),
        [0, Math.cos(am), Math.sin(am)]);
    }
    return mesh(v, gl.TRIANGLES);
  }
  // A disc of radius 0.5 in the x-y plane.
  function discMesh(sides) {
    var v = [];
    for (var k = 0; k < sides; k++) {
      var a0 = 2 * Math.PI * k / sides, a1 = 2 * Math.PI * (k + 1) / sides;
      [[0, 0, 0], [0.5 * Math.cos(a0), 0.5 * Math.sin(a0), 0], [0.5 * Math.cos(a1), 0.5 * Math.sin(a1), 0]]
        .forEach(function (p) { v.push(p[0], p[1], p[2], 0, 0, 1); });
    }
    return mesh(v, gl.TRIANGLES);
  }
  var box = boxMesh(), prism = prismMesh(12, 1), cone = prismMesh(12, 0), disc = discMesh(20);
  var lines = gl.createBuffer();

  // The vehicle's parts, each a mesh, a colour and its pose in the body at frame i.
  var model = data.model, parts = [], none = [0, 0, 0, 1];
  (model.cylinders || []).forEach(function (c) {
    parts.push({ mesh: c.top === 0 ? cone : prism, col: c.color, at: function () { return pose([c.x, 0, 0], none, [c.length, c.diameter, c.diameter]); } });
  });
  (model.boxes || []).forEach(function (b) {
    parts.push({ mesh: box, col: b.color, at: function () { return pose(b.center, b.q || none, b.size); } });
  });
  (model.surfaces || []).forEach(function (s) {
    parts.push({ mesh: box, col: s.color, at: function (i) {
      var p = surfacePose(s, data.surfaces.length ? data.surfaces.slice(3 * i, 3 * i + 3) : [0, 0, 0]);
      return pose(p.center, p.q, s.size);
    } });
  });
  (model.rotors || []).forEach(function (r, k) {
    parts.push({ mesh: disc, col: null, rotor: k, at: function () { return pose(r.center, none, [r.diameter, r.diameter, 1]); } });
  });
  var slow = [0.55, 0.57, 0.6], fast = [1.0, 0.45, 0.05];
  function rotorColour(i, k) {
    var f = data.rotors.length ? data.rotors[4 * i + k] : 0;
    return [0, 1, 2].map(function (j) { return slow[j] + (fast[j] - slow[j]) * f; });
  }

  var origin = data.p.slice(0, 3), size = model.length_m, view = { az: 0, el: 0.38, zoom: 1 };
  function position(i) { return [data.p[3 * i] - origin[0], data.p[3 * i + 1] - origin[1], data.p[3 * i + 2] - origin[2]]; }
  var path = [];
  for (var i = 0; i < frames; i++) { var p = position(i); path.push(p[0], p[1], p[2], 0, 0, 0); }
  var pathMesh = mesh(path, gl.LINE_STRIP);

  function bind(m) {
    gl.bindBuffer(gl.ARRAY_BUFFER, m.buffer);
    gl.vertexAttribPointer(at.p, 3, gl.FLOAT, false, 24, 0);
    gl.vertexAttribPointer(at.n, 3, gl.FLOAT, false, 24, 12);
  }
  function draw(vp, m, modelMatrix, col, lit, first, count) {
    bind(m);
    gl.uniformMatrix4fv(un.u_mvp, false, mul(vp, modelMatrix));
    gl.uniformMatrix4fv(un.u_model, false, modelMatrix);
    gl.uniform3fv(un.u_col, col);
    gl.uniform1f(un.u_lit, lit ? 1 : 0);
    gl.drawArrays(m.mode, first || 0, count === undefined ? m.count : count);
  }
  // Grid lines around `centre` on the plane at height `z`, `step` apart, each line in segments a step long (a line
  // that passes behind the camera is not drawn whole by every WebGL: SwiftShader's drops it).
  function grid(centre, z, step) {
    var v = [], n = 30, cx = Math.round(centre[0] / step) * step, cy = Math.round(centre[1] / step) * step;
    for (var k = -n; k <= n; k++)
      for (var j = -n; j < n; j++) {
        v.push(cx + k * step, cy + j * step, z, 0, 0, 0, cx + k * step, cy + (j + 1) * step, z, 0, 0, 0);
        v.push(cx + j * step, cy + k * step, z, 0, 0, 0, cx + (j + 1) * step, cy + k * step, z, 0, 0, 0);
      }
    gl.bindBuffer(gl.ARRAY_BUFFER, lines);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(v), gl.DYNAMIC_DRAW);
    return { buffer: lines, count: v.length / 6, mode: gl.LINES };
  }
  var identity = pose([0, 0, 0], none);
  var heading = 0;

  function render(i) {
    var w = canvas.width, h = canvas.height, p = position(i), q = data.q.slice(4 * i, 4 * i + 4);
    var r = quatMatrix(q), fwd = [r[0][0], r[1][0], r[2][0]];
    if (Math.hypot(fwd[0], fwd[1]) > 0.2) heading = Math.atan2(fwd[1], fwd[0]);
    var az = heading + Math.PI + view.az, el = view.el, d = 3.2 * size * view.zoom;
    var eye = [p[0] + d * Math.cos(el) * Math.cos(az), p[1] + d * Math.cos(el) * Math.sin(az), p[2] + d * Math.sin(el)];
    var vp = mul(perspective(0.8, w / h, 0.02 * size, 4000 * size), lookAt(eye, p, [0, 0, 1]));
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.93, 0.95, 0.97, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    draw(vp, grid(p, data.grid_z_m - origin[2], data.grid_step_m), identity, [0.74, 0.78, 0.82], false);
    draw(vp, pathMesh, identity, [0.6, 0.64, 0.7], false);
    draw(vp, pathMesh, identity, [0.05, 0.36, 0.68], false, 0, i + 1);
    var body = pose(p, q);
    parts.forEach(function (part) {
      var col = part.rotor === undefined ? part.col : rotorColour(i, part.rotor);
      draw(vp, part.mesh, mul(body, part.at(i)), col, true);
    });
    status.textContent = 't = ' + data.t[i].toFixed(2) + ' s, ' + data.height_name + ' ' +
      (data.p[3 * i + 2]).toFixed(2) + ' m, ' + Math.hypot(p[0], p[1]).toFixed(1) + ' m from the start, horizontally';
  }

  var slider = root.querySelector('input[type=range]'), play = root.querySelector('button');
  var speed = root.querySelector('select'), shown = 0, playing = false, last = 0;
  slider.max = String(frames - 1);
  function show(i) { shown = Math.max(0, Math.min(frames - 1, i)); slider.value = String(shown); render(shown); }
  slider.addEventListener('input', function () { show(Number(slider.value)); });
  function tick(now) {
    if (!playing) return;
    var t = data.t[shown] + (now - last) / 1000 * Number(speed.value);
    last = now;
    var i = shown;
    while (i + 1 < frames && data.t[i + 1] <= t) i++;
    show(i);
    if (i + 1 >= frames) { playing = false; play.textContent = 'play'; return; }
    requestAnimationFrame(tick);
  }
  play.addEventListener('click', function () {
    playing = !playing;
    play.textContent = playing ? 'pause' : 'play';
    if (playing) { if (shown + 1 >= frames) show(0); last = performance.now(); requestAnimationFrame(tick); }
  });
  // Drag to turn the camera about the vehicle, the wheel to come nearer.
  var drag = null;
  canvas.addEventListener('mousedown', function (e) { drag = [e.clientX, e.clientY]; });
  window.addEventListener('mouseup', function () { drag = null; });
  window.addEventListener('mousemove', function (e) {
    if (!drag) return;
    view.az -= (e.clientX - drag[0]) * 0.01;
    view.el = Math.max(-1.4, Math.min(1.4, view.el + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    render(shown);
  });
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    view.zoom = Math.max(0.2, Math.min(50, view.zoom * Math.exp(e.deltaY * 0.001)));
    render(shown);
  }, { passive: false });

  root.setAttribute('data-view3d-frames', String(frames));
  show(0);
  // What the browser test reads, asked for by the page's address ending in #view3d-test (reading pixels back
  // stalls the GPU, and the browser says so on the console): a checksum and a colour count of the pixels drawn at
  // the first and the last frame (a view that moves draws them differently).
  if (location.hash.indexOf('view3d-test') < 0) return;
  function pixels() {
    var px = new Uint8Array(canvas.width * canvas.height * 4), sum = 0, colours = {}, n = 0;
    gl.readPixels(0, 0, canvas.width, canvas.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
    for (var k = 0; k < px.length; k += 4) {
      var c = (px[k] << 16) | (px[k + 1] << 8) | px[k + 2];
      sum = (sum * 31 + c) >>> 0;
      if (!colours[c]) { colours[c] = 1; n++; }
    }
    return [sum, n];
  }
  render(frames - 1);
  var lastPixels = pixels();
  show(0);
  var firstPixels = pixels();
  root.setAttribute('data-view3d-first', String(firstPixels[0]));
  root.setAttribute('data-view3d-last', String(lastPixels[0]));
  root.setAttribute('data-view3d-colours', String(Math.min(firstPixels[1], lastPixels[1])));
})();
