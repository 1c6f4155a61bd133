#pragma once
// A per-point attribute of a LAS file stored as Extra Bytes (LasExtraField),
// apart from the reader and writer (las_io.h) so that the Extra Bytes
// encoding (host/io/las_extra_bytes.h) can take it without them.
#include <cstdint>
#include <string>
#include <vector>

namespace sapmvs {

// The value types of LAS Extra Bytes (the `data_type` of an Extra Bytes
// descriptor, LAS 1.4 R15 table "Values for data_type"; the deprecated
// array types 11-30 are not written).
enum class LasExtraType : uint8_t {
  kUint8 = 1,
  kInt8 = 2,
  kUint16 = 3,
  kInt16 = 4,
  kUint32 = 5,
  kInt32 = 6,
  kUint64 = 7,
  kInt64 = 8,
  kFloat32 = 9,
  kFloat64 = 10,
};

// One per-point attribute stored as LAS Extra Bytes: the bytes after the
// point format's own, described by one 192-byte descriptor in the Extra Bytes
// VLR (LASF_Spec/4). LAS 1.4 formalised that VLR for a practice older
// versions already allowed (records longer than their format), so 1.2 files
// carry it too; readers that do not know it skip the bytes by the record
// length.
struct LasExtraField {
  std::string name;         // 1-32 characters, unique within a file
  std::string description;  // at most 32 characters
  LasExtraType type = LasExtraType::kFloat32;
  // One value per point, as the caller means it (no scale or offset). The
  // writer refuses values the type cannot hold exactly (a fraction or an
  // out-of-range count in an integer type, a non-finite value).
  std::vector<double> values;
};

}  // namespace sapmvs
