// The interactive material report (docs/report.md). A classic script: it reads what svbtdf
// report wrote into window.SVBTDF_REPORT, SVBTDF_TEXELS, SVBTDF_LOBES and SVBTDF_GLTF (generated
// scripts, since a file:// page may fetch nothing) and three.js from three-bundle.js. The numbers
// are computed in C++; this file only draws them.
(function () {
  'use strict';
  const REPORT = window.SVBTDF_REPORT, TEXELS = window.SVBTDF_TEXELS, LOBES = window.SVBTDF_LOBES;
  const THREE = window.THREE;
  // What the browser test reads: whether the page is ready, the texel shown, the live view's state.
  const state = window.SVBTDF_PAGE = { ready: false, inspected: null, mode: null, sgDifference: null, errors: [] };

  // --- helpers -------------------------------------------------------------------------------
  function bytes(base64) {
    const text = atob(base64 || '');
    const out = new Uint8Array(text.length);
    for (let k = 0; k < text.length; ++k) out[k] = text.charCodeAt(k);
    return out;
  }
  function float32(base64) { return new Float32Array(bytes(base64).buffer); }
  // The same five-stop viridis ramp as the maps (report/src/picture.cc); white for NaN.
  const STOPS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  function ramp(t) {
    if (!isFinite(t)) return 'rgb(255,255,255)';
    t = Math.min(1, Math.max(0, t)) * 4;
    const k = Math.min(3, Math.floor(t)), f = t - k;
    const c = STOPS[k].map((v, j) => Math.round(v + f * (STOPS[k + 1][j] - v)));
    return `rgb(${c[0]},${c[1]},${c[2]})`;
  }
  function format(v) { return isFinite(v) ? Number(v).toPrecision(3) : 'n/a'; }
  function context(id) {
    const canvas = document.getElementById(id);
    if (!canvas) return null;
    const g = canvas.getContext('2d');
    g.clearRect(0, 0, canvas.width, canvas.height);
    g.font = '11px sans-serif';
    g.fillStyle = '#000';
    return g;
  }
  // Axes of a plot area (x0, y0, w, h) with labels and a few ticks.
  function axes(g, box, xRange, yRange, xLabel, yLabel, tickFormat, yTickFormat = tickFormat) {
    const [x0, y0, w, h] = box;
    g.strokeStyle = '#444';
    g.strokeRect(x0, y0, w, h);
    g.fillStyle = '#000';
    g.textAlign = 'center';
    for (let k = 0; k <= 4; ++k) {
      const xv = xRange[0] + (xRange[1] - xRange[0]) * k / 4, yv = yRange[0] + (yRange[1] - yRange[0]) * k / 4;
      g.fillText(tickFormat(xv), x0 + w * k / 4, y0 + h + 13);
      g.textAlign = 'right';
      g.fillText(yTickFormat(yv), x0 - 3, y0 + h - h * k / 4 + 4);
      g.textAlign = 'center';
    }
    g.fillText(xLabel, x0 + w / 2, y0 + h + 27);
    g.save();
    g.translate(x0 - 36, y0 + h / 2);
    g.rotate(-Math.PI / 2);
    g.fillText(yLabel, 0, 0);
    g.restore();
  }

  // --- section 2: the texel inspector --------------------------------------------------------
  const inspection = TEXELS && {
    measured: float32(TEXELS.measured), fitted: float32(TEXELS.fitted), ndf: bytes(TEXELS.ndf),
    trueNdf: bytes(TEXELS.true_ndf), residual: float32(TEXELS.residual), heldOut: new Set(TEXELS.held_out),
  };

  function nearest(list, value) {
    let best = 0;
    list.forEach((v, k) => { if (Math.abs(v - value) < Math.abs(list[best] - value)) best = k; });
    return best;
  }

  function lightDirection(k, q) {
    const p = TEXELS.dot_positions[q], c = TEXELS.texel_centres[k];
    const d = [p[0] - c[0], p[1] - c[1], p[2]];
    const n = Math.hypot(d[0], d[1], d[2]);
    return [d[0] / n, d[1] / n];
  }

  // The slice over the light directions, seen from above (x right, y up), log colour scale.
  function drawSlice(id, title, k, values, lo, hi) {
    const g = context(id);
    if (!g) return;
    const size = 240, cx = 130, cy = 150, radius = size / 2 - 4;
    g.textAlign = 'center';
    g.fillText(title, cx, 14);
    g.strokeStyle = '#bbb';
    g.beginPath(); g.arc(cx, cy, radius, 0, 2 * Math.PI); g.stroke();
    g.fillText('light direction i, x right, y up (unit disc)', cx, cy + radius + 14 > 288 ? 286 : cy + radius + 14);
    const dots = TEXELS.dots;
    for (let q = 0; q < dots; ++q) {
      const [x, y] = lightDirection(k, q);
      const v = values[k * dots + q];
      const px = cx + x * radius, py = cy - y * radius;
      if (!isFinite(v)) {
        g.strokeStyle = '#999';
        g.beginPath(); g.moveTo(px - 3, py - 3); g.lineTo(px + 3, py + 3); g.moveTo(px + 3, py - 3); g.lineTo(px - 3, py + 3); g.stroke();
        continue;
      }
      g.fillStyle = ramp((Math.log10(Math.max(v, lo)) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo)));
      g.beginPath(); g.arc(px, py, 4, 0, 2 * Math.PI); g.fill();
    }
    // The held-out dots' rings last, so that no neighbour covers them.
    g.strokeStyle = '#e00';
    g.lineWidth = 2;
    for (const q of inspection.heldOut) {
      if (q >= dots) continue;
      const [x, y] = lightDirection(k, q);
      g.beginPath(); g.arc(cx + x * radius, cy - y * radius, 5, 0, 2 * Math.PI); g.stroke();
    }
    g.lineWidth = 1;
    g.fillStyle = '#000';
  }

  function drawScatter(k, lo, hi) {
    const g = context('slice-scatter');
    if (!g) return;
    const box = [50, 20, 225, 225], dots = TEXELS.dots;
    const l0 = Math.log10(lo), l1 = Math.log10(hi);
    axes(g, box, [l0, l1], [l0, l1], 'measured R, log10 (1/sr)', 'fitted R, log10 (1/sr)', (v) => v.toFixed(1));
    g.textAlign = 'center';
    g.fillText('fitted against measured (red: held out)', 160, 12);
    g.strokeStyle = '#aaa';
    g.beginPath(); g.moveTo(box[0], box[1] + box[3]); g.lineTo(box[0] + box[2], box[1]); g.stroke();
    for (let q = 0; q < dots; ++q) {
      const m = inspection.measured[k * dots + q], f = inspection.fitted[k * dots + q];
      if (!isFinite(m) || !isFinite(f) || m <= 0 || f <= 0) continue;
      const px = box[0] + (Math.log10(m) - l0) / (l1 - l0) * box[2];
      const py = box[1] + box[3] - (Math.log10(f) - l0) / (l1 - l0) * box[3];
      g.fillStyle = inspection.heldOut.has(q) ? '#e00' : '#248';
      g.fillRect(px - 2, py - 2, 4, 4);
    }
  }

  function drawNdf(id, title, values, k) {
    const g = context(id);
    if (!g) return;
    const side = TEXELS.ndf_side, cells = side * side, scale = 128 / side;
    g.textAlign = 'center';
    g.fillText(title, 75, 12);
    if (values.length < (k + 1) * cells) { g.fillText('(no truth)', 75, 80); return; }
    for (let c = 0; c < cells; ++c) {
      const v = values[k * cells + c];  // the top 8 units of ln D as 0 .. 254; 255 outside the disc
      g.fillStyle = ramp(v === 255 ? NaN : v / 254);
      g.fillRect(11 + (c % side) * scale, 18 + Math.floor(c / side) * scale, scale, scale);
    }
    g.fillStyle = '#000';
    g.fillText('ln D, top 8 units', 75, 162);
  }

  function inspect(x, y) {
    if (!TEXELS) return;
    const c = nearest(TEXELS.x, x), r = nearest(TEXELS.y, y), k = r * TEXELS.cols + c;
    const dots = TEXELS.dots;
    let hi = 0;
    for (let q = 0; q < dots; ++q) {
      for (const v of [inspection.measured[k * dots + q], inspection.fitted[k * dots + q]]) if (isFinite(v)) hi = Math.max(hi, v);
    }
    hi = hi > 0 ? hi : 1;
    const lo = hi / 1000;
    const residual = inspection.residual[k];
    document.getElementById('inspect-title').textContent =
      `Texel (${TEXELS.x[c]}, ${TEXELS.y[r]}) (nearest inspected to (${x}, ${y}); ${TEXELS.cols} x ${TEXELS.rows} grid), ` +
      `fit residual ${residual >= 0 ? (100 * residual).toPrecision(3) + '%' : 'not fitted'}; colour: log10 R from ` +
      `${format(lo)} to ${format(hi)} 1/sr; ${dots} dots, ${inspection.heldOut.size} held out (ringed red).`;
    if (dots > 0) {
      drawSlice('slice-measured', 'measured', k, inspection.measured, lo, hi);
      drawSlice('slice-fitted', 'fitted', k, inspection.fitted, lo, hi);
      drawScatter(k, lo, hi);
    }
    drawNdf('ndf-fitted', 'NDF, fitted', inspection.ndf, k);
    drawNdf('ndf-truth', 'NDF, true', inspection.trueNdf, k);
    state.inspected = { x: TEXELS.x[c], y: TEXELS.y[r], dots };
  }

  function wireMaps() {
    document.querySelectorAll('figure.map').forEach((figure) => {
      const [w, h] = figure.dataset.texels.split(' ').map(Number);
      const img = figure.querySelector('img');
      img.addEventListener('click', (event) => {
        const x = Math.min(w - 1, Math.floor(event.offsetX / img.clientWidth * w));
        const y = Math.min(h - 1, Math.floor(event.offsetY / img.clientHeight * h));
        inspect(x, y);
        document.getElementById('inspect').scrollIntoView({ behavior: 'instant', block: 'start' });
      });
    });
  }

  // --- section 5: calibration plots ----------------------------------------------------------
  function drawCalibration() {
    const c = REPORT.calibration;
    if (!c) return;
    let g = context('plot-views');
    if (g) {
      const views = c.views, box = [50, 24, 355, 196];
      const top = Math.max(0.1, ...views.map((v) => v.rms_px)) * 1.1;
      axes(g, box, [0, views.length], [0, top], 'board view', 'reprojection RMS (px)', (v) => v.toFixed(0), (v) => v.toFixed(2));
      g.fillText('reprojection error per board view (red: dropped)', 225, 14);
      views.forEach((v, k) => {
        g.fillStyle = v.used ? '#248' : '#c00';
        const bh = Math.max(0, v.rms_px) / top * box[3], bw = box[2] / views.length;
        g.fillRect(box[0] + k * bw + 1, box[1] + box[3] - bh, Math.max(1, bw - 2), bh);
      });
    }
    g = context('plot-dots');
    if (g) {
      const dots = c.monitor.dots.filter((d) => d.monitor_px.length === 2), box = [50, 24, 300, 196];
      if (!dots.length) return;
      const xs = dots.map((d) => d.monitor_px[0]), ys = dots.map((d) => d.monitor_px[1]);
      const x0 = Math.min(...xs), x1 = Math.max(...xs) || 1, y0 = Math.min(...ys), y1 = Math.max(...ys) || 1;
      const top = Math.max(1e-3, ...dots.map((d) => d.residual_mm));
      axes(g, box, [x0, x1], [y1, y0], 'monitor x (px)', 'monitor y (px)', (v) => v.toFixed(0));
      g.fillText(`dots' residuals on the monitor plane (0 .. ${format(top)} mm; x: not found)`, 210, 14);
      dots.forEach((d) => {
        const px = box[0] + (d.monitor_px[0] - x0) / Math.max(1, x1 - x0) * box[2];
        const py = box[1] + (d.monitor_px[1] - y0) / Math.max(1, y1 - y0) * box[3];
        if (d.residual_mm < 0) { g.fillStyle = '#c00'; g.fillText('x', px, py + 4); return; }
        g.fillStyle = ramp(d.residual_mm / top);
        g.beginPath(); g.arc(px, py, 4, 0, 2 * Math.PI); g.fill();
      });
      for (let k = 0; k <= 20; ++k) { g.fillStyle = ramp(k / 20); g.fillRect(box[0] + box[2] + 20, box[1] + box[3] - (k + 1) * box[3] / 21, 14, box[3] / 21 + 1); }
      g.fillStyle = '#000';
      g.textAlign = 'left';
      g.fillText(`${format(top)} mm`, box[0] + box[2] + 12, box[1] - 4);
      g.fillText('0', box[0] + box[2] + 22, box[1] + box[3] + 12);
    }
  }

  // --- section 1: the live views -------------------------------------------------------------
  const SG_SHADER = `
    precision highp float;
    precision highp sampler2D;
    uniform sampler2D lobes;       // per lobe texel: its record, padded to ceil(stride / 4) RGBA texels
    uniform ivec2 grid;            // lobe texels (cols, rows)
    uniform vec2 sampleSize;       // metres
    uniform vec3 eye;
    uniform mat4 cameraWorld, projectionInverse;
    uniform float backgroundDistance, checkerSize, exposure;
    uniform int maskOnly;          // 1: white where the sample is seen, black elsewhere
    in vec2 ndc;
    out vec4 colour;
    const float PI = 3.141592653589793;
    // Number k of the record starting at float base (records are padded to whole RGBA texels).
    float fetch(int base, int k) {
      int f = base + k, t = f / 4, width = textureSize(lobes, 0).x;
      vec4 v = texelFetch(lobes, ivec2(t % width, t / width), 0);
      int c = f % 4;
      return c == 0 ? v.x : c == 1 ? v.y : c == 2 ? v.z : v.w;
    }
    // svbtdf render's checkerboard: squares of 0.9 and 0.1, a tile centred behind the sample.
    float checker(vec3 origin, vec3 d) {
      if (d.z >= -1e-6) return 0.0;
      float t = (-backgroundDistance - origin.z) / d.z;
      vec3 p = origin + t * d;
      int ix = int(floor((p.x + checkerSize) / checkerSize)), iy = int(floor((checkerSize - p.y) / checkerSize));
      return ((ix + iy) % 2 + 2) % 2 == 0 ? 0.9 : 0.1;
    }
    float srgb(float x) { x = clamp(x, 0.0, 1.0); return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055; }
    vec2 sequence(int k) { return fract(vec2(0.5) + float(k) * vec2(0.7548776662466927, 0.5698402909980532)); }
    void main() {
      vec4 far = projectionInverse * vec4(ndc, 1.0, 1.0);
      vec3 dir = normalize((cameraWorld * vec4(far.xyz / far.w, 0.0)).xyz);
      float t = -eye.z / dir.z;
      vec3 p = eye + t * dir;
      bool hit = dir.z < 0.0 && abs(p.x) <= 0.5 * sampleSize.x && abs(p.y) <= 0.5 * sampleSize.y;
      if (maskOnly == 1) { colour = vec4(vec3(hit ? 1.0 : 0.0), 1.0); return; }
      vec3 radiance;
      if (!hit) {
        radiance = vec3(checker(eye, dir));
      } else {
        int col = clamp(int((p.x + 0.5 * sampleSize.x) / sampleSize.x * float(grid.x)), 0, grid.x - 1);
        int row = clamp(int((0.5 * sampleSize.y - p.y) / sampleSize.y * float(grid.y)), 0, grid.y - 1);
        int perView = ${LOBES ? LOBES.per_view : 11};
        int base = (row * grid.x + col) * ${LOBES ? Math.ceil(LOBES.stride / 4) * 4 : 60};
        vec3 o = -dir;
        // Blend the five views' lobes: head-on, and 30 degrees toward +x, +y, -x, -y.
        float s = 0.5;
        float w[5];
        w[1] = max(o.x, 0.0) / s; w[2] = max(o.y, 0.0) / s; w[3] = max(-o.x, 0.0) / s; w[4] = max(-o.y, 0.0) / s;
        float sum = w[1] + w[2] + w[3] + w[4];
        if (sum > 1.0) { for (int v = 1; v < 5; ++v) w[v] /= sum; sum = 1.0; }
        w[0] = 1.0 - sum;
        vec3 shift = vec3(0.0), major = vec3(0.0), energy = vec3(0.0);
        vec2 sharpness = vec2(0.0);
        vec3 major0 = vec3(fetch(base, 3), fetch(base, 4), fetch(base, 5));
        for (int v = 0; v < 5; ++v) {
          int k = v * perView;
          shift += w[v] * vec3(fetch(base, k), fetch(base, k + 1), fetch(base, k + 2));
          vec3 m = vec3(fetch(base, k + 3), fetch(base, k + 4), fetch(base, k + 5));
          major += w[v] * (dot(m, major0) < 0.0 ? -m : m);  // an axis: m and -m are the same
          sharpness += w[v] * vec2(fetch(base, k + 6), fetch(base, k + 7));
          energy += w[v] * vec3(fetch(base, k + 8), fetch(base, k + 9), fetch(base, k + 10));
        }
        int after = 5 * perView;
        vec3 rhoD = vec3(fetch(base, after), fetch(base, after + 1), fetch(base, after + 2));
        vec3 axis = normalize(-o + shift);
        major = major - dot(major, axis) * axis;
        major = length(major) > 1e-6 ? normalize(major) : normalize(cross(axis, abs(axis.x) < 0.9 ? vec3(1, 0, 0) : vec3(0, 1, 0)));
        vec3 minor = cross(axis, major);
        vec2 spread = 1.0 / sqrt(max(sharpness, vec2(1e-3)));
        // The anisotropic lobe integrated against the background: 48 draws of a Gaussian across
        // its axis (the spherical Gaussian's small-angle form), weighted by the lobe's energy.
        float sum_l = 0.0;
        const int N = 48;
        for (int k = 0; k < N; ++k) {
          vec2 u = sequence(k);
          float r = sqrt(-2.0 * log(max(1.0 - u.x, 1e-6))), phi = 2.0 * PI * u.y;
          sum_l += checker(p, normalize(axis + r * cos(phi) * spread.x * major + r * sin(phi) * spread.y * minor));
        }
        // The diffuse part: rho_d times the cosine-weighted background below.
        float diffuse = 0.0;
        for (int k = 0; k < 16; ++k) {
          vec2 u = sequence(k + 100);
          float r = sqrt(u.x), phi = 2.0 * PI * u.y;
          diffuse += checker(p, vec3(r * cos(phi), r * sin(phi), -sqrt(max(0.0, 1.0 - u.x))));
        }
        radiance = energy * sum_l / float(N) + rhoD * PI * diffuse / 16.0;
      }
      radiance *= exposure;
      colour = vec4(srgb(radiance.r), srgb(radiance.g), srgb(radiance.b), 1.0);
    }`;

  function sgMaterial() {
    const data = float32(LOBES.data);
    const perTexel = Math.ceil(LOBES.stride / 4), count = LOBES.cols * LOBES.rows * perTexel;
    const width = Math.min(4096, count), height = Math.ceil(count / width);
    const packed = new Float32Array(width * height * 4);
    for (let t = 0; t < LOBES.cols * LOBES.rows; ++t) {
      packed.set(data.subarray(t * LOBES.stride, (t + 1) * LOBES.stride), t * perTexel * 4);
    }
    const texture = new THREE.DataTexture(packed, width, height, THREE.RGBAFormat, THREE.FloatType);
    texture.needsUpdate = true;
    return new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      uniforms: {
        lobes: { value: texture }, grid: { value: new THREE.Vector2(LOBES.cols, LOBES.rows) },
        sampleSize: { value: new THREE.Vector2(LOBES.width_m, LOBES.height_m) }, eye: { value: new THREE.Vector3() },
        cameraWorld: { value: new THREE.Matrix4() }, projectionInverse: { value: new THREE.Matrix4() },
        backgroundDistance: { value: 0.03 }, checkerSize: { value: 0.005 }, exposure: { value: 1 }, maskOnly: { value: 0 },
      },
      vertexShader: 'in vec3 position; out vec2 ndc; void main() { ndc = position.xy; gl_Position = vec4(position.xy, 0.0, 1.0); }',
      fragmentShader: SG_SHADER,
      depthTest: false, depthWrite: false,
    });
  }

  // The checkerboard behind the sample for the glTF view: the scene of svbtdf render.
  function checkerPlane(distance, square) {
    const data = new Uint8Array([230, 230, 230, 255, 26, 26, 26, 255, 26, 26, 26, 255, 230, 230, 230, 255]);
    const texture = new THREE.DataTexture(data, 2, 2);
    texture.magFilter = THREE.NearestFilter;
    texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
    const side = 0.4;
    texture.repeat.set(side / (2 * square), side / (2 * square));
    texture.offset.set(-side / (4 * square) % 1, 0);
    texture.colorSpace = THREE.SRGBColorSpace;
    texture.needsUpdate = true;
    const plane = new THREE.Mesh(new THREE.PlaneGeometry(side, side), new THREE.MeshBasicMaterial({ map: texture }));
    plane.position.z = -distance;
    return plane;
  }

  function startViewer() {
    const canvas = document.getElementById('viewer'), status = document.getElementById('viewer-status');
    if (!canvas || !THREE) return;
    const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(1);
    renderer.setSize(512, 512, false);
    const reference = (REPORT.renders || []).find((r) => r.camera && r.scene && r.scene.scene === 'background') || null;
    const background = reference ? reference.scene : { background_distance_m: 0.03, checker_size_m: 0.005 };
    const camera = new THREE.PerspectiveCamera(20, 1, 0.001, 10);
    const width = LOBES.width_m || 0.02, height = LOBES.height_m || 0.02;
    camera.position.set(0, 0, 0.3);
    const controls = new THREE.OrbitControls(camera, canvas);
    controls.target.set(0, 0, 0);
    controls.update();

    // The glTF scene: the export, a checkerboard behind it or a room around it.
    const gltfScene = new THREE.Scene();
    const pmrem = new THREE.PMREMGenerator(renderer);
    const room = pmrem.fromScene(new THREE.RoomEnvironment(), 0.04).texture;
    gltfScene.environment = room;
    const checker = checkerPlane(background.background_distance_m, background.checker_size_m);
    gltfScene.add(checker);
    gltfScene.add(new THREE.DirectionalLight(0xffffff, 1.5));
    if (window.SVBTDF_GLTF) {
      new THREE.GLTFLoader().parse(window.SVBTDF_GLTF, '', (gltf) => { gltfScene.add(gltf.scene); render(); },
        (error) => { state.errors.push('glTF: ' + error); status.textContent = 'The glTF export could not be loaded: ' + error; });
    }
    // The spherical-Gaussian scene: one full-screen triangle pair running the shader.
    const sgScene = new THREE.Scene();
    const sg = sgMaterial();
    sg.uniforms.backgroundDistance.value = background.background_distance_m;
    sg.uniforms.checkerSize.value = background.checker_size_m;
    const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), sg);
    quad.frustumCulled = false;
    sgScene.add(quad);

    function render() {
      camera.updateMatrixWorld();
      if (state.mode === 'sg') {
        sg.uniforms.eye.value.copy(camera.position);
        sg.uniforms.cameraWorld.value.copy(camera.matrixWorld);
        sg.uniforms.projectionInverse.value.copy(camera.projectionMatrixInverse);
        renderer.render(sgScene, camera);
      } else {
        const roomLight = document.getElementById('light').value === 'room';
        gltfScene.background = roomLight ? room : new THREE.Color(0x202020);
        checker.visible = !roomLight;
        renderer.render(gltfScene, camera);
      }
    }
    function setMode(mode) {
      state.mode = mode;
      document.querySelectorAll('.tabs button').forEach((b) => b.classList.toggle('active', b.dataset.mode === mode));
      status.textContent = mode === 'sg'
        ? `The full fitted material: every texel's transmission lobe as an anisotropic spherical Gaussian at five views (${LOBES.cols} x ` +
          `${LOBES.rows} texels), integrated against the checkerboard ${format(1000 * background.background_distance_m)} mm ` +
          'behind; drag to orbit.'
        : 'The glTF export (per-texel GGX lobes, KHR_materials_transmission), as three.js draws it; drag to orbit.';
      render();
    }
    document.querySelectorAll('.tabs button').forEach((b) => b.addEventListener('click', () => setMode(b.dataset.mode)));
    document.getElementById('light').addEventListener('change', render);
    controls.addEventListener('change', render);

    // The live view against svbtdf render of the fitted material at that render's view: relative
    // RMSE of linear RGB over the pixels where the sample is seen.
    const fitted = (REPORT.renders || []).find((r) => r.png_data && !/truth/i.test(r.surface) && !r.parametric && r.scene.scene === 'background');
    function compareWithRender(done) {
      if (!fitted) { done(); return; }
      const image = new Image();
      image.onload = () => {
        const w = fitted.camera.width, h = fitted.camera.height;
        const saved = camera.position.clone();
        const theta = fitted.camera.theta_deg * Math.PI / 180, phi = fitted.camera.phi_deg * Math.PI / 180;
        camera.position.set(Math.sin(theta) * Math.cos(phi), Math.sin(theta) * Math.sin(phi), Math.cos(theta)).multiplyScalar(fitted.camera.distance_m);
        camera.fov = 2 * Math.atan(Math.tan(fitted.camera.fov_deg * Math.PI / 360) * h / w) * 180 / Math.PI;
        camera.aspect = w / h;
        camera.lookAt(0, 0, 0);
        camera.updateProjectionMatrix();
        renderer.setSize(w, h, false);
        const previous = state.mode;
        state.mode = 'sg';
        sg.uniforms.exposure.value = fitted.exposure || 1;
        const read = () => { const gl = renderer.getContext(), px = new Uint8Array(w * h * 4); gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px); return px; };
        sg.uniforms.maskOnly.value = 1; render(); const mask = read();
        sg.uniforms.maskOnly.value = 0; render(); const live = read();
        const scratch = document.createElement('canvas');
        scratch.width = w; scratch.height = h;
        const g = scratch.getContext('2d');
        g.drawImage(image, 0, 0);
        const truth = g.getImageData(0, 0, w, h).data;
        const linear = (v) => { v /= 255; return v <= 0.04045 ? v / 12.92 : Math.pow((v + 0.055) / 1.055, 2.4); };
        let error = 0, norm = 0, pixels = 0, live_sum = 0, render_sum = 0;
        for (let y = 0; y < h; ++y) {
          for (let x = 0; x < w; ++x) {
            const gl = ((h - 1 - y) * w + x) * 4, im = (y * w + x) * 4;  // readPixels rows run bottom-up
            if (mask[gl] < 128) continue;
            ++pixels;
            for (let c = 0; c < 3; ++c) { const a = linear(live[gl + c]), b = linear(truth[im + c]); error += (a - b) * (a - b); norm += b * b; live_sum += a; render_sum += b; }
          }
        }
        const rmse = norm > 0 ? Math.sqrt(error / norm) : NaN;
        state.sgDifference = {
          relative_rmse: rmse, pixels, mean_ratio: live_sum / render_sum, view: [fitted.camera.theta_deg, fitted.camera.phi_deg], against: fitted.shown_png,
          text: `Against svbtdf render of the fitted material at (${format(fitted.camera.theta_deg)}, ${format(fitted.camera.phi_deg)}) ` +
                `degrees: relative RMSE ${(100 * rmse).toPrecision(3)}% over the ${pixels} pixels of the sample (mean brightness ` +
                `${(live_sum / render_sum).toPrecision(3)} times the render's; the render's own Monte Carlo noise, ` +
                `${fitted.samples_per_pixel} samples per pixel, is part of the figure).`,
        };
        document.getElementById('sg-difference') && (document.getElementById('sg-difference').textContent = state.sgDifference.text);
        renderer.setSize(512, 512, false);
        camera.aspect = 1;
        camera.fov = 20;
        camera.position.copy(saved);
        camera.lookAt(0, 0, 0);
        camera.updateProjectionMatrix();
        sg.uniforms.exposure.value = 1;
        state.mode = previous;
        done();
      };
      image.onerror = () => { state.errors.push('the render to compare with could not be decoded'); done(); };
      image.src = fitted.png_data;
    }
    compareWithRender(() => { setMode(window.SVBTDF_GLTF ? 'gltf' : 'sg'); state.ready = true; });
    state.setMode = setMode;
  }

  window.addEventListener('error', (event) => state.errors.push(String(event.message)));
  try {
    wireMaps();
    drawCalibration();
    if (TEXELS) inspect(TEXELS.x[Math.floor(TEXELS.cols / 2)], TEXELS.y[Math.floor(TEXELS.rows / 2)]);
    if (LOBES && THREE) startViewer(); else state.ready = true;
  } catch (error) {
    state.errors.push(String(error && error.stack || error));
    state.ready = true;
    throw error;
  }
})();
