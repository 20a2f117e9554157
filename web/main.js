// The page: plays the exported clip, shades every frame through the core (aprt.js) under an
// SH environment plus the light the user drags, with the model's occluder proxies when it has
// them, draws it (render.js) and shows the frame time and the core's µs per frame. The loop
// over the vertices runs on WebGPU (webgpu.js) when the browser gives an adapter and a
// device, else in the core; `?path=wasm` or `?path=webgpu` forces one. `window.aprtPage`
// exposes the state the browser test reads.

import { loadCore } from './aprt.js';
import { openWebGpu } from './webgpu.js';
import { frameAt, loadClip, poseOf, skinFrame } from './clip.js';
import { Renderer, camera } from './render.js';

const params = new URLSearchParams(location.search);
/** `?t=`, seconds into the clip: a finite number at least 0, else the clip's start (with a
 *  notice on the page). */
const asked = params.get('t');
const startSeconds = asked === null || (Number.isFinite(Number(asked)) && Number(asked) >= 0) ? Number(asked ?? 0) : 0;
const notice = startSeconds === Number(asked ?? 0) ? null : `?t=${asked.slice(0, 32)} is not a time in seconds: playing from 0`;
const frozen = params.get('freeze') === '1';
const dataDir = new URL(params.get('data') ?? 'data/', location.href);
/** `?path=`: 'wasm' or 'webgpu' forces that path (a forced WebGPU without an adapter is an
 *  error, not a silent fallback); otherwise WebGPU when the browser has it. */
const path = params.get('path');

/** The environment: a sky brighter above (z up) than below, order² SH coefficients. */
function environment(order) {
  const sh = new Float32Array(order * order);
  sh[0] = 0.5; // l = 0
  if (order > 1) sh[2] = 0.25; // l = 1, m = 0: z
  return sh;
}

/** The dragged light's direction from azimuth and elevation (radians), z up. */
function direction(azimuth, elevation) {
  const c = Math.cos(elevation);
  return [c * Math.cos(azimuth), c * Math.sin(azimuth), Math.sin(elevation)];
}

/** Running means of the last `size` samples. */
class Mean {
  constructor(size) {
    this.samples = [];
    this.size = size;
  }
  push(x) {
    this.samples.push(x);
    if (this.samples.length > this.size) this.samples.shift();
  }
  get value() {
    return this.samples.reduce((a, b) => a + b, 0) / Math.max(1, this.samples.length);
  }
}

async function main() {
  if (path !== null && path !== 'wasm' && path !== 'webgpu') throw new Error(`?path=${path.slice(0, 32)}: wasm or webgpu`);
  const [core, clip] = await Promise.all([loadCore(location.href, params.get('wasm') ?? 'auto'), loadClip(dataDir)]);
  core.load(clip.blob);
  const gpu = path === 'wasm' ? null : await openWebGpu(core, clip.blob, new URL('wgsl/', location.href));
  if (!gpu && path === 'webgpu') throw new Error('?path=webgpu: this browser gives no WebGPU adapter and device');
  /** A frame's shading before the proxies' correction, as a view of the module's: the
   *  core's three calls, or the core's pose and lighting weights and the GPU's loop. */
  const shade = gpu
    ? async () => {
      const out = core.shading();
      await gpu.shade(core.light(), out);
      return out;
    }
    : async () => core.shade();
  const m = clip.manifest;
  const canvas = document.getElementById('view');
  const renderer = new Renderer(canvas, clip.arrays.indices, m.vertices);
  const cam = camera(clip.arrays.positions, m.up, canvas.width / canvas.height);
  const light = { azimuth: -0.6, elevation: 0.8, strength: 2.5 };
  const env = environment(core.info.order);
  const shadeMean = new Mean(120);
  const proxiesMean = new Mean(120);
  const frameMean = new Mean(120);
  const page = { ready: false, frame: -1, core, manifest: m, shading: null, lighting: null, notice,
    path: gpu ? 'webgpu' : 'wasm', adapter: gpu?.adapter };
  window.aprtPage = page;

  /** One frame: skin the mesh into the core, pose and light it, shade and correct by the
   *  proxies (each timed alone), draw. */
  async function render(f) {
    const { angles, rotations, skinning } = poseOf(clip, f);
    const mesh = core.mesh();
    skinFrame(clip, f, mesh.positions, mesh.normals);
    core.setPose(angles, rotations, skinning);
    core.setLighting(env, direction(light.azimuth, light.elevation), light.strength);
    const t0 = performance.now();
    const shading = await shade();
    shadeMean.push(performance.now() - t0);
    if (core.info.proxies) {
      page.unoccluded = Float32Array.from(shading);
      const t1 = performance.now();
      core.occlude();
      proxiesMean.push(performance.now() - t1);
    }
    renderer.draw(cam, mesh.positions, mesh.normals, shading);
    page.frame = f;
    page.shading = Float32Array.from(shading);
    page.lighting = core.lighting();
  }

  /** µs per shading of the current frame over `n` calls (the page's own timer is coarse):
   *  `aprt_shade`, or on WebGPU `aprt_light`, the dispatch and the read-back; each followed by
   *  `aprt_occlude` when `proxies` is set (for a model with them). */
  page.bench = async (n, proxies = false) => {
    const t0 = performance.now();
    for (let i = 0; i < n; i++) {
      await shade();
      if (proxies) core.occlude();
    }
    return ((performance.now() - t0) * 1000) / n;
  };

  /** The live means of the last 120 frames' shade and proxies, in µs (cold caches, the GPU
   *  thread busy). */
  page.liveShadeUs = () => shadeMean.value * 1000;
  page.liveProxiesUs = () => proxiesMean.value * 1000;

  let dragging = null;
  /** A frozen frame to draw again: the light moved. */
  let moved = false;
  canvas.addEventListener('pointerdown', (e) => (dragging = { x: e.clientX, y: e.clientY }));
  window.addEventListener('pointerup', () => (dragging = null));
  window.addEventListener('pointermove', (e) => {
    if (!dragging) return;
    light.azimuth -= (e.clientX - dragging.x) * 0.01;
    light.elevation = Math.max(-1.5, Math.min(1.5, light.elevation + (e.clientY - dragging.y) * 0.01));
    dragging = { x: e.clientX, y: e.clientY };
    moved = frozen;
  });

  const stats = document.getElementById('stats');
  const started = performance.now();
  let last = started;
  /** One frame at a time: the next is asked for once this one is drawn (on WebGPU, after its
   *  read-back). */
  async function tick(now) {
    frameMean.push(now - last);
    last = now;
    const seconds = frozen ? startSeconds : startSeconds + (now - started) / 1000;
    try {
      if (!frozen || page.frame < 0 || moved) {
        moved = false;
        await render(frameAt(m, seconds));
      }
    } catch (err) {
      // A frame the core refuses stops the page with its message, never silently.
      stats.textContent = `error: ${err.message}`;
      page.error = err.message;
      return;
    }
    stats.textContent = [
      ...(notice ? [notice] : []),
      `clip ${m.clip}: frame ${page.frame + 1} of ${m.frames} at ${m.fps} fps`,
      `${m.vertices} vertices, order ${core.info.order}, ${core.info.bones} bones` +
        (core.info.proxies ? ', occluder proxies' : ''),
      gpu ? `shading on WebGPU (${gpu.adapter}), pose and lighting in wasm ${core.flavour}, ${core.wasmBytes} bytes`
        : `shading in wasm ${core.flavour}, ${core.wasmBytes} bytes`,
      `frame time   ${frameMean.value.toFixed(2)} ms`,
      `${(gpu ? 'GPU shade' : 'core shade').padEnd(13)}${(shadeMean.value * 1000).toFixed(0)} µs per frame`,
      ...(core.info.proxies ? [`proxies      ${(proxiesMean.value * 1000).toFixed(0)} µs per frame`] : []),
      `light az ${light.azimuth.toFixed(2)} el ${light.elevation.toFixed(2)}`,
    ].join('\n');
    page.ready = true;
    requestAnimationFrame(tick);
  }
  requestAnimationFrame(tick);
}

main().catch((err) => {
  document.getElementById('stats').textContent = `error: ${err.message}`;
  window.aprtPage = { ready: false, error: err.message };
});
