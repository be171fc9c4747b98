// The viewer's page and script: three.js draws the scene from /scene.json and moves
// its bodies with the binary pose frames of /ws (see pose_feed.hpp for their layout).
#include "afhub/viewer/view_server.hpp"

namespace afhub::viewer {

const std::string& page_html() {
  static const std::string html = R"(<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>afhub view</title>
<style>
body { margin: 0; overflow: hidden; background: #20262e; font: 13px sans-serif; color: #ddd; }
#info { position: absolute; top: 6px; left: 8px; background: rgba(0,0,0,0.4); padding: 4px 8px; }
#info a { color: #9cf; margin-right: 6px; }
#inspect { position: absolute; bottom: 6px; left: 8px; background: rgba(0,0,0,0.5);
           padding: 4px 8px; white-space: pre; font-family: monospace; }
#drive { position: absolute; top: 36px; right: 8px; background: rgba(0,0,0,0.5); padding: 4px 8px; }
#drive label { display: block; }
#drive:empty, #inspect:empty { display: none; }
</style></head>
<body><div id="info">afhub view <span id="status">connecting</span>
<span id="cameras"></span></div><div id="inspect"></div><div id="drive"></div>
<script src="/three/three.min.js"></script>
<script src="/three/OrbitControls.js"></script>
<script src="/three/STLLoader.js"></script>
<script src="/three/OBJLoader.js"></script>
<script src="/viewer.js"></script>
</body></html>
)";
  return html;
}

const std::string& page_script() {
  static const std::string script = R"JS('use strict';
// afhub view: the scene from /scene.json, poses from /ws (binary frames).
const params = new URLSearchParams(location.search);
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
let sceneInfo = null;
let generation = -1;
let loading = false;
window.afhub = {frames: 0, bodiesInFrame: 0, catalogBodies: 0, meshesLoaded: 0, sceneBodies: 0};

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

function meshGeometry(index, body, material, group) {
  const format = body.format.toLowerCase();
  const url = '/mesh/' + index;
  const done = () => { window.afhub.meshesLoaded++; };
  if (format === '.stl') {
    new THREE.STLLoader().load(url, (geometry) => {
      geometry.computeVertexNormals();
      group.add(new THREE.Mesh(geometry, material));
      done();
    });
  } else if (format === '.obj') {
    new THREE.OBJLoader().load(url, (object) => {
      object.traverse((child) => { if (child.isMesh) child.material = material; });
      group.add(object);
      done();
    });
  } else {
    // A format the page cannot read: a small marker where the body is.
    group.add(new THREE.Mesh(new THREE.SphereBufferGeometry(0.02, 8, 6), material));
  }
}

function chooseCamera(cameras) {
  const wanted = params.get('camera');
  let chosen = cameras[0];
  if (wanted) {
    const found = cameras.find((c) => c.name === wanted || c.name.endsWith('/' + wanted));
    if (found) chosen = found;
  }
  if (chosen) {
    camera.position.copy(vec(chosen.position));
    camera.up.copy(vec(chosen.up));
    controls.target.copy(vec(chosen.position).add(vec(chosen.direction)));
  } else {
    camera.position.set(2.0, 1.6, 1.4);
    controls.target.set(0, 0, 0.5);
  }
  controls.update();
  document.getElementById('cameras').innerHTML = cameras.map((c) =>
      '<a href="/?camera=' + encodeURIComponent(c.name) + '">' + c.name + '</a>').join('');
}

async function loadScene() {
  loading = true;
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
    if (body.mesh) meshGeometry(index, body, material, group);
    for (const shape of body.shapes) group.add(shapeMesh(shape, material));
    group.scale.setScalar(body.scale);
    group.position.copy(vec(body.position));
    const q = body.orientation;
    group.quaternion.set(q[0], q[1], q[2], q[3]);
    group.userData = {index: index, channel: body.channel};
    // Drawn where it was loaded until its first pose comes.
    root.add(group);
    return group;
  });
  sceneInfo = info;
  generation = info.generation >>> 0;
  window.afhub.sceneBodies = bodies.length;
  chooseCamera(info.cameras);
  loading = false;
}

function applyFrame(buffer) {
  const view = new DataView(buffer);
  if (view.getUint32(0, true) !== 0x31564641) return;
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
  // A live body the catalog no longer lists is gone.
  bodies.forEach((body, i) => { if (sceneInfo.bodies[i].publishes && !seen[i]) body.visible = false; });
  document.getElementById('status').textContent =
      (paused ? 'paused' : 'running') + ' t=' + time.toFixed(2) + ' s, ' + count + ' live bodies';
  showInspected();
}

let inspected = null;
function showInspected() {
  if (!inspected) return;
  const p = inspected.position, q = inspected.quaternion;
  document.getElementById('inspect').textContent = inspected.userData.channel +
      '\nposition ' + [p.x, p.y, p.z].map((v) => v.toFixed(3)).join(' ') +
      '\norientation ' + [q.x, q.y, q.z, q.w].map((v) => v.toFixed(3)).join(' ');
}

const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('click', (event) => {
  const pointer = new THREE.Vector2(event.clientX / innerWidth * 2 - 1,
                                    -(event.clientY / innerHeight) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  const hits = raycaster.intersectObjects(bodies, true);
  inspected = null;
  for (const hit of hits) {
    let o = hit.object;
    while (o && o.userData.channel === undefined) o = o.parent;
    if (o) { inspected = o; break; }
  }
  document.getElementById('inspect').textContent = '';
  showInspected();
  showDrive();
});

// Joint sliders (only when `afhub view --allow-commands`): a moved slider sends a
// position command, repeated while the panel is open (the physics' watchdog
// releases the joints half a second after the last).
let commandsAllowed = false;
let jointNames = {};
let driving = null;  // {channel, joint, value}
fetch('/options.json').then((r) => r.json()).then((o) => { commandsAllowed = o.commands; });
function sendDrive() {
  if (!driving) return;
  fetch('/command?body=' + encodeURIComponent(driving.channel) + '&joint=' + driving.joint +
        '&value=' + driving.value, {method: 'POST'});
}
setInterval(sendDrive, 200);
async function showDrive() {
  const panel = document.getElementById('drive');
  panel.innerHTML = '';
  driving = null;
  if (!commandsAllowed || !inspected) return;
  jointNames = await (await fetch('/joints.json', {cache: 'no-store'})).json();
  const channel = inspected.userData.channel;
  (jointNames[channel] || []).forEach((name, joint) => {
    const label = document.createElement('label');
    label.textContent = name + ' ';
    const slider = document.createElement('input');
    Object.assign(slider, {type: 'range', min: -3.14, max: 3.14, step: 0.01, value: 0});
    slider.addEventListener('input', () => {
      driving = {channel: channel, joint: joint, value: slider.value};
      sendDrive();
    });
    label.appendChild(slider);
    panel.appendChild(label);
  });
}

function connect() {
  const socket = new WebSocket((location.protocol === 'https:' ? 'wss://' : 'ws://') +
                               location.host + '/ws');
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { document.getElementById('status').textContent = 'connected'; };
  socket.onmessage = (event) => applyFrame(event.data);
  socket.onclose = () => {
    document.getElementById('status').textContent = 'disconnected; retrying';
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
)JS";
  return script;
}

}  // namespace afhub::viewer
