// The mission builder on the Missions page: the mission's fields (#mission-name, #mission-depth,
// #mission-ifc, #mission-storey) and its areas as rows (#mission-areas: name, marks, where, height,
// expected, remove), read from the mission YAML (#drill-yaml, the advanced view under the "YAML"
// toggle, which "Start drilling" sends) and written back to it line by line (mission.js). A YAML
// the builder does not read ("edited by hand") is shown as such and never rewritten.
import { $, esc } from './ui.js';
import { areaHeight, editArea, parseMission, removeArea, setField } from './mission.js';
import { stepper } from './controls.js';

const FIELD_IDS = { name: 'mission-name', depth: 'mission-depth', ifc: 'mission-ifc', storey: 'mission-storey' };
const listeners = new Set();
let current = { ok: false, why: 'not read yet' };
let wasSimple = true;

/// The mission as last read from the YAML box (parseMission's result).
export const mission = () => current;
/// Calls `fn(mission)` after every change of the YAML (the storey map draws the point areas).
export function onMissionChange(fn) { listeners.add(fn); }
/// Replaces the YAML (the one way code changes it: the builder follows).
export function setMissionYaml(text) {
  $('drill-yaml').value = text;
  render();
}
function edit(change) {
  try {
    setMissionYaml(change($('drill-yaml').value));
  } catch (e) {
    note(e.message, true);
  }
}
function note(text, bad = false) {
  $('mission-note').textContent = text;
  $('mission-note').classList.toggle('bad', bad);
}
function setYamlOpen(open) {
  $('drill-yaml-box').classList.toggle('collapsed', !open);
  $('drill-yaml-toggle').setAttribute('aria-expanded', String(open));
  $('drill-yaml-toggle').textContent = open ? 'YAML ▾ (hide)' : 'YAML ▸ (the mission file)';
}

/// What an area is on: its point, wall or camera pixel, in words.
function where(a) {
  if (a.point) return `point (${a.point[0].toFixed(2)}, ${a.point[1].toFixed(2)}) m`;
  if (a.wall !== undefined) return `BIM wall ${a.wall}` + (a.at ? `, ${a.at[0].toFixed(2)} m along` : '') + (a.face ? `, face ${a.face}` : '');
  if (a.pixel) return `camera pixel (${a.pixel[0]}, ${a.pixel[1]})`;
  return 'no point, wall or pixel: edit the YAML';
}

function renderRows(m) {
  const list = $('mission-areas');
  list.replaceChildren();
  m.areas.forEach((a, i) => {
    const li = document.createElement('li');
    li.className = 'area-row';
    li.dataset.index = i;
    li.dataset.area = a.name || '';
    li.dataset.testid = 'mission-area';
    const h = areaHeight(a);
    const name = a.name !== undefined ? esc(a.name) : `<span class="small">area ${i + 1}</span>`;
    const marks = a.marks || 'blobs';
    li.innerHTML = `<span class="area-name">${name}</span>` +
      `<label class="area-field">marks <select class="area-marks" aria-label="marks of area ${i + 1}">` +
      ['blobs', 'aruco'].map((k) => `<option${k === marks ? ' selected' : ''}>${k}</option>`).join('') + '</select></label>' +
      `<span class="area-where">${esc(where(a))}</span>` +
      (h !== null ? `<span class="area-field area-h">height [m] <input class="area-height" type="number" min="0" max="5" step="0.05" value="${h.toFixed(2)}" aria-label="height of area ${i + 1} [m]"></span>` : '') +
      `<span class="area-expected">${a.expected !== undefined ? `expected ${a.expected}` : 'expected: all'}</span>` +
      `<button type="button" class="area-remove" aria-label="remove area ${esc(a.name || i + 1)}">Remove</button>`;
    li.querySelector('.area-marks').onchange = (e) => edit((y) => editArea(y, i, { marks: e.target.value }));
    const hi = li.querySelector('.area-height');
    if (hi) {
      stepper(hi, { step: 0.05, digits: 2, name: `height of area ${i + 1}` });
      hi.addEventListener('change', () => {
        const v = parseFloat(hi.value);
        if (!Number.isFinite(v) || v < 0) { note('a height is a number of metres, 0 or more', true); return; }
        edit((y) => editArea(y, i, { height: v }));
      });
    }
    li.querySelector('.area-remove').onclick = () => edit((y) => removeArea(y, i));
    list.append(li);
  });
}

/// Reads the YAML box again and shows what it says.
export function render() {
  const m = parseMission($('drill-yaml').value);
  current = m;
  const depthButtons = $('mission-depth').closest('.stepper-group').querySelectorAll('button');
  for (const el of [...Object.values(FIELD_IDS).map($), ...depthButtons]) el.disabled = !m.ok;
  if (!m.ok) {
    $('mission-areas').replaceChildren();
    $('mission-count').textContent = '';
    note(`edited by hand: edit the YAML (${m.why})`, true);
    if (wasSimple) setYamlOpen(true);  // where the mission can still be edited
    wasSimple = false;
  } else {
    wasSimple = true;
    for (const [key, id] of Object.entries(FIELD_IDS)) {
      const el = $(id);
      if (document.activeElement !== el) el.value = m.fields[key] ?? '';
    }
    if ($('mission-depth').concertMarkPresets) $('mission-depth').concertMarkPresets();
    renderRows(m);
    const n = m.areas.length;
    $('mission-count').textContent = `${n} area${n === 1 ? '' : 's'}`;
    const walls = m.areas.some((a) => a.wall !== undefined);
    $('mission-ifc').classList.toggle('bad', walls && !m.fields.ifc);
    if (!n) note('No areas yet: tap a wall on the storey map, then add it.');
    else if (walls && !m.fields.ifc) note('BIM wall areas need the IFC file: type its path on the robot under "IFC file".', true);
    else note('');
  }
  for (const fn of listeners) fn(m);
}

export function initBuilder() {
  $('drill-yaml').addEventListener('input', render);
  $('drill-yaml-toggle').onclick = () => setYamlOpen($('drill-yaml-box').classList.contains('collapsed'));
  setYamlOpen(false);
  stepper($('mission-depth'), { step: 0.005, digits: 3, base: 0.05, unit: ' m', name: 'hole depth',
    presets: [[0.03, '0.03 m'], [0.05, '0.05 m'], [0.08, '0.08 m']] });
  for (const [key, id] of Object.entries(FIELD_IDS)) {
    $(id).addEventListener('change', () => {
      const v = $(id).value.trim();
      if (key === 'depth' && v !== '' && !(parseFloat(v) > 0 && parseFloat(v) <= 0.3)) {
        note('the hole depth is in metres, more than 0 and at most 0.3', true);
        return;
      }
      edit((y) => setField(y, key, v));
    });
  }
}
