// aprt.hpp refuses arrays that are not a whole number of items: a rotation is 9 floats, a
// vector or position 3, and a partial one throws APRT_STATUS_WRONG_LENGTH instead of being
// dropped by an integer division (154 floats were taken as 17 bones).
//
//   wrapper MODEL.aprt (a bone-frame model with an irradiance rig)
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <vector>

#include "aprt.hpp"

static int failures = 0;

// `call` must throw aprt::Error with `want`.
static void throws(const char *what, aprt_status want, const std::function<void()> &call) {
  try {
    call();
    std::fprintf(stderr, "wrapper: %s: no exception\n", what);
    failures++;
  } catch (const aprt::Error &e) {
    if (e.status() != want) {
      std::fprintf(stderr, "wrapper: %s: %s, want status %d\n", what, e.what(), int(want));
      failures++;
    }
  }
}

int main(int argc, char **argv) {
  if (argc != 2) return 2;
  std::ifstream file(argv[1], std::ios::binary);
  std::vector<std::uint8_t> blob((std::istreambuf_iterator<char>(file)), {});
  for (int streamed = 0; streamed < 2; streamed++) {
    aprt::Model model = streamed ? aprt::Model::streamed(blob) : aprt::Model(blob);
    const aprt_model_info &info = model.info();
    if (info.frame != APRT_FRAME_BONES || !info.has_rig) return 2;
    const std::size_t n = info.vertices, nb = info.bones;
    const std::vector<float> turn = {0.8f, -0.6f, 0.0f, 0.6f, 0.8f, 0.0f, 0.0f, 0.0f, 1.0f};
    std::vector<float> bones;
    for (std::size_t b = 0; b < nb; b++) bones.insert(bones.end(), turn.begin(), turn.end());
    std::vector<float> angles(info.pose_len, 0.1f), sky(info.coeffs, 0.5f);
    std::vector<float> positions(3 * n, 0.25f), rgb(3 * n, 0.0f);
    std::vector<float> vectors(3 * std::size_t(info.rig_vectors) * info.coeffs, 0.25f);
    std::vector<aprt_light> lights(1, aprt_light{APRT_LIGHT_POINT, {1.0f, 1.0f, 1.0f}, {}, 0.0f,
                                                 {1.0f, 1.0f, 1.0f}});
    const std::vector<float> weights(1, 1.0f);
    aprt::Frame frame;
    frame.set_pose(model, angles);
    frame.light_sh(model, sky, bones);
    frame.shade(model);

    // One float short of whole rotations, and one over.
    std::vector<float> short_bones(bones.begin(), bones.end() - 1), long_bones = bones;
    long_bones.push_back(0.0f);
    for (const auto *b : {&short_bones, &long_bones}) {
      throws("light_sh", APRT_STATUS_WRONG_LENGTH, [&] { frame.light_sh(model, sky, *b); });
      throws("shade_lights", APRT_STATUS_WRONG_LENGTH,
             [&] { frame.shade_lights(model, *b, lights, weights, positions, rgb); });
      throws("light_rig", APRT_STATUS_WRONG_LENGTH, [&] { frame.light_rig(model, vectors, *b); });
    }
    // Partial triples.
    std::vector<float> short_vectors(vectors.begin(), vectors.end() - 1);
    throws("light_rig vectors", APRT_STATUS_WRONG_LENGTH,
           [&] { frame.light_rig(model, short_vectors, bones); });
    std::vector<float> short_positions(positions.begin(), positions.end() - 1);
    std::vector<float> short_rgb(rgb.begin(), rgb.end() - 1);
    throws("shade_lights rgb", APRT_STATUS_WRONG_LENGTH, [&] {
      frame.shade_lights(model, bones, lights, weights, short_positions, short_rgb);
    });
    frame.light_rig(model, vectors, bones);
    aprt_placement place = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0, 0, 0}};
    throws("shade_rig", APRT_STATUS_WRONG_LENGTH,
           [&] { frame.shade_rig(model, place, short_positions); });
    // A new pose without light_sh: the wrapper's shade throws rather than serve the last.
    frame.set_pose(model, angles);
    throws("shade after a new pose", APRT_STATUS_WEIGHTS_NOT_SET, [&] { frame.shade(model); });
    // Whole arrays still work.
    frame.light_sh(model, sky, bones);
    frame.shade_lights(model, bones, lights, weights, positions, rgb);
  }
  // A streamed model opened at once with the scratch it needs.
  aprt::Model first = aprt::Model::streamed(blob);
  aprt::Model again = aprt::Model::streamed(blob, first.info().scratch_bytes);
  if (again.info().scratch_bytes != first.info().scratch_bytes) failures++;
  std::printf("wrapper: %d failed\n", failures);
  return failures ? 1 : 0;
}
