// The loop over the vertices on WebGPU, when the browser has it: aprt-gpu's own kernel
// (gpu/src/shaders/rows.wgsl followed by shade.wgsl, as gpu/src/shaders/mod.rs joins them;
// web/build.sh copies both into web/wgsl/) over the blob's vertex rows, uploaded once as
// stored. The core (aprt.js) still computes each frame's pose and lighting weights, with the
// same bits as on the CPU; only the per-vertex loop moves to the GPU, and its result is read
// back into the module, where the proxies' correction and the renderer find it.

/** Invocations per workgroup: `@workgroup_size` of shade.wgsl. */
const WORKGROUP = 64;

/** The kernel bound to `core`'s loaded model, whose blob is `blob`, on the browser's WebGPU
 *  device; null when the browser gives no adapter or device. `wgsl` is where rows.wgsl and
 *  shade.wgsl are served. */
export async function openWebGpu(core, blob, wgsl) {
  const adapter = await navigator.gpu?.requestAdapter();
  const device = await adapter?.requestDevice().catch(() => null);
  if (!device) return null;
  const sources = await Promise.all(['rows.wgsl', 'shade.wgsl'].map(async (name) => {
    const response = await fetch(new URL(name, wgsl));
    if (!response.ok) throw new Error(`${name}: HTTP ${response.status}`);
    return response.text();
  }));
  const { vendor, architecture } = adapter.info ?? {};
  const name = [vendor, architecture].filter(Boolean).join(' ') || 'unnamed adapter';
  return GpuShading.create(device, name, core, blob, sources.join(''));
}

/** One model's rows and the shading kernel on a device. */
class GpuShading {
  constructor(parts) {
    Object.assign(this, parts);
  }

  static async create(device, adapter, core, blob, code) {
    const { rows, info } = core;
    const usage = GPUBufferUsage;
    const buffer = (label, size, use) => device.createBuffer({ label, size, usage: use });
    device.pushErrorScope('validation');
    // rows.wgsl's `Rows` block, field for field, as gpu/src/model.rs fills it.
    const shape = new Uint32Array([
      info.vertices, rows.encoding, rows.leadRows, rows.rowWidth, rows.len / 4 / Math.max(1, rows.blocks),
      rows.bones, rows.coeffs, 0, // identity: read by the transfer kernel only
    ]);
    const layout = buffer('rows layout', shape.byteLength, usage.UNIFORM | usage.COPY_DST);
    device.queue.writeBuffer(layout, 0, shape);
    const rowsBuffer = buffer('vertex rows', rows.len, usage.STORAGE | usage.COPY_DST);
    device.queue.writeBuffer(rowsBuffer, 0, blob, rows.offset, rows.len);
    const lit = buffer('lit weights', rows.litLen * 4, usage.STORAGE | usage.COPY_DST);
    const bytes = info.vertices * 4;
    const shading = buffer('shading', bytes, usage.STORAGE | usage.COPY_SRC);
    const readBack = buffer('shading read-back', bytes, usage.MAP_READ | usage.COPY_DST);
    const module = device.createShaderModule({ label: 'rows.wgsl + shade.wgsl', code });
    const pipeline = device.createComputePipeline({ layout: 'auto', compute: { module, entryPoint: 'shade' } });
    const bindGroup = device.createBindGroup({
      layout: pipeline.getBindGroupLayout(0),
      entries: [layout, rowsBuffer, lit, shading].map((b, binding) => ({ binding, resource: { buffer: b } })),
    });
    const error = await device.popErrorScope();
    if (error) throw new Error(`WebGPU: ${error.message}`);
    // Rows of at most the device's workgroups per dimension, which `invocation` in rows.wgsl
    // turns back into one index.
    const groups = Math.ceil(info.vertices / WORKGROUP);
    const max = device.limits.maxComputeWorkgroupsPerDimension;
    return new GpuShading({
      device, adapter, lit, shading, readBack, bytes, pipeline, bindGroup,
      groups: [Math.min(groups, max), Math.ceil(groups / max)],
    });
  }

  /** Shades every vertex under the lighting weights `lit` (the core's `light`) and writes the
   *  result into `out` (the module's shading); resolves when it is there. */
  async shade(lit, out) {
    const { device } = this;
    device.queue.writeBuffer(this.lit, 0, lit);
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, this.bindGroup);
    pass.dispatchWorkgroups(...this.groups);
    pass.end();
    encoder.copyBufferToBuffer(this.shading, 0, this.readBack, 0, this.bytes);
    device.queue.submit([encoder.finish()]);
    await this.readBack.mapAsync(GPUMapMode.READ);
    out.set(new Float32Array(this.readBack.getMappedRange()));
    this.readBack.unmap();
  }
}
