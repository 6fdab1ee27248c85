// Opens a report page (svbtdf report) from file:// in Debian's headless chromium (puppeteer-core,
// pinned in package-lock.json; WebGL through SwiftShader) and writes what a person would check,
// as JSON, for tests/report/report_browser_test.cc (docs/report.md, "Checked in a browser"):
//
//   node browser_check.js REPORT/index.html --json OUT.json [--screenshots DIR]
//
// console errors and failed requests; images that did not load; the live view's canvas in both
// modes (distinct colours, share of pixels unlike the clear colour); a click on a map's texel and
// what the slice canvases then hold; the live view's difference from svbtdf render; load time.
'use strict';
const path = require('path');
const fs = require('fs');
const puppeteer = require('puppeteer-core');

function argument(name) {
  const k = process.argv.indexOf(name);
  return k > 0 ? process.argv[k + 1] : undefined;
}

// Pixel statistics of a canvas: distinct colours and the share of pixels unlike the corner's.
async function canvasStats(page, id) {
  return page.evaluate((id) => {
    const source = document.getElementById(id);
    const copy = document.createElement('canvas');
    copy.width = source.width; copy.height = source.height;
    const g = copy.getContext('2d');
    g.drawImage(source, 0, 0);
    const d = g.getImageData(0, 0, copy.width, copy.height).data;
    const colours = new Set();
    let differing = 0;
    const corner = [d[0], d[1], d[2]];
    for (let k = 0; k < d.length; k += 4) {
      colours.add((d[k] << 16) | (d[k + 1] << 8) | d[k + 2]);
      if (Math.abs(d[k] - corner[0]) + Math.abs(d[k + 1] - corner[1]) + Math.abs(d[k + 2] - corner[2]) > 6) ++differing;
    }
    return { distinct_colours: colours.size, differing_fraction: differing / (d.length / 4) };
  }, id);
}

async function main() {
  const page_file = path.resolve(process.argv[2]);
  const out = argument('--json'), shots = argument('--screenshots');
  const result = { page: page_file, console_errors: [], failed_requests: [], page_errors: [] };
  const started = Date.now();
  const browser = await puppeteer.launch({
    executablePath: process.env.SVBTDF_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
           '--disable-dev-shm-usage'],
  });
  try {
    const page = await browser.newPage();
    await page.setViewport({ width: 1280, height: 900 });
    page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
    page.on('pageerror', (e) => result.page_errors.push(String(e)));
    page.on('requestfailed', (r) => result.failed_requests.push(r.url()));
    const load_started = Date.now();
    await page.goto('file://' + page_file, { waitUntil: 'load', timeout: 120000 });
    try {
      await page.waitForFunction(() => window.SVBTDF_PAGE && window.SVBTDF_PAGE.ready, { timeout: 120000 });
    } catch (error) {
      // Say why: what the page logged before it failed to get ready.
      throw new Error(`the page never got ready: ${error}; console errors: ${JSON.stringify(result.console_errors)}; ` +
                      `page errors: ${JSON.stringify(result.page_errors)}`);
    }
    result.load_seconds = (Date.now() - load_started) / 1000;
    result.page_state_errors = await page.evaluate(() => window.SVBTDF_PAGE.errors);
    result.images = await page.evaluate(() => Array.from(document.images).map((i) => ({
      src: i.getAttribute('src'), loaded: i.complete && i.naturalWidth > 0 })));
    result.sections = await page.evaluate(() => Array.from(document.querySelectorAll('section')).map((s) => s.id));

    // The live view in both modes.
    result.live = {};
    for (const mode of ['gltf', 'sg']) {
      const has = await page.evaluate((m) => !!document.querySelector(`.tabs button[data-mode="${m}"]`), mode);
      if (!has) continue;
      await page.evaluate((m) => window.SVBTDF_PAGE.setMode(m), mode);
      await new Promise((r) => setTimeout(r, 300));
      result.live[mode] = await canvasStats(page, 'viewer');
      if (shots) {
        const box = await page.$('.live');
        await box.screenshot({ path: path.join(shots, `report-live-${mode}.png`) });
      }
    }
    result.sg_difference = await page.evaluate(() => window.SVBTDF_PAGE.sgDifference);

    // A click on the alpha map, off its centre: the inspector must draw that texel's slice.
    const before = await page.evaluate(() => window.SVBTDF_PAGE.inspected);
    const map = await page.$('figure.map img');
    await map.scrollIntoView();
    const box = await map.boundingBox();
    await map.click({ offset: { x: box.width * 0.2, y: box.height * 0.3 } });
    result.inspected_before = before;
    result.inspected = await page.evaluate(() => window.SVBTDF_PAGE.inspected);
    result.slice_measured = await canvasStats(page, 'slice-measured');
    result.slice_fitted = await canvasStats(page, 'slice-fitted');
    result.ndf_fitted = await canvasStats(page, 'ndf-fitted');
    if (shots) {
      await (await page.$('#inspect')).screenshot({ path: path.join(shots, 'report-inspect.png') });
      await (await page.$('#maps')).screenshot({ path: path.join(shots, 'report-maps.png') });
      await (await page.$('#numbers')).screenshot({ path: path.join(shots, 'report-numbers.png') });
      await (await page.$('#calibration')).screenshot({ path: path.join(shots, 'report-calibration.png') });
    }
  } finally {
    await browser.close();
  }
  result.total_seconds = (Date.now() - started) / 1000;
  const text = JSON.stringify(result, null, 2);
  if (out) fs.writeFileSync(out, text + '\n'); else console.log(text);
}

main().catch((e) => { console.error('browser_check: ' + (e && e.stack || e)); process.exit(1); });
