// The HTML report's performance (docs/PERFORMANCE.md, "The HTML report"):
//  1. `trochomill report` of the Wagih 2023 elliptical example with plan, analyze, mechanism,
//     fast forces and the HTML (a stand-in force model: the paper's P20 steel has none in the
//     materials library; the model only sets the numbers, not the work);
//  2. the HTML of a report whose force series has about a million samples;
//  3. the page interactive (its first figure drawn) in headless Chromium.
// Each time is the median of `runs` runs.
//   node bench/report_bench.mjs build/bin/trochomill build/web [runs]
import { execFileSync } from 'node:child_process';
import { mkdtempSync, statSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

const [bin, web, runsArg] = process.argv.slice(2);
if (!bin || !web) {
  console.error('usage: node bench/report_bench.mjs <trochomill> <build/web> [runs]');
  process.exit(2);
}
const runs = Number(runsArg || 5);
const src = resolve(new URL('..', import.meta.url).pathname);
const dir = mkdtempSync(join(tmpdir(), 'trochomill-report-bench-'));
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const time = (f) => { const t = process.hrtime.bigint(); f(); return Number(process.hrtime.bigint() - t) / 1e9; };

const wagih = join(src, 'examples/wagih2023/elliptical.toml');
const wagihHtml = join(dir, 'wagih.html');
const wagihArgs = ['report', wagih, '--set', 'material.name=al7075-t6-linear', '-o', wagihHtml];
const tw = [];
for (let i = 0; i < runs; i++) tw.push(time(() => execFileSync(bin, wagihArgs, { stdio: 'pipe' })));
console.log(`wagih elliptical report (plan + analyze + mechanism + forces + HTML): median ${median(tw).toFixed(3)} s of ${runs} (${tw.map((t) => t.toFixed(3)).join(', ')}), ${(statSync(wagihHtml).size / 1e6).toFixed(2)} MB`);

// Bergmann's trochoid with the fast chips at 600 steps per revolution and 796 rpm: about
// 8000 force steps per second of program; 126 s of it is a million.
const berg = join(src, 'examples/bergmann2021/trochoidal.toml');
const bigHtml = join(dir, 'bergmann-1m.html');
const tb = time(() => execFileSync(bin, ['report', berg, '--from', '100', '--to', '226', '--set', 'forces.fast_steps_per_rev=600', '-o', bigHtml], { stdio: 'pipe' }));
const doc = readFileSync(bigHtml, 'utf8');
const data = JSON.parse(doc.match(/<script type="application\/json" id="trochomill-data">([\s\S]*?)<\/script>/)[1].replace(/<\\\//g, '</'));
console.log(`bergmann forces over 100-226 s: ${data.forces.series.samples} force samples (${data.forces.series.shown} drawn), HTML ${(statSync(bigHtml).size / 1e6).toFixed(2)} MB, written in ${tb.toFixed(2)} s`);

const { chromium } = await import(pathToFileURL(join(resolve(web), 'node_modules/playwright-core/index.mjs')).href);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run'],
});
for (const [name, file] of [['wagih', wagihHtml], ['bergmann-1m', bigHtml]]) {
  const first = [], ready = [], load = [];
  for (let i = 0; i < runs; i++) {
    const page = await browser.newPage({ viewport: { width: 1200, height: 900 } });
    const t0 = Date.now();
    await page.goto(pathToFileURL(file).href);
    await page.waitForFunction(() => window.trochomillReport && window.trochomillReport.ready);
    load.push((Date.now() - t0) / 1000);
    const r = await page.evaluate(() => [window.trochomillReport.firstDrawSinceNavigationMs, window.trochomillReport.readyMs]);
    first.push(r[0] / 1000);
    ready.push(r[1] / 1000);
    await page.close();
  }
  console.log(`${name} in headless Chromium: first figure drawn ${median(first).toFixed(3)} s after the navigation started, all figures ${median(ready).toFixed(3)} s after the script started; goto to ready seen by the driver ${median(load).toFixed(3)} s (medians of ${runs})`);
}
await browser.close();
