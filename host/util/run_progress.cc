#include "util/run_progress.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "sapmvs/util/byte_size.h"

namespace sapmvs {

RunProgress::RunProgress(int groups, long images, bool enabled, std::FILE* out)
    : enabled_(enabled && groups > 0),
      out_(out),
      images_(images),
      start_(std::chrono::steady_clock::now()),
      group_start_(start_),
      last_draw_(start_ - std::chrono::seconds(1)) {}

std::string RunProgress::Clock(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

double RunProgress::Elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double RunProgress::EtaSeconds() const {
  if (images_done_ == 0) return -1;
  const double per_image = matched_seconds_ / images_done_;
  const double in_group =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - group_start_).count();
  // The current group's share already spent counts against what is left.
  return std::max(0.0, per_image * (images_ - images_done_) - in_group);
}

void RunProgress::StartGroup(int index, int group_count, long group_images) {
  index_ = index;
  group_count_ = group_count;
  group_images_ = group_images;
  group_start_ = std::chrono::steady_clock::now();
  last_ = MatchProgressEvent{};  // a new group always shows at once
  Update(MatchProgressEvent{"load", 0, 0, ""});
}

std::string RunProgress::Line() const {
  std::string line = "group " + std::to_string(index_ + 1) + "/" + std::to_string(group_count_) +
                     " (" + std::to_string(group_images_) + " images)  " + last_.stage;
  if (last_.total > 0) {
    line += " " + std::to_string(last_.done) + "/" + std::to_string(last_.total);
  }
  if (!last_.detail.empty()) line += ", " + last_.detail;
  line += "  " + Clock(Elapsed());
  const double eta = EtaSeconds();
  line += eta < 0 ? "  ETA after the first group" : "  ETA " + Clock(eta);
  return line;
}

void RunProgress::Update(const MatchProgressEvent& e) {
  const bool new_stage = e.stage != last_.stage;
  last_ = e;
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  // At most 10 redraws a second, but every change of stage shows.
  if (!new_stage && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const std::string line = Line();
  std::fprintf(out_, "\r%s%*s", line.c_str(),
               static_cast<int>(drawn_ > line.size() ? drawn_ - line.size() : 0), "");
  drawn_ = line.size();
  std::fflush(out_);
}

void RunProgress::EndGroup(long points, double peak_rss_bytes, double estimate_bytes) {
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - group_start_).count();
  matched_seconds_ += seconds;
  images_done_ += group_images_;
  if (!enabled_) return;
  std::string line = "group " + std::to_string(index_ + 1) + "/" + std::to_string(group_count_) +
                     ": " + std::to_string(group_images_) + " images, " + std::to_string(points) +
                     " points, " + Clock(seconds);
  if (peak_rss_bytes > 0 && estimate_bytes > 0) {
    line +=
        ", peak " + FormatBytes(peak_rss_bytes) + " (estimate " + FormatBytes(estimate_bytes) + ")";
  }
  std::fprintf(out_, "\r%s%*s\n", line.c_str(),
               static_cast<int>(drawn_ > line.size() ? drawn_ - line.size() : 0), "");
  drawn_ = 0;
  std::fflush(out_);
}

void RunProgress::Finish() {
  if (!enabled_ || drawn_ == 0) return;
  std::fprintf(out_, "\r%*s\r", static_cast<int>(drawn_), "");
  drawn_ = 0;
  std::fflush(out_);
}

}  // namespace sapmvs
