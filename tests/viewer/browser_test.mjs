// End-to-end test of `pdyn serve` in a real browser: Debian's Chromium,
// headless, driven by playwright-core (viewer/node_modules; no browser
// download). Starts the server on a free port with the 100 x 100 cloth,
// then: the canvas changes between frames; a particle dragged with the mouse
// moves toward the cursor (read back through /api/state); a nailed particle
// stays put while the simulation runs; a created particle is attached to
// the cloth by a new link; pause + step advances exactly one step; Ctrl-C
// stops the server with status 0. With --constraint-scene (the double
// pendulum), a second server: the page draws its two rods as constraint
// segments and lists the constraint, and a bob dragged with the mouse moves
// while its rods keep their lengths. Screenshots go to --artifacts.
//
//   node tests/viewer/browser_test.mjs --pdyn build/bin/pdyn --chromium /usr/bin/chromium \
//        --scene configs/hanging_cloth.yaml --artifacts build/artifacts/viewer \
//        [--constraint-scene configs/double_pendulum.yaml]
import { spawn } from 'node:child_process';
import { mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(resolve(here, '../../viewer/package.json'));
const { chromium } = require('playwright-core');

const args = Object.fromEntries(process.argv.slice(2).reduce((acc, a, i, all) =>
  a.startsWith('--') ? [...acc, [a.slice(2), all[i + 1]]] : acc, []));
for (const key of ['pdyn', 'scene', 'artifacts']) {
  if (!args[key]) { console.error(`usage: browser_test.mjs --pdyn BIN --scene YAML --artifacts DIR [--chromium BIN] [--constraint-scene YAML]`); process.exit(2); }
}
mkdirSync(args.artifacts, { recursive: true });

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures += 1;
  return ok;
}
async function until(what, predicate, timeout = 20000) {
  const end = Date.now() + timeout;
  for (;;) {
    const value = await predicate();
    if (value) return value;
    if (Date.now() > end) throw new Error(`timed out after ${timeout} ms waiting for ${what}`);
    await sleep(50);
  }
}
const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);

// ---- the server ----
async function serve(scene) {
  const child = spawn(args.pdyn, ['serve', scene, '--port', '0'], { stdio: ['ignore', 'pipe', 'inherit'] });
  const exit = new Promise((r) => child.on('exit', (code, signal) => r({ code, signal })));
  const address = await new Promise((resolveUrl, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error(`no address from pdyn serve: ${out}`)), 60000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/^pdyn serve: (http:\/\/\S+) /m);
      if (m) { clearTimeout(timer); resolveUrl(m[1]); }
    });
    child.on('exit', (code) => reject(new Error(`pdyn serve exited with ${code} before listening: ${out}`)));
  });
  console.log(`server at ${address} (${scene})`);
  return { child, exit, url: address };
}
// Ctrl-C, and the exit status it gave (null: it had to be killed).
async function stop({ child, exit }) {
  child.kill('SIGINT');
  const status = await Promise.race([exit, sleep(10000).then(() => null)]);
  if (!status) child.kill('SIGKILL');
  return status;
}
const { child: server, exit: serverExit, url } = await serve(args.scene);
let state = async () => (await fetch(new URL('api/state', url))).json();

// ---- the browser ----
const profile = mkdtempSync(join(tmpdir(), 'pdyn-chromium-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: args.chromium || '/usr/bin/chromium',
  headless: true,
  viewport: { width: 1280, height: 800 },
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync', '--use-gl=swiftshader', '--enable-unsafe-swiftshader'],
});
const page = context.pages()[0] ?? await context.newPage();
const pageErrors = [];
page.on('pageerror', (e) => pageErrors.push(`page error: ${e.message}`));
page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(`console error: ${m.text()}`); });
const shot = (name) => page.screenshot({ path: join(args.artifacts, name) });
const hooks = (expr) => page.evaluate(expr);

// The double pendulum (pivot 0, bobs 1 and 2, rods 0-1 of 1 m and 1-2 of
// 0.7 m) on a server of its own: both rods drawn as constraint segments,
// the constraint listed, and bob 2 dragged with the mouse for 1 s moves
// while the rods keep their lengths (Witkin's constraint force resists the
// mouse spring along them).
async function constraints() {
  const second = await serve(args['constraint-scene']);
  try {
    state = async () => (await fetch(new URL('api/state', second.url))).json();
    await page.goto(second.url);
    await until('the pendulum\'s first frame', () => hooks('window.pdyn.frames > 0 && window.pdyn.status && window.pdyn.scene.constraints'));
    const segments = await hooks('window.pdyn.constraintSegments');
    check(segments === 2, `the page draws the pendulum's ${segments} rods as constraint segments`);
    const listed = await page.locator('#constraints li').allTextContents();
    check(listed.length === 1 && listed[0].startsWith('distance: 2 rows'), `the panel lists ${JSON.stringify(listed)}`);
    await page.click('#play');
    await until('playing', () => hooks('window.pdyn.status.playing'));
    const from = await hooks('window.pdyn.screenOf(2)');
    const before = (await state()).particles[2].x;
    await page.check('input[name=mode][value=drag]');
    await page.mouse.move(from.x, from.y);
    await page.mouse.down();
    await page.mouse.move(from.x, from.y - 120, { steps: 10 });
    await sleep(1000);
    await shot('5-constraints-drag.png');
    const s = await state();
    await page.mouse.up();
    const [p0, p1, p2] = s.particles.map((q) => q.x);
    const rods = [dist(p0, p1), dist(p1, p2)];
    check(dist(before, p2) > 0.05, `the dragged bob moved ${dist(before, p2).toFixed(3)} m`);
    check(Math.abs(rods[0] - 1) < 1e-5 && Math.abs(rods[1] - 0.7) < 1e-5,
          `the rods kept their lengths while dragged: ${rods.map((r) => r.toFixed(7)).join(' m, ')} m (1 m, 0.7 m)`);
    const error = await hooks('window.pdyn.status.constraint_error');
    check(typeof error === 'number' && error < 1e-5, `the status reports the constraint error ${error} m`);
  } finally {
    await page.goto('about:blank');  // a page left open would log its failed reconnects
    const exit = await stop(second);
    check(exit && exit.code === 0, `Ctrl-C stopped the pendulum's server with status ${exit ? exit.code ?? exit.signal : 'none (killed)'}`);
  }
}

let summary = '';
try {
  await page.goto(url);
  await until('the first frame', () => hooks('window.pdyn && window.pdyn.frames > 0 && window.pdyn.status'));
  const count = await hooks('window.pdyn.scene.count');
  check(count === 10000, `the page shows the scene's ${count} particles`);
  await shot('1-loaded.png');

  // Play; two pictures of the canvas half a second apart differ.
  await page.click('#play');
  await until('playing', () => hooks('window.pdyn.status.playing'));
  const canvas = page.locator('#view canvas');
  const a = await canvas.screenshot();
  await sleep(700);
  const b = await canvas.screenshot();
  check(!a.equals(b), 'the canvas changes between frames while playing');

  // Frame rate and real-time factor, measured over 3 s.
  const f0 = await hooks('window.pdyn.frames');
  await sleep(3000);
  const f1 = await hooks('window.pdyn.frames');
  const fps = (f1 - f0) / 3;
  const rtf = await hooks('window.pdyn.status.rtf');
  check(fps > 0.3 && fps <= 62, `frames arrive at ${fps.toFixed(1)} per second (at most ~60)`);
  // The same without drawing the 59 002 springs: in a software-rendered
  // headless Chromium, drawing is most of the page's work.
  await page.uncheck('#springs');
  const g0 = await hooks('window.pdyn.frames');
  await sleep(3000);
  const g1 = await hooks('window.pdyn.frames');
  await page.check('#springs');
  const fpsPoints = (g1 - g0) / 3;
  const rtf2 = await hooks('window.pdyn.status.rtf');
  summary = `viewer.browser: ${fps.toFixed(1)} frames/s (rtf ${rtf.toFixed(3)}) with springs drawn, ` +
            `${fpsPoints.toFixed(1)} frames/s (rtf ${rtf2.toFixed(3)}) with points only, ${count} particles`;

  // Drag: the free bottom-left corner (id 0) towards a point 150 px up and
  // 100 px left of it on the screen, held for 3 s.
  const id = 0;
  const from = await hooks(`window.pdyn.screenOf(${id})`);
  const to = { x: from.x - 100, y: from.y - 150 };
  const target = await hooks(`window.pdyn.worldOf(${to.x}, ${to.y}, ${id})`);
  const before = (await state()).particles[id].x;
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  await page.mouse.move(to.x, to.y, { steps: 10 });
  await sleep(1500);
  await shot('2-drag.png');
  // Held until it has come a fifth of the way, or 30 s: on a loaded machine
  // the simulation gets what the browser's software rendering leaves.
  const d0 = dist(before, target);
  let d1 = d0;
  for (const end = Date.now() + 30000; Date.now() < end && d1 >= 0.8 * d0; await sleep(500)) {
    d1 = dist((await state()).particles[id].x, target);
  }
  await page.mouse.up();
  check(d1 < 0.8 * d0, `the dragged particle moved toward the cursor: ${d0.toFixed(3)} m -> ${d1.toFixed(3)} m`);

  // Nail the centre of the cloth; it stays put while the rest moves. The
  // click lands while paused: on the moving cloth, a loaded machine can
  // draw the particle elsewhere than where the click was aimed, and the
  // nail then goes to a neighbour.
  const nailed = 5050;
  await page.click('#play');
  await until('paused', () => hooks('!window.pdyn.status.playing'));
  await page.check('input[name=mode][value=nail]');
  const c = await hooks(`window.pdyn.screenOf(${nailed})`);
  await page.mouse.click(c.x, c.y);
  await until('the nail', async () => (await state()).particles[nailed].fixed);
  await page.click('#play');
  await until('playing again', () => hooks('window.pdyn.status.playing'));
  const s1 = await state();
  await sleep(1000);
  const s2 = await state();
  check(s2.step > s1.step, `the simulation ran on (${s2.step - s1.step} steps)`);
  check(dist(s1.particles[nailed].x, s2.particles[nailed].x) === 0, 'the nailed particle stayed exactly where it was');
  await shot('3-nail.png');

  // Pause, create a particle left of the cloth, attach it to particle 0.
  await page.click('#play');
  await until('paused', () => hooks('!window.pdyn.status.playing'));
  const links = await hooks('window.pdyn.scene.links.length');
  await page.check('input[name=mode][value=create]');
  const corner = await hooks('window.pdyn.screenOf(0)');
  await page.mouse.click(corner.x - 80, corner.y + 40);
  const created = await until('the new particle', async () => {
    const s = await state();
    return s.count === count + 1 && s;
  });
  check(created.count === count + 1, `create added particle ${created.count - 1}`);
  await until('its scene message', () => hooks(`window.pdyn.scene.count === ${count + 1}`));
  await sleep(200);
  await page.check('input[name=mode][value=attach]');
  const p = await hooks(`window.pdyn.screenOf(${count})`);
  const q = await hooks('window.pdyn.screenOf(0)');
  await page.mouse.click(p.x, p.y);
  await page.mouse.click(q.x, q.y);
  await until('the new link', () => hooks(`window.pdyn.scene.links.length === ${links + 1}`));
  const last = await hooks('window.pdyn.scene.links[window.pdyn.scene.links.length - 1]');
  check(last[0] === count && last[1] === 0, `attach linked particles ${last}`);
  await shot('4-create-attach.png');

  // Single step while paused: exactly one.
  const k0 = (await state()).step;
  await page.click('#step');
  await until('the step', async () => (await state()).step === k0 + 1);
  await sleep(500);
  check((await state()).step === k0 + 1, `step advanced the paused simulation by exactly one (${k0} -> ${k0 + 1})`);

  if (args['constraint-scene']) await constraints();

  check(pageErrors.length === 0, `no page or console errors${pageErrors.length ? ': ' + pageErrors.join('; ') : ''}`);
} catch (e) {
  check(false, e.stack || String(e));
  await shot('failure.png').catch(() => {});
} finally {
  await context.close().catch(() => {});
  rmSync(profile, { recursive: true, force: true });
  const exit = await stop({ child: server, exit: serverExit });
  check(exit && exit.code === 0, `Ctrl-C stopped the server with status ${exit ? exit.code ?? exit.signal : 'none (killed)'}`);
}
if (summary) console.log(summary);
console.log(failures ? `${failures} check(s) failed` : 'all checks passed');
process.exit(failures ? 1 : 0);
