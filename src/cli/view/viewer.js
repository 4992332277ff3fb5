// urdyn's replay page: a small WebGL2 renderer (no third-party code).
// The data (geometry, body poses per frame, plot series, contacts) is the JSON in
// <script id="urdyn-data">; see src/cli/view/mod.rs for its layout.
"use strict";
(function () {
  const D = JSON.parse(document.getElementById("urdyn-data").textContent);

  // ---- data -------------------------------------------------------------
  function bytes(b64) {
    const s = atob(b64);
    const out = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
    return out.buffer;
  }
  const times = D.times;
  const nframes = times.length;
  const M = D.moving; // moving bodies (1..M); body 0 is the world
  const positions = new Float64Array(bytes(D.positions));
  const rotations = new Float32Array(bytes(D.rotations));
  const duration = nframes ? times[nframes - 1] - times[0] : 0;
  const links = D.links;
  const linkByName = new Map(links.map((l) => [l.name, l]));
  let arrows = null, arrowOffsets = null, maxForce = 0;
  if (D.contactForces) {
    arrows = new Float32Array(bytes(D.contactForces.arrows));
    arrowOffsets = D.contactForces.offsets;
    // Arrows scaled so that a typical force (the 90th percentile: impacts are
    // brief and far larger) is drawn at a fixed length.
    const norms = [];
    for (let i = 0; i < arrows.length; i += 6) norms.push(Math.hypot(arrows[i + 3], arrows[i + 4], arrows[i + 5]));
    norms.sort((a, b) => a - b);
    maxForce = norms.length ? norms[Math.floor(0.9 * (norms.length - 1))] : 0;
  }

  // ---- small math (double precision; matrices column-major 4×4) ---------
  // Body b's pose at frame f: {R: row-major 3×3, p: [3]} (R maps body to world);
  // with 0 < a < 1, the pose a of the way to frame f + 1 (drawing during playback).
  function bodyPose(f, b, a) {
    if (b === 0) return { R: [1, 0, 0, 0, 1, 0, 0, 0, 1], p: [0, 0, 0] };
    const i = (f * M + b - 1);
    let x = rotations[4 * i], y = rotations[4 * i + 1], z = rotations[4 * i + 2], w = rotations[4 * i + 3];
    let p = [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
    if (a > 0 && f + 1 < nframes) {
      const j = i + M;
      const q1 = [rotations[4 * j], rotations[4 * j + 1], rotations[4 * j + 2], rotations[4 * j + 3]];
      const s = x * q1[0] + y * q1[1] + z * q1[2] + w * q1[3] < 0 ? -1 : 1;
      x += a * (s * q1[0] - x); y += a * (s * q1[1] - y); z += a * (s * q1[2] - z); w += a * (s * q1[3] - w);
      p = p.map((v, k) => v + a * (positions[3 * j + k] - v));
    }
    const n = Math.hypot(x, y, z, w);
    x /= n; y /= n; z /= n; w /= n;
    const R = [
      1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
      2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
      2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
    ];
    return { R, p };
  }
  function mul3(A, B) { // row-major 3×3 product
    const C = new Array(9);
    for (let r = 0; r < 3; r++) for (let c = 0; c < 3; c++) {
      C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
    }
    return C;
  }
  function act(P, v) { // pose acting on a point
    const R = P.R;
    return [
      R[0] * v[0] + R[1] * v[1] + R[2] * v[2] + P.p[0],
      R[3] * v[0] + R[4] * v[1] + R[5] * v[2] + P.p[1],
      R[6] * v[0] + R[7] * v[1] + R[8] * v[2] + P.p[2],
    ];
  }
  function compose(A, B) { return { R: mul3(A.R, B.R), p: act(A, B.p) }; }
  function poseMat4(P, s) { // column-major, with a scale s = [sx, sy, sz] applied first
    const R = P.R, k = s || [1, 1, 1];
    return new Float32Array([
      R[0] * k[0], R[3] * k[0], R[6] * k[0], 0,
      R[1] * k[1], R[4] * k[1], R[7] * k[1], 0,
      R[2] * k[2], R[5] * k[2], R[8] * k[2], 0,
      P.p[0], P.p[1], P.p[2], 1,
    ]);
  }
  function mat4mul(a, b) {
    const o = new Float32Array(16);
    for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) {
      o[4 * c + r] = a[r] * b[4 * c] + a[4 + r] * b[4 * c + 1] + a[8 + r] * b[4 * c + 2] + a[12 + r] * b[4 * c + 3];
    }
    return o;
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function norm(a) { const n = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
  function lookAt(eye, target, up) {
    const f = norm(sub(target, eye)), s = norm(cross(f, up)), u = cross(s, f);
    return new Float32Array([
      s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
      -dot(s, eye), -dot(u, eye), dot(f, eye), 1,
    ]);
  }
  function perspective(fovy, aspect, near, far) {
    const t = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return new Float32Array([t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
  }
  function ortho(l, r, b, t, n, f) {
    return new Float32Array([2 / (r - l), 0, 0, 0, 0, 2 / (t - b), 0, 0, 0, 0, -2 / (f - n), 0,
      -(r + l) / (r - l), -(t + b) / (t - b), -(f + n) / (f - n), 1]);
  }

  // The world pose of a URDF link at frame f, as eval's link_poses.
  function linkPoseAt(f, name, a) {
    const l = linkByName.get(name);
    if (!l) return null;
    return compose(bodyPose(f, l.body, a || 0), { R: l.R, p: l.p });
  }

  // ---- WebGL ------------------------------------------------------------
  const canvas = document.getElementById("view");
  const gl = canvas.getContext("webgl2", { antialias: true, preserveDrawingBuffer: true });
  if (!gl) {
    const e = document.getElementById("error");
    e.hidden = false;
    e.textContent = "This page needs WebGL2, which this browser does not offer.";
    return;
  }
  function shader(type, src) {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  function program(vs, fs) {
    const p = gl.createProgram();
    gl.attachShader(p, shader(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fs));
    gl.bindAttribLocation(p, 0, "a_pos");
    gl.bindAttribLocation(p, 1, "a_col");
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    const u = {};
    const n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; i++) {
      const name = gl.getActiveUniform(p, i).name;
      u[name] = gl.getUniformLocation(p, name);
    }
    return { p, u };
  }
  const VS_MESH = `#version 300 es
    layout(location=0) in vec3 a_pos;
    uniform mat4 u_model, u_vp, u_light;
    uniform vec3 u_qmin, u_qext;
    out vec3 v_world; out vec4 v_light;
    void main() {
      vec4 w = u_model * vec4(u_qmin + a_pos * u_qext, 1.0);
      v_world = w.xyz; v_light = u_light * w;
      gl_Position = u_vp * w;
    }`;
  const SHADOW_FN = `
    uniform highp sampler2DShadow u_shadow;
    uniform float u_texel;
    float shadowAt(vec4 lp, float bias) {
      vec3 p = lp.xyz / lp.w * 0.5 + 0.5;
      if (p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 || p.z > 1.0) return 1.0;
      float s = 0.0;
      for (int i = -1; i <= 1; i++) for (int j = -1; j <= 1; j++)
        s += texture(u_shadow, vec3(p.xy + vec2(i, j) * u_texel, p.z - bias));
      return s / 9.0;
    }`;
  const FS_MESH = `#version 300 es
    precision highp float;
    in vec3 v_world; in vec4 v_light;
    uniform vec4 u_color; uniform vec3 u_eye, u_lightDir;
    out vec4 o;
    ${SHADOW_FN}
    void main() {
      vec3 n = normalize(cross(dFdx(v_world), dFdy(v_world)));
      vec3 toEye = normalize(u_eye - v_world);
      if (dot(n, toEye) < 0.0) n = -n;
      float nl = max(dot(n, u_lightDir), 0.0);
      float sh = nl > 0.0 ? shadowAt(v_light, 0.002 + 0.004 * (1.0 - nl)) : 0.0;
      vec3 sky = mix(vec3(0.2, 0.19, 0.18), vec3(0.42, 0.45, 0.5), n.z * 0.5 + 0.5);
      vec3 h = normalize(u_lightDir + toEye);
      float spec = pow(max(dot(n, h), 0.0), 48.0) * 0.22 * sh;
      float fill = max(dot(n, normalize(vec3(-0.5, 0.6, 0.2))), 0.0) * 0.16;
      vec3 c = u_color.rgb * (sky + vec3(1.0, 0.97, 0.9) * nl * sh * 0.72 + fill) + spec;
      o = vec4(min(c, vec3(1.0)), u_color.a);
    }`;
  const VS_DEPTH = `#version 300 es
    layout(location=0) in vec3 a_pos;
    uniform mat4 u_model, u_light; uniform vec3 u_qmin, u_qext;
    void main() { gl_Position = u_light * u_model * vec4(u_qmin + a_pos * u_qext, 1.0); }`;
  const FS_DEPTH = `#version 300 es
    precision mediump float; out vec4 o; void main() { o = vec4(1.0); }`;
  const VS_GROUND = `#version 300 es
    layout(location=0) in vec3 a_pos;
    uniform mat4 u_vp, u_light; uniform vec3 u_center; uniform float u_size, u_z;
    out vec3 v_world; out vec4 v_light;
    void main() {
      vec4 w = vec4(u_center.xy + a_pos.xy * u_size, u_z, 1.0);
      v_world = w.xyz; v_light = u_light * w; gl_Position = u_vp * w;
    }`;
  const FS_GROUND = `#version 300 es
    precision highp float;
    in vec3 v_world; in vec4 v_light;
    uniform float u_minor, u_size; uniform vec3 u_center;
    out vec4 o;
    ${SHADOW_FN}
    float grid(vec2 p, float s) {
      vec2 g = abs(fract(p / s - 0.5) - 0.5) / fwidth(p / s);
      return 1.0 - min(min(g.x, g.y), 1.0);
    }
    void main() {
      float minor = grid(v_world.xy, u_minor), major = grid(v_world.xy, u_minor * 10.0);
      float sh = shadowAt(v_light, 0.0015);
      vec3 base = vec3(0.90, 0.91, 0.92);
      vec3 c = mix(base, vec3(0.62, 0.65, 0.70), max(minor * 0.55, major));
      c *= 0.55 + 0.45 * sh;
      float fade = smoothstep(u_size * 0.95, u_size * 0.35, length(v_world.xy - u_center.xy));
      o = vec4(mix(vec3(0.874, 0.89, 0.91), c, fade), 1.0);
    }`;
  const VS_LINE = `#version 300 es
    layout(location=0) in vec3 a_pos; layout(location=1) in vec3 a_col;
    uniform mat4 u_vp; out vec3 v_col;
    void main() { v_col = a_col; gl_Position = u_vp * vec4(a_pos, 1.0); }`;
  const FS_LINE = `#version 300 es
    precision mediump float; in vec3 v_col; out vec4 o; void main() { o = vec4(v_col, 1.0); }`;

  const progMesh = program(VS_MESH, FS_MESH);
  const progDepth = program(VS_DEPTH, FS_DEPTH);
  const progGround = program(VS_GROUND, FS_GROUND);
  const progLine = program(VS_LINE, FS_LINE);

  // A drawable: VAO, index count and type, dequantisation.
  function drawable(pos, posType, idx, qmin, qext) {
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    const vb = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, vb);
    gl.bufferData(gl.ARRAY_BUFFER, pos, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, posType, posType === gl.UNSIGNED_SHORT, 0, 0);
    const ib = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ib);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    return {
      vao, count: idx.length, type: idx instanceof Uint32Array ? gl.UNSIGNED_INT : gl.UNSIGNED_SHORT,
      qmin: qmin || [0, 0, 0], qext: qext || [1, 1, 1],
    };
  }
  // Primitive shapes (unit sizes, scaled by the model matrix).
  function prim(verts, tris) { return drawable(new Float32Array(verts), gl.FLOAT, new Uint16Array(tris)); }
  function boxShape() {
    const v = [], t = [];
    for (let i = 0; i < 8; i++) v.push(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5);
    const q = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    for (const [a, b, c, d] of q) t.push(a, b, c, a, c, d);
    return prim(v, t);
  }
  // A surface of revolution about z: profile [[r, z], ...] from bottom to top.
  function lathe(profile, seg) {
    const v = [], t = [];
    for (const [r, z] of profile) for (let i = 0; i < seg; i++) {
      const a = 2 * Math.PI * i / seg;
      v.push(r * Math.cos(a), r * Math.sin(a), z);
    }
    for (let k = 0; k + 1 < profile.length; k++) for (let i = 0; i < seg; i++) {
      const a = k * seg + i, b = k * seg + (i + 1) % seg, c = a + seg, d = b + seg;
      t.push(a, b, d, a, d, c);
    }
    return prim(v, t);
  }
  // A circular arc of radius 1 about (0, zc) in the (r, z) plane, angles from +z.
  function arc(steps, zc, th0, th1) {
    const p = [];
    for (let k = 0; k <= steps; k++) {
      const th = th0 + (th1 - th0) * k / steps;
      p.push([Math.sin(th), zc + Math.cos(th)]);
    }
    return p;
  }
  const shapes = {};
  function shapeFor(v) {
    if (v.kind === "box") return (shapes.box = shapes.box || boxShape());
    if (v.kind === "cylinder") {
      return (shapes.cyl = shapes.cyl || lathe([[0, -0.5], [1, -0.5], [1, 0.5], [0, 0.5]], 48));
    }
    if (v.kind === "sphere" || v.kind === "ellipsoid") return (shapes.sph = shapes.sph || lathe(arc(24, 0, Math.PI, 0), 48));
    // capsule: its own shape (radius 1 before scaling by r; half length l / 2r)
    const r = v.dims[0] || 1e-9, h = v.dims[1] / 2 / r;
    return lathe(arc(12, -h, Math.PI, Math.PI / 2).concat(arc(12, h, Math.PI / 2, 0)), 48);
  }
  function visualScale(v) {
    const d = v.dims;
    switch (v.kind) {
      case "box": return d;
      case "cylinder": return [d[0], d[0], d[1]];
      case "sphere": case "capsule": return [d[0], d[0], d[0]];
      case "ellipsoid": return d;
      default: return [1, 1, 1];
    }
  }
  const meshes = D.meshes.map((m) => {
    const v = new Uint16Array(bytes(m.v));
    const ib = bytes(m.i);
    const idx = m.wide ? new Uint32Array(ib) : new Uint16Array(ib);
    return drawable(v, gl.UNSIGNED_SHORT, idx, m.min, m.ext);
  });
  const visuals = D.visuals.map((v) => {
    const d = v.kind === "mesh" ? meshes[v.mesh] : shapeFor(v);
    const scale = visualScale(v);
    let radius;
    if (v.kind === "mesh") {
      const m = D.meshes[v.mesh];
      radius = 0.5 * Math.hypot(m.ext[0], m.ext[1], m.ext[2]) + Math.hypot(m.min[0] + m.ext[0] / 2, m.min[1] + m.ext[1] / 2, m.min[2] + m.ext[2] / 2);
    } else {
      const d = v.dims;
      radius = v.kind === "box" ? Math.hypot(d[0], d[1], d[2]) / 2
        : v.kind === "cylinder" ? Math.hypot(d[0], d[1] / 2)
          : v.kind === "ellipsoid" ? Math.max(d[0], d[1], d[2])
            : d[0] + (v.kind === "capsule" ? d[1] / 2 : 0);
    }
    // the parts drawn, each in its colour: a DAE mesh's colour groups (a group
    // without a colour takes the visual's), else the whole drawable
    const bytesPerIndex = d.type === gl.UNSIGNED_INT ? 4 : 2;
    const groups = v.kind === "mesh" ? D.meshes[v.mesh].groups : null;
    const parts = groups
      ? groups.filter((g) => g[1] > 0).map((g) => ({ offset: g[0] * bytesPerIndex, count: g[1], color: g[2] || v.rgba }))
      : [{ offset: 0, count: d.count, color: v.rgba }];
    // the visual's local box (a mesh's bounds, a box's half extents; else none)
    const m = v.kind === "mesh" ? D.meshes[v.mesh] : null;
    const box = m ? { lo: m.min, hi: m.min.map((x, k) => x + m.ext[k]) }
      : v.kind === "box" ? { lo: v.dims.map((x) => -x / 2), hi: v.dims.map((x) => x / 2) } : null;
    return { d, body: v.body, local: { R: v.R, p: v.p }, scale, color: v.rgba, parts, radius, box };
  });
  const quad = drawable(new Float32Array([-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0]), gl.FLOAT, new Uint16Array([0, 1, 2, 0, 2, 3]));

  // Line buffer (link frames, contact arrows), refilled per draw.
  const lineVao = gl.createVertexArray();
  const lineBuf = gl.createBuffer();
  gl.bindVertexArray(lineVao);
  gl.bindBuffer(gl.ARRAY_BUFFER, lineBuf);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 24, 0);
  gl.enableVertexAttribArray(1);
  gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 24, 12);
  gl.bindVertexArray(null);

  // Shadow map.
  const SHADOW = 2048;
  const shadowTex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, shadowTex);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.DEPTH_COMPONENT24, SHADOW, SHADOW);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_COMPARE_MODE, gl.COMPARE_REF_TO_TEXTURE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_COMPARE_FUNC, gl.LEQUAL);
  const shadowFb = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, shadowFb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.TEXTURE_2D, shadowTex, 0);
  gl.drawBuffers([gl.NONE]);
  gl.readBuffer(gl.NONE);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);

  // ---- scene extent, camera ------------------------------------------------
  function visualWorld(f, v, a) { return compose(bodyPose(f, v.body, a || 0), v.local); }
  // The camera, the grid step and the force arrows' scale follow what moves (the
  // robots, not a 4 m height field under them), unless nothing does.
  const framed = visuals.some((v) => v.body > 0) ? visuals.filter((v) => v.body > 0) : visuals;
  function sceneBounds(f, a) {
    let c = [0, 0, 0], n = 0;
    const ps = framed.map((v) => visualWorld(f, v, a).p);
    for (const p of ps) { c = [c[0] + p[0], c[1] + p[1], c[2] + p[2]]; n++; }
    if (!n) {
      for (const l of links) { const p = linkPoseAt(f, l.name, a).p; c = [c[0] + p[0], c[1] + p[1], c[2] + p[2]]; n++; }
    }
    c = n ? [c[0] / n, c[1] / n, c[2] / n] : [0, 0, 0];
    let r = 0.05;
    framed.forEach((v, i) => { r = Math.max(r, Math.hypot(...sub(ps[i], c)) + v.radius); });
    if (!framed.length) for (const l of links) r = Math.max(r, Math.hypot(...sub(linkPoseAt(f, l.name, a).p, c)) + 0.05);
    return { c, r };
  }
  const start = nframes ? sceneBounds(0) : { c: [0, 0, 0], r: 1 };
  // z_min of a visual at frame 0: over its box's eight corners, else centre − radius
  function lowestZ(v) {
    const w = visualWorld(0, v);
    if (!v.box) return w.p[2] - v.radius;
    let z = Infinity;
    for (let k = 0; k < 8; k++) {
      const x = [0, 1, 2].map((i) => ((k >> i) & 1 ? v.box.hi[i] : v.box.lo[i]));
      z = Math.min(z, w.p[2] + w.R[6] * x[0] + w.R[7] * x[1] + w.R[8] * x[2]);
    }
    return z;
  }
  // The grid is the ground where there is one; without one it lies under
  // everything drawn (never through a height field or an obstacle below z = 0).
  const groundZ = D.ground === null || D.ground === undefined
    ? Math.min(0, ...(nframes ? visuals.map(lowestZ) : [])) - 1e-3
    : D.ground;
  const R0 = start.r;
  const minor = Math.pow(10, Math.floor(Math.log10(R0 / 2)));
  // Force arrows: metres per newton, chosen so that a typical force (see
  // maxForce) is about a third of the robot's size and a grid step stands for
  // a round number of newtons (1, 2 or 5 × 10^k); the legend says how many.
  let forceScale = 0, forceLegend = "";
  if (maxForce > 0) {
    const perGrid = maxForce * minor / (R0 * 0.35);
    const p10 = Math.pow(10, Math.floor(Math.log10(perGrid)));
    const nice = [1, 2, 5, 10].map((k) => k * p10).find((x) => x >= perGrid * 0.75) || 10 * p10;
    forceScale = minor / nice;
    forceLegend = `force arrows: ${fmtLength(minor)} = ${+nice.toPrecision(3)} N (one grid step)`;
  }
  function fmtLength(x) {
    return x >= 1 ? `${+x.toPrecision(3)} m` : x >= 0.01 ? `${+(x * 100).toPrecision(3)} cm` : `${+(x * 1000).toPrecision(3)} mm`;
  }
  // The camera looks at the robot (following it, unless "follow" is off) from
  // a distance that shows it whole; panning moves the point looked at.
  const cam = { offset: [0, 0, 0], fixed: start.c.slice(), dist: R0 * 2.5, yaw: -1.1, pitch: 0.3, target: start.c.slice() };
  function aim(sb) {
    const c = ui.follow.checked ? sb.c : cam.fixed;
    cam.target = [c[0] + cam.offset[0], c[1] + cam.offset[1], Math.max(c[2], groundZ + R0 * 0.25) + cam.offset[2]];
  }

  function eye() {
    const cp = Math.cos(cam.pitch);
    return [
      cam.target[0] + cam.dist * cp * Math.cos(cam.yaw),
      cam.target[1] + cam.dist * cp * Math.sin(cam.yaw),
      cam.target[2] + cam.dist * Math.sin(cam.pitch),
    ];
  }

  // ---- drawing --------------------------------------------------------------
  let frame = 0;
  let blend = 0; // during playback: how far the drawing is between frame and frame + 1
  const ui = {
    follow: document.getElementById("follow"),
    frames: document.getElementById("frames"),
    forces: document.getElementById("forces"),
    loops: document.getElementById("loops"),
  };
  if (!arrows) document.getElementById("forces-label").style.display = "none";
  const loops = D.loops || [];
  if (!loops.length) document.getElementById("loops-label").style.display = "none";
  const legend = document.getElementById("legend");
  function showLegend() {
    legend.textContent = arrows && ui.forces.checked ? forceLegend : "";
  }

  function draw() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    const f = Math.min(frame, Math.max(0, nframes - 1));
    const world = visuals.map((v) => ({ v, m: poseMat4(visualWorld(f, v, blend), v.scale) }));
    const sb = nframes ? sceneBounds(f, blend) : start;
    aim(sb);
    const e = eye();
    const view = lookAt(e, cam.target, [0, 0, 1]);
    const far = cam.dist * 4 + R0 * 60, near = Math.max(cam.dist * 0.01, 1e-4);
    const vp = mat4mul(perspective(0.75, w / h, near, far), view);
    const L = norm([0.35, 0.25, 1.0]);
    const lr = sb.r * 1.15;
    const lc = [sb.c[0], sb.c[1], Math.max(sb.c[2], groundZ)];
    const lview = lookAt([lc[0] + L[0] * lr * 3, lc[1] + L[1] * lr * 3, lc[2] + L[2] * lr * 3], lc, [0, 1, 0]);
    const light = mat4mul(ortho(-lr * 1.5, lr * 1.5, -lr * 1.5, lr * 1.5, 0.01, lr * 6 + Math.abs(lc[2] - groundZ) * 2), lview);

    // shadow pass
    gl.bindFramebuffer(gl.FRAMEBUFFER, shadowFb);
    gl.viewport(0, 0, SHADOW, SHADOW);
    gl.enable(gl.DEPTH_TEST);
    gl.clear(gl.DEPTH_BUFFER_BIT);
    gl.useProgram(progDepth.p);
    gl.uniformMatrix4fv(progDepth.u.u_light, false, light);
    for (const { v, m } of world) {
      gl.uniformMatrix4fv(progDepth.u.u_model, false, m);
      gl.uniform3fv(progDepth.u.u_qmin, v.d.qmin);
      gl.uniform3fv(progDepth.u.u_qext, v.d.qext);
      gl.bindVertexArray(v.d.vao);
      for (const part of v.parts) {
        if (part.color[3] < 0.5) continue;
        gl.drawElements(gl.TRIANGLES, part.count, v.d.type, part.offset);
      }
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);

    // main pass
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.874, 0.89, 0.91, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, shadowTex);
    const gsize = Math.max(R0 * 40, 4);
    gl.useProgram(progGround.p);
    const gu = progGround.u;
    gl.uniformMatrix4fv(gu.u_vp, false, vp);
    gl.uniformMatrix4fv(gu.u_light, false, light);
    gl.uniform3fv(gu.u_center, start.c);
    gl.uniform1f(gu.u_size, gsize);
    gl.uniform1f(gu.u_z, groundZ);
    gl.uniform1f(gu.u_minor, minor);
    gl.uniform1i(gu.u_shadow, 0);
    gl.uniform1f(gu.u_texel, 1 / SHADOW);
    gl.bindVertexArray(quad.vao);
    gl.drawElements(gl.TRIANGLES, quad.count, quad.type, 0);

    gl.useProgram(progMesh.p);
    const mu = progMesh.u;
    gl.uniformMatrix4fv(mu.u_vp, false, vp);
    gl.uniformMatrix4fv(mu.u_light, false, light);
    gl.uniform3fv(mu.u_eye, e);
    gl.uniform3fv(mu.u_lightDir, L);
    gl.uniform1i(mu.u_shadow, 0);
    gl.uniform1f(mu.u_texel, 1 / SHADOW);
    for (const pass of [0, 1]) { // opaque, then translucent
      if (pass) { gl.enable(gl.BLEND); gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA); gl.depthMask(false); }
      for (const { v, m } of world) {
        gl.uniformMatrix4fv(mu.u_model, false, m);
        gl.uniform3fv(mu.u_qmin, v.d.qmin);
        gl.uniform3fv(mu.u_qext, v.d.qext);
        gl.bindVertexArray(v.d.vao);
        for (const part of v.parts) {
          if ((part.color[3] < 0.99) !== (pass === 1)) continue;
          gl.uniform4fv(mu.u_color, part.color);
          gl.drawElements(gl.TRIANGLES, part.count, v.d.type, part.offset);
        }
      }
    }
    gl.disable(gl.BLEND);
    gl.depthMask(true);

    // lines on top: link frames, contact forces
    const lines = [];
    function seg(a, b, c) { lines.push(a[0], a[1], a[2], c[0], c[1], c[2], b[0], b[1], b[2], c[0], c[1], c[2]); }
    if (ui.frames.checked) {
      const s = R0 * 0.12;
      for (const l of links) {
        const P = linkPoseAt(f, l.name, blend);
        for (let k = 0; k < 3; k++) {
          const col = [k === 0 ? 0.9 : 0.1, k === 1 ? 0.75 : 0.1, k === 2 ? 0.95 : 0.1];
          seg(P.p, [P.p[0] + P.R[k] * s, P.p[1] + P.R[3 + k] * s, P.p[2] + P.R[6 + k] * s], col);
        }
      }
    }
    if (arrows && ui.forces.checked && f + 1 < arrowOffsets.length) {
      const scale = forceScale, mk = R0 * 0.02;
      for (let k = arrowOffsets[f]; k < arrowOffsets[f + 1]; k++) {
        const a = Array.from(arrows.subarray(6 * k, 6 * k + 6));
        const p = a.slice(0, 3), tip = [p[0] + a[3] * scale, p[1] + a[4] * scale, p[2] + a[5] * scale];
        const col = [0.95, 0.3, 0.05];
        seg(p, tip, col);
        const d = norm(sub(tip, p)), side = norm(Math.abs(d[2]) < 0.9 ? cross(d, [0, 0, 1]) : cross(d, [1, 0, 0]));
        const hl = Math.min(Math.hypot(...sub(tip, p)) * 0.25, R0 * 0.05);
        for (const sgn of [1, -1]) {
          seg(tip, [tip[0] - d[0] * hl + side[0] * hl * 0.5 * sgn, tip[1] - d[1] * hl + side[1] * hl * 0.5 * sgn, tip[2] - d[2] * hl + side[2] * hl * 0.5 * sgn], col);
        }
        seg([p[0] - mk, p[1], p[2]], [p[0] + mk, p[1], p[2]], col);
        seg([p[0], p[1] - mk, p[2]], [p[0], p[1] + mk, p[2]], col);
      }
    }
    // loop constraints: a line between the two anchor points (closed: a
    // point), a cross at each (side 1 magenta, side 2 cyan)
    if (ui.loops && ui.loops.checked) {
      const mk = R0 * 0.015;
      for (const l of loops) {
        const a = act(bodyPose(f, l.body1, blend), l.p1), b = act(bodyPose(f, l.body2, blend), l.p2);
        seg(a, b, [0.95, 0.85, 0.1]);
        for (const [p, col] of [[a, [0.9, 0.1, 0.8]], [b, [0.1, 0.8, 0.9]]]) {
          for (let k = 0; k < 3; k++) {
            const lo = p.slice(), hi = p.slice();
            lo[k] -= mk; hi[k] += mk;
            seg(lo, hi, col);
          }
        }
      }
    }
    if (lines.length) {
      gl.disable(gl.DEPTH_TEST);
      gl.useProgram(progLine.p);
      gl.uniformMatrix4fv(progLine.u.u_vp, false, vp);
      gl.bindVertexArray(lineVao);
      gl.bindBuffer(gl.ARRAY_BUFFER, lineBuf);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(lines), gl.DYNAMIC_DRAW);
      gl.drawArrays(gl.LINES, 0, lines.length / 6);
      gl.enable(gl.DEPTH_TEST);
    }
    gl.bindVertexArray(null);
  }

  // ---- plot -------------------------------------------------------------------
  const plot = document.getElementById("plot");
  const series = [
    { name: "energy (J)", data: D.energy, color: "#1f5fbf" },
    { name: "contacts", data: D.contacts, color: "#444" },
    { name: "penetration (m)", data: D.penetration, color: "#c0392b" },
  ].filter((s) => s.data && s.data.some((x) => x !== null));
  let plotBase = null, plotLabels = [];
  function drawPlot() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(plot.clientWidth * dpr)), h = Math.max(1, Math.round(plot.clientHeight * dpr));
    const ctx = plot.getContext("2d");
    if (plot.width !== w || plot.height !== h || !plotBase) {
      plot.width = w; plot.height = h;
      ctx.clearRect(0, 0, w, h);
      plotLabels = [];
      // the time axis: a strip at the bottom with ticks at round times
      const axis = 16 * dpr;
      const lane = (h - axis) / Math.max(series.length, 1);
      ctx.font = `${11 * dpr}px system-ui, sans-serif`;
      if (duration > 0) {
        const raw = duration / Math.max(2, Math.floor(w / (70 * dpr)));
        const p10 = Math.pow(10, Math.floor(Math.log10(raw)));
        const step = [1, 2, 5, 10].map((k) => k * p10).find((x) => x >= raw);
        const digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
        ctx.textBaseline = "alphabetic";
        for (let k = Math.ceil(times[0] / step - 1e-9); k * step <= times[0] + duration + 1e-9 * step; k++) {
          const t = k * step, x = (t - times[0]) / duration * w;
          ctx.strokeStyle = "#e3e6ea"; ctx.lineWidth = 1 * dpr;
          ctx.beginPath(); ctx.moveTo(x, 0); ctx.lineTo(x, h - axis); ctx.stroke();
          ctx.strokeStyle = "#7a828e";
          ctx.beginPath(); ctx.moveTo(x, h - axis); ctx.lineTo(x, h - axis + 4 * dpr); ctx.stroke();
          const label = `${t.toFixed(digits)} s`;
          const tw = ctx.measureText(label).width;
          ctx.fillStyle = "#4a525e";
          ctx.fillText(label, Math.min(Math.max(x - tw / 2, 0), w - tw), h - 3 * dpr);
        }
        ctx.strokeStyle = "#7a828e";
        ctx.beginPath(); ctx.moveTo(0, h - axis); ctx.lineTo(w, h - axis); ctx.stroke();
      }
      series.forEach((s, k) => {
        const vals = s.data.filter((x) => x !== null);
        let lo = Math.min(...vals), hi = Math.max(...vals);
        if (hi - lo < 1e-12) { hi += 0.5; lo -= 0.5; }
        const y0 = lane * k + 3 * dpr, y1 = lane * (k + 1) - 3 * dpr;
        ctx.strokeStyle = "#d5d9df";
        ctx.beginPath(); ctx.moveTo(0, y1 + 2 * dpr); ctx.lineTo(w, y1 + 2 * dpr); ctx.stroke();
        ctx.strokeStyle = s.color; ctx.lineWidth = 1.4 * dpr;
        ctx.beginPath();
        let pen = false;
        s.data.forEach((y, i) => {
          if (y === null) { pen = false; return; }
          const x = duration > 0 ? (times[i] - times[0]) / duration * w : 0;
          const yy = y1 - (y - lo) / (hi - lo) * (y1 - y0);
          if (pen) ctx.lineTo(x, yy); else ctx.moveTo(x, yy);
          pen = true;
        });
        ctx.stroke();
        plotLabels.push({ text: `${s.name}  [${fmt(lo)}, ${fmt(hi)}]`, color: s.color, x: 6 * dpr, y: y0 + 10 * dpr });
      });
      plotBase = ctx.getImageData(0, 0, w, h);
    }
    ctx.putImageData(plotBase, 0, 0);
    if (nframes) {
      const x = duration > 0 ? (times[frame] - times[0]) / duration * w : 0;
      ctx.strokeStyle = "#000"; ctx.lineWidth = 1 * dpr;
      ctx.beginPath(); ctx.moveTo(x, 0); ctx.lineTo(x, h - 16 * dpr); ctx.stroke();
    }
    // the series' names on top of the curves and the cursor, on a backing
    ctx.font = `${11 * dpr}px system-ui, sans-serif`;
    for (const l of plotLabels) {
      const tw = ctx.measureText(l.text).width;
      ctx.fillStyle = "rgba(247, 248, 250, 0.85)";
      ctx.fillRect(l.x - 3 * dpr, l.y - 10 * dpr, tw + 6 * dpr, 13 * dpr);
      ctx.fillStyle = l.color;
      ctx.fillText(l.text, l.x, l.y);
    }
  }
  function fmt(x) { return Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-3 && x !== 0) ? x.toExponential(2) : +x.toPrecision(4) + ""; }

  // ---- playback and input --------------------------------------------------------
  const slider = document.getElementById("slider");
  const clock = document.getElementById("clock");
  const playBtn = document.getElementById("play");
  const speedSel = document.getElementById("speed");
  slider.max = String(Math.max(0, nframes - 1));
  let playing = nframes > 1, simT = nframes ? times[0] : 0, dirty = true, lastWall = null;

  function nearest(t) {
    let lo = 0, hi = nframes - 1;
    if (hi < 0) return 0;
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (times[mid] <= t) lo = mid; else hi = mid; }
    return Math.abs(times[hi] - t) < Math.abs(t - times[lo]) ? hi : lo;
  }
  function floorFrame(t) { // the last frame at or before t
    let k = nearest(t);
    if (k > 0 && times[k] > t) k--;
    return k;
  }
  function show(k) {
    frame = k;
    slider.value = String(k);
    clock.textContent = nframes ? `${times[k].toFixed(3)} s` : "";
    dirty = true;
  }
  function setPlaying(p) {
    playing = p && nframes > 1;
    playBtn.textContent = playing ? "❚❚" : "▶";
    lastWall = null;
    blend = 0;
    dirty = true;
  }
  playBtn.addEventListener("click", () => {
    if (!playing && frame >= nframes - 1) { simT = times[0]; show(0); }
    setPlaying(!playing);
  });
  slider.addEventListener("input", () => { setPlaying(false); const k = +slider.value; simT = times[k]; show(k); });
  ui.frames.addEventListener("change", () => { dirty = true; });
  ui.follow.addEventListener("change", () => {
    // keep the view where it is: the offset moves to the other reference point
    const c = ui.follow.checked ? sceneBounds(frame).c : cam.fixed;
    for (let i = 0; i < 3; i++) cam.offset[i] = cam.target[i] - c[i];
    dirty = true;
  });
  ui.forces.addEventListener("change", () => { showLegend(); dirty = true; });
  ui.loops.addEventListener("change", () => { dirty = true; });
  window.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target.tagName !== "BUTTON") { e.preventDefault(); playBtn.click(); }
  });
  window.addEventListener("resize", () => { plotBase = null; dirty = true; });
  function plotSeek(e) {
    const r = plot.getBoundingClientRect();
    const t = times[0] + (e.clientX - r.left) / r.width * duration;
    setPlaying(false); simT = t; show(nearest(t));
  }
  plot.addEventListener("pointerdown", (e) => { plotSeek(e); plot.setPointerCapture(e.pointerId); });
  plot.addEventListener("pointermove", (e) => { if (e.buttons) plotSeek(e); });

  let drag = null;
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    if (drag.pan || e.shiftKey) {
      const k = cam.dist * 0.0016;
      const f = norm(sub(cam.target, eye())), s = norm(cross(f, [0, 0, 1])), u = cross(s, f);
      for (let i = 0; i < 3; i++) cam.offset[i] += (-dx * s[i] + dy * u[i]) * k;
    } else {
      cam.yaw -= dx * 0.008;
      cam.pitch = Math.max(-1.5, Math.min(1.5, cam.pitch + dy * 0.008));
    }
    dirty = true;
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    cam.dist *= Math.exp(e.deltaY * 0.0012);
    cam.dist = Math.max(R0 * 0.05, Math.min(cam.dist, R0 * 200));
    dirty = true;
  }, { passive: false });

  function tick(now) {
    if (playing) {
      if (lastWall !== null) {
        simT += (now - lastWall) / 1000 * +speedSel.value;
        if (simT >= times[nframes - 1]) { simT = times[nframes - 1]; setPlaying(false); }
      }
      lastWall = now;
      const k = floorFrame(simT);
      if (k !== frame) show(k);
      const a = playing && k + 1 < nframes ? (simT - times[k]) / (times[k + 1] - times[k]) : 0;
      blend = a > 0 && a < 1 ? a : 0;
      dirty = true;
    }
    if (dirty) { dirty = false; draw(); drawPlot(); }
    requestAnimationFrame(tick);
  }

  showLegend();
  show(0);
  setPlaying(playing);
  draw();
  drawPlot();
  dirty = false;
  window.urdynViewer = {
    ready: true,
    duration,
    frames: nframes,
    times: times.slice(),
    readyMs: performance.now(),
    seek(t) {
      setPlaying(false);
      const k = nearest(+t);
      simT = times[k];
      show(k);
      draw();
      drawPlot();
      dirty = false;
      return times[k];
    },
    // the drawn loop constraints' two anchor points (world) at the frame shown
    loopAnchors() {
      return loops.map((l) => ({ name: l.name, point1: act(bodyPose(frame, l.body1, 0), l.p1),
        point2: act(bodyPose(frame, l.body2, 0), l.p2) }));
    },
    linkPose(name) {
      const P = linkPoseAt(frame, name);
      if (!P) return null;
      const R = P.R;
      return { position: P.p, rotation: [[R[0], R[1], R[2]], [R[3], R[4], R[5]], [R[6], R[7], R[8]]] };
    },
  };
  requestAnimationFrame(tick);
})();
