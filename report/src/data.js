// Decoding of the report's embedded data (written by cli/cmd_report.c):
// binary arrays are base64 strings of little-endian float32 / uint32 values.

function bytesOf(b64) {
  const text = atob(b64);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
  return bytes;
}

function view(b64, Type, expected, name) {
  if (typeof b64 !== 'string') return null;
  const bytes = bytesOf(b64);
  if (bytes.length % 4 !== 0) throw new Error(`report data: ${name} has ${bytes.length} bytes, not a multiple of 4`);
  const out = new Type(bytes.length / 4);
  const dv = new DataView(bytes.buffer);
  const get = Type === Float32Array ? (i) => dv.getFloat32(4 * i, true) : (i) => dv.getUint32(4 * i, true);
  for (let i = 0; i < out.length; ++i) out[i] = get(i);
  if (expected !== undefined && out.length !== expected)
    throw new Error(`report data: ${name} has ${out.length} values, expected ${expected}`);
  return out;
}

export function decodeF32(b64, expected, name) {
  return view(b64, Float32Array, expected, name);
}

export function decodeU32(b64, expected, name) {
  return view(b64, Uint32Array, expected, name);
}

// The page's data object, with its arrays decoded and checked against the
// counts it states.
export function loadReportData(doc) {
  const el = doc.getElementById('curvflow-data');
  if (!el) throw new Error('report data: no element #curvflow-data');
  const data = JSON.parse(el.textContent);
  if (data.format !== 'curvflow-report-1') throw new Error(`report data: unknown format ${data.format}`);
  const m = data.mesh;
  const nv = m.vertices, nf = m.faces;
  const mesh = {
    nv,
    nf,
    triangles: decodeU32(m.triangles, 3 * nf, 'triangles'),
    input: decodeF32(m.input, 3 * nv, 'input positions'),
    result: decodeF32(m.result, 3 * nv, 'result positions'),
    uv: m.uv ? decodeF32(m.uv, undefined, 'uv') : null,
    uvTriangles: m.uv_triangles ? decodeU32(m.uv_triangles, 3 * nf, 'uv triangles') : null,
  };
  for (let i = 0; i < mesh.triangles.length; ++i)
    if (mesh.triangles[i] >= nv) throw new Error(`report data: face ${Math.floor(i / 3)} uses vertex ${mesh.triangles[i]} >= ${nv}`);
  if (mesh.uv && mesh.uvTriangles)
    for (let i = 0; i < mesh.uvTriangles.length; ++i)
      if (2 * mesh.uvTriangles[i] + 1 >= mesh.uv.length)
        throw new Error(`report data: corner ${i} uses uv ${mesh.uvTriangles[i]} >= ${mesh.uv.length / 2}`);
  const fields = {};
  for (const [name, b64] of Object.entries(data.fields || {})) fields[name] = decodeF32(b64, nf, name);
  return { data, mesh, fields };
}
