// pdyn's viewer page: connects to `pdyn serve`'s WebSocket, draws every
// frame it receives, and turns the mouse into Witkin's interactions (drag
// with a mouse spring, nail, create, attach) as commands to the real
// simulation (docs/viewer.md).
//
// Test hooks (the browser test aims the mouse with them): window.pdyn =
//   { connected, scene, status, frames (received), fps (received in the last
//     second), step, screenOf(id) -> {x, y} page pixels,
//     worldOf(x, y, id) -> [x, y, z], the point the page would send for a
//     cursor at page (x, y) on the drag plane through particle id,
//     constraintSegments, constraintRings (what the page draws of the
//     scene's constraints), lastError }
import { decodeFrame } from './protocol.js';
import { EnergyPlot } from './plot.js';
import { View } from './view.js';

const $ = (id) => document.getElementById(id);
const view = new View($('view'));
const plot = new EnergyPlot($('energy'));
const hooks = window.pdyn = {
  connected: false, scene: null, status: null, frames: 0, fps: 0, step: 0, lastError: null,
  screenOf: (id) => view.screenOf(id),
  worldOf: (x, y, id) => view.worldAt(x, y, view.position(id)).toArray(),
  get constraintSegments() { return view.constraintSegments; },
  get constraintRings() { return view.constraintRings; },
};

let socket = null;
let scene = null;        // the last `scene` message
let lastFrame = null;
let fitted = false;
let retry = 250;         // ms before reconnecting, doubled up to 5 s
const arrivals = [];     // frame arrival times of the last second

function send(command) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(command));
}

function showError(text) {
  hooks.lastError = text;
  const box = $('error');
  box.textContent = text + '\n(click to dismiss)';
  box.hidden = false;
}
$('error').addEventListener('click', () => { $('error').hidden = true; });

function connect() {
  const url = new URL('ws', window.location.href);
  url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
  socket = new WebSocket(url);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { hooks.connected = true; retry = 250; };
  socket.onclose = () => {
    hooks.connected = false;
    $('status').textContent = `disconnected; retrying in ${(retry / 1000).toFixed(1)} s`;
    setTimeout(connect, retry);
    retry = Math.min(2 * retry, 5000);
  };
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') onMessage(JSON.parse(event.data));
    else onFrame(decodeFrame(event.data));
  };
}

function onMessage(msg) {
  if (msg.type === 'scene') {
    const keep = lastFrame && lastFrame.count === msg.count ? lastFrame.positions : null;
    const first = !scene || scene.file !== msg.file;
    scene = hooks.scene = msg;
    $('file').textContent = msg.file;
    const solver = $('solver');
    if (solver.options.length !== msg.solvers.length) {
      solver.replaceChildren(...msg.solvers.map((n) => new Option(n, n)));
    }
    view.setScene(msg, keep, false);
    listConstraints(msg.constraints ?? []);
    if (first && msg.flat) { $('camera').value = msg.flat; }
    if (first) fitted = false;
  } else if (msg.type === 'status') {
    hooks.status = msg;
    $('play').textContent = msg.playing ? 'Pause' : 'Play';
    if (document.activeElement !== $('dt')) $('dt').value = msg.dt;
    if (document.activeElement !== $('solver')) $('solver').value = msg.solver;
    if (msg.message) showError(msg.message);
    updateStatus();
  } else if (msg.type === 'error') {
    showError(msg.message);
  }
}

function onFrame(frame) {
  // Positions of an older topology (before a create or reload took effect)
  // do not fit the buffers: wait for the frames of the new scene.
  if (!scene || frame.topology !== scene.topology) return;
  lastFrame = frame;
  hooks.frames += 1;
  hooks.step = frame.step;
  const now = performance.now();
  arrivals.push(now);
  while (arrivals.length && arrivals[0] < now - 1000) arrivals.shift();
  hooks.fps = arrivals.length;
  view.setFrame(frame);
  if (!fitted) { view.fit(); view.setMode($('camera').value); fitted = true; }
  plot.add(frame.time, frame.kinetic, frame.potential);
}

/** The panel's list of constraint objects: type, rows, what is drawn. */
function listConstraints(constraints) {
  const list = $('constraints');
  list.replaceChildren(...constraints.map((c) => {
    const item = document.createElement('li');
    const over = new Set(c.rows.map((r) => r.length));
    const drawn = over.size === 1 && over.has(1) ? 'rings' : over.has(1) ? 'rods and rings' : 'rods';
    item.textContent = `${c.type || 'constraint'}: ${c.rows.length} row${c.rows.length === 1 ? '' : 's'} (${drawn})`;
    item.title = c.label;
    return item;
  }));
  $('constraints-box').hidden = constraints.length === 0;
}

function updateStatus() {
  const s = hooks.status;
  if (!s) return;
  $('status').textContent =
    `t ${s.time.toFixed(4)} s   step ${s.step}\n` +
    `real-time factor ${s.rtf.toPrecision(3)}\n` +
    `${hooks.fps} frames/s   ${s.count} particles\n` +
    `${s.solver}, dt ${s.dt} s, ${s.playing ? 'playing' : 'paused'}` +
    (s.constraint_error != null ? `\nconstraint error ${s.constraint_error.toExponential(2)} (max |C|)` : '') +
    (view.bySpeed ? `\nspeed colours: 0 .. ${view.topSpeed?.toPrecision(3)} m/s` : '');
}

// ---- controls ----
$('play').onclick = () => send({ op: hooks.status?.playing ? 'pause' : 'play' });
$('step').onclick = () => send({ op: 'step' });
$('reset').onclick = () => { plot.clear(); send({ op: 'reset' }); };
$('reload').onclick = () => { $('error').hidden = true; send({ op: 'reload' }); };
$('speed').oninput = () => {
  const speed = 10 ** Number($('speed').value);
  $('speed-value').textContent = `${speed.toPrecision(2)}x`;
  send({ op: 'speed', value: speed });
};
$('solver').onchange = () => send({ op: 'solver', name: $('solver').value });
$('dt').onchange = () => {
  const dt = Number($('dt').value);
  if (dt > 0) send({ op: 'dt', value: dt });
  else showError(`dt ${$('dt').value} (expected a number of seconds > 0)`);
};
$('springs').onchange = () => view.showLinks($('springs').checked);
$('constraints-shown').onchange = () => view.showConstraintRows($('constraints-shown').checked);
$('by-speed').onchange = () => { view.bySpeed = $('by-speed').checked; view.recolour(); };
$('camera').onchange = () => view.setMode($('camera').value);
window.addEventListener('keydown', (e) => {
  if (e.code === 'Space' && e.target === document.body) { e.preventDefault(); $('play').click(); }
});

// ---- Witkin's interactions ----
const mode = () => document.querySelector('input[name=mode]:checked').value;
const pending = { move: null };
let dragging = null;  // { id, through: the drag plane's point, to: the spring's end }
let firstPick = -1;   // attach: the first particle chosen

const canvas = view.renderer.domElement;
canvas.addEventListener('pointerdown', (e) => {
  if (e.button !== 0) return;
  const id = view.pick(e.clientX, e.clientY);
  const m = mode();
  if (m === 'drag' && id >= 0) {
    // The mouse spring's end moves on the plane through the particle,
    // facing the camera, so the particle follows the cursor in depth too.
    dragging = { id, through: view.position(id), to: null };
    view.controls.enabled = false;
    canvas.setPointerCapture(e.pointerId);
    const p = view.worldAt(e.clientX, e.clientY, dragging.through);
    send({ op: 'drag', id, point: p.toArray() });
    dragging.to = p;
  } else if (m === 'nail' && id >= 0) {
    send({ op: 'nail', id });
  } else if (m === 'create') {
    const p = view.worldAt(e.clientX, e.clientY, view.target());
    send({ op: 'create', point: p.toArray(), mass: Number($('mass').value) });
  } else if (m === 'attach' && id >= 0) {
    if (firstPick < 0 || firstPick === id) {
      firstPick = id;
      view.highlight = id;
    } else {
      send({ op: 'attach', a: firstPick, b: id, ks: Number($('ks').value), kd: Number($('kd').value) });
      firstPick = -1;
      view.highlight = -1;
    }
    view.recolour();
  }
});
canvas.addEventListener('pointermove', (e) => {
  if (!dragging) return;
  pending.move = view.worldAt(e.clientX, e.clientY, dragging.through);
});
const endDrag = () => {
  if (!dragging) return;
  if (pending.move) send({ op: 'move', point: pending.move.toArray() });
  pending.move = null;
  dragging = null;
  view.controls.enabled = true;
  view.showDrag(null);
  send({ op: 'release' });
};
canvas.addEventListener('pointerup', endDrag);
canvas.addEventListener('pointercancel', endDrag);
document.querySelectorAll('input[name=mode]').forEach((r) => r.addEventListener('change', () => {
  firstPick = -1;
  view.highlight = -1;
  view.recolour();
}));

// ---- the loop: at most one `move` per displayed frame ----
function animate() {
  if (dragging && pending.move) {
    send({ op: 'move', point: pending.move.toArray() });
    dragging.to = pending.move;
    pending.move = null;
  }
  if (dragging) view.showDrag(view.position(dragging.id), dragging.to);
  view.render();
  plot.draw();
  requestAnimationFrame(animate);
}
setInterval(updateStatus, 250);
connect();
animate();
