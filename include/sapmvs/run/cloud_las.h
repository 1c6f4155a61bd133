#pragma once
// A dense cloud (ply_io.h) as LAS (las_io.h): colour in the point records,
// and what LAS has no field for (score, views, normal) as Extra Bytes, so that
// cloud.las carries everything cloud.ply does.

#include <filesystem>
#include <vector>

#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"

namespace sapmvs {

// Extra Bytes field names. The normal's are PDAL's dimension names (what
// PDAL's own LAS writer and laspy scripts use), so that PDAL reads them back
// as a normal rather than three unknown attributes.
constexpr const char* kLasScoreField = "score";  // float32, mean NCC, -1..1
constexpr const char* kLasViewsField = "views";  // uint16, images matched in
constexpr const char* kLasNormalFields[3] = {"NormalX", "NormalY", "NormalZ"};  // float32

// Position, colour (ColorTo16) and class 1 (unclassified) per point.
std::vector<PointRecord> ToLasRecords(const PointCloud& cloud);

// The Extra Bytes fields of the cloud's known attributes (has_scores,
// has_views, has_normals), in the order score, views, NormalX/Y/Z.
std::vector<LasExtraField> ToLasExtras(const PointCloud& cloud);

// WriteLas of the two above; throws what WriteLas throws (a view count over
// 65535 among them).
void WriteCloudLas(const std::filesystem::path& path, const PointCloud& cloud,
                   const LasWriteOptions& options);

}  // namespace sapmvs
