// The storey view's geometry and the mission YAML edit, without the DOM (tested by
// app/test/storey_test.mjs with node's test runner).

/// The point of a box wall's faces nearest (px, py) in the world frame: {x, y, face, distance}.
/// `shape` is a WorldShape (position: centre, size: full extents along its local x and y, yaw
/// about world z); faces are named by the local axis of their outward normal, as in world files.
export function nearestFace(shape, px, py) {
  const [cx, cy] = shape.position, c = Math.cos(shape.yaw), s = Math.sin(shape.yaw);
  const lx = c * (px - cx) + s * (py - cy), ly = -s * (px - cx) + c * (py - cy);
  const hx = shape.size[0] / 2, hy = shape.size[1] / 2;
  const clamp = (v, a) => Math.max(-a, Math.min(a, v));
  const faces = [['+x', hx, clamp(ly, hy)], ['-x', -hx, clamp(ly, hy)], ['+y', clamp(lx, hx), hy], ['-y', clamp(lx, hx), -hy]];
  let best = null;
  for (const [face, fx, fy] of faces) {
    const d = Math.hypot(lx - fx, ly - fy);
    if (!best || d < best.distance) best = { face, x: cx + c * fx - s * fy, y: cy + s * fx + c * fy, distance: d };
  }
  return best;
}

/// The nearest face point of the nearest box wall within `reach` [m] of (px, py), with the
/// wall's name; null when no wall is that close.
export function pickWall(walls, px, py, reach = 0.6) {
  let best = null;
  for (const w of walls) {
    if (w.type !== undefined && w.type !== 'WORLD_BOX') continue;
    const f = nearestFace(w, px, py);
    if (!best || f.distance < best.distance) best = { ...f, wall: w.name };
  }
  return best && best.distance <= reach ? best : null;
}

/// The mission YAML with a point area appended to its `areas:` list (a new list at the end when
/// there is none), named pick1, pick2, ... (the first name not in the file). Returns {yaml, name}.
export function addPointArea(yaml, point, marks) {
  return appendArea(yaml, 'pick', (name) => `  - {name: ${name}, marks: ${marks}, point: [${point.map((v) => v.toFixed(3)).join(', ')}]` +
    `${marks === 'blobs' ? ', expected: 1' : ''}}`);
}

/// The mission YAML with a BIM wall area appended (as addPointArea): the wall's IFC GlobalId
/// (quoted, as services/drill/README.md writes it) and `at` [s, h]: s along the wall's axis from
/// its start, h above the storey's floor [m]. Named wall1, wall2, ... Returns {yaml, name}.
/// `face` (left or right of the axis, README `face:`) is written when given.
export function addWallArea(yaml, globalId, at, marks, face = '') {
  return appendArea(yaml, 'wall', (name) => `  - {name: ${name}, marks: ${marks}, wall: ${JSON.stringify(globalId)}, ` +
    `at: [${at.map((v) => v.toFixed(3)).join(', ')}]${face ? ', face: ' + face : ''}${marks === 'blobs' ? ', expected: 1' : ''}}`);
}

/// `yaml` with the line `line(name)` appended to its areas list, `name` the first of
/// prefix1, prefix2, ... not in the file.
function appendArea(yaml, prefix, line) {
  const lines = yaml.replace(/\s*$/, '').split('\n');
  const names = new Set(lines.flatMap((l) => [...l.matchAll(/name:\s*([\w-]+)/g)].map((m) => m[1])));
  let n = 1;
  while (names.has(prefix + n)) n++;
  const name = prefix + n;
  let at = lines.findIndex((l) => /^areas:\s*$/.test(l));
  if (at < 0) {
    if (lines.length === 1 && lines[0] === '') lines.pop();
    lines.push('areas:');
    at = lines.length - 1;
  }
  let end = at + 1;
  while (end < lines.length && /^(\s+|-)/.test(lines[end])) end++;
  lines.splice(end, 0, line(name));
  return { yaml: lines.join('\n') + '\n', name };
}

/// The IFC GlobalId of a world wall box made from a building's wall (libs/bim storey_world names
/// them `wall_<GlobalId>_<k>`, one box per rectangle of the rasterised wall), else null.
/// GlobalIds are 22 characters of IFC's base 64 (0-9, A-Z, a-z, _ and $; '_' may occur inside).
export function bimWallId(name) {
  const m = /^wall_([0-9A-Za-z_$]{22})_\d+$/.exec(name || '');
  return m ? m[1] : null;
}

/// Where (px, py) lies along the BIM wall `globalId`, from the world boxes named after it:
/// {ends: [[x, y], [x, y]], length, s} with the ends on the wall's long centre line (the first
/// one at the lower coordinate along it: x for a wall along x), and s the distance [m] of the
/// point's projection from ends[0], within [0, length]. Null when no box has that GlobalId.
/// The world does not say at which end the IFC axis starts (libs/bim: where the authoring tool
/// started drawing the wall), so the caller chooses the end s is measured from; the boxes are
/// the storey map's cells, up to a cell (5 cm) off the IFC's wall ends.
export function wallSpan(walls, globalId, px, py) {
  const boxes = walls.filter((w) => (w.type === undefined || w.type === 'WORLD_BOX') && bimWallId(w.name) === globalId);
  if (!boxes.length) return null;
  // The long direction, from the first box's axes: the one along which the boxes extend further.
  const yaw = boxes[0].yaw || 0;
  const axes = [[Math.cos(yaw), Math.sin(yaw)], [-Math.sin(yaw), Math.cos(yaw)]];
  const extent = axes.map(([ux, uy]) => {
    let lo = Infinity, hi = -Infinity;
    for (const b of boxes) {
      const c = Math.cos(b.yaw || 0), s = Math.sin(b.yaw || 0);
      for (const [sx, sy] of [[1, 1], [1, -1], [-1, 1], [-1, -1]]) {
        const x = b.position[0] + c * sx * b.size[0] / 2 - s * sy * b.size[1] / 2;
        const y = b.position[1] + s * sx * b.size[0] / 2 + c * sy * b.size[1] / 2;
        const t = x * ux + y * uy;
        lo = Math.min(lo, t); hi = Math.max(hi, t);
      }
    }
    return { lo, hi };
  });
  const k = extent[0].hi - extent[0].lo >= extent[1].hi - extent[1].lo ? 0 : 1;
  let [ux, uy] = axes[k];
  let { lo, hi } = extent[k];
  // ends[0] at the lower coordinate: flip the direction when it points down along x (or along y
  // for a wall across x).
  if (Math.abs(ux) > Math.abs(uy) ? ux < 0 : uy < 0) { ux = -ux; uy = -uy; [lo, hi] = [-hi, -lo]; }
  // The centre line: midway across, along the other axis (orthonormal with the long one).
  const [vx, vy] = axes[1 - k], mid = (extent[1 - k].lo + extent[1 - k].hi) / 2;
  const at = (t) => [ux * t + vx * mid, uy * t + vy * mid];
  const s = Math.min(hi - lo, Math.max(0, px * ux + py * uy - lo));
  return { ends: [at(lo), at(hi)], length: hi - lo, s };
}

/// The face of a wall (libs/bim: 'left' or 'right' of its axis) that the point (px, py) is on,
/// the axis running from `span.ends[from]` to the other end (wallSpan).
export function wallFace(span, from, px, py) {
  const [a, b] = from === 0 ? span.ends : [span.ends[1], span.ends[0]];
  const dx = b[0] - a[0], dy = b[1] - a[1];
  return dx * (py - a[1]) - dy * (px - a[0]) > 0 ? 'left' : 'right';  // left: (-dy, dx)
}
