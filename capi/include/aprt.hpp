// aprt.hpp: a small RAII wrapper over the C ABI (aprt.h), C++17.
//
// aprt::Model owns its blob (moved in, so it outlives the model that reads it in place) and
// the aligned storage of its handle; aprt::Frame and aprt::ProxyFrame own their storage.
// Array lengths are checked against each other before the call (a float array that is not a
// whole number of rotations, vectors or triples throws APRT_STATUS_WRONG_LENGTH rather than
// being cut short). A failing call throws aprt::Error, which carries the status and its
// message. Nothing else is hidden: every
// method is one C call, so the output is the C path's, bit for bit.
#ifndef APRT_HPP
#define APRT_HPP

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "aprt.h"

namespace aprt {

// A status other than APRT_STATUS_OK, as an exception.
class Error : public std::runtime_error {
 public:
  Error(aprt_status status, const char *what)
      : std::runtime_error(std::string(what) + ": " + aprt_status_message(status)),
        status_(status) {}
  aprt_status status() const noexcept { return status_; }

 private:
  aprt_status status_;
};

inline void check(aprt_status status, const char *what) {
  if (status != APRT_STATUS_OK) throw Error(status, what);
}

namespace detail {
// Storage of `size` bytes aligned to `align`, freed by the matching aligned delete.
struct AlignedDelete {
  std::size_t align;
  void operator()(void *p) const noexcept { ::operator delete(p, std::align_val_t(align)); }
};
using Storage = std::unique_ptr<void, AlignedDelete>;
inline Storage allocate(std::size_t size, std::size_t align) {
  return Storage(::operator new(size, std::align_val_t(align)), AlignedDelete{align});
}
// The count of `per`-float items in `floats` floats (9 a rotation, 3 a vector); throws
// APRT_STATUS_WRONG_LENGTH for a partial item, which the C call could not see.
inline std::size_t items(std::size_t floats, std::size_t per, const char *what) {
  if (floats % per) throw Error(APRT_STATUS_WRONG_LENGTH, what);
  return floats / per;
}
}  // namespace detail

// A model: resident (the blob read in place) or streamed through a read callback and a
// scratch buffer the model owns. Either way it validates the blob once.
class Model {
 public:
  explicit Model(std::vector<std::uint8_t> blob) : Model(std::move(blob), false, 0) {}

  // A model streamed from `blob` through the read callback, copying as a read from flash
  // would; a real source reads a file or flash. The scratch starts at `scratch_bytes` and
  // grows to what the model asks for (an ask reads only the blob's header): pass
  // info().scratch_bytes of an earlier run to skip the ask.
  static Model streamed(std::vector<std::uint8_t> blob, std::size_t scratch_bytes = 0) {
    return Model(std::move(blob), true, scratch_bytes);
  }

  // The handle points into storage_ and reads *blob_ and scratch_: moving keeps all three
  // where they are.
  Model(Model &&) = default;
  Model &operator=(Model &&) = default;
  Model(const Model &) = delete;
  Model &operator=(const Model &) = delete;

  const aprt_model_info &info() const noexcept { return info_; }
  const aprt_model *get() const noexcept { return handle_; }

 private:
  Model(std::vector<std::uint8_t> blob, bool stream, std::size_t scratch_bytes)
      : blob_(std::make_unique<std::vector<std::uint8_t>>(std::move(blob))),
        storage_(detail::allocate(aprt_model_size(), aprt_model_align())),
        scratch_(stream ? scratch_bytes : 0) {
    if (aprt_abi_version() != APRT_ABI_VERSION) throw Error(APRT_STATUS_UNKNOWN, "ABI version");
    if (stream) {
      aprt_source source{&Model::read_at, blob_.get(), blob_->size()};
      std::size_t needed = 0;
      aprt_status s;
      while ((s = aprt_model_stream_init(&source, scratch_.data(), scratch_.size(), &needed,
                                         storage_.get(), aprt_model_size(), &handle_)) ==
             APRT_STATUS_BUFFER_TOO_SMALL)
        scratch_.assign(needed, 0);
      check(s, "aprt_model_stream_init");
    } else {
      check(aprt_model_init(blob_->data(), blob_->size(), storage_.get(), aprt_model_size(),
                            &handle_),
            "aprt_model_init");
    }
    check(aprt_model_get_info(handle_, &info_), "aprt_model_get_info");
  }

  static std::int32_t read_at(void *user, std::uint64_t offset, std::uint8_t *buf,
                              std::size_t len) noexcept {
    const auto &bytes = *static_cast<const std::vector<std::uint8_t> *>(user);
    if (offset > bytes.size() || len > bytes.size() - offset) return 1;
    std::memcpy(buf, bytes.data() + offset, len);
    return 0;
  }

  std::unique_ptr<std::vector<std::uint8_t>> blob_;
  detail::Storage storage_;
  std::vector<std::uint8_t> scratch_;
  aprt_model *handle_ = nullptr;
  aprt_model_info info_{};
};

// One character's per-frame state, and the steps of a frame.
class Frame {
 public:
  Frame() : storage_(detail::allocate(aprt_frame_size(), aprt_frame_align())) {
    check(aprt_frame_init(storage_.get(), aprt_frame_size(), &handle_), "aprt_frame_init");
  }

  void set_pose(const Model &m, const std::vector<float> &angles) {
    check(aprt_set_pose(m.get(), handle_, angles.data(), angles.size()), "aprt_set_pose");
  }
  // `bones`: 9 floats (a row-major rotation) per bone of a bone-frame model.
  void light_sh(const Model &m, const std::vector<float> &lighting,
                const std::vector<float> &bones) {
    check(aprt_light_sh(m.get(), handle_, lighting.data(), lighting.size(), bones.data(),
                        detail::items(bones.size(), 9, "aprt_light_sh")),
          "aprt_light_sh");
  }
  std::vector<float> shade(const Model &m) const {
    std::vector<float> out(m.info().vertices);
    check(aprt_shade(m.get(), handle_, 0, out.data(), out.size()), "aprt_shade");
    return out;
  }
  std::vector<float> transfer(const Model &m) const {
    std::vector<float> out(std::size_t(m.info().vertices) * m.info().coeffs);
    check(aprt_transfer(m.get(), handle_, 0, out.data(), out.size()), "aprt_transfer");
    return out;
  }
  // Adds the lights' shading at `positions` (3 floats per vertex) to `rgb`.
  void shade_lights(const Model &m, const std::vector<float> &bones,
                    const std::vector<aprt_light> &lights, const std::vector<float> &weights,
                    const std::vector<float> &positions, std::vector<float> &rgb) const {
    const char *what = "aprt_shade_lights";
    if (weights.size() != lights.size() || rgb.size() != positions.size())
      throw Error(APRT_STATUS_WRONG_LENGTH, what);
    check(aprt_shade_lights(m.get(), handle_, bones.data(), detail::items(bones.size(), 9, what),
                            lights.data(), weights.data(), lights.size(), positions.data(), 0,
                            rgb.data(), detail::items(rgb.size(), 3, what)),
          what);
  }
  // The rig's lighting weights live in rig_lit_, which the frame keeps for shade_rig.
  void light_rig(const Model &m, const std::vector<float> &vectors,
                 const std::vector<float> &bones) {
    const char *what = "aprt_light_rig";
    std::size_t count = detail::items(vectors.size(), 3, what);
    std::size_t bone_count = detail::items(bones.size(), 9, what);
    rig_lit_.assign(m.info().rig_lit_len, 0.0f);
    check(aprt_light_rig(m.get(), handle_, vectors.data(), count, bones.data(), bone_count,
                         rig_lit_.data(), rig_lit_.size()),
          what);
  }
  std::vector<float> shade_rig(const Model &m, const aprt_placement &place,
                               const std::vector<float> &positions) const {
    std::size_t count = detail::items(positions.size(), 3, "aprt_shade_rig");
    std::vector<float> out(positions.size());
    check(aprt_shade_rig(m.get(), handle_, &place, positions.data(), 0, out.data(), count),
          "aprt_shade_rig");
    return out;
  }

 private:
  detail::Storage storage_;
  aprt_frame *handle_ = nullptr;
  std::vector<float> rig_lit_;
};

// One frame's posed occluder proxies, for a model with info().has_proxies: pose them every
// frame, then subtract their occlusion from Frame::shade or Frame::transfer output. Positions
// and normals are the skinned mesh's, 3 floats per vertex.
class ProxyFrame {
 public:
  ProxyFrame() : storage_(detail::allocate(aprt_proxy_frame_size(), aprt_proxy_frame_align())) {
    check(aprt_proxy_frame_init(storage_.get(), aprt_proxy_frame_size(), &handle_),
          "aprt_proxy_frame_init");
  }

  // `skinning`: 12 floats per bone, its bind-to-posed matrix (3 x 4, row-major).
  void pose(const Model &m, const std::vector<float> &skinning) {
    check(aprt_pose_proxies(m.get(), skinning.data(), skinning.size(), handle_),
          "aprt_pose_proxies");
  }
  // Subtracts from `shading` (vertices first .. first + shading.size()) what the proxies
  // block under the SH `lighting` given to Frame::light_sh.
  void occlude(const Model &m, const std::vector<float> &lighting,
               const std::vector<float> &positions, const std::vector<float> &normals,
               std::vector<float> &shading, std::size_t first = 0) const {
    if (positions.size() != 3 * shading.size() || normals.size() != positions.size())
      throw Error(APRT_STATUS_WRONG_LENGTH, "aprt_occlude");
    check(aprt_occlude(m.get(), handle_, lighting.data(), lighting.size(), positions.data(),
                       normals.data(), first, shading.data(), shading.size()),
          "aprt_occlude");
  }
  // Subtracts the proxies' occlusion from `transfer` (info().coeffs floats per vertex from
  // `first`, one vertex per position), in the bone frames of `bones` (9 floats per bone).
  void occlude_transfer(const Model &m, const std::vector<float> &bones,
                        const std::vector<float> &positions, const std::vector<float> &normals,
                        std::vector<float> &transfer, std::size_t first = 0) const {
    const char *what = "aprt_occlude_transfer";
    if (normals.size() != positions.size()) throw Error(APRT_STATUS_WRONG_LENGTH, what);
    std::size_t bone_count = detail::items(bones.size(), 9, what);
    std::size_t count = detail::items(positions.size(), 3, what);
    check(aprt_occlude_transfer(m.get(), handle_, bones.data(), bone_count, positions.data(),
                                normals.data(), first, count, transfer.data(), transfer.size()),
          what);
  }
  const aprt_proxy_frame *get() const noexcept { return handle_; }

 private:
  detail::Storage storage_;
  aprt_proxy_frame *handle_ = nullptr;
};

}  // namespace aprt

#endif  // APRT_HPP
