// scanmesh serve: the page. Plain JavaScript and three.js (Debian's libjs-three, r111); every
// action is a JSON call to the server (docs/ui.md, "API"); long work runs as a job whose state
// the page polls.
'use strict';

const $ = (id) => document.getElementById(id);
const state = { status: null, tab: 'live', scanSession: null, pointsFrom: 0, shownJob: null, scanXyz: [], scanRgb: [],
  lines: [], current: null, texture: null, grid: null, meshGeometry: null };

// ---------------------------------------------------------------------------------------------
// Server calls

async function api(path, body) {
  const options = body === undefined ? {} : {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) };
  const response = await fetch(path, options);
  const text = await response.text();
  let data = null;
  try { data = JSON.parse(text); } catch (e) { data = { error: text }; }
  if (!response.ok) throw new Error((data && data.error) || ('HTTP ' + response.status));
  return data;
}

// Text from files, devices and other programs goes into HTML only escaped.
function esc(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' }[c]));
}

function showError(id, error) { $(id).textContent = error ? String(error.message || error) : ''; }

function fileUrl(rel) { return '/files/' + rel.split('/').map(encodeURIComponent).join('/') + '?t=' + Date.now(); }

// ---------------------------------------------------------------------------------------------
// Tabs

function selectTab(name) {
  state.tab = name;
  document.querySelectorAll('#tabs button').forEach((b) => b.classList.toggle('active', b.dataset.tab === name));
  document.querySelectorAll('.tab').forEach((t) => t.classList.toggle('active', t.id === 'tab-' + name));
  if (name === 'sessions') refreshSessions();
  if (name === 'meshes') refreshMeshes();
  if (name === 'lines') refreshGrids();
  if (name === 'live') refreshDevices();
  Object.values(viewers).forEach((v) => v.resize());
}
document.querySelectorAll('#tabs button').forEach((b) => b.addEventListener('click', () => selectTab(b.dataset.tab)));

// ---------------------------------------------------------------------------------------------
// 3D views

class Viewer {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x1e1e1e);
    this.camera = new THREE.PerspectiveCamera(35, 1, 1, 5000);
    this.camera.up.set(0, 0, 1);  // the scanner's frame: z along the turntable axis
    this.camera.position.set(0, -600, 250);
    this.controls = new THREE.OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 100);
    this.controls.addEventListener('change', () => this.render());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 0.7));
    const sun = new THREE.DirectionalLight(0xffffff, 0.6);
    sun.position.set(-300, -500, 600);
    this.scene.add(sun);
    this.object = null;
    this.resize();
  }
  resize() {
    const w = this.container.clientWidth || 640, h = this.container.clientHeight || 480;
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }
  show(object) {
    if (this.object) this.scene.remove(this.object);
    this.object = object;
    if (object) this.scene.add(object);
    this.render();
  }
  frame(box) {
    const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length();
    this.controls.target.copy(centre);
    this.camera.position.set(centre.x, centre.y - 1.6 * size, centre.z + 0.5 * size);
    this.camera.near = size / 100; this.camera.far = size * 20;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.render();
  }
  render() { this.renderer.render(this.scene, this.camera); }
}
const viewers = {};

function pointsObject(xyz, rgb) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(xyz, 3));
  g.setAttribute('color', new THREE.Float32BufferAttribute(rgb.map((c) => c / 255), 3));
  return new THREE.Points(g, new THREE.PointsMaterial({ size: 1.5, vertexColors: THREE.VertexColors }));
}

// Per-face quality of a non-indexed triangle geometry: min angle (degrees) and the radius ratio
// q = 2 r_in / R_circ (core/include/scanmesh/core/triangle_quality.h).
function faceQualities(geometry) {
  const p = geometry.attributes.position.array, n = p.length / 9;
  const minAngle = new Float32Array(n), q = new Float32Array(n);
  const len = (i, j) => Math.hypot(p[i] - p[j], p[i + 1] - p[j + 1], p[i + 2] - p[j + 2]);
  for (let f = 0; f < n; ++f) {
    const a = len(9 * f + 3, 9 * f + 6), b = len(9 * f, 9 * f + 6), c = len(9 * f, 9 * f + 3);
    const angle = (x, y, z) => Math.acos(Math.max(-1, Math.min(1, (y * y + z * z - x * x) / (2 * y * z || 1))));
    minAngle[f] = Math.min(angle(a, b, c), angle(b, c, a), angle(c, a, b)) * 180 / Math.PI;
    const s = (a + b + c) / 2, area2 = s * (s - a) * (s - b) * (s - c);
    const area = area2 > 0 ? Math.sqrt(area2) : 0;
    q[f] = area > 0 ? (2 * (area / s)) / ((a * b * c) / (4 * area)) : 0;
  }
  return { minAngle, q };
}

// Red (poor) to green (good) through yellow: 0..1.
function ramp(t) {
  const stops = [[0.84, 0.10, 0.11], [0.99, 0.68, 0.38], [1, 1, 0.75], [0.65, 0.85, 0.42], [0.10, 0.59, 0.25]];
  const x = Math.max(0, Math.min(0.9999, t)) * (stops.length - 1), i = Math.floor(x), u = x - i;
  return stops[i].map((v, k) => v + (stops[i + 1][k] - v) * u);
}

function meshObject(geometry, mode, wireframe, texture) {
  const g = geometry.index ? geometry.toNonIndexed() : geometry.clone();
  const hasColour = !!g.attributes.color;
  let material;
  if (mode === 'minangle' || mode === 'q') {
    const { minAngle, q } = faceQualities(g);
    const colours = new Float32Array(g.attributes.position.count * 3);
    for (let f = 0; f < minAngle.length; ++f) {
      const c = ramp(mode === 'q' ? q[f] : minAngle[f] / 60);
      for (let k = 0; k < 3; ++k) colours.set(c, 9 * f + 3 * k);
    }
    g.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    material = new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide });
  } else if (mode === 'texture' && texture && g.attributes.uv) {
    material = new THREE.MeshLambertMaterial({ map: texture, side: THREE.DoubleSide });
  } else if (mode === 'texture' && hasColour) {
    material = new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide });
  } else {
    material = new THREE.MeshLambertMaterial({ color: 0xd8cfc4, side: THREE.DoubleSide });
  }
  if (!g.attributes.normal) g.computeVertexNormals();
  const mesh = new THREE.Mesh(g, material);
  if (!wireframe) return mesh;
  const group = new THREE.Group();
  group.add(mesh);
  group.add(new THREE.LineSegments(new THREE.WireframeGeometry(g), new THREE.LineBasicMaterial({ color: 0x222222 })));
  return group;
}

async function fetchOk(rel) {
  const response = await fetch(fileUrl(rel));
  if (!response.ok) throw new Error('cannot load ' + rel + ': HTTP ' + response.status);
  return response;
}

async function loadPly(rel) {
  return new THREE.PLYLoader().parse(await (await fetchOk(rel)).arrayBuffer());
}

// An OBJ (as grid-mesh --obj writes it: one object, UVs, a .mtl naming the texture PNG):
// its geometry and, when the .mtl names one, the texture.
async function loadObj(rel) {
  const group = new THREE.OBJLoader().parse(await (await fetchOk(rel)).text());
  let geometry = null;
  group.traverse((o) => { if (!geometry && o.isMesh) geometry = o.geometry; });
  if (!geometry) throw new Error(rel + ' holds no triangles');
  let texture = null;
  const dir = rel.includes('/') ? rel.substring(0, rel.lastIndexOf('/') + 1) : '';
  try {
    const mtl = await (await fetchOk(rel.replace(/\.obj$/i, '.mtl'))).text();
    const map = /^\s*map_Kd\s+(\S+)/m.exec(mtl);
    if (map) texture = await new Promise((resolve, reject) => new THREE.TextureLoader().load(fileUrl(dir + map[1]), resolve, undefined, reject));
  } catch (e) { texture = null; }  // no material: shaded and quality colours still work
  return { geometry, texture };
}

async function loadMesh(rel) {
  if (/\.obj$/i.test(rel)) return loadObj(rel);
  return { geometry: await loadPly(rel), texture: null };
}

// ---------------------------------------------------------------------------------------------
// Job bar and polling

function describeJob(job) {
  if (!job || !job.kind) return 'no job';
  let text = job.kind + ' #' + job.id + ': ' + job.state;
  if (job.state === 'running' && job.steps > 1) text += ' (command ' + (job.step + 1) + ' of ' + job.steps + ': ' + job.commands[job.step].argv[0] + ')';
  if (job.error) text += ' — ' + job.error;
  return text;
}

async function poll() {
  try {
    const s = await api('/api/status');
    state.status = s;
    const job = s.job;
    $('job-text').textContent = describeJob(job);
    $('job-stop').disabled = !(job.state === 'running');
    updateScan(s);
    updateCalibration(s);
    const key = job.id + job.state;
    if (state.shownJob === null) {
      state.shownJob = key;  // a job that ended before the page loaded is not acted on
    } else if (state.shownJob !== key && job.state !== 'running' && job.state !== 'stopping') {
      state.shownJob = key;
      jobFinished(job);
    }
  } catch (e) {
    $('job-text').textContent = 'server not answering: ' + e.message;
  }
  setTimeout(poll, 400);
}
$('job-stop').addEventListener('click', () => api('/api/job/stop', {}).catch((e) => alert(e.message)));

function jobFinished(job) {
  if (!job.kind) return;
  if (job.kind === 'scan') scanFinished(job);
  if (job.kind === 'calibration') calibrationFinished(job);
  if (job.kind === 'replay' && job.state === 'succeeded') $('sessions-sheet').src = fileUrl(job.info.out + '/contact_sheet.png');
  if (job.kind === 'reconstruct' && job.state === 'succeeded') { selectTab('meshes'); openMesh(job.info.out + '/mesh.ply'); }
  if (job.kind === 'regions') regionsFinished(job);
  if (job.kind === 'animesh') animeshFinished(job);
  if (job.kind === 'sim-grid' && job.state === 'succeeded') refreshGrids(job.info.grid);
  if (state.tab === 'sessions') refreshSessions();
}

// ---------------------------------------------------------------------------------------------
// Live view

let liveBusy = false;
async function liveLoop() {
  const s = state.status;
  const deviceJob = s && s.job && (s.job.state === 'running' || s.job.state === 'stopping') && (s.job.kind === 'scan' || s.job.kind === 'calibration');
  if (state.tab === 'live' && $('live-run').checked && !liveBusy && !deviceJob) {
    liveBusy = true;
    try {
      const response = await fetch('/api/live/frame', { cache: 'no-store' });
      if (!response.ok) throw new Error((await response.json()).error);
      const blob = await response.blob();
      const old = $('live-img').src;
      $('live-img').src = URL.createObjectURL(blob);
      if (old.startsWith('blob:')) URL.revokeObjectURL(old);
      $('live-info').textContent = 'table ' + Number(response.headers.get('X-Angle')).toFixed(1) + '°, ' +
        response.headers.get('X-Peaks') + ' laser peaks (' + response.headers.get('X-Saturated') + ' saturated), mean level ' +
        Number(response.headers.get('X-Mean-Level')).toFixed(1);
      showError('live-error', null);
    } catch (e) { showError('live-error', e); }
    liveBusy = false;
  } else if (deviceJob && state.tab === 'live') {
    $('live-info').textContent = 'the devices are recording (' + s.job.kind + '): live view paused';
  }
  setTimeout(liveLoop, 300);
}

async function refreshDevices() {
  try {
    const d = await api('/api/devices');
    const live = d.in_use;
    let html = '<b>in use:</b> camera ' + esc(live.camera) + ', board ' + esc(live.board) + ' (' + live.width + '×' + live.height + ')' +
      (live.firmware ? ', firmware “' + esc(live.firmware) + '”' : '') + '<br><b>cameras found:</b> ';
    html += d.cameras.length ? d.cameras.map((c) => esc(c.path) + ' “' + esc(c.card) + '”').join(', ') : 'none';
    html += '<br><b>USB boards found:</b> ' + (d.usb_boards.length ? d.usb_boards.map((b) => esc(b.id + ' ' + b.kind)).join(', ') : 'none');
    $('devices').innerHTML = html;
    $('live-exposure').value = live.exposure; $('live-exposure-v').textContent = ' ' + live.exposure;
    $('live-threshold').value = live.threshold; $('live-threshold-v').textContent = ' ' + live.threshold;
    $('live-method').value = live.method.toLowerCase().includes('gauss') ? 'gaussian' : live.method.toLowerCase().includes('blais') ? 'blais-rioux' : 'com';
    $('live-laser').value = String(live.laser);
  } catch (e) { showError('live-error', e); }
}

async function applyLive(settings) {
  try { await api('/api/live/settings', settings); showError('live-error', null); } catch (e) { showError('live-error', e); }
}
$('live-exposure').addEventListener('change', (e) => { $('live-exposure-v').textContent = ' ' + e.target.value; applyLive({ exposure: Number(e.target.value) }); });
$('live-threshold').addEventListener('change', (e) => { $('live-threshold-v').textContent = ' ' + e.target.value; applyLive({ threshold: Number(e.target.value) }); });
$('live-method').addEventListener('change', (e) => applyLive({ method: e.target.value }));
$('live-laser').addEventListener('change', (e) => applyLive({ laser: Number(e.target.value) }));
$('turn-minus').addEventListener('click', () => api('/api/live/turn', { degrees: -15 }).catch((e) => showError('live-error', e)));
$('turn-plus').addEventListener('click', () => api('/api/live/turn', { degrees: 15 }).catch((e) => showError('live-error', e)));

// ---------------------------------------------------------------------------------------------
// Scan

function newName(prefix) {
  const d = new Date(), pad = (x) => String(x).padStart(2, '0');
  return prefix + '-' + d.getFullYear() + pad(d.getMonth() + 1) + pad(d.getDate()) + '-' + pad(d.getHours()) + pad(d.getMinutes()) + pad(d.getSeconds());
}

function resetScanView(session) {
  state.scanSession = session; state.pointsFrom = 0; state.scanXyz = []; state.scanRgb = [];
  viewers.scan.show(null);
  $('scan-result').innerHTML = '';
}

$('scan-start').addEventListener('click', async () => {
  const name = $('scan-name').value || newName('scan');
  try {
    resetScanView(name);
    await api('/api/scan/start', { name, steps: Number($('scan-steps').value) });
    $('scan-name').value = '';
    showError('scan-error', null);
  } catch (e) { showError('scan-error', e); }
});
$('scan-pause').addEventListener('click', () => api('/api/job/stop', {}).catch((e) => showError('scan-error', e)));
$('scan-stop').addEventListener('click', () => api('/api/job/stop', {}).then(() => { state.scanStopped = true; }).catch((e) => showError('scan-error', e)));
$('scan-resume').addEventListener('click', async () => {
  try { await api('/api/scan/resume', { session: state.scanSession }); showError('scan-error', null); } catch (e) { showError('scan-error', e); }
});

let pointsBusy = null;  // the session whose points are being fetched
async function fetchPoints(done) {
  const session = state.scanSession;
  if (pointsBusy === session || !session || !state.status.calibration.exists) return;
  pointsBusy = session;
  try {
    while (state.pointsFrom < done) {
      const p = await api('/api/scan/points?session=' + encodeURIComponent(session) + '&from=' + state.pointsFrom);
      if (state.scanSession !== session) return;  // another scan started meanwhile
      state.scanXyz.push(...p.xyz); state.scanRgb.push(...p.rgb);
      state.pointsFrom = p.to;
      if (p.to <= p.from) break;
    }
    const cloud = pointsObject(state.scanXyz, state.scanRgb);
    const first = !viewers.scan.object;
    viewers.scan.show(cloud);
    if (first && state.scanXyz.length) { cloud.geometry.computeBoundingBox(); viewers.scan.frame(cloud.geometry.boundingBox); }
    $('scan-info').textContent = (state.scanXyz.length / 3) + ' points from ' + state.pointsFrom + ' steps';
  } catch (e) { showError('scan-error', e); } finally { if (pointsBusy === session) pointsBusy = null; }
}

function updateScan(s) {
  const job = s.job, running = job.state === 'running' || job.state === 'stopping';
  const scanning = running && job.kind === 'scan';
  $('scan-start').disabled = running;
  $('scan-pause').disabled = !(scanning && job.step === 0);
  $('scan-stop').disabled = !(scanning && job.step === 0);
  $('scan-resume').disabled = running || !(job.kind === 'scan' && job.state === 'stopped');
  if (!$('scan-steps').value) $('scan-steps').value = s.default_steps;
  $('scan-calib-note').textContent = s.calibration.exists ? 'Points appear as the table turns; the grid and its mesh follow the scan.'
    : 'Not calibrated yet: the scan records, but points and mesh need a calibration (Calibration tab).';
  if (job.kind === 'scan' && s.job_session) {
    if (state.scanSession !== job.session) resetScanView(job.session);
    const js = s.job_session;
    if (js.steps_planned) $('scan-progress').style.width = (100 * js.steps_done / js.steps_planned) + '%';
    if (scanning && job.step === 0 && js.steps_done > 0 && state.tab === 'scan') {
      $('scan-frame').src = '/api/sessions/frame?session=' + encodeURIComponent(job.session) + '&frame=1&t=' + js.steps_done;
    }
    if (js.steps_done > state.pointsFrom && state.tab === 'scan') fetchPoints(js.steps_done);
    if (running) $('scan-info').textContent = 'step ' + js.steps_done + ' of ' + js.steps_planned + (job.step > 0 ? ' — ' + job.commands[job.step].argv[0] : '');
  }
}

async function scanFinished(job) {
  const js = state.status.job_session || {};
  if (job.state === 'failed') { showError('scan-error', job.error); return; }
  if (job.state === 'stopped') {
    $('scan-info').textContent = 'paused at step ' + js.steps_done + ' of ' + js.steps_planned + ': Resume continues (every complete step is kept)';
    return;
  }
  await fetchPoints(js.steps_done || 0);
  if (job.steps > 1) {
    const rec = job.commands[1].result || {};
    $('scan-result').innerHTML = 'grid: ' + rec.valid_cells + ' valid cells from ' + rec.peaks + ' laser peaks<br>' +
      '<img src="' + fileUrl(job.info.out + '/render.png') + '" alt="render">';
    try {
      const g = await loadPly(job.info.out + '/mesh.ply');
      const mesh = meshObject(g, 'texture', false);
      viewers.scan.show(mesh);
      g.computeBoundingBox(); viewers.scan.frame(g.boundingBox);
      $('scan-info').textContent = 'scan complete: mesh of ' + (g.index ? g.index.count / 3 : g.attributes.position.count / 3) + ' triangles (' + job.info.out + '/mesh.ply)';
    } catch (e) { showError('scan-error', e); }
  } else {
    $('scan-info').textContent = 'scan recorded (' + js.steps_done + ' steps); calibrate, then Reconstruct it on the Sessions tab';
  }
}

// ---------------------------------------------------------------------------------------------
// Calibration

$('calib-start').addEventListener('click', async () => {
  try {
    $('calib-result').innerHTML = ''; $('calib-check').innerHTML = '';
    await api('/api/calibration/start', { name: newName('calibration'), poses: Number($('calib-poses').value) });
    showError('calib-error', null);
  } catch (e) { showError('calib-error', e); }
});
$('calib-continue').addEventListener('click', () => api('/api/job/continue', {}).catch((e) => showError('calib-error', e)));

function updateCalibration(s) {
  const job = s.job, running = job.state === 'running';
  $('calib-start').disabled = running || job.state === 'stopping';
  $('calib-continue').disabled = !(running && job.kind === 'calibration' && job.step === 0 && !s.live.simulated);
  if (job.kind !== 'calibration' || !s.job_session) return;
  const js = s.job_session;
  if (js.steps_planned) $('calib-progress').style.width = (100 * js.steps_done / js.steps_planned) + '%';
  if (running && job.step === 0) {
    $('calib-info').textContent = 'pose ' + ((js.pose === undefined ? js.poses - 1 : js.pose) + 1) + ' of ' + js.poses + ': view ' + js.steps_done + ' of ' + js.steps_planned;
    if (js.steps_done > 0 && state.tab === 'calibration')
      $('calib-frame').src = '/api/sessions/frame?session=' + encodeURIComponent(job.session) + '&frame=0&t=' + js.steps_done;
  } else if (running) {
    $('calib-info').textContent = job.commands[job.step].argv[0] + ' …';
  }
}

const fmt = (x, d = 3) => (typeof x === 'number' ? x.toFixed(d) : '–');

function calibrationFinished(job) {
  if (job.state !== 'succeeded') { showError('calib-error', job.error || job.state); return; }
  const r = job.commands[1].result || {}, u = r.camera_uncertainty || {};
  let html = '<table><tr><th></th><th>value</th><th>± 1σ</th></tr>';
  for (const k of ['fx', 'fy', 'cx', 'cy']) html += '<tr><td>' + k + ' (px)</td><td>' + fmt(r.camera[k], 2) + '</td><td>' + fmt(u[k], 2) + '</td></tr>';
  for (const l of r.lasers || []) html += '<tr><td>laser ' + esc(l.name) + ' distance (mm)</td><td>' + fmt(l.distance_mm, 2) + '</td><td>' + fmt(l.distance_uncertainty_mm, 2) + '</td></tr>' +
    '<tr><td>laser ' + esc(l.name) + ' normal (°)</td><td></td><td>' + fmt(l.normal_uncertainty_deg, 3) + '</td></tr>';
  html += '<tr><td>axis point (mm)</td><td></td><td>' + fmt(r.axis_point_uncertainty_mm, 2) + '</td></tr>';
  html += '<tr><td>axis direction (°)</td><td></td><td>' + fmt(r.axis_direction_uncertainty_deg, 3) + '</td></tr></table>';
  html += 'reprojection RMS ' + fmt(r.reprojection_rms_px, 3) + ' px, laser RMS ' + fmt(r.laser_rms_mm, 3) + ' mm; ' + r.views_detected + ' views used, ' + r.views_rejected + ' rejected';
  $('calib-result').innerHTML = html;
  if (job.commands.length > 2) {
    const c = job.commands[2].result || {};
    const pass = job.commands[2].exit_code === 0;
    let check = '<span class="' + (pass ? 'ok' : 'error') + '" id="calib-verdict">' + (pass ? 'PASS' : 'FAIL') + '</span>';
    if (c.sphere) check += '<br>probing sphere: radius error ' + fmt(c.sphere.radius_error_mm) + ' mm, RMS ' + fmt(c.sphere.rms_distance_mm) + ' mm';
    if (c.dumbbell) check += '<br>dumbbell: spacing error ' + fmt(c.dumbbell.spacing_error_mm) + ' mm';
    $('calib-check').innerHTML = check;
  }
  $('calib-info').textContent = 'calibration saved (calibration.yaml in the data folder)';
}

// ---------------------------------------------------------------------------------------------
// Sessions

async function refreshSessions() {
  try {
    const list = await api('/api/sessions');
    const body = $('sessions-table').querySelector('tbody');
    body.innerHTML = '';
    for (const s of list) {
      const tr = document.createElement('tr');
      tr.innerHTML = '<td>' + esc(s.name) + '</td><td>' + esc(s.kind || '?') + '</td><td>' +
        (s.error ? '<span class="error">' + esc(s.error) + '</span>' : s.steps_done + ' / ' + s.steps_planned) + '</td><td>' + (s.width || '') + '×' + (s.height || '') + '</td><td></td>';
      const actions = tr.lastChild;
      const add = (label, path, body) => {
        const b = document.createElement('button');
        b.textContent = label;
        b.addEventListener('click', () => api(path, body).then(() => showError('sessions-error', null)).catch((e) => showError('sessions-error', e)));
        actions.appendChild(b);
      };
      if (!s.error) add('Replay', '/api/sessions/replay', { session: s.name });
      if (!s.error && s.kind === 'scan' && s.complete) add('Reconstruct + mesh', '/api/sessions/reconstruct', { session: s.name });
      if (!s.error && !s.complete) add('Resume', '/api/scan/resume', { session: s.name });
      body.appendChild(tr);
    }
  } catch (e) { showError('sessions-error', e); }
}

// ---------------------------------------------------------------------------------------------
// Meshes

async function refreshMeshes() {
  try {
    const list = (await api('/api/meshes')).concat(await api('/api/meshes?ext=obj'));
    const ul = $('mesh-list');
    ul.innerHTML = '';
    for (const m of list) {
      const li = document.createElement('li');
      li.textContent = m.path;
      li.addEventListener('click', () => openMesh(m.path));
      ul.appendChild(li);
    }
  } catch (e) { showError('mesh-error', e); }
}

let meshRequest = 0;
async function openMesh(rel) {
  const request = ++meshRequest;
  try {
    const { geometry: g, texture } = await loadMesh(rel);
    if (request !== meshRequest) return;  // a later click won
    state.meshGeometry = g; state.meshTexture = texture; state.meshPath = rel;
    showMesh(true);
    showError('mesh-error', null);
  } catch (e) { showError('mesh-error', e); }
}

// OBJLoader gives every triangle its own three corners: count the distinct positions.
function distinctVertices(g) {
  if (g.index) return g.attributes.position.count;
  const p = g.attributes.position.array, seen = new Set();
  for (let i = 0; i < p.length; i += 3) seen.add(p[i] + ',' + p[i + 1] + ',' + p[i + 2]);
  return seen.size;
}

function showMesh(reframe) {
  const g = state.meshGeometry;
  if (!g) return;
  const mode = $('mesh-colour').value;
  viewers.mesh.show(meshObject(g, mode, $('mesh-wire').checked, state.meshTexture));
  if (reframe) { g.computeBoundingBox(); viewers.mesh.frame(g.boundingBox); }
  const flat = g.index ? g.toNonIndexed() : g;
  const { minAngle, q } = faceQualities(flat);
  const n = minAngle.length;
  const good = minAngle.filter((a) => a >= 30).length;
  const worst = n ? Math.min(...minAngle) : 0;
  const meanQ = n ? q.reduce((a, b) => a + b, 0) / n : 0;
  $('mesh-stats').innerHTML = '<b>' + esc(state.meshPath) + '</b><br>' + distinctVertices(g) + ' vertices, ' + n + ' triangles<br>' +
    fmt(100 * good / Math.max(n, 1), 1) + ' % of triangles with min angle ≥ 30°, worst ' + fmt(worst, 2) + '°, mean radius ratio 2r/R ' + fmt(meanQ, 3);
  $('mesh-legend').innerHTML = mode === 'minangle' ? 'min angle: 0° <span class="legend-bar"></span> 60°'
    : mode === 'q' ? 'radius ratio 2r/R: 0 <span class="legend-bar"></span> 1' : '';
}
$('mesh-colour').addEventListener('change', () => showMesh(false));
$('mesh-wire').addEventListener('change', () => showMesh(false));

// ---------------------------------------------------------------------------------------------
// Animation lines over the upright texture

async function refreshGrids(select) {
  try {
    const grids = (await api('/api/grids')).filter((g) => g.has_texture);
    const sel = $('lines-grid'), before = select || sel.value;
    sel.innerHTML = '';
    for (const g of grids) {
      const o = document.createElement('option');
      o.value = o.textContent = g.path;
      sel.appendChild(o);
    }
    if (before && grids.some((g) => g.path === before)) sel.value = before;
    if (sel.value && sel.value !== state.grid) openGrid(sel.value);
  } catch (e) { showError('lines-error', e); }
}
$('lines-grid').addEventListener('change', (e) => openGrid(e.target.value));
$('lines-sim').addEventListener('click', () => api('/api/grids/sim', { name: newName('head') }).catch((e) => showError('lines-error', e)));

async function openGrid(rel) {
  state.grid = rel; state.lines = []; state.current = null; state.texture = null;
  const dir = rel.substring(0, rel.lastIndexOf('/'));
  let lines = [];
  try { lines = (await api('/api/lines?grid=' + encodeURIComponent(rel))).lines; } catch (e) { lines = []; }
  if (state.grid !== rel) return;  // another grid was chosen meanwhile
  state.lines = lines;
  $('lines-regions').removeAttribute('src');
  listLines();
  // The texture last: once it shows, the grid's saved lines are in place too.
  const image = new Image();
  image.onload = () => {
    if (state.grid !== rel) return;
    const c = $('lines-canvas');
    c.width = image.width; c.height = image.height;
    c.style.width = image.width + 'px'; c.style.height = image.height + 'px';
    state.texture = image;
    drawLines();
  };
  image.src = fileUrl(dir + '/texture.png');
}

const kindColour = { line: '#ff1744', opening: '#00e5ff', seam: '#ffea00' };
function drawLines() {
  const c = $('lines-canvas'), g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  if (state.texture) g.drawImage(state.texture, 0, 0);
  const all = state.current ? state.lines.concat([state.current]) : state.lines;
  for (const line of all) {
    g.strokeStyle = kindColour[line.kind] || '#fff'; g.lineWidth = line === state.current ? 2 : 1.5;
    g.beginPath();
    line.points.forEach(([x, y], i) => (i ? g.lineTo(x, y) : g.moveTo(x, y)));
    if (line.closed && line !== state.current) g.closePath();
    g.stroke();
    g.fillStyle = g.strokeStyle;
    for (const [x, y] of line.points) g.fillRect(x - 1.5, y - 1.5, 3, 3);
  }
}

function listLines() {
  const ul = $('lines-list');
  ul.innerHTML = '';
  state.lines.forEach((line, i) => {
    const li = document.createElement('li');
    li.textContent = line.id + ' (' + line.kind + (line.closed ? ', closed' : '') + ', ' + line.points.length + ' points) ';
    const del = document.createElement('button');
    del.textContent = 'delete';
    del.addEventListener('click', () => { state.lines.splice(i, 1); listLines(); drawLines(); });
    li.appendChild(del);
    ul.appendChild(li);
  });
}

// Texture pixels under the pointer (inside the canvas's border: the picture is its content box).
function canvasPoint(event) {
  const c = $('lines-canvas'), r = c.getBoundingClientRect();
  const x = (event.clientX - r.left - c.clientLeft) * c.width / c.clientWidth;
  const y = (event.clientY - r.top - c.clientTop) * c.height / c.clientHeight;
  return [Math.round(x * 10) / 10, Math.round(y * 10) / 10];
}

function finishLine() {
  const line = state.current;
  state.current = null;
  if (line && line.points.length >= 2) addLine(line.points, line.kind, line.closed, line.smooth);
  drawLines();
}

// Adds a finished line; the page's API for scripts and tests as well (window.scanmeshUI).
function addLine(points, kind = 'line', closed = false, smooth = false) {
  let n = state.lines.length + 1;
  while (state.lines.some((l) => l.id === kind + n)) ++n;
  const line = { id: kind + n, kind, closed, smooth, points: points.map(([x, y]) => [x, y]) };
  state.lines.push(line);
  listLines(); drawLines();
  return line.id;
}

// Editing: a point of a finished line is dragged to a new place.
function nearestPoint(p) {
  let best = null, bestDistance = 6;
  state.lines.forEach((line) => line.points.forEach((q, i) => {
    const d = Math.hypot(q[0] - p[0], q[1] - p[1]);
    if (d < bestDistance) { best = { line, index: i }; bestDistance = d; }
  }));
  return best;
}
$('lines-canvas').addEventListener('mousedown', (e) => {
  if (state.current) return;
  state.drag = nearestPoint(canvasPoint(e));
  state.dragged = false;
});
$('lines-canvas').addEventListener('mousemove', (e) => {
  if (!state.drag) return;
  state.drag.line.points[state.drag.index] = canvasPoint(e);
  state.dragged = true;
  drawLines();
});
window.addEventListener('mouseup', () => {
  if (state.drag && state.dragged) listLines();
  state.drag = null;
  // The click that follows a drag's release on the canvas is not a new point; one elsewhere
  // never comes, so the flag must not outlive this event.
  setTimeout(() => { state.dragged = false; }, 0);
});

$('lines-canvas').addEventListener('click', (e) => {
  if (state.dragged) { state.dragged = false; return; }
  if (!state.current) state.current = { kind: $('lines-kind').value, closed: $('lines-closed').checked, smooth: $('lines-smooth').checked, points: [] };
  state.current.points.push(canvasPoint(e));
  drawLines();
});
$('lines-canvas').addEventListener('dblclick', finishLine);
$('lines-finish').addEventListener('click', finishLine);
$('lines-undo').addEventListener('click', () => { if (state.current) { state.current.points.pop(); drawLines(); } });

async function saveLines() {
  if (!state.grid) throw new Error('no grid: make one (New simulated head) or reconstruct a scan');
  finishLine();
  const c = $('lines-canvas');
  return api('/api/lines', { grid: state.grid, lines: state.lines, width: c.width, height: c.height });
}
$('lines-save').addEventListener('click', () => saveLines().then(() => showError('lines-error', null)).catch((e) => showError('lines-error', e)));
$('lines-mesh').addEventListener('click', () => api('/api/animesh', { grid: state.grid }).then(() => showError('lines-error', null)).catch((e) => showError('lines-error', e)));

function regionsFinished(job) {
  if (job.state !== 'succeeded') { showError('lines-error', job.error); $('lines-result').textContent = ''; return; }
  const r = job.commands[0].result || {};
  $('lines-regions').src = fileUrl(job.info.png);
  $('lines-result').innerHTML = '<span id="lines-region-count">' + (r.regions || []).length + '</span> regions from ' + r.segments + ' line segments';
  showError('lines-error', null);
}

async function animeshFinished(job) {
  const r = job.commands[0].result || {};
  if (job.state !== 'succeeded' && job.commands[0].exit_code !== 9) { showError('lines-error', job.error); return; }
  $('lines-result').innerHTML = 'animation mesh: ' + (r.vertices || '?') + ' vertices, ' + (r.faces || r.triangles || '?') + ' triangles' +
    (job.commands[0].exit_code === 9 ? ' <span class="error">(incomplete: ' + esc(job.commands[0].error || '') + ')</span>' : '') +
    '<br><img src="' + fileUrl(job.info.out + '/render.png') + '" alt="animesh render">';
  selectTab('meshes');
  openMesh(job.info.out + '/mesh.ply');
}

// ---------------------------------------------------------------------------------------------

window.scanmeshUI = { addLine, saveLines, openMesh, selectTab, state };

viewers.scan = new Viewer($('scan-view'));
viewers.mesh = new Viewer($('mesh-view'));
window.addEventListener('resize', () => Object.values(viewers).forEach((v) => v.resize()));
refreshDevices();
poll();
liveLoop();
