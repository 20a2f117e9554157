// The aprt core in the page: web/wasm compiled to a raw wasm32 module (no wasm-bindgen, no
// allocator). The module keeps its buffers in statics and exports their addresses; this file
// copies a frame's inputs in, calls `aprt_shade` (and `aprt_occlude` for a model with
// occluder proxies) and hands back a view of the shading. On the WebGPU path (webgpu.js) it
// calls `aprt_light` instead and hands back the lighting weights, for the GPU's loop.

/** Loads `aprt-simd.wasm` when the browser validates it (or `choice` is 'simd'), else
 *  `aprt-scalar.wasm`; `choice` 'scalar' forces the scalar build. */
export async function loadCore(base, choice = 'auto') {
  const bytesOf = async (name) => {
    const response = await fetch(new URL(name, base));
    if (!response.ok) throw new Error(`${name}: HTTP ${response.status}`);
    return new Uint8Array(await response.arrayBuffer());
  };
  let bytes = null;
  let flavour = 'scalar';
  if (choice !== 'scalar') {
    const simd = await bytesOf('aprt-simd.wasm');
    if (WebAssembly.validate(simd)) {
      bytes = simd;
      flavour = 'simd';
    } else if (choice === 'simd') {
      throw new Error('this browser does not validate the SIMD build');
    }
  }
  if (bytes === null) bytes = await bytesOf('aprt-scalar.wasm');
  const { instance } = await WebAssembly.instantiate(bytes, {});
  return new Core(instance.exports, flavour, bytes.length);
}

/** One loaded module and, after `load`, one model. */
export class Core {
  constructor(exports, flavour, wasmBytes) {
    this.e = exports;
    this.flavour = flavour;
    this.wasmBytes = wasmBytes;
    this.info = null;
  }

  /** The module's memory as floats at `ptr` (a new view each time: cheap, never stale). */
  f32(ptr, len) {
    return new Float32Array(this.e.memory.buffer, ptr, len);
  }

  /** The last error's text. */
  error() {
    const bytes = new Uint8Array(this.e.memory.buffer, this.e.aprt_error(), this.e.aprt_error_len());
    return new Error(`aprt: ${new TextDecoder().decode(bytes)}`);
  }

  /** Validates a blob (Uint8Array) once and keeps it; reads the model's dimensions. */
  load(blob) {
    const ptr = this.e.aprt_blob(blob.length);
    if (ptr === 0) throw this.error();
    new Uint8Array(this.e.memory.buffer, ptr, blob.length).set(blob);
    if (this.e.aprt_load(blob.length) !== 0) throw this.error();
    this.info = {
      vertices: this.e.aprt_vertices(),
      poseLen: this.e.aprt_pose_len(),
      bones: this.e.aprt_bones(),
      order: this.e.aprt_order(),
      proxies: this.e.aprt_has_proxies() === 1,
    };
    this.info.coeffs = this.info.order * this.info.order;
    const rows = this.e.aprt_vertex_rows();
    if (rows === 0) throw this.error();
    // The nine u32 of `RowsLayout` (web/wasm/src/session.rs), in its order.
    const [offset, len, encoding, leadRows, rowWidth, blocks, bones, coeffs, litLen] =
      new Uint32Array(this.e.memory.buffer, rows, 9);
    this.rows = { offset, len, encoding, leadRows, rowWidth, blocks, bones, coeffs, litLen };
  }

  /** The lighting: the SH `environment` plus a directional light from `dir` of `strength`. */
  setLighting(environment, dir, strength) {
    this.f32(this.e.aprt_lighting(), this.info.coeffs).set(environment);
    if (this.e.aprt_add_directional(dir[0], dir[1], dir[2], strength) !== 0) throw this.error();
  }

  /** A copy of the lighting the next `shade` uses. */
  lighting() {
    return Float32Array.from(this.f32(this.e.aprt_lighting(), this.info.coeffs));
  }

  /** Writes a frame's pose vector, bone rotations (bones × 9, row-major) and, for a model
   *  with occluder proxies, the bones' skinning matrices (bones × 12, 3 × 4 row-major). */
  setPose(angles, rotations, skinning) {
    this.f32(this.e.aprt_angles(), this.info.poseLen).set(angles);
    this.f32(this.e.aprt_bone_rotations(), this.info.bones * 9).set(rotations);
    if (this.info.proxies) this.f32(this.e.aprt_skinning(), this.info.bones * 12).set(skinning);
  }

  /** Views of the module's posed mesh (vertices × 3 each), where the page skins the frame:
   *  `occlude` reads it there, and the renderer draws it, without a copy. */
  mesh() {
    const n = this.info.vertices * 3;
    return { positions: this.f32(this.e.aprt_positions(), n), normals: this.f32(this.e.aprt_normals(), n) };
  }

  /** One frame through the core (set_pose, light, shade); returns a view of the shading. */
  shade() {
    if (this.e.aprt_shade() !== 0) throw this.error();
    return this.shading();
  }

  /** `shade` without its loop over the vertices (set_pose, light), for a device that runs
   *  that loop itself: a view of the lighting weights (`rows.litLen`). */
  light() {
    const ptr = this.e.aprt_light();
    if (ptr === 0) throw this.error();
    return this.f32(ptr, this.rows.litLen);
  }

  /** A view of the module's shading: where `shade` leaves it, and where a device that ran
   *  the loop itself writes it for `occlude`. */
  shading() {
    return this.f32(this.e.aprt_shading(), this.info.vertices);
  }

  /** After `shade`, for a model with occluder proxies: poses them by the skinning matrices
   *  and takes what they block from the shading, in place, under the same lighting. */
  occlude() {
    if (this.e.aprt_occlude() !== 0) throw this.error();
  }
}
