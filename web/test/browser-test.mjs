// The page in headless Chromium (the system's, through playwright-core; nothing downloaded):
// for each wasm build (`?path=wasm`) and for WebGPU (`?path=webgpu`, SwiftShader's adapter)
// it loads `?t=T&freeze=1`, reads the per-vertex shading back from the module and compares it
// with `aprt eval` of the same frame under the page's lighting (for a model with occluder
// proxies, after their correction, which must matter far beyond the tolerance), checks the
// page's skinned mesh against the trainer's bit for bit (--posed), times the frame's shading
// (batched, and live while the clip plays), and compares a screenshot of the canvas with
// reference.png (the wasm builds) or with the SIMD build's screenshot (WebGPU; pixelmatch).
// Without `?path=` the page must pick WebGPU in this Chromium and the wasm core in one
// started without WebGPU. When this Chromium offers no WebGPU adapter, the WebGPU half is
// skipped with a line saying so, or fails under $APRT_REQUIRE_BROWSER (as CI sets it).
//
//   node browser-test.mjs --reference eval.npy [--posed posed.npy] [--t 1.25] [--bench 300]
//                         [--out DIR] [--update-reference]
//
// eval.npy is `aprt eval web/data/model.aprt --builtin --clip wave --npy eval.npy`
// (frames × vertices × n² world transfer, the proxies' occlusion subtracted);
// shading_j = Σ_c T[f, j, c] L_c. posed.npy is the trainer's posed mesh of every frame
// (frames × 2 × vertices × 3: positions, normals), which `aprt eval` gives the proxies.

import { readFile, writeFile, mkdir } from 'node:fs/promises';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';
import { chromium } from 'playwright-core';
import pixelmatch from 'pixelmatch';
import { PNG } from 'pngjs';
import { readNpy } from './npy.mjs';
import { serve } from './serve.mjs';

const here = dirname(fileURLToPath(import.meta.url));
/** Largest |page − eval| over the vertices, relative to the largest |eval|. */
const MAX_RELATIVE = 1e-5;
/** pixelmatch's per-pixel threshold (YIQ distance, 0 to 1), and how many pixels may exceed it.
 *  SwiftShader renders the same bits run to run (0 pixels here); measured on this page, at
 *  0.02 the next frame of the clip flags 430 pixels and the light dragged 0.1 rad 7,099 (at
 *  pixelmatch's default 0.1, 149 and 0: too blind to the shading). 100 pixels (0.03 % of the
 *  canvas) catch both and leave room for another Chromium's edge rasterisation. */
const PIXEL_THRESHOLD = 0.02;
const MAX_DIFF_PIXELS = 100;
/** SwiftShader's WebGL2 without a GPU, and no network or profile state. */
const CHROMIUM_ARGS = [
  '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
];
/** With these, headless Chromium 156 offers SwiftShader's WebGPU adapter (vendor google,
 *  architecture swiftshader), `--disable-gpu` notwithstanding; without the flag it has none. */
const WEBGPU_ARGS = [...CHROMIUM_ARGS, '--enable-unsafe-webgpu'];
/** The page's runs: each wasm build, and WebGPU's loop after the SIMD build's pose and
 *  lighting (whose screenshot it must match). */
const RUNS = [
  { name: 'scalar', path: 'wasm', flavour: 'scalar' },
  { name: 'simd', path: 'wasm', flavour: 'simd' },
  { name: 'webgpu', path: 'webgpu', flavour: 'simd' },
];

const { values: opts } = parseArgs({
  options: {
    reference: { type: 'string' },
    posed: { type: 'string' },
    t: { type: 'string', default: '1.25' },
    bench: { type: 'string', default: '300' },
    out: { type: 'string' },
    'update-reference': { type: 'boolean', default: false },
  },
});

/** The shading `aprt eval` implies for frame `f` under `lighting`, in f64. */
function evalShading(npy, f, lighting) {
  const [frames, vertices, n2] = npy.shape;
  if (f >= frames || n2 !== lighting.length) throw new Error(`eval.npy ${npy.shape} vs frame ${f}, n² ${lighting.length}`);
  const out = new Float64Array(vertices);
  for (let j = 0; j < vertices; j++) {
    const row = (f * vertices + j) * n2;
    for (let c = 0; c < n2; c++) out[j] += npy.data[row + c] * lighting[c];
  }
  return out;
}

/** Loads the page with one of `RUNS`; returns what it computed and its timing. */
async function runPage(browser, url, { name, path, flavour }) {
  const page = await browser.newPage({ viewport: { width: 1100, height: 560 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  const query = `path=${path}&wasm=${flavour}`;
  await page.goto(`${url}?t=${opts.t}&freeze=1&${query}`);
  await page.waitForFunction(() => window.aprtPage?.ready || window.aprtPage?.error, null, { timeout: 60000 });
  const state = await page.evaluate(() => {
    const p = window.aprtPage;
    if (p.error) return { error: p.error };
    const mesh = p.core.mesh();
    return { frame: p.frame, path: p.path, adapter: p.adapter, flavour: p.core.flavour, wasmBytes: p.core.wasmBytes,
      fps: p.manifest.fps,
      shading: Array.from(p.shading), lighting: Array.from(p.lighting), proxies: p.core.info.proxies,
      unoccluded: p.unoccluded && Array.from(p.unoccluded),
      posed: { positions: Array.from(mesh.positions), normals: Array.from(mesh.normals) } };
  });
  if (state.error || errors.length) throw new Error(`page (${name}): ${state.error ?? errors.join('; ')}`);
  // Median of 5 runs of `bench` calls each: the page's timer is coarse, a batch is not. A
  // WebGPU frame waits for its read-back, milliseconds on SwiftShader: a tenth as many calls
  // time it as finely.
  const calls = path === 'webgpu' ? Math.ceil(Number(opts.bench) / 10) : Number(opts.bench);
  const median = async (proxies) => {
    const runs = [];
    for (let i = 0; i < 5; i++) {
      runs.push(await page.evaluate(([n, p]) => window.aprtPage.bench(n, p), [calls, proxies]));
    }
    return runs.sort((a, b) => a - b)[2];
  };
  state.shadeUs = await median(false);
  if (state.proxies) state.frameUs = await median(true);
  state.screenshot = await page.locator('#view').screenshot();
  // The page as a user sees it: the clip playing, the shade timed every frame, with cold
  // caches and the renderer busy; the mean of the last 120 frames after 3 s.
  await page.goto(`${url}?${query}`);
  await page.waitForFunction(() => window.aprtPage?.ready, null, { timeout: 60000 });
  await page.waitForTimeout(3000);
  state.liveUs = await page.evaluate(() => window.aprtPage.liveShadeUs());
  state.liveProxiesUs = await page.evaluate(() => window.aprtPage.liveProxiesUs());
  await page.close();
  return state;
}

/** Why `browser` offers a page no WebGPU adapter and device, or null when it does. */
async function noWebGpu(browser, url) {
  const page = await browser.newPage();
  await page.goto(`${url}data/manifest.json`); // a file of the server: a secure context
  const why = await page.evaluate(async () => {
    if (!navigator.gpu) return 'no navigator.gpu';
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) return 'no adapter';
    return (await adapter.requestDevice().catch(() => null)) ? null : 'an adapter but no device';
  });
  await page.close();
  return why && `headless Chromium with ${WEBGPU_ARGS.join(' ')} offers WebGPU ${why}`;
}

/** The path the page picks without `?path=`: `expected` ('webgpu' in a Chromium with
 *  WebGPU, 'wasm' without), and an unknown `?path=` refused with a message. Returns the
 *  failures. */
async function checkPathChoice(browser, url, expected) {
  const failures = [];
  for (const [query, wanted] of [['', expected], ['&path=gpu', 'error']]) {
    const page = await browser.newPage();
    await page.goto(`${url}?t=${opts.t}&freeze=1${query}`);
    await page.waitForFunction(() => window.aprtPage?.ready || window.aprtPage?.error, null, { timeout: 60000 });
    const chosen = await page.evaluate(() => (window.aprtPage.error ? 'error' : window.aprtPage.path));
    await page.close();
    if (chosen !== wanted) failures.push(`?${query.slice(1)} in a Chromium ${expected === 'webgpu' ? 'with' : 'without'} WebGPU: ${chosen}, not ${wanted}`);
  }
  return failures;
}

/** Bad `?t=` queries: the page still shows a frame, with no uncaught error, and says when it
 *  ignored the time. Returns the failures. */
async function checkBadQueries(browser, url) {
  const failures = [];
  for (const [t, noticed] of [['NaN', true], ['-3', true], ['1e999', true], ['1e308', false]]) {
    const page = await browser.newPage();
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    await page.goto(`${url}?t=${t}&freeze=1&wasm=scalar`);
    await page.waitForFunction(() => window.aprtPage?.ready || window.aprtPage?.error, null, { timeout: 60000 });
    const state = await page.evaluate(() => {
      const p = window.aprtPage;
      return { ready: p.ready, error: p.error, frame: p.frame, frames: p.manifest?.frames, notice: p.notice };
    });
    await page.close();
    if (!state.ready || errors.length) failures.push(`?t=${t}: ${state.error ?? errors.join('; ')}`);
    else if (!(state.frame >= 0 && state.frame < state.frames)) failures.push(`?t=${t}: frame ${state.frame}`);
    else if (Boolean(state.notice) !== noticed) failures.push(`?t=${t}: notice ${state.notice}`);
  }
  return failures;
}

/** Largest |`shading` − `aprt eval` of `frame`| relative to the largest |eval|. */
function compareShading(state, npy, frame = state.frame, shading = state.shading) {
  const expected = evalShading(npy, frame, state.lighting);
  let worst = 0;
  let scale = 0;
  for (let j = 0; j < expected.length; j++) {
    worst = Math.max(worst, Math.abs(shading[j] - expected[j]));
    scale = Math.max(scale, Math.abs(expected[j]));
  }
  if (shading.length !== expected.length) throw new Error('vertex count differs from eval.npy');
  return worst / scale;
}

/** How many of the page's posed coordinates (positions and normals of its frame) differ from
 *  the trainer's in posed.npy: the proxies must see the mesh `aprt eval` gave them. */
function posedMismatches(state, posed) {
  const [frames, two, vertices, three] = posed.shape;
  if (two !== 2 || three !== 3 || state.frame >= frames) throw new Error(`posed.npy ${posed.shape}`);
  const page = [...state.posed.positions, ...state.posed.normals];
  if (page.length !== 2 * vertices * 3) throw new Error('vertex count differs from posed.npy');
  const base = state.frame * page.length;
  return page.filter((x, i) => x !== posed.data[base + i]).length;
}

/** Pixels of the screenshot `png` over pixelmatch's threshold against the screenshot
 *  `reference`. */
async function compareImage(png, reference, outDir) {
  const actual = PNG.sync.read(png);
  const expected = PNG.sync.read(reference);
  if (actual.width !== expected.width || actual.height !== expected.height) {
    throw new Error(`screenshot ${actual.width}×${actual.height}, reference ${expected.width}×${expected.height}`);
  }
  const diff = new PNG({ width: actual.width, height: actual.height });
  const pixels = pixelmatch(actual.data, expected.data, diff.data, actual.width, actual.height, { threshold: PIXEL_THRESHOLD });
  if (outDir) {
    await mkdir(outDir, { recursive: true });
    await writeFile(join(outDir, 'screenshot.png'), png);
    await writeFile(join(outDir, 'diff.png'), PNG.sync.write(diff));
  }
  return pixels;
}

async function main() {
  if (!opts.reference) throw new Error('give --reference eval.npy (aprt eval of the exported clip)');
  const npy = readNpy(new Uint8Array(await readFile(opts.reference)));
  const posed = opts.posed && readNpy(new Uint8Array(await readFile(opts.posed)));
  if (opts.out) await mkdir(opts.out, { recursive: true });
  const server = await serve(dirname(here));
  const launch = (args) => chromium.launch({
    executablePath: process.env.APRT_CHROMIUM ?? '/usr/bin/chromium', headless: true, args });
  const browser = await launch(WEBGPU_ARGS);
  const failures = [];
  const results = {};
  const screenshots = {};
  const referencePath = join(here, 'reference.png');
  try {
    const webGpuMissing = await noWebGpu(browser, server.url);
    if (webGpuMissing && process.env.APRT_REQUIRE_BROWSER) failures.push(webGpuMissing);
    else if (webGpuMissing) console.log(`skipped the WebGPU half: ${webGpuMissing}`);
    for (const run of RUNS.filter((r) => !(webGpuMissing && r.path === 'webgpu'))) {
      const { name, path } = run;
      const state = await runPage(browser, server.url, run);
      if (state.flavour !== run.flavour) failures.push(`asked for ${run.flavour}, the page loaded ${state.flavour}`);
      if (state.path !== path) failures.push(`asked for ${path}, the page took ${state.path}`);
      const relative = compareShading(state, npy);
      const expectedFrame = Math.floor(Number(opts.t) * state.fps + 1e-9) % npy.shape[0];
      if (state.frame !== expectedFrame) failures.push(`${name}: frame ${state.frame}, expected ${expectedFrame}`);
      if (!(relative <= MAX_RELATIVE)) failures.push(`${name}: shading differs from aprt eval by ${relative.toExponential(2)} relative`);
      // Not a vacuous comparison: the next frame's shading is far outside the tolerance.
      const neighbour = compareShading(state, npy, (state.frame + 1) % npy.shape[0]);
      if (!(neighbour > 100 * MAX_RELATIVE)) failures.push(`${name}: the next frame is only ${neighbour} from this one`);
      // With proxies, what the page shades without them must be far from aprt eval too, so a
      // page that skipped them would fail.
      const without = state.proxies ? compareShading(state, npy, state.frame, state.unoccluded) : null;
      if (state.proxies && !(without > 100 * MAX_RELATIVE)) {
        failures.push(`${name}: the proxies change the shading by only ${without}`);
      }
      const mismatches = posed ? posedMismatches(state, posed) : null;
      if (mismatches) failures.push(`${name}: ${mismatches} posed coordinates differ from the trainer's`);
      // The wasm builds against reference.png, WebGPU against the SIMD build's screenshot.
      screenshots[name] = state.screenshot;
      const against = path === 'wasm' ? 'reference.png' : `the ${run.flavour} build's screenshot`;
      if (path === 'wasm' && opts['update-reference']) await writeFile(referencePath, state.screenshot);
      const reference = path === 'wasm' ? await readFile(referencePath) : screenshots[run.flavour];
      const pixels = await compareImage(state.screenshot, reference, opts.out && join(opts.out, name));
      if (pixels > MAX_DIFF_PIXELS) failures.push(`${name}: ${pixels} pixels differ from ${against}`);
      results[name] = { frame: state.frame, path, adapter: state.adapter, wasm_bytes: state.wasmBytes, max_relative: relative,
        without_proxies: without, shade_us: state.shadeUs, with_proxies_us: state.frameUs, live_shade_us: state.liveUs,
        live_proxies_us: state.proxies ? state.liveProxiesUs : null, posed_mismatches: mismatches, diff_pixels: pixels };
      const [proxies, withProxies, liveProxies] = state.proxies
        ? [`; without the proxies ${without.toExponential(2)}`, ` (${state.frameUs.toFixed(1)} with the proxies)`,
          ` (+${state.liveProxiesUs.toFixed(0)} for the proxies)`]
        : ['', '', ''];
      const gpu = path === 'webgpu' ? `WebGPU on ${state.adapter} after the ${run.flavour} build's pose and lighting, ` : '';
      console.log(`${name}: frame ${state.frame}, ${gpu}${state.wasmBytes} wasm bytes, shading vs aprt eval ` +
        `${relative.toExponential(2)} relative (≤ ${MAX_RELATIVE}; the next frame ${neighbour.toExponential(2)}${proxies}), ` +
        `${state.shadeUs.toFixed(1)} µs per frame${withProxies}, ${state.liveUs.toFixed(0)} µs live${liveProxies}, ` +
        (posed ? `posed mesh ${mismatches} coordinates off the trainer's, ` : '') +
        `${pixels} pixels differ from ${against} (≤ ${MAX_DIFF_PIXELS})`);
    }
    if (!webGpuMissing) failures.push(...(await checkPathChoice(browser, server.url, 'webgpu')));
    // The fallback: a Chromium without WebGPU gets the wasm core, and plays every bad `?t=`.
    const plain = await launch(CHROMIUM_ARGS);
    try {
      failures.push(...(await checkPathChoice(plain, server.url, 'wasm')));
      failures.push(...(await checkBadQueries(plain, server.url)));
    } finally {
      await plain.close();
    }
  } finally {
    await browser.close();
    server.close();
  }
  console.log(`browser: ${JSON.stringify({ chromium: browser.version(), ...results })}`);
  if (failures.length) throw new Error(failures.join('\n'));
  console.log('browser test passed');
}

main().catch((err) => {
  console.error(`browser test failed: ${err.message}`);
  process.exit(1);
});
