#include "run/point_spill.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <memory>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Position, normal, colour, score, views: CloudPoint without its padding.
constexpr size_t kSpillRecord = 24 + 12 + 3 + 4 + 4;

void Encode(const CloudPoint& p, uint8_t* b) {
  std::memcpy(b, p.position.data(), 24);
  std::memcpy(b + 24, p.normal.data(), 12);
  std::memcpy(b + 36, p.color.data(), 3);
  std::memcpy(b + 39, &p.score, 4);
  const int32_t views = p.num_views;
  std::memcpy(b + 43, &views, 4);
}

void Decode(const uint8_t* b, CloudPoint* p) {
  std::memcpy(p->position.data(), b, 24);
  std::memcpy(p->normal.data(), b + 24, 12);
  std::memcpy(p->color.data(), b + 36, 3);
  std::memcpy(&p->score, b + 39, 4);
  int32_t views = 0;
  std::memcpy(&views, b + 43, 4);
  p->num_views = views;
}

}  // namespace

PointSpill::PointSpill(const std::filesystem::path& dir) : file_(dir / "merged_points") {
  out_.open(file_.temp_path(), std::ios::binary | std::ios::trunc);
  if (!out_) {
    throw Error(file_.temp_path().string() + ": cannot write (" + std::strerror(errno) + ")");
  }
}

void PointSpill::Append(const std::vector<CloudPoint>& points) {
  std::vector<uint8_t> buffer(points.size() * kSpillRecord);
  for (size_t i = 0; i < points.size(); ++i) Encode(points[i], &buffer[i * kSpillRecord]);
  out_.write(reinterpret_cast<const char*>(buffer.data()),
             static_cast<std::streamsize>(buffer.size()));
  if (!out_) {
    throw Error(file_.temp_path().string() + ": write failed (" + std::strerror(errno) + ")");
  }
  size_ += points.size();
}

NextPoints PointSpill::Read(size_t chunk) {
  out_.flush();
  if (!out_) {
    throw Error(file_.temp_path().string() + ": write failed (" + std::strerror(errno) + ")");
  }
  struct State {
    std::ifstream in;
    std::vector<uint8_t> raw;
    std::vector<CloudPoint> points;
    size_t left = 0;
  };
  auto state = std::make_shared<State>();
  state->in.open(file_.temp_path(), std::ios::binary);
  state->left = size_;
  const std::string name = file_.temp_path().string();
  return [state, chunk, name]() -> PointSpan {
    const size_t n = std::min(chunk, state->left);
    if (n == 0) return {};
    state->raw.resize(n * kSpillRecord);
    state->in.read(reinterpret_cast<char*>(state->raw.data()),
                   static_cast<std::streamsize>(state->raw.size()));
    if (!state->in) throw Error(name + ": read failed (the merged points are truncated)");
    state->points.resize(n);
    for (size_t i = 0; i < n; ++i) Decode(&state->raw[i * kSpillRecord], &state->points[i]);
    state->left -= n;
    return {state->points.data(), n};
  };
}

}  // namespace sapmvs
