// cncstream web page: ES modules (this one and shop.js), no framework, no build step. It speaks the
// daemon's API v1 (docs/api-v1.md): REST for commands and files, one WebSocket
// for status, job progress, events and the continuous-jog dead man.

// The shop view: its own module (applyShopFrame draws a push that says what in the shop changed).
import { setupShop, applyShopFrame } from './shop.js';
// The tool library: its panel, the tool-path form's pickers, the tool change's name and stick-out.
import { setupTools, pickedLibraryTool, toolChangeLibraryText } from './tools.js';
import { setupRoutines, onRoutineFrame, renderRoutines } from './routines.js';

const API = '/api/v1';
const JOG_RENEW_MS = 150;  // the daemon's lease is 0.3 s; renew well inside it (the API asks <= 250 ms)
const FINISHED = new Set(['done', 'failed', 'stopped', 'interrupted', 'cancelled']);
const UNFINISHED = new Set(['queued', 'generating', 'ready', 'running', 'held']);

const $ = (sel) => document.querySelector(sel);
const el = (tag, props = {}, ...kids) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(props)) {
    if (k === 'class') e.className = v;
    else if (k === 'dataset') Object.assign(e.dataset, v);
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? '' : v);
  }
  for (const kid of kids.flat()) if (kid !== null && kid !== undefined) e.append(kid);
  return e;
};

// ---------------------------------------------------------------- identity
// A tab's client id names it for control ownership; sessionStorage keeps it
// across a reload of this tab but not across tabs.
function tabClientId() {
  let id = sessionStorage.getItem('cncstream.client_id');
  if (!id) {
    const r = new Uint8Array(6);
    crypto.getRandomValues(r);
    id = 'tab-' + Array.from(r, (b) => b.toString(16).padStart(2, '0')).join('');
    sessionStorage.setItem('cncstream.client_id', id);
  }
  return id;
}

// Off loopback the daemon wants a token: from the URL fragment (#token=…, which
// never reaches a server log) or typed in; kept for this tab only.
function tokenFromFragment() {
  const m = /(?:^|[#&])token=([^&]+)/.exec(location.hash);
  if (m) {
    sessionStorage.setItem('cncstream.token', decodeURIComponent(m[1]));
    // Out of the address bar, so it is not bookmarked or shown over a shoulder.
    history.replaceState(null, '', location.pathname + location.search);
  }
  return sessionStorage.getItem('cncstream.token') || '';
}

const S = {
  clientId: tabClientId(),
  token: tokenFromFragment(),
  machines: new Map(),   // name -> {summary, status, alarmInfo}
  current: localStorage.getItem('cncstream.machine') || '',
  jobs: new Map(),       // id -> Job
  control: new Map(),    // machine -> holder
  ws: null,
  wsUp: false,
  lastGenerated: null,   // id of the job the form made (its preview is shown when ready)
  previewJob: null,
  previewDraw: null,     // the last drawing's arguments and its mm -> pixel maps (a click picks a line)
  previewLine: null,     // {job, x, y, line}: the start from a line's marker
  previewUrl: null,      // the object URL the preview picture is shown from
  upload: null,          // FileInfo of the last upload
};

// ---------------------------------------------------------------- HTTP
class ApiError extends Error {
  constructor(status, code, message) { super(message); this.status = status; this.code = code; }
}

let tokenPrompt = null;  // one prompt at a time, however many requests hit 401
let tokenDeclined = false;  // the operator cancelled: no prompt at every reconnect, a banner instead
async function askToken() {
  if (tokenDeclined) return false;
  if (!tokenPrompt) {
    tokenPrompt = Promise.resolve().then(() => {
      const t = window.prompt('This controller needs its access token (printed in the daemon log, or in its data folder as "token"):', '');
      if (t) { S.token = t.trim(); sessionStorage.setItem('cncstream.token', S.token); closeBanner('token'); return true; }
      tokenDeclined = true;
      showBanner({ key: 'token', kind: 'error', title: 'This controller needs its access token',
        text: 'Without it the page cannot show or control the machines.',
        todo: 'Open the page as …/#token=<token>, or enter the token (in the daemon\'s data folder, file "token").',
        actions: [{ label: 'Enter the token', fn: async () => { tokenDeclined = false; if (await askToken()) { wsBackoff = 500; scheduleConnect(0); } } }] });
      return false;
    }).finally(() => { setTimeout(() => { tokenPrompt = null; }, 0); });
  }
  return tokenPrompt;
}

async function api(method, path, body, { raw = false, blob = false, retry = true } = {}) {
  const headers = { 'X-Client-Id': S.clientId };
  if (S.token) headers.Authorization = 'Bearer ' + S.token;
  let payload;
  // A Blob (a File) goes as it is: an upload (POST /files).
  if (body instanceof Blob) { headers['Content-Type'] = 'application/octet-stream'; payload = body; }
  else if (body !== undefined) { headers['Content-Type'] = 'application/json'; payload = JSON.stringify(body); }
  const r = await fetch(API + path, { method, headers, body: payload, cache: 'no-store' });
  if (r.status === 401 && retry) {
    if (await askToken()) return api(method, path, body, { raw, blob, retry: false });
    throw new ApiError(401, 'unauthorized', 'This controller needs an access token.');
  }
  if (!r.ok) throw await errorOf(r);
  if (raw) return r.text();
  if (blob) return r.blob();
  if (r.status === 204) return null;
  const text = await r.text();
  return text ? JSON.parse(text) : null;
}

async function errorOf(r) {
  let code = 'http_' + r.status, message = r.statusText || ('HTTP ' + r.status);
  try {
    const b = await r.json();
    if (b && b.error) { code = b.error.code || code; message = b.error.message || message; }
  } catch { /* not JSON: keep the status line */ }
  return new ApiError(r.status, code, message);
}

// Commands that move or configure a machine need this tab to hold its control.
// Acquire it when nobody holds it; when another screen does, ask the operator.
async function controlled(machine, fn) {
  // Known not to be ours: ask first rather than be refused (one round trip less).
  if (S.control.get(machine) !== S.clientId && !(await takeControl(machine, false))) return undefined;
  try {
    return await fn();
  } catch (e) {
    if (!(e instanceof ApiError) || !isControlError(e)) throw e;
    const got = await takeControl(machine, false);
    if (!got) return undefined;
    return fn();
  }
}
function isControlError(e) {
  return e.code === 'control_required' || e.code === 'control_held' ||
    (e.status === 409 && /control/i.test(e.message) && !/refused/.test(e.code));
}
async function takeControl(machine, force) {
  try {
    const r = await api('POST', `/machines/${enc(machine)}/control`, { force });
    S.control.set(machine, r.holder);
    if (machine === S.current) renderMachine();
    return true;
  } catch (e) {
    if (e instanceof ApiError && e.status === 409) {
      showBanner({
        key: 'control-' + machine, kind: 'error', title: `Another screen controls ${machine}`,
        text: e.message, todo: 'Use that screen, or take control here if nobody is working at it.',
        actions: [{ label: 'Take control', cls: 'btn-warn', fn: () => takeControl(machine, true) }],
      });
      return false;
    }
    throw e;
  }
}
const enc = encodeURIComponent;

// Any failed command is shown with its reason; the daemon's refusals say why.
function reportError(what, e) {
  const advice = {
    refused: 'The machine refused it in its present state; see the reason, and the state above.',
    bad_state: 'The job is not in a state that allows this; the queue shows its state.',
    unauthorized: 'Open the page with its token (…/#token=…) or reload and type it.',
    forbidden_origin: 'Open the page from the controller\'s own address.',
    too_large: 'The file is larger than the controller accepts.',
    unsupported_media: 'Upload an STL (binary or ASCII) or a G-code text file.',
    bad_request: 'Correct the value named in the message.',
    busy: 'Too many screens are connected; close one and try again.',
  };
  showBanner({ key: 'err-' + what, kind: 'error', title: `${what} failed`,
    text: e.message || String(e), todo: advice[e.code] || 'Check the connection and try again.', dismiss: true });
}
async function run(what, fn) {
  try { return await fn(); } catch (e) { reportError(what, e); return undefined; }
}

// ---------------------------------------------------------------- banners
// Alarms and errors, explained in words with what to do; alarms stay until the
// machine leaves the alarm, errors until dismissed.
const banners = new Map();
function showBanner({ key, kind, title, text, todo, actions = [], dismiss = false }) {
  closeBanner(key);
  const b = el('div', { class: 'banner ' + kind, role: kind === 'alarm' ? 'alert' : 'status', dataset: { key } },
    el('div', { class: 'b-title b-body' }, title),
    text ? el('div', { class: 'b-text b-body' }, text) : null,
    todo ? el('div', { class: 'b-todo b-body' }, todo) : null,
    el('div', { class: 'b-actions' },
      actions.map((a) => el('button', { class: 'btn small ' + (a.cls || ''), onclick: () => run(a.label, async () => { await a.fn(); if (a.close !== false) closeBanner(key); }) }, a.label)),
      dismiss ? el('button', { class: 'btn small', 'aria-label': 'Dismiss', onclick: () => closeBanner(key) }, 'OK') : null));
  $('#banners').append(b);
  banners.set(key, b);
  // A few errors at most: the newest ones matter.
  const errs = [...banners.entries()].filter(([, v]) => v.classList.contains('error'));
  while (errs.length > 3) closeBanner(errs.shift()[0]);
}
function closeBanner(key) {
  const b = banners.get(key);
  if (b) { b.remove(); banners.delete(key); }
}

// ---------------------------------------------------------------- machines
function machine(name) {
  if (!S.machines.has(name)) S.machines.set(name, { summary: { name }, status: null, alarmInfo: null });
  return S.machines.get(name);
}

async function loadMachines() {
  const r = await api('GET', '/machines');
  for (const m of r.machines) {
    const rec = machine(m.name);
    rec.summary = m;
    S.control.set(m.name, m.control_holder);
  }
  if (!S.machines.has(S.current)) S.current = r.machines.length ? r.machines[0].name : '';
  renderMachinePicker();
  await loadMachineDetail(S.current);
}

async function loadMachineDetail(name) {
  if (!name) return;
  const d = await api('GET', `/machines/${enc(name)}`);
  const rec = machine(name);
  rec.summary = { ...rec.summary, ...d };
  if (d.status) rec.status = { ...d.status, link: d.link, alarm: d.alarm, jogging: d.jogging, job_active: d.job_active, tool_change: d.tool_change };
  rec.alarmInfo = d.alarm_info;
  rec.toolChange = d.tool_change || null;
  rec.routine = d.routine || null;
  rec.toolReference = d.tool_reference || null;
  renderAll();
}

function renderMachinePicker() {
  const sel = $('#machine-select');
  sel.replaceChildren(...[...S.machines.keys()].map((n) => el('option', { value: n, selected: n === S.current }, n)));
  renderMachineList();
}

function renderMachineList() {
  $('#machines').replaceChildren(...[...S.machines.values()].map((rec) => {
    const st = stateOf(rec);
    return el('li', {}, el('button', { 'aria-pressed': String(rec.summary.name === S.current), onclick: () => selectMachine(rec.summary.name) },
      el('span', { class: 'dot state-' + st.cls }), rec.summary.name, el('span', { class: 'muted' }, st.label)));
  }));
}

function selectMachine(name) {
  if (name === S.current) return;
  releaseJog('machine changed');
  S.current = name;
  localStorage.setItem('cncstream.machine', name);
  renderMachinePicker();
  formButton();
  run('Loading the machine', async () => { await loadMachineDetail(name); await loadJobs(); });
}

function stateOf(rec) {
  const link = (rec.status && rec.status.link) || rec.summary.link;
  if (link && link !== 'ready') return { label: link === 'connecting' ? 'Connecting' : link === 'disconnected' ? 'Disconnected' : 'Closed', cls: 'offline' };
  const s = (rec.status && rec.status.state) || rec.summary.state;
  if (!s) return { label: '—', cls: 'unknown' };
  const text = (rec.status && rec.status.state_text) || s;
  return { label: STATE_WORDS[text] || text.split(':')[0], cls: s.toLowerCase().split(':')[0], text };
}
// GRBL's sub-states in words (Hold:1 means still slowing down: not safe to walk up to yet).
const STATE_WORDS = {
  'Hold:0': 'Held', 'Hold:1': 'Holding…', 'Door:0': 'Door closed', 'Door:1': 'Door open',
  'Door:2': 'Door open, parking', 'Door:3': 'Door closed, restoring',
};

const fmt = (v, d = 3) => (typeof v === 'number' && isFinite(v) ? v.toFixed(d) : '—');

function renderMachine() {
  const rec = S.machines.get(S.current);
  const stEl = $('#state');
  if (!rec) {
    // Nothing known yet (not connected): nothing to press but STOP.
    stEl.textContent = 'No machine';
    stEl.className = 'state state-unknown';
    document.querySelectorAll('#panel-jog button:not(#jog-stop), #panel-job .run-actions button, #panel-job .overrides button').forEach((b) => { b.disabled = true; });
    return;
  }
  const st = stateOf(rec);
  stEl.textContent = st.label;
  stEl.className = 'state state-' + st.cls;
  stEl.dataset.state = st.cls;
  stEl.dataset.text = st.text || '';
  $('#top-state').textContent = st.label;
  $('#top-state').className = 'state top-state state-' + st.cls;
  const s = rec.status || {};
  const w = s.wpos || [], m = s.mpos || [];
  ['x', 'y', 'z'].forEach((a, i) => { $('#dro-' + a).textContent = fmt(w[i]); $('#dro-m' + a).textContent = fmt(m[i]); });
  $('#feed').textContent = fmt(s.feed, 0);
  $('#spindle').textContent = fmt(s.spindle, 0);
  const ov = s.overrides || [];
  $('#ov-feed').textContent = (ov[0] ?? 100) + ' %';
  $('#ov-rapid').textContent = (ov[1] ?? 100) + ' %';
  $('#ov-spindle').textContent = (ov[2] ?? 100) + ' %';
  const link = s.link || rec.summary.link;
  const holder = S.control.get(S.current);
  $('#control').textContent = holder === S.clientId ? 'this screen has control' : holder ? `controlled by another screen (${holder})` : '';
  $('#machine-link').textContent = [rec.summary.profile, link && link !== 'ready' ? 'link ' + link : ''].filter(Boolean).join(' · ');

  // What may be pressed follows the machine's state (the daemon refuses the
  // rest anyway, with a reason; greying them out says so before the press).
  const ready = link === 'ready';
  const alarm = !!s.alarm || st.cls === 'alarm';
  const jobActive = !!s.job_active || !!rec.summary.job_active;
  // At a tool change's prompt the machine is idle and the operator's: the pad works.
  const tc = rec.toolChange;
  const operatorTurn = !!(tc && tc.operator_turn);
  const canJog = ready && !alarm && (!jobActive || operatorTurn);
  document.querySelectorAll('#jogpad .jog:not(.jstop)').forEach((b) => { if (!b.classList.contains('held')) b.disabled = !canJog; });
  for (const id of ['zero-xy', 'zero-z', 'go-zero', 'safe-z']) $('#' + id).disabled = !canJog;
  $('#unlock').disabled = !ready || jobActive;
  $('#home').disabled = !ready || jobActive;
  $('#reset').disabled = !ready;
  document.querySelectorAll('#panel-job .overrides button').forEach((b) => { b.disabled = !ready; });
  renderAlarm(rec, alarm);
  renderToolChange(rec, ready && !alarm && operatorTurn);
  renderRoutines(rec, { ready, alarm, jobActive });
}

// ---------------------------------------------------------------- tool change
// The steps of the session's routine as the operator lives them; the daemon
// says which one the machine is at (its `step`), the page remembers whether
// the operator's prompt of this change has passed.
function toolChangeSteps(tc) {
  const t = tc.tool ? `T${tc.tool}` : 'the next tool';
  if (tc.method === 'manual') {
    return [
      { key: 'before', text: 'Spindle and coolant off, up to the safe Z' },
      { key: 'zero_manually', text: `Mount ${t}, jog down, zero work Z (Probe Z on the touch plate, or Zero Z here), then Continue` },
      { key: 'after', text: 'Back to the work: safe Z, XY, the spindle, then Z' },
    ];
  }
  if (tc.method === 'controller') {
    // grblHAL's own: the M6 goes to the controller; in its Tool state jogs work, probing does not (error:40).
    return [
      { key: 'before', text: 'Spindle and coolant off, up to the safe Z; M6 to the controller, which enters its Tool state' },
      { key: 'zero_manually', text: `Mount ${t}, jog down, zero work Z here (Zero Z), then Continue` },
      { key: 'after', text: 'Cycle start ends the Tool state; back to the work: safe Z, XY, the spindle, then Z' },
    ];
  }
  const where = tc.method === 'sensor' ? 'the tool-length sensor' : 'the touch plate';
  return [
    { key: 'before', text: `Spindle and coolant off, up to the safe Z, over ${where}; the tool in the spindle is measured if no reference is kept` },
    { key: 'mount_tool', text: `Mount ${t}, then Continue` },
    { key: 'after', text: `${t} measured on ${where}, the work offset written and read back` },
    { key: 'back', text: 'Back to the work: safe Z, XY, the spindle, then Z' },
  ];
}

function renderToolChange(rec, operatorTurn) {
  const panel = $('#panel-toolchange');
  const tc = rec.toolChange;
  if (!tc) {
    if (!panel.hidden) { panel.hidden = true; delete panel.dataset.step; }
    return;
  }
  const first = panel.hidden;
  panel.hidden = false;
  panel.dataset.step = tc.step;
  panel.dataset.line = tc.line;
  const key = `${rec.summary.name}:${tc.line}`;
  if (tc.step !== 'routine') rec.tcPrompted = key;
  const prompted = rec.tcPrompted === key;
  $('#tc-what').textContent = `${tc.tool ? 'T' + tc.tool : 'Next tool'}${tc.description ? ' — ' + tc.description : ''}` +
    ` (line ${tc.line}, ${tc.method}${tc.from_tool ? ', T' + tc.from_tool + ' in the spindle' : ''})`;
  $('#tc-library').textContent = toolChangeLibraryText(tc);
  const steps = toolChangeSteps(tc);
  let current = 0;
  if (tc.step === 'mount_tool' || tc.step === 'zero_manually') current = 1;
  else if (tc.step === 'question') current = 2;
  else if (prompted) current = 2;
  const sig = JSON.stringify([steps.map((x) => x.text), current]);
  if (panel.dataset.sig !== sig) {
    panel.dataset.sig = sig;
    $('#tc-steps').replaceChildren(...steps.map((x, i) => el('li', { class: i < current ? 'done' : i === current ? 'current' : '', dataset: { step: x.key } },
      x.text + (i === current && tc.step === 'routine' ? ' — the machine works, wait' : ''))));
  }
  $('#tc-prompt').textContent = tc.prompt ? tc.prompt.text : '';
  $('#tc-confirm').disabled = !operatorTurn;
  $('#tc-decline').disabled = !operatorTurn;
  $('#tc-probe').disabled = !operatorTurn || tc.step === 'question' || tc.method === 'controller';
  $('#tc-zero-z').disabled = !operatorTurn || tc.step !== 'zero_manually';
  $('#tc-confirm').textContent = tc.step === 'question' ? 'Apply the measured length' : 'Continue';
  if (first) panel.scrollIntoView({ block: 'nearest' });
}

// ---------------------------------------------------------------- start from a line
// The job shown in the preview starts after a line the operator picks: the
// daemon's resume planner (the same as `cncstream resume --from-line`) writes
// the way back in (safe Z, spindle, XY, then Z); the plan is shown, then
// queued as a new ready job that still needs Start.
let fromLinePlan = null;  // {job, plan_id}
function setupFromLine() {
  $('#from-line-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const id = S.previewJob;
    const j = S.jobs.get(id);
    if (!j) return;
    const line = Number($('#from-line').value);
    run('Plan the start', async () => {
      const plan = await controlled(j.machine, () => api('POST', `/jobs/${id}/resume-plan`, { from_line: line }));
      if (!plan) return;
      fromLinePlan = { job: id, plan_id: plan.plan_id };
      const op = plan.operation ? ` It continues ${plan.operation.name} with T${plan.operation.tool} (${plan.operation.cutter}): mount it first.` : '';
      const why = /from-line/.test(plan.reason) ? '' : ` ${plan.reason.replace(/\.$/, '')}.`;  // the planner's own choice only
      $('#from-line-text').textContent = `Job #${id} continues after line ${plan.from_line}: ${plan.lines.toLocaleString()} lines to send, ` +
        `the way back in first (safe height, spindle, XY, then Z).${why}${op}`;
      $('#from-line-preamble').textContent = plan.preamble.join('\n');
      $('#from-line-plan').hidden = false;
    });
  });
  $('#from-line-cancel').addEventListener('click', () => { fromLinePlan = null; $('#from-line-plan').hidden = true; });
  // A click on the drawing picks the line of the nearest cutting point; a
  // typed line moves the marker to the last drawn point at or before it.
  const redraw = () => { if (S.previewDraw) drawPreview(...S.previewDraw.args); };
  $('#preview-canvas').addEventListener('click', (e) => {
    const cv = e.currentTarget;
    const r = cv.getBoundingClientRect();
    const p = pickPreviewPoint((e.clientX - r.left) * cv.width / r.width, (e.clientY - r.top) * cv.height / r.height);
    if (!p) return;
    $('#from-line').value = p.line;
    S.previewLine = { ...p, job: S.previewJob };
    redraw();
  });
  $('#from-line').addEventListener('input', () => {
    const n = Number($('#from-line').value);
    const p = n > 0 ? previewPointOfLine(n) : null;
    S.previewLine = p ? { ...p, line: n, job: S.previewJob } : null;
    redraw();
  });
  $('#from-line-queue').addEventListener('click', () => {
    const p = fromLinePlan;
    if (!p) return;
    const j = S.jobs.get(p.job);
    run('Queue the start from a line', async () => {
      const created = await controlled(j.machine, () => api('POST', `/jobs/${p.job}/resume-confirm`, { plan_id: p.plan_id }));
      if (!created) return;
      fromLinePlan = null;
      $('#from-line-plan').hidden = true;
      S.jobs.set(created.id, created);
      renderJobs();
    });
  });
}

function setupToolChange() {
  const m = () => S.current;
  const post = (what, path, body = {}) => () => run(what, () => controlled(m(), () => api('POST', `/machines/${enc(m())}/${path}`, body)));
  $('#tc-confirm').addEventListener('click', post('Continue', 'tool-change/confirm'));
  $('#tc-decline').addEventListener('click', post('Decline', 'tool-change/decline'));
  $('#tc-probe').addEventListener('click', post('Probe Z', 'actions/probe_z'));
  $('#tc-zero-z').addEventListener('click', post('Zero Z', 'actions/zero_axes', { axes: 'Z' }));
}

function renderAlarm(rec, alarm) {
  const key = 'alarm-' + rec.summary.name;
  if (!alarm) { closeBanner(key); return; }
  if (banners.has(key) && banners.get(key).dataset.code === String(rec.alarmInfo && rec.alarmInfo.code)) return;
  const i = rec.alarmInfo || {};
  const actions = [];
  if (i.reset_required) actions.push({ label: 'Reset', cls: 'btn-warn', close: false, fn: () => controlled(rec.summary.name, () => api('POST', `/machines/${enc(rec.summary.name)}/actions/reset`, {})) });
  if (i.position_lost) actions.push({ label: 'Home', cls: 'btn-go', close: false, fn: () => controlled(rec.summary.name, () => api('POST', `/machines/${enc(rec.summary.name)}/actions/home`, {})) });
  actions.push({ label: 'Unlock', close: false, fn: () => controlled(rec.summary.name, () => api('POST', `/machines/${enc(rec.summary.name)}/actions/unlock`, {})) });
  showBanner({
    key, kind: 'alarm',
    title: `ALARM on ${rec.summary.name}` + (i.code ? ` (${i.code}): ${i.name || ''}` : ''),
    text: i.text || 'The controller stopped everything and ignores motion until the alarm is cleared.',
    todo: i.action || 'Make the machine safe, then Unlock (or Home if the position may be lost).',
    actions,
  });
  banners.get(key).dataset.code = String(i.code);
}

// ---------------------------------------------------------------- jobs
async function loadJobs() {
  const r = await api('GET', '/jobs');
  S.jobs = new Map(r.jobs.map((j) => [j.id, j]));
  renderJobs();
}
let jobsReload = null;
function reloadJobsSoon() {
  // queue events come in bursts (create, generate, ready): one fetch for a burst.
  clearTimeout(jobsReload);
  jobsReload = setTimeout(() => run('Loading the jobs', loadJobs), 120);
}

// The state, and the daemon's message unless it only says the state again.
function outcomeText(j) {
  const msg = j.message || '';
  if (!msg) return j.state;
  return msg.toLowerCase().startsWith(j.state) ? msg : `${j.state}: ${msg}`;
}
function jobTitle(j) { return `${j.file_name || 'job'} #${j.id}`; }
function toolText(p) {
  if (!p || !p.tool) return 'G-code as uploaded';
  const spacing = p.scallop ? `scallop ${p.scallop} mm` : `stepover ${p.stepover} mm`;  // a scallop height sets the spacing
  return `${p.rough ? `${p.rough} roughing, then ` : ''}${p.tool}, ${spacing}, rows along ${(p.direction || 'x').toUpperCase()}` +
    `${p.strategy === 'raster' ? ' only' : ''}${p.rest ? `, then ${p.rest} where it cannot reach` : ''}` +
    `${p.stock && p.stock !== 'auto' ? `, stock ${p.stock}` : ''}`;
}
function duration(s) {
  if (!(s >= 0) || !isFinite(s)) return '—';
  s = Math.round(s);
  const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), sec = s % 60;
  return h ? `${h} h ${String(m).padStart(2, '0')} min` : m ? `${m} min ${String(sec).padStart(2, '0')} s` : `${sec} s`;
}

function renderJobs() {
  const mine = [...S.jobs.values()].filter((j) => j.machine === S.current);
  const queue = mine.filter((j) => UNFINISHED.has(j.state)).sort((a, b) => (a.position ?? 0) - (b.position ?? 0));
  $('#queue-empty').hidden = queue.length > 0;
  // Rebuild an entry only when what it shows changed: progress messages come
  // many times a second, and a button replaced under a finger loses its tap.
  // Entries are updated in place and their buttons rebuilt only when the set of
  // actions changes: progress and reloads come many times a second, and a
  // button replaced under a finger loses its tap.
  const items = queue.map((j) => {
    const old = queueItems.get(j.id);
    const item = queueItem(j, old);
    queueItems.set(j.id, item);
    return item.li;
  });
  for (const id of queueItems.keys()) if (!queue.some((j) => j.id === id)) queueItems.delete(id);
  sameChildren($('#queue'), items);
  renderRunning(mine);
  renderHistory();
  renderFormStatus();
}

const queueItems = new Map();  // job id -> {li, actKey}
function sameChildren(parent, nodes) {
  const kids = parent.children;
  if (kids.length === nodes.length && nodes.every((n, i) => kids[i] === n)) return;
  parent.replaceChildren(...nodes);
}

function queueItem(j, old) {
  const g = j.generation || {};
  let meta = toolText(j.params);
  if (j.state === 'generating') meta += ` · ${g.stage || 'starting'} ${g.fraction != null ? Math.round(g.fraction * 100) + ' %' : ''}`;
  if (j.program) meta += ` · ${j.program.lines.toLocaleString()} lines · about ${duration(j.program.estimated_s)}`;
  if (j.message) meta += ` · ${j.message}`;
  const li = old ? old.li : el('li', { dataset: { job: j.id } },
    el('div', { class: 'title' }, el('span', { class: 't-name' }), el('span', { class: 'badge' })),
    el('div', { class: 'meta' }), el('div', { class: 'actions' }));
  li.dataset.state = j.state;
  li.querySelector('.t-name').textContent = jobTitle(j);
  const badge = li.querySelector('.badge');
  badge.textContent = j.state;
  badge.className = 'badge ' + j.state;
  li.querySelector('.meta').textContent = meta;
  const actKey = JSON.stringify([j.state, (j.position ?? 0) > 0, j.kind]);
  if (!old || old.actKey !== actKey) li.querySelector('.actions').replaceChildren(...queueActions(j));
  li.querySelector('.actions').hidden = !li.querySelector('.actions').children.length;
  return { li, actKey };
}

// The handlers look the job up when pressed: the entry outlives the job object it was made from.
function queueActions(j0) {
  const id = j0.id, m = j0.machine;
  const job = () => S.jobs.get(id) || j0;
  const b = (act, label, cls, fn, { text, ...attrs } = {}) => el('button', { class: 'btn ' + cls, 'data-act': act, onclick: () => run(label, fn), ...attrs }, text || label);
  const acts = [];
  const st = j0.state;
  if (st === 'ready') {
    acts.push(b('start', 'Start', 'btn-go', () => controlled(m, () => api('POST', `/jobs/${id}/start`, {}))));
    acts.push(b('preview', 'Preview', '', () => showPreview(id)));
  }
  if (st === 'queued') acts.push(b('generate', 'Generate', '', () => api('POST', `/jobs/${id}/generate`, {})));
  if (st === 'running') acts.push(b('hold', 'Hold', 'btn-warn', () => api('POST', `/jobs/${id}/hold`, {})));
  if (st === 'held') acts.push(b('resume', 'Resume', 'btn-go', () => controlled(m, () => api('POST', `/jobs/${id}/resume`, {}))));
  if (st === 'running' || st === 'held') acts.push(b('stop', 'Stop', 'btn-danger', () => api('POST', `/jobs/${id}/stop`, {})));
  if (['queued', 'generating', 'ready'].includes(st)) {
    if ((j0.position ?? 0) > 0) acts.push(b('up', 'Move', '', () => api('POST', `/jobs/${id}/move`, { position: Math.max(0, (job().position ?? 1) - 1) }), { 'aria-label': 'Move up', text: '↑' }));
    acts.push(b('cancel', 'Remove', '', () => controlled(m, () => api('POST', `/jobs/${id}/cancel`, {}))));
  }
  return acts;
}

// The running panel shows the active job, else the last one that ran here (so
// its end, 100 % or where it stopped, stays readable).
function renderRunning(mine) {
  const active = mine.find((j) => j.state === 'running' || j.state === 'held');
  const last = active || mine.filter((j) => j.started_at).sort((a, b) => String(b.started_at).localeCompare(String(a.started_at)))[0];
  const bar = $('#progressbar');
  if (!last) {
    $('#job-name').textContent = `No job has run on ${S.current || 'this machine'} yet`;
    $('#job-name').className = 'job-name muted';
    setProgress(0, '', '');
    $('#progress-pct').textContent = '—';
    bar.dataset.state = 'none';
  } else {
    const p = last.progress || {};
    const total = (last.program && last.program.lines) || p.total_lines || 0;
    const frac = last.state === 'done' ? 1 : (p.fraction ?? (total ? p.lines_answered / total : 0));
    $('#job-name').textContent = `${jobTitle(last)} — ${outcomeText(last)}`;
    $('#job-name').className = 'job-name';
    const lines = total ? `${(p.lines_answered || 0).toLocaleString()} / ${total.toLocaleString()} lines` : '';
    let eta = '';
    if (active) {
      const e = p.eta_s ?? last.eta_s;
      if (e != null) eta = `ETA ${new Date(Date.now() + e * 1000).toLocaleTimeString([], { hour: '2-digit', minute: '2-digit' })} (${duration(e)} left)`;
    } else if (last.started_at && last.ended_at) {
      eta = `took ${duration((Date.parse(last.ended_at) - Date.parse(last.started_at)) / 1000)}`;
    }
    // The simulator's cut checked against the part (sim machines only).
    if (last.verify && last.verify.text) eta += (eta ? ' · ' : '') + last.verify.text;
    setProgress(frac, lines, eta);
    bar.dataset.state = last.state;
    bar.dataset.job = last.id;
  }
  const st = active ? active.state : '';
  $('#btn-hold').disabled = st !== 'running' && !(S.machines.get(S.current)?.status?.jogging);
  $('#btn-resume').disabled = st !== 'held';
  $('#btn-stop').disabled = !active;
  $('#panel-job').dataset.job = active ? active.id : '';
  // While a job runs its controls matter more than the (disabled) jog pad.
  document.body.classList.toggle('job-active', !!active);
}

function setProgress(frac, lines, eta) {
  const pct = Math.max(0, Math.min(100, Math.floor(frac * 1000) / 10));
  $('#progress-bar').style.width = pct + '%';
  $('#progressbar').setAttribute('aria-valuenow', String(pct));
  $('#progress-pct').textContent = (pct === 100 ? '100' : pct.toFixed(1)) + ' %';
  $('#progress-lines').textContent = lines;
  $('#eta').textContent = eta;
}

let historySig = null;
function renderHistory() {
  const done = [...S.jobs.values()].filter((j) => FINISHED.has(j.state))
    .sort((a, b) => String(b.ended_at || b.created_at).localeCompare(String(a.ended_at || a.created_at))).slice(0, 50);
  const sig = JSON.stringify(done.map((j) => [j.id, j.state, j.message, j.ended_at, j.progress && j.progress.last_answered_line]));
  if (sig === historySig) return;
  historySig = sig;
  $('#history tbody').replaceChildren(...(done.length ? done.map((j) => {
    const p = j.progress || {};
    const total = j.program ? j.program.lines : null;
    return el('tr', { dataset: { job: j.id, state: j.state } },
      el('td', { class: 'c-when' }, j.ended_at ? new Date(j.ended_at).toLocaleString([], { month: 'short', day: 'numeric', hour: '2-digit', minute: '2-digit' }) : '—'),
      el('td', { class: 'c-machine' }, j.machine),
      el('td', { class: 'c-job' }, jobTitle(j)),
      el('td', { class: 'c-outcome oc-' + (j.state === 'done' ? 'completed' : j.state === 'failed' ? 'error' : j.state) }, outcomeText(j)),
      el('td', { class: 'mono c-lines' }, total ? `${(p.last_answered_line || p.lines_answered || 0).toLocaleString()} / ${total.toLocaleString()}` : '—'));
  }) : [el('tr', {}, el('td', { colspan: 5, class: 'muted' }, 'No finished jobs yet.'))]));
}

function onJobMessage(m) {
  const j = S.jobs.get(m.job);
  if (!j) { reloadJobsSoon(); return; }
  j.state = m.state ?? j.state;
  if (m.progress) j.progress = { ...j.progress, ...m.progress };
  if (m.eta_s !== undefined) j.progress = { ...(j.progress || {}), eta_s: m.eta_s };
  if (m.message !== undefined) j.message = m.message;
  if (m.generation) j.generation = m.generation;
  if (m.program) j.program = m.program;
  // A state change brings fields the message lacks (program, times): fetch them.
  if (m.state && (m.state !== j._lastState)) { j._lastState = m.state; reloadJobsSoon(); }
  renderJobs();
}

// ---------------------------------------------------------------- upload and tool path form
function setupUpload() {
  const drop = $('#drop');
  drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('over'));
  drop.addEventListener('drop', (e) => {
    e.preventDefault();
    drop.classList.remove('over');
    const f = e.dataTransfer && e.dataTransfer.files[0];
    if (f) upload(f);
  });
  // A file dropped beside the zone should not make the browser navigate away from the controls.
  window.addEventListener('dragover', (e) => e.preventDefault());
  window.addEventListener('drop', (e) => e.preventDefault());
  $('#file-input').addEventListener('change', (e) => { const f = e.target.files[0]; if (f) upload(f); e.target.value = ''; });
  $('#tp-cutter').addEventListener('change', () => { $('#tp-radius-label').hidden = $('#tp-cutter').value !== 'bull'; });
  $('#toolpath-form').addEventListener('submit', (e) => { e.preventDefault(); run('Generate', generate); });
}

function upload(file) {
  const status = $('#upload-status');
  status.textContent = `Uploading ${file.name}…`;
  // XHR, not fetch: it reports upload progress (a 100 MB STL over Wi-Fi takes a while).
  return new Promise((resolve) => {
    const x = new XMLHttpRequest();
    x.open('POST', `${API}/files?name=${enc(file.name)}`);
    x.setRequestHeader('X-Client-Id', S.clientId);
    if (S.token) x.setRequestHeader('Authorization', 'Bearer ' + S.token);
    x.setRequestHeader('Content-Type', 'application/octet-stream');
    x.upload.onprogress = (e) => { if (e.lengthComputable) status.textContent = `Uploading ${file.name}… ${Math.round(100 * e.loaded / e.total)} %`; };
    x.onerror = () => { status.textContent = ''; reportError('Upload', new Error('The connection to the controller was lost during the upload.')); resolve(); };
    x.onload = async () => {
      let b = null;
      try { b = JSON.parse(x.responseText); } catch { /* keep null */ }
      if (x.status === 401 && await askToken()) { resolve(upload(file)); return; }
      if (x.status < 200 || x.status >= 300) {
        status.textContent = '';
        const err = b && b.error ? new ApiError(x.status, b.error.code, b.error.message) : new ApiError(x.status, 'http_' + x.status, x.statusText);
        reportError('Upload', err);
        resolve();
        return;
      }
      S.upload = b;
      status.textContent = b.kind === 'stl'
        ? `${b.name}: STL, ${Number(b.facets).toLocaleString()} facets. Set the tool path below.`
        : `${b.name}: G-code, ${Number(b.lines).toLocaleString()} lines.`;
      showForm(b);
      resolve(b);
    };
    x.send(file);
  });
}

function showForm(f) {
  const form = $('#toolpath-form');
  form.hidden = false;
  form.dataset.kind = f.kind;
  $('#tp-part').textContent = f.name;
  const stl = f.kind === 'stl';
  form.querySelector('.grid').hidden = !stl;
  formButton();
  $('#tp-status').textContent = '';
}
// The job is made for the machine shown: the button says which.
function formButton() {
  if (!S.upload) return;
  $('#tp-generate').textContent = S.upload.kind === 'stl' ? `Generate tool path for ${S.current}` : `Add to the queue of ${S.current}`;
}

function numberOf(id, { optional = false } = {}) {
  const v = $(id).value.trim();
  if (v === '' && optional) return null;
  const n = Number(v);
  if (!isFinite(n)) throw new ApiError(400, 'bad_request', `${$(id).closest('label').firstChild.textContent.trim()}: not a number`);
  return n;
}

async function generate() {
  if (!S.upload) return;
  if (!S.current) throw new Error('No machine to queue the job on.');
  const body = { machine: S.current, file: S.upload.id };
  if (S.upload.kind === 'stl') {
    const cutter = $('#tp-cutter').value;
    const d = numberOf('#tp-diameter');
    const tool = pickedLibraryTool() || (cutter === 'bull' ? `bull:${d}:${numberOf('#tp-radius')}` : `${cutter}:${d}`);
    body.params = {
      tool, stepover: numberOf('#tp-stepover'), direction: $('#tp-direction').value,
      feed: numberOf('#tp-feed'), plunge_feed: numberOf('#tp-plunge'), rpm: numberOf('#tp-rpm'),
      safe_z: numberOf('#tp-safez', { optional: true }), step: numberOf('#tp-step', { optional: true }) ?? 0,
      strategy: $('#tp-strategy').value,
    };
    // Left empty, the daemon's defaults: rows at the stepover given, stock
    // `auto`, roughing with the finishing cutter when the finish alone would cut too deep.
    const scallop = numberOf('#tp-scallop', { optional: true });
    if (scallop != null) body.params.scallop = scallop;
    for (const [key, id] of [['stock', '#tp-stock'], ['rough', '#tp-rough'], ['rest', '#tp-rest']]) {
      const v = $(id).value.trim();
      if (v) body.params[key] = v;
    }
  }
  $('#tp-generate').disabled = true;
  try {
    const j = await api('POST', '/jobs', body);
    S.jobs.set(j.id, j);
    S.lastGenerated = j.id;
    renderJobs();
  } finally {
    $('#tp-generate').disabled = false;
  }
}

function renderFormStatus() {
  const j = S.lastGenerated != null ? S.jobs.get(S.lastGenerated) : null;
  if (!j) return;
  const s = $('#tp-status');
  const g = j.generation || {};
  if (j.state === 'generating' || j.state === 'queued') s.textContent = `Generating #${j.id}: ${g.stage || 'waiting'}${g.fraction != null ? ' ' + Math.round(g.fraction * 100) + ' %' : ''}`;
  else if (j.state === 'ready') s.textContent = `#${j.id} ready${j.program ? `: ${j.program.lines.toLocaleString()} lines, about ${duration(j.program.estimated_s)}` : ''}. Start it from the queue.`;
  else if (j.state === 'failed') s.textContent = `#${j.id} failed: ${j.message}`;
  else s.textContent = `#${j.id}: ${j.state}`;
  s.dataset.state = j.state;
  if (j.state === 'ready' && S.previewJob !== j.id && j.program) {
    S.previewJob = j.id;
    run('Preview', () => showPreview(j.id));
  }
}

// ---------------------------------------------------------------- preview
// The daemon draws the tool tip's heights (GET …/clmap.png, colour = Z between
// the Job's preview.z) and thins the program's path (GET …/path), so a phone
// never downloads a whole program to see it. The path is drawn over the
// picture, rapids dashed.
async function showPreview(id) {
  if (S.previewJob !== id) { fromLinePlan = null; $('#from-line-plan').hidden = true; }
  S.previewJob = id;
  // The bounds and heights come with the Job: at `ready` for an STL job, a
  // moment later for G-code (the daemon traces it with the time estimate).
  let j = await api('GET', `/jobs/${id}`);
  for (let waited = 0; j.program && !j.preview && waited < 30000 && S.previewJob === id; waited += 500) {
    await new Promise((r) => setTimeout(r, 500));
    j = await api('GET', `/jobs/${id}`);
  }
  if (S.previewJob !== id) return;  // another preview was asked for meanwhile
  $('#preview').hidden = false;  // shown first: the drawing is sized to its width
  const cv = $('#preview-canvas');
  const dpr = Math.min(2, window.devicePixelRatio || 1);
  const W = Math.round(Math.max(320, Math.min(900, cv.parentElement.clientWidth || 640) * dpr));
  const pv = j.preview;
  let img = null, path = { cuts: [], rapids: [], points: 0, total_points: 0 };
  if (pv) {
    // About as many pixels as the canvas has, and points enough for its
    // width, in steps, so that screens of about the same size share the
    // daemon's cached answers.
    const max = Math.min(1024, Math.ceil(W / 128) * 128);
    const points = Math.min(20000, Math.max(2000, Math.round(W * 16 / 2000) * 2000));
    [img, path] = await Promise.all([loadPreviewImage(id, max), api('GET', `/jobs/${id}/path?max_points=${points}`)]);
    if (S.previewJob !== id) return;
  }
  const none = !j.program ? 'No program yet' : 'No cutting moves to show (or still being traced)';
  drawPreview(cv, W, dpr, pv, img, path, none);
  const title = jobTitle(j);
  if (!pv) $('#preview-meta').textContent = `${title} · ${none.toLowerCase()}`;
  else {
    const [x0, y0, x1, y1] = pv.bounds;
    const drawn = path.points < path.total_points ? ` (${path.points.toLocaleString()} drawn)` : '';
    $('#preview-meta').textContent = `${title} · ${path.total_points.toLocaleString()} points${drawn} · X ${fmt(x0, 1)}…${fmt(x1, 1)} Y ${fmt(y0, 1)}…${fmt(y1, 1)} Z ${fmt(pv.z[0], 2)}…${fmt(pv.z[1], 2)} mm`;
  }
  $('#preview').dataset.job = id;
  renderMachine();  // the set-up panel's outline traces the previewed job
}

// The PNG through fetch (it needs the token header an <img src> cannot send),
// shown by the page's hidden <img> (the canvas draws from it).
async function loadPreviewImage(id, max) {
  const blob = await api('GET', `/jobs/${id}/clmap.png?max=${max}`, undefined, { blob: true });
  const img = $('#preview-img');
  const url = URL.createObjectURL(blob);
  await new Promise((ok, fail) => {
    img.onload = ok;
    img.onerror = () => fail(new Error('the preview picture could not be decoded'));
    img.src = url;
  });
  if (S.previewUrl) URL.revokeObjectURL(S.previewUrl);
  S.previewUrl = url;
  return img;
}

// The daemon's ramp (viridis), for the legend.
const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];

function drawPreview(cv, W, dpr, pv, img, path, none) {
  const ctx = cv.getContext('2d');
  const pad = 24 * dpr;
  if (!pv) {
    S.previewDraw = null;
    cv.width = W; cv.height = Math.round(W / 4);
    ctx.fillStyle = '#0b0d10';
    ctx.fillRect(0, 0, cv.width, cv.height);
    ctx.fillStyle = '#9aa5b1';
    ctx.font = `${Math.round(14 * dpr)}px sans-serif`;
    ctx.fillText(none, pad, pad + 14 * dpr);
    return;
  }
  const [x0, y0, x1, y1] = pv.bounds;
  const sx = x1 - x0 || 1, sy = y1 - y0 || 1;
  const scale = (W - 2 * pad) / sx;
  cv.width = W;
  const H = cv.height = Math.max(Math.round(4 * pad), Math.min(Math.round(sy * scale + 2 * pad), 2 * W));
  const s = Math.min(scale, (H - 2 * pad) / sy);
  const X = (x) => pad + (x - x0) * s, Y = (y) => H - pad - (y - y0) * s;
  ctx.fillStyle = '#0b0d10';
  ctx.fillRect(0, 0, W, H);
  // The picture spans the bounds exactly, north up.
  ctx.imageSmoothingEnabled = true;
  ctx.drawImage(img, X(x0), Y(y1), (x1 - x0) * s || 1, (y1 - y0) * s || 1);
  const stroke = (lines) => {
    ctx.beginPath();
    for (const l of lines) {
      ctx.moveTo(X(l[0]), Y(l[1]));
      for (let i = 3; i < l.length; i += 3) ctx.lineTo(X(l[i]), Y(l[i + 1]));
    }
    ctx.stroke();
  };
  // Cutting moves thin and dark, rapids dashed red.
  ctx.lineWidth = 1;
  ctx.strokeStyle = 'rgba(0,0,0,0.35)';
  stroke(path.cuts);
  ctx.strokeStyle = 'rgba(255,90,90,0.8)';
  ctx.setLineDash([4 * dpr, 4 * dpr]);
  stroke(path.rapids);
  ctx.setLineDash([]);
  // Legend: the colours' heights, laid out left to right by measured width.
  ctx.font = `${Math.round(14 * dpr)}px sans-serif`;
  ctx.fillStyle = '#e8ecf0';
  const lo = `tool tip Z ${fmt(pv.z[0], 2)}`, hi = `${fmt(pv.z[1], 2)} mm`, base = H - 6 * dpr;
  ctx.fillText(lo, pad, base);
  const gx0 = pad + ctx.measureText(lo).width + 8 * dpr, gw0 = Math.min(120 * dpr, W - gx0 - ctx.measureText(hi).width - pad - 8 * dpr);
  const lg = ctx.createLinearGradient(gx0, 0, gx0 + gw0, 0);
  VIRIDIS.forEach((c, k) => lg.addColorStop(k / (VIRIDIS.length - 1), `rgb(${c.join(',')})`));
  ctx.fillStyle = lg;
  ctx.fillRect(gx0, H - 16 * dpr, gw0, 10 * dpr);
  ctx.fillStyle = '#e8ecf0';
  ctx.fillText(hi, gx0 + gw0 + 8 * dpr, base);
  if (x0 <= 0 && x1 >= 0 && y0 <= 0 && y1 >= 0) {  // the work zero
    ctx.strokeStyle = '#fff';
    ctx.beginPath(); ctx.arc(X(0), Y(0), 5 * dpr, 0, 2 * Math.PI); ctx.stroke();
  }
  // Where the start from a line picks up (a click on the drawing picks it).
  S.previewDraw = { args: [cv, W, dpr, pv, img, path, none], X, Y };
  const at = S.previewLine;
  if (at && at.job === S.previewJob) {
    ctx.strokeStyle = '#ff4fd8';
    ctx.lineWidth = 2 * dpr;
    ctx.beginPath(); ctx.arc(X(at.x), Y(at.y), 7 * dpr, 0, 2 * Math.PI); ctx.stroke();
    ctx.fillStyle = '#ff4fd8';
    ctx.fillText(`line ${at.line}`, X(at.x) + 10 * dpr, Y(at.y) - 8 * dpr);
  }
}

// The drawn cut point nearest a click (canvas pixels), with its program line.
function pickPreviewPoint(px, py) {
  const d = S.previewDraw;
  if (!d) return null;
  const path = d.args[5];
  let best = null, bestD = Infinity;
  (path.cuts || []).forEach((l, i) => {
    const lines = (path.cut_lines || [])[i] || [];
    for (let k = 0; k < l.length / 3; k++) {
      const dx = d.X(l[3 * k]) - px, dy = d.Y(l[3 * k + 1]) - py, dd = dx * dx + dy * dy;
      if (dd < bestD && lines[k]) { bestD = dd; best = { x: l[3 * k], y: l[3 * k + 1], line: lines[k] }; }
    }
  });
  return best && bestD <= (24 * d.args[2]) ** 2 ? best : null;
}

// The last drawn point at or before a typed line, for the marker.
function previewPointOfLine(line) {
  const d = S.previewDraw;
  if (!d) return null;
  const path = d.args[5];
  let best = null;
  (path.cuts || []).forEach((l, i) => {
    const lines = (path.cut_lines || [])[i] || [];
    for (let k = 0; k < lines.length; k++)
      if (lines[k] <= line && (!best || lines[k] >= best.line)) best = { x: l[3 * k], y: l[3 * k + 1], line: lines[k] };
  });
  return best;
}

// ---------------------------------------------------------------- WebSocket
let wsBackoff = 500;
let pingTimer = null;
let wsTimer = null;
function scheduleConnect(ms) {
  clearTimeout(wsTimer);
  wsTimer = setTimeout(connectWs, ms);
}
function retryConnect() {
  scheduleConnect(wsBackoff);
  wsBackoff = Math.min(wsBackoff * 2, 5000);
}
async function connectWs() {
  if (S.ws) return;  // one socket at a time
  let oneShot = '';
  try {
    const r = await api('POST', '/ws-token', {});
    oneShot = r.token;
  } catch (e) {
    if (e.status === 401) { setLink(false, false); retryConnect(); return; }  // no token: a socket would be refused too
    // Otherwise still try without it: on loopback the daemon needs no token.
    if (e.status !== 404) console.warn('ws-token', e);
  }
  if (S.ws) return;
  const proto = location.protocol === 'https:' ? 'wss' : 'ws';
  const q = `client_id=${enc(S.clientId)}` + (oneShot ? `&token=${enc(oneShot)}` : '');
  const ws = new WebSocket(`${proto}://${location.host}${API}/ws?${q}`);
  S.ws = ws;
  ws.onopen = () => {
    S.wsUp = true;
    wsBackoff = 500;
    setLink(true);
    ws.send(JSON.stringify({ type: 'subscribe', machines: ['*'] }));
    // Catch up on what happened while the socket was down.
    run('Loading', async () => { await loadMachines(); await loadJobs(); });
    clearInterval(pingTimer);
    pingTimer = setInterval(() => wsSend({ type: 'ping', id: Date.now() }), 10000);
  };
  ws.onmessage = (e) => { let m; try { m = JSON.parse(e.data); } catch { return; } onMessage(m); };
  ws.onclose = () => {
    if (S.ws !== ws) return;
    S.wsUp = false;
    S.ws = null;
    clearInterval(pingTimer);
    setLink(false);
    // The daemon cancels our jog when the socket drops; stop renewing at once.
    releaseJog('connection lost');
    retryConnect();
  };
}

function wsSend(m) {
  if (S.ws && S.ws.readyState === WebSocket.OPEN) { S.ws.send(JSON.stringify(m)); return true; }
  return false;
}

function setLink(up, banner = true) {
  const l = $('#link');
  l.textContent = up ? 'connected' : 'not connected — retrying';
  l.className = 'link ' + (up ? 'link-up' : 'link-down');
  l.dataset.up = up ? '1' : '0';
  if (up) closeBanner('link');
  else if (banner) showBanner({ key: 'link', kind: 'error', title: 'No connection to the controller',
    text: 'The page cannot reach cncstreamd; the DRO and progress are not live.',
    todo: 'Check the network or that the daemon runs; the page reconnects by itself. A running job continues on the controller.' });
}

const wsWaiters = new Map();  // id -> resolve, for acks of jog_start
let wsSeq = 0;
function wsRequest(m) {
  const id = ++wsSeq;
  return new Promise((resolve) => {
    if (!wsSend({ ...m, id })) { resolve({ type: 'error', code: 'not_connected', message: 'not connected' }); return; }
    wsWaiters.set(id, resolve);
    setTimeout(() => { if (wsWaiters.delete(id)) resolve({ type: 'error', code: 'timeout', message: 'no answer from the controller' }); }, 3000);
  });
}

function onMessage(m) {
  switch (m.type) {
    case 'hello':
      for (const n of m.machines || []) machine(n);
      renderMachinePicker();
      break;
    case 'status': {
      const rec = machine(m.machine);
      const wasAlarm = rec.status && rec.status.alarm;
      const changed = !rec.status || rec.status.state_text !== m.state_text || rec.status.link !== m.link;
      rec.status = m;
      if (m.tool_change !== undefined) rec.toolChange = m.tool_change;
      rec.summary.job_active = m.job_active;
      rec.summary.link = m.link ?? rec.summary.link;
      if (m.alarm && !wasAlarm && !rec.alarmInfo) run('Loading the alarm', () => loadMachineDetail(m.machine));
      if (!m.alarm) rec.alarmInfo = null;
      if (m.machine === S.current) { renderMachine(); renderRunButtons(); }
      if (changed) renderMachineList(); else renderMachineListSoon();  // a new state shows at once
      break;
    }
    case 'job': onJobMessage(m); break;
    case 'tool_change': {
      const rec = machine(m.machine);
      rec.toolChange = m.state || null;
      if (m.record) log(m.machine, `tool change: ${m.record.note}`, m.record.length_known ? 'info' : 'err');
      if (m.machine === S.current) renderMachine();
      break;
    }
    case 'routine': {
      const rec = machine(m.machine);
      onRoutineFrame(rec, m);
      if (m.machine === S.current) renderMachine();
      break;
    }
    case 'queue': reloadJobsSoon(); break;
    // The hub said what in the shop changed (docs/api-v1.md): the shop view draws it.
    case 'shop': applyShopFrame(m); break;
    case 'event': onEvent(m); break;
    case 'console': log(m.machine, m.dir === 'out' ? '> ' + m.text : m.text, m.dir === 'out' ? 'out' : /^error|alarm/i.test(m.text) ? 'err' : ''); break;
    case 'link': {
      const rec = machine(m.machine);
      rec.summary.link = m.link;
      if (rec.status) rec.status.link = m.link;
      log(m.machine, `link ${m.link}${m.text ? ': ' + m.text : ''}`, 'info');
      if (m.machine === S.current) renderMachine();
      renderMachineList();
      break;
    }
    case 'control':
      S.control.set(m.machine, m.holder);
      if (m.machine === S.current) renderMachine();
      if (m.holder && m.holder !== S.clientId) {
        log(m.machine, `control taken by ${m.holder}`, 'info');
        if (jog.machine === m.machine) releaseJog('control lost');
      }
      break;
    case 'ack': case 'error': {
      if (m.id === 'renew') {
        // The jog ended on the machine's side (an alarm, a limit, the lease): stop renewing.
        if (m.type === 'error' && jog.timer) { endHold(); log(jog.machine || S.current, `jog ended: ${m.message}`, 'info'); }
        break;
      }
      const w = wsWaiters.get(m.id);
      if (w) { wsWaiters.delete(m.id); w(m); } else if (m.type === 'error') log(S.current, `${m.code}: ${m.message}`, 'err');
      break;
    }
    default: break;
  }
}
let listTimer = null;
function renderMachineListSoon() { if (!listTimer) listTimer = setTimeout(() => { listTimer = null; renderMachineList(); }, 500); }
function renderRunButtons() { renderRunning([...S.jobs.values()].filter((j) => j.machine === S.current)); }

function onEvent(m) {
  const i = m.info || {};
  const where = m.line ? ` (file line ${m.line})` : '';
  const named = i.name && !m.text.includes(i.name) ? ' — ' + i.name : '';
  log(m.machine, `${m.kind}${m.code ? ' ' + m.code : ''}${where}: ${m.text}${named}`, m.kind === 'error' || m.kind === 'alarm' ? 'err' : 'info');
  if (m.kind === 'alarm') {
    const rec = machine(m.machine);
    rec.alarmInfo = { code: m.code, ...i };
    if (rec.status) rec.status.alarm = true;
    if (m.machine === S.current) renderMachine();
  } else if (m.kind === 'error') {
    showBanner({ key: `error-${m.machine}-${m.code}-${m.line}`, kind: 'error', dismiss: true,
      title: `${m.machine}: error ${m.code || ''}${where}${i.name ? ' — ' + i.name : ''}`,
      text: i.text || m.text, todo: i.action || 'Read the console for the line the controller rejected.' });
  }
}

// ---------------------------------------------------------------- console
function log(machineName, text, cls = '') {
  const c = $('#console');
  const atBottom = c.scrollTop + c.clientHeight >= c.scrollHeight - 4;
  const t = new Date().toLocaleTimeString([], { hour12: false });
  c.append(el('span', { class: cls }, `${t} ${machineName && S.machines.size > 1 ? '[' + machineName + '] ' : ''}${text}\n`));
  while (c.childNodes.length > 500) c.firstChild.remove();
  if (atBottom) c.scrollTop = c.scrollHeight;
}

function setupConsole() {
  $('#console-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const line = $('#console-input').value.trim();
    if (!line) return;
    run('Console', async () => {
      await controlled(S.current, () => api('POST', `/machines/${enc(S.current)}/console`, { line }));
      $('#console-input').value = '';
    });
  });
}

// ---------------------------------------------------------------- jog
// A step is one REST call. A continuous jog lives while the button is held:
// jog_start, then jog_renew every JOG_RENEW_MS; any way the hold can end
// (finger lifted, pointer cancelled, window blurred, tab hidden, socket lost)
// releases at once, and the daemon's lease stops the machine if we go silent.
const jog = { timer: null, machine: null, button: null, pending: null };

function jogStep() {
  const v = document.querySelector('input[name=jogstep]:checked').value;
  return v === 'hold' ? null : Number(v);
}
function jogFeed() { const f = Number($('#jog-feed').value); return f > 0 ? f : 1000; }
function dirOf(b) { const d = [0, 0, 0]; d['XYZ'.indexOf(b.dataset.axis)] = Number(b.dataset.dir); return d; }

async function startHold(b) {
  if (jog.timer || jog.pending) return;
  const m = S.current;
  jog.machine = m;
  jog.button = b;
  b.classList.add('held');
  const req = { type: 'jog_start', machine: m, dir: dirOf(b), feed: jogFeed() };
  jog.pending = wsRequest(req);
  let r = await jog.pending;
  if (r.type === 'error' && (r.code === 'control_required' || r.code === 'control_held') && jog.button === b) {
    // Take control (only if nobody holds it), then start if still held.
    if (await takeControl(m, false).catch(() => false) && jog.button === b) r = await (jog.pending = wsRequest(req));
  }
  jog.pending = null;
  if (jog.button !== b) { wsSend({ type: 'jog_release', machine: m }); return; }  // released while starting
  if (r.type === 'error') {
    endHold();
    if (r.code !== 'control_held') reportError('Jog', new ApiError(409, r.code, r.message));
    return;
  }
  jog.timer = setInterval(() => {
    if (!wsSend({ type: 'jog_renew', machine: m, id: 'renew' })) releaseJog('connection lost');
  }, JOG_RENEW_MS);
}

function endHold() {
  clearInterval(jog.timer);
  jog.timer = null;
  if (jog.button) jog.button.classList.remove('held');
  jog.button = null;
}

function releaseJog(why) {
  if (!jog.button && !jog.timer) return;
  const m = jog.machine;
  endHold();
  if (!wsSend({ type: 'jog_release', machine: m })) {
    // No socket: the daemon's dead man stops it; ask over HTTP too, in case.
    api('POST', `/machines/${enc(m)}/jog/cancel`, {}).catch(() => {});
  }
  if (why && why !== 'released') log(m, `jog released: ${why}`, 'info');
}

function setupJog() {
  const pad = $('#jogpad');
  for (const b of pad.querySelectorAll('.jog:not(.jstop)')) {
    b.addEventListener('pointerdown', (e) => {
      if (jogStep() !== null || e.button !== 0) return;
      e.preventDefault();
      b.setPointerCapture(e.pointerId);
      startHold(b);
    });
    const up = () => { if (jog.button === b) releaseJog('released'); };
    b.addEventListener('pointerup', up);
    b.addEventListener('pointercancel', up);
    b.addEventListener('lostpointercapture', up);
    // Keyboard hold: Space/Enter down moves, up stops.
    b.addEventListener('keydown', (e) => {
      if (jogStep() !== null || (e.key !== ' ' && e.key !== 'Enter') || e.repeat) return;
      e.preventDefault();
      startHold(b);
    });
    b.addEventListener('keyup', (e) => { if (e.key === ' ' || e.key === 'Enter') up(); });
    b.addEventListener('click', () => {
      const d = jogStep();
      if (d === null) return;
      const m = S.current;
      run('Jog', () => controlled(m, () => api('POST', `/machines/${enc(m)}/jog`, { dir: dirOf(b), distance: d, feed: jogFeed() })));
    });
    b.addEventListener('contextmenu', (e) => e.preventDefault());  // a long press must not open a menu
  }
  // The big red button stops whatever moves: a jog gently (jog cancel), a job
  // with its controlled stop, anything else (go to zero, a console move) with
  // the machine's controlled stop. None of these needs control.
  $('#jog-stop').addEventListener('click', () => {
    const m = S.current;
    const wasHeld = !!jog.button;
    releaseJog('stop pressed');
    const st = (S.machines.get(m) && S.machines.get(m).status) || {};
    const active = [...S.jobs.values()].find((j) => j.machine === m && (j.state === 'running' || j.state === 'held'));
    if (active) run('Stop', () => api('POST', `/jobs/${active.id}/stop`, {}));
    else if (wasHeld || st.jogging || st.state === 'Jog') run('Stop jog', () => api('POST', `/machines/${enc(m)}/jog/cancel`, {}));
    else run('Stop', () => api('POST', `/machines/${enc(m)}/stop`, {}));
  });
  window.addEventListener('blur', () => releaseJog('window lost focus'));
  document.addEventListener('visibilitychange', () => { if (document.hidden) releaseJog('page hidden'); });
  window.addEventListener('pagehide', () => releaseJog('page closed'));
  document.querySelectorAll('input[name=jogstep]').forEach((r) => r.addEventListener('change', () => {
    $('#jog-hint').textContent = jogStep() === null
      ? 'Hold to move: the machine moves while you hold the button and stops when you let go.'
      : `Step: each press moves ${jogStep()} mm.`;
  }));
}

// ---------------------------------------------------------------- buttons
function setupButtons() {
  const m = () => S.current;
  const action = (name, body = {}) => () => run(name, () => controlled(m(), () => api('POST', `/machines/${enc(m())}/actions/${name}`, body)));
  $('#zero-xy').addEventListener('click', action('zero_axes', { axes: 'XY' }));
  $('#zero-z').addEventListener('click', action('zero_axes', { axes: 'Z' }));
  $('#go-zero').addEventListener('click', action('go_to_work_zero'));
  $('#safe-z').addEventListener('click', action('safe_z'));
  $('#unlock').addEventListener('click', action('unlock'));
  $('#home').addEventListener('click', action('home'));
  $('#reset').addEventListener('click', action('reset'));
  const activeJob = () => $('#panel-job').dataset.job;
  // Hold and stop need no control: safety beats ownership.
  $('#btn-hold').addEventListener('click', () => run('Hold', () => activeJob() ? api('POST', `/jobs/${activeJob()}/hold`, {}) : api('POST', `/machines/${enc(m())}/hold`, {})));
  $('#btn-resume').addEventListener('click', () => run('Resume', () => controlled(m(), () => api('POST', `/jobs/${activeJob()}/resume`, {}))));
  $('#btn-stop').addEventListener('click', () => run('Stop', () => activeJob() ? api('POST', `/jobs/${activeJob()}/stop`, {}) : api('POST', `/machines/${enc(m())}/stop`, {})));
  const ovCmd = { feed: ['feed_ov_minus_10', 'feed_ov_plus_10', 'feed_ov_reset'], spindle: ['spindle_ov_minus_10', 'spindle_ov_plus_10', 'spindle_ov_reset'] };
  const rapid = { 25: 'rapid_ov_low', 50: 'rapid_ov_medium', 100: 'rapid_ov_reset' };
  document.querySelectorAll('[data-ov]').forEach((b) => b.addEventListener('click', () => {
    const kind = b.dataset.ov;
    const command = kind === 'rapid' ? rapid[b.dataset.value] : ovCmd[kind][b.dataset.delta === '-10' ? 0 : b.dataset.delta === '10' ? 1 : 2];
    run('Override', () => controlled(m(), () => api('POST', `/machines/${enc(m())}/realtime`, { command })));
  }));
  $('#machine-select').addEventListener('change', (e) => selectMachine(e.target.value));
}

function renderAll() { renderMachinePicker(); renderMachine(); renderJobs(); }

// ---------------------------------------------------------------- start
setupUpload();
setupJog();
setupButtons();
setupToolChange();
setupFromLine();
setupConsole();
renderMachine();
renderHistory();
connectWs();
run('Loading the shop', setupShop);
run('Loading the tool library', setupTools);
setupRoutines();
// The shop view (shop.js) and the tool library (tools.js) use the page's helpers.
export { $, el, api, run, duration, S, controlled, enc };
// For the browser tests and for debugging from the console.
window.cncstream = { state: S, showPreview };  // the browser test drives and reads these
