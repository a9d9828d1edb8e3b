// curvflow report viewer: builds the page from the data that
// `curvflow report` embeds (<script type="application/json"
// id="curvflow-data">): figures, the 3D view of input and result coloured by
// per-face Q / log area distortion, the energy and residual curves of the
// step log, the run's parameters and timings. Works offline: everything is
// in the one HTML file.
//
// For tests, <html> gets data-curvflow-ready="1" when the page is built,
// data-curvflow-errors (number of errors seen, see the inline script in
// cli/cmd_report.c) and data-curvflow-canvas (the canvas rectangle in CSS
// pixels: x,y,width,height).
import css from './style.css';
import { lineChart, formatNumber } from './charts.js';
import { blueWhiteRed, cssGradient, robustSymmetricRange } from './colormap.js';
import { loadReportData } from './data.js';
import { createViewer, webglAvailable } from './view3d.js';

const errors = window.__curvflowErrors || [];
const root = document.documentElement;

function h(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}

function fmt(v, digits = 4) {
  if (v === null || v === undefined || !Number.isFinite(v)) return '–';
  return v.toFixed(digits);
}

function table(rows, head) {
  const t = h('table', { class: 'cf-table' });
  if (head) t.append(h('thead', {}, h('tr', {}, ...head.map((x) => h('th', {}, x)))));
  const body = h('tbody');
  for (const r of rows) body.append(h('tr', {}, ...r.map((x, i) => h(i === 0 ? 'th' : 'td', {}, x))));
  t.append(body);
  return t;
}

function card(label, value, note) {
  return h('div', { class: 'cf-card' }, h('div', { class: 'cf-card-label' }, label), h('div', { class: 'cf-card-value' }, value), note ? h('div', { class: 'cf-card-note' }, note) : null);
}

function figuresSection(data) {
  const f = data.figures || {};
  const run = data.run || {};
  const w = f.willmore_over_4pi || [];
  const q = f.Q || {};
  const lad = f.log_area_distortion || {};
  const log = Array.isArray(data.log) ? data.log : [];
  const done = run.steps_done ?? (log.length ? log[log.length - 1].iteration : undefined);
  const steps = done !== undefined ? `${done}` : '–';
  const exitNote =
    run.exit_status === undefined ? '' : run.exit_status === 0 ? (run.converged ? 'converged' : 'ok') : `exit ${run.exit_status}: ${run.message || ''}`;
  return h(
    'section',
    { class: 'cf-cards' },
    card('W / 4π', `${fmt(w[0], 3)} → ${fmt(w[1], 3)}`, '1 for a round sphere'),
    card('quasi-conformal error Q', `mean ${fmt(q.mean, 4)}`, `p95 ${fmt(q.p95, 4)} · max ${fmt(q.max, 4)} (1 = conformal)`),
    card('log area distortion', `mean ${formatNumber(lad.mean)}`, `std ${formatNumber(lad.std)} · range ${formatNumber(lad.min)} … ${formatNumber(lad.max)}`),
    card('steps', steps, exitNote),
    card('time', run.seconds && Number.isFinite(run.seconds.run) ? `${run.seconds.run.toFixed(2)} s` : '–', 'wall clock of the run'),
  );
}

function viewSection(mesh, fields, data) {
  const section = h('section', { class: 'cf-view' });
  const toolbar = h('div', { class: 'cf-toolbar' });
  const viewBox = h('div', { class: 'cf-viewer' });
  const bar = h('div', { class: 'cf-colorbar' });
  section.append(toolbar, viewBox, bar);
  if (!webglAvailable()) {
    viewBox.append(h('p', { class: 'cf-note' }, 'The 3D view needs WebGL, which this browser does not offer here; the figures, curves and tables below do not.'));
    return section;
  }
  const viewer = createViewer(viewBox, mesh);
  const q = fields.Q, lad = fields.log_area_distortion;
  const ladRange = lad ? robustSymmetricRange(lad) : 1;
  const modes = [];
  if (q)
    modes.push({
      key: 'q',
      label: 'Q (quasi-conformal error)',
      apply: () => viewer.setColoring((f) => blueWhiteRed((q[f] - 1) / 0.5)),
      bar: { left: '1', mid: '1.25', right: '≥ 1.5', title: 'quasi-conformal error Q of each face (input → result); 1 = conformal' },
    });
  if (lad)
    modes.push({
      key: 'lad',
      label: 'log area distortion',
      apply: () => viewer.setColoring((f) => blueWhiteRed(0.5 + lad[f] / (2 * ladRange))),
      bar: { left: `≤ −${formatNumber(ladRange)}`, mid: '0', right: `≥ +${formatNumber(ladRange)}`, title: 'log(area after / area before) of each face, total area normalised; blue shrinks, red grows' },
    });
  if (viewer.hasUv) modes.push({ key: 'uv', label: 'uv checkerboard', apply: () => viewer.setChecker(), bar: null, note: 'texture coordinates: a conformal map keeps the squares’ right angles' });
  modes.push({ key: 'plain', label: 'shaded', apply: () => viewer.setColoring(null), bar: null, note: 'drag to rotate, wheel to zoom, right-drag to pan (both views follow)' });

  const buttons = [];
  function choose(m) {
    m.apply();
    buttons.forEach((b) => b.classList.toggle('active', b.dataset.mode === m.key));
    bar.replaceChildren();
    if (m.bar) {
      bar.append(
        h('div', { class: 'cf-colorbar-title' }, m.bar.title),
        h('div', { class: 'cf-colorbar-ramp', style: `background: ${cssGradient()}` }),
        h('div', { class: 'cf-colorbar-ticks' }, h('span', {}, m.bar.left), h('span', {}, m.bar.mid), h('span', {}, m.bar.right)),
      );
    } else {
      bar.append(h('div', { class: 'cf-colorbar-title' }, m.note || ''));
    }
    root.dataset.curvflowMode = m.key;
  }
  for (const m of modes) {
    const b = h('button', { type: 'button', 'data-mode': m.key, onclick: () => choose(m) }, m.label);
    buttons.push(b);
    toolbar.append(b);
  }
  toolbar.append(h('button', { type: 'button', class: 'cf-reset', onclick: () => viewer.resetView() }, 'reset view'));
  section.viewer = viewer;
  section.start = () => {
    viewer.resize();
    choose(modes[0]);
  };
  return section;
}

function chartsSection(data) {
  const log = Array.isArray(data.log) ? data.log : [];
  const section = h('section', { class: 'cf-charts' });
  if (log.length === 0) {
    section.append(h('p', { class: 'cf-note' }, 'No step log was given (flow --log / report --log), so there are no curves.'));
    return section;
  }
  const x = log.map((r) => r.iteration);
  const num = (v) => (typeof v === 'number' ? v : null);
  const energy = [{ name: 'energy', values: log.map((r) => num(r.energy)) }];
  const termNames = [...new Set(log.flatMap((r) => Object.keys(r.terms || {})))];
  if (termNames.length > 1) for (const t of termNames) energy.push({ name: t, values: log.map((r) => num((r.terms || {})[t])) });
  const resNames = [...new Set(log.flatMap((r) => Object.keys(r.residuals || {})))];
  const residuals = resNames.map((n) => ({ name: n, values: log.map((r) => num((r.residuals || {})[n])) }));
  section.append(lineChart({ id: 'cf-chart-energy', title: `energy per step (${(data.run || {}).method || 'flow'})`, xLabel: 'step', yLabel: 'energy', x, series: energy, log: 'auto' }));
  section.append(lineChart({ id: 'cf-chart-residuals', title: 'residuals per step', xLabel: 'step', yLabel: 'residual', x, series: residuals, log: true }));
  return section;
}

function paramsSection(data) {
  const run = data.run || {};
  const runRows = [
    ['command', run.command || '–'],
    ['method', run.method || '–'],
    ['input', run.input || '–'],
    ['result', run.output || '–'],
    ['step log', run.log || (Array.isArray(data.log) && data.log.length ? 'in this report (no --log file)' : '–')],
    ['steps', `${run.steps_done ?? '–'} of ${run.steps_requested ?? '–'}${run.converged ? ' (converged)' : ''}`],
    ['exit status', run.exit_status === undefined ? '–' : `${run.exit_status}${run.message ? ': ' + run.message : ''}`],
    ['mesh', `${data.mesh.vertices} vertices, ${data.mesh.faces} faces, genus ${data.mesh.genus ?? '–'}, ${data.mesh.boundary_loops ?? '–'} boundary loops`],
    ['curvflow', data.curvflow || '–'],
  ];
  const params = (run.parameters || []).map(([k, v]) => [k, String(v)]);
  const log = Array.isArray(data.log) ? data.log.filter((r) => r.iteration > 0) : [];
  const sum = (key) => log.reduce((a, r) => a + ((r.seconds || {})[key] || 0), 0);
  const timeRows = [];
  const s = run.seconds || {};
  for (const [k, label] of [['run', 'run (wall clock)'], ['load', 'loading the input'], ['write', 'writing the result']])
    if (Number.isFinite(s[k])) timeRows.push([label, `${s[k].toFixed(3)} s`]);
  if (log.length > 0)
    for (const k of ['assemble', 'factorize', 'solve', 'total'])
      timeRows.push([`${k} per step`, `${((1e3 * sum(k)) / log.length).toFixed(2)} ms (sum ${sum(k).toFixed(3)} s over ${log.length} steps)`]);
  return h(
    'section',
    { class: 'cf-tables' },
    h('div', {}, h('h2', {}, 'run'), table(runRows)),
    h('div', {}, h('h2', {}, 'parameters'), params.length ? table(params) : h('p', { class: 'cf-note' }, 'not recorded (write the report with flow --report or from a run directory with run.json)')),
    h('div', {}, h('h2', {}, 'timings'), timeRows.length ? table(timeRows) : h('p', { class: 'cf-note' }, 'not recorded')),
  );
}

function stepsSection(data) {
  const log = Array.isArray(data.log) ? data.log : [];
  if (log.length === 0) return null;
  const resNames = [...new Set(log.flatMap((r) => Object.keys(r.residuals || {})))];
  const head = ['step', 'time', 'energy', ...resNames, 'area drift', 'volume drift', 'ms'];
  const rows = log.map((r) => [
    String(r.iteration),
    formatNumber(r.time),
    typeof r.energy === 'number' ? r.energy.toPrecision(9) : '–',
    ...resNames.map((n) => formatNumber((r.residuals || {})[n])),
    formatNumber(r.area_drift),
    formatNumber(r.volume_drift),
    r.seconds && Number.isFinite(r.seconds.total) ? (1e3 * r.seconds.total).toFixed(1) : '–',
  ]);
  return h('details', { class: 'cf-steps' }, h('summary', {}, `step log (${log.length} rows)`), table(rows, head));
}

function build() {
  const style = document.createElement('style');
  style.textContent = css;
  document.head.append(style);
  const { data, mesh, fields } = loadReportData(document);
  const run = data.run || {};
  const page = h('main', { class: 'cf-page' });
  page.append(
    h('header', {}, h('h1', {}, data.title || 'curvflow report'), h('p', { class: 'cf-sub' }, `${run.command || 'run'} · ${run.method || ''} · ${run.input || ''} → ${run.output || ''}`)),
    figuresSection(data),
  );
  const view = viewSection(mesh, fields, data);
  page.append(view, chartsSection(data), paramsSection(data));
  const steps = stepsSection(data);
  if (steps) page.append(steps);
  page.append(
    h(
      'footer',
      {},
      `Written by curvflow ${data.curvflow || ''}; 3D view by three.js ${CURVFLOW_THREE_VERSION} (MIT licence, © three.js authors), bundled into this file — it needs no network access.`,
    ),
  );
  document.body.append(page);
  if (view.start) view.start();
  const canvas = view.viewer && view.viewer.canvas;
  if (canvas) {
    const r = canvas.getBoundingClientRect();
    root.dataset.curvflowCanvas = [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height].map((v) => Math.round(v)).join(',');
  }
}

try {
  build();
} catch (e) {
  // the inline script's console.error hook counts it (data-curvflow-errors)
  console.error('curvflow report:', (e && e.stack) || e);
  const p = document.createElement('pre');
  p.className = 'cf-error';
  p.textContent = `The report could not be shown: ${e && e.message ? e.message : e}`;
  document.body.append(p);
}
root.dataset.curvflowErrors = String(errors.length);
root.dataset.curvflowReady = '1';
