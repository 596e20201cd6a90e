// The skin viewer that scripts/sinew-view writes into view.html: the run's skin.glb (embedded in the
// page) read by three.js's GLTFLoader, orbit controls, play/pause, a frame slider, and colour by J or by
// the distance to the rig's own skinning (fields the glTF file carries per frame).
// URL options (after #, joined by &): frame=K (start at frame K), color=NAME, play=1.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const status = document.getElementById('status');
const fail = (message) => {
  status.textContent = 'cannot show the skin: ' + message;
  document.title = 'sinew-view: error';
  throw new Error(message);
};

const options = Object.fromEntries(
  location.hash.replace(/^#/, '').split('&').filter((s) => s).map((s) => s.split('=').map(decodeURIComponent)));

// The embedded glb, base64.
const bytes = Uint8Array.from(atob(document.getElementById('skin-glb').textContent.trim()), (c) => c.charCodeAt(0));

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf2f2f2);
scene.add(new THREE.HemisphereLight(0xffffff, 0x666677, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(1, 2, 1.5);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(35, window.innerWidth / window.innerHeight, 0.001, 1000);
const controls = new OrbitControls(camera, renderer.domElement);

new GLTFLoader().parse(bytes.buffer, '', async (gltf) => {
  const mesh = gltf.scene.getObjectByProperty('type', 'Mesh');
  if (!mesh) fail('the file has no mesh');
  const extras = gltf.parser.json.meshes[0].extras || {};
  const steps = extras.sinew_steps || [];
  const clip = gltf.animations[0];
  const times = clip ? clip.tracks[0].times : new Float32Array([0]);
  const frames = times.length;
  const V = mesh.geometry.attributes.position.count;

  // Per-frame fields, frame-major, one accessor each.
  const fields = {};
  for (const [name, index] of Object.entries(extras.sinew_fields || {})) {
    const values = (await gltf.parser.getDependency('accessor', index)).array;
    // The colour scale spans 99% of the values (J's distance from 1, or the distance itself), so that
    // a few extreme vertices do not wash out the rest.
    const spread = Array.from(values, (v) => (name === 'J' ? Math.abs(v - 1) : Math.abs(v))).filter(Number.isFinite);
    spread.sort((a, b) => a - b);
    fields[name] = { values, span: Math.max(spread[Math.floor(0.99 * (spread.length - 1))] || 0, 1e-12) };
  }
  const colors = new Float32Array(3 * V).fill(0.85);
  mesh.geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
  mesh.material = new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.6, side: THREE.DoubleSide });
  scene.add(gltf.scene);

  const mixer = new THREE.AnimationMixer(gltf.scene);
  // Played once and held at its end: a looping action wraps the last frame's time back to the first.
  if (clip) mixer.clipAction(clip).setLoop(THREE.LoopOnce, 1).play().clampWhenFinished = true;

  // Frame the skin as it is at the first frame.
  mixer.setTime(times[0]);
  gltf.scene.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromObject(mesh, true);
  const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length();
  camera.position.copy(centre).add(new THREE.Vector3(0.35, 0.25, 1).normalize().multiplyScalar(1.8 * size));
  camera.near = size / 100;
  camera.far = size * 100;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();

  // The controls.
  const slider = document.getElementById('frame');
  const play = document.getElementById('play');
  const colour = document.getElementById('colour');
  const label = document.getElementById('label');
  const legend = document.getElementById('legend');
  slider.max = frames - 1;
  for (const name of Object.keys(fields)) colour.add(new Option(name === 'J' ? 'J = det F' : name.replace(/_/g, ' '), name));

  // J: blue (compressed) - white (1) - red (stretched); a distance: white (0) to red (largest).
  const paint = (k) => {
    const f = fields[colour.value];
    if (!f) {
      colors.fill(0.85);
      legend.textContent = '';
    } else {
      const centreJ = colour.value === 'J';
      const span = f.span;
      for (let v = 0; v < V; ++v) {
        const value = f.values[k * V + v];
        const s = centreJ ? Math.max(-1, Math.min(1, (value - 1) / span)) : Math.max(0, Math.min(1, value / span));
        const r = s >= 0 ? 1 : 1 + s, g = 1 - Math.abs(s), b = s >= 0 ? 1 - s : 1;
        colors[3 * v] = r * 0.9; colors[3 * v + 1] = g * 0.9; colors[3 * v + 2] = b * 0.9;
      }
      legend.textContent = centreJ ? `J ${(1 - span).toPrecision(3)} (blue) to ${(1 + span).toPrecision(3)} (red)`
                                   : `${colour.value.replace(/_/g, ' ')} 0 (white) to ${span.toPrecision(3)} (red)`;
    }
    mesh.geometry.attributes.color.needsUpdate = true;
  };
  let current = -1;
  const show = (k) => {
    k = Math.max(0, Math.min(frames - 1, k | 0));
    current = k;
    mixer.setTime(times[k]);
    paint(k);
    slider.value = k;
    label.textContent = `frame ${k + 1}/${frames}  step ${steps[k] ?? k}  t = ${times[k].toFixed(3)} s`;
  };
  slider.addEventListener('input', () => { playing = false; play.textContent = 'play'; show(+slider.value); });
  colour.addEventListener('change', () => paint(current));
  let playing = options.play === '1', last = performance.now();
  const rate = extras.sinew_frame_rate || 24;
  play.textContent = playing ? 'pause' : 'play';
  play.addEventListener('click', () => { playing = !playing; play.textContent = playing ? 'pause' : 'play'; last = performance.now(); });
  if (options.color && fields[options.color]) colour.value = options.color;
  show(options.frame ? +options.frame : 0);

  const animate = (now) => {
    requestAnimationFrame(animate);
    if (playing && now - last > 1000 / rate) {
      last = now;
      show((current + 1) % frames);
    }
    controls.update();
    renderer.render(scene, camera);
  };
  requestAnimationFrame(animate);
  // Tests wait for this title: the first frame has been drawn.
  requestAnimationFrame(() => requestAnimationFrame(() => {
    document.title = `sinew-view: frame ${current}`;
    status.textContent = '';
  }));
}, (error) => fail(String(error && error.message || error)));

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
});
