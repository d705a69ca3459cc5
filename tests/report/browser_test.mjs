// The HTML report in a real browser: Debian's Chromium, headless, driven by playwright-core
// (from the npm registry into the build tree; it uses the installed browser and downloads
// nothing). Each report is made by the CLI, opened from a file with the network refused, and
// checked for console errors, failed requests, drawn figures, the summary against
// `analyze --json`, the path scrubber against `path --csv`, the 3D view's triangles, printing
// to PDF and a non-blank screenshot (kept in the output folder as an artifact).
//
// Environment: TROCHOMILL_BIN (the CLI), TROCHOMILL_SOURCE (the source tree), TROCHOMILL_WEB
// (the build tree's web folder, with node_modules), TROCHOMILL_TEST_OUT (artifacts),
// CHROMIUM (default /usr/bin/chromium).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdirSync, readFileSync, writeFileSync, existsSync, statSync } from 'node:fs';
import { join } from 'node:path';
import { pathToFileURL } from 'node:url';

const BIN = process.env.TROCHOMILL_BIN;
const SRC = process.env.TROCHOMILL_SOURCE;
const WEB = process.env.TROCHOMILL_WEB;
const OUT = process.env.TROCHOMILL_TEST_OUT;
const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';
for (const [k, v] of Object.entries({ BIN, SRC, WEB, OUT })) assert.ok(v, `set TROCHOMILL_${k}`);
mkdirSync(OUT, { recursive: true });
const { chromium } = await import(pathToFileURL(join(WEB, 'node_modules/playwright-core/index.mjs')).href);

const ex = (p) => join(SRC, 'examples', p);
const cli = (...args) => execFileSync(BIN, args, { encoding: 'utf8', maxBuffer: 1 << 28 });

let browser;
before(async () => {
  browser = await chromium.launch({
    executablePath: CHROMIUM,
    // As root in CI; no GPU (WebGL by SwiftShader); no background connections (the machine has
    // no network, and each refused connection would be noise).
    args: ['--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--no-first-run', '--disable-quic'],
  });
});
after(async () => { await browser?.close(); });

// Opens a report; every request other than the file itself is refused and recorded, as are
// console errors and page errors.
async function open(file) {
  const page = await browser.newPage({ viewport: { width: 1200, height: 900 } });
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('requestfailed', (r) => problems.push(`request failed: ${r.url()}`));
  const url = pathToFileURL(file).href;
  await page.route('**/*', (route) => {
    if (route.request().url() === url) return route.continue();
    problems.push(`request: ${route.request().url()}`);
    return route.abort();
  });
  const t0 = Date.now();
  await page.goto(url);
  await page.waitForFunction(() => window.trochomillReport && window.trochomillReport.ready, null, { timeout: 60000 });
  return { page, problems, loadMs: Date.now() - t0 };
}

// Share of a figure's canvas pixels that are neither transparent nor white, and the number
// of distinct colours among them: a drawn plot has axes, grid and traces.
async function canvasInk(page, id) {
  return page.evaluate((fid) => {
    const u = window.trochomillReport.plots[fid];
    const cv = u.ctx.canvas;
    const d = u.ctx.getImageData(0, 0, cv.width, cv.height).data;
    let ink = 0;
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) {
      if (d[i + 3] === 0 || (d[i] > 250 && d[i + 1] > 250 && d[i + 2] > 250)) continue;
      ink++;
      if (colours.size < 64) colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    }
    return { share: ink / (cv.width * cv.height), colours: colours.size, series: u.series.length - 1 };
  }, id);
}

// The same for a PNG (a screenshot or an export): decoded by the browser itself. With
// `againstCorner`, ink is what differs from the top-left pixel (a view's own background)
// rather than what is not white.
async function pngInk(png, againstCorner = false) {
  const page = await browser.newPage();
  await page.setContent('<canvas id=c></canvas>');
  const r = await page.evaluate(async ([b64, againstCorner]) => {
    const img = new Image();
    img.src = 'data:image/png;base64,' + b64;
    await img.decode();
    const c = document.getElementById('c');
    c.width = img.width; c.height = img.height;
    const x = c.getContext('2d');
    x.drawImage(img, 0, 0);
    const d = x.getImageData(0, 0, c.width, c.height).data;
    let ink = 0;
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) {
      if (againstCorner ? d[i] === d[0] && d[i + 1] === d[1] && d[i + 2] === d[2]
        : d[i] > 245 && d[i + 1] > 245 && d[i + 2] > 245) continue;
      ink++;
      if (colours.size < 256) colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    }
    return { width: c.width, height: c.height, share: ink / (c.width * c.height), colours: colours.size };
  }, [Buffer.from(png).toString('base64'), againstCorner]);
  await page.close();
  return r;
}

// Flattens analyze's JSON to "a.b" keys with scalar values.
function flatten(obj, prefix = '', out = {}) {
  for (const [k, v] of Object.entries(obj)) {
    const key = prefix ? `${prefix}.${k}` : k;
    if (v !== null && typeof v === 'object' && !Array.isArray(v)) flatten(v, key, out);
    else out[key] = v;
  }
  return out;
}

// Linear interpolation of a `path --csv` at time t.
function csvPositionAt(csv, t) {
  const lines = csv.trim().split('\n');
  const head = lines[0].split(',');
  const [it, ix, iy] = ['t_s', 'x_mm', 'y_mm'].map((k) => head.indexOf(k));
  const rows = lines.slice(1).map((l) => l.split(',').map(Number));
  let k = rows.findIndex((r) => r[it] >= t);
  if (k <= 0) k = 1;
  const a = rows[k - 1], b = rows[k];
  const f = (t - a[it]) / (b[it] - a[it]);
  return { x: a[ix] + f * (b[ix] - a[ix]), y: a[iy] + f * (b[iy] - a[iy]) };
}

// What every report must show, and the series each figure draws.
const BASE_FIGURES = {
  'path-top': 7, 'engagement-program': 3, 'engagement-cycle': 3, 'wall-left': 2, 'wall-right': 2,
  'imprint': 1, 'mechanism-kre': 2, 'mechanism-geometry': 4,
};

async function checkReport(t, name, jobArgs, reportArgs, expect) {
  const html = join(OUT, `${name}.html`);
  const t0 = Date.now();
  cli('report', ...jobArgs, ...reportArgs, '-o', html);
  const writeMs = Date.now() - t0;
  const size = statSync(html).size;
  const analysis = JSON.parse(cli('analyze', ...jobArgs, '--json', '-'));
  const { page, problems, loadMs } = await open(html);
  try {
    await t.test('no console error, no failed or outside request', () => {
      assert.deepEqual(problems, []);
    });
    const state = await page.evaluate(() => ({
      errors: window.trochomillReport.errors, figures: window.trochomillReport.figures,
      firstDrawMs: window.trochomillReport.firstDrawMs, readyMs: window.trochomillReport.readyMs,
    }));
    await t.test('every figure is drawn with its traces', async () => {
      assert.deepEqual(state.errors, []);
      const want = { ...BASE_FIGURES, ...expect.figures };
      for (const id of Object.keys(want)) assert.ok(state.figures.includes(id), `figure ${id} missing`);
      for (const id of state.figures) {
        if (id === 'surface-3d') continue; // WebGL: checked below
        const ink = await canvasInk(page, id);
        // Axes, grid and at least one trace: over 0.3 % of the canvas inked in over 3 colours
        // (an empty uPlot canvas has its axes only: under 0.2 % and 2 colours here).
        assert.ok(ink.share > 0.003 && ink.colours > 3, `${id}: blank (${JSON.stringify(ink)})`);
        if (want[id] !== undefined) assert.equal(ink.series, want[id], `${id}: series`);
      }
    });
    await t.test('the summary holds analyze --json\'s numbers', async () => {
      const cells = await page.evaluate(() => Object.fromEntries(
        [...document.querySelectorAll('#summary-table tr[data-key]')].map((r) => [r.dataset.key, JSON.parse(r.children[1].dataset.value)])));
      const flat = flatten(analysis);
      let numbers = 0;
      for (const [k, v] of Object.entries(flat)) {
        assert.ok(k in cells, `summary key ${k} missing`);
        // The same formatter and inputs: equal to the last bit (JSON round trip of a double).
        assert.deepEqual(cells[k], v, k);
        if (typeof v === 'number') numbers++;
      }
      assert.ok(numbers > 30, `only ${numbers} numbers`);
      // The headline first: the figures that matter, each analyze's own number shown to 4
      // significant digits; the full table folded below it.
      const head = await page.evaluate(() => [...document.querySelectorAll('#summary-headline tr[data-key]')]
        .map((r) => [r.dataset.key, JSON.parse(r.children[1].dataset.value), r.children[1].textContent]));
      assert.ok(head.length >= 6, `headline of ${head.length} figures`);
      for (const [k, v, shown] of head) {
        assert.deepEqual(v, flat[k], k);
        assert.equal(Number(shown), Number(v.toPrecision(4)), `${k} shown as ${shown}`);
      }
      // And `analyze`'s text shows the same figures as the same text (one rounding for both).
      const text = cli('analyze', ...jobArgs);
      const inText = ['machining_time_with_acceleration_s', 'path_length_mm', 'mrr_total_mm3_per_min',
        'removed_volume_mm3', 'engagement_angle_max_deg', 'cycle_time_s', 'cycle_mrr_mm3_per_min',
        'cycle_h_max_mm', 'cycle_engagement_angle_max_deg'];
      let compared = 0;
      for (const [k, , shown] of head) {
        if (!inText.includes(k)) continue;
        compared++;
        assert.match(text, new RegExp(`[ (]${shown.replace('.', '\\.')} `), `${k}: ${shown} not in analyze's text\n${text}`);
      }
      assert.ok(compared >= 4, `${compared} headline figures compared with analyze's text`);
      assert.equal(await page.evaluate(() => document.querySelector('#summary-all').open), false);
    });
    await t.test('the path slider moves the tool disc to the planned position', async () => {
      const d = await page.evaluate(() => ({ T: window.trochomillReport.data.path.duration_s, dt: window.trochomillReport.data.path.dt_s }));
      const csv = cli('path', ...jobArgs, '--dt', String(d.dt / 10), '--csv', '-');
      const lines = csv.trim().split('\n');
      const head = lines[0].split(',');
      const ik = head.indexOf('curvature_per_mm'), is = head.indexOf('s_mm'), it = head.indexOf('t_s');
      let kMax = 0, vMax = 0;
      let prev = null;
      for (const l of lines.slice(1)) {
        const r = l.split(',').map(Number);
        kMax = Math.max(kMax, Math.abs(r[ik]));
        if (prev) vMax = Math.max(vMax, (r[is] - prev[is]) / Math.max(1e-12, r[it] - prev[it]));
        prev = r;
      }
      // The page interpolates linearly between its samples dt apart: a chord of length
      // v dt deviates from the curve by at most (v dt)^2 kappa / 8; the coordinates carry six
      // significant digits (under 100 mm: 5e-5 mm); the reference's own chords are 10x finer.
      const chord = vMax * d.dt;
      const tol = (chord * chord * kMax) / 8 * 1.01 + 1e-4;
      for (const f of [0.137, 0.5, 0.861]) {
        const t = f * d.T;
        const q = await page.evaluate((tt) => window.trochomillReport.setTime(tt), t);
        const want = csvPositionAt(csv, q.t);
        const err = Math.hypot(q.x - want.x, q.y - want.y);
        assert.ok(err <= tol, `t ${q.t}: tool at (${q.x}, ${q.y}), planned (${want.x}, ${want.y}), error ${err} > ${tol} mm`);
        // The disc drawn is the tool circle around that point.
        const disc = await page.evaluate(() => { const u = window.trochomillReport.plots['path-top']; return u.data[6]; });
        const r = Math.hypot(disc[0][0] - q.x, disc[1][0] - q.y);
        const R = await page.evaluate(() => window.trochomillReport.data.path.tool_radius_mm);
        assert.ok(Math.abs(r - R) < 1e-9, `disc radius ${r} against ${R}`);
      }
    });
    if (expect.check) await expect.check(t, page);
    await t.test('a screenshot is not blank, and the page prints to PDF', async () => {
      const png = await page.screenshot({ fullPage: true });
      writeFileSync(join(OUT, `${name}.png`), png);
      const ink = await pngInk(png);
      assert.ok(ink.height > 3000, `page height ${ink.height}`);
      assert.ok(ink.share > 0.03 && ink.colours > 40, `screenshot blank: ${JSON.stringify(ink)}`);
      const pdf = await page.pdf({ format: 'A4', printBackground: true });
      writeFileSync(join(OUT, `${name}.pdf`), pdf);
      assert.equal(pdf.subarray(0, 5).toString(), '%PDF-');
      const pages = (pdf.toString('latin1').match(/\/Type\s*\/Page[^s]/g) || []).length;
      assert.ok(pages >= 3, `${pages} PDF pages`);
    });
    writeFileSync(join(OUT, `${name}.timing.json`), JSON.stringify({ writeMs, size, loadMs, ...state }, null, 1));
  } finally {
    await page.close();
  }
}

test('Wagih 2023 elliptical: the default report', async (t) => {
  await checkReport(t, 'wagih-elliptical', [ex('wagih2023/elliptical.toml')], [], {
    // The published chip model is the circular trochoid's: one K_re trace here.
    figures: { 'texture-left': 2, 'texture-right': 2, 'mechanism-kre': 1 },
    check: async (tt, page) => {
      await tt.test('the example\'s P20 gives the cutting force alone, and the page says so', async () => {
        const text = await page.locator('#forces').innerText();
        assert.match(text, /p20-kienzle gives the force along the cutting direction only/);
        assert.match(await page.locator('#summary').innerText(), /cutting direction only/);
      });
    },
  });
});

test('Bergmann 2021: forces new against worn, and the simulation in 3D', async (t) => {
  const sim = ['--set', 'simulation.resolution=0.1', '--set', 'simulation.steps_per_rev=36'];
  await checkReport(t, 'bergmann', [ex('bergmann2021/trochoidal.toml'), ...sim], ['--with', 'simulate', '--cycles', '3:4'], {
    figures: { 'forces-xyz': 4, 'forces-torque': 2, 'forces-wear': 4, 'chip-map': 1, 'sim-removed': 3, 'surface-3d': undefined },
    check: async (tt, page) => {
      await tt.test('the forces\' peaks equal `forces --fast --json`', async () => {
        const f = JSON.parse(cli('forces', ex('bergmann2021/trochoidal.toml'), ...sim, '--fast', '--cycles', '3:4', '--json', '-'));
        const worn = JSON.parse(cli('forces', ex('bergmann2021/trochoidal.toml'), ...sim, '--set', 'topography.state=1', '--fast', '--cycles', '3:4', '--json', '-'));
        const page_ = await page.evaluate(() => window.trochomillReport.data.forces);
        for (const k of ['f_resultant_max_n', 'f_x_max_n', 'f_z_max_n', 'torque_max_nm', 'power_max_w']) {
          assert.equal(page_.summary[k], f[k], k);
          assert.equal(page_.worn.summary[k], worn[k], `worn ${k}`);
        }
        // Decimation keeps every extreme: the largest resultant drawn is the summary's (to
        // the six significant digits the page carries).
        const drawn = Math.max(...page_.series.f_resultant_n);
        assert.ok(Math.abs(drawn - f.f_resultant_max_n) <= 5e-6 * f.f_resultant_max_n, `${drawn} against ${f.f_resultant_max_n}`);
      });
      await tt.test('the 3D view holds the mesh\'s triangles and draws them', async () => {
        const v = await page.evaluate(() => {
          const view = window.trochomillReport.views['surface-3d'];
          const m = window.trochomillReport.data.simulation.mesh;
          return { triangles: view.triangles, meshTriangles: m.triangles, columns: m.columns, rows: m.rows, png: view.png().split(',')[1] };
        });
        assert.equal(v.triangles, v.meshTriangles);
        assert.equal(v.triangles, 2 * (v.columns - 1) * (v.rows - 1));
        assert.ok(v.triangles > 10000 && v.triangles <= 400000, `${v.triangles} triangles`);
        const ink = await pngInk(Buffer.from(v.png, 'base64'));
        // The surface fills a good part of the view in more than a few shades.
        assert.ok(ink.share > 0.1 && ink.colours > 20, `3D view blank: ${JSON.stringify(ink)}`);
        // And on the page as a reader sees it (the compositor's pixels, SwiftShader's WebGL in
        // headless Chromium): a blank view is its background colour alone; the surface covers
        // about a quarter of it at the default camera (0.1 leaves room for other cameras).
        const view3d = page.locator('#fig-surface-3d .view3d');
        await view3d.scrollIntoViewIfNeeded();
        const shot = await pngInk(await view3d.screenshot(), true);
        assert.ok(shot.share > 0.1 && shot.colours > 20, `3D view blank on the page: ${JSON.stringify(shot)}`);
        await page.selectOption('#surface-colour', 'deviation');
        const range = await page.evaluate(() => window.trochomillReport.views['surface-3d'].range());
        // Deviation from the nominal slot: the floor at -depth is 0; stock left inside the
        // slot's outline stands up to the depth (1 mm) above it.
        assert.ok(range[0] > -0.05 && range[1] <= 1.0 + 1e-3, `deviation range ${range}`);
      });
    },
  });
});

test('Pivkin 2025: mechanism with both chip models and the acoustic monitor', async (t) => {
  const wav = join(OUT, 'pivkin-synthetic.wav');
  cli('synth-signal', ex('pivkin2025/trochoidal.toml'), '-o', wav, '--cycles', '6', '--wear-drift', '0.8');
  await checkReport(t, 'pivkin', [ex('pivkin2025/trochoidal.toml')], ['--signal', wav, '--start', '0.1'], {
    figures: { 'monitor-kf': 3, 'monitor-cycles': 6, 'monitor-spectrum': 1, 'monitor-spectrogram': 1 },
    check: async (tt, page) => {
      await tt.test('the monitor\'s numbers equal `monitor --json`', async () => {
        const m = JSON.parse(cli('monitor', wav, '--job', ex('pivkin2025/trochoidal.toml'), '--start', '0.1', '--json', '-'));
        const s = await page.evaluate(() => window.trochomillReport.data.monitor.summary);
        assert.deepEqual(s.k_f_per_cycle, m.k_f_per_cycle);
        assert.deepEqual(s.flags, m.flags);
      });
      await tt.test('the mechanism\'s zone shares equal `mechanism --json`', async () => {
        const m = JSON.parse(cli('mechanism', ex('pivkin2025/trochoidal.toml'), '--json', '-'));
        const s = await page.evaluate(() => window.trochomillReport.data.mechanism);
        assert.deepEqual(s.summary.zone_share, m.zone_share);
        assert.equal(s.curve.model, 'exact');
        assert.equal(s.other.model, 'pivkin2025');
      });
    },
  });
});

test('calibration against a measured record, a parameter study, and the exports', async (t) => {
  // A "measured" record made by the model itself (fast chips, library coefficients), fitted
  // from a wrong k_c: the fit must reproduce it.
  const berg = ex('bergmann2021/trochoidal.toml');
  const meas = join(OUT, 'measured.csv');
  cli('forces', berg, '--fast', '--from', '134', '--to', '134.5', '--set', 'forces.fast_steps_per_rev=400', '--csv', meas);
  const html = join(OUT, 'calibration.html');
  cli('report', berg, '--measured', meas, '--set', 'material.k_c=1500', '-o', html);
  const { page, problems } = await open(html);
  await t.test('measured against model, and the residuals', async () => {
    assert.deepEqual(problems, []);
    assert.equal((await canvasInk(page, 'calibration-fit')).series, 2);
    assert.equal((await canvasInk(page, 'calibration-residual')).series, 3);
    const c = await page.evaluate(() => window.trochomillReport.data.calibration);
    // The record is the model at other time steps (400 per revolution against the report's
    // own): a near-perfect fit, residuals a few percent of the force at most (the force
    // jumps as each insert enters fall between different steps).
    assert.ok(c.summary.r2 > 0.99, `R2 ${c.summary.r2}`);
    assert.ok(Math.abs(c.summary.k_c - 1926.08) / 1926.08 < 0.02, `k_c ${c.summary.k_c}`);
    const peak = Math.max(...c.model.f_resultant_n);
    const rms = Math.sqrt(c.residual.f_x_n.filter((v) => v != null).reduce((a, v) => a + v * v, 0) / c.residual.f_x_n.length);
    assert.ok(rms < 0.05 * peak, `residual RMS ${rms} N against ${peak} N`);
  });
  await page.close();

  const study = join(OUT, 'study.html');
  cli('report', ex('wagih2023/elliptical.toml'), '--vary', 'path.aspect_ratio=0.8,1.0,1.2', '-o', study);
  const s = await open(study);
  await t.test('the study plots any metric against the varied key', async () => {
    assert.deepEqual(s.problems, []);
    const compare = JSON.parse(cli('compare', ex('wagih2023/elliptical.toml'), '--vary', 'path.aspect_ratio=0.8,1.0,1.2', '--json', '-'));
    await s.page.selectOption('#study-metric', 'h_max_mm');
    const drawn = await s.page.evaluate(() => { const u = window.trochomillReport.plots.study; return [u.data[0], u.data[1]]; });
    assert.deepEqual(drawn[0], [0.8, 1.0, 1.2]);
    assert.deepEqual(drawn[1], compare.points.map((p) => p.metrics.h_max_mm));
  });
  await t.test('a figure exports as PNG and as SVG', async () => {
    const [png] = await Promise.all([s.page.waitForEvent('download'), s.page.click('#fig-engagement-program button:text("PNG")')]);
    const pngPath = join(OUT, 'export.png');
    await png.saveAs(pngPath);
    const ink = await pngInk(readFileSync(pngPath));
    assert.ok(ink.share > 0.02 && ink.colours > 10, `PNG export blank: ${JSON.stringify(ink)}`);
    const [svg] = await Promise.all([s.page.waitForEvent('download'), s.page.click('#fig-engagement-program button:text("SVG")')]);
    const svgPath = join(OUT, 'export.svg');
    await svg.saveAs(svgPath);
    const text = readFileSync(svgPath, 'utf8');
    assert.match(text, /^<svg xmlns/);
    // One path per trace (3), each with hundreds of points.
    const paths = [...text.matchAll(/<path d="([^"]*)"/g)].map((m) => m[1]);
    assert.equal(paths.length, 3);
    for (const d of paths) assert.ok((d.match(/[ML]/g) || []).length > 100, 'a trace with few points');
    assert.match(text, /engagement angle/);
  });
  await s.page.close();
});

test('the same command writes the same page, whatever the thread count', () => {
  const job = ex('bergmann2021/trochoidal.toml');
  const args = (threads) => ['report', job, '--with', 'simulate', '--cycles', '3:4', '--set', 'simulation.resolution=0.2',
    '--set', 'simulation.steps_per_rev=24', '--set', `simulation.threads=${threads}`];
  const a = join(OUT, 'same-a.html'), b = join(OUT, 'same-b.html'), c = join(OUT, 'same-c.html');
  cli(...args(1), '-o', a);
  cli(...args(1), '-o', b);
  cli(...args(2), '-o', c);
  assert.ok(readFileSync(a).equals(readFileSync(b)), 'two runs of one command differ');
  // With another thread count only the recorded command and overrides differ.
  const strip = (f) => readFileSync(f, 'utf8').replace(/simulation\.threads=\d/g, 'simulation.threads=N');
  assert.equal(strip(a), strip(c));
});

test('optimize --html shows the Pareto set it wrote', async () => {
  const job = join(OUT, 'linear.toml');
  writeFileSync(job, readFileSync(ex('wagih2023/trochoidal.toml'), 'utf8').replace('type = "trochoidal"', 'type = "linear"'));
  const csv = join(OUT, 'pareto.csv'), html = join(OUT, 'pareto.html');
  cli('optimize', job, '--var', 'cutting.feed_rate=100:2000', '--maximize', 'mrr_total_mm3_per_min', '--minimize', 'h_max_mm',
    '--max-evals', '32', '--population', '8', '--pareto', csv, '--html', html);
  const rows = readFileSync(csv, 'utf8').trim().split('\n').slice(1).map((l) => l.split(','));
  const { page, problems } = await open(html);
  assert.deepEqual(problems, []);
  const ink = await canvasInk(page, 'pareto-front');
  assert.ok(ink.share > 0.003 && ink.colours > 3, JSON.stringify(ink));
  const cells = await page.evaluate(() => [...document.querySelectorAll('#pareto-table tr')].slice(1).map((r) => [...r.children].map((c) => c.textContent)));
  assert.equal(cells.length, rows.length);
  // The same points in the same order, the goals to the six digits the page shows.
  cells.forEach((c, i) => {
    assert.equal(c[0], rows[i][0]);
    for (const g of [1, 2]) assert.ok(Math.abs(Number(c[g]) - Number(rows[i][g])) <= 5e-6 * Math.abs(Number(rows[i][g])), `${c[g]} ${rows[i][g]}`);
  });
  await page.close();
});

test('optimize-feed --html shows feed, chip and force before and after', async () => {
  // Bergmann 2021's slot (a [material] model: forces too), shortened, in LinuxCNC's language.
  const job = join(OUT, 'bergmann-linuxcnc.toml');
  writeFileSync(job, readFileSync(ex('bergmann2021/trochoidal.toml'), 'utf8').replace('dialect = "sinumerik"', 'dialect = "linuxcnc"'));
  const prog = join(OUT, 'bergmann.ngc'), fast = join(OUT, 'bergmann-fast.ngc');
  const html = join(OUT, 'optimize-feed.html'), summary = join(OUT, 'optimize-feed.json');
  cli('plan', job, '--set', 'slot.length=1', '-o', prog);
  cli('optimize-feed', prog, '--job', job, '--set', 'slot.length=1', '-o', fast, '--json', summary, '--html', html);
  const s = JSON.parse(readFileSync(summary, 'utf8'));
  const { page, problems } = await open(html);
  assert.deepEqual(problems, []);
  for (const id of ['feed-feed', 'feed-chip', 'feed-force']) {
    const ink = await canvasInk(page, id);
    assert.ok(ink.share > 0.003 && ink.colours > 3, `${id}: ${JSON.stringify(ink)}`);
  }
  // The page's data is the summary the command wrote, and its table shows it.
  const data = await page.evaluate(() => window.trochomillReport.data.feed.summary);
  assert.equal(data.time_after_s, s.time_after_s);
  const cells = await page.evaluate(() => [...document.querySelectorAll('#feed-table tr')][1].textContent);
  assert.match(cells, /h_max/);
  assert.ok(cells.includes(String(Number(s.h_max_after_mm.max.toPrecision(4)))), `${cells} ${s.h_max_after_mm.max}`);
  await page.close();
});

test('a job whose text holds "</script>" cannot break out of the page', async () => {
  const job = join(OUT, 'script-in-comment.toml');
  writeFileSync(job, readFileSync(ex('wagih2023/circular.toml'), 'utf8') + '\n# </script><script>document.title="broken"</script>\n');
  const html = join(OUT, 'script-in-comment.html');
  cli('report', job, '-o', html);
  const { page, problems } = await open(html);
  assert.deepEqual(problems, []);
  assert.notEqual(await page.title(), 'broken');
  assert.match(await page.evaluate(() => window.trochomillReport.data.job_text), /<\/script><script>/);
  await page.close();
});

test('bad input: exit 2, the precise message, no report file', () => {
  const html = join(OUT, 'never.html');
  const bad = join(OUT, 'bad-columns.csv');
  writeFileSync(bad, 'time,a,b\n0,1,2\n0.1,1,2\n');
  const cases = [
    [['--with', 'simulate,plots'], /--with 'plots': unknown item; allowed: mechanism, forces, simulate/],
    [['--signal', join(OUT, 'pivkin-synthetic.wav')], /--signal needs --start/],
    [['--measured', bad], /bad-columns\.csv.*(column|t_s)/],
  ];
  for (const [args, message] of cases) {
    const job = args[0] === '--measured' ? ex('bergmann2021/trochoidal.toml') : ex('pivkin2025/trochoidal.toml');
    const r = spawnSync(BIN, ['report', job, ...args, '-o', html], { encoding: 'utf8' });
    assert.equal(r.status, 2, `${args.join(' ')}: exit ${r.status}\n${r.stderr}`);
    assert.match(r.stderr, message);
    assert.ok(!existsSync(html), 'a report was written');
  }
});
