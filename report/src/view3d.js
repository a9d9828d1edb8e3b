// The report's 3D view: input (left) and result (right) in one WebGL canvas
// with two viewports and one shared orbit camera, so turning one turns both.
// Faces are coloured by a per-face field (Q, log area distortion), by a uv
// checkerboard, or plainly shaded.
import {
  AmbientLight,
  BufferAttribute,
  BufferGeometry,
  Color,
  DataTexture,
  DirectionalLight,
  DoubleSide,
  Mesh,
  MeshLambertMaterial,
  NearestFilter,
  PerspectiveCamera,
  RepeatWrapping,
  RGBAFormat,
  Scene,
  SRGBColorSpace,
  Vector3,
  WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export function webglAvailable() {
  try {
    const c = document.createElement('canvas');
    return !!(c.getContext('webgl2') || c.getContext('webgl'));
  } catch (e) {
    return false;
  }
}

// Area-weighted vertex normals of one position set.
function vertexNormals(pos, tri, nv) {
  const n = new Float32Array(3 * nv);
  for (let f = 0; f < tri.length; f += 3) {
    const a = 3 * tri[f], b = 3 * tri[f + 1], c = 3 * tri[f + 2];
    const ux = pos[b] - pos[a], uy = pos[b + 1] - pos[a + 1], uz = pos[b + 2] - pos[a + 2];
    const vx = pos[c] - pos[a], vy = pos[c + 1] - pos[a + 1], vz = pos[c + 2] - pos[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    for (const v of [a, b, c]) {
      n[v] += nx;
      n[v + 1] += ny;
      n[v + 2] += nz;
    }
  }
  for (let v = 0; v < 3 * nv; v += 3) {
    const l = Math.hypot(n[v], n[v + 1], n[v + 2]) || 1;
    n[v] /= l;
    n[v + 1] /= l;
    n[v + 2] /= l;
  }
  return n;
}

function bounds(pos) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < pos.length; i += 3)
    for (let k = 0; k < 3; ++k) {
      lo[k] = Math.min(lo[k], pos[i + k]);
      hi[k] = Math.max(hi[k], pos[i + k]);
    }
  const centre = lo.map((l, k) => 0.5 * (l + hi[k]));
  let r = 0;
  for (let i = 0; i < pos.length; i += 3)
    r = Math.max(r, Math.hypot(pos[i] - centre[0], pos[i + 1] - centre[1], pos[i + 2] - centre[2]));
  return { centre, radius: r || 1 };
}

// One unindexed geometry per shape: three corners per face, so that a face
// can carry its own colour and uv; normals are the smooth vertex normals.
function buildGeometry(mesh, pos, scale, centre) {
  const tri = mesh.triangles, nv = mesh.nv;
  const normals = vertexNormals(pos, tri, nv);
  const corners = tri.length;
  const p = new Float32Array(3 * corners), n = new Float32Array(3 * corners), col = new Float32Array(3 * corners);
  for (let c = 0; c < corners; ++c) {
    const v = 3 * tri[c];
    for (let k = 0; k < 3; ++k) {
      p[3 * c + k] = (pos[v + k] - centre[k]) * scale;
      n[3 * c + k] = normals[v + k];
    }
  }
  const g = new BufferGeometry();
  g.setAttribute('position', new BufferAttribute(p, 3));
  g.setAttribute('normal', new BufferAttribute(n, 3));
  g.setAttribute('color', new BufferAttribute(col, 3));
  if (mesh.uv && mesh.uvTriangles) {
    const uv = new Float32Array(2 * corners);
    for (let c = 0; c < corners; ++c) {
      uv[2 * c] = mesh.uv[2 * mesh.uvTriangles[c]];
      uv[2 * c + 1] = mesh.uv[2 * mesh.uvTriangles[c] + 1];
    }
    g.setAttribute('uv', new BufferAttribute(uv, 2));
  }
  return g;
}

function checkerTexture() {
  const size = 2;
  const texel = new Uint8Array(4 * size * size);
  const light = [238, 238, 238, 255], dark = [60, 75, 110, 255];
  for (let i = 0; i < size * size; ++i) texel.set((i + (i >> 1)) % 2 ? dark : light, 4 * i);
  const t = new DataTexture(texel, size, size, RGBAFormat);
  t.magFilter = NearestFilter;
  t.minFilter = NearestFilter;
  t.wrapS = t.wrapT = RepeatWrapping;
  t.repeat.set(8, 8); // 16 squares per unit of uv, as `curvflow render --uv-checker`
  t.colorSpace = SRGBColorSpace;
  t.needsUpdate = true;
  return t;
}

// container: element to fill; mesh/fields from loadReportData. Returns
// { setColoring(fn or null), setChecker(bool), render() }.
export function createViewer(container, mesh) {
  const canvasHolder = document.createElement('div');
  canvasHolder.className = 'cf-canvas-holder';
  container.appendChild(canvasHolder);
  const renderer = new WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setScissorTest(true);
  canvasHolder.appendChild(renderer.domElement);
  for (const [cls, text] of [['cf-pane-label left', 'input'], ['cf-pane-label right', 'result']]) {
    const label = document.createElement('div');
    label.className = cls;
    label.textContent = text;
    canvasHolder.appendChild(label);
  }

  // both shapes at one scale (sizes compare truthfully), each centred on
  // its own bounding box
  const b0 = bounds(mesh.input), b1 = bounds(mesh.result);
  const scale = 1 / Math.max(b0.radius, b1.radius);
  const geometries = [buildGeometry(mesh, mesh.input, scale, b0.centre), buildGeometry(mesh, mesh.result, scale, b1.centre)];
  const texture = checkerTexture();
  const materials = geometries.map(
    () => new MeshLambertMaterial({ vertexColors: true, side: DoubleSide, color: new Color(1, 1, 1) }),
  );
  const scenes = geometries.map((g, i) => {
    const s = new Scene();
    s.background = new Color(0xffffff);
    s.add(new Mesh(g, materials[i]));
    s.add(new AmbientLight(0xffffff, 1.1));
    const head = new DirectionalLight(0xffffff, 2.0);
    s.add(head);
    s.userData.head = head;
    return s;
  });

  const camera = new PerspectiveCamera(30, 1, 0.01, 100);
  const fit = 1.08 / Math.sin((camera.fov * Math.PI) / 360);
  const home = new Vector3(0.4, 0.5, 1).normalize().multiplyScalar(fit);
  camera.position.copy(home);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;

  function render() {
    const w = canvasHolder.clientWidth, h = canvasHolder.clientHeight;
    if (w === 0 || h === 0) return;
    const half = Math.floor(w / 2);
    camera.aspect = half / h;
    camera.updateProjectionMatrix();
    scenes.forEach((s, i) => {
      s.userData.head.position.copy(camera.position);
      renderer.setViewport(i * half, 0, half, h);
      renderer.setScissor(i * half, 0, half, h);
      renderer.render(s, camera);
    });
  }
  function resize() {
    renderer.setSize(canvasHolder.clientWidth, canvasHolder.clientHeight, false);
    render();
  }
  controls.addEventListener('change', render);
  new ResizeObserver(resize).observe(canvasHolder);

  return {
    canvas: renderer.domElement,
    // colourOf(face) -> [r, g, b] in [0, 1], or null for plain grey
    setColoring(colourOf) {
      for (const g of geometries) {
        const col = g.getAttribute('color');
        const a = col.array;
        for (let f = 0; f < mesh.nf; ++f) {
          const rgb = colourOf ? colourOf(f) : [0.72, 0.75, 0.82];
          for (let k = 0; k < 3; ++k) a.set(rgb, 9 * f + 3 * k);
        }
        col.needsUpdate = true;
      }
      for (const m of materials) {
        m.map = null;
        m.needsUpdate = true;
      }
      render();
    },
    hasUv: !!(mesh.uv && mesh.uvTriangles),
    setChecker() {
      for (const g of geometries) {
        const a = g.getAttribute('color').array;
        a.fill(1);
        g.getAttribute('color').needsUpdate = true;
      }
      for (const m of materials) {
        m.map = texture;
        m.needsUpdate = true;
      }
      render();
    },
    resetView() {
      camera.position.copy(home);
      controls.target.set(0, 0, 0);
      controls.update();
      render();
    },
    resize,
    render,
  };
}
