// The tool library of the web page (docs/web.md, "Tools"): the daemon's
// library (GET/POST/PUT/DELETE /api/v1/tools, import) listed, edited and
// offered where a cutter is typed (the tool-path form). A module of its own
// beside app.js, which imports it and whose helpers it imports back (as shop.js).
import { $, el, api } from './app.js';

const TOOLS = { list: [], editing: null };  // editing: the number of the tool in the form (null: a new one)

export async function setupTools() {
  $('#tools-form').addEventListener('submit', (e) => { e.preventDefault(); saveTool(); });
  $('#tools-new').addEventListener('click', () => editTool(null));
  $('#tools-cancel').addEventListener('click', () => { $('#tools-form').hidden = true; });
  $('#tools-import-file').addEventListener('change', (e) => {
    const f = e.target.files[0];
    e.target.value = '';  // the same file may be imported again
    if (f) importFile(f);
  });
  // The tool-path form: a library tool replaces the typed cutter.
  $('#tp-library').addEventListener('change', libraryPicked);
  await loadTools();
}

export async function loadTools() {
  const r = await api('GET', '/tools');
  TOOLS.list = (r && r.tools) || [];
  renderTools();
  renderPickers();
}

// "12.5 mm", or the words for a length the library does not know (0).
const mm = (v) => (v ? `${+v} mm` : 'not known');

function renderTools() {
  const rows = TOOLS.list.map((t) => el('tr', { dataset: { tool: t.number } },
    el('td', { class: 'mono' }, `T${t.number}`),
    el('td', { class: 'tool-name' }, t.name),
    el('td', {}, el('span', { class: 'mono' }, t.shape), el('br'), el('span', { class: 'muted' }, t.description)),
    el('td', { class: 'mono' }, String(t.flutes)),
    el('td', { class: 'mono' }, mm(t.stick_out)),
    el('td', { class: 'tool-acts' },
      el('button', { class: 'btn small', type: 'button', dataset: { act: 'edit' }, onclick: () => editTool(t) }, 'Edit'),
      el('button', { class: 'btn small btn-danger', type: 'button', dataset: { act: 'delete' }, onclick: () => deleteTool(t) }, 'Delete'))));
  $('#tools-table tbody').replaceChildren(...(rows.length ? rows
    : [el('tr', {}, el('td', { colspan: 6, class: 'muted' }, 'The library is empty. Add a tool or import a file.'))]));
}

// The tool-path form's pickers: the finishing cutter's select and the
// roughing and rest fields' suggestions. A tool is named by its number ("T3"),
// which the API's `tool`, `rough` and `rest` accept (docs/api-v1.md, "Jobs").
function renderPickers() {
  const pick = $('#tp-library');
  const was = pick.value;
  pick.replaceChildren(el('option', { value: '' }, 'None: the cutter below'),
    ...TOOLS.list.map((t) => el('option', { value: `T${t.number}` }, `T${t.number} ${t.name} (${t.shape})`)));
  pick.value = TOOLS.list.some((t) => `T${t.number}` === was) ? was : '';
  libraryPicked();
  $('#tool-library-list').replaceChildren(...TOOLS.list.map((t) =>
    el('option', { value: `T${t.number}`, label: `${t.name} (${t.shape})` })));
}

function libraryPicked() {
  const fromLibrary = $('#tp-library').value !== '';
  for (const id of ['#tp-cutter', '#tp-diameter', '#tp-radius']) $(id).disabled = fromLibrary;
}

// The finishing cutter the form asks for: the library tool picked, else null (the typed one).
export function pickedLibraryTool() {
  return $('#tp-library').value || null;
}

function editTool(t) {
  TOOLS.editing = t ? t.number : null;
  const f = $('#tools-form');
  f.hidden = false;
  $('#tools-form-title').textContent = t ? `Edit T${t.number}` : 'New tool';
  $('#tool-number').value = t ? t.number : '';
  $('#tool-number').disabled = !!t;  // a tool keeps its number: delete and add to renumber
  $('#tool-name').value = t ? t.name : '';
  $('#tool-shape').value = t ? t.shape : '';
  $('#tool-flutes').value = t ? t.flutes : 2;
  $('#tool-flute-length').value = t && t.flute_length ? t.flute_length : '';
  $('#tool-stick-out').value = t && t.stick_out ? t.stick_out : '';
  $('#tool-notes').value = t ? t.notes : '';
  formStatus('', '');
  $('#tool-name').focus();
}

function formStatus(text, kind) {
  const s = $('#tools-form-status');
  s.textContent = text;
  s.className = kind === 'error' ? 'tools-error' : 'muted';
}

// A number field: empty is 0 ("not known" to the library); anything else goes
// as typed, so the daemon names what is wrong with it.
function lengthOf(id) {
  const v = $(id).value.trim();
  return v === '' ? 0 : Number(v);
}

async function saveTool() {
  // Fields the form does not show (cutting data, lengths) are kept as they were.
  const old = TOOLS.editing != null ? TOOLS.list.find((t) => t.number === TOOLS.editing) : null;
  const body = { ...(old || {}) };
  delete body.description;  // read-only
  body.name = $('#tool-name').value.trim();
  body.shape = $('#tool-shape').value.trim();
  body.flutes = Number($('#tool-flutes').value);
  body.flute_length = lengthOf('#tool-flute-length');
  body.stick_out = lengthOf('#tool-stick-out');
  body.notes = $('#tool-notes').value;
  try {
    let saved;
    if (old) {
      saved = await api('PUT', `/tools/${old.number}`, body);
    } else {
      const n = $('#tool-number').value.trim();
      if (n !== '') body.number = Number(n);
      saved = await api('POST', '/tools', body);
    }
    $('#tools-form').hidden = true;
    TOOLS.editing = null;
    await loadTools();
    toolsStatus(`T${saved.number} ${saved.name} saved.`);
  } catch (e) {
    formStatus(e.message, 'error');  // the daemon's own words: what is wrong with which field
  }
}

async function deleteTool(t) {
  if (!window.confirm(`Delete T${t.number} ${t.name} from the library?`)) return;
  try {
    await api('DELETE', `/tools/${t.number}`);
    if (TOOLS.editing === t.number) $('#tools-form').hidden = true;
    await loadTools();
    toolsStatus(`T${t.number} ${t.name} deleted.`);
  } catch (e) {
    toolsStatus(e.message, 'error');
  }
}

function toolsStatus(text, kind) {
  const s = $('#tools-status');
  s.textContent = text;
  s.className = kind === 'error' ? 'tools-error' : 'muted';
}

async function importFile(file) {
  const out = $('#tools-import-result');
  out.hidden = true;
  toolsStatus(`Importing ${file.name}…`);
  try {
    const r = await api('POST', '/tools/import', {
      name: file.name, content: await file.text(),
      replace: $('#tools-import-replace').checked, inch: $('#tools-import-inch').checked,
    });
    const list = (title, lines, cls) => (lines.length
      ? [el('h4', {}, `${title} (${lines.length})`), el('ul', { class: cls }, ...lines.map((x) => el('li', {}, x)))] : []);
    out.replaceChildren(el('p', {}, `${file.name}: ${r.format}.`),
      ...list('Understood', r.understood, 'tools-understood'),
      ...list('Skipped', r.skipped, 'tools-skipped'),
      ...list('Placed in the library', r.placed, 'tools-placed'));
    out.hidden = false;
    toolsStatus('');
    await loadTools();
  } catch (e) {
    toolsStatus(`${file.name} was not imported: ${e.message}`, 'error');
  }
}

// What the tool-change panel says of the incoming tool, from the daemon's
// library (the tool-change state's `library_tool`, docs/api-v1.md): its name
// and the stick-out the operator should see from the collet. Nothing when the
// library has no such tool (a guess would be worse than no line). A program the
// daemon generated numbers its tools by operation, so the library's number may differ.
export function toolChangeLibraryText(tc) {
  const t = tc && tc.library_tool;
  if (!t) return '';
  return `${t.number === tc.tool ? `T${t.number}` : `T${tc.tool} is the library's T${t.number}`}: ${t.name}, ` +
    `${t.description || t.shape}; expected stick-out ` +
    (t.stick_out ? `${+t.stick_out} mm from the collet.` : 'not known (the library has none).');
}
