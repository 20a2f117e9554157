// The frame of shade.c through the RAII wrapper aprt.hpp: the same inputs, the same lines
// of hex float bits, so a test can compare C, C++ and Rust to the last bit.
//
//   c++ -std=c++17 -ffp-contract=off -I capi/include capi/examples/shade.cpp
//       target/release/libaprt_capi.a -lpthread -ldl -lm -o shade_cpp   (one line)
//   ./shade_cpp fixtures/golden/v1-bones.aprt
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "aprt.hpp"

namespace {

const float ANGLES[8] = {0.1f, -0.2f, 0.3f, 0.05f, -0.15f, 0.25f, 0.0f, 0.4f};
const float POSITIONS[8][3] = {
    {0.0f, 0.0f, 0.0f},  {0.5f, 0.1f, 0.2f},  {-0.3f, 0.4f, 0.1f}, {0.2f, -0.5f, 0.6f},
    {0.1f, 0.3f, -0.4f}, {-0.6f, 0.2f, 0.3f}, {0.4f, 0.4f, 0.4f},  {0.0f, -0.2f, 0.8f},
};
const float SKY_DIR[3] = {0.5f, -0.8f, 0.9f};
const float TURN[9] = {0.8f, -0.6f, 0.0f, 0.6f, 0.8f, 0.0f, 0.0f, 0.0f, 1.0f};
const float IDENTITY[9] = {1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f};
const float SHIFT[3] = {0.05f, -0.1f, 0.2f};
const float NORMALS[8][3] = {
    {0.0f, 0.0f, 1.0f},  {0.6f, 0.0f, 0.8f},  {0.0f, 0.6f, 0.8f}, {-0.6f, 0.0f, 0.8f},
    {0.0f, -0.6f, 0.8f}, {0.0f, 0.0f, -1.0f}, {0.8f, 0.0f, 0.6f}, {0.0f, 0.0f, 0.0f},
};
const std::vector<aprt_light> LIGHTS = {
    {APRT_LIGHT_SPHERE, {0.5f, 1.0f, 2.0f}, {0.0f, 0.0f, 0.0f}, 0.3f, {2.0f, 1.5f, 1.0f}},
    {APRT_LIGHT_POINT, {-1.0f, 0.5f, 1.0f}, {0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 1.0f, 1.0f}},
    {APRT_LIGHT_DIRECTIONAL, {0.0f, 0.0f, 0.0f}, {0.3f, -0.2f, 0.9f}, 0.0f, {0.5f, 0.6f, 0.7f}},
};
const std::vector<float> WEIGHTS = {1.0f, 0.5f, 1.0f};
const aprt_placement PLACE = {{{0.8f, 0.0f, -0.6f}, {0.0f, 1.0f, 0.0f}, {0.6f, 0.0f, 0.8f}},
                              {0.1f, 0.0f, -0.2f}};

void print(const char *name, const float *v, std::size_t n) {
  std::printf("%s %zu", name, n);
  for (std::size_t i = 0; i < n; i++) {
    std::uint32_t bits;
    std::memcpy(&bits, &v[i], sizeof bits);
    std::printf(" %08" PRIx32, bits);
  }
  std::printf("\n");
}
void print(const char *name, const std::vector<float> &v) { print(name, v.data(), v.size()); }

std::vector<std::uint8_t> read_file(const char *path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(std::string("cannot open ") + path);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void run(const char *path) {
  const std::vector<std::uint8_t> blob = read_file(path);
  const aprt::Model model(blob);
  const aprt_model_info &info = model.info();
  std::printf("model order %u coeffs %u vertices %u pose_len %u bones %u rig %u atlas %d"
              " proxies %d\n",
              info.order, info.coeffs, info.vertices, info.pose_len, info.bones,
              info.rig_vectors, int(info.has_atlas), int(info.has_proxies));
  const std::size_t n = info.vertices, n2 = info.coeffs, k = info.rig_vectors;

  std::vector<float> angles(info.pose_len), bones(9 * std::size_t(info.bones));
  for (std::size_t i = 0; i < angles.size(); i++) angles[i] = ANGLES[i % 8];
  for (std::size_t b = 0; b < info.bones; b++) std::memcpy(&bones[9 * b], b % 2 ? TURN : IDENTITY, 36);
  std::vector<float> sky(36);
  aprt::check(aprt_project_directional(info.order, SKY_DIR, 3.0f, sky.data(), sky.size()), "sky");
  sky.resize(n2);

  aprt::Frame frame;
  frame.set_pose(model, angles);
  frame.light_sh(model, sky, bones);
  const std::vector<float> shading = frame.shade(model);
  print("shade", shading);
  const std::vector<float> transfer = frame.transfer(model);
  print("transfer", transfer);

  std::vector<float> positions(3 * n), rgb(3 * n, 0.0f);
  for (std::size_t j = 0; j < n; j++) std::memcpy(&positions[3 * j], POSITIONS[j % 8], 12);
  frame.shade_lights(model, bones, LIGHTS, WEIGHTS, positions, rgb);
  print("lights", rgb);

  // The occluder proxies, posed by each bone's rotation with SHIFT as its translation.
  std::vector<float> skinning(12 * std::size_t(info.bones)), normals(3 * n);
  for (std::size_t b = 0; b < info.bones; b++)
    for (std::size_t r = 0; r < 3; r++) {
      std::memcpy(&skinning[12 * b + 4 * r], &bones[9 * b + 3 * r], 12);
      skinning[12 * b + 4 * r + 3] = SHIFT[r];
    }
  for (std::size_t j = 0; j < n; j++) std::memcpy(&normals[3 * j], NORMALS[j % 8], 12);
  if (info.has_proxies) {
    aprt::ProxyFrame proxies;
    proxies.pose(model, skinning);
    std::vector<float> occluded = shading;
    proxies.occlude(model, sky, positions, normals, occluded);
    print("occluded", occluded);
    occluded = transfer;
    proxies.occlude_transfer(model, bones, positions, normals, occluded);
    print("occluded_transfer", occluded);
  }

  std::vector<float> vectors(3 * k * n2);
  if (info.has_rig) {
    float share;
    aprt::check(aprt_rig_share(model.get(), &LIGHTS[0], &PLACE, 1.0f, 0.25f, &share), "share");
    print("share", &share, 1);
    aprt::check(aprt_rig_vectors(model.get(), &PLACE, LIGHTS.data(), LIGHTS.size(), nullptr, 0,
                                 vectors.data(), k * n2),
                "rig vectors");
    print("vectors", vectors);
    frame.light_rig(model, vectors, bones);
    print("rig", frame.shade_rig(model, PLACE, positions));
  }

  std::vector<float> env(3 * n2);
  for (std::size_t c = 0; c < n2; c++) env[3 * c] = env[3 * c + 1] = env[3 * c + 2] = sky[c];
  aprt::check(aprt_lightmap_compose(info.order, transfer.data(), transfer.size(), env.data(), n2,
                                    rgb.data(), n),
              "compose");
  print("lightmap", rgb);
  aprt::check(aprt_lightmap_compose_lights(info.order, transfer.data(), transfer.size(),
                                           positions.data(), LIGHTS.data(), LIGHTS.size(),
                                           env.data(), n2, rgb.data(), n),
              "compose lights");
  print("lightmap_lights", rgb);
  if (info.has_rig) {
    aprt::check(aprt_lightmap_compose_rig(model.get(), transfer.data(), transfer.size(),
                                          vectors.data(), k * n2, &PLACE, positions.data(),
                                          rgb.data(), n),
                "compose rig");
    print("lightmap_rig", rgb);
  }

  const aprt::Model streamed = aprt::Model::streamed(blob);
  aprt::Frame again;
  again.set_pose(streamed, angles);
  again.light_sh(streamed, sky, bones);
  std::vector<float> streamed_shading = again.shade(streamed);
  print("streamed", streamed_shading);
  if (info.has_proxies) {
    aprt::ProxyFrame proxies;
    proxies.pose(streamed, skinning);
    proxies.occlude(streamed, sky, positions, normals, streamed_shading);
    print("streamed_occluded", streamed_shading);
    std::vector<float> streamed_transfer = again.transfer(streamed);
    proxies.occlude_transfer(streamed, bones, positions, normals, streamed_transfer);
    print("streamed_occluded_transfer", streamed_transfer);
  }
}

}  // namespace

int main(int argc, char **argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: shade_cpp MODEL.aprt\n");
    return 2;
  }
  try {
    run(argv[1]);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "shade_cpp: %s\n", e.what());
    return 1;
  }
  return 0;
}
