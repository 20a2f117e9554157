// The files `aprt export-web` writes (manifest.json, clip.bin, model.aprt), and the linear
// blend skinning of one frame of the clip, done here so only small per-frame arrays ship.

const FORMAT = 'aprt-web 1';
const TYPES = { f32: Float32Array, u32: Uint32Array, u16: Uint16Array };

/** Fetches an export directory: the manifest, its arrays as typed views, and the blob. */
export async function loadClip(base) {
  const get = async (name) => {
    const response = await fetch(new URL(name, base));
    if (!response.ok) throw new Error(`${name}: HTTP ${response.status}`);
    return response;
  };
  const manifest = await (await get('manifest.json')).json();
  if (manifest.format !== FORMAT) {
    throw new Error(`manifest.json: format ${manifest.format}, this page reads ${FORMAT}`);
  }
  const bin = await (await get('clip.bin')).arrayBuffer();
  const arrays = {};
  for (const [name, a] of Object.entries(manifest.arrays)) {
    const count = a.shape.reduce((x, y) => x * y, 1);
    arrays[name] = new TYPES[a.dtype](bin, a.offset, count);
  }
  const blob = new Uint8Array(await (await get(manifest.model)).arrayBuffer());
  return { manifest, arrays, blob };
}

/** The frame shown at `seconds` (finite) into the clip, looping: the time is wrapped into
 *  the clip's length first, so that huge times (1e308 s) still give a frame. */
export function frameAt(manifest, seconds) {
  const length = manifest.frames / manifest.fps;
  const wrapped = ((seconds % length) + length) % length;
  return Math.min(Math.floor(wrapped * manifest.fps + 1e-9), manifest.frames - 1);
}

/** Skins frame `f`'s positions and normals into `positions` and `normals` (vertices × 3,
 *  Float32Array) bit for bit as the trainer does (`trainer/src/rig/skin.rs`, glam): every
 *  operation rounded to f32 in its order (`fround`, or a store to a Float32Array), the normal
 *  through the blend's cofactor matrix and renormalised. Occluder proxies need exactly the
 *  mesh `aprt eval` posed. Scratch arrays, no allocation per vertex. */
export function skinFrame(clip, f, positions, normals) {
  const { manifest: m, arrays: a } = clip;
  const [k, mats, weights, joints, bind, bindNormals] = [m.influences, a.joint_matrices, a.skin_weights,
    a.skin_joints, a.positions, a.normals];
  const base = f * m.joints * 12;
  const fr = Math.fround;
  const b = new Float32Array(12); // the blend, row-major 3 × 4
  const col = new Float32Array(9); // its columns
  const cof = new Float32Array(9); // their cross products: the cofactor matrix's columns
  const n = new Float32Array(3); // the posed normal before renormalising
  const cross = (s, r, o) => {
    cof[o] = fr(col[s + 1] * col[r + 2]) - fr(col[r + 1] * col[s + 2]);
    cof[o + 1] = fr(col[s + 2] * col[r]) - fr(col[r + 2] * col[s]);
    cof[o + 2] = fr(col[s] * col[r + 1]) - fr(col[r] * col[s + 1]);
  };
  const dot = (x, xo, y, yo) => fr(fr(fr(x[xo] * y[yo]) + fr(x[xo + 1] * y[yo + 1])) + fr(x[xo + 2] * y[yo + 2]));
  for (let v = 0; v < m.vertices; v++) {
    b.fill(0);
    for (let i = 0; i < k; i++) {
      const w = weights[v * k + i];
      if (w === 0) continue; // padding: the trainer's skin has no zero weights
      const o = base + joints[v * k + i] * 12;
      for (let c = 0; c < 12; c++) b[c] += fr(mats[o + c] * w);
    }
    const j = v * 3;
    const [x, y, z] = [bind[j], bind[j + 1], bind[j + 2]];
    for (let r = 0; r < 3; r++) {
      positions[j + r] = fr(fr(fr(b[r * 4] * x) + fr(b[r * 4 + 1] * y)) + fr(b[r * 4 + 2] * z)) + b[r * 4 + 3];
    }
    for (let c = 0; c < 3; c++) for (let r = 0; r < 3; r++) col[c * 3 + r] = b[r * 4 + c];
    cross(3, 6, 0);
    cross(6, 0, 3);
    cross(0, 3, 6);
    const det = dot(col, 0, cof, 0);
    const sign = det < 0 || Object.is(det, -0) ? -1 : det >= 0 ? 1 : NaN;
    for (let r = 0; r < 3; r++) {
      const u = fr(cof[r] * bindNormals[j]);
      const s = fr(cof[3 + r] * bindNormals[j + 1]);
      n[r] = fr(fr(u + s) + fr(cof[6 + r] * bindNormals[j + 2])) * sign;
    }
    const rcp = fr(1 / fr(Math.sqrt(dot(n, 0, n, 0))));
    const ok = Number.isFinite(rcp) && rcp > 0;
    for (let r = 0; r < 3; r++) normals[j + r] = ok ? n[r] * rcp : bindNormals[j + r];
  }
}

/** Frame `f`'s pose vector, bone rotations and the bones' skinning matrices (a model's bones
 *  are the first joints), as the core takes them. */
export function poseOf(clip, f) {
  const { manifest: m, arrays: a } = clip;
  const bones = a.bone_rotations.length / (m.frames * 9);
  const skinning = f * m.joints * 12;
  return {
    angles: a.angles.subarray(f * m.pose_len, (f + 1) * m.pose_len),
    rotations: a.bone_rotations.subarray(f * bones * 9, (f + 1) * bones * 9),
    skinning: a.joint_matrices.subarray(skinning, skinning + bones * 12),
  };
}
