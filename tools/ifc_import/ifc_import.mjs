#!/usr/bin/env node
// IFC import step of libs/bim: reads an IFC2x3/IFC4 file with the web-ifc geometry engine and
// writes what the C++ core reads (libs/bim/README.md "Import format"):
//   OUT.json  storeys (name, GlobalId, elevation) and building elements (GlobalId, IFC type,
//             category, name, storey, host wall of doors/windows, wall placement) with the
//             offsets of their triangle meshes in OUT.bin;
//   OUT.bin   little-endian float32 vertices (x y z) then uint32 triangle indices.
// Frame: the IFC world frame (Z up, web-ifc's Y-up output converted back), in metres (the
// project's length unit applied by web-ifc's linear scaling factor). Openings are already cut
// into the walls' meshes by web-ifc.
// Usage: node ifc_import.mjs FILE.ifc OUT_PREFIX
// Exit codes: 0 success, 1 bad input file (message on stderr), 2 wrong command line.
import * as fs from 'node:fs';
import * as W from 'web-ifc';

const kCategories = [
  ['wall', ['IFCWALL', 'IFCWALLSTANDARDCASE', 'IFCWALLELEMENTEDCASE', 'IFCCURTAINWALL']],
  ['door', ['IFCDOOR', 'IFCDOORSTANDARDCASE']],
  ['window', ['IFCWINDOW', 'IFCWINDOWSTANDARDCASE']],
  ['column', ['IFCCOLUMN', 'IFCCOLUMNSTANDARDCASE']],
  ['slab', ['IFCSLAB', 'IFCSLABSTANDARDCASE', 'IFCSLABELEMENTEDCASE']],
  ['stair', ['IFCSTAIR', 'IFCSTAIRFLIGHT', 'IFCRAMP', 'IFCRAMPFLIGHT']],
  ['railing', ['IFCRAILING']],
  ['covering', ['IFCCOVERING']],
  ['furnishing', ['IFCFURNISHINGELEMENT', 'IFCFURNITURE']],
  ['beam', ['IFCBEAM', 'IFCBEAMSTANDARDCASE']],
  ['member', ['IFCMEMBER', 'IFCMEMBERSTANDARDCASE', 'IFCPLATE', 'IFCPLATESTANDARDCASE']],
  ['roof', ['IFCROOF']],
  ['proxy', ['IFCBUILDINGELEMENTPROXY']],
];

function fail(message, code = 1) {
  process.stderr.write(`ifc_import: ${message}\n`);
  process.exit(code);
}

const args = process.argv.slice(2);
if (args.length !== 2) fail('usage: ifc_import.mjs FILE.ifc OUT_PREFIX', 2);
const [inPath, outPrefix] = args;

let bytes;
try {
  bytes = fs.readFileSync(inPath);
} catch (e) {
  fail(`${inPath}: cannot read (${e.code === 'ENOENT' ? 'no such file' : e.message})`);
}
// The STEP physical file frame (ISO 10303-21): web-ifc reads whatever it is given, so the
// checks that name what is wrong come first.
const head = bytes.subarray(0, 256).toString('latin1').trimStart();
if (!head.startsWith('ISO-10303-21;')) {
  fail(`${inPath}: not an IFC file (an IFC-SPF file starts with 'ISO-10303-21;')`);
}
const tail = bytes.subarray(Math.max(0, bytes.length - 256)).toString('latin1').trimEnd();
if (!tail.endsWith('END-ISO-10303-21;')) {
  fail(`${inPath}: truncated IFC file (it does not end with 'END-ISO-10303-21;', ` +
       `${bytes.length} bytes read)`);
}
const schemaMatch = /FILE_SCHEMA\s*\(\s*\(\s*'([^']*)'/i.exec(bytes.subarray(0, 4096).toString('latin1'));
if (!schemaMatch) fail(`${inPath}: no FILE_SCHEMA in the header`);
const schema = schemaMatch[1].toUpperCase();
if (!/^IFC(2X3|4|4X3)/.test(schema)) {
  fail(`${inPath}: schema '${schemaMatch[1]}' is not IFC2X3 or IFC4`);
}

const api = new W.IfcAPI();
await api.Init();
api.SetLogLevel(W.LogLevel.LOG_LEVEL_OFF);
const model = api.OpenModel(new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.length),
                            { COORDINATE_TO_ORIGIN: false });
if (model < 0) fail(`${inPath}: web-ifc could not open the model`);

const text = (v) => (v && v.value !== undefined && v.value !== null ? String(v.value) : '');
const ref = (v) => (v && typeof v.value === 'number' ? v.value : null);
const ids = (type) => {
  const out = [];
  const v = api.GetLineIDsWithType(model, type);
  for (let i = 0; i < v.size(); ++i) out.push(v.get(i));
  return out;
};

// Length unit -> metres: web-ifc scales the meshes; the elevations and placements read here are
// in project units and scaled by the same factor, which is found from the IfcSIUnit/prefix.
const kPrefix = { EXA: 1e18, PETA: 1e15, TERA: 1e12, GIGA: 1e9, MEGA: 1e6, KILO: 1e3, HECTO: 1e2,
  DECA: 1e1, DECI: 1e-1, CENTI: 1e-2, MILLI: 1e-3, MICRO: 1e-6, NANO: 1e-9, PICO: 1e-12 };
function lengthScale() {
  for (const id of ids(W.IFCUNITASSIGNMENT)) {
    const ua = api.GetLine(model, id);
    for (const u of ua.Units || []) {
      const unit = api.GetLine(model, ref(u));
      if (!unit || text(unit.UnitType) !== 'LENGTHUNIT') continue;
      if (unit.type === W.IFCSIUNIT) {
        return text(unit.Prefix) ? kPrefix[text(unit.Prefix)] ?? 1 : 1;
      }
      if (unit.type === W.IFCCONVERSIONBASEDUNIT) {
        const m = api.GetLine(model, ref(unit.ConversionFactor));
        const value = m && m.ValueComponent ? Number(m.ValueComponent.value) : NaN;
        const base = m ? api.GetLine(model, ref(m.UnitComponent)) : null;
        const baseScale = base && text(base.Prefix) ? kPrefix[text(base.Prefix)] ?? 1 : 1;
        if (Number.isFinite(value)) return value * baseScale;
      }
    }
  }
  return 1;
}
const scale = lengthScale();

// web-ifc's Y-up frame -> the IFC Z-up frame: (x, y, z)_ifc = (x, -z, y)_webifc.
const toZUp = (x, y, z) => [x, -z, y];
// A column-major 4x4 mesh placement in web-ifc's Y-up frame (its linear part scaled by the
// length unit) -> origin and unit x axis in the Z-up frame.
function placementZUp(m) {
  const n = Math.hypot(m[0], m[1], m[2]) || 1;
  return { origin: toZUp(m[12], m[13], m[14]), x_axis: toZUp(m[0] / n, m[1] / n, m[2] / n) };
}

// Storeys, with the world elevation of their placement (GetWorldTransformMatrix: Z up, project
// units).
const storeys = [];
const storeyByExpress = new Map();
for (const id of ids(W.IFCBUILDINGSTOREY)) {
  const s = api.GetLine(model, id);
  let elevation = Number(text(s.Elevation)) * scale;
  const placement = ref(s.ObjectPlacement);
  if (placement !== null) {
    const m = api.GetWorldTransformMatrix(model, placement);
    if (m && m.length === 16) elevation = m[14] * scale;
  }
  if (!Number.isFinite(elevation)) elevation = 0;
  const storey = { name: text(s.Name) || text(s.LongName) || text(s.GlobalId), global_id: text(s.GlobalId),
                   elevation, express_id: id };
  storeys.push(storey);
  storeyByExpress.set(id, storey);
}
storeys.sort((a, b) => a.elevation - b.elevation);

// Spatial containment and decomposition: element -> storey, following IfcRelAggregates parents
// (a stair flight in its stair, a space in its storey).
const parentOf = new Map();
for (const id of ids(W.IFCRELAGGREGATES)) {
  const r = api.GetLine(model, id);
  for (const o of r.RelatedObjects || []) parentOf.set(ref(o), ref(r.RelatingObject));
}
const containerOf = new Map();
for (const id of ids(W.IFCRELCONTAINEDINSPATIALSTRUCTURE)) {
  const r = api.GetLine(model, id);
  for (const e of r.RelatedElements || []) containerOf.set(ref(e), ref(r.RelatingStructure));
}
function storeyOf(expressId) {
  let cur = expressId;
  for (let depth = 0; depth < 32 && cur !== null && cur !== undefined; ++depth) {
    if (storeyByExpress.has(cur)) return storeyByExpress.get(cur);
    cur = containerOf.has(cur) ? containerOf.get(cur) : parentOf.get(cur);
  }
  return null;
}

// Doors and windows -> the element whose opening they fill.
const openingHost = new Map();
for (const id of ids(W.IFCRELVOIDSELEMENT)) {
  const r = api.GetLine(model, id);
  openingHost.set(ref(r.RelatedOpeningElement), ref(r.RelatingBuildingElement));
}
const hostOf = new Map();
for (const id of ids(W.IFCRELFILLSELEMENT)) {
  const r = api.GetLine(model, id);
  const host = openingHost.get(ref(r.RelatingOpeningElement));
  if (host !== undefined) hostOf.set(ref(r.RelatedBuildingElement), host);
}

const elements = [];
const elementByExpress = new Map();
for (const [category, typeNames] of kCategories) {
  for (const typeName of typeNames) {
    const code = W[typeName];
    if (code === undefined) continue;
    for (const id of ids(code)) {
      const e = api.GetLine(model, id);
      const element = { global_id: text(e.GlobalId), ifc_type: api.GetNameFromTypeCode(code),
                        category, name: text(e.Name), express_id: id, storey: null,
                        storey_from: 'containment', host: null, placement: null,
                        vertex_offset: 0, vertex_count: 0, index_offset: 0, index_count: 0 };
      const s = storeyOf(id);
      if (s) element.storey = s.global_id;
      elements.push(element);
      elementByExpress.set(id, element);
    }
  }
}
for (const [filler, host] of hostOf) {
  const e = elementByExpress.get(filler);
  const h = elementByExpress.get(host);
  if (e && h) e.host = h.global_id;
}

// Meshes in world coordinates (metres, Z up), one triangle soup per element.
const vertexChunks = [];
const indexChunks = [];
let vertexTotal = 0;
let indexTotal = 0;
const wanted = [...new Set(elements.map((e) => W[e.ifc_type.toUpperCase()]).filter((c) => c !== undefined))];
api.StreamAllMeshesWithTypes(model, wanted, (mesh) => {
  const element = elementByExpress.get(mesh.expressID);
  if (!element) return;
  const verts = [];
  const tris = [];
  for (let g = 0; g < mesh.geometries.size(); ++g) {
    const placed = mesh.geometries.get(g);
    const m = placed.flatTransformation;
    if (element.placement === null) element.placement = placementZUp(m);
    const geometry = api.GetGeometry(model, placed.geometryExpressID);
    const v = api.GetVertexArray(geometry.GetVertexData(), geometry.GetVertexDataSize());
    const ix = api.GetIndexArray(geometry.GetIndexData(), geometry.GetIndexDataSize());
    const base = verts.length / 3;
    for (let k = 0; k < v.length; k += 6) {
      const x = v[k], y = v[k + 1], z = v[k + 2];
      const wx = m[0] * x + m[4] * y + m[8] * z + m[12];
      const wy = m[1] * x + m[5] * y + m[9] * z + m[13];
      const wz = m[2] * x + m[6] * y + m[10] * z + m[14];
      verts.push(...toZUp(wx, wy, wz));
    }
    for (let k = 0; k < ix.length; ++k) tris.push(ix[k] + base);
    geometry.delete();
  }
  element.vertex_offset = vertexTotal;
  element.vertex_count = verts.length / 3;
  element.index_offset = indexTotal;
  element.index_count = tris.length;
  vertexChunks.push(Float32Array.from(verts));
  indexChunks.push(Uint32Array.from(tris));
  vertexTotal += verts.length / 3;
  indexTotal += tris.length;
});

// Elements in no storey: the storey with the highest elevation at or below the element's lowest
// point (the lowest storey when it is below all of them).
const vertexData = new Float32Array(vertexTotal * 3);
{
  let at = 0;
  for (const c of vertexChunks) { vertexData.set(c, at); at += c.length; }
}
for (const e of elements) {
  if (e.storey !== null || storeys.length === 0) continue;
  e.storey_from = 'height';
  let zMin = Infinity;
  for (let k = 0; k < e.vertex_count; ++k) zMin = Math.min(zMin, vertexData[(e.vertex_offset + k) * 3 + 2]);
  let chosen = storeys[0];
  for (const s of storeys) if (s.elevation <= zMin + 0.05) chosen = s;
  e.storey = chosen.global_id;
}

const binPath = `${outPrefix}.bin`;
const indexData = new Uint32Array(indexTotal);
{
  let at = 0;
  for (const c of indexChunks) { indexData.set(c, at); at += c.length; }
}
try {
  const fd = fs.openSync(binPath, 'w');
  fs.writeSync(fd, new Uint8Array(vertexData.buffer));
  fs.writeSync(fd, new Uint8Array(indexData.buffer));
  fs.closeSync(fd);
  const out = {
    format: 'concert-ifc-import', version: 1, source: inPath, schema: api.GetModelSchema(model),
    length_unit_m: scale, web_ifc: api.GetVersion(), frame: 'IFC world, Z up, metres',
    binary: { file: binPath.split('/').pop(), vertex_count: vertexTotal, index_count: indexTotal },
    storeys: storeys.map(({ express_id, ...s }) => s),
    elements: elements.map(({ express_id, ...e }) => e),
  };
  fs.writeFileSync(`${outPrefix}.json`, JSON.stringify(out));
} catch (e) {
  fail(`cannot write ${outPrefix}.json/.bin: ${e.message}`);
}
api.CloseModel(model);
