// The viewer page's module (plotting/view/view.html; the scene's JSON: plotting/view_html.cpp). Base frame,
// metres, seconds; the page's "up" is the scene's up.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const data = JSON.parse(document.getElementById('scene').textContent);
const $ = (id) => document.getElementById(id);
// JSON has no NaN: non-finite numbers arrive as null.
const floats = (a) => Float32Array.from(a, (x) => (x === null ? NaN : x));
const variants = data.variants.map((v) => ({
  ...v,
  ends: floats(v.ends),
  rigid: v.rigid_ends.length ? floats(v.rigid_ends) : null,
  tool: floats(v.tool),
}));
const capsules = data.capsules;
const nc = capsules.length;
const up = new THREE.Vector3(...data.up).normalize();
const t0 = Math.min(...variants.map((v) => v.t[0]));
const t1 = Math.max(...variants.map((v) => v.t[v.t.length - 1]));
$('title').textContent = data.title;

// Rows of n values (one per sample time ts) at time t, linear between samples and held outside them, with
// rigid + k (value - rigid) when rigid rows are given: the shown capsule ends (n = 6 per capsule: a, b) with
// the elastic deflection times k, or the tool point (n = 3).
function sample(ts, values, rigid, n, t, k, out) {
  let lo = 0, hi = ts.length - 1;
  if (t <= ts[0]) hi = 0;
  else if (t >= ts[hi]) lo = hi;
  else while (hi - lo > 1) { const m = (lo + hi) >> 1; if (ts[m] <= t) lo = m; else hi = m; }
  const w = hi > lo ? (t - ts[lo]) / (ts[hi] - ts[lo]) : 0;
  const a = lo * n, b = hi * n;
  for (let j = 0; j < n; ++j) {
    const e = values[a + j] * (1 - w) + values[b + j] * w;
    const r = rigid ? rigid[a + j] * (1 - w) + rigid[b + j] * w : e;
    out[j] = r + k * (e - r);
  }
}

// ---- Renderer, camera frame, lights.
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f5f7);
const hemi = new THREE.HemisphereLight(0xffffff, 0x8090a0, 2.2);
hemi.position.copy(up);
scene.add(hemi);

// ---- World shapes, each with its own material (the worst one turns red).
const shapeColor = 0x9aa5b1;
const worldMaterial = (opacity) => new THREE.MeshStandardMaterial({
  color: shapeColor, roughness: 0.8, transparent: opacity < 1, opacity, side: THREE.DoubleSide, depthWrite: opacity >= 1 });
const alongZ = (g) => g.rotateX(Math.PI / 2);  // three's round shapes run along y; ours along z
function shapeGeometry(s) {
  switch (s.type) {
    case 'box': return new THREE.BoxGeometry(...s.size);
    case 'sphere': return new THREE.SphereGeometry(s.radius, 32, 16);
    case 'cylinder': return alongZ(new THREE.CylinderGeometry(s.radius, s.radius, s.length, 40));
    case 'capsule': return alongZ(new THREE.CapsuleGeometry(s.radius, s.length, 8, 32));
    case 'bore': return alongZ(new THREE.CylinderGeometry(s.radius, s.radius, s.length, 48, 1, true));
    case 'mesh': {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute(s.vertices, 3));
      g.setIndex(s.triangles);
      g.computeVertexNormals();
      return g;
    }
  }
  throw new Error(`shape '${s.name}': unknown type '${s.type}'`);
}
// The camera frames the arm's swept volume (every capsule end over every sample, deflected and rigid,
// the tool paths and the worst pair's points), not the world: a tank's wall or waste plane would make the
// arm a speck. The world's shapes frame the view only when no point of the arm is finite.
const worldBounds = new THREE.Box3();
const shapeMeshes = data.shapes.map((s) => {
  const pose = new THREE.Matrix4().set(...s.pose);
  const opacity = s.type === 'bore' ? 0.25 : s.type === 'plane' ? 0.3 : 0.75;
  const mesh = new THREE.Mesh(s.type === 'plane' ? new THREE.BufferGeometry() : shapeGeometry(s), worldMaterial(opacity));
  mesh.matrixAutoUpdate = false;
  mesh.matrix.copy(pose);
  mesh.updateMatrixWorld(true);
  if (s.type !== 'plane') worldBounds.expandByObject(mesh);
  scene.add(mesh);
  return mesh;
});
const bounds = new THREE.Box3();
const point = new THREE.Vector3();
const expandBy = (a) => {
  for (let i = 0; i + 2 < a.length; i += 3) {
    point.set(a[i], a[i + 1], a[i + 2]);
    if (Number.isFinite(point.x + point.y + point.z)) bounds.expandByPoint(point);
  }
};
for (const v of variants) for (const a of [v.ends, v.rigid, v.tool]) if (a) expandBy(a);
if (variants[0].worst_capsule >= 0 && variants[0].worst_a !== null && variants[0].worst_b !== null)
  expandBy([...variants[0].worst_a, ...variants[0].worst_b]);
if (bounds.isEmpty()) bounds.copy(worldBounds);
const maxRadius = Math.max(0, ...capsules.map((c) => c.radius));
if (bounds.isEmpty()) bounds.setFromCenterAndSize(new THREE.Vector3(), new THREE.Vector3(1, 1, 1));
bounds.expandByScalar(maxRadius);
const centre = bounds.getCenter(new THREE.Vector3());
const diagonal = Math.max(bounds.getSize(new THREE.Vector3()).length(), 1e-3);
document.documentElement.setAttribute('data-view-frame', diagonal.toPrecision(4));  // m: the framed diagonal

// Planes: a translucent square of 3 diagonals with its outline, under the scene's centre.
data.shapes.forEach((s, i) => {
  if (s.type !== 'plane') return;
  const local = centre.clone().applyMatrix4(shapeMeshes[i].matrix.clone().invert());
  const g = new THREE.PlaneGeometry(3 * diagonal, 3 * diagonal).translate(local.x, local.y, 0);
  shapeMeshes[i].geometry = g;
  shapeMeshes[i].add(new THREE.LineSegments(new THREE.EdgesGeometry(g), new THREE.LineBasicMaterial({ color: 0x607080 })));
});

// Ground grid perpendicular to up through the lowest point, a 1-2-5 step about a fifth of the diagonal.
const niceStep = (x) => {
  const p = 10 ** Math.floor(Math.log10(x)), m = x / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
};
const gridStep = niceStep(diagonal / 5);  // m
{
  const step = gridStep, half = Math.ceil(0.9 * diagonal / step) * step;
  const grid = new THREE.GridHelper(2 * half, Math.round(2 * half / step), 0x8a94a0, 0xc4cad2);
  grid.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), up);
  let lowest = Infinity;
  for (const x of [bounds.min.x, bounds.max.x]) for (const y of [bounds.min.y, bounds.max.y]) for (const z of [bounds.min.z, bounds.max.z])
    lowest = Math.min(lowest, up.dot(point.set(x, y, z)));
  grid.position.copy(centre).addScaledVector(up, lowest - up.dot(centre));
  scene.add(grid);
}
// The base frame's axes at its origin (x red, y green, z blue), one grid step long.
scene.add(new THREE.AxesHelper(gridStep));
// A length as the scale bar writes it: mm below 1 cm, cm below 1 m.
const lengthText = (x) => (x < 0.01 ? `${+(x * 1000).toPrecision(3)} mm` : x < 1 ? `${+(x * 100).toPrecision(3)} cm` : `${+x.toPrecision(3)} m`);
$('legend').textContent = `grid ${lengthText(gridStep)}; axes at the base: x red, y green, z blue, ${lengthText(gridStep)} long`;

// Camera: from azimuth -55 deg (about up, from base x laid on the ground), 25 deg above the ground,
// the scene's bounding sphere filling the view.
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, diagonal / 1000, diagonal * 100);
camera.up.copy(up);
{
  const e1 = new THREE.Vector3(1, 0, 0).addScaledVector(up, -up.x);
  if (e1.length() < 0.1) e1.set(0, 1, 0).addScaledVector(up, -up.y);
  e1.normalize();
  const e2 = up.clone().cross(e1);
  const az = -55 * Math.PI / 180, el = 25 * Math.PI / 180;
  const dir = e1.multiplyScalar(Math.cos(el) * Math.cos(az)).addScaledVector(e2, Math.cos(el) * Math.sin(az)).addScaledVector(up, Math.sin(el));
  const halfFov = Math.min(20, Math.atan(Math.tan(20 * Math.PI / 180) * camera.aspect) * 180 / Math.PI) * Math.PI / 180;
  camera.position.copy(centre).addScaledVector(dir, 0.5 * diagonal / Math.sin(halfFov));
  camera.lookAt(centre);
}
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.copy(camera.position).addScaledVector(up, diagonal);
sun.target.position.copy(centre);
scene.add(sun, sun.target);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.copy(centre);
controls.update();

// ---- The arms: instanced cylinders and end spheres, variants[0] solid, the others ghosts.
const cylinder = new THREE.CylinderGeometry(1, 1, 1, 24, 1, true);
const sphere = new THREE.SphereGeometry(1, 24, 12);
const solidMaterial = new THREE.MeshStandardMaterial({ color: 0xffffff, roughness: 0.5, metalness: 0.1 });
const ghostMaterial = new THREE.MeshStandardMaterial({ color: 0x4a78c0, roughness: 0.6, transparent: true, opacity: 0.15, depthWrite: false });
function armMeshes(copies, material) {
  if (copies * nc === 0) return null;
  const m = { cyl: new THREE.InstancedMesh(cylinder, material, copies * nc), sph: new THREE.InstancedMesh(sphere, material, 2 * copies * nc) };
  for (const x of [m.cyl, m.sph]) { x.frustumCulled = false; scene.add(x); }
  return m;
}
const solid = armMeshes(1, solidMaterial);
const ghosts = armMeshes(variants.length - 1, ghostMaterial);
const armBlue = new THREE.Color(0x2f6db5), worstRed = new THREE.Color(0xe01010);
const Y = new THREE.Vector3(0, 1, 0), quat = new THREE.Quaternion(), scale = new THREE.Vector3(), matrix = new THREE.Matrix4();
const pa = new THREE.Vector3(), pb = new THREE.Vector3(), mid = new THREE.Vector3(), axis = new THREE.Vector3();
const hidden = new THREE.Matrix4().makeScale(0, 0, 0);
// Capsule c of the ends `e` as instance j of m (cylinder j, spheres 2j and 2j + 1).
function placeCapsule(m, j, e, c) {
  pa.fromArray(e, 6 * c);
  pb.fromArray(e, 6 * c + 3);
  if (!Number.isFinite(pa.x + pa.y + pa.z + pb.x + pb.y + pb.z)) {
    for (const [x, i] of [[m.cyl, j], [m.sph, 2 * j], [m.sph, 2 * j + 1]]) x.setMatrixAt(i, hidden);
    return;
  }
  const r = capsules[c].radius;
  axis.subVectors(pb, pa);
  const len = axis.length();
  quat.setFromUnitVectors(Y, len > 0 ? axis.divideScalar(len) : Y);
  m.cyl.setMatrixAt(j, matrix.compose(mid.addVectors(pa, pb).multiplyScalar(0.5), quat, scale.set(r, Math.max(len, 1e-9), r)));
  quat.identity();
  scale.setScalar(r);
  m.sph.setMatrixAt(2 * j, matrix.compose(pa, quat, scale));
  m.sph.setMatrixAt(2 * j + 1, matrix.compose(pb, quat, scale));
}

// ---- Tool paths (the true tool point, not exaggerated) and the tool's dot.
const finitePoints = (a) => {
  const ps = [];
  for (let i = 0; i + 2 < a.length; i += 3) if (Number.isFinite(a[i] + a[i + 1] + a[i + 2])) ps.push(new THREE.Vector3(a[i], a[i + 1], a[i + 2]));
  return ps;
};
const ghostLine = new THREE.LineBasicMaterial({ color: 0x4a78c0, transparent: true, opacity: 0.3 });
variants.forEach((v, i) => {
  if (v.tool.length) scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(finitePoints(v.tool)),
                                              i ? ghostLine : new THREE.LineBasicMaterial({ color: 0xe07b00 })));
});
const toolDot = new THREE.Mesh(sphere, new THREE.MeshBasicMaterial({ color: 0xe07b00, depthTest: false }));
toolDot.scale.setScalar(diagonal / 150);
toolDot.renderOrder = 5;  // drawn over the capsule it ends
toolDot.visible = false;
scene.add(toolDot);

// ---- The worst pair of variants[0]: a red line between the closest points, the capsule (and the shape, or
// the other capsule) red, shown within 2 % of the duration around its time.
const v0 = variants[0];
const hasWorst = v0.worst_capsule >= 0 && v0.worst_time !== null && v0.worst_a !== null && v0.worst_b !== null;
const worstWindow = Math.max(0.02 * (t1 - t0), 1e-9);
const worstGroup = new THREE.Group();
if (hasWorst) {
  const a = new THREE.Vector3(...v0.worst_a), b = new THREE.Vector3(...v0.worst_b);
  const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([a, b]),
                              new THREE.LineBasicMaterial({ color: 0xe01010, depthTest: false }));
  line.renderOrder = 10;
  worstGroup.add(line);
  for (const p of [a, b]) {
    const dot = new THREE.Mesh(sphere, new THREE.MeshBasicMaterial({ color: 0xe01010, depthTest: false }));
    dot.position.copy(p);
    dot.scale.setScalar(Math.max(0.5 * maxRadius, diagonal / 400));
    dot.renderOrder = 10;
    worstGroup.add(dot);
  }
  scene.add(worstGroup);
  const mark = document.createElement('option');
  mark.value = v0.worst_time;
  const marks = document.createElement('datalist');
  marks.id = 'marks';
  marks.appendChild(mark);
  document.body.appendChild(marks);
  $('time').setAttribute('list', 'marks');
}
const otherCapsule = v0.worst_shape <= -2 ? -(v0.worst_shape + 2) : -1;
const worstShape = v0.worst_shape >= 0 ? shapeMeshes[v0.worst_shape] : null;

// ---- State and controls. The URL hash "#t=1.25&exaggeration=10" sets them and pauses.
const fmt = (x, digits = 4) => (x === null ? 'n/a' : Number(x).toPrecision(digits));
let t = t0, k = 1, playing = true, ghostsOn = true;
const timeInput = $('time'), exInput = $('exaggeration');
timeInput.min = t0;
timeInput.max = t1;
const setExaggeration = (x) => {
  k = Math.min(100, Math.max(1, x));
  exInput.value = Math.log10(k);
  $('exaggeration-value').textContent = fmt(k, 3);
};
const setPlaying = (p) => { playing = p; $('play').textContent = p ? 'Pause' : 'Play'; };
const hash = new URLSearchParams(location.hash.slice(1));
if (hash.has('t')) {
  t = Math.min(t1, Math.max(t0, Number(hash.get('t'))));
  if (!Number.isFinite(t)) throw new Error(`URL hash: t=${hash.get('t')} is not a number`);
  playing = false;
}
setExaggeration(hash.has('exaggeration') ? Number(hash.get('exaggeration')) : 1);
if (!Number.isFinite(k)) throw new Error(`URL hash: exaggeration=${hash.get('exaggeration')} is not a number`);
setPlaying(playing);
timeInput.value = t;
$('play').onclick = () => {
  if (!playing && t >= t1) t = t0;
  setPlaying(!playing);
};
timeInput.oninput = () => { t = Number(timeInput.value); setPlaying(false); };
exInput.oninput = () => setExaggeration(10 ** Number(exInput.value));
$('ghosts').onchange = (e) => { ghostsOn = e.target.checked; };
$('ghost-opacity').oninput = (e) => {
  ghostMaterial.opacity = Number(e.target.value);
  ghostLine.opacity = Math.min(1, 2 * ghostMaterial.opacity);
};
$('worst').disabled = !hasWorst;
$('worst').onclick = () => { t = v0.worst_time; setPlaying(false); };
window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
});

const shapeName = (j) => (j >= 0 ? data.shapes[j].name : j <= -2 ? capsules[-(j + 2)].name : 'none');
const clearanceText = hasWorst
  ? `min clearance ${fmt(v0.min_clearance)} m at t = ${fmt(v0.worst_time)} s: ${capsules[v0.worst_capsule].name} to ${shapeName(v0.worst_shape)}`
  : v0.min_clearance === null ? '' : `min clearance ${fmt(v0.min_clearance)} m`;
// The ghosts, and the lowest clearance of any variant when a ghost's is lower than variants[0]'s.
const lowest = variants.reduce((a, v) => (v.min_clearance !== null && (a === null || v.min_clearance < a.min_clearance) ? v : a), null);
const ghostText = variants.length < 2 ? '' : `${variants.length - 1} ghost${variants.length > 2 ? 's' : ''}` +
  (lowest && lowest !== v0 && lowest.min_clearance < (v0.min_clearance ?? Infinity) ? `, lowest ${fmt(lowest.min_clearance)} m: ${lowest.label}` : '');

// ---- Each frame: advance the time, place the arms, the highlight and the text, render.
const frame = new Float32Array(nc * 6), tool = new Float32Array(3);
let last = performance.now();
function draw(now) {
  if (playing) {
    t += (now - last) / 1000 * Number($('speed').value);
    if (t >= t1) { t = t1; setPlaying(false); }
    timeInput.value = t;
  }
  last = now;
  const nearWorst = hasWorst && Math.abs(t - v0.worst_time) <= worstWindow;
  if (solid) {
    sample(v0.t, v0.ends, v0.rigid, 6 * nc, t, k, frame);
    for (let c = 0; c < nc; ++c) {
      placeCapsule(solid, c, frame, c);
      const red = nearWorst && (c === v0.worst_capsule || c === otherCapsule);
      for (const [x, i] of [[solid.cyl, c], [solid.sph, 2 * c], [solid.sph, 2 * c + 1]]) x.setColorAt(i, red ? worstRed : armBlue);
    }
    for (const x of [solid.cyl, solid.sph]) { x.instanceMatrix.needsUpdate = true; x.instanceColor.needsUpdate = true; }
  }
  if (ghosts) {
    ghosts.cyl.visible = ghosts.sph.visible = ghostsOn;
    for (let g = 1; g < variants.length && ghostsOn; ++g) {
      sample(variants[g].t, variants[g].ends, variants[g].rigid, 6 * nc, t, k, frame);
      for (let c = 0; c < nc; ++c) placeCapsule(ghosts, (g - 1) * nc + c, frame, c);
    }
    ghosts.cyl.instanceMatrix.needsUpdate = ghosts.sph.instanceMatrix.needsUpdate = true;
  }
  if (v0.tool.length) {
    sample(v0.t, v0.tool, null, 3, t, 1, tool);
    toolDot.visible = Number.isFinite(tool[0] + tool[1] + tool[2]);
    toolDot.position.fromArray(tool);
  }
  worstGroup.visible = nearWorst;
  if (worstShape) worstShape.material.emissive.setHex(nearWorst ? 0x900000 : 0x000000);
  $('status').textContent = [`t = ${t.toFixed(3)} s`, v0.label, clearanceText, ghostText].filter((x) => x).join(' | ');
  controls.update();
  // The scale bar: a 1-2-5 length of about 100 px at the orbit centre's distance.
  const pxPerMetre = window.innerHeight / (2 * camera.position.distanceTo(controls.target) * Math.tan(camera.fov * Math.PI / 360));
  const barLength = niceStep(100 / pxPerMetre);
  $('scale-bar').style.width = `${Math.round(barLength * pxPerMetre)}px`;
  $('scale-text').textContent = lengthText(barLength);
  renderer.render(scene, camera);
  // A test's screenshot waits for this: the first frame at the requested time is drawn.
  if (!window.flexfarmViewReady) {
    window.flexfarmViewReady = true;
    document.documentElement.setAttribute('data-view-ready', String(t));
  }
  requestAnimationFrame(draw);
}
requestAnimationFrame(draw);
