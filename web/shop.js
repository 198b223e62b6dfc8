// The shop view of the web page (docs/shop.md, "The shop view"): a module of
// its own beside app.js, which imports it and whose helpers it imports back
// (an ES module cycle: nothing here runs before app.js has been evaluated).
import { $, el, api, run, duration } from './app.js';

const enc = encodeURIComponent;

// ---------------------------------------------------------------- shop
// The shop view (docs/shop.md): the hub's machines, queue and history, read
// through this daemon (GET /shop/…). The daemon pushes what changed as a
// `shop` WebSocket frame (the machine rows and jobs the hub's NOTIFY named,
// docs/api-v1.md), which applyShopFrame draws into what is shown; a frame
// marked `resync` or `more` (or a change it cannot place) reads the whole
// view. A slow poll (`poll_ms`, 5 s) stays as the fallback, not while the tab is hidden.
const SHOP = { member: false, pollMs: 5000, timer: null, eventsJob: null, machinesSig: null, jobsSig: null, eventsSig: null,
  machines: null, jobs: null };
const when = (t) => (t ? new Date(t).toLocaleString([], { month: 'short', day: 'numeric', hour: '2-digit', minute: '2-digit', second: '2-digit' }) : '—');
// MTConnect's execution as the page's state colours.
const EXECUTION_CLASS = { READY: 'idle', ACTIVE: 'run', FEED_HOLD: 'hold', INTERRUPTED: 'door', STOPPED: 'alarm', PROGRAM_COMPLETED: 'idle' };

export async function setupShop() {
  const r = await api('GET', '/shop');
  SHOP.member = !!(r && r.member);
  $('#panel-shop').hidden = !SHOP.member;
  $('#shop-nav').hidden = !SHOP.member;
  if (!SHOP.member) return;
  SHOP.pollMs = r.poll_ms || 5000;
  $('#shop-name').textContent = `“${r.name}” · this PC: ${r.pc}`;
  $('#shop-status-filter').addEventListener('change', () => pollShopSoon(0));
  $('#shop-machine-filter').addEventListener('change', () => pollShopSoon(0));
  $('#shop-submit').addEventListener('submit', (e) => { e.preventDefault(); run('Submit to the shop', submitToShop); });
  $('#shop-file').addEventListener('change', showToolField);
  showToolField();
  $('#shop-events-close').addEventListener('click', () => { SHOP.eventsJob = null; SHOP.eventsSig = null; $('#shop-events').hidden = true; });
  document.addEventListener('visibilitychange', () => { if (!document.hidden) pollShopSoon(0); });
  pollShopSoon(0);
}

export function pollShopSoon(ms) {
  clearTimeout(SHOP.timer);
  SHOP.timer = setTimeout(pollShop, ms);
}

export async function pollShop() {
  if (document.hidden) return;  // visibilitychange starts it again
  try {
    const q = new URLSearchParams({ limit: '100' });
    if ($('#shop-status-filter').value) q.set('status', $('#shop-status-filter').value);
    if ($('#shop-machine-filter').value) q.set('machine', $('#shop-machine-filter').value);
    const [m, j] = await Promise.all([api('GET', '/shop/machines'), api('GET', '/shop/jobs?' + q)]);
    renderShopMachines(m.machines);
    renderShopJobs(j);
    if (SHOP.eventsJob) renderShopEvents(await api('GET', `/shop/jobs/${SHOP.eventsJob}/events`));
    $('#shop-status').textContent = `Read from the hub at ${new Date().toLocaleTimeString()}`;
    $('#shop-status').className = 'shop-status muted';
    $('#panel-shop').classList.remove('shop-stale');
  } catch (e) {
    // The hub being down is the view's news, not an error of the page's.
    $('#shop-status').textContent = e.code === 'hub_unavailable' ? `The hub cannot be read: ${e.message}` : `The shop view failed: ${e.message}`;
    $('#shop-status').className = 'shop-status shop-down';
    $('#panel-shop').classList.add('shop-stale');  // what is shown is the last that could be read
  }
  pollShopSoon(SHOP.pollMs);
}

// A `shop` frame: its rows drawn into what is shown, without reading the
// view again; a whole read when the frame asks for one or a job cannot be
// placed under the filters (its old status unknown, so the counts would drift).
export function applyShopFrame(f) {
  if (!SHOP.member) return;
  if (f.resync || f.more || !SHOP.machines || !SHOP.jobs) { pollShopSoon(0); return; }
  if ((f.machines || []).length) {
    const list = SHOP.machines.slice();
    for (const m of f.machines) {
      const i = list.findIndex((x) => x.name === m.name);
      if (i >= 0) list[i] = m; else list.push(m);
    }
    list.sort((a, b) => (a.pc === b.pc ? a.name.localeCompare(b.name) : a.pc.localeCompare(b.pc)));
    renderShopMachines(list);
  }
  if ((f.jobs || []).length) {
    const statuses = $('#shop-status-filter').value ? $('#shop-status-filter').value.split(',') : null;
    const machineFilter = $('#shop-machine-filter').value;
    const shown = (j) => (!statuses || statuses.includes(j.status)) &&
      (!machineFilter || j.machine === machineFilter || j.requested_machine === machineFilter);
    const r = { ...SHOP.jobs, jobs: SHOP.jobs.jobs.slice(), counts: { ...(SHOP.jobs.counts || {}) } };
    const newest = r.jobs.length ? r.jobs[0].id : 0;
    for (const j of f.jobs) {
      const i = r.jobs.findIndex((x) => x.id === j.id);
      if (i >= 0) {
        const old = r.jobs[i];
        r.counts[old.status] = (r.counts[old.status] || 1) - 1;
        if (!r.counts[old.status]) delete r.counts[old.status];
        if (shown(j)) { r.jobs[i] = j; r.counts[j.status] = (r.counts[j.status] || 0) + 1; } else r.jobs.splice(i, 1);
      } else if (j.id > newest) {
        if (shown(j)) { r.jobs.unshift(j); r.counts[j.status] = (r.counts[j.status] || 0) + 1; }
      } else { pollShopSoon(0); return; }  // an older job not on the page: its old status is not known here
    }
    r.jobs.sort((a, b) => b.id - a.id);
    renderShopJobs(r);
    if (SHOP.eventsJob && f.jobs.some((j) => j.id === SHOP.eventsJob))
      api('GET', `/shop/jobs/${SHOP.eventsJob}/events`).then(renderShopEvents, () => {});
  }
  if (f.now) $('#shop-status').textContent = `Pushed by the hub at ${new Date(f.now).toLocaleTimeString()}`;
}

function renderShopMachines(list) {
  SHOP.machines = list;
  const sig = JSON.stringify(list.map((m) => [m.name, m.pc, m.state, m.job, Math.round(m.heartbeat_age_s)]));
  if (sig === SHOP.machinesSig) return;
  SHOP.machinesSig = sig;
  $('#shop-machines tbody').replaceChildren(...(list.length ? list.map((m) => {
    const st = m.state || {};
    const avail = st.availability === 'AVAILABLE';
    const label = avail ? (st.alarm ? `${st.execution}: ${st.alarm}` : `${st.execution || '—'} · ${(st.controller_mode || '').toLowerCase()}`) : 'UNAVAILABLE';
    const age = m.heartbeat_age_s;
    return el('tr', { dataset: { machine: m.name } },
      el('td', { class: 'c-job' }, m.name),
      el('td', {}, m.pc),
      el('td', {}, el('span', { class: 'state shop-state state-' + (avail ? (EXECUTION_CLASS[st.execution] || 'unknown') : 'offline') }, label)),
      el('td', { class: 'mono' }, st.program || '—'),
      el('td', { class: 'mono' }, st.line ? st.line.toLocaleString() : '—'),
      el('td', {}, m.job ? `#${m.job.id} ${m.job.file_name} (${m.job.status.replace('_', ' ')})` : '—'),
      el('td', { class: age > 15 ? 'oc-error' : 'muted' }, age == null ? 'never' : `${duration(age)} ago`));
  }) : [el('tr', {}, el('td', { colspan: 7, class: 'muted' }, 'No machine has joined the shop yet.'))]));
  // The machine filter and the submit form offer every machine of the shop.
  const names = list.map((m) => m.name);
  for (const [sel, any] of [[$('#shop-machine-filter'), 'Any'], [$('#shop-submit-machine'), 'Any that can']]) {
    const have = [...sel.options].slice(1).map((o) => o.value);
    if (JSON.stringify(names) === JSON.stringify(have)) continue;
    const cur = sel.value;
    sel.replaceChildren(el('option', { value: '' }, any), ...names.map((n) => el('option', { value: n, selected: n === cur }, n)));
  }
}

// ---------------------------------------------------------------- submit, cancel, requeue
// The operator's acts, through this daemon (POST /shop/jobs…), which calls
// the hub's functions; the hub refuses what its rules forbid (docs/shop.md).
const isStl = (f) => !!f && /\.stl$/i.test(f.name);
function showToolField() { $('#shop-tool-label').hidden = !isStl($('#shop-file').files[0]); }

async function submitToShop() {
  const file = $('#shop-file').files[0];
  if (!file) throw new Error('Choose a part (STL) or a program (G-code) to submit.');
  const body = {};
  const needs = $('#shop-needs').value.split(/[\s,]+/).filter(Boolean);
  if (needs.length) body.needs = needs;
  if ($('#shop-submit-machine').value) body.machine = $('#shop-submit-machine').value;
  const status = $('#shop-submit-status');
  status.textContent = `Uploading ${file.name}…`;
  try {
    const stored = await api('POST', `/files?name=${enc(file.name)}`, file);
    body.file = stored.id;
    if (stored.kind === 'stl') {
      const tool = $('#shop-tool').value.trim();
      if (!tool) throw new Error('An STL needs its cutter (e.g. ball:3.175): the machine that claims it makes the tool path.');
      body.params = { tool };
    }
    status.textContent = `Submitting ${file.name}…`;
    const job = await api('POST', '/shop/jobs', body);
    status.textContent = `${job.file_name} is job #${job.id} of the shop, pending.`;
    $('#shop-submit').reset();
    showToolField();
  } catch (e) {
    status.textContent = '';
    throw e;
  }
  pollShopSoon(0);
}

// The buttons a job's row offers for its status.
function jobActions(j) {
  const act = (label, what, fn, title) => el('button', {
    class: 'btn small', type: 'button', title, dataset: { act: what },
    onclick: (e) => { e.stopPropagation(); run(label, async () => { await fn(); SHOP.jobsSig = null; pollShopSoon(0); }); },
  }, label);
  if (['pending', 'assigned', 'awaiting_operator'].includes(j.status))
    return [act('Cancel', 'cancel', () => api('POST', `/shop/jobs/${j.id}/cancel`, {}), 'Take it out of the queue (only a job that has not started)')];
  if (['interrupted', 'failed', 'cancelled'].includes(j.status)) {
    const again = (on) => () => api('POST', `/shop/jobs/${j.id}/requeue`, { on });
    return [
      j.machine ? act(`Resume on ${j.machine}`, 'requeue-same', again('same_machine'), j.last_line
        ? `Back to ${j.machine} as a resume after line ${j.last_line} (its last reported line; the daemon backs off what the controller may not have cut): it waits for its operator there`
        : `Back to ${j.machine}, from the top (no line was reported): it waits for its operator there`) : null,
      act('Requeue anywhere', 'requeue-any', again('any_machine'), 'Back into the queue for any machine that can do it: a restart from the beginning'),
    ];
  }
  return [];
}

function renderShopJobs(r) {
  SHOP.jobs = r;
  const sig = JSON.stringify([r.jobs.map((j) => [j.id, j.status, j.machine, j.last_line, j.message, j.ended_at]), r.counts]);
  if (sig === SHOP.jobsSig) return;
  SHOP.jobsSig = sig;
  $('#shop-counts').textContent = Object.entries(r.counts || {}).map(([k, n]) => `${n} ${k.replace('_', ' ')}`).join(' · ');
  $('#shop-jobs tbody').replaceChildren(...(r.jobs.length ? r.jobs.map((j) => el('tr', {
    class: 'shop-job', tabindex: 0, dataset: { job: j.id, status: j.status }, 'aria-selected': String(SHOP.eventsJob === j.id),
    title: 'Show this job\'s events', onclick: () => showShopEvents(j.id),
    onkeydown: (e) => { if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); showShopEvents(j.id); } },
  },
  el('td', { class: 'mono' }, `#${j.id}`),
  el('td', { class: 'c-job' }, j.file_name),
  el('td', { class: 'oc-' + (j.status === 'failed' || j.status === 'interrupted' ? 'error' : j.status) }, j.status.replace('_', ' ')),
  el('td', {}, j.machine || (j.requested_machine ? `(${j.requested_machine})` : j.needs.length ? `needs ${j.needs.join(', ')}` : 'any')),
  el('td', { class: 'mono' }, j.last_line ? j.last_line.toLocaleString() : '—'),
  el('td', { class: 'c-when' }, when(j.created_at)),
  el('td', { class: 'c-when' }, when(j.ended_at)),
  el('td', { class: 'muted' }, j.message || ''),
  el('td', { class: 'c-act' }, jobActions(j)))) : [el('tr', {}, el('td', { colspan: 9, class: 'muted' }, 'No shop job matches.'))]));
}

async function showShopEvents(id) {
  SHOP.eventsJob = id;
  SHOP.eventsSig = null;
  document.querySelectorAll('#shop-jobs tr.shop-job').forEach((tr) => tr.setAttribute('aria-selected', String(Number(tr.dataset.job) === id)));
  await run('Loading the job\'s events', async () => {
    renderShopEvents(await api('GET', `/shop/jobs/${id}/events`));
    $('#shop-events').hidden = false;
    $('#shop-events').scrollIntoView({ block: 'nearest' });
  });
}

function eventText(e) {
  const b = e.body || {};
  if (e.kind === 'job') return [b.state, b.last_line ? `line ${b.last_line}` : '', b.message].filter(Boolean).join(' · ');
  if (e.kind === 'progress') return `line ${b.line}`;
  if (e.kind === 'state') return [b.availability, b.execution, b.alarm].filter(Boolean).join(' · ');
  return JSON.stringify(b);
}

function renderShopEvents(r) {
  const sig = JSON.stringify([r.job.id, r.job.status, r.events.length]);
  if (sig === SHOP.eventsSig) return;
  SHOP.eventsSig = sig;
  $('#shop-events-job').textContent = `#${r.job.id} ${r.job.file_name} (${r.job.status.replace('_', ' ')})`;
  $('#shop-events-table tbody').replaceChildren(...(r.events.length ? r.events.map((e) => el('tr', {},
    el('td', {}, e.machine), el('td', { class: 'mono' }, String(e.seq)), el('td', { class: 'c-when' }, when(e.at)),
    el('td', {}, e.kind), el('td', {}, eventText(e)))) : [el('tr', {}, el('td', { colspan: 5, class: 'muted' }, 'No event reported yet.'))]));
}
