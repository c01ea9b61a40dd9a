// IFC (IFC2x3 / IFC4) -> fploc building (JSON on stdout), read by modules/floorplan/src/ifc.cpp.
//
//   node tools/ifc/ifc2plan.mjs [--cut-height 1.0] [--classes IfcWall,IfcColumn,...] FILE.ifc
//
// web-ifc (npm, MPL-2.0) parses the STEP file and turns every element's representation into a
// triangle mesh (openings already subtracted) with a placement matrix. This script only cuts those
// meshes with a horizontal plane at `cut height` above each storey's floor: each triangle crossing
// the plane gives one segment; segments of one element that continue each other on a line are
// merged. Layers are the IFC class names (IfcWall, IfcCurtainWall, IfcColumn, ...), so layer globs
// such as 'IfcWall*' select them.
//
// Storeys: IfcBuildingStorey with its Elevation (model length unit -> metres). A model without
// storeys is one floor named after its IfcBuilding (elevation 0). Ceiling heights: per storey, the
// lowest underside of an IfcSlab / IfcCovering / IfcRoof above the cut plane and below the next
// storey's cut plane (relative to the storey's floor); per IfcSpace that crosses the cut plane, its
// footprint (the cut outline) and its top as the area's ceiling height.
//
// Output: {"schema", "source", "storeys":[{"name","id","elevation","ceiling_height",
//          "elements":[{"layer","id","a":[x,y],"b":[x,y]}],"spaces":[{"name","id","ceiling_height","polygon":[[x,y],..]}]}],
//          "unhandled_representation": N, "warnings": ["FILE:LINE: #ID=IFCTYPE: warning: ..."]}
// Warnings (also on stderr): an element of a cut class with a representation item web-ifc gives no
// geometry for (the element, or that part of it, is not in the plan); N counts those elements.
// Errors: one line on stderr "FILE:LINE: ..." or "FILE: #ID=IFCTYPE: ..." and exit status 2: a broken
// STEP structure (checkStep), a used entity that is malformed or refers to a missing one, or has an
// empty point list or an extrusion depth that is not > 0 (checkUsed).
import fs from 'node:fs';

const DEFAULT_CLASSES = ['IfcWall', 'IfcWallStandardCase', 'IfcWallElementedCase', 'IfcCurtainWall', 'IfcPlate',
  'IfcMember', 'IfcColumn', 'IfcWindow', 'IfcDoor'];
const CEILING_CLASSES = ['IfcSlab', 'IfcCovering', 'IfcRoof'];

function die(msg) {
  process.stderr.write(msg + '\n');
  process.exit(2);
}

// ---- arguments
let cut = 1.0, classes = DEFAULT_CLASSES, file = null;
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; ++i) {
  if (argv[i] === '--cut-height') cut = Number(argv[++i]);
  else if (argv[i] === '--classes') classes = argv[++i].split(',').filter((s) => s);
  else if (argv[i].startsWith('--')) die(`ifc2plan: unknown option ${argv[i]}`);
  else file = argv[i];
}
if (!file) die('usage: ifc2plan.mjs [--cut-height M] [--classes A,B] FILE.ifc');
if (!(cut > 0) || !Number.isFinite(cut)) die(`ifc2plan: --cut-height must be > 0 (got ${cut})`);

let bytes;
try {
  bytes = fs.readFileSync(file);
} catch (e) {
  die(`${file}: cannot open (${e.message})`);
}

// ---- STEP syntax check (web-ifc skips what it cannot parse silently; a truncated or garbled file
// must be one clear error naming the line). Checks the header, that every DATA record is
// "#id=TYPE(...);" with balanced parentheses outside strings, and the trailer. Indexes the records
// in `entities` (id -> {type, line, args: offset after '(', end: offset of ';'}) for checkUsed.
const entities = new Map();
function checkStep(text) {
  if (!text.startsWith('ISO-10303-21;')) die(`${file}:1: not an IFC (STEP) file: it does not start with ISO-10303-21;`);
  const schema = /FILE_SCHEMA\s*\(\s*\(\s*'([^']*)'/i.exec(text);
  if (!schema) die(`${file}: no FILE_SCHEMA in the header`);
  const s = schema[1].toUpperCase();
  if (!/^IFC(2X3|4|4X1|4X2|4X3)/.test(s)) die(`${file}: unsupported IFC schema '${schema[1]}' (IFC2X3 and IFC4 are read)`);
  const dataAt = text.search(/^DATA;/m);
  if (dataAt < 0) die(`${file}: no DATA section`);
  let line = text.slice(0, dataAt).split('\n').length;
  let depth = 0, inStr = false, recStart = -1, recLine = line, recText = '', lastId = '';
  let ended = false;
  for (let i = dataAt + 5; i < text.length; ++i) {
    const c = text[i];
    if (c === '\n') ++line;
    if (recStart < 0) {
      if (/\s/.test(c)) continue;
      if (text.startsWith('ENDSEC;', i)) {
        ended = true;
        break;
      }
      if (c !== '#') die(`${file}:${line}: expected an entity '#id=...' or ENDSEC;, got '${text.slice(i, i + 20).split('\n')[0]}'`);
      recStart = i;
      recLine = line;
      continue;
    }
    if (inStr) {
      if (c === "'") {
        if (text[i + 1] === "'") ++i;
        else inStr = false;
      }
      continue;
    }
    if (c === "'") inStr = true;
    else if (c === '(') ++depth;
    else if (c === ')') {
      if (--depth < 0) die(`${file}:${line}: ${head(text, recStart)}: unbalanced ')'`);
    } else if (c === ';' && depth === 0) {
      recText = text.slice(recStart, i);
      const m = /^#(\d+)\s*=\s*([A-Za-z0-9_]+)\s*\(/.exec(recText);
      if (!m) die(`${file}:${recLine}: malformed entity '${recText.slice(0, 60)}'`);
      const id = Number(m[1]);
      const prev = entities.get(id);
      if (prev) die(`${file}:${recLine}: #${id} is defined twice (first at line ${prev.line})`);
      entities.set(id, { type: m[2].toUpperCase(), line: recLine, args: recStart + m[0].length, end: i });
      lastId = head(text, recStart);
      recStart = -1;
    }
  }
  if (recStart >= 0 || !ended)
    die(`${file}:${line}: truncated file: ${recStart >= 0 ? `entity ${head(text, recStart)} (line ${recLine}) is not finished` : 'no ENDSEC; after the DATA section'}` +
        (lastId ? ` (last complete entity ${lastId})` : ''));
  if (!/END-ISO-10303-21;\s*$/.test(text)) die(`${file}:${line}: truncated file: no END-ISO-10303-21; at the end`);
  return s;
}
function head(text, at) {
  const m = /^#(\d+)\s*=\s*([A-Za-z0-9_]+)/.exec(text.slice(at, at + 80));
  return m ? `#${m[1]}=${m[2].toUpperCase()}` : text.slice(at, at + 20);
}
const stepText = bytes.toString('latin1');
const schemaName = checkStep(stepText);

// ---- open with web-ifc (imported only now: loading it takes most of a second)
const WebIFC = await import('web-ifc');

// ---- the entities this script uses must be well-formed. web-ifc reads a bad number ('abc', '1.#INF')
// as 0, a missing argument as unset and a reference to a missing entity as nothing, so a corrupt file
// would give a distorted plan or lose a wall without a word. From every entity of the classes read
// (and the storeys, spaces, ceilings, units), every entity reachable by references is parsed here:
// each value must be valid STEP (number, 'string', #ref, .ENUM., $, *, TYPED(value) or a list), each
// reference must name an entity of the file, and an entity of a type the schema knows must have as
// many arguments as the schema's constructor (web-ifc's IFC2X3/IFC4/IFC4X3 classes) takes. Entities of
// types the schema does not know are not read by web-ifc and are left alone here, as are entities no
// used entity refers to (relations, property sets).
function checkUsed(text, schema, roots) {
  const ns = schema.startsWith('IFC2X3') ? WebIFC.IFC2X3 : schema.startsWith('IFC4X') ? WebIFC.IFC4X3 ?? WebIFC.IFC4 : WebIFC.IFC4;
  const arity = new Map();
  for (const [k, v] of Object.entries(ns ?? {})) if (typeof v === 'function' && k.startsWith('Ifc')) arity.set(k.toUpperCase(), v.length);
  const num = /[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?/y;
  const word = /[A-Za-z_][A-Za-z0-9_]*/y;
  const seen = new Set();
  let rec, recId, i, arg, refs, derived, spans;
  const bad = (what) => {
    throw new Error(`${file}:${rec.line}: #${recId}=${rec.type}: argument ${arg}: ${what}`);
  };
  const token = () => text.slice(i, Math.min(rec.end, i + 40)).split(/[,()\s]/)[0] || text.slice(i, i + 1);
  const ws = () => {
    while (i < rec.end && text.charCodeAt(i) <= 32) ++i;
  };
  function value() {
    ws();
    const c = text[i];
    if (c === '$') {
      ++i;
    } else if (c === '*') {  // an attribute derived in this subtype: not a constructor argument
      ++i;
      ++derived;
    } else if (c === "'") {
      for (++i; ; ++i) {
        if (i >= rec.end) bad('unterminated string');
        if (text[i] === "'") {
          if (text[i + 1] !== "'") break;
          ++i;
        }
      }
      ++i;
    } else if (c === '#') {
      const s = ++i;
      while (i < rec.end && text.charCodeAt(i) >= 48 && text.charCodeAt(i) <= 57) ++i;
      if (i === s) bad(`'#' without an entity number`);
      refs.push([Number(text.slice(s, i)), arg]);
    } else if (c === '(') {
      ++i;
      ws();
      if (text[i] === ')') {
        ++i;
        return;
      }
      for (;;) {
        value();
        ws();
        if (text[i] === ')') break;
        if (text[i] !== ',') bad(`expected ',' or ')' in a list, got '${token()}'`);
        ++i;
      }
      ++i;
    } else if (c === '"') {
      const e = text.indexOf('"', i + 1);
      if (e < 0 || e > rec.end || !/^[0-9A-Fa-f]*$/.test(text.slice(i + 1, e))) bad(`bad binary value '${token()}'`);
      i = e + 1;
    } else if (c === '.') {
      word.lastIndex = i + 1;
      if (!word.test(text) || text[word.lastIndex] !== '.') bad(`'${token()}' is not a number or an .ENUMERATION.`);
      i = word.lastIndex + 1;
    } else {
      word.lastIndex = i;
      if (word.test(text)) {  // a typed value IFCLABEL('x'), or garbage such as abc
        const s = i;
        i = word.lastIndex;
        ws();
        if (text[i] !== '(') {
          i = s;
          bad(`'${token()}' is not a number (nor a 'string', #reference, .ENUM., $ or typed value)`);
        }
        ++i;
        value();
        ws();
        if (text[i] !== ')') bad(`expected ')' after the typed value ${text.slice(s, s + 40).split('(')[0]}(...)`);
        ++i;
        return;
      }
      num.lastIndex = i;
      const s = i;
      if (!num.test(text)) bad(`'${token()}' is not a number`);
      i = num.lastIndex;
      const d = text[i];
      if (i < rec.end && d !== ',' && d !== ')' && !/\s/.test(d)) {
        i = s;
        bad(`'${token()}' is not a number`);
      }
      if (!Number.isFinite(Number(text.slice(s, i)))) bad(`'${text.slice(s, i)}' is not a finite number`);
    }
  }
  // Values web-ifc accepts although the schema does not, and that give no (or wrong) geometry without a
  // word: a coordinate list without points, an extrusion depth that is not > 0.
  const minItems = { IFCPOLYLINE: [1, 2, 'points'], IFCPOLYLOOP: [1, 3, 'points'], IFCCARTESIANPOINT: [1, 1, 'coordinates'],
    IFCCARTESIANPOINTLIST2D: [1, 1, 'points'], IFCCARTESIANPOINTLIST3D: [1, 1, 'points'] };
  const positive = { IFCEXTRUDEDAREASOLID: [4, 'depth'], IFCEXTRUDEDAREASOLIDTAPERED: [4, 'depth'] };
  function listItems(s, e) {  // number of items of the list text[s, e) ("(a,(b,c),'x')" -> 3), -1 if no list
    if (text[s] !== '(') return -1;
    if (text.slice(s + 1, e - 1).trim() === '') return 0;
    let depth = 0, n = 1, inStr = false;
    for (let k = s; k < e; ++k) {
      const c = text[k];
      if (inStr) {
        if (c === "'") inStr = false;  // '' (an escaped quote) reopens at the next character
      } else if (c === "'") inStr = true;
      else if (c === '(') ++depth;
      else if (c === ')') --depth;
      else if (c === ',' && depth === 1) ++n;
    }
    return n;
  }
  function checkValues(t, sp) {
    const mi = minItems[t];
    if (mi && sp.length >= mi[0]) {
      const [a, min, what] = mi;
      const n = listItems(sp[a - 1][0], sp[a - 1][1]);
      if (n >= 0 && n < min) {
        arg = a;
        bad(`${n === 0 ? `an empty list of ${what}` : `a list of ${n} ${what.replace(/s$/, '')}`} (${className(t)} needs at least ${min})`);
      }
    }
    const po = positive[t];
    if (po && sp.length >= po[0]) {
      const [a, what] = po;
      const v = text.slice(sp[a - 1][0], sp[a - 1][1]);
      if (!(Number(v) > 0)) {
        arg = a;
        bad(`${what} '${v}' is not > 0 (a positive length)`);
      }
    }
  }
  const className = (t) => Object.keys(ns ?? {}).find((k) => k.toUpperCase() === t) ?? t;
  const via = new Map();  // id -> the used entity it was reached from (for the message)
  try {
    for (const root of roots) {
      const stack = [root];
      while (stack.length) {
        recId = stack.pop();
        if (seen.has(recId)) continue;
        seen.add(recId);
        rec = entities.get(recId);
        const want = arity.get(rec.type);
        if (want === undefined) continue;  // a type web-ifc does not know: it ignores it, so do we
        i = rec.args;
        refs = [];
        spans = [];
        arg = 0;
        derived = 0;
        ws();
        if (text[i] !== ')') {
          for (;;) {
            ++arg;
            ws();
            const s = i;
            value();
            spans.push([s, i]);
            ws();
            if (text[i] === ')') break;
            if (text[i] !== ',') bad(`expected ',' or ')' after the argument, got '${token()}'`);
            ++i;
          }
        }
        if (arg - derived !== want && arg !== want) {
          const got = derived ? `${arg} (${derived} of them derived '*')` : `${arg}`;
          throw new Error(`${file}:${rec.line}: #${recId}=${rec.type}: expects ${want} argument${want === 1 ? '' : 's'}, got ${got}`);
        }
        checkValues(rec.type, spans);
        for (const [ref, a] of refs) {
          if (!entities.has(ref)) {
            arg = a;
            bad(`refers to #${ref}, which does not exist`);
          }
          if (ref === recId) {
            arg = a;
            bad('refers to the entity itself');
          }
          if (!seen.has(ref)) {
            if (!via.has(ref)) via.set(ref, via.get(recId) ?? recId);
            stack.push(ref);
          }
        }
      }
    }
  } catch (e) {
    const from = via.get(recId);
    die(e.message + (from !== undefined && from !== recId ? ` (used by #${from}=${entities.get(from).type})` : ''));
  }
}
{
  const used = new Set([...classes, ...CEILING_CLASSES, 'IfcSpace', 'IfcBuildingStorey', 'IfcBuilding', 'IfcUnitAssignment'].map((c) => c.toUpperCase()));
  const roots = [];
  for (const [id, e] of entities) if (used.has(e.type)) roots.push(id);
  checkUsed(stepText, schemaName, roots);
}
const api = new WebIFC.IfcAPI();
await api.Init();
api.SetLogLevel(WebIFC.LogLevel.LOG_LEVEL_OFF);
const model = api.OpenModel(new Uint8Array(bytes), { COORDINATE_TO_ORIGIN: false });
if (model < 0) die(`${file}: web-ifc cannot open the model`);
const type = (name) => api.GetTypeCodeFromName(name.toUpperCase());
const typeName = (code) => api.GetNameFromTypeCode(code);
const value = (x) => (x && typeof x === 'object' && 'value' in x ? x.value : x);
const label = (id) => {
  try {
    return `#${id}=${typeName(api.GetLineType(model, id)).toUpperCase()}`;
  } catch {
    return `#${id}`;
  }
};

// Length unit of the model (Elevation attributes are in it; web-ifc's meshes are in metres).
function lengthScale() {
  const prefix = { EXA: 1e18, PETA: 1e15, TERA: 1e12, GIGA: 1e9, MEGA: 1e6, KILO: 1e3, HECTO: 1e2, DECA: 1e1,
    DECI: 1e-1, CENTI: 1e-2, MILLI: 1e-3, MICRO: 1e-6, NANO: 1e-9 };
  for (const id of api.GetLineIDsWithType(model, type('IFCUNITASSIGNMENT'))) {
    const ua = api.GetLine(model, id, true);
    for (const u of ua.Units || []) {
      if (!u || value(u.UnitType) !== 'LENGTHUNIT') continue;
      if (u.Prefix !== undefined && value(u.Name) === 'METRE') return u.Prefix ? prefix[value(u.Prefix)] ?? 1 : 1;
      if (u.ConversionFactor) {
        const f = value(u.ConversionFactor.ValueComponent);
        const base = u.ConversionFactor.UnitComponent;
        const bs = base && base.Prefix ? prefix[value(base.Prefix)] ?? 1 : 1;
        if (Number.isFinite(f)) return f * bs;
      }
    }
  }
  return 1;
}
const unit = lengthScale();

// ---- storeys
const storeys = [];
for (const id of api.GetLineIDsWithType(model, type('IFCBUILDINGSTOREY'))) {
  const s = api.GetLine(model, id);
  const el = Number(value(s.Elevation));
  storeys.push({ name: String(value(s.Name) ?? value(s.LongName) ?? `#${id}`), id, elevation: Number.isFinite(el) ? el * unit : 0 });
}
if (storeys.length === 0) {
  const b = [...api.GetLineIDsWithType(model, type('IFCBUILDING'))];
  const name = b.length ? String(value(api.GetLine(model, b[0]).Name) ?? 'building') : 'building';
  storeys.push({ name, id: b[0] ?? 0, elevation: 0 });
}
storeys.sort((a, b) => a.elevation - b.elevation);
{
  const seen = new Map();
  for (const s of storeys) {  // unique names (storeys may share one)
    const n = seen.get(s.name) ?? 0;
    seen.set(s.name, n + 1);
    if (n) s.name = `${s.name} (#${s.id})`;
  }
}

// ---- meshes: world triangles in plan coordinates. web-ifc's frame is y-up: (x, y, z) -> plan
// (x, -z), height y.
function worldTriangles(mesh) {
  const tris = [];
  const geoms = mesh.geometries;
  for (let g = 0; g < geoms.size(); ++g) {
    const pg = geoms.get(g);
    const geo = api.GetGeometry(model, pg.geometryExpressID);
    const v = api.GetVertexArray(geo.GetVertexData(), geo.GetVertexDataSize());
    const ix = api.GetIndexArray(geo.GetIndexData(), geo.GetIndexDataSize());
    const T = pg.flatTransformation;
    const P = new Float64Array((v.length / 6) * 3);
    for (let i = 0, k = 0; i < v.length; i += 6, k += 3) {
      const x = v[i], y = v[i + 1], z = v[i + 2];
      const X = T[0] * x + T[4] * y + T[8] * z + T[12];
      const Y = T[1] * x + T[5] * y + T[9] * z + T[13];
      const Z = T[2] * x + T[6] * y + T[10] * z + T[14];
      P[k] = X;
      P[k + 1] = -Z;
      P[k + 2] = Y;
    }
    geo.delete();
    for (let t = 0; t + 2 < ix.length; t += 3) tris.push([ix[t] * 3, ix[t + 1] * 3, ix[t + 2] * 3, P]);
  }
  return tris;
}

// Segments where the plane z = h cuts the triangles.
function cutAt(tris, h) {
  const segs = [];
  for (const [i0, i1, i2, P] of tris) {
    const pts = [];
    const vs = [i0, i1, i2];
    for (let e = 0; e < 3; ++e) {
      const a = vs[e], b = vs[(e + 1) % 3];
      const za = P[a + 2] - h, zb = P[b + 2] - h;
      if ((za < 0) === (zb < 0)) continue;
      const t = za / (za - zb);
      pts.push([P[a] + t * (P[b] - P[a]), P[a + 1] + t * (P[b + 1] - P[a + 1])]);
    }
    if (pts.length === 2 && Math.hypot(pts[1][0] - pts[0][0], pts[1][1] - pts[0][1]) > 1e-6) segs.push(pts);
  }
  return segs;
}

// Merge segments that share an end point and continue on the same line (the two triangles of a
// face, a face split by the tessellation); drop exact duplicates.
function mergeCollinear(segs) {
  const key = (p) => `${Math.round(p[0] * 1e5)},${Math.round(p[1] * 1e5)}`;
  let changed = true;
  let list = segs.map((s) => [s[0], s[1]]);
  while (changed) {
    changed = false;
    const ends = new Map();
    list.forEach((s, i) => {
      for (const e of [0, 1]) {
        const k = key(s[e]);
        if (!ends.has(k)) ends.set(k, []);
        ends.get(k).push([i, e]);
      }
    });
    const dead = new Uint8Array(list.length);
    for (const [, at] of ends) {
      if (at.length !== 2) continue;
      const [[i, ei], [j, ej]] = at;
      if (i === j || dead[i] || dead[j]) continue;
      const s = list[i], t = list[j];
      const p = s[1 - ei], q = s[ei], r = t[1 - ej];
      const ux = q[0] - p[0], uy = q[1] - p[1], vx = r[0] - q[0], vy = r[1] - q[1];
      const lu = Math.hypot(ux, uy), lv = Math.hypot(vx, vy);
      if (Math.abs(ux * vy - uy * vx) > 1e-6 * lu * lv + 1e-12 || ux * vx + uy * vy <= 0) continue;
      list[i] = [p, r];
      dead[j] = 1;
      changed = true;
    }
    list = list.filter((_, i) => !dead[i]);
  }
  const seen = new Set();
  return list.filter((s) => {
    const a = key(s[0]), b = key(s[1]);
    const k = a < b ? a + '|' + b : b + '|' + a;
    if (seen.has(k) || a === b) return false;
    seen.add(k);
    return true;
  });
}

// Longest closed loop of a set of segments (a space's outline at the cut plane).
function outline(segs) {
  const key = (p) => `${Math.round(p[0] * 1e4)},${Math.round(p[1] * 1e4)}`;
  const adj = new Map();
  for (const s of segs) {
    for (const [a, b] of [[s[0], s[1]], [s[1], s[0]]]) {
      const k = key(a);
      if (!adj.has(k)) adj.set(k, { p: a, n: [] });
      adj.get(k).n.push(key(b));
    }
  }
  const used = new Set();
  let best = [];
  for (const [start] of adj) {
    if (used.has(start)) continue;
    const loop = [];
    let prev = null, cur = start;
    while (cur && !used.has(cur)) {
      used.add(cur);
      loop.push(adj.get(cur).p);
      const next = adj.get(cur).n.find((k) => k !== prev && !used.has(k));
      prev = cur;
      cur = next;
    }
    if (loop.length > best.length) best = loop;
  }
  return best;
}

// The representation items of an element (IfcMappedItem followed to the items of its mapped
// representation), each [id, representation identifier].
function representationItems(id) {
  const items = [];
  const walk = (repId, depth) => {
    const r = api.GetLine(model, repId);
    const ident = value(r.RepresentationIdentifier) ?? '';
    for (const it of r.Items || []) {
      const iid = value(it);
      if (api.GetLineType(model, iid) === type('IFCMAPPEDITEM') && depth < 8) {
        const map = api.GetLine(model, value(api.GetLine(model, iid).MappingSource));
        walk(value(map.MappedRepresentation), depth + 1);
      } else items.push([iid, ident]);
    }
  };
  const e = api.GetLine(model, id);
  if (e.Representation) for (const r of api.GetLine(model, value(e.Representation)).Representations || []) walk(value(r), 0);
  return items;
}

// Elements of the cut classes whose body has representation items web-ifc gives no geometry for
// (IfcBlock, IfcCsgSolid, IfcBoundingBox, an 'Axis' curve as the only representation, ...): without this they, or those
// parts of them, were left out of the plan without a word. One warning per element.
const warnings = [];
let unhandledElements = 0;
function checkRepresentation(id, mesh) {
  const got = new Set();
  for (let g = 0; mesh && g < mesh.geometries.size(); ++g) {  // items with at least one triangle
    const gid = mesh.geometries.get(g).geometryExpressID;
    const geo = api.GetGeometry(model, gid);
    if (geo.GetIndexDataSize() > 0) got.add(gid);
    geo.delete();
  }
  let items;
  try {
    items = representationItems(id);
  } catch {
    return;  // a representation web-ifc cannot even list: checkUsed has vetted the references
  }
  // With some geometry, only body items count (an 'Axis' polyline or a 'Box' gives none, rightly).
  const missing = items.filter(([iid, ident]) => !got.has(iid) && (got.size === 0 || ident === '' || ident === 'Body'));
  if (missing.length === 0) return;
  ++unhandledElements;
  const e = entities.get(id);
  const where = (iid) => `${label(iid)} (line ${entities.get(iid)?.line ?? '?'})`;
  const types = [...new Set(missing.map(([iid]) => typeName(api.GetLineType(model, iid))))];
  const w = `${file}:${e?.line ?? '?'}: ${label(id)}: warning: representation item${missing.length > 1 ? 's' : ''} ` +
    `${missing.map(([iid]) => where(iid)).join(', ')}: ${types.join(', ')} ${types.length > 1 ? 'are types' : 'is a type'} ` +
    `the IFC reader does not handle (no geometry): ${got.size ? 'that part of the element is' : 'the element is'} left out of the plan`;
  warnings.push(w);
  process.stderr.write(w + '\n');
}

function streamClass(cls, fn, check = false) {
  const code = type(cls);
  if (!code) return;
  const ids = [...api.GetLineIDsWithType(model, code)];
  for (const id of ids) {
    let mesh;
    try {
      mesh = api.GetFlatMesh(model, id);
    } catch (e) {
      die(`${file}: ${label(id)}: web-ifc cannot build its geometry (${e.message ?? e})`);
    }
    if (check) checkRepresentation(id, mesh);
    if (!mesh || mesh.geometries.size() === 0) continue;  // no body (e.g. a container)
    let tris;
    try {
      tris = worldTriangles(mesh);
    } catch (e) {
      die(`${file}: ${label(id)}: bad geometry (${e.message ?? e})`);
    }
    for (const t of tris)
      for (const k of [t[0], t[1], t[2]])
        if (!Number.isFinite(t[3][k]) || !Number.isFinite(t[3][k + 1]) || !Number.isFinite(t[3][k + 2]))
          die(`${file}: ${label(id)}: geometry has non-finite coordinates`);
    fn(id, tris);
  }
}

// Cut elements.
const out = storeys.map((s) => ({ ...s, ceiling_height: 0, elements: [], spaces: [] }));
for (const cls of classes) {
  const layer = typeName(type(cls)) || cls;
  streamClass(cls, (id, tris) => {
    for (const s of out) {
      for (const [a, b] of mergeCollinear(cutAt(tris, s.elevation + cut))) s.elements.push({ layer, id, a, b });
    }
  }, true);
}

// Ceilings: slab undersides above the cut plane of each storey, below the next storey's cut plane.
const undersides = [];  // [zmin, xmin, ymin, xmax, ymax]
for (const cls of CEILING_CLASSES) {
  streamClass(cls, (id, tris) => {
    let z = Infinity;
    for (const t of tris) for (const k of [t[0], t[1], t[2]]) z = Math.min(z, t[3][k + 2]);
    undersides.push(z);
  });
}
out.forEach((s, i) => {
  const lo = s.elevation + cut, hi = i + 1 < out.length ? out[i + 1].elevation + cut : Infinity;
  const zs = undersides.filter((z) => z > lo && z < hi);
  if (zs.length) s.ceiling_height = Math.min(...zs) - s.elevation;
});

// Spaces: footprint at the cut plane, top = the space's ceiling.
streamClass('IfcSpace', (id, tris) => {
  let top = -Infinity;
  for (const t of tris) for (const k of [t[0], t[1], t[2]]) top = Math.max(top, t[3][k + 2]);
  for (const s of out) {
    const poly = outline(cutAt(tris, s.elevation + cut));
    if (poly.length < 3) continue;
    const sp = api.GetLine(model, id);
    s.spaces.push({ name: String(value(sp.LongName) ?? value(sp.Name) ?? `#${id}`), id, ceiling_height: top - s.elevation, polygon: poly });
  }
});
api.CloseModel(model);

const total = out.reduce((n, s) => n + s.elements.length, 0);
if (total === 0)
  die(`${file}: no ${classes.join('/')} element crosses the cut plane ${cut} m above any storey's floor` +
      (unhandledElements ? ` (${unhandledElements} element${unhandledElements > 1 ? 's have' : ' has'} representation items the IFC reader does not handle: see the warnings above)` : ''));
process.stdout.write(JSON.stringify({ schema: schemaName, source: file, cut_height: cut, storeys: out,
  unhandled_representation: unhandledElements, warnings }));
