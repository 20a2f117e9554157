// WebGL2 drawing of the skinned mesh with one shading value per vertex (from the core).
// Radiance is shading × albedo / π, tone-mapped by a gamma of 2.2; the normals only add a
// faint rim so the silhouette reads: all the lighting and self-shadowing is the core's.

const VERTEX = `#version 300 es
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in float shading;
uniform mat4 viewProjection;
uniform mat4 view;
out float vShading;
out vec3 vNormal;
void main() {
  vShading = shading;
  vNormal = mat3(view) * normal;
  gl_Position = viewProjection * vec4(position, 1.0);
}`;

const FRAGMENT = `#version 300 es
precision highp float;
in float vShading;
in vec3 vNormal;
uniform float exposure;
out vec4 color;
void main() {
  float radiance = max(vShading, 0.0) * 0.6 / 3.14159265 * exposure;
  float rim = pow(1.0 - abs(normalize(vNormal).z), 4.0) * 0.06;
  vec3 linear = vec3(radiance) * vec3(1.0, 0.96, 0.9) + rim;
  color = vec4(pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}`;

function compile(gl, type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
  return shader;
}

/** A perspective camera looking at the bind mesh's bounding box from the front, `up` up. */
export function camera(positions, up, aspect) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    lo[i % 3] = Math.min(lo[i % 3], positions[i]);
    hi[i % 3] = Math.max(hi[i % 3], positions[i]);
  }
  const centre = lo.map((l, i) => (l + hi[i]) / 2);
  const size = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  // The built-in characters face -y with z up: the eye is in front, slightly to the side.
  const forward = up[2] !== 0 ? [0.35, -1, 0.15] : [0.35, 0.15, 1];
  const eye = centre.map((c, i) => c + forward[i] * size * 1.25);
  const view = lookAt(eye, centre, up);
  const projection = perspective(0.7, aspect, size * 0.1, size * 10);
  return { view, viewProjection: multiply(projection, view) };
}

function normalize(v) {
  const n = Math.hypot(...v);
  return v.map((x) => x / n);
}

function cross(a, b) {
  return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
}

/** Column-major 4 × 4 view matrix. */
function lookAt(eye, target, up) {
  const z = normalize(eye.map((e, i) => e - target[i]));
  const x = normalize(cross(up, z));
  const y = cross(z, x);
  const dot = (a) => a[0] * eye[0] + a[1] * eye[1] + a[2] * eye[2];
  return [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x), -dot(y), -dot(z), 1];
}

function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2);
  const nf = 1 / (near - far);
  return [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0];
}

function multiply(a, b) {
  const out = new Array(16).fill(0);
  for (let c = 0; c < 4; c++)
    for (let r = 0; r < 4; r++) for (let k = 0; k < 4; k++) out[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
  return out;
}

/** The mesh on the GPU: `draw` uploads this frame's positions, normals and shading. */
export class Renderer {
  constructor(canvas, indices, vertices) {
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true });
    if (!gl) throw new Error('WebGL2 is not available');
    this.gl = gl;
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, FRAGMENT));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
    this.program = program;
    this.vao = gl.createVertexArray();
    gl.bindVertexArray(this.vao);
    this.buffers = [3, 3, 1].map((size, location) => {
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, vertices * size * 4, gl.DYNAMIC_DRAW);
      gl.enableVertexAttribArray(location);
      gl.vertexAttribPointer(location, size, gl.FLOAT, false, 0, 0);
      return buffer;
    });
    const ibo = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ibo);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indices, gl.STATIC_DRAW);
    this.count = indices.length;
  }

  draw(cam, positions, normals, shading, exposure = 1) {
    const gl = this.gl;
    gl.viewport(0, 0, gl.canvas.width, gl.canvas.height);
    gl.clearColor(0.16, 0.17, 0.2, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(this.program);
    gl.bindVertexArray(this.vao);
    [positions, normals, shading].forEach((data, i) => {
      gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers[i]);
      gl.bufferSubData(gl.ARRAY_BUFFER, 0, data);
    });
    const uniform = (name) => gl.getUniformLocation(this.program, name);
    gl.uniformMatrix4fv(uniform('viewProjection'), false, cam.viewProjection);
    gl.uniformMatrix4fv(uniform('view'), false, cam.view);
    gl.uniform1f(uniform('exposure'), exposure);
    gl.drawElements(gl.TRIANGLES, this.count, gl.UNSIGNED_INT, 0);
  }
}
