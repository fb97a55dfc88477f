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
  const lines = yaml.replace(/\s*$/, '').split('\n');
  const names = new Set(lines.flatMap((l) => [...l.matchAll(/name:\s*([\w-]+)/g)].map((m) => m[1])));
  let n = 1;
  while (names.has('pick' + n)) n++;
  const name = 'pick' + n;
  const area = `  - {name: ${name}, marks: ${marks}, point: [${point.map((v) => v.toFixed(3)).join(', ')}]` +
    `${marks === 'blobs' ? ', expected: 1' : ''}}`;
  let at = lines.findIndex((l) => /^areas:\s*$/.test(l));
  if (at < 0) {
    if (lines.length === 1 && lines[0] === '') lines.pop();
    lines.push('areas:');
    at = lines.length - 1;
  }
  let end = at + 1;
  while (end < lines.length && /^(\s+|-)/.test(lines[end])) end++;
  lines.splice(end, 0, area);
  return { yaml: lines.join('\n') + '\n', name };
}
