// The operator GUI: Robot (module tree, model, 3D view, customisation, hot swap, camera),
// Missions (drilling, the storey view and driving, sanding/spraying), Transport, Safety
// (state, causes, e-stop inputs, services), Topics. The safety strip with the E-STOP and the
// STOPPED banner: safety.js; sign-in and roles: access.js; the link: link.js.
import { Link } from './link.js';
import { Viewer } from './viewer.js';
import { addPointArea, addWallArea, bimWallId, pickWall, wallFace, wallSpan } from './storey.js';
import { PanZoom } from './panzoom.js';
import { stepper } from './controls.js';
import { initBuilder, mission, onMissionChange, setMissionYaml } from './builder.js';
import { $, esc, svgEl, confirmDialog, initConfirm, notice, now, requestId } from './ui.js';
import { services, trackServices, alive, statusOf } from './status.js';
import { initAccess, gate, applyGate, refreshGates, roleFor, onAccessChange } from './access.js';
import { initSafety } from './safety.js';

const link = new Link(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`);
window.concertLink = link;  // for the browser tests and the curious
initConfirm();
trackServices(link);
initAccess(link);
initSafety(link);

/// Subscribes once to `topic` when the gateway's catalogue has it (called on every hello).
const optionalSubs = new Set();
function subscribeIf(topic, fn, maxHz = 0) {
  if (optionalSubs.has(topic) || !link.hasTopic(topic)) return;
  optionalSubs.add(topic);
  link.subscribe(topic, fn, maxHz);
}
/// Shows `text` in `el`, class 'result ok|bad' (an answer to a command).
function answer(el, text, kind = '') {
  el.textContent = text;
  el.classList.toggle('ok', kind === 'ok');
  el.classList.toggle('bad', kind === 'bad');
}

// ---- pages
for (const b of document.querySelectorAll('#tabs button')) {
  b.onclick = () => {
    for (const o of document.querySelectorAll('#tabs button')) o.classList.toggle('active', o === b);
    for (const p of document.querySelectorAll('.page')) p.classList.toggle('active', p.id === 'page-' + b.dataset.page);
    if (b.dataset.page === 'missions') renderBim();  // the map's scale is known once it is shown
  };
}

// ---- services (heartbeats on concert/system/status every 200 ms: status.js)
function need(name, el, what) {
  const ok = !!alive(name);
  el.textContent = ok ? '' : `The ${name} service is not running: ${what} unavailable.`;
  return ok;
}
function renderServices() {
  const rows = [...services.values()].sort((a, b) => a.status.service.localeCompare(b.status.service)).map(({ status: s, seen }) => {
    const age = (now() - seen) / 1000;
    const state = age > 3 ? `silent ${age.toFixed(0)} s` : s.state.replace('SERVICE_', '').toLowerCase();
    return `<tr class="${age > 3 ? 'unknown' : ''}"><td>${esc(s.service)}</td><td>${esc(s.host)}</td><td>${esc(state)}</td><td>${s.model_version}</td><td>${esc(s.message)}</td></tr>`;
  });
  $('services').querySelector('tbody').innerHTML = rows.join('');
}

// ---- robot: tree, model, 3D, joints
const viewer = new Viewer($('viewer'));
window.concertViewer = viewer;
let model = null, lastJoints = null;
link.subscribe('concert/topology/module_tree', (t) => {
  $('tree-version').textContent = `tree v${t.version}`;
  const kids = new Map();
  for (const m of t.modules) {
    if (!kids.has(m.parent_module)) kids.set(m.parent_module, []);
    kids.get(m.parent_module).push(m);
  }
  const node = (m) => {
    const kind = m.kind.replace('MODULE_', '').toLowerCase().replace('_', ' ');
    const port = m.parent_connector >= 0 ? ` · port ${m.parent_connector}` : '';
    const label = m.known ? esc(m.key || '(no key)') : `<span class="fault">unknown module (type ${m.mod_type}, id ${m.mod_id})</span>`;
    const sub = (kids.get(m.index) || []).map(node).join('');
    return `<li data-module="${esc(m.key)}">${label} <span class="small">${kind}${port} · ESC ${m.slave_positions.join(',')}</span>${sub ? `<ul>${sub}</ul>` : ''}</li>`;
  };
  $('module-tree').innerHTML = (kids.get(-1) || []).map(node).join('');
  $('tree-issues').innerHTML = t.issues.map((i) => `<p class="${i.error ? 'fault' : 'missing'}">slave ${i.position}: ${esc(i.message)}</p>`).join('');
});
/// "drill_A (drill), ..." for a model's end-effectors.
const effectors = (m) => m.end_effectors.map((e) => `${e.name} (${e.kind})`).join(', ') || 'none';
link.subscribe('concert/model/robot_model', (m) => {
  const before = model;
  model = m;
  $('model-version').textContent = `version ${m.version}`;
  $('model-info').textContent = `${m.joints.length} joints, chains ${m.chains.map((c) => c.name + ' (' + c.role + ')').join(', ')}; ` +
    `end-effectors ${effectors(m)}; hash ${m.content_hash.slice(0, 12)}`;
  const chain = $('homing-chain').value;
  $('homing-chain').innerHTML = m.chains.map((c) => `<option>${esc(c.name)}</option>`).join('');
  if (m.chains.some((c) => c.name === chain)) $('homing-chain').value = chain;
  // The add-on's module: one of the model's modules, not typed.
  const mod = $('addon-module').value;
  $('addon-module').innerHTML = '<option value="">choose a module</option>' +
    m.modules.map((k) => `<option value="${esc(k)}">${esc(k)}</option>`).join('');
  if (m.modules.includes(mod)) $('addon-module').value = mod;
  viewer.setModel(m);
  if (before && before.version !== m.version) {
    notice(`Model version ${m.version} (was ${before.version}): end-effectors ${effectors(m)}.`, 'ok', 8000);
  }
  renderCustom();
  refreshGates();
});
link.subscribe('concert/robot/joint_state', (js) => { lastJoints = js; viewer.setJoints(js); }, 10);

// ---- robot: customisation (homing, add-ons). Each changes the model: confirmed first, then
// followed until the model service answers: a new model version, or its status message for
// this request (a refusal, or "unchanged").
let customPending = null;  // {request_id, base_version, what, sent}
function renderCustom() {
  const p = customPending;
  if (!p) return;
  const st = statusOf('modelgen');
  const tag = `customisation request ${p.request_id}`;
  if (st && st.message.startsWith(tag)) {
    const rest = st.message.slice(tag.length).replace(/^:\s*/, '');
    if (/unchanged/.test(rest)) answer($('custom-result'), `${p.what}: no change, ${rest}`, 'ok');
    else answer($('custom-result'), `${p.what} refused by the model service: ${rest}`, 'bad');
    customPending = null;
  } else if (model && model.version > p.base_version) {
    answer($('custom-result'), `${p.what}: the robot is now at model version ${model.version}`, 'ok');
    customPending = null;
  } else if (now() - p.sent > 15000) {
    answer($('custom-result'), `${p.what}: no answer from the model service in 15 s` + (alive('modelgen') ? '' : ' (it is not running)'), 'bad');
    customPending = null;
  }
}
async function sendCustomisation(what, text, data) {
  // Made against the version the dialog names: if the model changes while it is open, the
  // model service refuses the request rather than apply it to a model nobody confirmed.
  const base = model.version;
  if (!await confirmDialog(text, 'Yes, change the model')) { answer($('custom-result'), `${what}: cancelled`); return; }
  const cmd = { request_id: requestId(), base_version: base, ...data };
  answer($('custom-result'), `${what}: sending…`);
  try {
    await link.publish('concert/model/customisation', cmd);
    customPending = { request_id: cmd.request_id, base_version: base, what, sent: now() };
    answer($('custom-result'), `${what}: sent; waiting for the model service`);
  } catch (e) {
    answer($('custom-result'), `${what} not sent: ${e.message}`, 'bad');
  }
}
/// A customisation request replaces the previous one (services/modelgen: the service keeps the
/// latest request's homing and add-ons), so each dialog says so.
const REPLACES = 'A customisation replaces the previous one: homing or add-ons sent earlier and not repeated here are dropped.';
$('send-homing').onclick = () => {
  if (!model || !lastJoints) { answer($('custom-result'), 'no model or joint states yet', 'bad'); return; }
  const chain = model.chains.find((c) => c.name === $('homing-chain').value);
  if (!chain) { answer($('custom-result'), 'choose a chain', 'bad'); return; }
  const names = chain.joints;
  const pos = names.map((n) => lastJoints.position[lastJoints.name.indexOf(n)] ?? 0);
  const posture = names.map((n, i) => `${n} ${pos[i].toFixed(3)}`).join(', ');
  sendCustomisation(`homing of chain ${chain.name}`,
    `Make the current posture of chain ${chain.name} the homing posture (${posture} rad): a new model version after version ${model.version}. ${REPLACES}`,
    { homing_joints: names, homing_positions: pos });
};
$('send-addon').onclick = () => {
  const module = $('addon-module').value, addon = $('addon-key').value.trim();
  if (!model) { answer($('custom-result'), 'no model yet', 'bad'); return; }
  if (!module || !addon) { answer($('custom-result'), 'Choose the module and type the add-on key (both are needed).', 'bad'); return; }
  sendCustomisation(`add-on ${addon} on ${module}`,
    `Mount add-on ${addon} on module ${module}: a new model version after version ${model.version}. ${REPLACES}`,
    { addons: [{ module_name: module, addon }] });
};
gate($('send-homing'), 'concert/model/customisation', () => (!model || !lastJoints ? 'no model or joint states yet' : ''));
gate($('send-addon'), 'concert/model/customisation', () => (!model ? 'no model yet' : ''));

// ---- robot: hot swap of the simulated robot (concert/sim/command, like `concert sim swap`):
// an assembly file from this device, confirmed, then the simulator's reply for that request.
const MAX_ASSEMBLY_BYTES = 900 * 1024;  // the gateway refuses messages over 1 MiB
const simReplies = new Map();  // request_id -> SimCommandReply
let swapSent = null;           // {request_id, name}
function renderSwap() {
  if (!swapSent) return;
  const r = simReplies.get(swapSent.request_id);
  if (r) answer($('swap-result'), `${swapSent.name}: ${r.accepted ? 'accepted' : 'refused'}: ${r.message}`, r.accepted ? 'ok' : 'bad');
}
$('swap-send').onclick = async () => {
  const file = $('swap-file').files[0];
  if (!file) { answer($('swap-result'), 'Choose an assembly file (YAML) first.', 'bad'); return; }
  if (file.size > MAX_ASSEMBLY_BYTES) { answer($('swap-result'), `${file.name} is ${(file.size / 1024).toFixed(0)} KiB: at most ${MAX_ASSEMBLY_BYTES / 1024} KiB.`, 'bad'); return; }
  const content = await file.text();
  if (!content.trim()) { answer($('swap-result'), `${file.name} is empty.`, 'bad'); return; }
  if (!await confirmDialog(`Hot swap the simulated robot to the assembly in ${file.name}: the module tree changes and the model gets a new version` +
    (model ? ` after version ${model.version}` : '') + '.', 'Yes, swap the robot')) {
    answer($('swap-result'), 'swap cancelled');
    return;
  }
  const cmd = { request_id: requestId(), kind: 'SIM_SWAP_ASSEMBLY', name: file.name, content, source: 'concert gui' };
  answer($('swap-result'), `${file.name}: sending…`);
  try {
    await link.publish('concert/sim/command', cmd);
    swapSent = { request_id: cmd.request_id, name: file.name };
    answer($('swap-result'), `${file.name}: sent (request ${cmd.request_id}); waiting for the simulator`);
    renderSwap();
  } catch (e) {
    answer($('swap-result'), `${file.name} not sent: ${e.message}`, 'bad');
  }
};
gate($('swap-send'), 'concert/sim/command');

// ---- robot: camera. Frames carry their camera's name (header.sensor); several cameras share
// a topic, so only the chosen one is shown, named in the caption, greyed when it stops.
let cameraUrl = null;
let cameraSensor = '';       // the chosen camera ('' until one is heard or chosen)
let cameraLast = null;       // {header, at: now()} of the last frame shown
const cameraNames = new Set();
function cameraOptions() {
  const names = [...cameraNames].sort();
  const html = names.length ? names.map((n) => `<option value="${esc(n)}">${esc(n)}</option>`).join('') : '<option value="">none heard yet</option>';
  if ($('camera-sensor').innerHTML !== html) $('camera-sensor').innerHTML = html;
  $('camera-sensor').value = cameraSensor;
}
function renderCamera() {
  const topic = $('camera-topic').value;
  const kind = topic.endsWith('depth') ? 'depth' : 'colour';
  let text;
  if (!topic) text = 'camera off';
  else if (!cameraSensor) text = `waiting for a ${kind} camera`;
  else if (!cameraLast) text = `${cameraSensor} (${kind}): waiting for its first frame`;
  else {
    const age = (now() - cameraLast.at) / 1000;
    const h = cameraLast.header;
    text = `${cameraSensor} (${kind}), ${h.width}×${h.height}` + (age > 2.5 ? `: no frame for ${age.toFixed(0)} s (the picture is old)` : '');
  }
  $('camera-name').textContent = text;
  $('camera').classList.toggle('stale', !cameraLast || now() - cameraLast.at > 2500);
}
function clearCamera() {
  cameraLast = null;
  $('camera').removeAttribute('src');
  if (cameraUrl) { URL.revokeObjectURL(cameraUrl); cameraUrl = null; }
}
function addCameras(names) {
  let added = false;
  for (const n of names) if (n && !cameraNames.has(n)) { cameraNames.add(n); added = true; }
  if (!cameraSensor && cameraNames.size) cameraSensor = [...cameraNames].sort()[0];
  if (added) cameraOptions();
}
$('camera-topic').onchange = () => {
  const topic = $('camera-topic').value;
  clearCamera();
  if (!topic) { for (const t of [...link.frames.keys()]) link.unwatchFrames(t); renderCamera(); return; }
  link.watchFrames(topic, (header, blob) => {
    addCameras([header.sensor]);
    if (header.sensor !== cameraSensor) return;  // another camera on the same topic
    if (cameraUrl) URL.revokeObjectURL(cameraUrl);
    cameraUrl = URL.createObjectURL(blob);
    $('camera').src = cameraUrl;
    $('camera').alt = `${header.sensor} ${header.width}x${header.height}`;
    cameraLast = { header, at: now() };
    renderCamera();
  }, 2);
  renderCamera();
};
$('camera-sensor').onchange = () => {
  cameraSensor = $('camera-sensor').value;
  clearCamera();  // never show one camera's last frame under another's name
  renderCamera();
};

// ---- missions: drilling. The mission sent from here is followed by its id: the drill service
// answers a refusal with a DrillStatus for that id (DRILL_FAILED, the reason, never running).
initBuilder();
setMissionYaml('name: gui mission\ndepth: 0.03\nareas:\n  - {name: blobs, marks: blobs, point: [2.2, 0.03, 1.2], expected: 1}\n');
const drills = new Map();  // mission_id -> DrillStatus
let drillSent = null;      // {id, sent: now(), running: whether it was seen running}
function drillBlocked() {
  if (!alive('drill')) return 'the drill service is not running';
  if (!model) return 'no robot model yet';
  if (!model.end_effectors.some((e) => e.kind === 'drill')) return `the robot (model version ${model.version}) has no drill end-effector`;
  return '';
}
function renderDrill() {
  const mine = drillSent ? drills.get(drillSent.id) : null;
  const latest = [...drills.values()].sort((a, b) => b.stamp_ns - a.stamp_ns)[0];
  const s = drillSent ? mine : latest;
  if (s) {
    const areas = s.areas.map((a) => `<li>${esc(a.name)}: ${a.state.replace('AREA_', '').toLowerCase()} ${esc(a.reason)} (${a.holes.filter((h) => h.state === 'HOLE_DRILLED').length}/${a.holes.length} holes)</li>`).join('');
    $('drill-status').innerHTML = `<b>${esc(s.mission)}</b> <span class="small">(mission ${s.mission_id})</span>: ${s.state.replace('DRILL_', '').toLowerCase()} ` +
      `<span class="small">${esc(s.active)}</span> ${esc(s.reason)}<ul>${areas}</ul>` +
      `<span class="small">${s.holes_drilled} drilled of ${s.holes_marked} marked, ${s.time_total.toFixed(1)} s</span>`;
  } else if (drillSent) {
    $('drill-status').innerHTML = `mission ${drillSent.id}: no status yet` +
      (latest ? ` <span class="small">(the latest other mission, ${latest.mission_id} '${esc(latest.mission)}', is ${latest.state.replace('DRILL_', '').toLowerCase()})</span>` : '');
  }
  if (!drillSent) return;
  const r = $('drill-result');
  if (!mine) {
    const waited = (now() - drillSent.sent) / 1000;
    answer(r, `mission ${drillSent.id} sent; waiting for the drill service` + (waited > 10 ? ` (no answer for ${waited.toFixed(0)} s)` : ''), waited > 10 ? 'bad' : '');
    return;
  }
  switch (mine.state) {
    case 'DRILL_FAILED':
      answer(r, `${drillSent.running || mine.time_total > 0 ? 'failed' : 'refused'}: ${mine.reason}`, 'bad'); break;
    case 'DRILL_ABORTED': answer(r, `aborted: ${mine.reason}`, 'bad'); break;
    case 'DRILL_SUCCEEDED': answer(r, `succeeded: ${mine.holes_drilled} holes drilled of ${mine.holes_marked} marked`, 'ok'); break;
    case 'DRILL_RUNNING': answer(r, `running: ${mine.active}`); break;
    default: answer(r, `accepted (${mine.state.replace('DRILL_', '').toLowerCase()})`);
  }
}
link.subscribe('concert/drill/status', (s) => {
  drills.set(s.mission_id, s);
  if (drillSent && s.mission_id === drillSent.id && s.state === 'DRILL_RUNNING') drillSent.running = true;
  renderDrill();
});
$('drill-start').onclick = () => {
  const yaml = $('drill-yaml').value;
  if (!yaml.trim()) { answer($('drill-result'), 'The mission file is empty.', 'bad'); return; }
  const id = requestId();
  // Followed from now on: its status may arrive before the gateway's ack.
  drillSent = { id, sent: now(), running: false };
  answer($('drill-result'), `mission ${id}: sending…`);
  link.publish('concert/drill/mission', { mission_id: id, source: 'concert gui', name: 'gui mission', yaml, base_dir: '' })
    .then(renderDrill)
    .catch((e) => {
      if (drillSent && drillSent.id === id) drillSent = null;
      answer($('drill-result'), `mission not sent: ${e.message}`, 'bad');
    });
};
$('drill-abort').onclick = () => {
  link.publish('concert/drill/abort', { mission_id: 0, source: 'concert gui', reason: 'operator abort' })
    .then(() => answer($('drill-result'), 'abort sent')).catch((e) => answer($('drill-result'), `abort not sent: ${e.message}`, 'bad'));
};
gate($('drill-start'), 'concert/drill/mission', drillBlocked, $('drill-why'));
gate($('drill-abort'), 'concert/drill/abort');

// ---- missions: the storey seen from above. The walls and obstacles are the world every service
// reads (concert/world/world: with `concert up --ifc` the simulator's world made from the IFC
// storey, walls with their door openings as gaps); the robot's pose is nav's localisation in the
// map when nav localises, else the simulator's truth (labelled so), else none. A tap on a wall
// picks the nearest point of its nearest face; "add" appends it to the mission YAML as a point
// area (drill README: `point` is in the world/map frame, the height from the field). A wall made
// from the IFC (named wall_<GlobalId>_<k>) can be added as a BIM wall area instead (`wall:`
// GlobalId, `at: [s, h]`). In "drive" mode a tap picks a goal for the base (concert/nav/goal).
// The map pans and zooms (panzoom.js: drag, pinch, wheel, the buttons; "Fit" shows everything);
// a tap that did not move picks. Map coordinates are (x, -y) of the world: SVG's y points down.
const POSE_FRESH_MS = 1000;
let world = null, poseNav = null, poseTruth = null, picked = null;
let bimMode = 'pick', navTarget = null, navSent = null;
const navStatuses = new Map();  // request_id -> NavStatus
/// The view showing every wall and obstacle, the robot and the goal, with a margin.
let bimFit = { x: -1, y: -1, w: 2, h: 2 };
let bimFrame = 0;  // a pending redraw after a pan or zoom
const bimPan = new PanZoom($('bim'), {
  fit: () => bimFit,
  onTap: (cx, cy) => bimTap(cx, cy),
  onChange: () => { if (!bimFrame) bimFrame = requestAnimationFrame(() => { bimFrame = 0; renderBim(); }); },
});
$('bim-zoom-in').onclick = () => bimPan.zoomBy(1 / 1.5);
$('bim-zoom-out').onclick = () => bimPan.zoomBy(1.5);
$('bim-fit').onclick = () => bimPan.reset();
link.subscribe('concert/world/world', (w) => {
  if (world && world.source !== w.source) bimPan.reset();  // another building: show all of it
  world = w;
  if (picked && !world.walls.some((x) => x.name === picked.wall)) bimPick(null);
  renderBim();
});
link.subscribe('concert/nav/localisation', (l) => { poseNav = { ...l.pose, seen: now(), state: l.state }; }, 4);
link.subscribe('concert/sim/truth', (t) => { poseTruth = { x: t.x, y: t.y, yaw: t.yaw, seen: now() }; }, 4);
/// The robot's pose and where it comes from, or null: never a made-up (0, 0).
function robotPose() {
  if (poseNav && now() - poseNav.seen < POSE_FRESH_MS && poseNav.state !== 'LOCALISATION_NONE') {
    return { ...poseNav, src: `nav localisation, ${poseNav.state.replace('LOCALISATION_', '').toLowerCase()}`, truth: false };
  }
  if (poseTruth && now() - poseTruth.seen < POSE_FRESH_MS) return { ...poseTruth, src: 'simulator truth: nav does not localise', truth: true };
  return null;
}
// Where a BIM wall's `s` is counted from, per GlobalId (0: the wall's end at the lower x, or y
// for a wall along y; 1: the other). The world does not carry the IFC axis's direction (libs/bim
// takes it from where the authoring tool started drawing the wall), so the operator chooses, and
// the map marks the end chosen.
const bimWallFrom = new Map();
/// Picks the face point nearest to world (px, py); null clears the pick.
function bimPick(px, py) {
  const best = world && px !== null ? pickWall(world.walls, px, py) : null;
  if (!best) {
    picked = null;
    $('bim-picked').textContent = px === null ? 'Tap a wall to pick a point on it.' : `(${px.toFixed(2)}, ${py.toFixed(2)}) m is not on a wall: tap closer to one.`;
  } else {
    const id = bimWallId(best.wall);
    picked = { ...best, bim: id ? { id, ...wallSpan(world.walls, id, best.x, best.y) } : null };
    $('bim-picked').textContent = `picked: ${best.wall}, face ${best.face}, at (${best.x.toFixed(3)}, ${best.y.toFixed(3)}) m`;
  }
  $('bim-add').disabled = !picked;
  renderBimWall();
  renderBim();
}
/// The picked BIM wall's s [m] from the end chosen, that end, and the face tapped (left or right
/// of the axis running from that end).
function bimWallAt() {
  const b = picked.bim, from = bimWallFrom.get(b.id) || 0;
  return { from, s: from === 0 ? b.s : b.length - b.s, end: b.ends[from], face: wallFace(b, from, picked.x, picked.y) };
}
function renderBimWall() {
  const b = picked && picked.bim;
  $('bim-wall').hidden = !b;
  if (!b) return;
  const { from, s, face } = bimWallAt();
  const xy = (p) => `(${p[0].toFixed(2)}, ${p[1].toFixed(2)})`;
  $('bim-wall-text').textContent = `BIM wall ${b.id}, ${b.length.toFixed(2)} m long: s = ${s.toFixed(2)} m from the end at ${xy(b.ends[from])} ` +
    `(ringed on the map); the face tapped is the ${face} one, seen along the axis from that end. The world does not say ` +
    "at which end the wall's IFC axis starts: choose it here (s and the face follow).";
  for (const btn of $('bim-wall-from').querySelectorAll('button')) {
    const end = Number(btn.dataset.end);
    btn.textContent = `s from ${xy(b.ends[end])}`;
    btn.classList.toggle('active', end === from);
    btn.onclick = () => { bimWallFrom.set(b.id, end); renderBimWall(); renderBim(); };
  }
}
/// A tap on the map (a press that did not move): a pick, or a drive goal.
function bimTap(cx, cy) {
  if (!world) return;
  const p = bimPan.toMap(cx, cy);
  if (!p) return;
  if (bimMode === 'pick') { bimPick(p.x, -p.y); return; }
  navTarget = { x: p.x, y: -p.y };
  renderBim();
  renderNav();
}
function bimToScreen(x, y) {  // for the browser test: where world (x, y) is on the screen
  const p = new DOMPoint(x, -y).matrixTransform($('bim').getScreenCTM());
  return { x: p.x, y: p.y };
}
window.concertBim = { toScreen: bimToScreen, picked: () => picked, view: () => bimPan.view() };
for (const b of document.querySelectorAll('#bim-mode button')) {
  b.onclick = () => {
    bimMode = b.dataset.mode;
    for (const o of document.querySelectorAll('#bim-mode button')) o.classList.toggle('active', o === b);
    $('bim-pick-controls').hidden = bimMode !== 'pick';
    $('nav-controls').hidden = bimMode !== 'drive';
    renderBim();
    renderNav();
  };
}
/// The height field's value [m], or null (saying why).
function bimHeight() {
  const h = parseFloat($('bim-height').value);
  if (Number.isFinite(h) && h >= 0) return h;
  $('bim-added').textContent = 'the height must be a number of metres, 0 or more';
  return null;
}
$('bim-add').onclick = () => {
  if (!picked) return;
  const h = bimHeight();
  if (h === null) return;
  const added = addPointArea($('drill-yaml').value, [picked.x, picked.y, h], $('bim-marks').value);
  setMissionYaml(added.yaml);
  $('bim-added').textContent = `area ${added.name} added to the mission file`;
};
$('bim-add-wall').onclick = () => {
  if (!picked || !picked.bim) return;
  const h = bimHeight();
  if (h === null) return;
  const { s, face } = bimWallAt();
  const added = addWallArea($('drill-yaml').value, picked.bim.id, [s, h], $('bim-marks').value, face);
  setMissionYaml(added.yaml);
  const m = mission();
  $('bim-added').textContent = `area ${added.name} (BIM wall ${picked.bim.id}, s ${s.toFixed(2)} m, h ${h.toFixed(2)} m, face ${face}) added to the mission file` +
    (m.ok && !m.fields.ifc ? '; the mission needs the IFC file: fill in "IFC file on the robot"' : '');
};
stepper($('bim-height'), { step: 0.05, digits: 2, unit: ' m', name: 'height', presets: [0.5, 1.0, 1.5, 2.0].map((v) => [v, `${v.toFixed(1)} m`]) });
onMissionChange(() => renderBim());
/// The heading of a drive goal: along the way from the robot to the goal (0 when the pose is unknown).
function goalYaw() {
  const pose = robotPose();
  return pose && navTarget ? Math.atan2(navTarget.y - pose.y, navTarget.x - pose.x) : 0;
}
function navBlocked() {
  if (!alive('nav')) return 'the nav service is not running';
  if (!navTarget) return 'tap the storey where the base should go';
  return '';
}
function renderNav() {
  $('nav-goal-text').textContent = navTarget
    ? `goal (${navTarget.x.toFixed(2)}, ${navTarget.y.toFixed(2)}) m, heading ${(goalYaw() * 180 / Math.PI).toFixed(0)}°`
    : 'Tap the storey where the base should go.';
  applyGate($('nav-go'));
  applyGate($('nav-cancel'));
  if (!navSent) return;
  const s = navStatuses.get(navSent.id);
  if (!s) { answer($('nav-result'), `goal ${navSent.id} sent; waiting for the nav service`); return; }
  const state = s.state.replace('NAV_', '').toLowerCase();
  const bad = ['failed', 'refused', 'cancelled'].includes(state);
  answer($('nav-result'), `goal ${navSent.id}: ${state}` + (s.reason ? `: ${s.reason}` : '') +
    (state === 'following' || state === 'planning' ? `, ${s.distance_remaining.toFixed(1)} m to go` : ''), bad ? 'bad' : state === 'reached' ? 'ok' : '');
}
$('nav-go').onclick = async () => {
  if (navBlocked()) return;
  const target = { ...navTarget, yaw: goalYaw() };
  if (!await confirmDialog(`Drive the base to (${target.x.toFixed(2)}, ${target.y.toFixed(2)}) m, heading ${(target.yaw * 180 / Math.PI).toFixed(0)}°?`, 'Yes, drive')) return;
  const nav = alive('nav');
  const cmd = { request_id: requestId(), model_version: nav && nav.model_version ? nav.model_version : model ? model.version : 0,
    kind: 'NAV_GOAL_POSE', pose: target, source: 'concert gui' };
  try {
    await link.publish('concert/nav/goal', cmd);
    navSent = { id: cmd.request_id };
    renderNav();
  } catch (e) {
    answer($('nav-result'), `goal not sent: ${e.message}`, 'bad');
  }
};
$('nav-cancel').onclick = () => {
  link.publish('concert/nav/cancel', { request_id: 0, source: 'concert gui' })
    .then(() => answer($('nav-result'), 'cancel sent (whatever goal runs)'))
    .catch((e) => answer($('nav-result'), `cancel not sent: ${e.message}`, 'bad'));
};
gate($('nav-go'), 'concert/nav/goal', navBlocked, $('nav-why'));
gate($('nav-cancel'), 'concert/nav/cancel');
function renderBim() {
  const svg = $('bim');
  const pose = robotPose();
  $('bim-missing').textContent = world ? '' : 'No world yet (concert/world/world, from the robot service: `concert up --world FILE` or `--ifc FILE`).';
  $('bim-source').textContent = world ? `${world.source.split('/').pop()} v${world.version}` : '';
  svg.replaceChildren();
  svg.style.display = world ? '' : 'none';
  if (!world) return;
  // The fit view: every wall and obstacle, the robot, the goal, a margin (follows the world and
  // the robot until the operator pans or zooms).
  const xs = [0], ys = [0];
  for (const w of [...world.walls, ...world.obstacles]) {
    if (w.type === 'WORLD_CYLINDER') {
      xs.push(w.position[0] - w.size[0], w.position[0] + w.size[0]); ys.push(w.position[1] - w.size[0], w.position[1] + w.size[0]);
      continue;
    }
    const c = Math.cos(w.yaw), s = Math.sin(w.yaw), hx = w.size[0] / 2, hy = w.size[1] / 2;
    for (const [a, b] of [[hx, hy], [hx, -hy], [-hx, hy], [-hx, -hy]]) { xs.push(w.position[0] + c * a - s * b); ys.push(w.position[1] + s * a + c * b); }
  }
  if (pose) { xs.push(pose.x); ys.push(pose.y); }
  if (navTarget) { xs.push(navTarget.x); ys.push(navTarget.y); }
  const ymax = Math.max(...ys) + 0.5;
  bimFit = { x: Math.min(...xs) - 0.5, y: -ymax, w: Math.max(...xs) - Math.min(...xs) + 1, h: Math.max(...ys) - Math.min(...ys) + 1 };
  bimPan.apply();
  // Labels and marks keep their size on the screen whatever the zoom.
  const px = 1 / (bimPan.scale() || 40);  // map units per screen pixel
  svg.style.setProperty('--label', `${(13 * px).toFixed(4)}px`);
  // The grid, 1 m, over the view and its letterbox margins.
  const v = bimPan.view(), pad = Math.max(v.w, v.h);
  const gx0 = Math.floor(v.x - pad), gx1 = Math.ceil(v.x + v.w + pad), gy0 = Math.floor(v.y - pad), gy1 = Math.ceil(v.y + v.h + pad);
  if ((gx1 - gx0) + (gy1 - gy0) < 600) {
    for (let gx = gx0; gx <= gx1; gx++) svg.append(svgEl('line', { class: 'grid', x1: gx, x2: gx, y1: gy0, y2: gy1 }));
    for (let gy = gy0; gy <= gy1; gy++) svg.append(svgEl('line', { class: 'grid', y1: gy, y2: gy, x1: gx0, x2: gx1 }));
  }
  const draw = (w, cls) => {
    const deg = -w.yaw * 180 / Math.PI;
    if (w.type === 'WORLD_CYLINDER') {
      svg.append(svgEl('circle', { class: cls, cx: w.position[0], cy: -w.position[1], r: w.size[0] }));
    } else {
      svg.append(svgEl('rect', { class: cls, 'data-wall': w.name, x: -w.size[0] / 2, y: -w.size[1] / 2, width: w.size[0], height: w.size[1],
        transform: `translate(${w.position[0]} ${-w.position[1]}) rotate(${deg})` }));
    }
  };
  for (const w of world.walls) draw(w, 'wall-box');
  for (const o of world.obstacles) draw(o, 'obstacle');
  if (pose) {
    const deg = -pose.yaw * 180 / Math.PI;
    svg.append(svgEl('path', { class: 'robot-pose' + (pose.truth ? ' truth' : ''), d: 'M0.45,0 L-0.3,0.3 L-0.3,-0.3 Z', transform: `translate(${pose.x} ${-pose.y}) rotate(${deg})` }));
    svg.append(svgEl('text', { x: pose.x + 0.4, y: -pose.y - 0.35 }, pose.truth ? 'robot (simulator truth)' : 'robot (nav)'));
  }
  // The mission's point areas, named.
  const m = mission();
  if (m.ok) {
    for (const a of m.areas) {
      if (!a.point) continue;
      svg.append(svgEl('circle', { class: 'mission-area', cx: a.point[0], cy: -a.point[1], r: 5 * px }));
      svg.append(svgEl('text', { class: 'mission-area-label', x: a.point[0] + 7 * px, y: -a.point[1] + 4 * px }, a.name || ''));
    }
  }
  if (picked && bimMode === 'pick') {
    if (picked.bim) {  // s along the wall, from the end chosen (ringed)
      const { end } = bimWallAt(), b = picked.bim;
      const dx = b.ends[1][0] - b.ends[0][0], dy = b.ends[1][1] - b.ends[0][1], k = b.s / (b.length || 1);
      const foot = [b.ends[0][0] + dx * k, b.ends[0][1] + dy * k];
      svg.append(svgEl('line', { class: 'wall-s', x1: end[0], y1: -end[1], x2: foot[0], y2: -foot[1] }));
      svg.append(svgEl('circle', { class: 'wall-start', cx: end[0], cy: -end[1], r: 9 * px }));
      svg.append(svgEl('text', { x: end[0] + 11 * px, y: -end[1] - 8 * px }, 's = 0'));
    }
    svg.append(svgEl('circle', { class: 'pick', cx: picked.x, cy: -picked.y, r: Math.max(0.09, 6 * px) }));
  }
  if (navTarget && bimMode === 'drive') svg.append(svgEl('circle', { class: 'goal', cx: navTarget.x, cy: -navTarget.y, r: 0.25 }));
  $('bim-info').textContent = `${world.walls.length} walls, ${world.obstacles.length} obstacles; grid 1 m; ` +
    (pose ? `robot at (${pose.x.toFixed(2)}, ${pose.y.toFixed(2)}) m, ${(pose.yaw * 180 / Math.PI).toFixed(0)}° (${pose.src})` : 'robot pose unknown (neither nav nor the simulator publishes it)');
}

// ---- missions: the sanding/spraying panel (paper Fig. 15). The surface_finish service
// publishes the predetermined areas of the mounted tool for each model version
// (concert/finish/areas, latched); the operator picks one (optionally reshaped inside it), sets
// the force (sanding) and speed, and starts: a FinishCommand on concert/finish/command carrying
// the areas' model version (the service refuses any other). Runs report on concert/finish/status.
let finishAvailable = false;
let finishAreas = null;   // the latest FinishAreas
let finishChosen = null;  // area id
const finishRuns = new Map();  // request_id -> FinishStatus
const finishRect = () => ['x0', 'x1', 'y0', 'y1'].map((k) => parseFloat($('finish-' + k).value));
function finishChoose(id) {
  finishChosen = id;
  const a = finishAreas && finishAreas.areas.find((x) => x.id === id);
  if (a) {
    $('finish-x0').value = a.x0.toFixed(2); $('finish-x1').value = a.x1.toFixed(2);
    $('finish-y0').value = a.y0.toFixed(2); $('finish-y1').value = a.y1.toFixed(2);
  }
  renderFinish();
}
/// Why the start button is disabled ('' when it is not), besides the role.
function finishBlocked() {
  if (!finishAvailable) return 'no surface finishing topics in this build';
  const svc = alive('surface_finish');
  if (!svc) return 'the surface_finish service is not running';
  if (!finishAreas) return 'no areas from the surface_finish service yet';
  if (!finishAreas.tool) return finishAreas.reason || 'the mounted robot carries no sanding or spraying tool';
  if (model && finishAreas.model_version !== model.version) {
    return `the areas are for model version ${finishAreas.model_version}, the robot is at version ${model.version}: the service is computing the new areas`;
  }
  if (!finishChosen) return 'choose an area';
  return '';
}
function renderFinish() {
  const svc = alive('surface_finish');
  if (!finishAvailable) {
    $('finish-missing').textContent = 'No surface finishing topics (concert/finish/*) in this build.';
  } else if (!svc) {
    $('finish-missing').textContent = 'The surface_finish service is not running: sanding and spraying unavailable (start concert_surface_finish).';
  } else {
    $('finish-missing').textContent = svc.state === 'SERVICE_RECONFIGURING' ? 'surface_finish: ' + svc.message : '';
  }
  const a = finishAreas;
  const tool = a ? a.tool : '';
  $('finish-tool').textContent = a ? (tool ? `${tool === 'sand' ? 'sanding' : 'spraying'} tool, model version ${a.model_version}` : 'no tool') : '';
  $('finish-force-label').style.display = tool === 'spray' ? 'none' : '';
  $('finish-rect').classList.toggle('off', !$('finish-reshape').checked);
  $('finish-start').textContent = tool === 'spray' ? 'Start spraying' : tool === 'sand' ? 'Start sanding' : 'Start';
  applyGate($('finish-start'));
  // The area buttons (touch) and the wall drawing (wall coordinates: x lateral to the right seen
  // from the robot, y height above the floor).
  const areas = a ? a.areas : [];
  const buttons = areas.map((x) => `<button class="action area${x.id === finishChosen ? ' active' : ''}" data-area="${esc(x.id)}">${esc(x.id)}</button>`).join('');
  if ($('finish-areas').innerHTML !== buttons) {
    $('finish-areas').innerHTML = buttons || '<span class="small">none</span>';
    for (const b of $('finish-areas').querySelectorAll('button.area')) b.onclick = () => finishChoose(b.dataset.area);
  }
  const svg = $('finish-wall');
  svg.replaceChildren();
  svg.style.display = areas.length ? '' : 'none';
  if (!areas.length) {
    $('finish-info').textContent = a ? 'no areas: ' + (a.reason || 'none for this model') : '';
    return;
  }
  const xs = areas.flatMap((x) => [x.x0, x.x1]), ys = areas.flatMap((x) => [x.y1]);
  const xmin = Math.min(-0.5, ...xs) - 0.2, xmax = Math.max(0.5, ...xs) + 0.2, ymax = Math.max(...ys) + 0.25;
  const W = 200, H = 120, s = Math.min((W - 10) / (xmax - xmin), (H - 12) / ymax);
  const X = (x) => 5 + (x - xmin) * s + ((W - 10) - (xmax - xmin) * s) / 2, Y = (y) => H - 8 - y * s;
  svg.append(svgEl('line', { class: 'floor', x1: 0, x2: W, y1: Y(0), y2: Y(0) }));
  svg.append(svgEl('path', { class: 'robot', d: `M${X(0) - 4},${Y(0)} L${X(0) + 4},${Y(0)} L${X(0)},${Y(0) - 5} Z` }));
  svg.append(svgEl('text', { x: X(0) + 5, y: Y(0) + 6 }, `robot, ${a.wall_distance.toFixed(2)} m from the wall`));
  for (const x of [...areas].sort((p, q) => (q.x1 - q.x0) - (p.x1 - p.x0))) {  // the band ('all') first, below
    const r = svgEl('rect', { class: (x.id === 'all' ? 'band area' : 'area') + (x.id === finishChosen ? ' active' : ''), 'data-area': x.id,
      x: X(x.x0), y: Y(x.y1), width: (x.x1 - x.x0) * s, height: (x.y1 - x.y0) * s });
    r.onclick = () => finishChoose(x.id);
    svg.append(r);
    if (x.id !== 'all') svg.append(svgEl('text', { x: X(x.x0) + 1.5, y: Y(x.y1) - 1.5 }, x.id));
  }
  const band = areas.find((x) => x.id === 'all') || areas[0];
  svg.append(svgEl('text', { x: X(band.x1) + 2, y: Y(band.y1) + 4 }, `${band.y1.toFixed(2)} m`));
  svg.append(svgEl('text', { x: X(band.x1) + 2, y: Y(band.y0) }, `${band.y0.toFixed(2)} m`));
  if ($('finish-reshape').checked && finishChosen) {
    const [x0, x1, y0, y1] = finishRect();
    if ([x0, x1, y0, y1].every(Number.isFinite) && x1 > x0 && y1 > y0) {
      svg.append(svgEl('rect', { class: 'reshaped', x: X(x0), y: Y(y1), width: (x1 - x0) * s, height: (y1 - y0) * s }));
    }
  }
  $('finish-info').textContent = `${a.standoff > 0 ? 'standoff ' + a.standoff.toFixed(2) + ' m' : 'in contact'}, tool roll ${(a.roll * 180 / Math.PI).toFixed(0)}°; ` +
    areas.map((x) => `${x.id}: x ${x.x0.toFixed(2)}..${x.x1.toFixed(2)} m, height ${x.y0.toFixed(2)}..${x.y1.toFixed(2)} m`).join('; ');
}
function renderFinishStatus() {
  const s = [...finishRuns.values()].sort((p, q) => q.stamp_ns - p.stamp_ns)[0];
  if (!s) return;
  let report = '';
  if (s.report_json) {
    try {
      const r = JSON.parse(s.report_json);
      report = `<br>coverage ${r.coverage_percent} %, overspray ${r.overspray_m2} m², max |Δh| ${r.max_abs_delta_h_mm} mm, coat width error ≤ ${r.max_width_error_mm} mm`;
    } catch (e) { report = '<br>report unreadable: ' + esc(e.message); }
  }
  const state = s.state.replace('FINISH_', '').toLowerCase();
  // The service publishes RUNNING when the path starts and the result at its end; the elapsed
  // time is this browser's, counted from that RUNNING status's arrival.
  const running = state === 'running' && s.seen ? (now() - s.seen) / 1000 : null;
  const progress = running !== null && s.progress === 0 && s.duration > 0 ? Math.min(running / s.duration, 1) : s.progress;
  $('finish-status').innerHTML = `request ${s.request_id}: <b data-testid="finish-state">${state}</b> ` +
    `<span class="${state === 'failed' || state === 'aborted' ? 'fault' : 'small'}">${esc(s.reason)}</span>` +
    `<progress max="1" value="${progress}"></progress>` +
    `<span class="small">${s.strokes} strokes, ${running !== null ? `${running.toFixed(0)} s of ` : ''}${s.duration.toFixed(1)} s planned` +
    (s.wall_distance > 0 ? `, wall ${s.wall_distance.toFixed(2)} m away` : '') + `</span>${report}`;
}
link.subscribe('concert/finish/areas', (a) => {
  finishAreas = a;
  if (!a.areas.some((x) => x.id === finishChosen)) finishChosen = null;
  renderFinish();
});
link.subscribe('concert/finish/status', (s) => {
  const before = finishRuns.get(s.request_id);
  finishRuns.set(s.request_id, { ...s, seen: before && before.state === s.state ? before.seen : now() });
  renderFinishStatus();
});
$('finish-reshape').onchange = renderFinish;
for (const k of ['x0', 'x1', 'y0', 'y1']) $('finish-' + k).oninput = renderFinish;
$('finish-start').onclick = () => {
  const blocked = finishBlocked();
  if (blocked) { $('finish-result').textContent = blocked; return; }
  const sand = finishAreas.tool === 'sand';
  const cmd = {
    request_id: requestId(), model_version: finishAreas.model_version,
    verb: sand ? 'FINISH_SAND' : 'FINISH_SPRAY', area: finishChosen,
    speed: parseFloat($('finish-speed').value) || 0, force: sand ? parseFloat($('finish-force').value) || 0 : 0,
  };
  if ($('finish-reshape').checked) {
    const [x0, x1, y0, y1] = finishRect();
    if (![x0, x1, y0, y1].every(Number.isFinite) || x1 <= x0 || y1 <= y0) {
      $('finish-result').textContent = 'reshaped area: x from < x to and height from < height to, in metres';
      return;
    }
    Object.assign(cmd, { has_rect: true, x0, x1, y0, y1 });
  }
  link.publish('concert/finish/command', cmd)
    .then(() => { $('finish-result').textContent = `${sand ? 'sanding' : 'spraying'} of ${cmd.area} sent (request ${cmd.request_id})`; })
    .catch((e) => { $('finish-result').textContent = 'not sent: ' + e.message; });
};
$('finish-abort').onclick = () => {
  link.publish('concert/finish/command', { request_id: requestId(), verb: 'FINISH_ABORT', model_version: finishAreas ? finishAreas.model_version : 0 })
    .then(() => { $('finish-result').textContent = 'abort sent'; }).catch((e) => { $('finish-result').textContent = 'abort not sent: ' + e.message; });
};
gate($('finish-start'), 'concert/finish/command', finishBlocked, $('finish-why'));
stepper($('finish-force'), { step: 1, digits: 0, unit: ' N', name: 'sanding force', presets: [15, 25, 35] });
stepper($('finish-speed'), { step: 0.05, digits: 2, unit: ' m/s', name: 'speed',
  presets: [[0, 'default'], [0.05, '0.05 m/s'], [0.1, '0.10 m/s'], [0.2, '0.20 m/s']] });
gate($('finish-abort'), 'concert/finish/command');

// Pages whose service or message types are not in this build say so (and which ones); the
// optional topics are subscribed once the catalogue says they exist.
let transportBuilt = false;
function renderOptional() {
  finishAvailable = link.hasTopic('concert/finish/command') && link.hasTopic('concert/finish/areas');
  renderFinish();
  $('swap-panel').hidden = !link.hasTopic('concert/sim/command');
  subscribeIf('concert/sim/reply', (r) => { simReplies.set(r.request_id, r); renderSwap(); });
  subscribeIf('concert/sensors/list', (l) => addCameras(l.sensors.filter((s) => s.kind === 'SENSOR_RGBD').map((s) => s.name)));
  const canDrive = link.hasTopic('concert/nav/goal');
  $('bim-mode').hidden = !canDrive;
  if (canDrive) subscribeIf('concert/nav/status', (s) => { navStatuses.set(s.request_id, s); renderNav(); });
  if (link.hasTopic('concert/collab/command')) {
    if (transportBuilt) return;
    transportBuilt = true;
    const modes = ['teaching', 'autonomous', 'follow-me', 'stop', 'open', 'close', 'lift', 'place'];
    $('transport-panel').innerHTML = '<div id="collab-missing" class="missing"></div><p>State: <b id="collab-state">?</b> ' +
      '<span id="collab-last" class="small"></span></p><div class="row">' +
      modes.map((m) => `<button class="action mode" data-mode="${m}">${m}</button>`).join('') + '</div><p id="collab-result" class="small"></p>';
    for (const b of document.querySelectorAll('#transport-panel button.mode')) {
      b.onclick = () => link.publish('concert/collab/command', { command_id: requestId(), text: b.dataset.mode })
        .then(() => { $('collab-result').textContent = b.dataset.mode + ' sent'; })
        .catch((e) => { $('collab-result').textContent = e.message; });
      gate(b, 'concert/collab/command');
    }
    link.subscribe('concert/collab/state', (c) => {
      $('collab-state').textContent = c.state || c.mode;
      $('collab-last').textContent = c.command ? `last: ${c.command} ${c.accepted ? 'accepted' : 'ignored: ' + c.reason}` : '';
      for (const b of document.querySelectorAll('#transport-panel button.mode')) {
        b.classList.toggle('active', c.mode.replace('COLLAB_', '').toLowerCase().replace('_', '-') === b.dataset.mode);
      }
    });
  } else {
    $('transport-panel').innerHTML = '<p class="missing">No collaborative-transport topics in this build.</p>';
  }
}
link.on('hello', () => { renderOptional(); renderTopics(); refreshGates(); });
onAccessChange(() => { renderNav(); renderTopics(); });

// ---- topics
let lastRates = new Map();
link.rates.add((list) => { lastRates = new Map(list.map((r) => [r.topic, r])); renderTopics(); });
function renderTopics() {
  if (!link.hello) return;
  // The last column: the least role that may command the topic.
  const who = (t) => (t.commandable ? esc(roleFor(t.topic) || 'yes') : '');
  $('topics').querySelector('tbody').innerHTML = link.hello.topics.map((t) => {
    const r = lastRates.get(t.topic) || { hz: 0, count: 0, age_s: -1 };
    if (t.kind === 'command' && r.count === 0) {
      return `<tr><td>${esc(t.topic)}</td><td class="small">${esc(t.type.replace('concert::msg::', ''))}</td><td>${t.kind}</td>` +
        `<td colspan="3" class="small">not watched (commands are read only on demand)</td><td>${who(t)}</td></tr>`;
    }
    return `<tr><td>${esc(t.topic)}</td><td class="small">${esc(t.type.replace('concert::msg::', ''))}</td><td>${t.kind}</td>` +
      `<td class="num">${r.hz.toFixed(1)}</td><td class="num">${r.count}</td><td class="num">${r.age_s < 0 ? '–' : r.age_s.toFixed(1)}</td><td>${who(t)}</td></tr>`;
  }).join('');
}

setInterval(() => {
  renderServices();
  need('safety', $('safety-missing'), 'the safety state and reset');
  need('drill', $('drill-missing'), 'drilling missions');
  if ($('collab-missing')) need('collab', $('collab-missing'), 'the transport modes');
  refreshGates();
  renderFinish();
  renderFinishStatus();
  renderBim();
  renderNav();
  renderDrill();
  renderCustom();
  renderCamera();
}, 1000);
