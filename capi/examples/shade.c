/*
 * Shades one frame of a model through the C ABI and prints every output as the hex bits of
 * its floats, so a test can compare them with the Rust path's to the last bit.
 *
 *   cc -std=c11 -ffp-contract=off -I capi/include capi/examples/shade.c \
 *      target/release/libaprt_capi.a -lpthread -ldl -lm -o shade
 *   ./shade fixtures/golden/v1-bones.aprt
 *
 * The frame: a resident model, a pose, SH lighting from a directional light, shading and
 * transfer of every vertex; three lights per vertex; the occluder proxies' occlusion of the
 * shading and the transfer when the model has proxies; the irradiance rig when the model has
 * one; light maps composed from the transfer; and the same shading (and occlusion) through a
 * streamed model. Inputs are literal tables (no arithmetic), so C and Rust start from the same
 * bits.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aprt.h"

static const float ANGLES[8] = {0.1f, -0.2f, 0.3f, 0.05f, -0.15f, 0.25f, 0.0f, 0.4f};
static const float POSITIONS[8][3] = {
    {0.0f, 0.0f, 0.0f},  {0.5f, 0.1f, 0.2f},  {-0.3f, 0.4f, 0.1f}, {0.2f, -0.5f, 0.6f},
    {0.1f, 0.3f, -0.4f}, {-0.6f, 0.2f, 0.3f}, {0.4f, 0.4f, 0.4f},  {0.0f, -0.2f, 0.8f},
};
static const float SKY_DIR[3] = {0.5f, -0.8f, 0.9f};
/* A quarter turn's 3-4-5 cousin about z: exactly orthonormal. */
static const float TURN[9] = {0.8f, -0.6f, 0.0f, 0.6f, 0.8f, 0.0f, 0.0f, 0.0f, 1.0f};
static const float IDENTITY[9] = {1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f};
/* The translation of every bone's skinning matrix (its rotation is the bone's, above). */
static const float SHIFT[3] = {0.05f, -0.1f, 0.2f};
/* The vertices' normals, cycled like POSITIONS (the last one zero: it sees no proxy). */
static const float NORMALS[8][3] = {
    {0.0f, 0.0f, 1.0f},  {0.6f, 0.0f, 0.8f},  {0.0f, 0.6f, 0.8f}, {-0.6f, 0.0f, 0.8f},
    {0.0f, -0.6f, 0.8f}, {0.0f, 0.0f, -1.0f}, {0.8f, 0.0f, 0.6f}, {0.0f, 0.0f, 0.0f},
};

static const aprt_light LIGHTS[3] = {
    {APRT_LIGHT_SPHERE, {0.5f, 1.0f, 2.0f}, {0.0f, 0.0f, 0.0f}, 0.3f, {2.0f, 1.5f, 1.0f}},
    {APRT_LIGHT_POINT, {-1.0f, 0.5f, 1.0f}, {0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 1.0f, 1.0f}},
    {APRT_LIGHT_DIRECTIONAL, {0.0f, 0.0f, 0.0f}, {0.3f, -0.2f, 0.9f}, 0.0f, {0.5f, 0.6f, 0.7f}},
};
static const float WEIGHTS[3] = {1.0f, 0.5f, 1.0f};
static const aprt_placement PLACE = {
    {{0.8f, 0.0f, -0.6f}, {0.0f, 1.0f, 0.0f}, {0.6f, 0.0f, 0.8f}}, {0.1f, 0.0f, -0.2f}};

static void check(aprt_status s, const char *what) {
  if (s != APRT_STATUS_OK) {
    fprintf(stderr, "shade: %s: %s (status %d)\n", what, aprt_status_message(s), (int)s);
    exit(1);
  }
}

static void *zalloc(size_t count, size_t size) {
  void *p = calloc(count ? count : 1, size);
  if (!p) {
    fprintf(stderr, "shade: out of memory\n");
    exit(1);
  }
  return p;
}

/* Handle storage: aligned to what the library asks. */
static void *storage(size_t size, size_t align) {
  void *p = aligned_alloc(align, (size + align - 1) / align * align);
  if (!p) {
    fprintf(stderr, "shade: out of memory\n");
    exit(1);
  }
  return p;
}

static void print(const char *name, const float *v, size_t n) {
  printf("%s %zu", name, n);
  for (size_t i = 0; i < n; i++) {
    unsigned int bits;
    memcpy(&bits, &v[i], sizeof bits);
    printf(" %08x", bits);
  }
  printf("\n");
}

static unsigned char *read_file(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "shade: cannot open %s\n", path);
    exit(1);
  }
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  unsigned char *bytes = zalloc((size_t)n, 1);
  if (n < 0 || fread(bytes, 1, (size_t)n, f) != (size_t)n) {
    fprintf(stderr, "shade: cannot read %s\n", path);
    exit(1);
  }
  fclose(f);
  *len = (size_t)n;
  return bytes;
}

/* The stream's read callback: the blob in memory, copied as flash would be. */
typedef struct {
  const unsigned char *bytes;
  size_t len;
} memory;

static int32_t read_at(void *user, uint64_t offset, uint8_t *buf, size_t len) {
  const memory *m = user;
  if (offset > m->len || len > m->len - offset) return 1;
  memcpy(buf, m->bytes + offset, len);
  return 0;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: shade MODEL.aprt\n");
    return 2;
  }
  if (aprt_abi_version() != APRT_ABI_VERSION) {
    fprintf(stderr, "shade: header ABI %d, library ABI %u\n", APRT_ABI_VERSION,
            aprt_abi_version());
    return 1;
  }
  size_t blob_len;
  unsigned char *blob = read_file(argv[1], &blob_len);

  /* The model, validated once; it reads the blob in place. */
  aprt_model *model;
  void *model_mem = storage(aprt_model_size(), aprt_model_align());
  check(aprt_model_init(blob, blob_len, model_mem, aprt_model_size(), &model), "model");
  aprt_model_info info;
  check(aprt_model_get_info(model, &info), "info");
  printf("model order %u coeffs %u vertices %u pose_len %u bones %u rig %u atlas %d"
         " proxies %d\n",
         info.order, info.coeffs, info.vertices, info.pose_len, info.bones, info.rig_vectors,
         (int)info.has_atlas, (int)info.has_proxies);

  aprt_frame *frame;
  void *frame_mem = storage(aprt_frame_size(), aprt_frame_align());
  check(aprt_frame_init(frame_mem, aprt_frame_size(), &frame), "frame");

  /* Pose, SH lighting, bones' rotations. */
  size_t n = info.vertices, n2 = info.coeffs;
  float *angles = zalloc(info.pose_len, sizeof(float));
  for (size_t i = 0; i < info.pose_len; i++) angles[i] = ANGLES[i % 8];
  float *bones = zalloc(9 * (size_t)info.bones, sizeof(float));
  for (size_t b = 0; b < info.bones; b++) memcpy(&bones[9 * b], b % 2 ? TURN : IDENTITY, 36);
  float sky[36];
  check(aprt_project_directional(info.order, SKY_DIR, 3.0f, sky, 36), "sky");
  check(aprt_set_pose(model, frame, angles, info.pose_len), "pose");
  check(aprt_light_sh(model, frame, sky, n2, bones, info.bones), "light");

  float *shading = zalloc(n, sizeof(float));
  check(aprt_shade(model, frame, 0, shading, n), "shade");
  print("shade", shading, n);
  float *transfer = zalloc(n * n2, sizeof(float));
  check(aprt_transfer(model, frame, 0, transfer, n * n2), "transfer");
  print("transfer", transfer, n * n2);

  /* Lights per vertex, at each vertex's position. */
  float *positions = zalloc(3 * n, sizeof(float));
  for (size_t j = 0; j < n; j++) memcpy(&positions[3 * j], POSITIONS[j % 8], 12);
  float *rgb = zalloc(3 * n, sizeof(float));
  check(aprt_shade_lights(model, frame, bones, info.bones, LIGHTS, WEIGHTS, 3, positions, 0, rgb,
                          n),
        "lights");
  print("lights", rgb, 3 * n);

  /* The occluder proxies: each bone's skinning matrix is its rotation with SHIFT as the
   * translation (3 x 4, row-major); normals from the table. Shading and transfer lose what
   * the posed spheres block. */
  float *skinning = zalloc(12 * (size_t)info.bones, sizeof(float));
  for (size_t b = 0; b < info.bones; b++)
    for (size_t r = 0; r < 3; r++) {
      memcpy(&skinning[12 * b + 4 * r], &bones[9 * b + 3 * r], 12);
      skinning[12 * b + 4 * r + 3] = SHIFT[r];
    }
  float *normals = zalloc(3 * n, sizeof(float));
  for (size_t j = 0; j < n; j++) memcpy(&normals[3 * j], NORMALS[j % 8], 12);
  aprt_proxy_frame *proxies;
  void *proxies_mem = storage(aprt_proxy_frame_size(), aprt_proxy_frame_align());
  check(aprt_proxy_frame_init(proxies_mem, aprt_proxy_frame_size(), &proxies), "proxy frame");
  if (info.has_proxies) {
    check(aprt_pose_proxies(model, skinning, 12 * (size_t)info.bones, proxies), "pose proxies");
    float *occluded = zalloc(n * n2, sizeof(float));
    memcpy(occluded, shading, n * sizeof(float));
    check(aprt_occlude(model, proxies, sky, n2, positions, normals, 0, occluded, n), "occlude");
    print("occluded", occluded, n);
    memcpy(occluded, transfer, n * n2 * sizeof(float));
    check(aprt_occlude_transfer(model, proxies, bones, info.bones, positions, normals, 0, n,
                                occluded, n * n2),
          "occlude transfer");
    print("occluded_transfer", occluded, n * n2);
    free(occluded);
  }

  /* The irradiance rig: its vectors from the lights, then rig-lit shading. */
  size_t k = info.rig_vectors;
  float *vectors = zalloc(3 * k * n2, sizeof(float));
  if (info.has_rig) {
    float share;
    check(aprt_rig_share(model, &LIGHTS[0], &PLACE, 1.0f, 0.25f, &share), "share");
    print("share", &share, 1);
    check(aprt_rig_vectors(model, &PLACE, LIGHTS, 3, NULL, 0, vectors, k * n2), "rig vectors");
    print("vectors", vectors, 3 * k * n2);
    float *rig_lit = zalloc(info.rig_lit_len, sizeof(float));
    check(aprt_light_rig(model, frame, vectors, k * n2, bones, info.bones, rig_lit,
                         info.rig_lit_len),
          "light rig");
    check(aprt_shade_rig(model, frame, &PLACE, positions, 0, rgb, n), "shade rig");
    print("rig", rgb, 3 * n);
    free(rig_lit);
  }

  /* Light maps: the posed transfer as n texels, composed three ways. */
  float env[36 * 3];
  for (size_t c = 0; c < n2; c++) env[3 * c] = env[3 * c + 1] = env[3 * c + 2] = sky[c];
  check(aprt_lightmap_compose(info.order, transfer, n * n2, env, n2, rgb, n), "compose");
  print("lightmap", rgb, 3 * n);
  check(aprt_lightmap_compose_lights(info.order, transfer, n * n2, positions, LIGHTS, 3, env, n2,
                                     rgb, n),
        "compose lights");
  print("lightmap_lights", rgb, 3 * n);
  if (info.has_rig) {
    check(aprt_lightmap_compose_rig(model, transfer, n * n2, vectors, k * n2, &PLACE, positions,
                                    rgb, n),
          "compose rig");
    print("lightmap_rig", rgb, 3 * n);
  }

  /* The same frame streamed: the first call asks for the scratch (from the header). */
  memory mem = {blob, blob_len};
  aprt_source source = {read_at, &mem, blob_len};
  aprt_model *streamed;
  void *streamed_mem = storage(aprt_model_size(), aprt_model_align());
  unsigned char *scratch = NULL;
  size_t scratch_len = 0, needed = 0;
  aprt_status s;
  while ((s = aprt_model_stream_init(&source, scratch, scratch_len, &needed, streamed_mem,
                                     aprt_model_size(), &streamed)) ==
         APRT_STATUS_BUFFER_TOO_SMALL) {
    free(scratch);
    scratch = zalloc(needed, 1);
    scratch_len = needed;
  }
  check(s, "stream");
  check(aprt_frame_init(frame_mem, aprt_frame_size(), &frame), "frame again");
  check(aprt_set_pose(streamed, frame, angles, info.pose_len), "streamed pose");
  check(aprt_light_sh(streamed, frame, sky, n2, bones, info.bones), "streamed light");
  check(aprt_shade(streamed, frame, 0, shading, n), "streamed shade");
  print("streamed", shading, n);
  if (info.has_proxies) {
    check(aprt_proxy_frame_init(proxies_mem, aprt_proxy_frame_size(), &proxies),
          "proxy frame again");
    check(aprt_pose_proxies(streamed, skinning, 12 * (size_t)info.bones, proxies),
          "streamed pose proxies");
    check(aprt_occlude(streamed, proxies, sky, n2, positions, normals, 0, shading, n),
          "streamed occlude");
    print("streamed_occluded", shading, n);
    check(aprt_transfer(streamed, frame, 0, transfer, n * n2), "streamed transfer");
    check(aprt_occlude_transfer(streamed, proxies, bones, info.bones, positions, normals, 0, n,
                                transfer, n * n2),
          "streamed occlude transfer");
    print("streamed_occluded_transfer", transfer, n * n2);
  }

  free(proxies_mem), free(normals), free(skinning);
  free(scratch), free(streamed_mem), free(vectors), free(rgb), free(positions);
  free(transfer), free(shading), free(bones), free(angles);
  free(frame_mem), free(model_mem), free(blob);
  return 0;
}
