#include "sapmvs/run/cloud_las.h"

namespace sapmvs {

std::vector<PointRecord> ToLasRecords(const PointCloud& cloud) {
  std::vector<PointRecord> out(cloud.points.size());
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const CloudPoint& p = cloud.points[i];
    PointRecord& r = out[i];
    r.x = p.position.x();
    r.y = p.position.y();
    r.z = p.position.z();
    r.r = ColorTo16(p.color[0]);
    r.g = ColorTo16(p.color[1]);
    r.b = ColorTo16(p.color[2]);
    r.classification = 1;  // unclassified
  }
  return out;
}

std::vector<LasExtraField> ToLasExtras(const PointCloud& cloud) {
  const size_t n = cloud.points.size();
  std::vector<LasExtraField> fields;
  auto add = [&](const char* name, const char* description, LasExtraType type, auto value) {
    LasExtraField f{name, description, type, {}};
    f.values.reserve(n);
    for (const CloudPoint& p : cloud.points) f.values.push_back(value(p));
    fields.push_back(std::move(f));
  };
  if (cloud.has_scores) {
    add(kLasScoreField, "photo-consistency (mean NCC)", LasExtraType::kFloat32,
        [](const CloudPoint& p) { return double{p.score}; });
  }
  if (cloud.has_views) {
    add(kLasViewsField, "images the point was matched in", LasExtraType::kUint16,
        [](const CloudPoint& p) { return double(p.num_views); });
  }
  if (cloud.has_normals) {
    const char* descriptions[3] = {"unit surface normal, X", "unit surface normal, Y",
                                   "unit surface normal, Z"};
    for (int a = 0; a < 3; ++a) {
      add(kLasNormalFields[a], descriptions[a], LasExtraType::kFloat32,
          [a](const CloudPoint& p) { return double{p.normal[a]}; });
    }
  }
  return fields;
}

void WriteCloudLas(const std::filesystem::path& path, const PointCloud& cloud,
                   const LasWriteOptions& options) {
  WriteLas(path, ToLasRecords(cloud), options, ToLasExtras(cloud));
}

}  // namespace sapmvs
