// The storey view's pure functions (app/src/storey.js) under node's test runner: the face point
// a tap picks on axis-aligned and turned walls, the reach limit, and the mission YAML edit.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { addPointArea, nearestFace, pickWall } from '../src/storey.js';

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
