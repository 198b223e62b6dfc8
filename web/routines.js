// The set-up routines outside a job (docs/web.md, "Set-up"): corner probing
// with a touch plate, tracing the previewed job's outline, and the tool-length
// routines (measure the reference, change a tool, check the length). Each runs
// on the machine session (POST /machines/{m}/routines/{name}); its prompts are
// answered here (POST /machines/{m}/routine/confirm|decline) and its end comes
// as a `routine` frame with what it found or why it failed. A module of its
// own beside app.js (as tools.js and shop.js).
import { $, api, run, S, controlled, enc } from './app.js';

function start(label, name, body) {
  const m = S.current;
  if (!m) return;
  run(label, async () => {
    const rec = S.machines.get(m);
    if (rec) rec.routineResult = null;  // the last routine's result goes with its start
    $('#rt-result').textContent = '';
    await controlled(m, () => api('POST', `/machines/${enc(m)}/routines/${name}`, body));
  });
}

function answer(yes) {
  const m = S.current;
  run(yes ? 'Confirm' : 'Decline', () => controlled(m, () => api('POST', `/machines/${enc(m)}/routine/${yes ? 'confirm' : 'decline'}`)));
}

function numberOf(id) {
  const v = $(id).value.trim();
  return v === '' ? undefined : Number(v);
}

export function setupRoutines() {
  $('#rt-corner-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const body = {
      axes: $('#rt-corner-axes').value,
      plate: { thickness: numberOf('#rt-plate-thickness'), lip: numberOf('#rt-plate-lip'), size: numberOf('#rt-plate-size') },
    };
    const tool = $('#rt-corner-tool').value.trim();
    if (tool) body.tool = tool;
    start('Probe the corner', 'corner_probe', body);
  });
  $('#rt-outline-form').addEventListener('submit', (e) => {
    e.preventDefault();
    if (!S.previewJob) return;
    const body = { job: S.previewJob, shape: $('#rt-outline-shape').value, feed: numberOf('#rt-outline-feed') };
    const z = numberOf('#rt-outline-safe-z');
    if (z !== undefined) body.safe_z = z;
    start('Trace the outline', 'outline', body);
  });
  const inSpindle = (body) => {
    const t = numberOf('#rt-in-spindle');
    if (t !== undefined) body.in_spindle = t;
    return body;
  };
  $('#rt-measure').addEventListener('click', () => start('Measure the reference', 'tool_measure', inSpindle({})));
  $('#rt-change').addEventListener('click', () => start('Change the tool', 'tool_change', inSpindle({ tool: numberOf('#rt-change-to') })));
  $('#rt-check').addEventListener('click', () => start('Check the length', 'tool_check', inSpindle({})));
  $('#rt-confirm').addEventListener('click', () => answer(true));
  $('#rt-decline').addEventListener('click', () => answer(false));
}

// A `routine` frame: the state now, and at the end whether it succeeded.
export function onRoutineFrame(rec, m) {
  rec.routine = m.state || null;
  rec.toolReference = m.tool_reference ?? rec.toolReference;
  if (m.succeeded !== null && m.succeeded !== undefined) rec.routineResult = { ok: m.succeeded, text: m.text };
}

function referenceText(ref) {
  if (!ref) return 'No tool-length reference kept (measured again at the next change).';
  return `Reference: T${ref.tool} (${ref.method}), trigger at machine Z ${ref.trigger_z.toFixed(3)}` +
    (ref.measured_tool && ref.measured_tool !== ref.tool ? `; T${ref.measured_tool} measured since` : '');
}

// env: {ready, alarm, jobActive}: what may be started now.
export function renderRoutines(rec, env) {
  const r = rec ? rec.routine : null;
  $('#rt-active').hidden = !r;
  if (r) {
    $('#rt-name').textContent = r.name;
    $('#rt-prompt').textContent = r.prompt ? r.prompt.text : '';
    $('#rt-wait').hidden = !!r.prompt;
    $('#rt-confirm').disabled = !r.prompt;
    $('#rt-decline').disabled = !r.prompt;
  }
  const res = rec ? rec.routineResult : null;
  const out = $('#rt-result');
  out.textContent = res ? (res.ok ? 'Done: ' : 'Failed: ') + res.text : '';
  out.className = 'rt-result' + (res ? (res.ok ? ' ok' : ' failed') : '');
  $('#rt-reference').textContent = rec ? referenceText(rec.toolReference) : '';
  const idle = !!(rec && env.ready && !env.alarm && !env.jobActive && !r);
  for (const id of ['#rt-corner-go', '#rt-measure', '#rt-change', '#rt-check']) $(id).disabled = !idle;
  $('#rt-outline-go').disabled = !idle || !S.previewJob;
  $('#rt-outline-job').textContent = S.previewJob ? `Job #${S.previewJob}, shown in the preview.` : 'Open a job in the preview first.';
}
