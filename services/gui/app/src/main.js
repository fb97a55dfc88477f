// The operator GUI: Robot (module tree, model, 3D view, customisation, camera), Missions
// (drilling, the storey view, sanding/spraying), Transport, Safety (state, reasons, e-stop, reset), Topics.
import { Link } from './link.js';
import { Viewer } from './viewer.js';
import { addPointArea, pickWall } from './storey.js';

const $ = (id) => document.getElementById(id);
const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
const svgEl = (tag, attrs, text) => {
  const e = document.createElementNS('http://www.w3.org/2000/svg', tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
};
const link = new Link(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`);
window.concertLink = link;  // for the browser tests and the curious

// ---- pages
for (const b of document.querySelectorAll('#tabs button')) {
  b.onclick = () => {
    for (const o of document.querySelectorAll('#tabs button')) o.classList.toggle('active', o === b);
    for (const p of document.querySelectorAll('.page')) p.classList.toggle('active', p.id === 'page-' + b.dataset.page);
  };
}
link.onstate = (up) => {
  $('link').textContent = up ? 'gateway connected' : 'gateway lost: reconnecting';
  $('link').className = 'badge ' + (up ? 'ok' : 'bad');
};

// ---- services alive (heartbeats on concert/system/status every 200 ms)
const services = new Map();  // service@host -> {status, seen}
function alive(name) {
  const now = Date.now();
  for (const s of services.values()) {
    if (s.status.service === name && now - s.seen < 3000 && s.status.state !== 'SERVICE_STOPPED') return s.status;
  }
  return null;
}
function need(name, el, what) {
  const ok = !!alive(name);
  el.textContent = ok ? '' : `The ${name} service is not running: ${what} unavailable.`;
  return ok;
}
link.subscribe('concert/system/status', (s) => {
  services.set(s.service + '@' + s.host, { status: s, seen: Date.now() });
});
function renderServices() {
  const rows = [...services.values()].sort((a, b) => a.status.service.localeCompare(b.status.service)).map(({ status: s, seen }) => {
    const age = (Date.now() - seen) / 1000;
    const state = age > 3 ? `silent ${age.toFixed(0)} s` : s.state.replace('SERVICE_', '').toLowerCase();
    return `<tr><td>${esc(s.service)}</td><td>${esc(s.host)}</td><td>${esc(state)}</td><td>${s.model_version}</td><td>${esc(s.message)}</td></tr>`;
  });
  $('services').querySelector('tbody').innerHTML = rows.join('');
}

// ---- safety
let safety = null;
const estops = new Map();
link.subscribe('concert/safety/state', (s) => {
  safety = s;
  const stopped = s.mode === 'SAFETY_STOPPED';
  $('safety-mode').textContent = stopped ? 'STOPPED' : 'RUNNING';
  $('safety-badge').textContent = 'safety: ' + (stopped ? 'STOPPED' : 'RUNNING');
  $('safety-badge').className = 'badge ' + (stopped ? 'bad' : 'ok');
  $('safety-causes').innerHTML = s.causes.map((c) => `<li class="fault">${esc(c)}</li>`).join('') +
    (s.reset_required ? '<li>latched: release every input, then reset</li>' : '');
});
link.subscribe('concert/safety/estop', (e) => {
  estops.set(e.source, e);
  $('estop-inputs').innerHTML = [...estops.values()].map((i) =>
    `<li class="${i.engaged ? 'fault' : ''}">${esc(i.source.replace('ESTOP_', '').toLowerCase())}: ${i.engaged ? 'ENGAGED' : 'released'} ${esc(i.reason)}</li>`).join('');
});
$('estop').onclick = () => {
  link.publish('concert/safety/estop', { engaged: true, reason: 'operator GUI' })
    .then(() => { $('safety-result').textContent = 'software e-stop engaged'; })
    .catch((e) => { $('safety-result').textContent = 'e-stop NOT sent: ' + e.message; alert('E-stop not sent: ' + e.message); });
};
$('reset').onclick = async () => {
  try {
    await link.publish('concert/safety/estop', { engaged: false, reason: 'operator GUI' });
    await new Promise((r) => setTimeout(r, 300));  // the release reaches safety before the reset
    await link.publish('concert/safety/reset', { request_id: Date.now() % 4294967295, reason: 'operator GUI' });
    $('safety-result').textContent = 'reset sent';
  } catch (e) {
    $('safety-result').textContent = 'reset not sent: ' + e.message;
  }
};

// ---- robot: tree, model, 3D, joints, customisation, camera
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
link.subscribe('concert/model/robot_model', (m) => {
  model = m;
  $('model-version').textContent = `version ${m.version}`;
  $('model-info').textContent = `${m.joints.length} joints, chains ${m.chains.map((c) => c.name + ' (' + c.role + ')').join(', ')}; ` +
    `end-effectors ${m.end_effectors.map((e) => e.name).join(', ') || 'none'}; hash ${m.content_hash.slice(0, 12)}`;
  $('homing-chain').innerHTML = m.chains.map((c) => `<option>${esc(c.name)}</option>`).join('');
  viewer.setModel(m);
});
link.subscribe('concert/robot/joint_state', (js) => { lastJoints = js; viewer.setJoints(js); }, 10);
$('send-homing').onclick = () => {
  if (!model || !lastJoints) { $('custom-result').textContent = 'no model or joint states yet'; return; }
  const chain = model.chains.find((c) => c.name === $('homing-chain').value);
  const names = chain ? chain.joints : [];
  const pos = names.map((n) => lastJoints.position[lastJoints.name.indexOf(n)] ?? 0);
  link.publish('concert/model/customisation', { request_id: Date.now() % 4294967295, base_version: model.version, homing_joints: names, homing_positions: pos })
    .then(() => { $('custom-result').textContent = `homing of ${names.length} joints sent`; })
    .catch((e) => { $('custom-result').textContent = e.message; });
};
$('send-addon').onclick = () => {
  link.publish('concert/model/customisation', {
    request_id: Date.now() % 4294967295, base_version: model ? model.version : 0,
    addons: [{ module_name: $('addon-module').value, addon: $('addon-key').value }],
  }).then(() => { $('custom-result').textContent = 'add-on sent'; }).catch((e) => { $('custom-result').textContent = e.message; });
};
let cameraUrl = null;
$('camera-topic').onchange = () => {
  const topic = $('camera-topic').value;
  if (!topic) { for (const t of [...link.frames.keys()]) link.unwatchFrames(t); $('camera').removeAttribute('src'); return; }
  link.watchFrames(topic, (header, blob) => {
    if (cameraUrl) URL.revokeObjectURL(cameraUrl);
    cameraUrl = URL.createObjectURL(blob);
    $('camera').src = cameraUrl;
    $('camera').title = `${header.sensor} ${header.width}x${header.height}`;
  }, 2);
};

// ---- missions: drilling, sanding/spraying
$('drill-yaml').value = 'name: gui mission\ndepth: 0.03\nareas:\n  - {name: blobs, marks: blobs, point: [2.2, 0.03, 1.2], expected: 1}\n';
const drills = new Map();
link.subscribe('concert/drill/status', (s) => {
  drills.set(s.mission_id, s);
  const latest = [...drills.values()].sort((a, b) => b.stamp_ns - a.stamp_ns)[0];
  const areas = latest.areas.map((a) => `<li>${esc(a.name)}: ${a.state.replace('AREA_', '').toLowerCase()} ${esc(a.reason)} (${a.holes.filter((h) => h.state === 'HOLE_DRILLED').length}/${a.holes.length} holes)</li>`).join('');
  $('drill-status').innerHTML = `<b>${esc(latest.mission)}</b>: ${latest.state.replace('DRILL_', '').toLowerCase()} ` +
    `<span class="small">${esc(latest.active)}</span> ${esc(latest.reason)}<ul>${areas}</ul>` +
    `<span class="small">${latest.holes_drilled} drilled of ${latest.holes_marked} marked, ${latest.time_total.toFixed(1)} s</span>`;
});
$('drill-start').onclick = () => {
  link.publish('concert/drill/mission', {
    mission_id: (Date.now() % 2147483647) >>> 0, source: 'concert gui', name: 'gui mission', yaml: $('drill-yaml').value, base_dir: '',
  }).then(() => { $('drill-result').textContent = 'mission sent'; }).catch((e) => { $('drill-result').textContent = e.message; });
};
$('drill-abort').onclick = () => {
  link.publish('concert/drill/abort', { mission_id: 0, source: 'concert gui', reason: 'operator abort' })
    .then(() => { $('drill-result').textContent = 'abort sent'; }).catch((e) => { $('drill-result').textContent = e.message; });
};

// ---- missions: the storey seen from above. The walls and obstacles are the world every service
// reads (concert/world/world: with `concert up --ifc` the simulator's world made from the IFC
// storey, walls with their door openings as gaps); the robot's pose is nav's localisation in the
// map when nav runs, else the simulator's truth (labelled so). A tap on a wall picks the nearest
// point of its nearest face; "add" appends it to the mission YAML as a point area (drill
// README: `point` is in the world/map frame, the height from the field).
let world = null, poseNav = null, poseTruth = null, picked = null;
const bimView = { xmin: -1, ymax: 1, w: 2, h: 2 };
link.subscribe('concert/world/world', (w) => { world = w; renderBim(); });
link.subscribe('concert/nav/localisation', (l) => { poseNav = { ...l.pose, seen: Date.now(), state: l.state }; }, 2);
link.subscribe('concert/sim/truth', (t) => { poseTruth = { x: t.x, y: t.y, yaw: t.yaw, seen: Date.now() }; }, 2);
function bimPick(px, py) {
  const best = world ? pickWall(world.walls, px, py) : null;
  if (!best) {
    picked = null;
    $('bim-picked').textContent = `(${px.toFixed(2)}, ${py.toFixed(2)}) m is not on a wall: tap closer to one.`;
  } else {
    picked = best;
    $('bim-picked').textContent = `picked: ${best.wall}, face ${best.face}, at (${best.x.toFixed(3)}, ${best.y.toFixed(3)}) m`;
  }
  $('bim-add').disabled = !picked;
  renderBim();
}
function bimToScreen(x, y) {  // for the browser test: where world (x, y) is on the screen
  const p = new DOMPoint(x, -y).matrixTransform($('bim').getScreenCTM());
  return { x: p.x, y: p.y };
}
window.concertBim = { toScreen: bimToScreen, picked: () => picked };
$('bim').addEventListener('click', (ev) => {
  if (!world) return;
  const p = new DOMPoint(ev.clientX, ev.clientY).matrixTransform($('bim').getScreenCTM().inverse());
  bimPick(p.x, -p.y);
});
$('bim-add').onclick = () => {
  if (!picked) return;
  const h = parseFloat($('bim-height').value);
  if (!Number.isFinite(h) || h < 0) { $('bim-picked').textContent = 'the height must be a number of metres'; return; }
  const added = addPointArea($('drill-yaml').value, [picked.x, picked.y, h], $('bim-marks').value);
  $('drill-yaml').value = added.yaml;
  $('drill-result').textContent = `area ${added.name} added to the mission`;
};
function renderBim() {
  const svg = $('bim');
  const pose = poseNav && Date.now() - poseNav.seen < 3000 ? { ...poseNav, src: 'nav localisation' }
    : poseTruth && Date.now() - poseTruth.seen < 3000 ? { ...poseTruth, src: 'simulator truth' } : null;
  $('bim-missing').textContent = world ? '' : 'No world yet (concert/world/world, from the robot service: `concert up --world FILE` or `--ifc FILE`).';
  $('bim-source').textContent = world ? `${world.source.split('/').pop()} v${world.version}` : '';
  svg.replaceChildren();
  svg.style.display = world ? '' : 'none';
  if (!world) return;
  // The view: every wall and obstacle, the robot, a margin (recomputed when the world changes).
  const xs = [0], ys = [0];
  for (const w of [...world.walls, ...world.obstacles]) {
    const r = Math.hypot(w.size[0], w.size[1]) / 2;
    xs.push(w.position[0] - r, w.position[0] + r); ys.push(w.position[1] - r, w.position[1] + r);
  }
  if (pose) { xs.push(pose.x); ys.push(pose.y); }
  Object.assign(bimView, { xmin: Math.min(...xs) - 0.5, ymax: Math.max(...ys) + 0.5 });
  bimView.w = Math.max(...xs) + 0.5 - bimView.xmin; bimView.h = bimView.ymax - (Math.min(...ys) - 0.5);
  svg.setAttribute('viewBox', `${bimView.xmin} ${-bimView.ymax} ${bimView.w} ${bimView.h}`);
  for (let gx = Math.ceil(bimView.xmin); gx < bimView.xmin + bimView.w; gx++) svg.append(svgEl('line', { class: 'grid', x1: gx, x2: gx, y1: -bimView.ymax, y2: -bimView.ymax + bimView.h }));
  for (let gy = Math.ceil(bimView.ymax - bimView.h); gy < bimView.ymax; gy++) svg.append(svgEl('line', { class: 'grid', y1: -gy, y2: -gy, x1: bimView.xmin, x2: bimView.xmin + bimView.w }));
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
    svg.append(svgEl('path', { class: 'robot-pose', d: 'M0.45,0 L-0.3,0.3 L-0.3,-0.3 Z', transform: `translate(${pose.x} ${-pose.y}) rotate(${deg})` }));
  }
  if (picked) svg.append(svgEl('circle', { class: 'pick', cx: picked.x, cy: -picked.y, r: 0.09 }));
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
/// Why the start button is disabled ('' when it is not).
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
  const blocked = finishBlocked();
  $('finish-start').disabled = !!blocked;
  $('finish-start').title = blocked;
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
  const running = state === 'running' && s.seen ? (Date.now() - s.seen) / 1000 : null;
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
  finishRuns.set(s.request_id, { ...s, seen: before && before.state === s.state ? before.seen : Date.now() });
  renderFinishStatus();
});
$('finish-reshape').onchange = renderFinish;
for (const k of ['x0', 'x1', 'y0', 'y1']) $('finish-' + k).oninput = renderFinish;
$('finish-start').onclick = () => {
  const blocked = finishBlocked();
  if (blocked) { $('finish-result').textContent = blocked; return; }
  const sand = finishAreas.tool === 'sand';
  const cmd = {
    request_id: Date.now() % 4294967295, model_version: finishAreas.model_version,
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
  link.publish('concert/finish/command', { request_id: Date.now() % 4294967295, verb: 'FINISH_ABORT', model_version: finishAreas ? finishAreas.model_version : 0 })
    .then(() => { $('finish-result').textContent = 'abort sent'; }).catch((e) => { $('finish-result').textContent = 'abort not sent: ' + e.message; });
};

// Pages whose service or message types are not in this build say so (and which ones).
function renderOptional() {
  finishAvailable = link.hasTopic('concert/finish/command') && link.hasTopic('concert/finish/areas');
  renderFinish();
  if (link.hasTopic('concert/collab/command')) {
    const modes = ['teaching', 'autonomous', 'follow-me', 'stop', 'open', 'close', 'lift', 'place'];
    $('transport-panel').innerHTML = '<div id="collab-missing" class="missing"></div><p>State: <b id="collab-state">?</b> ' +
      '<span id="collab-last" class="small"></span></p><div class="row">' +
      modes.map((m) => `<button class="action mode" data-mode="${m}">${m}</button>`).join('') + '</div><p id="collab-result" class="small"></p>';
    for (const b of document.querySelectorAll('#transport-panel button.mode')) {
      b.onclick = () => link.publish('concert/collab/command', { command_id: Date.now() % 4294967295, text: b.dataset.mode })
        .then(() => { $('collab-result').textContent = b.dataset.mode + ' sent'; })
        .catch((e) => { $('collab-result').textContent = e.message; });
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
link.onhello = () => { renderOptional(); renderTopics(); };

// ---- topics
let lastRates = new Map();
link.rates.add((list) => { lastRates = new Map(list.map((r) => [r.topic, r])); renderTopics(); });
function renderTopics() {
  if (!link.hello) return;
  $('topics').querySelector('tbody').innerHTML = link.hello.topics.map((t) => {
    const r = lastRates.get(t.topic) || { hz: 0, count: 0, age_s: -1 };
    if (t.kind === 'command' && r.count === 0) {
      return `<tr><td>${esc(t.topic)}</td><td class="small">${esc(t.type.replace('concert::msg::', ''))}</td><td>${t.kind}</td>` +
        `<td colspan="3" class="small">not watched (commands are read only on demand)</td><td>${t.commandable ? 'yes' : ''}</td></tr>`;
    }
    return `<tr><td>${esc(t.topic)}</td><td class="small">${esc(t.type.replace('concert::msg::', ''))}</td><td>${t.kind}</td>` +
      `<td class="num">${r.hz.toFixed(1)}</td><td class="num">${r.count}</td><td class="num">${r.age_s < 0 ? '–' : r.age_s.toFixed(1)}</td><td>${t.commandable ? 'yes' : ''}</td></tr>`;
  }).join('');
}

setInterval(() => {
  renderServices();
  need('safety', $('safety-missing'), 'the safety state and reset');
  need('drill', $('drill-missing'), 'drilling missions');
  if ($('collab-missing')) need('collab', $('collab-missing'), 'the transport modes');
  $('drill-start').disabled = !alive('drill');
  renderFinish();
  renderFinishStatus();
  renderBim();
}, 1000);
