// Line charts of per-step values (energy, residuals) as inline SVG. Each
// curve is one <path> that carries the values it was drawn from
// (data-values, data-x), and the <svg> carries its axis mapping
// (data-plot, data-y-scale, data-y-domain), so that a test can check that
// what is drawn is what the log says.
const NS = 'http://www.w3.org/2000/svg';
const PALETTE = ['#1f5fa8', '#c8402a', '#2b8a3e', '#8a4fbf', '#b8860b', '#0f8b8d', '#6b6b6b', '#d6336c'];

function el(name, attrs = {}, text) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
  if (text !== undefined) e.textContent = text;
  return e;
}

function niceStep(span, count) {
  const raw = span / Math.max(count, 1);
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
}

export function formatNumber(v) {
  if (v === null || v === undefined || !Number.isFinite(v)) return '–';
  const a = Math.abs(v);
  if (a !== 0 && (a >= 1e5 || a < 1e-3)) return v.toExponential(2).replace(/\.?0+e/, 'e').replace('e+', 'e');
  return String(Number(v.toPrecision(4)));
}

// options: title, xLabel, yLabel, x (numbers), series [{name, values}],
// log: true (a log axis for the positive values), 'auto' (a log axis when
// the positive values span more than a factor 30, else linear) or false
export function lineChart({ title, xLabel, yLabel, x, series, log = false, id }) {
  const W = 560, H = 290, L = 70, R = 16, T = 12, B = 44;
  const wrap = document.createElement('figure');
  wrap.className = 'cf-chart';
  const cap = document.createElement('figcaption');
  cap.textContent = title;
  wrap.appendChild(cap);

  const finite = [];
  for (const s of series) for (const v of s.values) if (Number.isFinite(v)) finite.push(v);
  // a log axis shows the positive values; zeros and negative values (a
  // counter at 0, an exact residual) leave gaps in their curve
  const positive = finite.filter((v) => v > 0);
  const span = positive.length ? Math.max(...positive) / Math.min(...positive) : 1;
  const useLog = (log === true || (log === 'auto' && finite.every((v) => v > 0) && span > 30)) && positive.length > 0;
  if (useLog) for (let i = finite.length - 1; i >= 0; --i) if (!(finite[i] > 0)) finite.splice(i, 1);
  const legend = document.createElement('div');
  legend.className = 'cf-legend';
  wrap.appendChild(legend);
  const svg = el('svg', { viewBox: `0 0 ${W} ${H}`, role: 'img', 'aria-label': title });
  if (id) svg.id = id;
  wrap.appendChild(svg);
  if (finite.length === 0 || x.length === 0) {
    svg.appendChild(el('text', { x: W / 2, y: H / 2, 'text-anchor': 'middle', class: 'cf-axis' }, 'no values in the log'));
    return wrap;
  }

  // domains
  const xmin = Math.min(...x), xmax = Math.max(...x, xmin + 1);
  let ylo = Math.min(...finite), yhi = Math.max(...finite);
  let yTicks = [];
  if (useLog) {
    let a = Math.floor(Math.log10(ylo)), b = Math.ceil(Math.log10(yhi));
    if (b === a) b = a + 1;
    ylo = Math.pow(10, a);
    yhi = Math.pow(10, b);
    const every = Math.ceil((b - a) / 7);
    for (let e = a; e <= b; e += every) {
      yTicks.push(Math.pow(10, e));
      // one or two decades: 2 and 5 times each power as well
      if (b - a <= 2 && e < b) yTicks.push(2 * Math.pow(10, e), 5 * Math.pow(10, e));
    }
  } else {
    if (yhi === ylo) {
      const d = Math.abs(yhi) > 0 ? 0.05 * Math.abs(yhi) : 1;
      ylo -= d;
      yhi += d;
    }
    const step = niceStep(yhi - ylo, 5);
    ylo = Math.floor(ylo / step) * step;
    yhi = Math.ceil(yhi / step) * step;
    for (let t = ylo; t <= yhi + 0.5 * step; t += step) yTicks.push(Number(t.toPrecision(12)));
  }
  const px = (v) => L + ((v - xmin) / (xmax - xmin)) * (W - L - R);
  const ty = useLog ? (v) => Math.log10(v) : (v) => v;
  const y0 = ty(ylo), y1 = ty(yhi);
  const py = (v) => H - B - ((ty(v) - y0) / (y1 - y0)) * (H - T - B);
  svg.setAttribute('data-plot', `${L},${T},${W - R},${H - B}`);
  svg.setAttribute('data-x-domain', `${xmin},${xmax}`);
  svg.setAttribute('data-y-domain', `${ylo},${yhi}`);
  svg.setAttribute('data-y-scale', useLog ? 'log' : 'linear');

  // grid and axes
  const grid = el('g', { class: 'cf-grid' });
  for (const t of yTicks) {
    const y = py(t);
    grid.appendChild(el('line', { x1: L, x2: W - R, y1: y, y2: y }));
    grid.appendChild(el('text', { x: L - 6, y: y + 4, 'text-anchor': 'end', class: 'cf-axis' }, formatNumber(t)));
  }
  const xstep = Math.max(1, niceStep(xmax - xmin, 8));
  for (let t = Math.ceil(xmin / xstep) * xstep; t <= xmax; t += xstep) {
    const xx = px(t);
    grid.appendChild(el('line', { x1: xx, x2: xx, y1: T, y2: H - B, class: 'cf-vgrid' }));
    grid.appendChild(el('text', { x: xx, y: H - B + 16, 'text-anchor': 'middle', class: 'cf-axis' }, formatNumber(t)));
  }
  svg.appendChild(grid);
  svg.appendChild(el('rect', { x: L, y: T, width: W - L - R, height: H - T - B, class: 'cf-frame' }));
  svg.appendChild(el('text', { x: (L + W - R) / 2, y: H - 8, 'text-anchor': 'middle', class: 'cf-axis-label' }, xLabel));
  svg.appendChild(
    el('text', { x: 14, y: (T + H - B) / 2, 'text-anchor': 'middle', class: 'cf-axis-label', transform: `rotate(-90 14 ${(T + H - B) / 2})` }, yLabel + (useLog ? ' (log)' : '')),
  );

  // curves
  series.forEach((s, i) => {
    const color = PALETTE[i % PALETTE.length];
    let d = '';
    let pen = false, points = 0;
    s.values.forEach((v, k) => {
      if (!Number.isFinite(v) || (useLog && v <= 0)) {
        pen = false;
        return;
      }
      d += `${pen ? 'L' : 'M'}${px(x[k]).toFixed(2)},${py(v).toFixed(2)}`;
      pen = true;
      ++points;
    });
    const path = el('path', { class: 'cf-line', stroke: color });
    if (d) path.setAttribute('d', d);
    path.setAttribute('data-series', s.name);
    path.setAttribute('data-values', JSON.stringify(s.values.map((v) => (Number.isFinite(v) ? v : null))));
    path.setAttribute('data-x', JSON.stringify(x));
    path.setAttribute('data-points', String(points));
    svg.appendChild(path);
    if (points <= 60)
      s.values.forEach((v, k) => {
        if (Number.isFinite(v) && !(useLog && v <= 0))
          svg.appendChild(el('circle', { cx: px(x[k]).toFixed(2), cy: py(v).toFixed(2), r: 2.2, fill: color }));
      });
    const item = document.createElement('span');
    item.style.color = color;
    item.textContent = `— ${s.name}`;
    if (points === 0) {
      // e.g. a counter that stayed at 0: nothing to draw on a log axis
      const zero = s.values.every((v) => v === 0 || !Number.isFinite(v));
      item.textContent = `${s.name}: ${zero ? '0 at every step' : 'no positive value'} (not drawn)`;
      item.className = 'cf-legend-off';
    }
    if (points === 0) legend.appendChild(item);
    else legend.insertBefore(item, legend.querySelector('.cf-legend-off'));
  });
  return wrap;
}
