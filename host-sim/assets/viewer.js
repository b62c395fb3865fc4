// viewer.html's own code (inlined by host-sim/src/render/viewer.rs after
// three.js and the run's data, RUN). Builds the scene, plays the frames, and
// reports in the page title for the browser test: "ok <frames> frames" once
// the first frame is drawn, "error: ..." when it cannot be.
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const view = $('view');
  function fail(message) {
    document.title = 'error: ' + message;
    view.textContent = message;
  }
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true });
  } catch (e) {
    fail('WebGL is not available here (' + e.message + '); animation.html needs none');
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(view.clientWidth, view.clientHeight);
  view.appendChild(renderer.domElement);

  // World frame: z up, as in the scenario. Units: RUN.unit.
  const side = RUN.side;
  const centre = new THREE.Vector3(...RUN.centre);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f6f9);
  const camera = new THREE.PerspectiveCamera(40, view.clientWidth / view.clientHeight, side / 200, side * 100);
  camera.up.set(0, 0, 1);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  function home() {
    camera.position.set(-0.7, -1.7, 0.9).normalize().multiplyScalar(2.1 * side).add(centre);
    controls.target.copy(centre);
    controls.update();
  }
  home();

  const sky = new THREE.HemisphereLight(0xffffff, 0x707888, 2.2);
  sky.position.set(0, 0, 1);
  scene.add(sky);
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(0.4, -0.8, 1).multiplyScalar(side).add(centre);
  sun.target.position.copy(centre);
  scene.add(sun, sun.target);

  // A grid just under the lowest point of the motion, its squares RUN.grid
  // wide; the world frame at the origin.
  const cells = Math.ceil(side / RUN.grid);
  const grid = new THREE.GridHelper(cells * RUN.grid, cells, 0x8a929e, 0xcfd4db);
  grid.rotation.x = Math.PI / 2;
  grid.position.set(
    Math.round(centre.x / RUN.grid) * RUN.grid,
    Math.round(centre.y / RUN.grid) * RUN.grid,
    RUN.floor - 0.01 * side,
  );
  scene.add(grid);
  function arrows(length, width) {
    const group = new THREE.Group();
    const list = [0xd03020, 0x20a040, 0x2050d0].map((color) => {
      const a = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), length, color, 0.25 * length, width);
      group.add(a);
      return a;
    });
    return { group, list };
  }
  function orient(frame, origin, axes, offset) {
    frame.group.position.copy(origin);
    frame.list.forEach((a, i) => a.setDirection(new THREE.Vector3(axes[offset + 3 * i], axes[offset + 3 * i + 1], axes[offset + 3 * i + 2])));
  }
  const world = arrows(0.12 * side, 0.05 * side);
  orient(world, new THREE.Vector3(), [1, 0, 0, 0, 1, 0, 0, 0, 1], 0);
  scene.add(world.group);

  // Obstacles: each surface a (lat + 1) x lon grid of points, pole to pole.
  const colours = [0x7a8ca0, 0xb08850, 0x6a9a78, 0x9a7aa8, 0xa07060, 0x5f9aa8];
  const legend = $('legend');
  function legendRow(colour, text) {
    const row = document.createElement('div');
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = colour;
    row.append(swatch, text);
    legend.append(row);
  }
  // A convex hull instead: its face triangles, flat shaded, and each face's outline.
  RUN.obstacles.forEach((o, i) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(o.triangles || o.xyz, 3));
    if (!o.triangles) {
      const index = [];
      for (let a = 0; a < o.lat; a++) {
        for (let b = 0; b < o.lon; b++) {
          const p = a * o.lon + b, q = a * o.lon + ((b + 1) % o.lon);
          index.push(p, p + o.lon, q, q, p + o.lon, q + o.lon);
        }
      }
      geometry.setIndex(index);
    }
    geometry.computeVertexNormals();
    const colour = colours[i % colours.length];
    (o.outlines || []).forEach((loop) => {
      const edge = new THREE.BufferGeometry();
      edge.setAttribute('position', new THREE.Float32BufferAttribute(loop, 3));
      scene.add(new THREE.Line(edge, new THREE.LineBasicMaterial({ color: colour })));
    });
    geometry.computeBoundingSphere();
    // See-through; the more so for walls and floors larger than the scene.
    const opacity = geometry.boundingSphere.radius > side ? 0.22 : 0.45;
    const material = new THREE.MeshLambertMaterial({
      color: colour, transparent: true, opacity, side: THREE.DoubleSide, depthWrite: false,
    });
    scene.add(new THREE.Mesh(geometry, material));
    legendRow('#' + colour.toString(16).padStart(6, '0'), o.name);
  });

  // The end-effector path and the waypoints; the target's frame if it has an orientation.
  const path = new THREE.BufferGeometry();
  path.setAttribute('position', new THREE.Float32BufferAttribute(RUN.path, 3));
  scene.add(new THREE.Line(path, new THREE.LineBasicMaterial({ color: 0x202020 })));
  const r = RUN.radius;
  RUN.waypoints.forEach((w, i) => {
    const p = new THREE.Vector3(...w.position);
    const dot = new THREE.Mesh(new THREE.SphereGeometry(1.2 * r, 16, 12), new THREE.MeshLambertMaterial({ color: 0x149640 }));
    dot.position.copy(p);
    scene.add(dot);
    if (w.axes) {
      const target = arrows(0.1 * side, 0.04 * side);
      orient(target, p, w.axes, 0);
      scene.add(target.group);
    }
    if (i === RUN.waypoints.length - 1) legendRow('#149640', w.axes ? 'target and its frame (x red, y green, z blue)' : 'target');
  });
  legendRow('#202020', 'end-effector path');
  // The escapes: each stretch of the path in its kind's colour, a dot where it started.
  const escapeNames = { detour: 'detour round an obstacle', walk: 'walk from a dead end', return: 'return to the best configuration' };
  const shownKinds = new Set();
  RUN.escapes.forEach((e) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(e.path, 3));
    const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: e.colour }));
    line.renderOrder = 1; // after the black path it lies on, so it wins where they coincide
    scene.add(line);
    if (e.kind !== 'return') {
      const dot = new THREE.Mesh(new THREE.SphereGeometry(0.8 * RUN.radius, 12, 8), new THREE.MeshLambertMaterial({ color: e.colour }));
      dot.position.set(e.path[0], e.path[1], e.path[2]);
      scene.add(dot);
    }
    if (!shownKinds.has(e.kind)) {
      shownKinds.add(e.kind);
      legendRow(e.colour, escapeNames[e.kind] + (e.kind === 'return' ? '' : ' (dot: where it started)'));
    }
  });
  const escapeColours = {};
  RUN.escapes.forEach((e) => { escapeColours[e.kind] = e.colour; });
  legendRow('#d05a28', 'links; their end-effector frame');
  legendRow('#4f86d6', 'link capsules (checkbox above): ' + (RUN.self_collision
    ? 'the closest checked pair red' : 'self-collision is off in this scenario'));
  if (RUN.collision_capsules) legendRow('#e07800', 'URDF collision capsules (fitted to the collision geometry of each body; enclosed by the link capsules, except those of the base, which nothing checks)');
  legendRow('#8a929e', 'grid: ' + RUN.grid + ' ' + RUN.unit + ' squares; world frame at the origin');

  // The arm: links as cylinders between frame origins, joints as spheres.
  const J = RUN.joints;
  const linkGeometry = new THREE.CylinderGeometry(r, r, 1, 16);
  const linkMaterial = new THREE.MeshLambertMaterial({ color: 0xd05a28 });
  const jointGeometry = new THREE.SphereGeometry(1.3 * r, 16, 12);
  const jointMaterial = new THREE.MeshLambertMaterial({ color: 0x3a3f48 });
  const links = [], joints = [];
  for (let i = 0; i < J; i++) {
    const joint = new THREE.Mesh(jointGeometry, jointMaterial);
    scene.add(joint);
    joints.push(joint);
    if (i + 1 < J) {
      const link = new THREE.Mesh(linkGeometry, linkMaterial);
      scene.add(link);
      links.push(link);
    }
  }
  // The link capsules: link i is a see-through tube of radius
  // RUN.capsules[i] with a ball at each end, round its segment: per frame
  // RUN.link_segments (six numbers a link) when given, else the chord from
  // origin i to origin i + 1.
  // Hidden until the checkbox (or `c`, or #capsules in the URL) shows them.
  const capsules = new THREE.Group();
  const capsuleMaterial = new THREE.MeshLambertMaterial({
    color: 0x4f86d6, transparent: true, opacity: 0.3, depthWrite: false,
  });
  const closeMaterial = new THREE.MeshLambertMaterial({
    color: 0xd02020, transparent: true, opacity: 0.45, depthWrite: false,
  });
  const tubeGeometry = new THREE.CylinderGeometry(1, 1, 1, 20, 1, true);
  const capGeometry = new THREE.SphereGeometry(1, 20, 12);
  const tubes = [];
  for (let i = 0; i + 1 < J && i < RUN.capsules.length; i++) {
    const radius = RUN.capsules[i];
    const parts = [new THREE.Mesh(tubeGeometry, capsuleMaterial),
      new THREE.Mesh(capGeometry, capsuleMaterial), new THREE.Mesh(capGeometry, capsuleMaterial)];
    parts.forEach((m) => capsules.add(m));
    tubes.push({ radius, parts });
  }
  // A URDF robot's fitted collision capsules (RUN.collision_capsules, per
  // frame, each [ax, ay, az, bx, by, bz, r]), orange, with the link capsules.
  const fitted = [];
  const fittedMaterial = new THREE.MeshLambertMaterial({
    color: 0xe07800, transparent: true, opacity: 0.45, depthWrite: false,
  });
  (RUN.collision_capsules ? RUN.collision_capsules[0] : []).forEach(() => {
    const parts = [new THREE.Mesh(tubeGeometry, fittedMaterial),
      new THREE.Mesh(capGeometry, fittedMaterial), new THREE.Mesh(capGeometry, fittedMaterial)];
    parts.forEach((m) => capsules.add(m));
    fitted.push(parts);
  });
  // A capsule's tube and end balls from a to b (THREE vectors), radius.
  function placeCapsule([tube, capA, capB], from, to, radius) {
    d.subVectors(to, from);
    const length = d.length();
    tube.visible = length > 1e-6 * side;
    if (tube.visible) {
      tube.position.addVectors(from, to).multiplyScalar(0.5);
      tube.quaternion.setFromUnitVectors(up, d.divideScalar(length));
      tube.scale.set(radius, length, radius);
    }
    capA.position.copy(from);
    capB.position.copy(to);
    capA.scale.setScalar(radius);
    capB.scale.setScalar(radius);
  }
  capsules.visible = false;
  scene.add(capsules);
  const capsuleBox = $('capsules');
  function showCapsules(on) {
    capsules.visible = on;
    document.body.dataset.capsules = on ? 'shown' : 'hidden';
  }
  capsuleBox.checked = false;
  capsuleBox.onchange = () => showCapsules(capsuleBox.checked);
  showCapsules(false);
  const tool = arrows(0.07 * side, 0.03 * side);
  scene.add(tool.group);
  const up = new THREE.Vector3(0, 1, 0), a = new THREE.Vector3(), b = new THREE.Vector3(), d = new THREE.Vector3();
  function pose(f) {
    const o = RUN.origins, base = 3 * J * f;
    for (let i = 0; i < J; i++) joints[i].position.set(o[base + 3 * i], o[base + 3 * i + 1], o[base + 3 * i + 2]);
    for (let i = 0; i + 1 < J; i++) {
      a.copy(joints[i].position);
      b.copy(joints[i + 1].position);
      d.subVectors(b, a);
      const length = d.length(), link = links[i];
      link.visible = length > 1e-6 * side;
      if (!link.visible) continue;
      link.position.addVectors(a, b).multiplyScalar(0.5);
      link.quaternion.setFromUnitVectors(up, d.divideScalar(length));
      link.scale.set(1, length, 1);
    }
    const close = RUN.closest_links[f];
    const segments = RUN.link_segments, stride = 6 * (J - 1);
    tubes.forEach((t, i) => {
      if (segments) {
        const s = stride * f + 6 * i;
        a.set(segments[s], segments[s + 1], segments[s + 2]);
        b.set(segments[s + 3], segments[s + 4], segments[s + 5]);
      } else {
        a.copy(joints[i].position);
        b.copy(joints[i + 1].position);
      }
      placeCapsule(t.parts, a, b, t.radius);
      const red = close !== null && (close[0] === i + 1 || close[1] === i + 1);
      t.parts.forEach((m) => { m.material = red ? closeMaterial : capsuleMaterial; });
    });
    fitted.forEach((parts, i) => {
      const c = RUN.collision_capsules[f][i];
      a.set(c[0], c[1], c[2]);
      b.set(c[3], c[4], c[5]);
      placeCapsule(parts, a, b, c[6]);
    });
    orient(tool, joints[J - 1].position, RUN.end_axes, 9 * f);
  }

  // What the step shows beside the scene.
  const fields = [
    ['step', (f) => RUN.step[f] + ' of ' + RUN.steps],
    ['plan time [s]', (f) => fmt(RUN.time[f], 3)],
    ['V [' + RUN.unit + '²]', (f) => fmt(RUN.v[f], 4)],
    ['position error [' + RUN.unit + ']', (f) => fmt(RUN.position_error[f], 4)],
    ['orientation error', (f) => fmt(RUN.orientation_error[f], 4)],
    ['clearance C − 1', (f) => fmt(RUN.clearance[f], 4)],
  ];
  if (RUN.closest_links.some((p) => p !== null)) {
    fields.push(['closest links [' + RUN.unit + ']', (f) => {
      const p = RUN.closest_links[f];
      return p === null ? '—' : p[0] + ' – ' + p[1] + ': ' + fmt(p[2], 4);
    }]);
  }
  // What the drives are asked for: per joint |velocity| / rate limit and
  // |acceleration| / acceleration limit as bars (the bar chart's top is
  // 1.25, the limit a dashed line at 1), the largest of each in the table.
  const drive = RUN.velocity_fraction !== null && RUN.acceleration_fraction !== null;
  const TOP = 1.25;
  // Over the limit by more than the 4-decimal rounding of the data.
  const OVER = 1.001;
  const bars = [];
  const J_DRIVE = RUN.joint_names.length;
  // The joint with the largest |fraction| at frame f (the first, at a tie).
  function largest(list, f) {
    let best = 0;
    for (let j = 1; j < J_DRIVE; j++) {
      if (Math.abs(list[f * J_DRIVE + j]) > Math.abs(list[f * J_DRIVE + best])) best = j;
    }
    return best;
  }
  if (drive) {
    for (let j = 0; j < J_DRIVE; j++) {
      const group = document.createElement('div');
      group.className = 'joint';
      const pair = ['velocity', 'acceleration'].map((kind) => {
        const bar = document.createElement('div');
        bar.className = 'bar ' + kind;
        bar.id = 'drive-' + kind + '-' + (j + 1);
        group.append(bar);
        return bar;
      });
      $('drive-bars').append(group);
      bars.push(pair);
      const label = document.createElement('span');
      label.textContent = j + 1;
      label.title = RUN.joint_names[j];
      $('drive-joints').append(label);
    }
    fields.push(['largest |velocity| / rate limit', (f) => {
      const j = largest(RUN.velocity_fraction, f);
      return fmt(Math.abs(RUN.velocity_fraction[f * J_DRIVE + j]), 3) + ' (' + RUN.joint_names[j] + ')';
    }]);
    fields.push(['largest |acceleration| / its limit', (f) => {
      const j = largest(RUN.acceleration_fraction, f);
      return fmt(Math.abs(RUN.acceleration_fraction[f * J_DRIVE + j]), 3) + ' (' + RUN.joint_names[j] + ')';
    }]);
  } else {
    $('drive-bars').style.display = 'none';
    $('drive-none').textContent = 'velocities and accelerations not recorded in this trajectory (written before they were)';
  }
  function showDrive(f) {
    if (!drive) return;
    const names = { velocity: 'rate limit', acceleration: 'acceleration limit' };
    bars.forEach((pair, j) => {
      [RUN.velocity_fraction, RUN.acceleration_fraction].forEach((list, i) => {
        const x = list[f * J_DRIVE + j], bar = pair[i];
        const kind = i === 0 ? 'velocity' : 'acceleration';
        bar.dataset.value = x;
        bar.style.height = (100 * Math.min(Math.abs(x), TOP) / TOP) + '%';
        bar.classList.toggle('over', Math.abs(x) > OVER);
        bar.title = RUN.joint_names[j] + ': ' + kind + ' ' + fmt(x, 3) + ' of its ' + names[kind];
      });
    });
  }
  function fmt(x, digits) {
    if (x === null || x === undefined) return '—';
    const m = Math.abs(x);
    return m !== 0 && (m < 1e-3 || m >= 1e5) ? x.toExponential(digits - 1) : x.toFixed(digits);
  }
  const values = fields.map(([label]) => {
    const row = $('now').insertRow();
    row.insertCell().textContent = label;
    const value = row.insertCell();
    value.className = 'value';
    return value;
  });
  const seek = $('seek'), play = $('play');
  seek.max = RUN.frames - 1;
  let frame = 0, playing = true, shown = 0;
  function show(f) {
    frame = f;
    pose(f);
    seek.value = f;
    fields.forEach(([, value], i) => { values[i].textContent = value(f); });
    showDrive(f);
    const now = RUN.escape[f];
    $('escape-text').textContent = 'escape: ' + (now === null ? 'none (the law drives)' : now);
    const kind = now === null ? null : now.split(' ')[0];
    $('escape-swatch').style.background = (kind && escapeColours[kind]) || 'transparent';
  }
  function setPlaying(on) {
    playing = on;
    play.textContent = on ? 'pause' : 'play';
  }
  play.onclick = () => setPlaying(!playing);
  seek.oninput = () => { setPlaying(false); show(+seek.value); };
  window.addEventListener('keydown', (e) => {
    if (e.key === ' ') { setPlaying(!playing); e.preventDefault(); }
    if (e.key === 'ArrowRight') { setPlaying(false); show(Math.min(frame + 1, RUN.frames - 1)); }
    if (e.key === 'ArrowLeft') { setPlaying(false); show(Math.max(frame - 1, 0)); }
    if (e.key === 'h') home();
    if (e.key === 'c') capsuleBox.click();
  });
  // Centre the scene in the space right of the panel on wide windows.
  function fit() {
    const w = view.clientWidth, h = view.clientHeight;
    const shift = w > 800 ? ($('hud').offsetWidth + 12) / 2 : 0;
    camera.aspect = w / h;
    camera.setViewOffset(w, h, -shift, 0, w, h);
    camera.updateProjectionMatrix();
    renderer.setSize(w, h);
  }
  fit();
  window.addEventListener('resize', fit);
  function loop(now) {
    requestAnimationFrame(loop);
    // About 30 frames a second; a second's pause on the last frame.
    if (playing && now - shown > (frame === RUN.frames - 1 ? 1000 : 33)) {
      shown = now;
      show((frame + 1) % RUN.frames);
    }
    controls.update();
    renderer.render(scene, camera);
  }
  // viewer.html#capsules opens with the capsules shown, through the
  // checkbox as a click would.
  if (RUN.capsules_shown || /capsules/.test(window.location.hash)) capsuleBox.click();
  // viewer.html#frame=N opens paused at frame N.
  const asked = /frame=(\d+)/.exec(window.location.hash);
  if (asked) setPlaying(false);
  show(asked ? Math.min(+asked[1], RUN.frames - 1) : 0);
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  if (!gl || gl.isContextLost()) {
    fail('the WebGL context was lost');
    return;
  }
  document.title = 'ok ' + RUN.frames + ' frames';
  requestAnimationFrame(loop);
})();
