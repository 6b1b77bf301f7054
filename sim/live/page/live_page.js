// ctsurg-live's page (sim/live/page, embedded in the server at build time by embed_live_page.cmake):
// shows a live session's surface in WebGL (three.js) and drives the session's tools with the mouse or
// touch. World coordinates are the model's: LPS millimetres.
//
// The page lives at http://HOST:PORT/<token>/; every URL it uses is relative to that, so it carries the
// token: ./live_page.js, ./three.module.js (which imports ./three.core.js), ./OrbitControls.js, and, as
// hello announces them, ./uvs.bin (float32 V x 2, v down the image) and ./normal_map.bin (RGBA8, rows top
// first; a glTF tangent-space normal map). The protocol (sim/live/include/ctsurg/sim/live/live_protocol.h,
// docs/live.md) runs over the WebSocket ./ws:
//   server -> page, JSON text: hello (first: the model, its box, the tools' defaults), began (a begin's
//     tool id), status (~4 per second), guard (the stability guard halved the step or stopped the
//     session), ended (the server let a tool go), error (a refused message), saved, closed (another
//     browser took over: no reconnecting);
//   server -> page, binary: frames, a 56-byte little-endian header (magic CTLF, version 2, flags,
//     frame number, time, steps, topology version, V, F, the seq of the last message applied) then
//     V x 3 float32 positions and, when flag bit 0 is set, F x 3 uint32 triangles;
//   page -> server, JSON text: begin (grab/probe with a radius, cut with a blade edge), move, end,
//     pause, resume, reset, save, each with "seq", the page's own count from 1.
// A begin's id comes back in "began": moves made before it are held (the latest only) and sent then.
// The latency of a move is the time from sending it to the first picture drawn from a frame whose seq
// is at least the move's (measured at the next animation frame after that picture was drawn).
//
// Controls: G grab, P probe, C cut (or the toolbar); drag on the organ to use the tool (grab and probe
// start at the point under the cursor, a cut's blade points into the view), elsewhere to turn the view
// (OrbitControls: left or right button rotates, shift+left or middle pans, wheel zooms, two fingers on
// touch); Space pauses/resumes, R resets, S saves, Esc lets go of the tool.
//
// window.ctsurgLive is the test hook (tests drive the page with real mouse events): the page's state,
// updated live, and project(p), surfacePointAt(x, y), centre().
import * as THREE from './three.module.js';
import { OrbitControls } from './OrbitControls.js';

const HEADER_BYTES = 56;
const FRAME_MAGIC = 'CTLF';
const FRAME_VERSION = 2;
const FLAG_TRIANGLES = 1, FLAG_PAUSED = 2;  // bit 2, stopped, comes with its message in status
const MAX_LATENCIES = 500;
const ERROR_SHOWN_MS = 6000;
const TOOL_KEYS = { g: 'grab', p: 'probe', c: 'cut' };
const TOOL_COLOURS = { grab: 0xffd23f, probe: 0x3f8fff, cut: 0xff3030 };

const hook = {
  ready: false, connected: false, hello: null, status: null, framesApplied: 0, picturesDrawn: 0, pageFps: 0,
  latencies: [], lastFrameSeq: 0, topologyVersion: 0, triangleCount: 0, bytesReceived: 0, errors: [], guards: [],
  ended: [], saved: null, closed: null, tool: 'grab', activeToolId: null,
  project, surfacePointAt, centre,
};
window.ctsurgLive = hook;

const $ = (id) => document.getElementById(id);
const canvas = $('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1b1d21);
const camera = new THREE.PerspectiveCamera(35, 1, 1, 1000);
camera.up.set(0, 0, 1);  // superior up
scene.add(camera);
scene.add(new THREE.HemisphereLight(0xffffff, 0x50463c, 1.2));
const headlight = new THREE.DirectionalLight(0xffffff, 2.2);
headlight.position.set(0.3, 0.5, 1);  // a little above and right of the eye, in camera space
camera.add(headlight, headlight.target);
headlight.target.position.set(0, 0, -1);

// The pointer handlers go on the canvas before OrbitControls' own, so a drag that starts a tool can
// stop the event reaching them.
canvas.addEventListener('pointerdown', onPointerDown);
canvas.addEventListener('pointermove', onPointerMove);
canvas.addEventListener('pointerup', onPointerUp);
canvas.addEventListener('pointercancel', onPointerUp);
canvas.addEventListener('pointerleave', () => setHover(null));
const controls = new OrbitControls(camera, canvas);
controls.mouseButtons = { LEFT: THREE.MOUSE.ROTATE, MIDDLE: THREE.MOUSE.PAN, RIGHT: THREE.MOUSE.ROTATE };
controls.addEventListener('change', () => { needsRender = true; });

const raycaster = new THREE.Raycaster();
const markers = makeMarkers();
scene.add(markers.sphere, markers.blade);

let surface = null;        // { geometry, mesh, lo, hi (the limits of positions sent, LPS mm) }
let socket = null;
let reconnectDelay = 500;  // ms, doubled up to 8 s while the server is away
let seq = 0;
let paused = false;
let drag = null;           // the tool being dragged: { kind, id, beginSeq, pointerId, plane, offset, position, size, edge, held }
const orphanBegins = new Set();  // seqs of begins let go before their id came: ended when it comes
const sentMoves = [];      // [{ seq, t }] moves not yet seen in a frame, in seq order
let shownMove = null;      // the latest move in the picture just drawn: its latency is taken next animation frame
let pendingFrame = null;   // the latest frame received, applied at the next animation frame
let needsRender = true;
let hoverAt = null;        // [clientX, clientY] to preview the tool at, or null
const pictureTimes = [];   // animation frame times of the new pictures of the last second
const sizes = { grab: 8, probe: 8, cut: 5 };  // radius or cut depth (mm), from hello
let errorTimer = 0;

setupToolbar();
window.addEventListener('keydown', onKey);
window.addEventListener('resize', resize);
resize();
connect();
requestAnimationFrame(animate);

// ---- connection -------------------------------------------------------------------------------------

function connect() {
  const url = new URL('ws', location.href);
  url.protocol = location.protocol === 'https:' ? 'wss:' : 'ws:';
  socket = new WebSocket(url);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { hook.connected = true; reconnectDelay = 500; showOverlay(); };
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') {
      hook.bytesReceived += event.data.length;
      onText(JSON.parse(event.data));
    } else {
      hook.bytesReceived += event.data.byteLength;
      onFrame(event.data);
    }
  };
  socket.onclose = () => {
    hook.connected = false;
    abandonDrag();
    orphanBegins.clear();  // a new connection starts afresh: the server let this one's tools go
    sentMoves.length = 0;
    showOverlay();
    if (hook.closed === null) {
      setTimeout(connect, reconnectDelay);
      reconnectDelay = Math.min(2 * reconnectDelay, 8000);
    }
  };
}

// Sends a message with the next seq; returns the seq (0 when the socket is not open).
function send(message) {
  if (!socket || socket.readyState !== WebSocket.OPEN) return 0;
  message.seq = ++seq;
  socket.send(JSON.stringify(message));
  return message.seq;
}

function onText(m) {
  switch (m.type) {
    case 'hello': onHello(m); break;
    case 'began': onBegan(m); break;
    case 'status':
      hook.status = m;
      paused = m.paused;
      break;
    case 'guard': onGuard(m); break;
    case 'ended':
      hook.ended.push(m);
      if (drag && drag.id === m.id) abandonDrag();
      break;
    case 'error':
      if (drag && drag.id === null && m.seq === drag.beginSeq) abandonDrag();  // the begin was refused
      showError(m.message);
      break;
    case 'saved': hook.saved = m; break;
    case 'closed': hook.closed = m.message; break;
    default: showError(`unknown message from the server: ${m.type}`);
  }
  showOverlay();
}

// The stability guard's message stays on show until the user resumes. A stop also ended the tools
// (their "ended" came first): the drag is over.
function onGuard(m) {
  hook.guards.push(m);
  $('guard').textContent = `${m.action === 'stopped' ? 'Stopped' : 'Step halved'}: ${m.message}`;
  if (m.action === 'stopped') abandonDrag();
}

// ---- the surface ------------------------------------------------------------------------------------

// A new session (or the same after reconnecting): the geometry for its V vertices, the material, the
// tools' defaults; the view is framed on the first hello only.
function onHello(h) {
  const first = hook.hello === null;
  hook.hello = h;
  hook.ready = false;
  if (surface) scene.remove(surface.mesh);
  const geometry = new THREE.BufferGeometry();
  const positions = new THREE.BufferAttribute(new Float32Array(3 * h.vertex_count), 3);
  positions.setUsage(THREE.DynamicDrawUsage);
  geometry.setAttribute('position', positions);
  const material = new THREE.MeshStandardMaterial({
    color: new THREE.Color(...h.colour), roughness: 0.55, metalness: 0, side: THREE.DoubleSide,
  });
  const mesh = new THREE.Mesh(geometry, material);
  mesh.frustumCulled = false;
  mesh.visible = false;  // until a frame brings the triangles
  scene.add(mesh);
  const [x0, y0, z0, x1, y1, z1] = h.bounds;
  const box = new THREE.Box3(new THREE.Vector3(x0, y0, z0), new THREE.Vector3(x1, y1, z1));
  const inset = 1e-3;  // stay strictly inside the server's limits, whatever the rounding
  const lo = box.min.clone().subScalar(h.margin_mm - inset), hi = box.max.clone().addScalar(h.margin_mm - inset);
  surface = { geometry, mesh, lo, hi };
  sizes.grab = h.tools.grab_radius_mm;
  sizes.probe = h.tools.probe_radius_mm;
  sizes.cut = h.tools.cut_depth_mm;
  selectTool(hook.tool);
  if (first) frameView(box);
  if (h.uvs && h.normal_map) loadNormalMap(surface, h.normal_map);
}

// Puts the camera in front of the patient (anterior is -y in LPS), superior up, the box in view.
function frameView(box) {
  const centre = box.getCenter(new THREE.Vector3());
  const radius = box.getSize(new THREE.Vector3()).length() / 2;
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
  camera.position.copy(centre).add(new THREE.Vector3(0, -distance, 0));
  camera.near = distance / 100;
  camera.far = distance * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
}

// Fetches the texture coordinates and the normal map and puts them on the surface's material. The map
// is a glTF normal texture, used as three's GLTFLoader uses one on a mesh without tangents: rows top
// first with flipY false (glTF's v runs down the image, as ours does) and the green scale negated (the
// tangent frame three derives from screen-space derivatives has the opposite v sense to glTF's
// bitangent, which points up the image).
async function loadNormalMap(target, size) {
  try {
    const [uvs, rgba] = await Promise.all([fetchBytes('uvs.bin'), fetchBytes('normal_map.bin')]);
    const vertices = target.geometry.getAttribute('position').count;
    if (uvs.byteLength !== 8 * vertices || rgba.byteLength !== 4 * size.width * size.height) {
      throw new Error(`uvs.bin (${uvs.byteLength} bytes) or normal_map.bin (${rgba.byteLength} bytes) do not match hello`);
    }
    if (target !== surface) return;  // a newer hello came meanwhile
    target.geometry.setAttribute('uv', new THREE.BufferAttribute(new Float32Array(uvs), 2));
    const map = new THREE.DataTexture(new Uint8Array(rgba), size.width, size.height, THREE.RGBAFormat);
    map.flipY = false;
    map.colorSpace = THREE.NoColorSpace;
    map.magFilter = THREE.LinearFilter;
    map.minFilter = THREE.LinearMipmapLinearFilter;
    map.generateMipmaps = true;
    map.anisotropy = renderer.capabilities.getMaxAnisotropy();
    map.needsUpdate = true;
    target.mesh.material.normalMap = map;
    target.mesh.material.normalScale.set(1, -1);
    target.mesh.material.needsUpdate = true;
    needsRender = true;
  } catch (e) {
    showError(`normal map: ${e.message}`);
  }
}

async function fetchBytes(name) {
  const response = await fetch(name, { cache: 'no-store' });
  if (!response.ok) throw new Error(`${name}: HTTP ${response.status}`);
  return response.arrayBuffer();
}

// A binary frame: checked, its triangles taken at once (a later frame may not repeat them), its
// positions kept as the latest to show at the next animation frame.
function onFrame(buffer) {
  const view = new DataView(buffer);
  const magic = String.fromCharCode(...new Uint8Array(buffer, 0, Math.min(4, buffer.byteLength)));
  if (buffer.byteLength < HEADER_BYTES || magic !== FRAME_MAGIC || view.getUint16(4, true) !== FRAME_VERSION) {
    showError(`a frame the page cannot read (${buffer.byteLength} bytes, magic ${magic})`);
    return;
  }
  const flags = view.getUint16(6, true);
  const vertices = view.getUint32(40, true), triangles = view.getUint32(44, true);
  const expected = HEADER_BYTES + 12 * vertices + (flags & FLAG_TRIANGLES ? 12 * triangles : 0);
  if (!surface || buffer.byteLength !== expected || vertices !== surface.geometry.getAttribute('position').count) {
    showError(`a frame that does not match the session (${buffer.byteLength} bytes, V ${vertices})`);
    return;
  }
  if (flags & FLAG_TRIANGLES) {
    const index = new Uint32Array(buffer, HEADER_BYTES + 12 * vertices, 3 * triangles);
    surface.geometry.setIndex(new THREE.BufferAttribute(index, 1));
    surface.mesh.visible = true;
  }
  hook.topologyVersion = Number(view.getBigUint64(32, true));
  hook.triangleCount = triangles;
  paused = (flags & FLAG_PAUSED) !== 0;
  pendingFrame = { positions: new Float32Array(buffer, HEADER_BYTES, 3 * vertices), seq: view.getUint32(48, true) };
}

// Puts the latest frame's positions on the surface; its normals and bounds follow them.
function applyFrame(frame) {
  const geometry = surface.geometry;
  geometry.getAttribute('position').array.set(frame.positions);
  geometry.getAttribute('position').needsUpdate = true;
  geometry.computeVertexNormals();
  geometry.computeBoundingSphere();  // the raycaster culls with it
  geometry.computeBoundingBox();
  hook.framesApplied += 1;
  hook.lastFrameSeq = frame.seq;
  takeShownMove(frame.seq);
}

// The newest move that this frame reflects becomes the one to time; older ones are dropped.
function takeShownMove(frameSeq) {
  let shown = 0;
  while (shown < sentMoves.length && sentMoves[shown].seq <= frameSeq) ++shown;
  if (shown > 0) shownMove = sentMoves.splice(0, shown)[shown - 1];
}

// ---- drawing ----------------------------------------------------------------------------------------

function animate(now) {
  requestAnimationFrame(animate);
  if (shownMove) {  // the picture showing it was drawn in the previous animation frame
    hook.latencies.push(performance.now() - shownMove.t);
    if (hook.latencies.length > MAX_LATENCIES) hook.latencies.shift();
    shownMove = null;
  }
  let newPicture = false;
  if (pendingFrame && surface && surface.geometry.index) {
    applyFrame(pendingFrame);
    pendingFrame = null;
    newPicture = needsRender = true;
  }
  if (hoverAt) {
    showPreview(hoverAt);
    hoverAt = null;
  }
  if (!needsRender) return;
  renderer.render(scene, camera);
  needsRender = false;
  if (newPicture) countPicture(now);
}

// Counts a picture drawn from a new frame; the page's pictures per second are those of the last second
// (the overlay shows them with each status, ~4 times a second).
function countPicture(now) {
  hook.picturesDrawn += 1;
  pictureTimes.push(now);
  while (pictureTimes[0] <= now - 1000) pictureTimes.shift();
  hook.pageFps = pictureTimes.length;
  if (hook.hello && !hook.ready) {
    hook.ready = true;
    showOverlay();
  }
}

function resize() {
  renderer.setSize(window.innerWidth, window.innerHeight, false);
  camera.aspect = window.innerWidth / Math.max(1, window.innerHeight);
  camera.updateProjectionMatrix();
  needsRender = true;
}

// The tool's marker: a translucent sphere (grab, probe) or the blade's edge, a red line with a dot at
// each end (the line points into the view, so it starts as a dot), drawn over the surface.
function makeMarkers() {
  const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, 32, 16),
    new THREE.MeshBasicMaterial({ transparent: true, depthWrite: false }));
  const edge = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
  const blade = new THREE.Group();
  blade.add(new THREE.Line(edge, new THREE.LineBasicMaterial({ transparent: true, depthTest: false })),
    new THREE.Points(edge, new THREE.PointsMaterial({ size: 6, sizeAttenuation: false, transparent: true, depthTest: false })));
  sphere.visible = blade.visible = false;
  sphere.renderOrder = 1;
  for (const part of blade.children) {
    part.renderOrder = 2;
    part.frustumCulled = false;  // its bounds would stay those of its first position
  }
  return { sphere, blade, edge };
}

// Shows the marker of `kind` at `position` (a blade along `edge`), strong while in use, faint as a preview.
function showMarker(kind, position, size, edge, active) {
  const { sphere, blade } = markers;
  sphere.visible = kind !== 'cut';
  blade.visible = kind === 'cut';
  for (const part of kind === 'cut' ? blade.children : [sphere]) {
    part.material.color.setHex(TOOL_COLOURS[kind]);
    part.material.opacity = active ? (kind === 'cut' ? 1 : 0.4) : (kind === 'cut' ? 0.4 : 0.18);
  }
  if (kind === 'cut') {
    const half = edge.clone().multiplyScalar(0.5);
    markers.edge.setFromPoints([position.clone().sub(half), position.clone().add(half)]);
  } else {
    sphere.position.copy(position);
    sphere.scale.setScalar(size);
  }
  needsRender = true;
}

function hideMarker() {
  if (markers.sphere.visible || markers.blade.visible) needsRender = true;
  markers.sphere.visible = markers.blade.visible = false;
}

// ---- picking ----------------------------------------------------------------------------------------

// The ray through the client point (CSS pixels).
function rayAt(clientX, clientY) {
  const r = canvas.getBoundingClientRect();
  const ndc = new THREE.Vector2((clientX - r.left) / r.width * 2 - 1, -(clientY - r.top) / r.height * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  return raycaster.ray;
}

// The surface's first hit under the client point: { point, normal (facing the camera), direction
// (the ray's, unit) }, or null.
function pick(clientX, clientY) {
  if (!surface || !surface.mesh.visible) return null;
  const ray = rayAt(clientX, clientY);
  const hit = raycaster.intersectObject(surface.mesh, false)[0];
  if (!hit) return null;
  const normal = hit.face.normal.clone();
  if (normal.dot(ray.direction) > 0) normal.negate();
  return { point: hit.point, normal, direction: ray.direction.clone() };
}

// Where a tool begun at `hit` sits: grab at the hit point, probe touching it from outside, the blade
// pointing into the view from 1 mm outside the surface to `size` deep (the edge is centred on the
// position). Returns { position, edge } (edge null for spheres).
function toolPlacement(kind, hit, size) {
  if (kind === 'grab') return { position: hit.point.clone(), edge: null };
  if (kind === 'probe') return { position: hit.point.clone().addScaledVector(hit.normal, size), edge: null };
  return {
    position: hit.point.clone().addScaledVector(hit.direction, (size - 1) / 2),
    edge: hit.direction.clone().multiplyScalar(size + 1),
  };
}

function clampToLimits(p) {
  return p.clone().clamp(surface.lo, surface.hi);
}

// The hover preview: the current tool, faint, where it would start under the cursor.
function showPreview([clientX, clientY]) {
  const hit = drag ? null : pick(clientX, clientY);
  if (!hit) {
    if (!drag) hideMarker();
    return;
  }
  const { position, edge } = toolPlacement(hook.tool, hit, sizes[hook.tool]);
  showMarker(hook.tool, position, sizes[hook.tool], edge, false);
}

function setHover(at) {
  hoverAt = at;
  if (!at && !drag) hideMarker();
}

// ---- tools ------------------------------------------------------------------------------------------

// A press on the organ (left button without shift, or a touch) begins the current tool there; any
// other press is left to OrbitControls.
function onPointerDown(event) {
  if (drag || event.button !== 0 || event.shiftKey || event.ctrlKey || event.metaKey || !event.isPrimary) return;
  const hit = pick(event.clientX, event.clientY);
  if (!hit || !hook.connected) return;
  event.stopImmediatePropagation();
  event.preventDefault();
  const kind = hook.tool, size = sizes[kind];
  const { position, edge } = toolPlacement(kind, hit, size);
  const start = clampToLimits(position);
  const begin = { type: 'begin', tool: kind, position_mm: start.toArray() };
  if (edge) begin.blade_edge_mm = edge.toArray();
  else begin.radius_mm = size;
  const beginSeq = send(begin);
  if (!beginSeq) return;
  // Drags move the tool in the plane through its start facing the camera, keeping the offset from
  // the cursor's point in that plane.
  const facing = camera.getWorldDirection(new THREE.Vector3()).negate();
  const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(facing, start);
  const grabbed = rayAt(event.clientX, event.clientY).intersectPlane(plane, new THREE.Vector3()) ?? start.clone();
  drag = {
    kind, id: null, beginSeq, pointerId: event.pointerId, plane, offset: start.clone().sub(grabbed),
    position: start, size, edge, held: false,
  };
  controls.enabled = false;
  canvas.setPointerCapture(event.pointerId);
  showMarker(kind, start, size, edge, true);
  showOverlay();
}

function onPointerMove(event) {
  if (!drag) {
    if (event.buttons === 0) setHover([event.clientX, event.clientY]);
    return;
  }
  if (event.pointerId !== drag.pointerId) return;
  const onPlane = rayAt(event.clientX, event.clientY).intersectPlane(drag.plane, new THREE.Vector3());
  if (!onPlane) return;  // the ray runs parallel to the plane
  drag.position = clampToLimits(onPlane.add(drag.offset));
  showMarker(drag.kind, drag.position, drag.size, drag.edge, true);
  if (drag.id === null) drag.held = true;
  else sendMove();
}

function onPointerUp(event) {
  if (drag && event.pointerId === drag.pointerId) endDrag();
}

function sendMove() {
  const moveSeq = send({ type: 'move', id: drag.id, position_mm: drag.position.toArray() });
  if (moveSeq) sentMoves.push({ seq: moveSeq, t: performance.now() });
  drag.held = false;
}

// The begin's id: a move held meanwhile goes now; a tool let go meanwhile ends now.
function onBegan(m) {
  if (orphanBegins.delete(m.seq)) {
    send({ type: 'end', id: m.id });
    return;
  }
  if (!drag || drag.id !== null || m.seq !== drag.beginSeq) return;
  drag.id = hook.activeToolId = m.id;
  if (drag.held) sendMove();
}

// Lets go of the tool being dragged (pointer up, Esc): the server ends it.
function endDrag() {
  if (drag.id === null) orphanBegins.add(drag.beginSeq);
  else send({ type: 'end', id: drag.id });
  abandonDrag();
}

// Forgets the drag without telling the server (it ended the tool itself, or the socket is gone).
function abandonDrag() {
  if (!drag) return;
  if (canvas.hasPointerCapture(drag.pointerId)) canvas.releasePointerCapture(drag.pointerId);
  drag = null;
  hook.activeToolId = null;
  controls.enabled = true;
  hideMarker();
  showOverlay();
}

function selectTool(kind) {
  hook.tool = kind;
  for (const button of document.querySelectorAll('[data-tool]')) {
    button.classList.toggle('selected', button.dataset.tool === kind);
  }
  const slider = $('size');
  $('size-name').textContent = kind === 'cut' ? 'depth' : 'radius';
  slider.min = kind === 'cut' ? 1 : 0.5;  // as ctsurg-live's options (a blade edge, depth + 1, stays <= 200 mm)
  slider.max = kind === 'cut' ? 150 : 50;
  slider.value = sizes[kind];
  $('size-value').textContent = `${sizes[kind]} mm`;
  hideMarker();
}

function togglePause() {
  if (paused) {
    send({ type: 'resume' });
    $('guard').textContent = '';  // the guard's message stays until the user resumes
  } else {
    send({ type: 'pause' });
  }
}

function setupToolbar() {
  for (const button of document.querySelectorAll('[data-tool]')) {
    button.addEventListener('click', () => { selectTool(button.dataset.tool); button.blur(); });
  }
  $('size').addEventListener('input', (event) => {
    sizes[hook.tool] = Number(event.target.value);
    $('size-value').textContent = `${sizes[hook.tool]} mm`;
  });
  const actions = { pause: togglePause, reset: () => send({ type: 'reset' }), save: () => send({ type: 'save' }) };
  for (const [id, action] of Object.entries(actions)) {
    $(id).addEventListener('click', () => { action(); $(id).blur(); });
  }
}

function onKey(event) {
  if (event.ctrlKey || event.metaKey || event.altKey || event.repeat) return;
  const key = event.key.toLowerCase();
  if (TOOL_KEYS[key]) selectTool(TOOL_KEYS[key]);
  else if (key === ' ') togglePause();
  else if (key === 'r') send({ type: 'reset' });
  else if (key === 's') send({ type: 'save' });
  else if (key === 'escape' && drag) endDrag();
  else return;
  event.preventDefault();
}

// ---- overlay ----------------------------------------------------------------------------------------

function showOverlay() {
  const h = hook.hello, s = hook.status;
  $('title').textContent = h ? `${h.scenario}: ${h.model}` : 'ctsurg-live: connecting…';
  const parts = [];
  if (s) {
    parts.push(`t ${s.time_s.toFixed(3)} s`, `real time ×${s.rtf.toFixed(2)}`, `step ${(s.dt_s * 1000).toPrecision(3)} ms`,
      `server ${s.pictures_per_s.toFixed(0)}/s`);
    // Each holding tool's pull on the tissue (N), and its moment (N mm): what a haptic device would render.
    for (const l of s.loads ?? []) {
      const f = Math.hypot(...l.force_n), m = Math.hypot(...l.moment_n_mm);
      parts.push(`tool ${l.id}: ${(f * 1000).toFixed(1)} mN, ${(m * 1000).toFixed(0)} mN·mm`);
    }
    // The solver's own estimate of how far this frame is from its converged solution (FEM quasi-Newton).
    if (typeof s.solver_error_mm === 'number') parts.push(`solver error ≈ ${s.solver_error_mm.toFixed(2)} mm`);
  }
  parts.push(`page ${hook.pageFps}/s`);
  const latency = hook.latencies[hook.latencies.length - 1];
  if (latency !== undefined) parts.push(`latency ${latency.toFixed(0)} ms`);
  $('stats').textContent = parts.join(' · ');
  const state = [];
  if (!hook.connected) state.push(hook.closed === null ? 'disconnected: reconnecting…' : 'disconnected');
  else if (s && s.stopped) state.push(`stopped: ${s.stopped}`);
  else if (paused) state.push('paused (Space resumes)');
  state.push(`tool: ${hook.tool}${drag ? ' (in use)' : ''}`);
  if (h && h.save_to) state.push(`S saves to ${h.save_to.scenario}`);
  $('state').textContent = state.join(' · ');
  $('closed').textContent = hook.closed ?? '';
  const saved = hook.saved;
  $('saved').textContent = saved
    ? `saved ${saved.frames} frames (${saved.time_s.toFixed(3)} s): ${saved.scenario}, ${saved.trajectory}` : '';
}

// Shows an error for a few seconds and keeps it in the hook.
function showError(message) {
  hook.errors.push(message);
  $('error').textContent = message;
  clearTimeout(errorTimer);
  errorTimer = setTimeout(() => { $('error').textContent = ''; }, ERROR_SHOWN_MS);
}

// ---- test hook ----------------------------------------------------------------------------------------

// [clientX, clientY] of the LPS point p (an array) on the page.
function project(p) {
  const ndc = new THREE.Vector3(...p).project(camera);
  const r = canvas.getBoundingClientRect();
  return [r.left + (ndc.x + 1) / 2 * r.width, r.top + (1 - ndc.y) / 2 * r.height];
}

// The LPS point of the surface under the client point, or null.
function surfacePointAt(clientX, clientY) {
  const hit = pick(clientX, clientY);
  return hit ? hit.point.toArray() : null;
}

// The centre of the current surface's bounding box (LPS), or null before the first frame.
function centre() {
  const box = surface && surface.geometry.boundingBox;
  return box ? box.getCenter(new THREE.Vector3()).toArray() : null;
}
