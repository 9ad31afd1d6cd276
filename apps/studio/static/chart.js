// One SVG line chart for the studio's pages: axes with round ticks, lines (with dots and value
// labels when asked), an optional legend and one vertical band (P5–P50–P95 at one x).
// Colours go in SVG's own attributes or in style.css's classes: a style attribute is inline
// style, which the server's Content-Security-Policy refuses.

const NS = 'http://www.w3.org/2000/svg';
const W = 340;
const H = 230;
const M = { l: 52, r: 14, t: 12, b: 44 };

/** About `count` round numbers from `lo` to `hi`. */
export function niceTicks(lo, hi, count = 5) {
  const step0 = (hi - lo || 1) / count;
  const mag = 10 ** Math.floor(Math.log10(step0));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= step0) || step0;
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-6; t += step) ticks.push(+t.toPrecision(12));
  return ticks;
}

/** [lo, hi] over `values` and 0 (and `include`), widened by `pad` × the span at the top. */
function range(values, { include = [], pad = 0 } = {}) {
  const all = values.concat(include).filter(Number.isFinite);
  const lo = Math.min(0, ...all);
  let hi = Math.max(lo, ...all);
  if (hi - lo < 1e-9) hi = lo + 1;
  return [lo, hi + (hi - lo) * pad];
}

/**
 * An `<svg>` chart.
 * - `axes`: `{ x: { label, include, pad }, y: { label, include, pad } }` — each range runs from
 *   0 (or below, for negative values) to the largest value or `include`, plus `pad` × the span.
 * - `series`: `[{ points: [[x, y], ...], label, color, cls, dots, pointLabel }]`: a polyline of
 *   class `cls` (default `series-line`), stroked `color` if given; `dots` draws a circle per
 *   point and `pointLabel(y)` a label above it; series with a `label` get a legend line.
 * - `band`: `{ x, lo, mid, hi, color, cls }`, a vertical line from lo to hi with a dot at mid.
 * - `label`: the chart's text alternative; `empty`: the text when no series has a point.
 */
export function svgChart({ axes, series, band = null, label = '', empty = 'Nothing to plot.' }) {
  const svg = document.createElementNS(NS, 'svg');
  svg.setAttribute('viewBox', `0 0 ${W} ${H}`);
  svg.setAttribute('role', 'img');
  svg.setAttribute('aria-label', label);
  const add = (tag, attrs, text) => {
    const e = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (text !== undefined) e.textContent = text;
    svg.append(e);
    return e;
  };
  const lines = series.map((s) => ({ ...s, points: s.points.filter((p) => Number.isFinite(p[0]) && Number.isFinite(p[1])) }));
  if (lines.every((s) => s.points.length === 0)) {
    add('text', { x: W / 2, y: H / 2, 'text-anchor': 'middle', class: 'axis-label' }, empty);
    return svg;
  }
  const xs = lines.flatMap((s) => s.points.map((p) => p[0])).concat(band ? [band.x] : []);
  const ys = lines.flatMap((s) => s.points.map((p) => p[1])).concat(band ? [band.lo, band.hi] : []);
  const [x0, x1] = range(xs, axes.x);
  const [y0, y1] = range(ys, axes.y);
  const X = (x) => M.l + ((x - x0) / (x1 - x0)) * (W - M.l - M.r);
  const Y = (y) => H - M.b - ((y - y0) / (y1 - y0)) * (H - M.t - M.b);
  for (const t of niceTicks(x0, x1)) {
    add('line', { x1: X(t), x2: X(t), y1: M.t, y2: H - M.b, class: 'grid' });
    add('text', { x: X(t), y: H - M.b + 16, 'text-anchor': 'middle', class: 'tick' }, String(t));
  }
  for (const t of niceTicks(y0, y1)) {
    add('line', { x1: M.l, x2: W - M.r, y1: Y(t), y2: Y(t), class: 'grid' });
    add('text', { x: M.l - 6, y: Y(t) + 4, 'text-anchor': 'end', class: 'tick' }, String(t));
  }
  add('line', { x1: M.l, x2: W - M.r, y1: H - M.b, y2: H - M.b, class: 'axis' });
  add('line', { x1: M.l, x2: M.l, y1: M.t, y2: H - M.b, class: 'axis' });
  if (axes.x.label) add('text', { x: (M.l + W - M.r) / 2, y: H - 8, 'text-anchor': 'middle', class: 'axis-label' }, axes.x.label);
  if (axes.y.label) {
    const mid = (M.t + H - M.b) / 2;
    add('text', { x: 14, y: mid, 'text-anchor': 'middle', class: 'axis-label', transform: `rotate(-90 14 ${mid})` }, axes.y.label);
  }
  let legend = 0;
  for (const s of lines) {
    const pts = [...s.points].sort((a, b) => a[0] - b[0]);
    const stroke = s.color ? { stroke: s.color, 'stroke-width': 2, fill: 'none' } : {};
    add('polyline', { points: pts.map((p) => `${X(p[0])},${Y(p[1])}`).join(' '), class: s.cls || 'series-line', ...stroke });
    for (const p of s.dots ? pts : []) {
      add('circle', { cx: X(p[0]), cy: Y(p[1]), r: 4, class: 'series-dot' });
      if (s.pointLabel) add('text', { x: X(p[0]), y: Y(p[1]) - 8, 'text-anchor': 'middle', class: 'point-label' }, s.pointLabel(p[1]));
    }
    if (s.label) add('text', { x: M.l + 8, y: M.t + 12 + 13 * legend++, class: 'legend', ...(s.color ? { fill: s.color } : {}) }, s.label);
  }
  if (band) {
    const colour = band.color ? { stroke: band.color, 'stroke-width': 2 } : {};
    add('line', { x1: X(band.x), x2: X(band.x), y1: Y(band.lo), y2: Y(band.hi), class: band.cls || 'band', ...colour });
    add('circle', { cx: X(band.x), cy: Y(band.mid), r: 4, ...(band.color ? { fill: band.color } : {}) });
  }
  return svg;
}
