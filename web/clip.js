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

/** The frame shown at `seconds` into the clip, looping. */
export function frameAt(manifest, seconds) {
  const f = Math.floor(seconds * manifest.fps + 1e-9);
  return ((f % manifest.frames) + manifest.frames) % manifest.frames;
}

/** Skins frame `f`'s positions and normals into `positions` and `normals` (vertices × 3). */
export function skinFrame(clip, f, positions, normals) {
  const { manifest: m, arrays: a } = clip;
  const k = m.influences;
  const mats = a.joint_matrices.subarray(f * m.joints * 12, (f + 1) * m.joints * 12);
  const blended = new Float64Array(12);
  for (let v = 0; v < m.vertices; v++) {
    blended.fill(0);
    for (let i = 0; i < k; i++) {
      const w = a.skin_weights[v * k + i];
      if (w === 0) continue;
      const o = a.skin_joints[v * k + i] * 12;
      for (let c = 0; c < 12; c++) blended[c] += w * mats[o + c];
    }
    const [x, y, z] = a.positions.subarray(v * 3, v * 3 + 3);
    const [nx, ny, nz] = a.normals.subarray(v * 3, v * 3 + 3);
    for (let r = 0; r < 3; r++) {
      const b = blended.subarray(r * 4, r * 4 + 4);
      positions[v * 3 + r] = b[0] * x + b[1] * y + b[2] * z + b[3];
      normals[v * 3 + r] = b[0] * nx + b[1] * ny + b[2] * nz;
    }
  }
}

/** Frame `f`'s pose vector and bone rotations, as the core takes them. */
export function poseOf(clip, f) {
  const { manifest: m, arrays: a } = clip;
  const bones = a.bone_rotations.length / (m.frames * 9);
  return {
    angles: a.angles.subarray(f * m.pose_len, (f + 1) * m.pose_len),
    rotations: a.bone_rotations.subarray(f * bones * 9, (f + 1) * bones * 9),
  };
}
