// report.html's 3D viewer (docs/user-guide.md, "report.html"). The quijibo command line writes the
// meshes into the page as JSON (<script type="application/json" id="quijibo-meshes">): per mesh its
// name, label, triangle counts, bounding box, positions quantized to Uint16 over the box and indices
// (Uint16 or Uint32), both base64. This script (bundled with three.js by `npm run build`, inlined by
// the writer) shows one mesh at a time, with orbit and zoom, and a button per mesh.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

function DecodeBase64(text) {
  const bytes = atob(text);
  const out = new Uint8Array(bytes.length);
  for (let i = 0; i < bytes.length; ++i) out[i] = bytes.charCodeAt(i);
  return out.buffer;
}

// One entry of the page's JSON as a BufferGeometry in the mesh's own (user) frame.
function MakeGeometry(m) {
  const q = new Uint16Array(DecodeBase64(m.positions));
  const lo = m.box.min, hi = m.box.max;
  const positions = new Float32Array(q.length);
  for (let i = 0; i < q.length; ++i) {
    const k = i % 3;
    positions[i] = lo[k] + (q[i] / 65535) * (hi[k] - lo[k]);
  }
  const raw = DecodeBase64(m.indices);
  const indices = m.index_bytes === 2 ? new Uint16Array(raw) : new Uint32Array(raw);
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  g.setIndex(new THREE.BufferAttribute(indices, 1));
  g.computeVertexNormals();
  g.computeBoundingSphere();
  return g;
}

function Start() {
  const host = document.getElementById('quijibo-viewer');
  const data = document.getElementById('quijibo-meshes');
  const state = { ready: false, shown: null, meshes: [], errors: [] };
  window.quijiboViewer = state;
  if (!host || !data) return;
  const meshes = JSON.parse(data.textContent);
  if (!meshes.length) return;

  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setClearColor(0xf4f4f2);
  const canvas = renderer.domElement;
  canvas.id = 'quijibo-canvas';
  host.querySelector('.stage').appendChild(canvas);

  const scene = new THREE.Scene();
  // Clay under a sky/ground hemisphere and two directional lights: the folds of a crust read as
  // light and shade from any side the user turns it to.
  scene.add(new THREE.HemisphereLight(0xffffff, 0x5a554c, 0.7));
  const key = new THREE.DirectionalLight(0xffffff, 3.2);
  const fill = new THREE.DirectionalLight(0xffffff, 0.6);
  const camera = new THREE.PerspectiveCamera(35, 1, 0.001, 1000);
  // The lights turn with the camera: their targets too, so that their directions are the camera's.
  camera.add(key, fill, key.target, fill.target);
  key.target.position.set(0, 0, -1);
  fill.target.position.set(0, 0, -1);
  key.position.set(-1.5, 2, 1);
  fill.position.set(2, -0.5, 1.5);
  scene.add(camera);
  const controls = new OrbitControls(camera, canvas);
  controls.enableDamping = false;

  const material = new THREE.MeshStandardMaterial({ color: 0xc9b79c, roughness: 0.75, metalness: 0.0,
                                                    side: THREE.DoubleSide });
  const objects = meshes.map((m) => {
    const mesh = new THREE.Mesh(MakeGeometry(m), material);
    mesh.visible = false;
    scene.add(mesh);
    return mesh;
  });

  function Render() { renderer.render(scene, camera); }
  function Resize() {
    const w = host.querySelector('.stage').clientWidth, h = Math.round(Math.min(w * 0.75, 640));
    renderer.setSize(w, h, true);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    Render();
  }
  // Meshes in the same frame (the run's, all in the user's frame) keep the view when switching, so
  // like is compared with like; a mesh elsewhere (another frame) is framed from the same direction.
  let framed = null;
  function Frame(sphere) {
    const r = Math.max(sphere.radius, 1e-9);
    if (framed && framed.center.distanceTo(sphere.center) < 0.25 * r && r / framed.radius > 0.67 &&
        r / framed.radius < 1.5) return;
    const d = r / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
    const direction = framed ? camera.position.clone().sub(controls.target).normalize()
                             : new THREE.Vector3(0.45, 0.35, 1).normalize();
    controls.target.copy(sphere.center);
    camera.position.copy(sphere.center).add(direction.multiplyScalar(d));
    camera.near = d / 100;
    camera.far = d * 10;
    camera.updateProjectionMatrix();
    controls.update();
    framed = { center: sphere.center.clone(), radius: r };
  }
  const buttons = host.querySelectorAll('button[data-mesh]');
  function Show(name) {
    objects.forEach((o, i) => {
      o.visible = meshes[i].name === name;
      if (o.visible) Frame(o.geometry.boundingSphere);
    });
    buttons.forEach((b) => b.classList.toggle('active', b.dataset.mesh === name));
    state.shown = name;
    Render();
  }
  buttons.forEach((b) => b.addEventListener('click', () => Show(b.dataset.mesh)));
  controls.addEventListener('change', Render);
  window.addEventListener('resize', Resize);
  Resize();
  Show((meshes.find((m) => m.initial) || meshes[0]).name);
  state.meshes = meshes.map((m) => m.name);
  state.ready = true;
}

try {
  Start();
} catch (e) {
  console.error('quijibo viewer: ' + e);
  throw e;
}
