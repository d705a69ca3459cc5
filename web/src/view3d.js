// The report's 3D view of a machined surface: the simulation's height field as a triangle mesh
// (two triangles per grid cell) in three.js, orbit/pan/zoom with OrbitControls, coloured by
// height or by the deviation from the nominal slot. Bundled as the global TrochomillView3D,
// loaded only by reports with a simulation.
import {
  AmbientLight, BufferAttribute, BufferGeometry, Color, DirectionalLight, DoubleSide, Mesh,
  MeshLambertMaterial, PerspectiveCamera, Scene, Vector3, WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

// opts: { grid: {columns, rows, x0_mm, x1_mm, y0_mm, y1_mm}, z: heights (row-major, mm),
// slot: {x_min_mm, x_max_mm, y_min_mm, y_max_mm, depth_mm}, palette(f) -> [r, g, b] }
export function createView(box, opts) {
  const { grid, z, slot, palette } = opts;
  const nx = grid.columns, ny = grid.rows;
  const width = Math.max(320, Math.floor(box.getBoundingClientRect().width || 900));
  const height = Math.max(240, Math.floor(box.getBoundingClientRect().height || 520));
  const renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  box.append(renderer.domElement);

  const dx = nx > 1 ? (grid.x1_mm - grid.x0_mm) / (nx - 1) : 0;
  const dy = ny > 1 ? (grid.y1_mm - grid.y0_mm) / (ny - 1) : 0;
  const n = nx * ny;
  const pos = new Float32Array(3 * n);
  const nominal = new Float32Array(n);
  for (let r = 0; r < ny; r++) {
    for (let c = 0; c < nx; c++) {
      const i = r * nx + c;
      const x = grid.x0_mm + c * dx, y = grid.y0_mm + r * dy;
      pos[3 * i] = x;
      pos[3 * i + 1] = y;
      pos[3 * i + 2] = Number.isNaN(z[i]) ? 0 : z[i];
      const inSlot = x >= slot.x_min_mm && x <= slot.x_max_mm && y >= slot.y_min_mm && y <= slot.y_max_mm;
      nominal[i] = inSlot ? -slot.depth_mm : 0;
    }
  }
  const index = new Uint32Array(6 * (nx - 1) * (ny - 1));
  let k = 0;
  for (let r = 0; r + 1 < ny; r++) {
    for (let c = 0; c + 1 < nx; c++) {
      const a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
      index[k++] = a; index[k++] = b; index[k++] = e;
      index[k++] = a; index[k++] = e; index[k++] = d;
    }
  }
  const geometry = new BufferGeometry();
  geometry.setAttribute('position', new BufferAttribute(pos, 3));
  geometry.setIndex(new BufferAttribute(index, 1));
  const colours = new Float32Array(3 * n);
  geometry.setAttribute('color', new BufferAttribute(colours, 3));
  geometry.computeVertexNormals();
  const mesh = new Mesh(geometry, new MeshLambertMaterial({ vertexColors: true, side: DoubleSide }));

  const scene = new Scene();
  scene.background = new Color(0xeef1f5);
  scene.add(mesh);
  scene.add(new AmbientLight(0xffffff, 1.2));
  const sun = new DirectionalLight(0xffffff, 2.0);
  sun.position.set(-0.4, -0.6, 1.0);
  scene.add(sun);

  const cx = (grid.x0_mm + grid.x1_mm) / 2, cy = (grid.y0_mm + grid.y1_mm) / 2;
  const span = Math.max(grid.x1_mm - grid.x0_mm, grid.y1_mm - grid.y0_mm, 1);
  const camera = new PerspectiveCamera(35, width / height, span / 1000, span * 20);
  camera.up.set(0, 0, 1);
  camera.position.set(cx - 0.8 * span, cy - 1.5 * span, 1.2 * span);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(cx, cy, -slot.depth_mm / 2);
  controls.update();
  const render = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);

  let mode = 'height';
  let lo = 0, hi = 0;
  const valueOf = (i) => (mode === 'height' ? pos[3 * i + 2] : pos[3 * i + 2] - nominal[i]);
  const paint = () => {
    lo = Infinity; hi = -Infinity;
    for (let i = 0; i < n; i++) { const v = valueOf(i); if (v < lo) lo = v; if (v > hi) hi = v; }
    const s = hi > lo ? hi - lo : 1;
    for (let i = 0; i < n; i++) {
      const [r, g, b] = palette((valueOf(i) - lo) / s);
      colours[3 * i] = r / 255; colours[3 * i + 1] = g / 255; colours[3 * i + 2] = b / 255;
    }
    geometry.attributes.color.needsUpdate = true;
  };
  paint();
  render();
  return {
    triangles: index.length / 3,
    vertices: n,
    setColour(m) { mode = m; paint(); render(); },
    /// Vertical exaggeration of the view (the data keep their heights).
    setZScale(f) { mesh.scale.set(1, 1, f); render(); },
    range() { return [lo, hi]; },
    png() { render(); return renderer.domElement.toDataURL('image/png'); },
    resize(w, h) { renderer.setSize(w, h); camera.aspect = w / h; camera.updateProjectionMatrix(); render(); },
    render,
  };
}
