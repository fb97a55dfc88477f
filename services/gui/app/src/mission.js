// The drilling mission's YAML as the mission builder reads and writes it, without the DOM (tested
// by app/test/storey_test.mjs). The YAML text stays the one source of truth: every edit parses
// it, changes one line and writes it back, so a line not edited comes back exactly as it was.
// Only the simple form the app itself writes is understood (services/drill/README.md "Mission
// files"): top-level `key: value` lines (name, ifc, storey, patterns, depth), blank and comment
// lines, and `areas:` followed by one flow map per line (`  - {name: a, marks: blobs, ...}`).
// Anything else (block-style areas, unknown keys, nested values) is "edited by hand": parsing
// says why, and no edit touches it.

const FIELDS = new Set(['name', 'ifc', 'storey', 'patterns', 'depth']);
/// The keys of an area and how many numbers the list-valued ones take.
const AREA_KEYS = new Set(['name', 'marks', 'point', 'wall', 'at', 'pixel', 'face', 'expected']);
const LISTS = { point: 3, at: 2, pixel: 2 };
const NUMBER = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/;
const AREA_LINE = /^\s*-\s+\{(.*)\}\s*(#.*)?$/;

/// A scalar as YAML: plain when that reads back as the same text, else double-quoted (a JSON
/// string is a valid YAML double-quoted scalar).
export function yamlScalar(s) {
  s = String(s);
  if (/^[A-Za-z0-9_./-](?:[A-Za-z0-9_ ./-]*[A-Za-z0-9_./-])?$/.test(s) &&
      !/^(true|false|yes|no|on|off|null|~)$/i.test(s) && !/^[-.]/.test(s)) return s;
  return JSON.stringify(s);
}

/// One scalar or flow list as written after `key:`; throws Error saying what is not simple.
function parseValue(text, where) {
  const t = text.trim();
  if (t.startsWith('[')) {
    if (!t.endsWith(']')) throw new Error(`${where}: an unclosed list`);
    const inner = t.slice(1, -1).trim();
    const parts = inner ? inner.split(',').map((p) => p.trim()) : [];
    if (!parts.every((p) => NUMBER.test(p))) throw new Error(`${where}: a list of anything but numbers`);
    return parts.map(Number);
  }
  if (t.startsWith('"')) {
    try { return String(JSON.parse(t)); } catch (e) { throw new Error(`${where}: a double-quoted string the builder does not read`); }
  }
  if (t.startsWith("'")) {
    if (!/^'([^']|'')*'$/.test(t)) throw new Error(`${where}: an unclosed single-quoted string`);
    return t.slice(1, -1).replace(/''/g, "'");
  }
  if (/^[{[&*!|>%@`]/.test(t) || /:(\s|$)/.test(t)) throw new Error(`${where}: a value the builder does not read`);
  return t;
}

/// The entries of a flow map's inside ("name: a, point: [1, 2, 3]") split at its top-level commas.
function splitEntries(inner, where) {
  const out = [];
  let depth = 0, quote = '', start = 0;
  for (let i = 0; i < inner.length; i++) {
    const c = inner[i];
    if (quote) {
      if (c === '\\' && quote === '"') i++;
      else if (c === quote) quote = '';
    } else if (c === '"' || c === "'") quote = c;
    else if (c === '[') depth++;
    else if (c === ']') depth--;
    else if (c === '{') throw new Error(`${where}: a nested map`);
    else if (c === ',' && depth === 0) { out.push(inner.slice(start, i)); start = i + 1; }
  }
  if (quote || depth !== 0) throw new Error(`${where}: unbalanced quotes or brackets`);
  out.push(inner.slice(start));
  return out.map((e) => e.trim()).filter((e) => e !== '');
}

/// An area from the inside of its flow map.
function parseArea(inner, where) {
  const area = {};
  for (const entry of splitEntries(inner, where)) {
    const m = entry.match(/^([A-Za-z_]+)\s*:\s*(.*)$/s);
    if (!m) throw new Error(`${where}: '${entry}' is not 'key: value'`);
    const [, key, raw] = m;
    if (!AREA_KEYS.has(key)) throw new Error(`${where}: the key '${key}'`);
    if (key in area) throw new Error(`${where}: '${key}' twice`);
    const v = parseValue(raw, `${where}, ${key}`);
    if (key in LISTS) {
      if (!Array.isArray(v) || v.length !== LISTS[key]) throw new Error(`${where}: ${key} is not a list of ${LISTS[key]} numbers`);
    } else if (Array.isArray(v)) {
      throw new Error(`${where}: ${key} is a list`);
    } else if (key === 'expected' && !/^\d+$/.test(v)) {
      throw new Error(`${where}: expected is not a whole number`);
    }
    area[key] = key === 'expected' ? Number(v) : v;
  }
  return area;
}

/// The mission in `yaml`: {ok: true, fields: {name, depth, ...} (strings), areas: [area],
/// items} or {ok: false, why} when it is not the simple form. An area has the keys it was
/// written with: name, marks, point [x, y, z], wall, at [s, h], pixel [u, v], face, expected.
/// `items` are the lines: {kind: 'raw' | 'field' | 'areas' | 'area', text, key?, area?}.
export function parseMission(yaml) {
  const items = [], fields = {}, areas = [];
  let inAreas = false, sawAreas = false;
  const lines = yaml.split('\n');
  try {
    lines.forEach((text, i) => {
      const where = `line ${i + 1}`;
      if (/^\s*(#.*)?$/.test(text)) { items.push({ kind: 'raw', text }); return; }
      const am = text.match(AREA_LINE);
      if (am) {
        if (!inAreas) throw new Error(`${where}: an area outside 'areas:'`);
        const area = parseArea(am[1], `${where} (area ${areas.length + 1})`);
        areas.push(area);
        items.push({ kind: 'area', text, area });
        return;
      }
      if (/^\s/.test(text) || /^-/.test(text)) throw new Error(`${where}: '${text.trim()}' (only one area per line, as a {...} map)`);
      inAreas = false;
      const m = text.match(/^([A-Za-z_]+):(?:\s+(.*?))?\s*$/);
      if (!m) throw new Error(`${where}: '${text}' is not 'key: value'`);
      const [, key, rest = ''] = m;
      if (key === 'areas') {
        if (sawAreas) throw new Error(`${where}: 'areas' twice`);
        if (rest && !rest.startsWith('#')) throw new Error(`${where}: areas written on one line`);
        sawAreas = inAreas = true;
        items.push({ kind: 'areas', text });
        return;
      }
      if (!FIELDS.has(key)) throw new Error(`${where}: the key '${key}'`);
      if (key in fields) throw new Error(`${where}: '${key}' twice`);
      // A plain value ends at a comment; a quoted one at its closing quote.
      const quoted = rest.match(/^("(?:[^"\\]|\\.)*"|'(?:[^']|'')*')\s*(#.*)?$/);
      const value = parseValue(quoted ? quoted[1] : rest.replace(/\s+#.*$/, ''), `${where}, ${key}`);
      if (Array.isArray(value)) throw new Error(`${where}: ${key} is a list`);
      fields[key] = value;
      items.push({ kind: 'field', text, key });
    });
  } catch (e) {
    return { ok: false, why: e.message };
  }
  return { ok: true, fields, areas, items };
}

const num = (v) => v.toFixed(3);
/// An area's line as the app writes it (keys in the README's order).
export function areaLine(a) {
  const parts = [];
  if (a.name !== undefined) parts.push(`name: ${yamlScalar(a.name)}`);
  if (a.marks !== undefined) parts.push(`marks: ${yamlScalar(a.marks)}`);
  if (a.point) parts.push(`point: [${a.point.map(num).join(', ')}]`);
  if (a.wall !== undefined) parts.push(`wall: ${JSON.stringify(String(a.wall))}`);
  if (a.at) parts.push(`at: [${a.at.map(num).join(', ')}]`);
  if (a.pixel) parts.push(`pixel: [${a.pixel.map((v) => String(Math.round(v))).join(', ')}]`);
  if (a.face !== undefined) parts.push(`face: ${yamlScalar(a.face)}`);
  if (a.expected !== undefined) parts.push(`expected: ${a.expected}`);
  return `  - {${parts.join(', ')}}`;
}
/// The text of parsed items (an item without `text` is written the app's way).
function emit(items) {
  return items.map((it) => {
    if (it.text !== undefined) return it.text;
    if (it.kind === 'area') return areaLine(it.area);
    return `${it.key}: ${yamlScalar(it.value)}`;
  }).join('\n');
}
function simple(yaml) {
  const m = parseMission(yaml);
  if (!m.ok) throw new Error('edited by hand: ' + m.why);
  return m;
}

/// The height of an area [m]: a point's z, a BIM wall area's h; null for a pixel area.
export function areaHeight(a) {
  if (a.point) return a.point[2];
  if (a.at) return a.at[1];
  return null;
}
/// The YAML with area `index` (0-based) changed: `change` may set marks, height, expected.
export function editArea(yaml, index, change) {
  const m = simple(yaml);
  const item = m.items.filter((it) => it.kind === 'area')[index];
  if (!item) throw new Error(`no area ${index + 1}`);
  const a = { ...item.area };
  if (change.marks !== undefined) a.marks = change.marks;
  if (change.expected !== undefined) a.expected = change.expected;
  if (change.height !== undefined) {
    if (a.point) a.point = [a.point[0], a.point[1], change.height];
    else if (a.at) a.at = [a.at[0], change.height];
  }
  item.area = a;
  delete item.text;
  return emit(m.items);
}
/// The YAML without area `index` (0-based).
export function removeArea(yaml, index) {
  const m = simple(yaml);
  const item = m.items.filter((it) => it.kind === 'area')[index];
  if (!item) throw new Error(`no area ${index + 1}`);
  return emit(m.items.filter((it) => it !== item));
}
/// The YAML with the top-level `key` set to `value` (a new line before `areas:` when there is
/// none); an empty value removes the line.
export function setField(yaml, key, value) {
  if (!FIELDS.has(key)) throw new Error(`'${key}' is not a mission field`);
  const m = simple(yaml);
  const at = m.items.findIndex((it) => it.kind === 'field' && it.key === key);
  value = String(value).trim();
  if (at >= 0) {
    if (value === '') m.items.splice(at, 1);
    else m.items[at] = { kind: 'field', key, value };
  } else if (value !== '') {
    let before = m.items.findIndex((it) => it.kind === 'areas');
    if (before < 0) {  // before the trailing blank lines
      before = m.items.length;
      while (before > 0 && m.items[before - 1].kind === 'raw' && m.items[before - 1].text === '') before--;
    }
    m.items.splice(before, 0, { kind: 'field', key, value });
  }
  const out = emit(m.items);
  return out === '' || out.endsWith('\n') ? out : out + '\n';
}
