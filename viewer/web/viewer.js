'use strict';
// afhub view: the scene from /scene.json, poses from /ws (binary frames).
const params = new URLSearchParams(location.search);
const token = params.get('token');  // commands' token (`afhub view --allow-commands`)
const renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(innerWidth, innerHeight);
document.body.appendChild(renderer.domElement);
const world = new THREE.Scene();
world.background = new THREE.Color(0x20262e);
const camera = new THREE.PerspectiveCamera(45, innerWidth / innerHeight, 0.01, 500);
camera.up.set(0, 0, 1);  // AMBF worlds are z-up
const controls = new THREE.OrbitControls(camera, renderer.domElement);
let root = null;          // everything of the current scene
let bodies = [];          // per scene body: its Object3D
let softBodies = [];      // per scene soft body: its Mesh (positions from the frames), or null
let sceneInfo = null;
let generation = -1;
let loading = false;
window.afhub = {frames: 0, bodiesInFrame: 0, catalogBodies: 0, meshesLoaded: 0, sceneBodies: 0,
                softBodies: 0, softCentres: []};

function vec(a) { return new THREE.Vector3(a[0], a[1], a[2]); }

function shapeMesh(shape, material) {
  const s = shape.size;
  let geometry;
  if (shape.kind === 'box') geometry = new THREE.BoxBufferGeometry(s[0], s[1], s[2]);
  else if (shape.kind === 'sphere') geometry = new THREE.SphereBufferGeometry(s[0], 24, 16);
  else if (shape.kind === 'cone') geometry = new THREE.ConeBufferGeometry(s[0], s[1], 24);
  else if (shape.kind === 'plane') geometry = new THREE.PlaneBufferGeometry(20, 20);
  else geometry = new THREE.CylinderBufferGeometry(s[0], s[0], s[1], 24);  // cylinder, capsule
  const mesh = new THREE.Mesh(geometry, material);
  const holder = new THREE.Group();
  holder.add(mesh);
  if (shape.kind === 'plane') {
    mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), vec(s).normalize());
  } else if (shape.kind !== 'box' && shape.kind !== 'sphere') {
    // three.js builds these along y; ADF names their axis.
    if (shape.axis === 2) mesh.rotation.x = Math.PI / 2;
    else if (shape.axis === 0) mesh.rotation.z = -Math.PI / 2;
  }
  holder.position.copy(vec(shape.position));
  const q = shape.orientation;
  holder.quaternion.set(q[0], q[1], q[2], q[3]);
  return holder;
}

// One of a body's meshes (scene.json's body.meshes[i]), scaled per axis and placed at
// its offset in the body's frame.
function meshGeometry(mesh, material, group) {
  const format = mesh.format.toLowerCase();
  const url = '/mesh/' + mesh.index;
  const holder = new THREE.Group();
  holder.position.copy(vec(mesh.position));
  const q = mesh.orientation;
  holder.quaternion.set(q[0], q[1], q[2], q[3]);
  holder.scale.copy(vec(mesh.scale));
  group.add(holder);
  const done = () => { window.afhub.meshesLoaded++; };
  if (format === '.stl') {
    new THREE.STLLoader().load(url, (geometry) => {
      geometry.computeVertexNormals();
      holder.add(new THREE.Mesh(geometry, material));
      done();
    });
  } else if (format === '.obj') {
    new THREE.OBJLoader().load(url, (object) => {
      object.traverse((child) => { if (child.isMesh) child.material = material; });
      holder.add(object);
      done();
    });
  } else {
    // A format the page cannot read: a small marker where the mesh is (not scaled).
    holder.scale.setScalar(1);
    holder.add(new THREE.Mesh(new THREE.SphereBufferGeometry(0.02, 8, 6), material));
  }
}

// Input devices' paired cameras (`afhub view --input-devices FILE`): {camera: [device]}.
let paired = {};
const pairedLoaded = fetch('/paired.json').then((r) => r.json()).then((p) => { paired = p; });

// A world camera's short name: "afhub/world/cameras/overview" -> "overview".
function shortName(name) { return name.slice(name.lastIndexOf('/') + 1); }

function chooseCamera(cameras) {
  const wanted = params.get('camera');
  let chosen = null;
  const message = document.getElementById('message');
  message.textContent = '';
  if (wanted) {
    chosen = cameras.find((c) => c.name === wanted || shortName(c.name) === wanted) || null;
    if (!chosen)
      message.textContent = 'No camera named "' + wanted + '" in this world; ' +
          (cameras.length ? 'its cameras: ' + cameras.map((c) => shortName(c.name)).join(', ') :
                            'it has no cameras') + '. Showing the default view.';
  } else {
    chosen = cameras[0] || null;
  }
  if (chosen) {
    camera.position.copy(vec(chosen.position));
    camera.up.copy(vec(chosen.up));
    controls.target.copy(vec(chosen.position).add(vec(chosen.direction)));
  } else {
    camera.position.set(2.0, 1.6, 1.4);
    camera.up.set(0, 0, 1);
    controls.target.set(0, 0, 0.5);
  }
  controls.update();
  window.afhub.camera = chosen ? chosen.name : '';
  const list = document.getElementById('cameras');
  list.textContent = '';
  for (const c of cameras) {
    const link = document.createElement('a');
    link.href = '/?camera=' + encodeURIComponent(shortName(c.name)) +
        (token ? '&token=' + encodeURIComponent(token) : '');
    link.textContent = shortName(c.name);
    if (c === chosen) link.className = 'current';
    // AMBF's devices pair a camera by its block key in the world file ("camera1");
    // its name (full or short) is accepted too.
    const devices = [...new Set([c.key, c.name, shortName(c.name)].flatMap((n) => paired[n] || []))];
    if (devices.length) {
      link.className += ' paired';
      link.textContent += ' [paired: ' + devices.join(', ') + ']';
      link.title = 'input devices paired with this camera: ' + devices.join(', ');
    }
    list.appendChild(link);
  }
  // Pairings that name no camera of this world are said, not dropped.
  const named = new Set(cameras.flatMap((c) => [c.key, c.name, shortName(c.name)]));
  const unmatched = Object.keys(paired).filter((name) => !named.has(name));
  if (unmatched.length) {
    const note = document.createElement('span');
    note.className = 'paired';
    note.textContent = unmatched.map((name) => name + ' (paired by ' + paired[name].join(', ') +
        ') is not a camera key or name of this world').join('; ');
    list.appendChild(note);
  }
}

// Loads the scene. One that fails to load (the viewer stopping mid-reply) leaves the
// generation as it was, so that the next frame tries again.
async function loadScene() {
  loading = true;
  try {
    await readScene();
  } catch (error) {
    document.getElementById('status').textContent = 'the scene did not load: ' + error;
  } finally {
    loading = false;
  }
}

async function readScene() {
  jointNames = await (await fetch('/joints.json', {cache: 'no-store'})).json();
  joints = [];
  const response = await fetch('/scene.json', {cache: 'no-store'});
  const info = await response.json();
  if (root) world.remove(root);
  root = new THREE.Group();
  world.add(root);
  root.add(new THREE.AmbientLight(0xffffff, 0.45));
  const lights = info.lights.length ? info.lights :
      [{position: [2, 2, 3], direction: [-2, -2, -3]}];
  for (const l of lights) {
    const light = new THREE.DirectionalLight(0xffffff, 0.7 / Math.sqrt(lights.length));
    light.position.copy(vec(l.position));
    light.target.position.copy(vec(l.position).add(vec(l.direction)));
    root.add(light, light.target);
  }
  const floor = new THREE.GridHelper(10, 40, 0x3a4350, 0x2c343e);
  floor.rotation.x = Math.PI / 2;  // three.js lays it in xz; the world's floor is xy
  root.add(floor);
  bodies = info.bodies.map((body, index) => {
    const group = new THREE.Group();
    const c = body.color;
    const material = new THREE.MeshPhongMaterial({color: new THREE.Color(c[0], c[1], c[2]),
        opacity: c[3], transparent: c[3] < 1});
    for (const mesh of body.meshes) meshGeometry(mesh, material, group);
    for (const shape of body.shapes) group.add(shapeMesh(shape, material));  // in metres
    group.position.copy(vec(body.position));
    const q = body.orientation;
    group.quaternion.set(q[0], q[1], q[2], q[3]);
    group.userData = {index: index, channel: body.channel};
    // Drawn where it was loaded until its first pose comes.
    root.add(group);
    return group;
  });
  // Soft bodies: their faces once from the scene, their node positions in every frame.
  softBodies = info.soft_bodies.map((soft) => {
    if (!soft.faces.length) return null;  // faces not read yet: the next scene has them
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position',
        new THREE.BufferAttribute(new Float32Array(soft.nodes * 3), 3));
    geometry.setIndex(soft.faces);
    const mesh = new THREE.Mesh(geometry, new THREE.MeshPhongMaterial(
        {color: 0xe0803a, side: THREE.DoubleSide}));
    mesh.frustumCulled = false;  // its bounds move with its nodes
    mesh.visible = false;        // until its first nodes come
    mesh.userData = {channel: soft.channel};
    root.add(mesh);
    return mesh;
  });
  window.afhub.softBodies = softBodies.filter((s) => s).length;
  sceneInfo = info;
  generation = info.generation >>> 0;
  window.afhub.sceneBodies = bodies.length;
  await pairedLoaded;
  chooseCamera(info.cameras);
}

function applyFrame(buffer) {
  const view = new DataView(buffer);
  if (view.getUint32(0, true) !== 0x31564641) return;
  // The viewer lost its hub and waits for it: the last scene stays, said to be stale.
  if ((view.getUint32(12, true) & 2) !== 0) {
    window.afhub.hubLost = true;
    document.getElementById('status').textContent =
        'hub lost: waiting for it to come back (the scene shown is the last one seen)';
    return;
  }
  window.afhub.hubLost = false;
  const frameGeneration = view.getUint32(4, true);
  if (frameGeneration !== generation) {
    if (!loading) loadScene();
    return;
  }
  const count = view.getUint32(8, true);
  const paused = (view.getUint32(12, true) & 1) !== 0;
  const time = view.getFloat64(16, true);
  window.afhub.frames++;
  window.afhub.bodiesInFrame = count;
  window.afhub.catalogBodies = view.getUint32(24, true);
  const seen = new Array(bodies.length).fill(false);
  for (let e = 0; e < count; e++) {
    const at = 32 + e * 32;
    const index = view.getUint32(at, true);
    const body = bodies[index];
    if (!body) continue;
    seen[index] = true;
    body.visible = true;
    body.position.set(view.getFloat32(at + 4, true), view.getFloat32(at + 8, true),
                      view.getFloat32(at + 12, true));
    body.quaternion.set(view.getFloat32(at + 16, true), view.getFloat32(at + 20, true),
                        view.getFloat32(at + 24, true), view.getFloat32(at + 28, true));
  }
  // The joint blocks: per body with joints, its joint positions.
  let at = 32 + count * 32;
  const blocks = view.getUint32(28, true);
  for (let k = 0; k < blocks; k++) {
    const index = view.getUint16(at, true), n = view.getUint16(at + 2, true);
    if (!joints[index] || joints[index].length !== n) joints[index] = new Float32Array(n);
    for (let j = 0; j < n; j++) joints[index][j] = view.getFloat32(at + 4 + 4 * j, true);
    at += 4 + 4 * n;
  }
  // The soft-body blocks: per soft body, its node positions.
  const softCount = at + 4 <= view.byteLength ? view.getUint32(at, true) : 0;
  at += 4;
  for (let k = 0; k < softCount; k++) {
    const index = view.getUint32(at, true), n = view.getUint32(at + 4, true);
    at += 8;
    const mesh = softBodies[index];
    if (mesh && mesh.geometry.attributes.position.count === n) {
      const positions = mesh.geometry.attributes.position;
      positions.array.set(new Float32Array(buffer.slice(at, at + 12 * n)));
      positions.needsUpdate = true;
      mesh.geometry.computeVertexNormals();
      mesh.visible = true;
      const centre = [0, 0, 0];
      for (let i = 0; i < 3 * n; i++) centre[i % 3] += positions.array[i] / n;
      window.afhub.softCentres[index] = centre;
    }
    at += 12 * n;
  }
  window.afhub.simTime = time;
  window.afhub.paused = paused;
  // A live body the catalog no longer lists is gone.
  bodies.forEach((body, i) => { if (sceneInfo.bodies[i].publishes && !seen[i]) body.visible = false; });
  document.getElementById('status').textContent =
      (paused ? 'paused' : 'running') + ' t=' + time.toFixed(2) + ' s, ' + count + ' live bodies';
  const pause = document.getElementById('pause');
  if (pause) pause.textContent = paused ? 'resume' : 'pause';
  recordPlot(time);
  showInspected();
}

// Inspect: the clicked body's live pose and joint positions, and a plot of its
// ticked joints over the last seconds of simulation time.
let inspected = null;
let jointNames = {};   // channel -> joint names (from /joints.json)
let joints = [];       // per scene body: its newest joint positions (Float32Array)
const plotColors = ['#ff6b6b', '#6bcB77', '#4d96ff', '#ffd93d', '#c77dff', '#ff9f45', '#2ec4b6'];
const plotSeconds = 5;
let plotHistory = [];  // {t, values} of the inspected body, oldest first
let plotted = [];      // per joint of the inspected body: ticked

function inspectedJoints() { return inspected ? joints[inspected.userData.index] : undefined; }

function showInspected() {
  if (!inspected) return;
  const p = inspected.position, q = inspected.quaternion;
  document.getElementById('pose').textContent = inspected.userData.channel +
      '\nposition ' + [p.x, p.y, p.z].map((v) => v.toFixed(3)).join(' ') +
      '\norientation ' + [q.x, q.y, q.z, q.w].map((v) => v.toFixed(3)).join(' ');
  const values = inspectedJoints();
  document.querySelectorAll('#joints .value').forEach((cell, j) => {
    cell.textContent = values && j < values.length ? values[j].toFixed(4) : '-';
  });
  drawPlot();
}

function recordPlot(time) {
  const values = inspectedJoints();
  if (!values) return;
  const last = plotHistory[plotHistory.length - 1];
  if (last && time < last.t) plotHistory = [];  // the world was reset
  if (last && time === last.t) return;          // paused: nothing new
  plotHistory.push({t: time, values: Array.from(values)});
  while (plotHistory.length && plotHistory[0].t < time - plotSeconds) plotHistory.shift();
}

function drawPlot() {
  const canvas = document.getElementById('plot');
  const g = canvas.getContext('2d');
  g.fillStyle = '#10151b';
  g.fillRect(0, 0, canvas.width, canvas.height);
  if (plotHistory.length < 2) return;
  const end = plotHistory[plotHistory.length - 1].t;
  let low = Infinity, high = -Infinity;
  for (const sample of plotHistory)
    sample.values.forEach((v, j) => { if (plotted[j]) { low = Math.min(low, v); high = Math.max(high, v); } });
  if (low === Infinity) return;
  if (high - low < 0.02) { low -= 0.01; high += 0.01; }  // a still joint: a flat line mid-plot
  const x = (t) => (t - (end - plotSeconds)) / plotSeconds * canvas.width;
  const y = (v) => canvas.height - 12 - (v - low) / (high - low) * (canvas.height - 24);
  g.lineWidth = 2;
  plotted.forEach((on, j) => {
    if (!on) return;
    g.strokeStyle = plotColors[j % plotColors.length];
    g.beginPath();
    plotHistory.forEach((sample, i) => {
      if (i === 0) g.moveTo(x(sample.t), y(sample.values[j]));
      else g.lineTo(x(sample.t), y(sample.values[j]));
    });
    g.stroke();
  });
  g.fillStyle = '#aab';
  g.font = '10px sans-serif';
  g.fillText(high.toFixed(3), 2, 10);
  g.fillText(low.toFixed(3) + '   last ' + plotSeconds + ' s', 2, canvas.height - 2);
}

async function inspect(body) {
  if (body) jointNames = await (await fetch('/joints.json', {cache: 'no-store'})).json();
  inspected = body;
  plotHistory = [];
  const panel = document.getElementById('inspect');
  const list = document.getElementById('joints');
  list.textContent = '';
  panel.hidden = !body;
  if (!body) return;
  const names = jointNames[body.userData.channel] || [];
  plotted = names.map(() => true);
  names.forEach((name, j) => {
    const row = document.createElement('label');
    row.style.display = 'block';
    row.style.color = plotColors[j % plotColors.length];
    const tick = document.createElement('input');
    Object.assign(tick, {type: 'checkbox', checked: true, title: 'plot this joint'});
    tick.addEventListener('change', () => { plotted[j] = tick.checked; });
    const value = document.createElement('span');
    value.className = 'value';
    row.append(tick, name + ' ', value);
    list.appendChild(row);
  });
  showInspected();
}

const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('click', (event) => {
  const pointer = new THREE.Vector2(event.clientX / innerWidth * 2 - 1,
                                    -(event.clientY / innerHeight) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  const hits = raycaster.intersectObjects(bodies, true);
  let found = null;
  for (const hit of hits) {
    let o = hit.object;
    while (o && o.userData.channel === undefined) o = o.parent;
    if (o) { found = o; break; }
  }
  inspect(found).then(showDrive);
});

// Drive (only with `afhub view --allow-commands`; the server refuses otherwise):
// joint sliders for the inspected body, whose moved slider sends a position command,
// repeated while the panel is open (the physics' watchdog releases the joints half
// a second after the last); and the world's pause, step and reset. Each command
// carries the token of the URL the viewer printed (/?token=...), which no other
// site's page can know.
let commandsAllowed = false;
let driving = null;  // {channel, joint, value}
const optionsLoaded = fetch('/options.json').then((r) => r.json()).then((o) => {
  commandsAllowed = o.commands;
  if (commandsAllowed) showWorldButtons();
  if (commandsAllowed && !token) {
    const note = document.createElement('span');
    note.id = 'token-needed';
    note.textContent = 'commands need the token: open the page at the URL `afhub view` ' +
        'printed (/?token=...)';
    document.getElementById('world').appendChild(note);
  }
});
function command(path) {
  return fetch(path, {method: 'POST', headers: {'X-Afhub-Token': token || ''}});
}
function sendDrive() {
  if (!driving) return;
  command('/command?body=' + encodeURIComponent(driving.channel) + '&joint=' + driving.joint +
          '&value=' + driving.value);
}
setInterval(sendDrive, 200);
function showDrive() {
  const panel = document.getElementById('drive');
  panel.textContent = '';
  driving = null;
  if (!commandsAllowed || !inspected) return;
  const channel = inspected.userData.channel;
  const values = inspectedJoints();
  (jointNames[channel] || []).forEach((name, joint) => {
    const label = document.createElement('label');
    label.textContent = name + ' ';
    const slider = document.createElement('input');
    const now = values && joint < values.length ? values[joint] : 0;
    Object.assign(slider, {type: 'range', min: -3.14, max: 3.14, step: 0.01, value: now});
    slider.dataset.joint = joint;
    slider.addEventListener('input', () => {
      driving = {channel: channel, joint: joint, value: slider.value};
      sendDrive();
    });
    label.appendChild(slider);
    panel.appendChild(label);
  });
}
function worldCommand(action) {
  command('/world?action=' + action).then(async (r) => {
    document.getElementById('message').textContent = r.ok ? '' : await r.text();
  });
}
function showWorldButtons() {
  const bar = document.getElementById('world');
  for (const [id, title] of [['pause', 'pause or resume the simulation'],
                             ['step', 'while paused: advance one step'],
                             ['reset', 'put every body back where the model starts it']]) {
    const button = document.createElement('button');
    Object.assign(button, {id: id, textContent: id, title: title});
    button.addEventListener('click', () => {
      worldCommand(id === 'pause' ? (window.afhub.paused ? 'resume' : 'pause') : id);
    });
    bar.appendChild(button);
  }
}

function connect() {
  const socket = new WebSocket((location.protocol === 'https:' ? 'wss://' : 'ws://') +
                               location.host + '/ws');
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { document.getElementById('status').textContent = 'connected'; };
  socket.onmessage = (event) => applyFrame(event.data);
  socket.onclose = () => {
    document.getElementById('status').textContent = 'disconnected; retrying';
    // The viewer may have restarted, counting its scenes from the start: reload the
    // scene with the next frame.
    generation = -1;
    setTimeout(connect, 1000);
  };
}

window.addEventListener('resize', () => {
  camera.aspect = innerWidth / innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(innerWidth, innerHeight);
});

function render() {
  requestAnimationFrame(render);
  controls.update();
  renderer.render(world, camera);
}
loadScene().then(connect);
render();
