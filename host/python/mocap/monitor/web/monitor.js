// The page: a WebSocket to `mocap monitor` (scene, then pose and health messages), the 3D view and
// the status panel. window.monitor holds what the page shows, for people and for tests.
import { COLOURS, View } from '/view.js';

const HEALTH_STALE_MS = 3000;  // mocapd sends Health once a second
const TEXT_MS = 250;  // the panel's pose lines are rewritten this often (text layout costs a CPU-only host)
const RECONNECT_MS = 1000;

const state = window.monitor = {
  connected: false,
  frames: 0,            // poses shown
  skipped: 0,           // frames the server skipped for this page (gaps in the frame index)
  lastFrame: null,      // the last pose message shown
  poses: {},            // subject id -> its last pose message shown (0: the one performer of a session of one)
  people: [],           // subject ids drawn (a performer without a pose for 2.5 s is taken away)
  health: null,         // the last Health message
  healthAt: 0,          // its arrival (performance.now())
  streams: {},          // stream name -> {state, rate_hz, ...} as shown
  updateHz: 0,          // poses received and applied during the last second
  get renderHz() { return view.renderHz; },  // 3D frames drawn during the last second
  webgl: false,
  drawnJoints: (subject = state.lastFrame?.subject ?? 0) => view.drawnJoints(subject),
};
const arrivals = [];
const view = new View(document.getElementById('view'));
state.webgl = view.ok;
document.getElementById('no-webgl').hidden = view.ok;

const text = (id, value) => { document.getElementById(id).textContent = value; };
const fixed = (x, digits = 1) => (typeof x === 'number' ? x.toFixed(digits) : '–');

const hex = (colour) => `#${colour.toString(16).padStart(6, '0')}`;

function onPose(pose) {
  const newest = Math.max(-1, ...Object.values(state.poses).map((p) => p.frame));
  if (newest >= 0 && pose.frame > newest + 1) state.skipped += pose.frame - newest - 1;
  state.lastFrame = state.poses[pose.subject] = pose;
  state.frames += 1;
  view.setPose(pose);
  const now = performance.now();
  arrivals.push(now);
  while (arrivals.length && arrivals[0] < now - 1000) arrivals.shift();
  state.updateHz = arrivals.length;
  if (now - (state.textAt || 0) < TEXT_MS) return;
  state.textAt = now;
  text('frame', `${pose.frame}  (${pose.cameras.length} cameras, ${pose.imus.length} IMUs)`);
  text('status', pose.status + (pose.distrusted.length ? `, distrusted: ${pose.distrusted.join(' ')}` : ''));
  text('update-hz', `${state.updateHz} Hz poses, ${view.renderHz} Hz drawn`);
  text('skipped', state.skipped);
  showPeople();
}

// One line per performer drawn, in its colour: its id, its inputs and the IMUs left out.
function showPeople() {
  state.people = view.retire();
  for (const subject of Object.keys(state.poses)) if (!state.people.includes(Number(subject))) delete state.poses[subject];
  const lines = state.people.map((subject) => {
    const pose = state.poses[subject], line = document.createElement('div');
    line.dataset.subject = subject;
    line.style.color = hex(COLOURS[subject % COLOURS.length][0]);
    line.textContent = `${subject === 0 ? 'performer' : `person ${subject}`}: ${pose.cameras.length} cameras, `
      + `${pose.imus.length} IMUs` + (pose.distrusted.length ? `, distrusted: ${pose.distrusted.join(' ')}` : '');
    return line;
  });
  document.getElementById('people').replaceChildren(...lines);
  const people = state.health?.people;
  text('people-counts', people ? `${people.tracked} tracked, ${people.born} found, ${people.retired} given up, `
    + `${people.suits_worn} suits worn` : '–');
}

function streamRow(s) {
  const cells = [s.name, s.state, fixed(s.rate_hz), s.lost, s.late, s.dropped, fixed(s.latency_p99_ms, 2),
    s.name.startsWith('imu/') ? fixed(s.heading_correction_deg) : ''];
  const row = document.createElement('tr');
  row.dataset.stream = s.name;
  row.className = s.state;
  for (const c of cells) row.appendChild(document.createElement('td')).textContent = c;
  return row;
}

function showStreams(streams) {
  state.streams = Object.fromEntries(streams.map((s) => [s.name, s]));
  document.querySelector('#streams tbody').replaceChildren(...streams.map(streamRow));
  for (const s of streams) {
    if (s.name.startsWith('camera/')) view.setCameraState(s.name.slice('camera/'.length), s.state);
  }
}

function onHealth(health) {
  state.health = health;
  state.healthAt = performance.now();
  text('latency', `p50 ${fixed(health.latency_p50_ms, 2)} ms, p99 ${fixed(health.latency_p99_ms, 2)} ms`);
  text('frames', `${health.frames_solved} / ${health.frames_dropped}`);
  const calibration = health.streams.find((s) => s.name === 'calibration');
  text('calibration', calibration ? (calibration.state === 'ok' ? 'IMUs calibrated' : 'video only (no IMU calibration)') : '–');
  showStreams(health.streams);
}

// No Health for HEALTH_STALE_MS: mocapd (or the link to it) is gone; every stream is shown stale.
function checkHostAlive() {
  const silent = state.health && performance.now() - state.healthAt > HEALTH_STALE_MS;
  if (silent && Object.values(state.streams).some((s) => s.state !== 'stale')) {
    showStreams(state.health.streams.map((s) => ({ ...s, state: 'stale' })));
  }
  const connection = document.getElementById('connection');
  connection.className = state.connected && !silent ? 'ok' : 'stale';
  connection.textContent = !state.connected ? 'disconnected from mocap monitor: retrying'
    : silent ? `no Health from mocapd for ${((performance.now() - state.healthAt) / 1000).toFixed(0)} s`
      : state.health ? 'live' : 'connected: waiting for mocapd';
}

function connect() {
  const socket = new WebSocket(`ws://${location.host}/ws`);
  socket.onopen = () => { state.connected = true; };
  socket.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.type === 'pose') onPose(message);
    else if (message.type === 'health') onHealth(message);
    else if (message.type === 'scene') view.setScene(message);
  };
  socket.onclose = () => { state.connected = false; setTimeout(connect, RECONNECT_MS); };
}

connect();
setInterval(() => { checkHostAlive(); showPeople(); }, 250);
