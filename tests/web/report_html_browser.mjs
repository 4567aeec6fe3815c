// report.html in a real browser (Debian's chromium, headless, driven by playwright-core from web/):
// `quijibo report-html` writes a page for a small results folder (report.md with a table and a
// picture, the shipped bunny and tooth as two meshes, decimated); the page must load from disk with no
// console error and no request leaving the file, the viewer must say it is ready, its canvas must show
// a shaded mesh (a screenshot of the canvas: enough pixels off the background, enough distinct
// colours), and the second mesh's button must change the picture.
//   node report_html_browser.mjs QUIJIBO_BINARY SOURCE_DIR WORK_DIR
// Exit 77 (ctest: skipped) when chromium or web/node_modules is missing, unless CI is set (CI installs
// both with scripts/install-deps.sh, so there their absence is a failure).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';

const [quijibo, source, work] = process.argv.slice(2);
const chromiumPath = process.env.QUIJIBO_CHROMIUM || '/usr/bin/chromium';

function Skip(why) {
  if (process.env.CI) {
    console.error(`report_html_browser: FAILED: ${why} (CI installs it: scripts/install-deps.sh)`);
    process.exit(1);
  }
  console.log(`report_html_browser: SKIPPED: ${why} (scripts/install-deps.sh installs it)`);
  process.exit(77);
}
if (!fs.existsSync(chromiumPath)) Skip(`no chromium at ${chromiumPath}`);
let chromium;
try {
  ({ chromium } = createRequire(path.join(source, 'web', 'package.json'))('playwright-core'));
} catch (e) {
  Skip(`playwright-core is not installed in ${path.join(source, 'web', 'node_modules')}`);
}

const failures = [];
function Check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures.push(what);
}

// The results folder: report.md as `quijibo run` writes it (a title, a table, a picture).
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(path.join(work, 'pictures'), { recursive: true });
fs.copyFileSync(path.join(source, 'docs/images/bunny-optimized-n1-render.png'), path.join(work, 'pictures/render.png'));
fs.writeFileSync(path.join(work, 'report.md'),
                 '# browser-test\n\n## Mesh\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n' +
                 '![the mesh, shaded](pictures/render.png)\n\n*the mesh, shaded*\n');
const t0 = Date.now();
const out = execFileSync(quijibo, ['report-html', work, '--only', '--mesh', `bunny=${source}/data/bunny.obj`,
                                   '--mesh', `tooth=${source}/data/tooth.obj`, '--max-triangles', '20000'],
                         { encoding: 'utf8' });
console.log(out.trim());
const page_path = path.join(work, 'report.html');
const html = fs.readFileSync(page_path, 'utf8');
Check(/<table>/.test(html) && /<img src="data:image\/png;base64,/.test(html), 'the report: its table, its picture embedded');
Check(!/(src|href)="(https?:)?\/\//.test(html), 'no reference to the network');
const tooth = /tooth (\d+) of (\d+) triangles/.exec(out);
Check(tooth && +tooth[1] <= 20000 && +tooth[2] > 20000, 'the tooth decimated to the budget (20000)');

// playwright starts chromium with a new empty profile of its own (no --user-data-dir).
const browser = await chromium.launch({
  executablePath: chromiumPath,
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync', '--use-angle=swiftshader',
         '--enable-unsafe-swiftshader'],
});
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 900 } });
  const errors = [];
  const requests = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.route('**/*', (route) => {
    const url = route.request().url();
    if (!url.startsWith('file:') && !url.startsWith('data:')) {
      requests.push(url);
      return route.abort();
    }
    return route.continue();
  });
  await page.goto('file://' + page_path);
  await page.waitForFunction(() => window.quijiboViewer && window.quijiboViewer.ready, null, { timeout: 60000 });
  const viewer = await page.evaluate(() => ({ shown: window.quijiboViewer.shown, meshes: window.quijiboViewer.meshes }));
  Check(JSON.stringify(viewer.meshes) === '["bunny","tooth"]', `the viewer holds both meshes (${viewer.meshes})`);

  // A screenshot of the canvas, its pixels read back through a 2D canvas in the page.
  async function Shot() {
    const png = await page.locator('#quijibo-canvas').screenshot();
    return page.evaluate(async (b64) => {
      const img = new Image();
      img.src = 'data:image/png;base64,' + b64;
      await img.decode();
      const c = document.createElement('canvas');
      c.width = img.width;
      c.height = img.height;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      // The background: the commonest colour (the viewer's clear colour).
      const count = new Map();
      for (let i = 0; i < d.length; i += 4) {
        const c = (d[i] << 16) | (d[i + 1] << 8) | d[i + 2];
        count.set(c, (count.get(c) || 0) + 1);
      }
      let bgc = 0, most = 0;
      for (const [c, n] of count) if (n > most) { most = n; bgc = c; }
      const bg = [bgc >> 16, (bgc >> 8) & 255, bgc & 255];
      let off = 0;
      for (let i = 0; i < d.length; i += 4)
        if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 24) ++off;
      const colours = count;
      return { width: c.width, height: c.height, colours: colours.size, off: off / (d.length / 4), sum: d.reduce((a, v, i) => (a * 31 + v * (i % 7 + 1)) % 1000000007, 7) };
    }, png.toString('base64'));
  }
  const first = await Shot();
  Check(first.width > 300 && first.height > 200, `the canvas is ${first.width}x${first.height}`);
  Check(first.off > 0.05 && first.off < 0.95, `${(100 * first.off).toFixed(1)} % of the canvas is off the background (5-95 %)`);
  Check(first.colours > 200, `${first.colours} distinct colours (> 200: shaded, not flat)`);
  await page.click('button[data-mesh="tooth"]');
  const second = await Shot();
  const shown = await page.evaluate(() => window.quijiboViewer.shown);
  Check(shown === 'tooth' && second.sum !== first.sum && second.off > 0.05, `the tooth's button shows another picture (${(100 * second.off).toFixed(1)} % off the background)`);
  await page.mouse.move(500, 300);
  await page.mouse.down();
  await page.mouse.move(620, 340, { steps: 5 });
  await page.mouse.up();
  const turned = await Shot();
  Check(turned.sum !== second.sum, 'dragging turns the view');
  fs.writeFileSync(path.join(work, 'screenshot.png'), await page.screenshot({ fullPage: false }));
  Check(errors.length === 0, `no console error${errors.length ? ': ' + errors.join(' | ') : ''}`);
  Check(requests.length === 0, `no request left the page${requests.length ? ': ' + requests.join(', ') : ''}`);
} finally {
  await browser.close();
}
console.log(`report_html_browser: ${failures.length ? 'FAILED' : 'passed'} in ${((Date.now() - t0) / 1000).toFixed(1)} s ` +
            `(page ${(html.length / 1e6).toFixed(2)} MB; screenshot ${path.join(work, 'screenshot.png')})`);
process.exit(failures.length ? 1 : 0);
