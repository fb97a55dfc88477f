// The app's pure functions under node's test runner: the storey view's (app/src/storey.js) face
// point a tap picks on axis-aligned and turned walls, the reach limit, the mission YAML edit, BIM
// walls by GlobalId and where a point lies along one; the mission builder's YAML reading and
// writing (app/src/mission.js); the map's pan and zoom arithmetic (app/src/panzoom.js); the
// number steppers' arithmetic (app/src/controls.js).
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { addPointArea, addWallArea, bimWallId, nearestFace, pickWall, wallFace, wallSpan } from '../src/storey.js';
import { areaHeight, areaLine, editArea, parseMission, removeArea, setField, yamlScalar } from '../src/mission.js';
import { clampZoom, panView, zoomView } from '../src/panzoom.js';
import { stepValue } from '../src/controls.js';

const near = (a, b, what) => assert.ok(Math.abs(a - b) < 1e-9, `${what}: ${a} != ${b}`);
// deploy/demo/drill_site.yaml's wall: its -x face at x = 2.2 m.
const site = { name: 'site_wall', type: 'WORLD_BOX', size: [0.2, 6.0, 3.0], position: [2.3, 0.0, 1.5], yaw: 0 };

test('a tap in front of a wall picks the point of its facing side', () => {
  const f = nearestFace(site, 2.0, 0.5);
  assert.equal(f.face, '-x');
  near(f.x, 2.2, 'x'); near(f.y, 0.5, 'y'); near(f.distance, 0.2, 'distance');
  const g = nearestFace(site, 2.31, -1.0);  // inside the wall, nearer its back face
  assert.equal(g.face, '+x');
  near(g.x, 2.4, 'x'); near(g.y, -1.0, 'y');
});

test('a turned wall: the face point is turned with it', () => {
  // 4 m long along world x at y = 3 (its local x is world y): the side facing the origin is -x.
  const w = { name: 'turned', type: 'WORLD_BOX', size: [0.2, 4.0, 3.0], position: [0.0, 3.0, 1.5], yaw: Math.PI / 2 };
  const f = nearestFace(w, 1.0, 2.5);
  assert.equal(f.face, '-x');
  near(f.x, 1.0, 'x'); near(f.y, 2.9, 'y'); near(f.distance, 0.4, 'distance');
  const end = nearestFace(w, 3.0, 2.9);  // beyond the wall's end at x = 2: its end face
  near(end.x, 2.0, 'x'); near(end.y, 2.9, 'y'); near(end.distance, 1.0, 'distance');
});

test('pickWall: the nearest wall within reach, cylinders left out', () => {
  const other = { name: 'other', type: 'WORLD_BOX', size: [0.2, 2.0, 3.0], position: [1.0, 0.0, 1.5], yaw: 0 };
  const pillar = { name: 'pillar', type: 'WORLD_CYLINDER', size: [0.3, 0, 3], position: [2.0, 0.5, 1.5], yaw: 0 };
  assert.equal(pickWall([site, other, pillar], 2.0, 0.5).wall, 'site_wall');
  assert.equal(pickWall([site, other, pillar], 1.3, 0.5).wall, 'other');
  assert.equal(pickWall([site], 1.0, 0.0), null);  // 1.2 m off: not a pick
  assert.equal(pickWall([], 1.0, 0.0), null);
});

test('addPointArea appends to the areas list, wherever it is, with a fresh name', () => {
  const base = 'name: m\ndepth: 0.03\nareas:\n  - {name: pick1, marks: blobs, point: [2.2, 0.03, 1.2], expected: 1}\n';
  const a = addPointArea(base, [2.2, 0.5, 1.2], 'blobs');
  assert.equal(a.name, 'pick2');
  assert.equal(a.yaml, base + '  - {name: pick2, marks: blobs, point: [2.200, 0.500, 1.200], expected: 1}\n');
  const middle = 'areas:\n  - {name: a, marks: aruco, point: [1, 2, 3]}\ndepth: 0.05\n';
  assert.equal(addPointArea(middle, [1, 2, 1.45], 'aruco').yaml,
    'areas:\n  - {name: a, marks: aruco, point: [1, 2, 3]}\n  - {name: pick1, marks: aruco, point: [1.000, 2.000, 1.450]}\ndepth: 0.05\n');
  assert.equal(addPointArea('name: m\ndepth: 0.03', [0, 0, 1], 'blobs').yaml,
    'name: m\ndepth: 0.03\nareas:\n  - {name: pick1, marks: blobs, point: [0.000, 0.000, 1.000], expected: 1}\n');
  assert.equal(addPointArea('', [0, 0, 1], 'aruco').yaml, 'areas:\n  - {name: pick1, marks: aruco, point: [0.000, 0.000, 1.000]}\n');
});

// ---- BIM walls (libs/bim storey_world: boxes named wall_<GlobalId>_<k>)
const GID = '1$wmdwWPjDYuku_ghVkynE';  // the FZK house's Wand-Int-ERDG-5: '$' and '_' inside

test('bimWallId: the GlobalId of a box made from an IFC wall, else null', () => {
  assert.equal(bimWallId(`wall_${GID}_0`), GID);
  assert.equal(bimWallId(`wall_${GID}_12`), GID);
  assert.equal(bimWallId('wall_3PfS__Y_DBAfq5naM6zD2Z_3'), '3PfS__Y_DBAfq5naM6zD2Z');
  assert.equal(bimWallId('site_wall'), null);
  assert.equal(bimWallId(`wall_${GID}`), null);             // no box index
  assert.equal(bimWallId(`column_${GID}_0`), null);         // not a wall
  assert.equal(bimWallId('wall_short_0'), null);            // not 22 characters
  assert.equal(bimWallId(undefined), null);
});

test('wallSpan: where a point lies along a wall made of several boxes', () => {
  // A wall along x from 2.0 to 6.0 at y = 4.13, split by a doorway at 3.0..4.0 into two boxes.
  const walls = [
    { name: `wall_${GID}_0`, type: 'WORLD_BOX', size: [1.0, 0.1, 2.5], position: [2.5, 4.13, 1.25], yaw: 0 },
    { name: `wall_${GID}_1`, type: 'WORLD_BOX', size: [2.0, 0.1, 2.5], position: [5.0, 4.13, 1.25], yaw: 0 },
    { name: 'wall_3PfS__Y_DBAfq5naM6zD2Z_0', type: 'WORLD_BOX', size: [0.1, 3.0, 2.5], position: [7.5, 5.5, 1.25], yaw: 0 },
  ];
  const a = wallSpan(walls, GID, 5.5, 4.08);
  near(a.length, 4.0, 'length'); near(a.s, 3.5, 's');
  near(a.ends[0][0], 2.0, 'start x'); near(a.ends[0][1], 4.13, 'start y');
  near(a.ends[1][0], 6.0, 'end x'); near(a.ends[1][1], 4.13, 'end y');
  near(wallSpan(walls, GID, 1.0, 4.2).s, 0, 'before its start: 0');
  near(wallSpan(walls, GID, 9.0, 4.2).s, 4.0, 'beyond its end: its length');
  // A wall along y: s counted from its lower y end.
  const b = wallSpan(walls, '3PfS__Y_DBAfq5naM6zD2Z', 7.45, 6.0);
  near(b.length, 3.0, 'length'); near(b.s, 2.0, 's');
  near(b.ends[0][0], 7.5, 'start x'); near(b.ends[0][1], 4.0, 'start y');
  assert.equal(wallSpan(walls, '0000000000000000000000', 0, 0), null);
});

test('wallSpan: a turned wall', () => {
  // 4 m long along world y (its local x is world y), centred at (1, 3).
  const w = [{ name: `wall_${GID}_0`, type: 'WORLD_BOX', size: [4.0, 0.2, 3.0], position: [1.0, 3.0, 1.5], yaw: Math.PI / 2 }];
  const a = wallSpan(w, GID, 0.9, 4.5);
  near(a.length, 4.0, 'length'); near(a.s, 3.5, 's');
  near(a.ends[0][0], 1.0, 'start x'); near(a.ends[0][1], 1.0, 'start y');
  near(a.ends[1][0], 1.0, 'end x'); near(a.ends[1][1], 5.0, 'end y');
});

test('wallFace: the side of the axis a point is on, the axis from the end chosen', () => {
  // The FZK living room is south of Wand-Int-ERDG-5, whose IFC axis runs +x: its face there is
  // 'right' (tests/system/drill_runner.hpp, scenario 2).
  const span = { ends: [[0.3, 4.13], [3.8, 4.13]], length: 3.5, s: 1.75 };
  assert.equal(wallFace(span, 0, 2.05, 4.01), 'right');
  assert.equal(wallFace(span, 0, 2.05, 4.25), 'left');
  assert.equal(wallFace(span, 1, 2.05, 4.01), 'left');   // the axis the other way round
  const alongY = { ends: [[7.5, 4.0], [7.5, 7.0]], length: 3, s: 1 };
  assert.equal(wallFace(alongY, 0, 7.45, 5.0), 'left');  // west of an axis running north
  assert.equal(wallFace(alongY, 1, 7.45, 5.0), 'right');
});

test('addWallArea appends a BIM wall area with its GlobalId quoted and a fresh name', () => {
  const base = 'name: m\nifc: /data/house.ifc\nareas:\n  - {name: pick1, marks: blobs, point: [2.2, 0.03, 1.2], expected: 1}\n';
  const a = addWallArea(base, GID, [1.75, 1.2], 'blobs');
  assert.equal(a.name, 'wall1');
  assert.equal(a.yaml, base + `  - {name: wall1, marks: blobs, wall: "${GID}", at: [1.750, 1.200], expected: 1}\n`);
  const b = addWallArea(a.yaml, GID, [0.5, 0.8], 'aruco', 'right');
  assert.equal(b.name, 'wall2');
  assert.ok(b.yaml.endsWith(`  - {name: wall2, marks: aruco, wall: "${GID}", at: [0.500, 0.800], face: right}\n`));
  // what it writes the mission builder reads
  const m = parseMission(b.yaml);
  assert.equal(m.ok, true);
  assert.deepEqual(m.areas[1], { name: 'wall1', marks: 'blobs', wall: GID, at: [1.75, 1.2], expected: 1 });
  assert.deepEqual(m.areas[2], { name: 'wall2', marks: 'aruco', wall: GID, at: [0.5, 0.8], face: 'right' });
  assert.equal(addWallArea('', GID, [1, 1], 'blobs', 'left').yaml,
    `areas:\n  - {name: wall1, marks: blobs, wall: "${GID}", at: [1.000, 1.000], face: left, expected: 1}\n`);
});

// ---- the mission builder's YAML (app/src/mission.js)
const DEFAULT = 'name: gui mission\ndepth: 0.03\nareas:\n  - {name: blobs, marks: blobs, point: [2.2, 0.03, 1.2], expected: 1}\n';

test('parseMission reads what the app writes', () => {
  const m = parseMission(DEFAULT);
  assert.equal(m.ok, true);
  assert.deepEqual(m.fields, { name: 'gui mission', depth: '0.03' });
  assert.deepEqual(m.areas, [{ name: 'blobs', marks: 'blobs', point: [2.2, 0.03, 1.2], expected: 1 }]);
  // the drill README's example areas, comments and a quoted GlobalId included
  const readme = '# east wall\nname: east wall               # optional\nifc: ../house.ifc\nstorey: Erdgeschoss\n' +
    'patterns: my_patterns.yaml\ndepth: 0.05\nareas:                        # drilled in this order\n' +
    `  - {name: a1, marks: blobs, wall: "${GID}", at: [1.2, 1.1], face: right}  # BIM wall\n` +
    "  - {name: a2, marks: aruco, point: [2.2, -0.9, 1.4]}\n  - {name: 'a 3', marks: blobs, pixel: [320, 240], expected: 2}\n";
  const r = parseMission(readme);
  assert.equal(r.ok, true, r.why);
  assert.deepEqual(r.fields, { name: 'east wall', ifc: '../house.ifc', storey: 'Erdgeschoss', patterns: 'my_patterns.yaml', depth: '0.05' });
  assert.deepEqual(r.areas.map((a) => a.name), ['a1', 'a2', 'a 3']);
  assert.deepEqual(r.areas[0], { name: 'a1', marks: 'blobs', wall: GID, at: [1.2, 1.1], face: 'right' });
  assert.deepEqual(r.areas[2].pixel, [320, 240]);
  assert.deepEqual(r.areas.map(areaHeight), [1.1, 1.4, null]);
  // no areas yet, no list yet, nothing at all
  assert.deepEqual(parseMission('name: m\nareas:\n').areas, []);
  assert.equal(parseMission('name: m\n').ok, true);
  assert.equal(parseMission('').ok, true);
});

test('parseMission: anything but the simple form is edited by hand, saying where', () => {
  const cases = [
    ['name: not a mission\nareas: 5\n', /line 2: areas written on one line/],
    ['areas:\n  - name: a\n    point: [1, 2, 3]\n', /line 2/],                     // block style
    ['areas:\n  - {name: a, point: [1, 2, 3], colour: red}\n', /the key 'colour'/],
    ['speed: 3\nareas:\n', /line 1: the key 'speed'/],
    ['name: a\nname: b\n', /'name' twice/],
    ['areas:\n  - {name: a, point: [1, 2]}\n', /point is not a list of 3 numbers/],
    ['areas:\n  - {name: a, point: [1, x, 3]}\n', /numbers/],
    ['areas:\n  - {name: a, expected: many}\n', /whole number/],
    ['  - {name: a, point: [1, 2, 3]}\n', /outside 'areas:'/],
    ['areas:\n  - {name: a, point: {x: 1}}\n', /nested map/],
    ['name: &anchor m\n', /does not read/],
    ['areas:\n  - {name: "a}\n', /line 2/],
    ['areas: []\n', /one line/],
  ];
  for (const [yaml, why] of cases) {
    const m = parseMission(yaml);
    assert.equal(m.ok, false, yaml);
    assert.match(m.why, why, yaml);
  }
});

test('edits change only their line: everything else comes back as it was', () => {
  const text = '# mine\nname: east wall   # the east side\ndepth: 0.05\nareas:\n' +
    `  - {name: a1, marks: blobs, wall: "${GID}", at: [1.2, 1.1], face: right}  # BIM wall\n` +
    '  - {name: a2, marks: aruco, point: [2.2, -0.9, 1.4]}\n\n';
  assert.equal(editArea(text, 1, { marks: 'blobs' }), text.replace('  - {name: a2, marks: aruco, point: [2.2, -0.9, 1.4]}',
    '  - {name: a2, marks: blobs, point: [2.200, -0.900, 1.400]}'));
  assert.equal(editArea(text, 0, { height: 1.35 }), text.replace(`  - {name: a1, marks: blobs, wall: "${GID}", at: [1.2, 1.1], face: right}  # BIM wall`,
    `  - {name: a1, marks: blobs, wall: "${GID}", at: [1.200, 1.350], face: right}`));
  assert.equal(editArea(DEFAULT, 0, { height: 1.5, marks: 'aruco' }),
    'name: gui mission\ndepth: 0.03\nareas:\n  - {name: blobs, marks: aruco, point: [2.200, 0.030, 1.500], expected: 1}\n');
  assert.equal(removeArea(text, 0), text.replace(/ {2}- \{name: a1.*\n/, ''));
  assert.equal(removeArea(DEFAULT, 0), 'name: gui mission\ndepth: 0.03\nareas:\n');
  assert.throws(() => removeArea(DEFAULT, 3), /no area 4/);
  assert.throws(() => editArea('areas: 5\n', 0, { marks: 'aruco' }), /edited by hand/);
  // an area line the app writes reads back as the same area
  for (const a of parseMission(text).areas) assert.deepEqual(parseMission('areas:\n' + areaLine(a) + '\n').areas[0], a);
});

test('setField sets, adds (before the areas) and removes the mission fields', () => {
  assert.equal(setField(DEFAULT, 'depth', '0.045'), DEFAULT.replace('depth: 0.03', 'depth: 0.045'));
  assert.equal(setField(DEFAULT, 'ifc', '/home/site/house.ifc'),
    DEFAULT.replace('areas:', 'ifc: /home/site/house.ifc\nareas:'));
  assert.equal(setField(DEFAULT, 'name', ''), DEFAULT.replace('name: gui mission\n', ''));
  assert.equal(setField(DEFAULT, 'storey', ''), DEFAULT);
  assert.equal(setField('name: m', 'depth', '0.05'), 'name: m\ndepth: 0.05\n');
  assert.equal(setField('', 'name', 'x'), 'name: x\n');
  // values YAML would read otherwise are quoted, and read back as they were typed
  for (const v of ['yes', 'a: b', '#1', ' padded ', 'Erdgeschoss 1', '-x', 'C:\\site\\h.ifc', "it's"]) {
    assert.equal(parseMission(setField(DEFAULT, 'storey', v)).fields.storey, v.trim(), v);
  }
  assert.equal(yamlScalar('Erdgeschoss'), 'Erdgeschoss');
  assert.equal(yamlScalar('no'), '"no"');
  assert.throws(() => setField(DEFAULT, 'areas', 'x'), /not a mission field/);
});

// ---- the storey map's pan and zoom (app/src/panzoom.js)
test('zoomView keeps the point under the cursor; panView moves the view', () => {
  const v = { x: -1, y: -5, w: 10, h: 6 };
  const z = zoomView(v, 2, -3, 0.5);
  assert.deepEqual(z, { x: 0.5, y: -4, w: 5, h: 3 });
  // the point's place in the view (as a fraction of its size) is unchanged
  near((2 - z.x) / z.w, (2 - v.x) / v.w, 'x fraction'); near((-3 - z.y) / z.h, (-3 - v.y) / v.h, 'y fraction');
  assert.deepEqual(zoomView(z, 2, -3, 2), v);
  assert.deepEqual(panView(v, 1.5, -2), { x: -2.5, y: -3, w: 10, h: 6 });
  near(clampZoom(v, 0.01, 0.5, 40), 0.05, 'no narrower than 0.5');
  near(clampZoom(v, 10, 0.5, 40), 4, 'no wider than 40');
  near(clampZoom(v, 0.8, 0.5, 40), 0.8, 'within');
});

test('stepValue: steps within the bounds, rounded to the step', () => {
  assert.equal(stepValue(1.2, 0.05, { min: 0, max: 5, digits: 2 }), 1.25);
  assert.equal(stepValue(0.1 + 0.2, 0.1, { digits: 2 }), 0.4);
  assert.equal(stepValue(0.02, -0.05, { min: 0, max: 5, digits: 2 }), 0);
  assert.equal(stepValue(99, 5, { min: 1, max: 100, digits: 0 }), 100);
  assert.equal(stepValue(NaN, 5, { min: 1, max: 100, digits: 0 }), 6);  // an empty field counts from its minimum
});
