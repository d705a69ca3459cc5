// trochomill report: draws the data block that `trochomill report` embeds (src/report/
// html_report.cpp writes it) with uPlot, and the 3D view with three.js (view3d.js). Everything
// comes from the page itself: nothing is fetched. window.trochomillReport exposes the data,
// the plots and the path scrubber to tests and scripts.
import uPlot from 'uplot';
import 'uplot/dist/uPlot.min.css';
import './report.css';

const t0 = performance.now();
const data = JSON.parse(document.getElementById('trochomill-data').textContent);
const api = (window.trochomillReport = {
  data,
  plots: {},   // id -> uPlot
  figures: [], // ids in page order
  views: {},   // id -> 3D view
  ready: false,
  firstDrawMs: null, // after the script started (ms)
  readyMs: null,
  firstDrawSinceNavigationMs: null, // after the navigation started (ms): the page's time to its first figure
  errors: [],
});

const COLORS = ['#1f6feb', '#d1242f', '#1a7f37', '#8250df', '#bf8700', '#0a7e8c', '#cf4f91'];
const ZONE_FILL = ['rgba(209,36,47,0.10)', 'rgba(191,135,0,0.12)', 'rgba(26,127,55,0.10)'];
const ZONE_NAMES = ['CZI', 'CZII', 'CZIII'];

// ---- small DOM helpers ------------------------------------------------------------------
function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k === 'text') e.textContent = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) if (c != null) e.append(c);
  return e;
}
const main = document.getElementById('report');
const toc = el('nav', { class: 'toc' });

function section(id, title, intro) {
  const s = el('section', { class: 'part', id }, el('h2', { text: title }));
  if (intro) s.append(el('p', { class: 'intro', text: intro }));
  main.append(s);
  toc.append(el('a', { href: '#' + id, text: title }));
  return s;
}
function note(parent, text) {
  parent.append(el('p', { class: 'note', text }));
}
function fmtNum(v, digits = 6) {
  if (v === null || v === undefined) return '-';
  if (typeof v !== 'number') return String(v);
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e6 || a < 1e-4) return v.toExponential(digits - 1);
  return String(Number(v.toPrecision(digits)));
}

// A figure: title, caption, toolbar (export), the plot's box and a read-out line.
function figure(parent, id, title, caption) {
  const box = el('div', { class: 'figure', id: 'fig-' + id, 'data-figure': id });
  box.append(el('h3', { text: title }));
  if (caption) box.append(el('div', { class: 'caption', text: caption }));
  const toolbar = el('div', { class: 'toolbar' });
  const plot = el('div', { class: 'plot' });
  const readout = el('div', { class: 'readout' });
  box.append(toolbar, plot, readout);
  parent.append(box);
  api.figures.push(id);
  return { id, box, toolbar, plot, readout, title };
}

function plotWidth(container) {
  return Math.max(320, Math.floor(container.getBoundingClientRect().width || 1000));
}

function download(name, url) {
  const a = el('a', { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
}

// PNG of a figure: its title, the plot's canvas and the legend's labels, drawn on one canvas.
function figurePng(fig, canvas, labels) {
  const pad = 10;
  const out = document.createElement('canvas');
  const legendH = labels.length ? 22 : 0;
  out.width = canvas.width + 2 * pad;
  out.height = canvas.height + 34 + legendH + pad;
  const c = out.getContext('2d');
  c.fillStyle = '#fff';
  c.fillRect(0, 0, out.width, out.height);
  c.fillStyle = '#1d2330';
  c.font = 'bold 15px sans-serif';
  c.fillText(fig.title, pad, 22);
  c.drawImage(canvas, pad, 30);
  let x = pad;
  c.font = '12px sans-serif';
  for (const { label, color } of labels) {
    c.fillStyle = color;
    c.fillRect(x, canvas.height + 40, 14, 4);
    c.fillStyle = '#1d2330';
    c.fillText(label, x + 18, canvas.height + 45);
    x += c.measureText(label).width + 34;
  }
  return out.toDataURL('image/png');
}

// SVG of a uPlot figure: its series as polylines on the current scales, with the axes' ticks.
function figureSvg(fig, u) {
  const W = u.width, H = u.height;
  const b = u.bbox, dpr = uPlot.pxRatio;
  const L = b.left / dpr, T = b.top / dpr, PW = b.width / dpr, PH = b.height / dpr;
  const parts = [`<svg xmlns="http://www.w3.org/2000/svg" width="${W}" height="${H + 30}" ` +
    `viewBox="0 0 ${W} ${H + 30}" font-family="sans-serif" font-size="11">`,
    `<rect width="100%" height="100%" fill="#fff"/>`,
    `<text x="8" y="16" font-size="14" font-weight="bold">${escapeXml(fig.title)}</text>`,
    `<g transform="translate(0,24)">`,
    `<rect x="${L}" y="${T}" width="${PW}" height="${PH}" fill="none" stroke="#999"/>`];
  const xs = u.series[0].scale || 'x';
  for (const [ai, axis] of u.axes.entries()) {
    if (!axis.show || !axis._splits) continue;
    const sc = axis.scale;
    const horiz = axis.side % 2 === 0;
    axis._splits.forEach((v, k) => {
      const label = axis._values ? axis._values[k] : fmtNum(v);
      if (horiz) {
        const px = u.valToPos(v, sc);
        parts.push(`<line x1="${L + px}" x2="${L + px}" y1="${T + PH}" y2="${T + PH + 4}" stroke="#555"/>`,
          `<text x="${L + px}" y="${T + PH + 16}" text-anchor="middle">${escapeXml(String(label))}</text>`);
      } else {
        const py = u.valToPos(v, sc);
        const right = axis.side === 1;
        const x0 = right ? L + PW : L;
        parts.push(`<line x1="${x0}" x2="${right ? x0 + 4 : x0 - 4}" y1="${T + py}" y2="${T + py}" stroke="#555"/>`,
          `<text x="${right ? x0 + 6 : x0 - 6}" y="${T + py + 4}" text-anchor="${right ? 'start' : 'end'}">${escapeXml(String(label))}</text>`);
      }
    });
    if (axis.label) {
      if (horiz) parts.push(`<text x="${L + PW / 2}" y="${T + PH + 32}" text-anchor="middle">${escapeXml(axis.label)}</text>`);
      else parts.push(`<text transform="translate(${axis.side === 1 ? L + PW + 50 : 12},${T + PH / 2}) rotate(-90)" text-anchor="middle">${escapeXml(axis.label)}</text>`);
    }
    void ai;
  }
  parts.push(`<clipPath id="c"><rect x="${L}" y="${T}" width="${PW}" height="${PH}"/></clipPath><g clip-path="url(#c)">`);
  const mode2 = u.mode === 2;
  for (let i = 1; i < u.series.length; i++) {
    const s = u.series[i];
    if (!s.show) continue;
    const xsData = mode2 ? u.data[i][0] : u.data[0];
    const ysData = mode2 ? u.data[i][1] : u.data[i];
    const xScale = mode2 ? s.facets[0].scale : xs;
    const yScale = mode2 ? s.facets[1].scale : s.scale;
    let d = '';
    let pen = false;
    for (let k = 0; k < xsData.length; k++) {
      const yv = ysData[k], xv = xsData[k];
      if (yv == null || xv == null) { pen = false; continue; }
      const px = L + u.valToPos(xv, xScale), py = T + u.valToPos(yv, yScale);
      d += (pen ? 'L' : 'M') + px.toFixed(1) + ' ' + py.toFixed(1);
      pen = true;
    }
    const color = typeof s._stroke === 'string' ? s._stroke : '#333';
    parts.push(`<path d="${d}" fill="none" stroke="${color}" stroke-width="1.2"/>`);
  }
  parts.push('</g>');
  let lx = L;
  for (let i = 1; i < u.series.length; i++) {
    const s = u.series[i];
    if (!s.show || !s.label) continue;
    const color = typeof s._stroke === 'string' ? s._stroke : '#333';
    parts.push(`<rect x="${lx}" y="${H + 2}" width="12" height="3" fill="${color}"/>`,
      `<text x="${lx + 16}" y="${H + 6}">${escapeXml(s.label)}</text>`);
    lx += 30 + 6.5 * s.label.length;
  }
  parts.push('</g></svg>');
  return 'data:image/svg+xml;charset=utf-8,' + encodeURIComponent(parts.join('\n'));
}
function escapeXml(s) {
  return String(s).replace(/[<>&"]/g, (c) => ({ '<': '&lt;', '>': '&gt;', '&': '&amp;', '"': '&quot;' })[c]);
}

function addExports(fig, u, labels) {
  const name = (ext) => `trochomill-${fig.id}.${ext}`;
  fig.toolbar.append(
    el('button', { text: 'PNG', title: 'save this figure as PNG', onclick: () => download(name('png'), figurePng(fig, u.ctx.canvas, labels())) }),
    el('button', { text: 'SVG', title: 'save this figure as SVG', onclick: () => download(name('svg'), figureSvg(fig, u)) }),
    el('span', { class: 'hint', text: 'drag to zoom, double-click to reset' }));
}

function register(fig, u) {
  api.plots[fig.id] = u;
  if (api.firstDrawMs === null) {
    api.firstDrawMs = performance.now() - t0;
    api.firstDrawSinceNavigationMs = performance.now();
  }
}

// ---- line plots --------------------------------------------------------------------------
// spec: { x: [], xLabel, series: [{label, values, color, scale ('y'|'y2'|...), dash, width,
// stepped, points}], axes: {y: label, y2: label, ...}, height, logY, draw(u) }
function linePlot(fig, spec) {
  const scales = { x: { time: false } };
  const axisDefs = [{ label: spec.xLabel, scale: 'x' }];
  const sides = [3, 1, 1];
  let k = 0;
  for (const [key, label] of Object.entries(spec.axes)) {
    scales[key] = spec.logY && key === 'y' ? { distr: 3 } : {};
    if (spec.ranges && spec.ranges[key]) scales[key].range = spec.ranges[key];
    axisDefs.push({ label, scale: key, side: sides[Math.min(k, 2)], grid: { show: k === 0 },
      size: 60 });
    k++;
  }
  const series = [{ label: spec.xLabel }];
  const cols = [spec.x];
  spec.series.forEach((s, i) => {
    const color = s.color || COLORS[i % COLORS.length];
    series.push({
      label: s.label, stroke: color, scale: s.scale || 'y', width: s.width || 1.3,
      dash: s.dash, spanGaps: s.spanGaps || false,
      paths: s.stepped ? uPlot.paths.stepped({ align: 1 }) : undefined,
      points: { show: s.points || false, size: 6, fill: color },
      value: (u, v) => (v == null ? '-' : fmtNum(v, 5)),
    });
    cols.push(s.values);
  });
  const opts = {
    width: plotWidth(fig.plot), height: spec.height || 280, scales, axes: axisDefs, series,
    cursor: { drag: { x: true, y: false, setScale: true } },
    legend: { live: true },
    hooks: { draw: spec.draw ? [spec.draw] : [] },
  };
  const u = new uPlot(opts, cols, fig.plot);
  register(fig, u);
  addExports(fig, u, () => spec.series.map((s, i) => ({ label: s.label, color: s.color || COLORS[i % COLORS.length] })));
  return u;
}

// Joins series with different x grids onto their union (uPlot.join), for overlays.
function joined(pairs) {
  return uPlot.join(pairs.map(([x, y]) => [x, y]));
}

// A marker with its label at (x, y) on a scale (a draw hook).
function marker(x, y, label, scale = 'y', color = '#d1242f') {
  return (u) => {
    if (x == null || y == null) return;
    const px = u.valToPos(x, 'x', true), py = u.valToPos(y, scale, true);
    const c = u.ctx;
    c.save();
    c.fillStyle = color;
    c.beginPath();
    c.arc(px, py, 4 * uPlot.pxRatio, 0, 2 * Math.PI);
    c.fill();
    c.font = `${11 * uPlot.pxRatio}px sans-serif`;
    c.fillText(label, px + 6 * uPlot.pxRatio, py - 6 * uPlot.pxRatio);
    c.restore();
  };
}

// Horizontal bands of a scale shaded (K_re zones): [{from, to, fill, label}].
function bands(list, scale = 'y') {
  return (u) => {
    const c = u.ctx;
    const { left, top, width, height } = u.bbox;
    c.save();
    c.beginPath();
    c.rect(left, top, width, height);
    c.clip();
    for (const b of list) {
      const y0 = u.valToPos(b.to, scale, true), y1 = u.valToPos(b.from, scale, true);
      c.fillStyle = b.fill;
      c.fillRect(left, Math.min(y0, y1), width, Math.abs(y1 - y0));
      if (b.label && Math.abs(y1 - y0) > 14 * uPlot.pxRatio) {
        c.fillStyle = '#5b6475';
        c.font = `${11 * uPlot.pxRatio}px sans-serif`;
        c.fillText(b.label, left + width - 48 * uPlot.pxRatio, Math.min(y0, y1) + 14 * uPlot.pxRatio);
      }
    }
    c.restore();
  };
}

// ---- heat maps ---------------------------------------------------------------------------
function decodeGrid(g) {
  const bin = atob(g.data);
  const n = g.columns * g.rows;
  const out = new Float64Array(n);
  const span = g.max - g.min;
  for (let i = 0; i < n; i++) {
    const q = bin.charCodeAt(2 * i) | (bin.charCodeAt(2 * i + 1) << 8);
    out[i] = q === 65535 ? NaN : g.min + (q / g.levels) * span;
  }
  return out;
}
// Viridis at five stops, interpolated.
const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
function palette(f) {
  const x = Math.min(1, Math.max(0, f)) * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x));
  const a = x - i;
  return VIRIDIS[i].map((c, k) => Math.round(c + a * (VIRIDIS[i + 1][k] - c)));
}
function colorbar(parent, lo, hi, label) {
  const cv = el('canvas', { width: 240, height: 12 });
  const c = cv.getContext('2d');
  for (let i = 0; i < 240; i++) {
    const [r, g, b] = palette(i / 239);
    c.fillStyle = `rgb(${r},${g},${b})`;
    c.fillRect(i, 0, 1, 12);
  }
  parent.append(el('div', { class: 'colorbar' }, el('span', { text: fmtNum(lo, 4) }), cv,
    el('span', { text: fmtNum(hi, 4) }), el('span', { text: label })));
}

// spec: {grid (decoded values, row-major rows x columns), columns, rows, x0, x1, y0, y1,
// xLabel, yLabel, valueLabel, lo, hi}
function heatPlot(fig, spec) {
  const { columns, rows, values } = spec;
  const img = document.createElement('canvas');
  img.width = columns;
  img.height = rows;
  const ictx = img.getContext('2d');
  const id = ictx.createImageData(columns, rows);
  const span = spec.hi > spec.lo ? spec.hi - spec.lo : 1;
  for (let r = 0; r < rows; r++) {
    for (let c = 0; c < columns; c++) {
      const v = values[r * columns + c];
      const o = 4 * ((rows - 1 - r) * columns + c); // row 0 at the bottom
      if (Number.isNaN(v)) { id.data[o + 3] = 0; continue; }
      const [R, G, B] = palette((v - spec.lo) / span);
      id.data[o] = R; id.data[o + 1] = G; id.data[o + 2] = B; id.data[o + 3] = 255;
    }
  }
  ictx.putImageData(id, 0, 0);
  const dx = (spec.x1 - spec.x0) / columns, dy = (spec.y1 - spec.y0) / rows;
  const draw = (u) => {
    const c = u.ctx;
    const { left, top, width, height } = u.bbox;
    const X0 = u.scales.x.min, X1 = u.scales.x.max, Y0 = u.scales.y.min, Y1 = u.scales.y.max;
    // The part of the image in view, in image pixels.
    const sx = ((X0 - spec.x0) / (spec.x1 - spec.x0)) * columns;
    const sw = ((X1 - X0) / (spec.x1 - spec.x0)) * columns;
    const sy = ((spec.y1 - Y1) / (spec.y1 - spec.y0)) * rows;
    const sh = ((Y1 - Y0) / (spec.y1 - spec.y0)) * rows;
    c.save();
    c.imageSmoothingEnabled = false;
    c.beginPath();
    c.rect(left, top, width, height);
    c.clip();
    c.drawImage(img, sx, sy, sw, sh, left, top, width, height);
    c.restore();
  };
  const opts = {
    width: plotWidth(fig.plot), height: spec.height || 300,
    scales: { x: { time: false, range: [spec.x0, spec.x1] }, y: { range: [spec.y0, spec.y1] } },
    axes: [{ label: spec.xLabel }, { label: spec.yLabel, size: 60 }],
    series: [{ label: spec.xLabel }, { label: spec.valueLabel, stroke: 'transparent', points: { show: false } }],
    cursor: { drag: { x: true, y: true, uni: 30, setScale: true }, points: { show: false } },
    legend: { show: false },
    hooks: {
      drawClear: [draw],
      setCursor: [(u) => {
        const { left, top } = u.cursor;
        if (left == null || left < 0) { fig.readout.textContent = ''; return; }
        const x = u.posToVal(left, 'x'), y = u.posToVal(top, 'y');
        const c = Math.floor((x - spec.x0) / dx), r = Math.floor((y - spec.y0) / dy);
        const v = c >= 0 && c < columns && r >= 0 && r < rows ? values[r * columns + c] : NaN;
        fig.readout.textContent = `${spec.xLabel} ${fmtNum(x, 5)}   ${spec.yLabel} ${fmtNum(y, 5)}   ` +
          `${spec.valueLabel} ${Number.isNaN(v) ? '-' : fmtNum(v, 5)}`;
      }],
    },
  };
  const u = new uPlot(opts, [[spec.x0, spec.x1], [null, null]], fig.plot);
  register(fig, u);
  addExports(fig, u, () => []);
  colorbar(fig.box, spec.lo, spec.hi, spec.valueLabel);
  return u;
}

// ---- the parts -----------------------------------------------------------------------------
function headerPart() {
  const s = data.summary;
  const head = el('header', { class: 'report-head' },
    el('h1', { text: `trochomill report: ${data.job_file || 'job'}` }),
    el('p', { text: `trochomill ${data.version}; ${data.gcode_file ? 'program ' + data.gcode_file : 'planned path'}` +
      (data.overrides.length ? `; overrides: ${data.overrides.join(', ')}` : '') }),
    el('p', { text: `command: ${data.command}` }));
  main.append(head, toc);
  const sec = section('summary', 'Summary', 'What matters for this job first (4 significant digits), then every number of `trochomill analyze --json` (same keys and units) folded below.');
  for (const n of data.notes) note(sec, n);
  // The headline: the figures that matter, in plain words, each with what it means; a figure
  // the job or program does not have (no steady cycle, no walls, no force model) is left out.
  const headline = [
    ['machining_time_with_acceleration_s', 'Machining time', 's', 'the whole program at the programmed feeds, slowed where the machine\'s acceleration limits it'],
    ['path_length_mm', 'Path length', 'mm', 'tool-centre path, rapids included'],
    ['h_max_after_entry_mm', 'Largest chip after the entry', 'mm', 'the largest local uncut chip thickness once the tool is in the cut (the exact engagement kernel)'],
    ['engagement_max_after_entry_deg', 'Largest engagement after the entry', '°', 'the largest engaged angle of the tool circle once in the cut'],
    ['h_max_mm', 'Largest chip, whole program', 'mm', 'the entry included (a descent into the stock may take the whole feed per tooth)'],
    ['engagement_angle_max_deg', 'Largest engagement, whole program', '°', 'the entry included (a helix or plunge is engaged all round: 360°)'],
    ['cycle_h_max_mm', 'Steady cycle: largest chip', 'mm', 'in one cycle of the steady state (Wagih 2023)'],
    ['cycle_engagement_angle_max_deg', 'Steady cycle: largest engagement', '°', 'in one cycle of the steady state'],
    ['cycle_time_s', 'Steady cycle: time', 's', 'one cycle'],
    ['cycle_mrr_mm3_per_min', 'Steady cycle: removal rate', 'mm³/min', 'the volume one cycle removes over its time'],
    ['mrr_total_mm3_per_min', 'Removal rate, whole program', 'mm³/min', 'removed volume over the machining time'],
    ['removed_volume_mm3', 'Removed volume', 'mm³', 'what the program cuts from the stock'],
    ['waviness_left_mm', 'Wall waviness, left', 'mm', 'peak to valley of the left wall\'s profile from the tool\'s passes'],
    ['waviness_right_mm', 'Wall waviness, right', 'mm', 'the same on the right wall'],
    ['cycle_force_max_predicted_n', 'Largest cutting force', 'N', 'the force model\'s largest resultant in the cycle'],
    ['performance_index', 'Performance index', '', 'Wagih 2023: removal rate per chip load, to compare paths'],
  ];
  const list = el('table', { class: 'summary headline', id: 'summary-headline' });
  for (const [key, name, unit, meaning] of headline) {
    const v = s[key];
    if (typeof v !== 'number') continue;
    list.append(el('tr', { 'data-key': key }, el('td', { text: name }),
      el('td', { class: 'num', 'data-value': JSON.stringify(v), text: fmtNum(v, 4) }), el('td', { text: unit }),
      el('td', { class: 'meaning', text: meaning })));
  }
  sec.append(list);
  const assumed = [];
  if (typeof s.feed_per_tooth_mm === 'number') assumed.push(`feed per tooth f_z ${fmtNum(s.feed_per_tooth_mm, 4)} mm`);
  if (s.job) {
    if (data.path && data.path.pocket) assumed.push(`pocket of layer '${data.path.pocket.boundary}'`);
    else if (s.job.path_type) assumed.push(`path ${s.job.path_type}`);
    if (typeof s.job.tool_diameter_mm === 'number') assumed.push(`tool ${fmtNum(s.job.tool_diameter_mm, 4)} mm, ${s.job.teeth} teeth`);
    if (typeof s.job.spindle_speed_rpm === 'number') assumed.push(`${fmtNum(s.job.spindle_speed_rpm, 4)} rpm at ${fmtNum(s.job.feed_rate_mm_per_min, 4)} mm/min`);
  }
  if (s.performance_index_note) assumed.push(`performance index: ${s.performance_index_note}`);
  if (assumed.length) sec.append(el('p', { class: 'assumed', text: `For: ${assumed.join('; ')}.` }));
  const table = el('table', { class: 'summary', id: 'summary-table' });
  table.append(el('tr', {}, el('th', { text: 'key' }), el('th', { text: 'value' }), el('th', { text: 'unit' })));
  const unitOf = (k) => {
    const units = [['_mm3_per_min', 'mm³/min'], ['_mm_per_min', 'mm/min'], ['_mm3', 'mm³'], ['_mm2', 'mm²'],
      ['_mm', 'mm'], ['_deg', '°'], ['_s', 's'], ['_n', 'N'], ['_nm', 'N m'], ['_w', 'W'], ['_rpm', 'rpm'], ['_pct', '%']];
    for (const [suf, u] of units) if (k.endsWith(suf)) return u;
    return '';
  };
  const rows = (obj, prefix) => {
    for (const [k, v] of Object.entries(obj)) {
      const key = prefix ? `${prefix}.${k}` : k;
      if (v !== null && typeof v === 'object' && !Array.isArray(v)) { rows(v, key); continue; }
      const shown = Array.isArray(v) ? v.map((x) => (typeof x === 'number' ? fmtNum(x) : String(x))).join(', ')
        : typeof v === 'number' ? String(v) : String(v);
      table.append(el('tr', { 'data-key': key }, el('td', { text: key }),
        el('td', { class: typeof v === 'number' ? 'num' : '', 'data-value': JSON.stringify(v), text: shown }),
        el('td', { text: unitOf(k) })));
    }
  };
  rows(s, '');
  sec.append(el('details', { id: 'summary-all' }, el('summary', { text: 'Every figure (analyze --json)' }), table));
  sec.append(el('details', {}, el('summary', { text: 'The job file as read' }), el('pre', { text: data.job_text })));
}

function pathPart() {
  const p = data.path;
  const pk = p.pocket;
  const sec = section('path', 'Tool path', `Top view of the ${pk ? 'pocket' : 'slot'} (mm): the tool-centre path (rapids dashed), the entry, ${data.path.periodic ? 'the steady cycle highlighted' : 'no steady cycle (each cycle differs: the figures are the whole program\'s)'}, and the tool disc at the time of the slider.`);
  const fig = figure(sec, 'path-top', 'Path, top view', `${pk ? `pocket of layer '${pk.boundary}'${pk.islands ? `, islands of layer '${pk.islands}'` : ''}, ${fmtNum(pk.depth_mm)} mm deep, engagement at most ${fmtNum(pk.max_engagement_deg)}°` : p.slot.along ? `slot ${fmtNum(p.slot.width_mm)} mm wide along '${p.slot.along}' (${fmtNum(p.slot.length_mm)} mm)` : `slot ${fmtNum(p.slot.width_mm)} x ${fmtNum(p.slot.length_mm)} mm`}, tool radius ${fmtNum(p.tool_radius_mm)} mm; ${p.samples} samples every ${fmtNum(p.dt_s, 4)} s`);
  const n = p.samples;
  // Uniform in time, the last sample at the path's end.
  p.t_s = Array.from({ length: n }, (_, i) => (i === n - 1 ? p.duration_s : i * p.dt_s));
  const isRapidAt = new Uint8Array(n);
  for (const [a, b] of p.rapid) for (let i = a; i <= b; i++) isRapidAt[i] = 1;
  const feed = [[], []], rapid = [[], []], entry = [[], []], cycle = [[], []];
  for (let i = 0; i < n; i++) {
    const x = p.x_mm[i], y = p.y_mm[i], t = p.t_s[i];
    const isRapid = isRapidAt[i] === 1, prevRapid = i > 0 && isRapidAt[i - 1] === 1;
    // A point joins the traces of both kinds where the motion changes, so lines stay unbroken.
    feed[0].push(!isRapid || !prevRapid ? x : null); feed[1].push(!isRapid || !prevRapid ? y : null);
    rapid[0].push(isRapid || prevRapid ? x : null); rapid[1].push(isRapid || prevRapid ? y : null);
    const inEntry = p.entry_to_s != null && t <= p.entry_to_s && !isRapid;
    entry[0].push(inEntry ? x : null); entry[1].push(inEntry ? y : null);
    const inCycle = t >= p.cycle_from_s && t <= p.cycle_to_s;
    cycle[0].push(inCycle ? x : null); cycle[1].push(inCycle ? y : null);
  }
  // A pocket: the path where the engagement comes near its target (90 % of it and more) and
  // where it passes it, from the engagement series (each path sample takes the largest
  // engagement of the series' samples since the path sample before).
  const near = [[], []], over = [[], []];
  if (pk && data.engagement && data.engagement.program) {
    const et = data.engagement.program.t_s, ev = data.engagement.program.engagement_deg;
    const target = pk.max_engagement_deg;
    let j = 0;
    for (let i = 0; i < n; i++) {
      let m = 0;
      while (j < et.length && et[j] <= p.t_s[i]) { if (ev[j] != null) m = Math.max(m, ev[j]); j++; }
      // Not the rapids nor the descents (the helices: all round in the stock).
      const feedHere = isRapidAt[i] !== 1 && !(i > 0 && p.z_mm[i] < p.z_mm[i - 1] - 1e-9);
      const isNear = feedHere && m >= 0.9 * target && m <= target, isOver = feedHere && m > target;
      near[0].push(isNear ? p.x_mm[i] : null); near[1].push(isNear ? p.y_mm[i] : null);
      over[0].push(isOver ? p.x_mm[i] : null); over[1].push(isOver ? p.y_mm[i] : null);
    }
  }
  const hasEngagement = near[0].some((v) => v != null) || over[0].some((v) => v != null);
  const sl = p.slot;
  // The slot's boundaries (a rectangle, or the region along a drawing's contour), null between.
  const outline = [p.outline.x_mm, p.outline.y_mm];
  // The drawing's other contours under the path (a curved slot's part), null between them.
  const drawing = p.drawing ? [p.drawing.x_mm, p.drawing.y_mm] : [[], []];
  const disc = (cx, cy) => {
    const xs = [], ys = [];
    for (let k = 0; k <= 72; k++) {
      const a = (k / 72) * 2 * Math.PI;
      xs.push(cx + p.tool_radius_mm * Math.cos(a));
      ys.push(cy + p.tool_radius_mm * Math.sin(a));
    }
    return [xs, ys];
  };
  // The position at time t: linear between the samples (uniform in time).
  const at = (t) => {
    const T = Math.min(Math.max(t, p.t_s[0]), p.t_s[n - 1]);
    let lo = 0, hi = n - 1;
    while (hi - lo > 1) { const m = (lo + hi) >> 1; if (p.t_s[m] <= T) lo = m; else hi = m; }
    const a = p.t_s[hi] > p.t_s[lo] ? (T - p.t_s[lo]) / (p.t_s[hi] - p.t_s[lo]) : 0;
    const lerp = (v) => v[lo] + a * (v[hi] - v[lo]);
    return { t: T, x: lerp(p.x_mm), y: lerp(p.y_mm), z: lerp(p.z_mm) };
  };
  const pos0 = at(p.cycle_from_s || 0);
  // Equal scales in x and y: the plot's height follows the slot's shape (within limits).
  const margin = p.tool_radius_mm * 1.5;
  let xr = [Math.min(sl.x_min_mm, ...feed[0].filter((v) => v != null).slice(0, 1)) - margin, sl.x_max_mm + margin];
  let yr = [sl.y_min_mm - margin, sl.y_max_mm + margin];
  for (let i = 0; i < n; i++) {
    xr = [Math.min(xr[0], p.x_mm[i] - p.tool_radius_mm), Math.max(xr[1], p.x_mm[i] + p.tool_radius_mm)];
    yr = [Math.min(yr[0], p.y_mm[i] - p.tool_radius_mm), Math.max(yr[1], p.y_mm[i] + p.tool_radius_mm)];
  }
  const width = plotWidth(fig.plot);
  const height = Math.max(260, Math.min(760, ((width - 80) * (yr[1] - yr[0])) / (xr[1] - xr[0]) + 60));
  // Widen the shorter range so one mm is as long on both axes.
  const ppmX = (width - 80) / (xr[1] - xr[0]), ppmY = (height - 60) / (yr[1] - yr[0]);
  if (ppmX > ppmY) { const c = (xr[0] + xr[1]) / 2, h = (width - 80) / ppmY / 2; xr = [c - h, c + h]; }
  else { const c = (yr[0] + yr[1]) / 2, h = (height - 60) / ppmX / 2; yr = [c - h, c + h]; }
  // Every point in drawing order (uPlot's linear paths thin points by pixel column, which
  // assumes x ascending: a path in the plane is not).
  const polyline = (uu, si) => {
    const [xs, ys] = uu.data[si];
    const path = new Path2D();
    let pen = false;
    for (let i = 0; i < xs.length; i++) {
      if (xs[i] == null || ys[i] == null) { pen = false; continue; }
      const px = uu.valToPos(xs[i], 'x', true), py = uu.valToPos(ys[i], 'y', true);
      if (pen) path.lineTo(px, py); else path.moveTo(px, py);
      pen = true;
    }
    return { stroke: path, fill: null, clip: null, band: null, gaps: null, flags: 0 };
  };
  const mk = (label, stroke, extra = {}) => ({ label, stroke, facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }],
    paths: polyline, points: { show: false }, width: 1.2, ...extra });
  const hasDrawing = drawing[0].length > 0;
  const stock = p.stock ? [p.stock.x_mm, p.stock.y_mm] : null;
  const series = [{}, mk(pk ? 'walls and islands' : 'slot', '#5b6475', { width: 2 }),
    ...(hasDrawing ? [mk(`drawing (${p.drawing.layers.join(', ')})`, '#2da44e', { width: 1.4 })] : []),
    mk('feed moves', '#9aa4b5'), mk('rapids', '#bf8700', { dash: [6, 4] }),
    ...(stock ? [mk(`stock mesh '${p.stock.file}' at the first level, z = ${fmtNum(p.stock.z_mm)} mm`, '#1b1f24', { width: 1.8, dash: [4, 4] })] : []),
    mk('entry', '#8250df', { width: 2 }), mk('steady cycle', '#1f6feb', { width: 2.2 }),
    ...(hasEngagement ? [mk(`engagement 90-100 % of ${fmtNum(pk.max_engagement_deg)}°`, '#0598bc', { width: 2 }),
      mk(`engagement above ${fmtNum(pk.max_engagement_deg)}°`, '#cf222e', { width: 3 })] : []),
    mk('tool disc', '#d1242f', { width: 2 }), mk('tool centre', '#d1242f', { width: 2 })];
  const cross = (cx, cy) => {
    const h = p.tool_radius_mm / 6;
    return [[cx - h, cx + h, null, cx, cx], [cy, cy, null, cy - h, cy + h]];
  };
  const dataTop = [null, outline, ...(hasDrawing ? [drawing] : []), feed, rapid, ...(stock ? [stock] : []), entry, cycle,
    ...(hasEngagement ? [near, over] : []), disc(pos0.x, pos0.y), cross(pos0.x, pos0.y)];
  const iDisc = dataTop.length - 2, iCross = dataTop.length - 1;
  const u = new uPlot({
    mode: 2, width, height,
    scales: { x: { time: false, range: xr }, y: { range: yr } },
    axes: [{ label: 'x (mm)', scale: 'x' }, { label: 'y (mm)', scale: 'y', size: 60 }],
    series,
    cursor: { drag: { x: true, y: true, uni: 30, setScale: true }, points: { show: false } },
    legend: { live: false },
    hooks: {
      setCursor: [(uu) => {
        const { left, top } = uu.cursor;
        if (left == null || left < 0) return;
        fig.readout.textContent = `x ${fmtNum(uu.posToVal(left, 'x'), 5)} mm   y ${fmtNum(uu.posToVal(top, 'y'), 5)} mm`;
      }],
    },
  }, dataTop, fig.plot);
  register(fig, u);
  addExports(fig, u, () => series.slice(1).map((s) => ({ label: s.label, color: s.stroke })));
  // The scrubber.
  const slider = el('input', { type: 'range', min: 0, max: p.duration_s, step: p.duration_s / 4000, value: pos0.t, id: 'path-slider' });
  const label = el('span', { class: 'readout' });
  const setTime = (t) => {
    const q = at(Number(t));
    dataTop[iDisc] = disc(q.x, q.y);
    dataTop[iCross] = cross(q.x, q.y);
    u.setData(dataTop, false);
    slider.value = q.t;
    label.textContent = `t ${q.t.toFixed(3)} s   x ${q.x.toFixed(4)} mm   y ${q.y.toFixed(4)} mm   z ${q.z.toFixed(4)} mm`;
    api.tool = q;
    return q;
  };
  slider.addEventListener('input', () => setTime(slider.value));
  fig.box.append(el('div', { class: 'slider' }, el('span', { text: 'time' }), slider, label));
  if (p.drawing && p.drawing.note) fig.box.append(el('p', { class: 'note', text: p.drawing.note }));
  api.setTime = setTime;
  api.positionAt = at;
  setTime(pos0.t);
}

function engagementPart() {
  const e = data.engagement;
  const sec = section('engagement', 'Engagement and chip thickness',
    'Wagih 2023: engaged angle of the tool circle, the largest local uncut chip thickness h and the teeth in cut, from the exact engagement kernel (one sample per tooth pass fraction). Series are decimated for display keeping every extreme (min and max per pixel column); the full series is `analyze --csv`.');
  // One plot of engagement, h and teeth in cut, with h_max marked.
  const plot = (fig, block, xLabel, peak) => linePlot(fig, {
    x: block.t_s, xLabel, axes: { y: 'engagement angle (°)', y2: 'h (mm)', y3: 'teeth in cut' },
    series: [{ label: 'engagement (°)', values: block.engagement_deg, scale: 'y' },
      { label: 'h_max (mm)', values: block.h_max_mm, scale: 'y2' },
      { label: 'teeth in cut', values: block.teeth_in_cut, scale: 'y3', stepped: true, color: '#8c959f' }],
    draw: marker(peak.t_s, peak.h_mm, `h_max ${fmtNum(peak.h_mm, 4)} mm`, 'y2'),
  });
  const pr = e.program;
  plot(figure(sec, 'engagement-program', 'Over the program', `${pr.samples} samples, ${pr.shown} shown; h_max of the program ${fmtNum(e.program_h_max.h_mm)} mm at ${fmtNum(e.program_h_max.t_s)} s`),
    pr, 'time (s)', e.program_h_max);
  if (e.cycle) {
    plot(figure(sec, 'engagement-cycle', data.summary.periodic === false ? 'Over the analysis window (no periodic cycle)' : 'Over the steady cycle',
      `from ${fmtNum(data.path.cycle_from_s)} s; h_max ${fmtNum(e.cycle_h_max.h_mm)} mm at ${fmtNum(e.cycle_h_max.t_s)} s into the cycle`),
    e.cycle, 'time from the cycle start (s)', e.cycle_h_max);
  }
}

function wallsPart() {
  const w = data.walls;
  const sec = section('walls', 'Walls and floor', 'Wall profiles along the feed over one period of the steady state: path level (envelope of the tool circles) and tooth level (envelope of the tooth tips), with their waviness; the predicted wall texture and the floor texture in the middle of the slot (ISO 16610-21 mean line); the floor imprint density (Wagih 2023 Figs. 21-22).');
  if (data.path && data.path.pocket) {
    sec.append(el('p', { text: 'A pocket has no steady cycle: the wall profiles over a slot\'s period do not apply (the finishing pass makes the walls).' }));
    return;
  }
  const cols = el('div', { class: 'columns' });
  sec.append(cols);
  for (const side of ['left', 'right']) {
    const a = w.path[side], b = w.tooth[side];
    if (!a.y_mm.length && !b.y_mm.length) continue;
    const fig = figure(cols, `wall-${side}`, `${side} wall`, `waviness: path ${fmtNum(a.waviness_mm, 4)} mm, tooth ${fmtNum(b.waviness_mm, 4)} mm`);
    const j = joined([[a.y_mm, a.x_mm], [b.y_mm, b.x_mm]]);
    linePlot(fig, { x: j[0], xLabel: 'y along the feed (mm)', axes: { y: 'wall x (mm)' }, height: 240,
      series: [{ label: 'path level', values: j[1], spanGaps: true }, { label: 'tooth level', values: j[2], spanGaps: true }] });
  }
  for (const side of ['left', 'right', 'floor']) {
    const t = w[`texture_${side}`];
    if (!t) continue;
    const title = side === 'floor' ? 'floor texture (middle of the slot, along the feed; the end edges\' passes)' : `${side} wall texture`;
    const fig = figure(cols, `texture-${side}`, title, `Ra ${fmtNum(t.ra_mm * 1000, 4)} µm, Rz ${fmtNum(t.rz_mm * 1000, 4)} µm, Wt ${fmtNum(t.wt_mm * 1000, 4)} µm; λc ${fmtNum(t.cutoff_mm)} mm (${t.cutoff_source})`);
    // The floor's marks are fractions of a micrometre: shown in µm (heights above its lowest).
    const um = side === 'floor', k = um ? 1000 : 1;
    linePlot(fig, { x: t.y_mm, xLabel: 'evaluation length (mm)', axes: { y: um ? 'height (µm)' : 'height (mm)' }, height: 240,
      series: [{ label: 'primary profile', values: t.primary_mm.map((v) => (v == null ? v : v * k)) },
        { label: 'mean line (W)', values: t.mean_line_mm.map((v) => (v == null ? v : v * k)), width: 2 }] });
  }
  if (w.imprint.x_mm.length) {
    const fig = figure(sec, 'imprint', 'Floor imprint density', 'tooth-pass circles crossing each line x = const, per mm of slot length');
    linePlot(fig, { x: w.imprint.x_mm, xLabel: 'x across the slot (mm)', axes: { y: 'crossings per mm' }, height: 220,
      series: [{ label: 'imprint density', values: w.imprint.crossings_per_mm }] });
  }
}

function mechanismPart() {
  const m = data.mechanism;
  const sec = section('mechanism', 'Cutting mechanism', 'Pivkin 2025: K_re = 100 h / r_e over the trochoid angle with the zones shaded (CZI ploughing, CZII, CZIII cutting), and the chip geometry: h, contact angle ψ, kinematic rake γ_k and angle change κ.');
  if (!m) return;
  const th = m.thresholds, c = m.curve, z = m.summary;
  const shares = z.zone_share ? Object.entries(z.zone_share).map(([k, v]) => `${k} ${(v * 100).toFixed(1)} %`).join(', ') : '';
  const fig = figure(sec, 'mechanism-kre', 'K_re over the cycle', `model ${c.model}${m.other ? ' (and ' + m.other.model + ')' : ''}; r_e ${fmtNum(c.edge_radius_mm * 1000, 4)} µm; shares of the cutting part: ${shares}`);
  const kre = m.use_wear ? c.k_re_wear_pct : c.k_re_pct;
  const series = [{ label: `K_re ${c.model} (%)`, values: kre, width: 2 }];
  let x = c.theta_deg;
  if (m.other) {
    const o = m.other;
    const j = joined([[c.theta_deg, kre], [o.theta_deg, m.use_wear ? o.k_re_wear_pct : o.k_re_pct]]);
    x = j[0];
    series[0].values = j[1];
    series[0].spanGaps = true;
    series.push({ label: `K_re ${o.model} (%)`, values: j[2], dash: [5, 3], spanGaps: true });
  }
  const maxK = Math.max(th.czii_max_pct * 1.5, ...kre.filter((v) => v != null));
  linePlot(fig, {
    x, xLabel: 'trochoid angle θ (°)', axes: { y: 'K_re (%)' }, series, ranges: { y: [0, maxK * 1.05] },
    draw: bands([{ from: 0, to: th.czi_max_pct, fill: ZONE_FILL[0], label: ZONE_NAMES[0] },
      { from: th.czi_max_pct, to: th.czii_max_pct, fill: ZONE_FILL[1], label: ZONE_NAMES[1] },
      { from: th.czii_max_pct, to: maxK * 2, fill: ZONE_FILL[2], label: ZONE_NAMES[2] }]),
  });
  const fig2 = figure(sec, 'mechanism-geometry', 'Chip geometry over the cycle', 'h in mm on the left; angles in degrees on the right');
  linePlot(fig2, {
    x: c.theta_deg, xLabel: 'trochoid angle θ (°)', axes: { y: 'h (mm)', y2: 'angle (°)' },
    series: [{ label: 'h (mm)', values: c.h_mm, scale: 'y', width: 2 }, { label: 'ψ (°)', values: c.psi_deg, scale: 'y2' },
      { label: 'γ_k (°)', values: c.gamma_k_deg, scale: 'y2' }, { label: 'κ (°)', values: c.kappa_deg, scale: 'y2' }],
  });
}

function forceSeriesPlot(sec, id, title, caption, s) {
  const fig = figure(sec, id, title, caption);
  linePlot(fig, {
    x: s.t_s, xLabel: 'time (s)', axes: { y: 'force (N)' },
    series: [{ label: 'F_x (N)', values: s.f_x_n }, { label: 'F_y (N)', values: s.f_y_n }, { label: 'F_z (N)', values: s.f_z_n },
      { label: 'F_R (N)', values: s.f_resultant_n, width: 2, color: '#1d2330' }],
  });
}

function forcesPart() {
  const f = data.forces;
  const sec = section('forces', 'Forces', 'Cutting forces on the workpiece over the window, from the job\'s [material] model with the fast chip source (analytic engagement, axial discs, helix lag): F_x, F_y, F_z, the resultant F_R, spindle torque and power.');
  if (!f) return;
  const s = f.series, sm = f.summary;
  if (sm.note) note(sec, `Note: ${sm.note}.`);
  forceSeriesPlot(sec, 'forces-xyz', `Forces, ${f.label}`, `F_R,max ${fmtNum(sm.f_resultant_max_n)} N; window ${fmtNum(sm.from_s)}-${fmtNum(sm.to_s)} s; ${s.samples} steps, ${s.shown} shown`, s);
  const fig = figure(sec, 'forces-torque', 'Torque and power', `torque max ${fmtNum(sm.torque_max_nm)} N m, power max ${fmtNum(sm.power_max_w)} W`);
  linePlot(fig, { x: s.t_s, xLabel: 'time (s)', axes: { y: 'torque (N m)', y2: 'power (W)' },
    series: [{ label: 'torque (N m)', values: s.torque_nm, scale: 'y' }, { label: 'power (W)', values: s.power_w, scale: 'y2' }] });
  if (f.worn) {
    const w = f.worn.series;
    // The forces swing every tooth pass: drawn raw, two states cover each other. Their
    // envelopes (the largest F_R and the most negative F_z in each of 400 time bins) show
    // the difference.
    const bins = 400;
    const t0 = Math.min(s.t_s[0], w.t_s[0]), t1 = Math.max(s.t_s[s.t_s.length - 1], w.t_s[w.t_s.length - 1]);
    const centres = Array.from({ length: bins }, (_, b) => t0 + ((b + 0.5) / bins) * (t1 - t0));
    const envelope = (t, v, pick) => {
      const out = new Array(bins).fill(null);
      for (let i = 0; i < t.length; i++) {
        if (v[i] == null) continue;
        const b = Math.min(bins - 1, Math.floor(((t[i] - t0) / (t1 - t0)) * bins));
        out[b] = out[b] == null ? v[i] : pick(out[b], v[i]);
      }
      return out;
    };
    const fig2 = figure(sec, 'forces-wear', `New against worn: ${f.label} and ${f.worn.label}`,
      `F_R,max ${fmtNum(sm.f_resultant_max_n)} N against ${fmtNum(f.worn.summary.f_resultant_max_n)} N; envelopes: the largest F_R and the most negative F_z in each of ${bins} time bins`);
    linePlot(fig2, { x: centres, xLabel: 'time (s)', axes: { y: 'force (N)' },
      series: [{ label: `F_R max ${f.label}`, values: envelope(s.t_s, s.f_resultant_n, Math.max), width: 1.8 },
        { label: `F_R max ${f.worn.label}`, values: envelope(w.t_s, w.f_resultant_n, Math.max), width: 1.8 },
        { label: `F_z min ${f.label}`, values: envelope(s.t_s, s.f_z_n, Math.min), dash: [4, 3] },
        { label: `F_z min ${f.worn.label}`, values: envelope(w.t_s, w.f_z_n, Math.min), dash: [4, 3] }] });
  }
}

function calibrationPart() {
  const c = data.calibration;
  if (!c) return;
  const sec = section('calibration', 'Calibration', `The force model fitted to the measured record ${c.measured_file} (Ceres, bounded least squares), the measured forces on the model's clock (shifted by ${fmtNum(c.summary.shift_s)} s) against the fitted model, and the residuals (measured less model, unfiltered).`);
  const table = el('table', { class: 'summary' }, el('tr', {}, el('th', { text: 'parameter' }), el('th', { text: 'value' }), el('th', { text: '95 % interval' })));
  for (const [k, ci] of Object.entries(c.summary.ci95 || {})) {
    table.append(el('tr', {}, el('td', { text: k }), el('td', { class: 'num', text: fmtNum(c.summary[k]) }),
      el('td', { class: 'num', text: `${fmtNum(ci.lo)} .. ${fmtNum(ci.hi)}${ci.at_bound ? ' (at a bound)' : ''}` })));
  }
  sec.append(el('p', { class: 'intro', text: `RMSE ${fmtNum(c.summary.rmse_n)} N, R² ${fmtNum(c.summary.r2)}` }), table);
  if (c.measured) {
    const m = c.measured, s = c.model;
    const fig = figure(sec, 'calibration-fit', 'Measured against model', 'resultant force');
    const j = joined([[m.t_s, m.f_resultant_n], [s.t_s, s.f_resultant_n]]);
    linePlot(fig, { x: j[0], xLabel: 'time (s)', axes: { y: 'F_R (N)' },
      series: [{ label: 'measured F_R (N)', values: j[1], spanGaps: true, color: '#8c959f' }, { label: 'model F_R (N)', values: j[2], spanGaps: true, width: 2 }] });
  }
  const r = c.residual;
  const fig2 = figure(sec, 'calibration-residual', 'Residuals', 'measured (interpolated at the model steps) less model, per axis');
  linePlot(fig2, { x: r.t_s, xLabel: 'time (s)', axes: { y: 'residual (N)' },
    series: [{ label: 'F_x (N)', values: r.f_x_n }, { label: 'F_y (N)', values: r.f_y_n }, { label: 'F_z (N)', values: r.f_z_n }] });
}

function simulationPart() {
  const s = data.simulation;
  if (!s) return;
  const sm = s.summary;
  const sec = section('simulation', 'Simulation', `Bergmann 2021's tri-dexel simulation of the window ${fmtNum(sm.from_s)}-${fmtNum(sm.to_s)} s: the machined surface in 3D, the chip map (largest chip of each edge segment per time bin) and the removed volume per step. The full data are \`simulate --out\`'s files.`);
  if (s.mesh) {
    const m = s.mesh;
    const fig = figure(sec, 'surface-3d', 'Machined surface', `${m.columns} x ${m.rows} grid every ${fmtNum(m.step_mm)} mm, ${m.triangles} triangles (budget ${400000}); drag to orbit, right-drag to pan, wheel to zoom`);
    const z = decodeGrid(m);
    const modeSel = el('select', { id: 'surface-colour' }, el('option', { value: 'height', text: 'colour: height (mm)' }),
      el('option', { value: 'deviation', text: 'colour: deviation from the nominal slot (mm)' }));
    fig.toolbar.append(modeSel);
    const box = el('div', { class: 'view3d' });
    fig.plot.append(box);
    if (typeof TrochomillView3D === 'undefined') {
      note(fig.box, 'The 3D view is missing from this page.');
    } else {
      try {
        const view = TrochomillView3D.createView(box, { grid: m, z, slot: data.path.slot, palette });
        api.views['surface-3d'] = view;
        modeSel.addEventListener('change', () => { view.setColour(modeSel.value); legend(); });
        const zSel = el('select', { id: 'surface-zscale' }, ...[1, 5, 20, 100].map((f) => el('option', { value: f, text: `heights x${f}` })));
        zSel.addEventListener('change', () => view.setZScale(Number(zSel.value)));
        fig.toolbar.append(zSel);
        const barBox = el('div');
        fig.box.append(barBox);
        const legend = () => { barBox.replaceChildren(); const [lo, hi] = view.range(); colorbar(barBox, lo, hi, modeSel.value === 'height' ? 'height (mm)' : 'deviation (mm)'); };
        legend();
        fig.toolbar.append(el('button', { text: 'PNG', onclick: () => download('trochomill-surface-3d.png', view.png()) }));
        if (api.firstDrawMs === null) api.firstDrawMs = performance.now() - t0;
      } catch (err) {
        note(fig.box, `The 3D view needs WebGL, which this browser did not give: ${err.message}`);
      }
    }
  }
  if (s.chip_map) {
    const cm = s.chip_map;
    const fig = figure(sec, 'chip-map', 'Chip map', `largest uncut chip h (mm) per edge segment (${cm.teeth} teeth x ${cm.segments_per_tooth} segments, tooth 0 at the bottom) and time bin; blank: not engaged`);
    const values = decodeGrid(cm);
    heatPlot(fig, { values, columns: cm.columns, rows: cm.rows, x0: cm.t0_s, x1: cm.t1_s, y0: 0, y1: cm.rows,
      xLabel: 'time (s)', yLabel: 'segment', valueLabel: 'h (mm)', lo: cm.min, hi: cm.max });
  }
  if (s.series) {
    const r = s.series;
    const fig = figure(sec, 'sim-removed', 'Removed volume and chip per step', `${r.samples} steps, ${r.shown} shown`);
    linePlot(fig, { x: r.t_s, xLabel: 'time (s)', axes: { y: 'removed per step (mm³)', y2: 'h (mm)' },
      series: [{ label: 'removed (mm³)', values: r.removed_mm3, scale: 'y' }, { label: 'h_max (mm)', values: r.h_max_mm, scale: 'y2' },
        { label: 'h_mean (mm)', values: r.h_mean_mm, scale: 'y2' }] });
  }
  if (s.floor) {
    const f = s.floor;
    const fig = figure(sec, 'floor-map', 'Floor height map', `${f.columns} x ${f.rows} dexels every ${fmtNum(f.dx_mm)} mm (the ISO 25178 input of \`texture --surface floor\`)`);
    heatPlot(fig, { values: decodeGrid(f), columns: f.columns, rows: f.rows, x0: f.x0_mm, x1: f.x0_mm + f.dx_mm * f.columns,
      y0: f.y0_mm, y1: f.y0_mm + f.dy_mm * f.rows, xLabel: 'x (mm)', yLabel: 'y (mm)', valueLabel: 'z (mm)', lo: f.min, hi: f.max });
  } else if (s.floor_note) {
    note(sec, `No floor map: ${s.floor_note}`);
  }
}

function monitorPart() {
  const m = data.monitor;
  if (!m) return;
  const sm = m.summary;
  const sec = section('monitor', 'Acoustic monitor', `Pivkin 2025's k_f = RMS(low band) / RMS(high band) of ${sm.signal} (${fmtNum(sm.rate_hz)} Hz, ${fmtNum(sm.duration_s)} s), per window and per cycle against the cycle phase with the model's zones.`);
  if (sm.flags.length || sm.warnings.length) {
    sec.append(el('ul', { class: 'flags' }, ...sm.flags.map((f) => el('li', { text: 'flag: ' + f })), ...sm.warnings.map((w) => el('li', { text: 'warning: ' + w }))));
  } else {
    sec.append(el('p', { class: 'intro', text: 'no flags' }));
  }
  const k = m.kf;
  const fig = figure(sec, 'monitor-kf', 'k_f over time', `mean k_f ${fmtNum(sm.k_f_mean)}, ${sm.cycles} cycles (${sm.cycle_source}), window ${fmtNum(sm.window_s)} s`);
  linePlot(fig, { x: k.t_s, xLabel: 'time in the recording (s)', axes: { y: 'k_f', y2: 'RMS' },
    series: [{ label: 'k_f', values: k.k_f, scale: 'y', width: 1.6 }, { label: 'RMS low band', values: k.rms_low, scale: 'y2', color: '#8c959f' },
      { label: 'RMS high band', values: k.rms_high, scale: 'y2', color: '#bf8700' }] });
  const cyc = sm.cycle_details || [];
  if (cyc.length && cyc[0].k_f_profile && cyc[0].k_f_profile.length) {
    const bins = cyc[0].k_f_profile.length;
    const phase = Array.from({ length: bins }, (_, b) => (b + 0.5) / bins);
    const series = cyc.map((c, i) => ({ label: `cycle ${i + 1}${c.wear ? ' (wear)' : ''}${c.ploughing ? ' (ploughing)' : ''}`,
      values: c.k_f_profile, color: `hsl(${220 - (160 * i) / Math.max(1, cyc.length - 1)},70%,45%)`, width: 1 }));
    let draw;
    if (sm.model) {
      const zones = sm.model.zone;
      draw = (u) => { // the model's zone of each phase bin as a band along the bottom
        const c = u.ctx;
        const { top, height } = u.bbox;
        for (let b = 0; b < zones.length; b++) {
          if (zones[b] < 1) continue;
          const x0 = u.valToPos(b / zones.length, 'x', true), x1 = u.valToPos((b + 1) / zones.length, 'x', true);
          c.fillStyle = ZONE_FILL[zones[b] - 1];
          c.fillRect(x0, top, x1 - x0, height);
        }
      };
    }
    const fig2 = figure(sec, 'monitor-cycles', 'k_f per cycle against the cycle phase', 'one trace per cycle (blue first, green last); shaded: the model\'s zones (red CZI, amber CZII, green CZIII)');
    linePlot(fig2, { x: phase, xLabel: 'cycle phase', axes: { y: 'k_f' }, series, draw });
  }
  if (m.spectrum) {
    const sp = m.spectrum;
    const fig3 = figure(sec, 'monitor-spectrum', 'Spectrum', 'Welch power spectral density');
    linePlot(fig3, { x: sp.f_hz, xLabel: 'frequency (Hz)', axes: { y: 'PSD (unit²/Hz)' }, logY: true,
      series: [{ label: 'PSD', values: sp.psd.map((v) => (v > 0 ? v : null)) }] });
  }
  if (m.spectrogram) {
    const g = m.spectrogram;
    const fig4 = figure(sec, 'monitor-spectrogram', 'Spectrogram', 'short-time Fourier magnitude (dB), the largest of each cell');
    heatPlot(fig4, { values: decodeGrid(g), columns: g.columns, rows: g.rows, x0: g.t0_s, x1: g.t1_s, y0: g.f0_hz, y1: g.f1_hz,
      xLabel: 'time (s)', yLabel: 'frequency (Hz)', valueLabel: 'dB', lo: g.min, hi: g.max });
  }
}

function studyPart() {
  const st = data.study;
  if (!st) return;
  const sec = section('study', 'Parameter study', 'Every metric of `compare` against the varied parameter (one trace per value of the second, when two are varied). Pick the metric below.');
  const points = st.points.filter((p) => p.ok !== false);
  const failed = st.points.length - points.length;
  if (failed) note(sec, `${failed} of ${st.points.length} points failed: see \`compare\`'s table.`);
  if (!points.length) return;
  const keys = st.vary.map((v) => v.key);
  const metrics = Object.keys(points[0].metrics || {}).filter((k) => typeof points[0].metrics[k] === 'number');
  const fig = figure(sec, 'study', 'Metric against ' + keys[0], `${st.points.length} points over ${keys.join(' x ')}`);
  const select = el('select', { id: 'study-metric' }, ...metrics.map((k) => el('option', { value: k, text: k })));
  fig.toolbar.prepend(select);
  const xsAll = [...new Set(points.map((p) => Number(p.set[keys[0]])))].sort((a, b) => a - b);
  const groups = keys.length > 1 ? [...new Set(points.map((p) => String(p.set[keys[1]])))] : [''];
  const draw = (metric) => {
    fig.plot.replaceChildren();
    fig.toolbar.querySelectorAll('button, .hint').forEach((b) => b.remove());
    const series = groups.map((g) => ({
      label: keys.length > 1 ? `${keys[1]} = ${g}` : metric,
      values: xsAll.map((x) => { const p = points.find((q) => Number(q.set[keys[0]]) === x && (keys.length < 2 || String(q.set[keys[1]]) === g)); return p ? p.metrics[metric] : null; }),
      points: true, spanGaps: true,
    }));
    linePlot(fig, { x: xsAll, xLabel: keys[0], axes: { y: metric }, series });
  };
  select.addEventListener('change', () => draw(select.value));
  const preferred = metrics.includes('mrr_mm3_per_min') ? 'mrr_mm3_per_min' : metrics[0];
  select.value = preferred;
  draw(preferred);
}

function paretoPart() {
  const p = data.pareto;
  if (!p) return;
  const sec = section('pareto', 'Pareto set', `The feasible points of \`trochomill optimize\` that no other point beats in every goal (${p.goals.map((g, i) => `${p.maximize[i] ? 'max' : 'min'} ${g}`).join(', ')}), ${p.points.length} points. The job above is the study's base job.`);
  if (p.goals.length >= 2) {
    const pts = [...p.points].sort((a, b) => a.goals[0] - b.goals[0]);
    const fig = figure(sec, 'pareto-front', `${p.goals[1]} against ${p.goals[0]}`, 'each point a job variant; hover for its values');
    const xs = pts.map((q) => q.goals[0]), ys = pts.map((q) => q.goals[1]);
    const u = new uPlot({
      mode: 2, width: plotWidth(fig.plot), height: 320,
      scales: { x: { time: false }, y: {} },
      axes: [{ label: p.goals[0] }, { label: p.goals[1], size: 70 }],
      series: [{}, { label: 'Pareto set', stroke: COLORS[0], fill: COLORS[0], facets: [{ scale: 'x', auto: true }, { scale: 'y', auto: true }],
        paths: () => null, points: { show: false } }],
      cursor: { drag: { x: true, y: true, uni: 30, setScale: true } },
      legend: { live: false },
      hooks: {
        draw: [(uu) => { // the points, and the front through them
          const c = uu.ctx;
          c.save();
          c.strokeStyle = COLORS[0];
          c.fillStyle = COLORS[0];
          c.beginPath();
          pts.forEach((q, i) => {
            const x = uu.valToPos(q.goals[0], 'x', true), y = uu.valToPos(q.goals[1], 'y', true);
            if (i) c.lineTo(x, y); else c.moveTo(x, y);
          });
          c.stroke();
          for (const q of pts) {
            c.beginPath();
            c.arc(uu.valToPos(q.goals[0], 'x', true), uu.valToPos(q.goals[1], 'y', true), 4 * uPlot.pxRatio, 0, 2 * Math.PI);
            c.fill();
          }
          c.restore();
        }],
        setCursor: [(uu) => {
          const { left, top } = uu.cursor;
          if (left == null || left < 0) return;
          let best = -1, bd = Infinity;
          pts.forEach((q, i) => {
            const d = Math.hypot(uu.valToPos(q.goals[0], 'x') - left, uu.valToPos(q.goals[1], 'y') - top);
            if (d < bd) { bd = d; best = i; }
          });
          if (best >= 0 && bd < 20) {
            const q = pts[best];
            fig.readout.textContent = p.keys.map((k, i) => `${k} = ${q.values[i]}`).join(', ') + '; ' +
              p.goals.map((g, i) => `${g} ${fmtNum(q.goals[i])}`).join(', ');
          }
        }],
      },
    }, [null, [xs, ys]], fig.plot);
    register(fig, u);
    addExports(fig, u, () => [{ label: 'Pareto set', color: COLORS[0] }]);
  }
  const table = el('table', { class: 'summary', id: 'pareto-table' },
    el('tr', {}, ...[...p.keys, ...p.goals].map((k) => el('th', { text: k }))));
  for (const q of p.points) {
    table.append(el('tr', {}, ...q.values.map((v) => el('td', { text: v })),
      ...q.goals.map((g) => el('td', { class: 'num', text: fmtNum(g) }))));
  }
  sec.append(table);
}

// optimize-feed --html: feed, chip and force along the program before and after, over the
// path length (the same place in both programs).
function feedPart() {
  const f = data.feed;
  if (!f) return;
  const s = f.summary;
  const sec = section('feed', 'Feed optimisation', `\`trochomill optimize-feed\`: every piece fed so its largest chip is ${fmtNum(s.h_target_mm)} mm, within the caps and the machine's feed limits; time with acceleration ${fmtNum(s.time_before_with_acceleration_s)} s before, ${fmtNum(s.time_after_with_acceleration_s)} s after (${fmtNum(s.time_saved_percent, 3)} % saved). The sections above analyse the rewritten program.`);
  const q = (k) => s[k] ? [s[k].p50, s[k].p90, s[k].p99, s[k].max] : null;
  const rows = [['h_max (mm)', q('h_max_before_mm'), q('h_max_after_mm')],
    ['removal rate (mm^3/min)', q('mrr_before_mm3_per_min'), q('mrr_after_mm3_per_min')],
    ['resultant force (N)', q('force_before_n'), q('force_after_n')],
    ['spindle power (W)', q('power_before_w'), q('power_after_w')],
    ['spindle torque (N m)', q('torque_before_nm'), q('torque_after_nm')]].filter((r) => r[1]);
  const table = el('table', { class: 'summary', id: 'feed-table' },
    el('tr', {}, ...['over the cutting time', 'before p50', 'p90', 'p99', 'max', 'after p50', 'p90', 'p99', 'max'].map((k) => el('th', { text: k }))));
  for (const [name, b, a] of rows) {
    table.append(el('tr', {}, el('td', { text: name }), ...[...b, ...a].map((v) => el('td', { class: 'num', text: fmtNum(v, 4) }))));
  }
  sec.append(table);
  const shares = Object.entries(s.share_of_feed_time).filter(([, v]) => v > 0)
    .map(([k, v]) => `${k.replace(/_/g, ' ')} ${fmtNum(100 * v, 3)} %`).join(', ');
  sec.append(el('p', { class: 'note', text: `Feed time held by: ${shares}.` }));
  if (s.unheld_axial && s.unheld_axial.length) {
    sec.append(el('p', { class: 'note', text: `Where the axial chip target (${fmtNum(s.h_axial_target_mm, 4)} mm) cannot be held: ${s.unheld_axial.map((u) => `${u.file}:${u.line} (${fmtNum(u.h_max_mm, 4)} mm a tooth at ${fmtNum(u.feed_mm_per_min)} mm/min)`).join('; ')}.` }));
  }
  if (s.unheld.length) {
    sec.append(el('p', { class: 'note', text: `Where the target cannot be held: ${s.unheld.map((u) => `${u.file}:${u.line} (h_max ${fmtNum(u.h_max_mm, 4)} mm at ${fmtNum(u.feed_mm_per_min)} mm/min)`).join('; ')}.` }));
  }
  const overlay = (id, title, caption, key, label, before, after, extra) => {
    const fig = figure(sec, id, title, caption);
    const j = joined([[before.s_mm, before[key]], [after.s_mm, after[key]]]);
    linePlot(fig, { x: j[0], xLabel: 'path length (mm)', axes: { y: label },
      series: [{ label: 'before', values: j[1], spanGaps: false }, { label: 'after', values: j[2], spanGaps: false }], draw: extra });
  };
  overlay('feed-feed', 'Feed along the program', 'before and after; gaps are rapids', 'feed_mm_per_min', 'feed (mm/min)', f.before, f.after);
  overlay('feed-chip', 'Largest chip along the program', 'h_max at every tooth pass; the line is the target', 'h_max_mm', 'h_max (mm)', f.before, f.after,
    (u) => {
      const y = u.valToPos(s.h_target_mm, 'y', true), c = u.ctx;
      c.save();
      c.strokeStyle = '#d1242f';
      c.setLineDash([6, 4]);
      c.beginPath();
      c.moveTo(u.bbox.left, y);
      c.lineTo(u.bbox.left + u.bbox.width, y);
      c.stroke();
      c.restore();
    });
  if (f.force_before) {
    overlay('feed-force', 'Resultant force along the program', 'the [material] model with the fast chip source', 'f_n', 'F_R (N)', f.force_before, f.force_after);
  }
}

// ---- the page ------------------------------------------------------------------------------
const parts = [headerPart, pathPart, engagementPart, wallsPart, mechanismPart, forcesPart, calibrationPart,
  simulationPart, monitorPart, studyPart, paretoPart, feedPart];
for (const part of parts) {
  try {
    part();
  } catch (err) {
    api.errors.push(`${part.name}: ${err.message}`);
    console.error(`trochomill report: ${part.name} failed:`, err);
  }
}
if (!data.mechanism) document.getElementById('mechanism')?.append(el('p', { class: 'note', text: 'not computed for this job (see the summary notes)' }));
if (!data.forces) document.getElementById('forces')?.append(el('p', { class: 'note', text: 'not computed for this job (see the summary notes)' }));

// Plots follow the page's width, and are redrawn at the paper's width when printed.
function resizeAll(width) {
  for (const u of Object.values(api.plots)) {
    const w = width || plotWidth(u.root.parentElement);
    if (Math.abs(w - u.width) > 2) u.setSize({ width: w, height: u.height });
  }
}
let resizeTimer = null;
window.addEventListener('resize', () => { clearTimeout(resizeTimer); resizeTimer = setTimeout(() => resizeAll(), 100); });
window.addEventListener('beforeprint', () => resizeAll(680));
window.addEventListener('afterprint', () => resizeAll());
api.readyMs = performance.now() - t0;
api.ready = true;
document.body.setAttribute('data-ready', '1');
