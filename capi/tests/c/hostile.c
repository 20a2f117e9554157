/*
 * The C ABI used the way a careless or hostile engine would: every entry point with every
 * wrong kind of handle, every length at 0, 1, the limit, one past it and SIZE_MAX, mirrored
 * and scaled rotations, NaN, infinities and FLT_MAX in every float argument, and read
 * callbacks that fail, return short or re-enter. Each misuse must get the status aprt.h
 * documents for it, and no call may return APRT_STATUS_OK with a non-finite output.
 *
 *   hostile MODEL.aprt... [--accepting-or-refusing MODEL.aprt...]
 *
 * Each model is checked resident and streamed. Models after --accepting-or-refusing are
 * hostile blobs (valid checksums, hostile values): they may be refused with a blob status
 * or accepted, and if accepted a whole frame must give finite outputs or a status.
 * Exits 0 when every check holds, 1 otherwise (each failure on stderr); C99, so it also
 * shows that aprt.h needs nothing newer.
 */
#define _POSIX_C_SOURCE 200112L

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aprt.h"

#define OK APRT_STATUS_OK
#define WRONG_LENGTH APRT_STATUS_WRONG_LENGTH
#define VERTEX_RANGE APRT_STATUS_VERTEX_RANGE
#define BAD_ROTATION APRT_STATUS_BAD_ROTATION
#define BAD_LIGHT APRT_STATUS_BAD_LIGHT

/* ---- Checks -------------------------------------------------------------------------- */

static unsigned long checks, failures;
/* The model and handle kind under test, for messages. */
static char subject[512];

static void failed(int line, const char *what, const char *detail) {
  failures++;
  fprintf(stderr, "hostile: %s: line %d: %s: %s\n", subject, line, what, detail);
}

/* `got` must be `want`. */
static void status_is(aprt_status got, aprt_status want, const char *what, int line) {
  checks++;
  if (got == want) return;
  char detail[256];
  snprintf(detail, sizeof detail, "status %d (%s), want %d (%s)", (int)got,
           aprt_status_message(got), (int)want, aprt_status_message(want));
  failed(line, what, detail);
}
#define EXPECT(want, call) status_is((call), (want), #call, __LINE__)

/* `got` must not be OK and must lie in [lo, hi]. */
static void refused_in(aprt_status got, int lo, int hi, const char *what, int line) {
  checks++;
  if (got != OK && (int)got >= lo && (int)got <= hi) return;
  char detail[160];
  snprintf(detail, sizeof detail, "status %d (%s), want one in %d..=%d", (int)got,
           aprt_status_message(got), lo, hi);
  failed(line, what, detail);
}

/* After OK, every one of the `n` floats at `v` must be finite; returns `s`. */
static aprt_status finite_if_ok(aprt_status s, const float *v, size_t n, const char *what,
                                int line) {
  checks++;
  if (s == APRT_STATUS_PANIC) failed(line, what, "the library panicked");
  if (s != OK) return s;
  for (size_t i = 0; i < n; i++) {
    if (!isfinite(v[i])) {
      char detail[128];
      snprintf(detail, sizeof detail, "status OK with output %zu = %g", i, (double)v[i]);
      failed(line, what, detail);
      break;
    }
  }
  return s;
}
#define FINITE(call, v, n) finite_if_ok((call), (v), (n), #call, __LINE__)

/* ---- Memory ---------------------------------------------------------------------------- */

static void *must(void *p) {
  if (!p) {
    fprintf(stderr, "hostile: out of memory\n");
    exit(2);
  }
  return p;
}

/* `n` floats and one spare (so "one past the limit" stays inside), zeroed. */
static float *floats(size_t n) { return must(calloc(n + 1, sizeof(float))); }

/* Exactly `size` bytes aligned to `align`: a read past a handle is past its block. */
static void *block(size_t size, size_t align) {
  void *p = NULL;
  if (posix_memalign(&p, align < sizeof(void *) ? sizeof(void *) : align, size)) p = NULL;
  return memset(must(p), 0, size);
}

static unsigned char *read_file(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "hostile: cannot open %s\n", path);
    exit(2);
  }
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  unsigned char *bytes = must(malloc(n > 0 ? (size_t)n : 1));
  if (n < 0 || fread(bytes, 1, (size_t)n, f) != (size_t)n) {
    fprintf(stderr, "hostile: cannot read %s\n", path);
    exit(2);
  }
  fclose(f);
  *len = (size_t)n;
  return bytes;
}

/* ---- The stream's source ----------------------------------------------------------------- */

typedef enum { READ_PLAIN, READ_FAIL, READ_SHORT, READ_REENTER } read_mode;

/* A blob in memory behind the read callback, which can be told to misbehave. */
typedef struct source {
  const unsigned char *bytes;
  size_t len;
  read_mode mode;
  unsigned long reads;      /* calls so far */
  unsigned long fail_after; /* READ_FAIL: reads that still succeed */
  /* READ_REENTER: the model this source feeds, another model, and what calls into each
   * from inside the callback returned. */
  const aprt_model *self, *other;
  aprt_frame *frame;
  const float *angles;
  size_t pose_len;
  aprt_status inner_info, inner_pose, inner_other;
  struct source *nested; /* a source to open a second model from inside the callback */
  aprt_status inner_open;
  int depth;
} source;

static aprt_status open_stream(source *src, unsigned char **scratch, size_t *scratch_len,
                               void *storage, aprt_model **out);

/* What READ_REENTER does inside a read: call the model being read (BUSY), another model
 * (fine) and open a new stream (fine). */
static void reenter(source *s) {
  if (s->depth++ > 0) return;
  aprt_model_info info;
  if (s->self) {
    s->inner_info = aprt_model_get_info(s->self, &info);
    s->inner_pose = aprt_set_pose(s->self, s->frame, s->angles, s->pose_len);
  }
  if (s->other) s->inner_other = aprt_model_get_info(s->other, &info);
  if (s->nested) {
    unsigned char *scratch = NULL;
    size_t scratch_len = 0;
    void *storage = block(aprt_model_size(), aprt_model_align());
    aprt_model *m;
    s->inner_open = open_stream(s->nested, &scratch, &scratch_len, storage, &m);
    free(scratch), free(storage);
  }
  s->depth--;
}

static int32_t read_at(void *user, uint64_t offset, uint8_t *buf, size_t len) {
  source *s = user;
  s->reads++;
  if (offset > s->len || len > s->len - offset) return 1;
  switch (s->mode) {
    case READ_FAIL:
      if (s->fail_after == 0) return 1;
      s->fail_after--;
      break;
    case READ_SHORT:
      /* Claims success with half the bytes; the rest of `buf` keeps what it held. */
      memcpy(buf, s->bytes + offset, len / 2);
      return 0;
    case READ_REENTER:
      reenter(s);
      break;
    case READ_PLAIN:
      break;
  }
  memcpy(buf, s->bytes + offset, len);
  return 0;
}

/* Opens `src` as a streamed model, growing `*scratch` while the library asks (at most
 * three times). */
static aprt_status open_stream(source *src, unsigned char **scratch, size_t *scratch_len,
                               void *storage, aprt_model **out) {
  aprt_source s = {read_at, src, src->len};
  aprt_status status = OK;
  for (int i = 0; i < 3; i++) {
    size_t needed = 0;
    status = aprt_model_stream_init(&s, *scratch, *scratch_len, &needed, storage,
                                    aprt_model_size(), out);
    if (status != APRT_STATUS_BUFFER_TOO_SMALL) return status;
    if (needed <= *scratch_len) return status;
    free(*scratch);
    *scratch = must(calloc(needed, 1));
    *scratch_len = needed;
  }
  return status;
}

/* ---- The fixture ------------------------------------------------------------------------- */

/* One model, both kinds of handle to it, a frame, a proxy frame, and valid inputs for every
 * call, each array exactly its limit plus one spare. */
typedef struct {
  const char *path;
  unsigned char *blob;
  size_t blob_len;
  source src;
  unsigned char *scratch;
  size_t scratch_len;
  void *resident_mem, *streamed_mem, *frame_mem, *proxies_mem;
  aprt_model *resident, *streamed;
  const aprt_model *model; /* the one under test: resident or streamed */
  aprt_frame *frame;
  aprt_proxy_frame *proxies;
  aprt_model_info info;
  size_t n, n2, nb, k, pose_len;
  float *angles, *bones, *sky, *shading, *transfer, *positions, *normals, *rgb, *skinning;
  float *vectors, *rig_lit, *env;
  uint16_t *vertex_bones;
  aprt_light lights[APRT_MAX_LIGHTS + 1];
  float weights[APRT_MAX_LIGHTS + 1];
  aprt_placement place;
} fixture;

static const aprt_light LIGHTS[3] = {
    {APRT_LIGHT_SPHERE, {0.5f, 1.0f, 2.0f}, {0.0f, 0.0f, 0.0f}, 0.3f, {2.0f, 1.5f, 1.0f}},
    {APRT_LIGHT_POINT, {-1.0f, 0.5f, 1.0f}, {0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 1.0f, 1.0f}},
    {APRT_LIGHT_DIRECTIONAL, {0.0f, 0.0f, 0.0f}, {0.3f, -0.2f, 0.9f}, 0.0f, {0.5f, 0.6f, 0.7f}},
};
static const float TURN[9] = {0.8f, -0.6f, 0.0f, 0.6f, 0.8f, 0.0f, 0.0f, 0.0f, 1.0f};
static const aprt_placement PLACE = {
    {{0.8f, 0.0f, -0.6f}, {0.0f, 1.0f, 0.0f}, {0.6f, 0.0f, 0.8f}}, {0.1f, 0.0f, -0.2f}};
static const float SKY_DIR[3] = {0.5f, -0.8f, 0.9f};

/* Fills every input with valid values (again, after a check poisoned one). */
static void fill_inputs(fixture *f) {
  for (size_t i = 0; i <= f->pose_len; i++) f->angles[i] = 0.05f * (float)(i % 7) - 0.1f;
  for (size_t b = 0; b <= f->nb; b++) {
    memcpy(&f->bones[9 * b], TURN, sizeof TURN);
    for (size_t r = 0; r < 3; r++) {
      memcpy(&f->skinning[12 * b + 4 * r], &TURN[3 * r], 3 * sizeof(float));
      f->skinning[12 * b + 4 * r + 3] = 0.1f * (float)r;
    }
  }
  memset(f->sky, 0, 37 * sizeof(float));
  aprt_project_directional(f->info.order, SKY_DIR, 3.0f, f->sky, 36);
  for (size_t c = 0; c <= f->n2; c++) {
    for (int i = 0; i < 3; i++) f->env[3 * c + (size_t)i] = c < f->n2 ? f->sky[c] : 0.0f;
  }
  for (size_t j = 0; j <= f->n; j++) {
    for (int i = 0; i < 3; i++) {
      f->positions[3 * j + (size_t)i] = 0.1f * (float)((j + (size_t)i) % 9) - 0.4f;
      f->normals[3 * j + (size_t)i] = i == 2 ? 1.0f : 0.3f * (float)(j % 3) - 0.3f;
    }
  }
  for (size_t i = 0; i <= 3 * f->k * f->n2; i++) f->vectors[i] = 0.25f;
  for (size_t i = 0; i <= (f->n + 1) * f->n2; i++) f->transfer[i] = 0.01f * (float)(i % 13);
  for (int i = 0; i <= APRT_MAX_LIGHTS; i++) {
    f->lights[i] = LIGHTS[i < 3 ? i : 2];
    f->weights[i] = i < 3 ? 1.0f : 0.01f;
  }
  f->place = PLACE;
}

static void fixture_init(fixture *f, const char *path) {
  memset(f, 0, sizeof *f);
  f->path = path;
  f->blob = read_file(path, &f->blob_len);
  f->resident_mem = block(aprt_model_size(), aprt_model_align());
  f->streamed_mem = block(aprt_model_size(), aprt_model_align());
  f->frame_mem = block(aprt_frame_size(), aprt_frame_align());
  f->proxies_mem = block(aprt_proxy_frame_size(), aprt_proxy_frame_align());
  f->src.bytes = f->blob;
  f->src.len = f->blob_len;
}

/* Opens both handles and sizes the inputs; 0 when the blob is refused (with its status). */
static aprt_status fixture_open(fixture *f) {
  aprt_status s = aprt_model_init(f->blob, f->blob_len, f->resident_mem, aprt_model_size(),
                                  &f->resident);
  if (s != OK) return s;
  s = open_stream(&f->src, &f->scratch, &f->scratch_len, f->streamed_mem, &f->streamed);
  if (s != OK) return s;
  EXPECT(OK, aprt_frame_init(f->frame_mem, aprt_frame_size(), &f->frame));
  EXPECT(OK, aprt_proxy_frame_init(f->proxies_mem, aprt_proxy_frame_size(), &f->proxies));
  EXPECT(OK, aprt_model_get_info(f->resident, &f->info));
  f->model = f->resident;
  f->n = f->info.vertices, f->n2 = f->info.coeffs, f->nb = f->info.bones;
  f->k = f->info.rig_vectors, f->pose_len = f->info.pose_len;
  f->angles = floats(f->pose_len);
  f->bones = floats(9 * (f->nb + 1));
  f->skinning = floats(12 * (f->nb + 1));
  f->sky = floats(36);
  f->env = floats(3 * (f->n2 + 1));
  f->shading = floats(f->n);
  f->transfer = floats((f->n + 1) * f->n2);
  f->positions = floats(3 * (f->n + 1));
  f->normals = floats(3 * (f->n + 1));
  f->rgb = floats(3 * (f->n + 1));
  f->vectors = floats(3 * (f->k * f->n2 + 1));
  f->rig_lit = floats(f->info.rig_lit_len);
  f->vertex_bones = must(calloc(f->n + 1, sizeof(uint16_t)));
  fill_inputs(f);
  return OK;
}

static void fixture_free(fixture *f) {
  free(f->angles), free(f->bones), free(f->skinning), free(f->sky), free(f->env);
  free(f->shading), free(f->transfer), free(f->positions), free(f->normals), free(f->rgb);
  free(f->vectors), free(f->rig_lit), free(f->vertex_bones), free(f->scratch);
  free(f->resident_mem), free(f->streamed_mem), free(f->frame_mem), free(f->proxies_mem);
  free(f->blob);
}

/* ---- Every entry point that takes a handle, as one valid call ------------------------------- */

typedef struct {
  const aprt_model *model;
  aprt_frame *frame;
  aprt_proxy_frame *proxies;
} handles;

static handles own(const fixture *f) {
  handles h = {f->model, f->frame, f->proxies};
  return h;
}

static aprt_status e_info(fixture *f, handles h) {
  aprt_model_info info;
  (void)f;
  return aprt_model_get_info(h.model, &info);
}
static aprt_status e_angle_index(fixture *f, handles h) {
  size_t index;
  (void)f;
  return aprt_model_angle_index(h.model, (const uint8_t *)"no such joint", 13, &index);
}
static aprt_status e_set_pose(fixture *f, handles h) {
  return aprt_set_pose(h.model, h.frame, f->angles, f->pose_len);
}
static aprt_status e_light_sh(fixture *f, handles h) {
  return aprt_light_sh(h.model, h.frame, f->sky, f->n2, f->bones, f->nb);
}
static aprt_status e_shade(fixture *f, handles h) {
  return FINITE(aprt_shade(h.model, h.frame, 0, f->shading, f->n), f->shading, f->n);
}
static aprt_status e_transfer(fixture *f, handles h) {
  size_t len = f->n * f->n2;
  return FINITE(aprt_transfer(h.model, h.frame, 0, f->transfer, len), f->transfer, len);
}
static aprt_status e_vertex_bones(fixture *f, handles h) {
  return aprt_vertex_bones(h.model, 0, f->vertex_bones, f->n);
}
static aprt_status e_shade_lights(fixture *f, handles h) {
  memset(f->rgb, 0, 3 * f->n * sizeof(float));
  return FINITE(aprt_shade_lights(h.model, h.frame, f->bones, f->nb, f->lights, f->weights, 3,
                                  f->positions, 0, f->rgb, f->n),
                f->rgb, 3 * f->n);
}
static aprt_status e_rig_vectors(fixture *f, handles h) {
  size_t count = f->k * f->n2;
  return FINITE(aprt_rig_vectors(h.model, &f->place, f->lights, 3, f->env, f->n2, f->vectors,
                                 count),
                f->vectors, 3 * count);
}
static aprt_status e_rig_share(fixture *f, handles h) {
  float share = 0.0f;
  return FINITE(aprt_rig_share(h.model, &f->lights[0], &f->place, 1.0f, 0.25f, &share), &share,
                1);
}
static aprt_status e_light_rig(fixture *f, handles h) {
  return aprt_light_rig(h.model, h.frame, f->vectors, f->k * f->n2, f->bones, f->nb, f->rig_lit,
                        f->info.rig_lit_len);
}
static aprt_status e_shade_rig(fixture *f, handles h) {
  return FINITE(aprt_shade_rig(h.model, h.frame, &f->place, f->positions, 0, f->rgb, f->n),
                f->rgb, 3 * f->n);
}
static aprt_status e_compose_rig(fixture *f, handles h) {
  return FINITE(aprt_lightmap_compose_rig(h.model, f->transfer, f->n * f->n2, f->vectors,
                                          f->k * f->n2, &f->place, f->positions, f->rgb, f->n),
                f->rgb, 3 * f->n);
}
static aprt_status e_pose_proxies(fixture *f, handles h) {
  return aprt_pose_proxies(h.model, f->skinning, 12 * f->nb, h.proxies);
}
static aprt_status e_occlude(fixture *f, handles h) {
  return FINITE(aprt_occlude(h.model, h.proxies, f->sky, f->n2, f->positions, f->normals, 0,
                             f->shading, f->n),
                f->shading, f->n);
}
static aprt_status e_occlude_transfer(fixture *f, handles h) {
  size_t len = f->n * f->n2;
  return FINITE(aprt_occlude_transfer(h.model, h.proxies, f->bones, f->nb, f->positions,
                                      f->normals, 0, f->n, f->transfer, len),
                f->transfer, len);
}

enum { MODEL = 1, FRAME = 2, PROXIES = 4 };
enum { NEEDS_RIG = 1, NEEDS_PROXIES = 2 };

typedef aprt_status (*entry_fn)(fixture *, handles);

typedef struct {
  const char *name;
  entry_fn call;
  unsigned slots; /* the handles it takes */
  unsigned needs;
  aprt_status without; /* its status when the model lacks what it needs */
  aprt_status valid;   /* its status with valid inputs */
  int reads;           /* whether a streamed model reads the blob for it */
} entry;

/* In the order of a frame. */
static const entry ENTRIES[] = {
    {"get_info", e_info, MODEL, 0, OK, OK, 0},
    {"angle_index", e_angle_index, MODEL, 0, OK, APRT_STATUS_NO_SUCH_NAME, 0},
    {"set_pose", e_set_pose, MODEL | FRAME, 0, OK, OK, 1},
    {"light_sh", e_light_sh, MODEL | FRAME, 0, OK, OK, 0},
    {"shade", e_shade, MODEL | FRAME, 0, OK, OK, 1},
    {"transfer", e_transfer, MODEL | FRAME, 0, OK, OK, 1},
    {"vertex_bones", e_vertex_bones, MODEL, 0, OK, OK, 1},
    {"shade_lights", e_shade_lights, MODEL | FRAME, 0, OK, OK, 1},
    {"rig_vectors", e_rig_vectors, MODEL, NEEDS_RIG, APRT_STATUS_NO_IRRADIANCE_RIG, OK, 0},
    {"rig_share", e_rig_share, MODEL, NEEDS_RIG, APRT_STATUS_NO_IRRADIANCE_RIG, OK, 0},
    {"light_rig", e_light_rig, MODEL | FRAME, NEEDS_RIG, APRT_STATUS_WRONG_LENGTH, OK, 0},
    {"shade_rig", e_shade_rig, MODEL | FRAME, NEEDS_RIG, APRT_STATUS_WEIGHTS_NOT_SET, OK, 1},
    {"compose_rig", e_compose_rig, MODEL, NEEDS_RIG, APRT_STATUS_NO_IRRADIANCE_RIG, OK, 0},
    {"pose_proxies", e_pose_proxies, MODEL | PROXIES, NEEDS_PROXIES, APRT_STATUS_NO_PROXIES, OK,
     0},
    {"occlude", e_occlude, MODEL | PROXIES, NEEDS_PROXIES, APRT_STATUS_NO_PROXIES, OK, 0},
    {"occlude_transfer", e_occlude_transfer, MODEL | PROXIES, NEEDS_PROXIES,
     APRT_STATUS_NO_PROXIES, OK, 0},
};
#define ENTRY_COUNT (sizeof ENTRIES / sizeof ENTRIES[0])

static int has(const fixture *f, unsigned needs) {
  return (!(needs & NEEDS_RIG) || f->info.has_rig) &&
         (!(needs & NEEDS_PROXIES) || f->info.has_proxies);
}

static aprt_status want_valid(const fixture *f, const entry *e) {
  return has(f, e->needs) ? e->valid : e->without;
}

/* A whole frame with valid inputs, each call checked: what every misuse is measured from. */
static void whole_frame(fixture *f) {
  fill_inputs(f);
  for (size_t i = 0; i < ENTRY_COUNT; i++) {
    status_is(ENTRIES[i].call(f, own(f)), want_valid(f, &ENTRIES[i]), ENTRIES[i].name,
              __LINE__);
  }
}

/* The frame's state every check starts from: posed, lit, rig-lit and proxies posed. */
static void prepare(fixture *f) {
  fill_inputs(f);
  handles h = own(f);
  EXPECT(OK, e_set_pose(f, h));
  EXPECT(OK, e_light_sh(f, h));
  if (f->info.has_rig) EXPECT(OK, e_rig_vectors(f, h));
  if (f->info.has_rig) EXPECT(OK, e_light_rig(f, h));
  if (f->info.has_proxies) EXPECT(OK, e_pose_proxies(f, h));
}

/* ---- Wrong handles ------------------------------------------------------------------------- */

typedef struct {
  const char *name;
  void *ptr;
  unsigned kind; /* MODEL, FRAME, PROXIES, or 0 for no handle at all */
  aprt_status want;
} handle_kind;

/* Every entry point with, in each handle slot, every handle of another kind, storage that
 * never held one (zeroed, all ones; 8 bytes, the size of a tag), a misaligned pointer and
 * NULL. The blocks are exact, so a check reading past the smallest handle is a read past a
 * block (valgrind). */
static void wrong_handles(fixture *f) {
  void *zeroed = block(8, 8), *ones = block(8, 8);
  memset(ones, 0xff, 8);
  const handle_kind kinds[] = {
      {"resident model", f->resident, MODEL, APRT_STATUS_BAD_HANDLE},
      {"streamed model", f->streamed, MODEL, APRT_STATUS_BAD_HANDLE},
      {"frame", f->frame, FRAME, APRT_STATUS_BAD_HANDLE},
      {"proxy frame", f->proxies, PROXIES, APRT_STATUS_BAD_HANDLE},
      {"zeroed storage", zeroed, 0, APRT_STATUS_BAD_HANDLE},
      {"all-ones storage", ones, 0, APRT_STATUS_BAD_HANDLE},
      {"misaligned pointer", (char *)f->frame_mem + 4, 0, APRT_STATUS_MISALIGNED},
      {"NULL", NULL, 0, APRT_STATUS_NULL_POINTER},
  };
  prepare(f);
  for (size_t e = 0; e < ENTRY_COUNT; e++) {
    for (unsigned slot = MODEL; slot <= PROXIES; slot <<= 1) {
      if (!(ENTRIES[e].slots & slot)) continue;
      for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
        if (kinds[k].kind == slot) continue;
        handles h = own(f);
        if (slot == MODEL) h.model = kinds[k].ptr;
        if (slot == FRAME) h.frame = kinds[k].ptr;
        if (slot == PROXIES) h.proxies = kinds[k].ptr;
        char what[160];
        snprintf(what, sizeof what, "%s given a %s for its %s", ENTRIES[e].name, kinds[k].name,
                 slot == MODEL ? "model" : slot == FRAME ? "frame" : "proxy frame");
        status_is(ENTRIES[e].call(f, h), kinds[k].want, what, __LINE__);
      }
    }
  }
  free(zeroed), free(ones);
}

/* ---- Lengths --------------------------------------------------------------------------------- */

/* The status of length `len` where exactly `limit` is right. */
static aprt_status exactly(size_t len, size_t limit) { return len == limit ? OK : WRONG_LENGTH; }

/* The status of `count` vertices from `first`. */
static aprt_status range(size_t first, size_t count, size_t n) {
  return first <= n && count <= n - first ? OK : VERTEX_RANGE;
}

#define LENGTHS(limit) {0, 1, (limit), (limit) + 1, SIZE_MAX / 2, SIZE_MAX}
#define LENGTH_COUNT 6

static void lengths_of_pose_and_lighting(fixture *f) {
  const aprt_model *m = f->model;
  aprt_frame *fr = f->frame;
  size_t angles[] = LENGTHS(f->pose_len), sky[] = LENGTHS(f->n2), bones[] = LENGTHS(f->nb);
  for (int i = 0; i < LENGTH_COUNT; i++) {
    EXPECT(exactly(angles[i], f->pose_len), aprt_set_pose(m, fr, f->angles, angles[i]));
  }
  EXPECT(OK, aprt_set_pose(m, fr, f->angles, f->pose_len));
  for (int i = 0; i < LENGTH_COUNT; i++) {
    EXPECT(exactly(sky[i], f->n2), aprt_light_sh(m, fr, f->sky, sky[i], f->bones, f->nb));
    /* A world-frame model takes no rotations: even one is refused. */
    EXPECT(exactly(bones[i], f->nb), aprt_light_sh(m, fr, f->sky, f->n2, f->bones, bones[i]));
  }
}

/* Shading, transfer and vertex bones over every kind of range. */
static void lengths_of_ranges(fixture *f) {
  const aprt_model *m = f->model;
  aprt_frame *fr = f->frame;
  size_t n = f->n, n2 = f->n2;
  const size_t ranges[][2] = {{0, 0},        {0, 1},        {0, n},           {0, n + 1},
                              {0, SIZE_MAX}, {1, SIZE_MAX}, {0, SIZE_MAX / 2}, {n, 0},
                              {n, 1},        {n + 1, 0},    {SIZE_MAX, 1},    {SIZE_MAX, 0},
                              {SIZE_MAX, SIZE_MAX}};
  prepare(f);
  for (size_t i = 0; i < sizeof ranges / sizeof ranges[0]; i++) {
    size_t first = ranges[i][0], count = ranges[i][1];
    aprt_status want = range(first, count, n);
    size_t end = strlen(subject);
    snprintf(subject + end, sizeof subject - end, " [first %zu, count %zu]", first, count);
    EXPECT(want, FINITE(aprt_shade(m, fr, first, f->shading, count), f->shading,
                        count <= n ? count : 0));
    EXPECT(want, aprt_vertex_bones(m, first, f->vertex_bones, count));
    /* The transfer's length counts floats, n² a vertex. */
    size_t floats = count <= n + 1 ? count * n2 : count;
    EXPECT(want, aprt_transfer(m, fr, first, f->transfer, floats));
    memset(f->rgb, 0, 3 * (n + 1) * sizeof(float));
    EXPECT(want, aprt_shade_lights(m, fr, f->bones, f->nb, f->lights, f->weights, 3,
                                   f->positions, first, f->rgb, count));
    if (f->info.has_rig) {
      EXPECT(want, aprt_shade_rig(m, fr, &f->place, f->positions, first, f->rgb, count));
    }
    if (f->info.has_proxies) {
      EXPECT(want, aprt_occlude(m, f->proxies, f->sky, n2, f->positions, f->normals, first,
                                f->shading, count));
      EXPECT(want, aprt_occlude_transfer(m, f->proxies, f->bones, f->nb, f->positions,
                                         f->normals, first, count, f->transfer, floats));
    }
    subject[end] = '\0';
  }
  if (n2 > 1) EXPECT(WRONG_LENGTH, aprt_transfer(m, fr, 0, f->transfer, 1));
}

/* Light counts: none and APRT_MAX_LIGHTS are fine, one more or SIZE_MAX too many. */
static void lengths_of_lights(fixture *f) {
  const aprt_model *m = f->model;
  size_t counts[] = {0, 1, 3, APRT_MAX_LIGHTS, APRT_MAX_LIGHTS + 1, SIZE_MAX / 2, SIZE_MAX};
  size_t bones[] = LENGTHS(f->nb), n = f->n, n2 = f->n2;
  prepare(f);
  for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
    aprt_status want = counts[i] <= APRT_MAX_LIGHTS ? OK : APRT_STATUS_TOO_MANY_LIGHTS;
    memset(f->rgb, 0, 3 * (n + 1) * sizeof(float));
    EXPECT(want, FINITE(aprt_shade_lights(m, f->frame, f->bones, f->nb, f->lights, f->weights,
                                          counts[i], f->positions, 0, f->rgb, n),
                        f->rgb, 3 * n));
    EXPECT(want, FINITE(aprt_lightmap_compose_lights(f->info.order, f->transfer, n * n2,
                                                     f->positions, f->lights, counts[i], NULL,
                                                     0, f->rgb, n),
                        f->rgb, 3 * n));
    if (f->info.has_rig) {
      EXPECT(want, aprt_rig_vectors(m, &f->place, f->lights, counts[i], NULL, 0, f->vectors,
                                    f->k * n2));
    }
  }
  for (int i = 0; i < LENGTH_COUNT; i++) {
    EXPECT(exactly(bones[i], f->nb),
           aprt_shade_lights(m, f->frame, f->bones, bones[i], f->lights, f->weights, 3,
                             f->positions, 0, f->rgb, n));
  }
}

/* The light maps' lengths: maps, lighting and environment against the texel count. */
static void lengths_of_light_maps(fixture *f) {
  size_t n = f->n, n2 = f->n2;
  uint32_t order = f->info.order;
  size_t coeffs[] = LENGTHS(n2), texels[] = {0, 1, n, SIZE_MAX / 2, SIZE_MAX};
  for (int i = 0; i < LENGTH_COUNT; i++) {
    EXPECT(exactly(coeffs[i], n2),
           aprt_lightmap_compose(order, f->transfer, n * n2, f->env, coeffs[i], f->rgb, n));
    /* The environment is optional: none (0) or exactly n². */
    EXPECT(coeffs[i] == 0 ? OK : exactly(coeffs[i], n2),
           aprt_lightmap_compose_lights(order, f->transfer, n * n2, f->positions, f->lights, 3,
                                        f->env, coeffs[i], f->rgb, n));
  }
  for (size_t i = 0; i < sizeof texels / sizeof texels[0]; i++) {
    size_t t = texels[i], maps = t <= n ? t * n2 : n * n2;
    aprt_status want = t <= n ? OK : WRONG_LENGTH;
    EXPECT(want, aprt_lightmap_compose(order, f->transfer, maps, f->env, n2, f->rgb, t));
    EXPECT(want, aprt_lightmap_compose_lights(order, f->transfer, maps, f->positions,
                                              f->lights, 3, f->env, n2, f->rgb, t));
  }
  size_t maps[] = {0, 1, n * n2 - 1, n * n2 + 1, SIZE_MAX / 2, SIZE_MAX};
  for (size_t i = 0; i < sizeof maps / sizeof maps[0]; i++) {
    EXPECT(WRONG_LENGTH, aprt_lightmap_compose(order, f->transfer, maps[i], f->env, n2, f->rgb,
                                               n));
  }
  uint32_t orders[] = {0, 7, UINT32_MAX};
  for (size_t i = 0; i < 3; i++) {
    EXPECT(APRT_STATUS_BAD_DIMENSION,
           aprt_lightmap_compose(orders[i], f->transfer, n * n2, f->env, n2, f->rgb, n));
  }
}

/* The irradiance rig's lengths: vectors, the buffer, the environment. */
static void lengths_of_the_rig(fixture *f) {
  if (!f->info.has_rig) return;
  const aprt_model *m = f->model;
  size_t kn = f->k * f->n2, n = f->n, lit = f->info.rig_lit_len;
  size_t vectors[] = LENGTHS(kn), env[] = LENGTHS(f->n2), bones[] = LENGTHS(f->nb);
  size_t buffers[] = {0, 1, lit - 1, lit, SIZE_MAX / 2, SIZE_MAX};
  prepare(f);
  for (int i = 0; i < LENGTH_COUNT; i++) {
    /* Enough vectors for the rig, or more, are fine: "at least". */
    EXPECT(vectors[i] >= kn && vectors[i] <= kn + 1 ? OK
           : vectors[i] < kn                       ? APRT_STATUS_BUFFER_TOO_SMALL
                                                   : WRONG_LENGTH,
           aprt_rig_vectors(m, &f->place, f->lights, 3, NULL, 0, f->vectors, vectors[i]));
    EXPECT(env[i] == 0 ? OK : exactly(env[i], f->n2),
           aprt_rig_vectors(m, &f->place, f->lights, 3, f->env, env[i], f->vectors, kn));
    EXPECT(exactly(vectors[i], kn), aprt_light_rig(m, f->frame, f->vectors, vectors[i], f->bones,
                                                   f->nb, f->rig_lit, lit));
    EXPECT(exactly(bones[i], f->nb), aprt_light_rig(m, f->frame, f->vectors, kn, f->bones,
                                                    bones[i], f->rig_lit, lit));
    EXPECT(buffers[i] == lit                  ? OK
           : buffers[i] < lit                 ? APRT_STATUS_WEIGHTS_TOO_SMALL
                                              : WRONG_LENGTH,
           aprt_light_rig(m, f->frame, f->vectors, kn, f->bones, f->nb, f->rig_lit, buffers[i]));
    EXPECT(exactly(vectors[i], kn),
           aprt_lightmap_compose_rig(m, f->transfer, n * f->n2, f->vectors, vectors[i],
                                     &f->place, f->positions, f->rgb, n));
  }
  size_t texels[] = {0, 1, n, SIZE_MAX / 2, SIZE_MAX};
  for (size_t i = 0; i < sizeof texels / sizeof texels[0]; i++) {
    size_t t = texels[i], maps = t <= n ? t * f->n2 : n * f->n2;
    EXPECT(t <= n ? OK : WRONG_LENGTH,
           aprt_lightmap_compose_rig(m, f->transfer, maps, f->vectors, kn, &f->place,
                                     f->positions, f->rgb, t));
  }
}

/* The occluder proxies' lengths: skinning, lighting, rotations. */
static void lengths_of_the_proxies(fixture *f) {
  if (!f->info.has_proxies) return;
  const aprt_model *m = f->model;
  size_t skin[] = LENGTHS(12 * f->nb), sky[] = LENGTHS(f->n2), bones[] = LENGTHS(f->nb);
  size_t n = f->n, n2 = f->n2;
  for (int i = 0; i < LENGTH_COUNT; i++) {
    prepare(f);
    EXPECT(exactly(sky[i], n2), aprt_occlude(m, f->proxies, f->sky, sky[i], f->positions,
                                             f->normals, 0, f->shading, n));
    EXPECT(exactly(bones[i], f->nb),
           aprt_occlude_transfer(m, f->proxies, f->bones, bones[i], f->positions, f->normals, 0,
                                 n, f->transfer, n * n2));
    size_t out_lens[] = {0, 1, n * n2 - 1, n * n2, n * n2 + 1, SIZE_MAX};
    EXPECT(out_lens[i] == n * n2     ? OK
           : out_lens[i] == SIZE_MAX ? VERTEX_RANGE
                                     : WRONG_LENGTH,
           aprt_occlude_transfer(m, f->proxies, f->bones, f->nb, f->positions, f->normals, 0, n,
                                 f->transfer, out_lens[i]));
    /* Last: a failure leaves the proxies unposed. */
    EXPECT(exactly(skin[i], 12 * f->nb), aprt_pose_proxies(m, f->skinning, skin[i], f->proxies));
  }
  EXPECT(APRT_STATUS_WEIGHTS_NOT_SET, aprt_occlude(m, f->proxies, f->sky, n2, f->positions,
                                                   f->normals, 0, f->shading, n));
}

/* Handle storage: 0, 1 and one byte short are too small; the size and SIZE_MAX are fine. */
static void lengths_of_storage(fixture *f) {
  const struct {
    const char *name;
    size_t size;
    void *mem;
  } kinds[] = {{"model", aprt_model_size(), f->resident_mem},
               {"frame", aprt_frame_size(), f->frame_mem},
               {"proxy frame", aprt_proxy_frame_size(), f->proxies_mem}};
  for (int k = 0; k < 3; k++) {
    size_t lens[] = {0, 1, kinds[k].size - 1, kinds[k].size, SIZE_MAX};
    for (int i = 0; i < 5; i++) {
      aprt_status want = lens[i] < kinds[k].size ? APRT_STATUS_STORAGE_TOO_SMALL : OK;
      aprt_model *model;
      aprt_frame *frame;
      aprt_proxy_frame *proxies;
      aprt_status got =
          k == 0   ? aprt_model_init(f->blob, f->blob_len, kinds[k].mem, lens[i], &model)
          : k == 1 ? aprt_frame_init(kinds[k].mem, lens[i], &frame)
                   : aprt_proxy_frame_init(kinds[k].mem, lens[i], &proxies);
      status_is(got, want, kinds[k].name, __LINE__);
    }
  }
  f->resident = NULL;
  EXPECT(OK, aprt_model_init(f->blob, f->blob_len, f->resident_mem, aprt_model_size(),
                             &f->resident));
}

/* Blob and name lengths. */
static void lengths_of_blobs_and_names(fixture *f) {
  aprt_model *m;
  void *mem = block(aprt_model_size(), aprt_model_align());
  unsigned char *longer = must(calloc(f->blob_len + 1, 1));
  memcpy(longer, f->blob, f->blob_len);
  size_t ms = aprt_model_size();
  EXPECT(APRT_STATUS_TRUNCATED, aprt_model_init(f->blob, 0, mem, ms, &m));
  EXPECT(APRT_STATUS_TRUNCATED, aprt_model_init(f->blob, 1, mem, ms, &m));
  EXPECT(OK, aprt_model_init(f->blob, f->blob_len, mem, ms, &m));
  EXPECT(APRT_STATUS_TRAILING_BYTES, aprt_model_init(longer, f->blob_len + 1, mem, ms, &m));
  EXPECT(WRONG_LENGTH, aprt_model_init(f->blob, SIZE_MAX / 2 + 1, mem, ms, &m));
  EXPECT(WRONG_LENGTH, aprt_model_init(f->blob, SIZE_MAX, mem, ms, &m));
  size_t index;
  const uint8_t *name = (const uint8_t *)"no such joint";
  EXPECT(APRT_STATUS_NO_SUCH_NAME, aprt_model_angle_index(f->model, name, 0, &index));
  EXPECT(APRT_STATUS_NO_SUCH_NAME, aprt_model_angle_index(f->model, name, 1, &index));
  EXPECT(WRONG_LENGTH, aprt_model_angle_index(f->model, name, SIZE_MAX, &index));
  const uint8_t not_utf8[] = {0xff, 0xfe, 0x00};
  EXPECT(APRT_STATUS_NO_SUCH_NAME, aprt_model_angle_index(f->model, not_utf8, 3, &index));
  free(longer), free(mem);
}

/* The stream's lengths: the scratch and the source's claimed length. */
static void lengths_of_the_stream(fixture *f) {
  void *mem = block(aprt_model_size(), aprt_model_align());
  aprt_model *m;
  size_t needed = 0, ms = aprt_model_size();
  aprt_source s = {read_at, &f->src, f->src.len};
  f->src.mode = READ_PLAIN;
  EXPECT(APRT_STATUS_BUFFER_TOO_SMALL, aprt_model_stream_init(&s, NULL, 0, &needed, mem, ms, &m));
  unsigned char *scratch = must(calloc(f->scratch_len, 1));
  EXPECT(APRT_STATUS_BUFFER_TOO_SMALL,
         aprt_model_stream_init(&s, scratch, 1, &needed, mem, ms, &m));
  EXPECT(APRT_STATUS_BUFFER_TOO_SMALL,
         aprt_model_stream_init(&s, scratch, f->scratch_len - 1, &needed, mem, ms, &m));
  EXPECT(OK, aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, ms, &m));
  EXPECT(WRONG_LENGTH, aprt_model_stream_init(&s, scratch, SIZE_MAX, &needed, mem, ms, &m));
  size_t storage[] = {0, 1, ms - 1, SIZE_MAX};
  for (int i = 0; i < 4; i++) {
    EXPECT(storage[i] < ms ? APRT_STATUS_STORAGE_TOO_SMALL : OK,
           aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, storage[i], &m));
  }
  uint64_t lens[] = {0, 1, (uint64_t)f->src.len - 1, (uint64_t)f->src.len + 1, UINT64_MAX};
  aprt_status want[] = {APRT_STATUS_TRUNCATED, APRT_STATUS_TRUNCATED, 0, 0, 0};
  for (int i = 0; i < 5; i++) {
    s.len = lens[i];
    aprt_status got = aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, ms, &m);
    /* A source longer or shorter than its blob is refused as the blob it claims to be. */
    if (want[i]) EXPECT(want[i], got);
    else refused_in(got, 100, 218, "stream of a source of the wrong length", __LINE__);
  }
  free(scratch), free(mem);
}

/* ---- Values -------------------------------------------------------------------------------- */

static const float NON_FINITE[] = {NAN, INFINITY, -INFINITY};

/* Sets element `i` of `v` to each non-finite value in turn: `call` must return `want`. Then
 * to ±FLT_MAX, with which it may refuse or succeed, but never with a non-finite output, nor
 * may `then` (the call that reads what `call` made) after it. */
static void poison(fixture *f, float *v, size_t i, aprt_status want, entry_fn call,
                   entry_fn then, const char *what, int line) {
  const float values[] = {NAN, INFINITY, -INFINITY, -FLT_MAX, FLT_MAX};
  size_t end = strlen(subject);
  for (int x = 0; x < 5; x++) {
    prepare(f);
    float keep = v[i];
    v[i] = values[x];
    snprintf(subject + end, sizeof subject - end, " [%s: element %zu = %g]", what, i,
             (double)values[x]);
    aprt_status s = call(f, own(f));
    if (x < 3) {
      status_is(s, want, what, line);
    } else {
      if (s == OK && then) s = then(f, own(f));
      finite_if_ok(s, NULL, 0, what, line);
    }
    v[i] = keep;
    subject[end] = '\0';
  }
}

/* The first and last of `count` floats. */
static void poison_ends(fixture *f, float *v, size_t count, aprt_status want, entry_fn call,
                        entry_fn then, const char *what, int line) {
  if (count == 0) return;
  poison(f, v, 0, want, call, then, what, line);
  if (count > 1) poison(f, v, count - 1, want, call, then, what, line);
}
#define POISON(v, count, want, call, then) \
  poison_ends(f, (v), (count), (want), (call), (then), #call " " #v, __LINE__)

static aprt_status e_lights_and_maps(fixture *f, handles h) {
  (void)h;
  size_t n = f->n;
  return FINITE(aprt_lightmap_compose_lights(f->info.order, f->transfer, n * f->n2, f->positions,
                                             f->lights, 3, f->env, f->n2, f->rgb, n),
                f->rgb, 3 * n);
}
/* Each of the first three lights' SH radiance at a point near the character. */
static aprt_status e_radiance(fixture *f, handles h) {
  const float at[3] = {0.1f, 0.2f, 0.3f};
  float out[36 * 3] = {0.0f};
  (void)h;
  for (int l = 0; l < 3; l++) {
    aprt_status s = aprt_light_radiance_sh(&f->lights[l], f->info.order, at, out, f->n2);
    if (FINITE(s, out, 3 * f->n2) != OK) return s;
  }
  return OK;
}
static aprt_status e_compose(fixture *f, handles h) {
  (void)h;
  return FINITE(aprt_lightmap_compose(f->info.order, f->transfer, f->n * f->n2, f->env, f->n2,
                                      f->rgb, f->n),
                f->rgb, 3 * f->n);
}

/* NaN and infinities in the inputs of the frame's calls. */
static void values_of_the_frame(fixture *f) {
  size_t n = f->n, n2 = f->n2, nb = f->nb;
  POISON(f->angles, f->pose_len, APRT_STATUS_NON_FINITE_ANGLE, e_set_pose, e_transfer);
  POISON(f->sky, n2, APRT_STATUS_NON_FINITE_LIGHTING, e_light_sh, e_shade);
  POISON(f->bones, 9 * nb, BAD_ROTATION, e_light_sh, e_shade);
  POISON(f->bones, 9 * nb, BAD_ROTATION, e_shade_lights, NULL);
  POISON(f->weights, 3, APRT_STATUS_BAD_LIGHT_WEIGHT, e_shade_lights, NULL);
  POISON(f->positions, 3 * n, APRT_STATUS_NON_FINITE_POSITION, e_shade_lights, NULL);
  POISON(f->transfer, n * n2, APRT_STATUS_NON_FINITE_LIGHT_MAP, e_compose, NULL);
  POISON(f->env, 3 * n2, APRT_STATUS_NON_FINITE_LIGHTING, e_compose, NULL);
  POISON(f->transfer, n * n2, APRT_STATUS_NON_FINITE_LIGHT_MAP, e_lights_and_maps, NULL);
  POISON(f->positions, 3 * n, APRT_STATUS_NON_FINITE_POSITION, e_lights_and_maps, NULL);
  POISON(f->env, 3 * n2, APRT_STATUS_NON_FINITE_LIGHTING, e_lights_and_maps, NULL);
  if (f->info.has_rig) {
    POISON(f->env, 3 * n2, APRT_STATUS_NON_FINITE_LIGHTING, e_rig_vectors, e_light_rig);
    POISON(f->vectors, 3 * f->k * n2, APRT_STATUS_NON_FINITE_LIGHTING, e_light_rig, e_shade_rig);
    POISON(f->bones, 9 * nb, BAD_ROTATION, e_light_rig, e_shade_rig);
    POISON(f->positions, 3 * n, APRT_STATUS_NON_FINITE_POSITION, e_shade_rig, NULL);
    POISON(f->vectors, 3 * f->k * n2, APRT_STATUS_NON_FINITE_LIGHTING, e_compose_rig, NULL);
    POISON(f->positions, 3 * n, APRT_STATUS_NON_FINITE_POSITION, e_compose_rig, NULL);
    POISON(f->transfer, n * n2, APRT_STATUS_NON_FINITE_LIGHT_MAP, e_compose_rig, NULL);
  }
  if (f->info.has_proxies) {
    POISON(f->skinning, 12 * nb, APRT_STATUS_BAD_SKINNING, e_pose_proxies, e_occlude);
    POISON(f->sky, n2, APRT_STATUS_NON_FINITE_LIGHTING, e_occlude, NULL);
    POISON(f->positions, 3 * n, APRT_STATUS_NON_FINITE_POSITION, e_occlude, NULL);
    POISON(f->normals, 3 * n, APRT_STATUS_NON_FINITE_NORMAL, e_occlude, NULL);
    POISON(f->bones, 9 * nb, BAD_ROTATION, e_occlude_transfer, NULL);
    POISON(f->positions, 3 * n, APRT_STATUS_NON_FINITE_POSITION, e_occlude_transfer, NULL);
    POISON(f->normals, 3 * n, APRT_STATUS_NON_FINITE_NORMAL, e_occlude_transfer, NULL);
  }
}

/* Every float of each kind of light that its kind uses; the others are ignored. */
static void values_of_lights(fixture *f) {
  entry_fn calls[] = {e_shade_lights, e_lights_and_maps, e_radiance, e_rig_vectors,
                      e_rig_share};
  size_t call_count = f->info.has_rig ? 5 : 3;
  for (size_t c = 0; c < call_count; c++) {
    /* rig_share takes light 0 only. */
    for (int l = 0; l < (calls[c] == e_rig_share ? 1 : 3); l++) {
      aprt_light *light = &f->lights[l];
      int kind = (int)light->kind;
      if (kind != APRT_LIGHT_DIRECTIONAL) {
        POISON(light->position, 3, BAD_LIGHT, calls[c], NULL);
        POISON(light->direction, 3, OK, calls[c], NULL);
      } else {
        POISON(light->direction, 3, BAD_LIGHT, calls[c], NULL);
        POISON(light->position, 3, OK, calls[c], NULL);
      }
      POISON(&light->radius, 1, kind == APRT_LIGHT_SPHERE ? BAD_LIGHT : OK, calls[c], NULL);
      POISON(light->colour, 3, BAD_LIGHT, calls[c], NULL);
      /* Negative colours, a sphere of no radius and a direction of no length. */
      prepare(f);
      light->colour[1] = -0.5f;
      status_is(calls[c](f, own(f)), BAD_LIGHT, "a negative colour", __LINE__);
      fill_inputs(f);
      light->radius = kind == APRT_LIGHT_SPHERE ? 0.0f : -1.0f;
      status_is(calls[c](f, own(f)), kind == APRT_LIGHT_SPHERE ? BAD_LIGHT : OK, "radius",
                __LINE__);
      fill_inputs(f);
      memset(light->direction, 0, sizeof light->direction);
      status_is(calls[c](f, own(f)), kind == APRT_LIGHT_DIRECTIONAL ? BAD_LIGHT : OK,
                "a zero direction", __LINE__);
      fill_inputs(f);
      light->kind = 0;
      status_is(calls[c](f, own(f)), APRT_STATUS_BAD_LIGHT_KIND, "kind 0", __LINE__);
      light->kind = UINT32_MAX;
      status_is(calls[c](f, own(f)), APRT_STATUS_BAD_LIGHT_KIND, "kind UINT32_MAX", __LINE__);
      fill_inputs(f);
    }
  }
  f->weights[1] = -1.0f;
  EXPECT(APRT_STATUS_BAD_LIGHT_WEIGHT, e_shade_lights(f, own(f)));
  fill_inputs(f);
}

/* Bone rotations that are not rotations: mirrored (determinant −1) and scaled. */
static const float NOT_ROTATIONS[][9] = {
    {-1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f},
    {-0.8f, 0.6f, 0.0f, -0.6f, -0.8f, 0.0f, 0.0f, 0.0f, -1.0f},
    {0.0f, 1.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f},
    {1.01f, 0.0f, 0.0f, 0.0f, 1.01f, 0.0f, 0.0f, 0.0f, 1.01f},
    {0.5f, 0.0f, 0.0f, 0.0f, 0.5f, 0.0f, 0.0f, 0.0f, 0.5f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
};
#define NOT_ROTATION_COUNT (sizeof NOT_ROTATIONS / sizeof NOT_ROTATIONS[0])

/* Mirrored and scaled bone rotations and placements. */
static void rotations(fixture *f) {
  entry_fn bone_calls[] = {e_light_sh, e_shade_lights, e_light_rig, e_occlude_transfer};
  unsigned needs[] = {0, 0, NEEDS_RIG, NEEDS_PROXIES};
  entry_fn place_calls[] = {e_rig_vectors, e_rig_share, e_shade_rig, e_compose_rig};
  for (size_t r = 0; r < NOT_ROTATION_COUNT; r++) {
    for (int c = 0; c < 4 && f->nb > 0; c++) {
      if (!has(f, needs[c])) continue;
      for (size_t b = 0; b < f->nb; b += f->nb - 1 > 0 ? f->nb - 1 : 1) {
        prepare(f);
        memcpy(&f->bones[9 * b], NOT_ROTATIONS[r], sizeof NOT_ROTATIONS[r]);
        status_is(bone_calls[c](f, own(f)), BAD_ROTATION, "a bone that is no rotation",
                  __LINE__);
      }
    }
    for (int c = 0; c < 4 && f->info.has_rig; c++) {
      prepare(f);
      memcpy(f->place.rotation, NOT_ROTATIONS[r], sizeof NOT_ROTATIONS[r]);
      status_is(place_calls[c](f, own(f)), BAD_ROTATION, "a placement that is no rotation",
                __LINE__);
    }
  }
  for (int c = 0; c < 4 && f->info.has_rig; c++) {
    for (int i = 0; i < 12; i++) {
      for (int x = 0; x < 3; x++) {
        prepare(f);
        float *v = i < 9 ? &f->place.rotation[i / 3][i % 3] : &f->place.translation[i - 9];
        *v = NON_FINITE[x];
        status_is(place_calls[c](f, own(f)),
                  i < 9 ? BAD_ROTATION : APRT_STATUS_NON_FINITE_POSITION,
                  "a non-finite placement", __LINE__);
      }
    }
  }
  fill_inputs(f);
}

/* The rig's share: its target and band must be finite and not negative. */
static void values_of_the_share(fixture *f) {
  if (!f->info.has_rig) return;
  const float bad[] = {NAN, INFINITY, -INFINITY, -1.0f};
  float share;
  for (int i = 0; i < 4; i++) {
    EXPECT(APRT_STATUS_BAD_LIGHT_WEIGHT,
           aprt_rig_share(f->model, &f->lights[0], &f->place, bad[i], 0.25f, &share));
    EXPECT(APRT_STATUS_BAD_LIGHT_WEIGHT,
           aprt_rig_share(f->model, &f->lights[0], &f->place, 1.0f, bad[i], &share));
  }
  const float fine[] = {0.0f, FLT_MAX, FLT_MIN};
  for (int i = 0; i < 3; i++) {
    for (int l = 0; l < 3; l++) {
      FINITE(aprt_rig_share(f->model, &f->lights[l], &f->place, fine[i], fine[2 - i], &share),
             &share, 1);
    }
  }
}

/* ---- The SH projections (no model) ----------------------------------------------------------- */

static void projections(void) {
  float out[37 * 3];
  const float dir[3] = {0.3f, -0.4f, 0.5f}, zero[3] = {0.0f, 0.0f, 0.0f};
  uint32_t bad_orders[] = {0, 7, UINT32_MAX};
  for (int i = 0; i < 3; i++) {
    EXPECT(APRT_STATUS_BAD_DIMENSION, aprt_project_directional(bad_orders[i], dir, 1.0f, out, 36));
    EXPECT(APRT_STATUS_BAD_DIMENSION,
           aprt_light_radiance_sh(&LIGHTS[i], bad_orders[i], dir, out, 36));
  }
  for (uint32_t order = 1; order <= 6; order++) {
    size_t n2 = (size_t)order * order;
    size_t lens[] = {0, 1, n2 - 1, n2, n2 + 1, SIZE_MAX / 2, SIZE_MAX};
    for (int i = 0; i < 7; i++) {
      aprt_status want = lens[i] > SIZE_MAX / 16 ? WRONG_LENGTH
                         : lens[i] < n2          ? APRT_STATUS_BUFFER_TOO_SMALL
                                                 : OK;
      EXPECT(want, FINITE(aprt_project_directional(order, dir, 2.0f, out, lens[i]), out,
                          lens[i] <= 37 ? lens[i] : 0));
      memset(out, 0, sizeof out);
      for (int l = 0; l < 3; l++) {
        EXPECT(want, FINITE(aprt_light_radiance_sh(&LIGHTS[l], order, dir, out, lens[i]), out,
                            lens[i] <= 36 ? 3 * lens[i] : 0));
      }
    }
  }
  const float intensities[] = {NAN, INFINITY, -INFINITY, -1.0f};
  for (int i = 0; i < 4; i++) {
    EXPECT(BAD_LIGHT, aprt_project_directional(3, dir, intensities[i], out, 9));
  }
  for (uint32_t order = 1; order <= 6; order++) {
    FINITE(aprt_project_directional(order, dir, FLT_MAX, out, 36), out, order * order);
  }
  EXPECT(BAD_LIGHT, aprt_project_directional(3, zero, 1.0f, out, 9));
  for (int c = 0; c < 3; c++) {
    for (int x = 0; x < 3; x++) {
      float d[3] = {dir[0], dir[1], dir[2]};
      d[c] = NON_FINITE[x];
      EXPECT(BAD_LIGHT, aprt_project_directional(3, d, 1.0f, out, 9));
      for (int l = 0; l < 3; l++) EXPECT(BAD_LIGHT, aprt_light_radiance_sh(&LIGHTS[l], 3, d, out, 9));
    }
  }
  /* At a point light or sphere centre, and ever nearer to it: finite or refused. */
  for (int l = 0; l < 2; l++) {
    for (int e = 0; e <= 45; e++) {
      float at[3] = {LIGHTS[l].position[0] + ldexpf(1.0f, -e * 3), LIGHTS[l].position[1],
                     LIGHTS[l].position[2]};
      if (e == 45) at[0] = LIGHTS[l].position[0];
      memset(out, 0, sizeof out);
      FINITE(aprt_light_radiance_sh(&LIGHTS[l], 3, at, out, 9), out, 27);
    }
  }
}

static void status_messages(void) {
  const int32_t codes[] = {INT32_MIN, -1, 0, 1, 99, 100, 199, 219, 220, 999, 1000, INT32_MAX};
  for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
    const char *m = aprt_status_message(codes[i]);
    checks++;
    if (!m || !m[0]) failed(__LINE__, "aprt_status_message", "NULL or empty");
  }
  checks++;
  if (aprt_abi_version() != APRT_ABI_VERSION) failed(__LINE__, "aprt_abi_version", "differs");
  const char *v = aprt_version();
  checks++;
  if (!v || !v[0]) failed(__LINE__, "aprt_version", "NULL or empty");
}

/* ---- Read callbacks ---------------------------------------------------------------------------- */

/* A callback that fails at its first read, at its second, ... gives SOURCE at init (every
 * count up to 64, then spread over the rest); one that fails after init gives SOURCE from
 * every call that reads and OK from those that do not. */
static void failing_reads(fixture *f) {
  void *mem = block(aprt_model_size(), aprt_model_align());
  unsigned char *scratch = must(calloc(f->scratch_len, 1));
  size_t needed, ms = aprt_model_size();
  aprt_model *m;
  aprt_source s = {read_at, &f->src, f->src.len};
  f->src.mode = READ_PLAIN, f->src.reads = 0;
  EXPECT(OK, aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, ms, &m));
  unsigned long total = f->src.reads, step = total / 64 + 1;
  for (unsigned long after = 0; after < total; after += after < 64 ? 1 : step) {
    f->src.mode = READ_FAIL, f->src.fail_after = after;
    EXPECT(APRT_STATUS_SOURCE,
           aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, ms, &m));
  }
  f->src.mode = READ_FAIL, f->src.fail_after = total;
  EXPECT(OK, aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, ms, &m));
  /* Each call on the streamed model under test, from a prepared frame, fails every read:
   * those that read the blob say so, the others do what they do with a working source. */
  f->model = f->streamed;
  for (size_t i = 0; i < ENTRY_COUNT; i++) {
    const entry *e = &ENTRIES[i];
    f->src.mode = READ_PLAIN;
    prepare(f);
    f->src.mode = READ_FAIL, f->src.fail_after = 0;
    aprt_status got = e->call(f, own(f));
    if (e->reads && has(f, e->needs)) {
      status_is(got, APRT_STATUS_SOURCE, e->name, __LINE__);
    } else if (got != APRT_STATUS_SOURCE) {
      status_is(got, want_valid(f, e), e->name, __LINE__);
    }
  }
  f->src.mode = READ_PLAIN;
  free(scratch), free(mem);
}

/* A callback that claims success with half the bytes: refused at init as a damaged blob;
 * after init, no call may return OK with a non-finite output (the blob is no longer what
 * was validated, so any status is fair). */
static void short_reads(fixture *f) {
  void *mem = block(aprt_model_size(), aprt_model_align());
  unsigned char *scratch = must(calloc(f->scratch_len, 1));
  size_t needed;
  aprt_model *m;
  aprt_source s = {read_at, &f->src, f->src.len};
  f->src.mode = READ_SHORT;
  refused_in(aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, aprt_model_size(),
                                    &m),
             100, 199, "a stream of short reads", __LINE__);
  f->src.mode = READ_PLAIN;
  f->model = f->streamed;
  prepare(f);
  f->src.mode = READ_SHORT;
  for (size_t i = 0; i < ENTRY_COUNT; i++) {
    finite_if_ok(ENTRIES[i].call(f, own(f)), NULL, 0, ENTRIES[i].name, __LINE__);
  }
  f->src.mode = READ_PLAIN;
  free(scratch), free(mem);
}

/* A callback that calls back: into the model it reads for (BUSY), into another model and a
 * new stream (fine); the outer call is not disturbed. Also from inside an init. */
static void reentrant_reads(fixture *f) {
  source nested = f->src;
  nested.mode = READ_PLAIN;
  nested.self = nested.other = NULL, nested.nested = NULL;
  /* The inner pose goes to a frame of its own: the outer call holds its frame. */
  void *inner_mem = block(aprt_frame_size(), aprt_frame_align());
  aprt_frame *inner;
  EXPECT(OK, aprt_frame_init(inner_mem, aprt_frame_size(), &inner));
  f->model = f->streamed;
  prepare(f);
  f->src.mode = READ_REENTER;
  f->src.self = f->streamed, f->src.other = f->resident, f->src.nested = &nested;
  f->src.frame = inner, f->src.angles = f->angles, f->src.pose_len = f->pose_len;
  f->src.inner_info = f->src.inner_pose = f->src.inner_other = f->src.inner_open = OK;
  EXPECT(OK, e_set_pose(f, own(f)));
  EXPECT(APRT_STATUS_BUSY, f->src.inner_info);
  EXPECT(APRT_STATUS_BUSY, f->src.inner_pose);
  EXPECT(OK, f->src.inner_other);
  EXPECT(OK, f->src.inner_open);
  /* The outer pose is the one that holds. */
  EXPECT(OK, e_light_sh(f, own(f)));
  EXPECT(OK, e_shade(f, own(f)));
  /* From inside an init: the model does not exist yet. */
  void *mem = block(aprt_model_size(), aprt_model_align());
  unsigned char *scratch = must(calloc(f->scratch_len, 1));
  size_t needed;
  aprt_model *m;
  aprt_source s = {read_at, &f->src, f->src.len};
  f->src.self = NULL, f->src.inner_open = APRT_STATUS_UNKNOWN;
  EXPECT(OK, aprt_model_stream_init(&s, scratch, f->scratch_len, &needed, mem, aprt_model_size(),
                                    &m));
  EXPECT(OK, f->src.inner_open);
  f->src.mode = READ_PLAIN, f->src.self = f->src.other = NULL, f->src.nested = NULL;
  free(scratch), free(mem), free(inner_mem);
}

/* ---- Driver ------------------------------------------------------------------------------------ */

static void check_kind(fixture *f, const char *kind, const aprt_model *model) {
  snprintf(subject, sizeof subject, "%s (%s)", f->path, kind);
  f->model = model;
  whole_frame(f);
  wrong_handles(f);
  lengths_of_pose_and_lighting(f);
  lengths_of_ranges(f);
  lengths_of_lights(f);
  lengths_of_light_maps(f);
  lengths_of_the_rig(f);
  lengths_of_the_proxies(f);
  values_of_the_frame(f);
  values_of_lights(f);
  rotations(f);
  values_of_the_share(f);
}

static void check_model(const char *path) {
  fixture f;
  fixture_init(&f, path);
  snprintf(subject, sizeof subject, "%s", path);
  aprt_status s = fixture_open(&f);
  EXPECT(OK, s);
  if (s == OK) {
    check_kind(&f, "resident", f.resident);
    check_kind(&f, "streamed", f.streamed);
    snprintf(subject, sizeof subject, "%s (streamed)", path);
    lengths_of_the_stream(&f);
    failing_reads(&f);
    short_reads(&f);
    reentrant_reads(&f);
    snprintf(subject, sizeof subject, "%s", path);
    lengths_of_storage(&f);
    lengths_of_blobs_and_names(&f);
  }
  fixture_free(&f);
}

/* A hostile blob: refused as a blob, or a whole frame with finite outputs or statuses. */
static void check_hostile_blob(const char *path) {
  fixture f;
  fixture_init(&f, path);
  snprintf(subject, sizeof subject, "%s (hostile blob)", path);
  aprt_status s = fixture_open(&f);
  if (s != OK) {
    refused_in(s, 100, 199, "a hostile blob", __LINE__);
    printf("hostile blob %s: refused (%d)\n", path, (int)s);
  } else {
    const aprt_model *kinds[] = {f.resident, f.streamed};
    int overflowed = 0;
    for (int k = 0; k < 2; k++) {
      f.model = kinds[k];
      fill_inputs(&f);
      for (size_t i = 0; i < ENTRY_COUNT; i++) {
        aprt_status got = ENTRIES[i].call(&f, own(&f));
        overflowed += got == APRT_STATUS_OVERFLOW;
        finite_if_ok(got, NULL, 0, ENTRIES[i].name, __LINE__);
      }
    }
    printf("hostile blob %s: accepted, %d calls overflowed\n", path, overflowed);
  }
  fixture_free(&f);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: hostile MODEL.aprt... [--accepting-or-refusing MODEL.aprt...]\n");
    return 2;
  }
  snprintf(subject, sizeof subject, "no model");
  status_messages();
  projections();
  int hostile = 0;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--accepting-or-refusing") == 0) {
      hostile = 1;
      continue;
    }
    if (hostile) {
      check_hostile_blob(argv[i]);
    } else {
      check_model(argv[i]);
    }
  }
  printf("hostile: %lu checks, %lu failed\n", checks, failures);
  return failures ? 1 : 0;
}
