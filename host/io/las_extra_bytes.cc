#include "io/las_extra_bytes.h"
#include "sapmvs/util/number_text.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>

namespace sapmvs::las {
namespace {

// Offsets within a descriptor (LAS 1.4 R15, struct EXTRA_BYTES).
constexpr size_t kTypeAt = 2, kOptionsAt = 3, kNameAt = 4, kMinAt = 64, kMaxAt = 88, kScaleAt = 112,
                 kOffsetAt = 136, kDescriptionAt = 160;
constexpr size_t kNameSize = 32, kDescriptionSize = 32;
constexpr uint8_t kMinBit = 1u << 1, kMaxBit = 1u << 2, kScaleBit = 1u << 3, kOffsetBit = 1u << 4;

template <typename T>
void Put(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}
template <typename T>
T Get(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

bool IsFloat(LasExtraType t) { return t == LasExtraType::kFloat32 || t == LasExtraType::kFloat64; }

// The range of values `type` holds exactly, as doubles.
std::pair<double, double> Range(LasExtraType type) {
  switch (type) {
    case LasExtraType::kUint8:
      return {0, 255};
    case LasExtraType::kInt8:
      return {-128, 127};
    case LasExtraType::kUint16:
      return {0, 65535};
    case LasExtraType::kInt16:
      return {-32768, 32767};
    case LasExtraType::kUint32:
      return {0, 4294967295.0};
    case LasExtraType::kInt32:
      return {-2147483648.0, 2147483647.0};
    case LasExtraType::kUint64:  // whole doubles up to 2^53 stay exact
    case LasExtraType::kInt64:
      return {type == LasExtraType::kUint64 ? 0 : -9007199254740992.0, 9007199254740992.0};
    case LasExtraType::kFloat32:
      return {-std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
    case LasExtraType::kFloat64:
      return {-std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  }
  return {0, 0};
}

}  // namespace

size_t ExtraTypeSize(LasExtraType type) {
  switch (type) {
    case LasExtraType::kUint8:
    case LasExtraType::kInt8:
      return 1;
    case LasExtraType::kUint16:
    case LasExtraType::kInt16:
      return 2;
    case LasExtraType::kUint32:
    case LasExtraType::kInt32:
    case LasExtraType::kFloat32:
      return 4;
    case LasExtraType::kUint64:
    case LasExtraType::kInt64:
    case LasExtraType::kFloat64:
      return 8;
  }
  return 0;
}

std::string ExtraFieldsProblem(const std::vector<LasExtraField>& fields, size_t points) {
  std::set<std::string> names;
  for (const LasExtraField& f : fields) {
    const std::string label = "extra bytes field '" + f.name + "'";
    if (f.name.empty() || f.name.size() > kNameSize) {
      return label + ": expected a name of 1-32 characters";
    }
    if (!names.insert(f.name).second) return label + ": the name is given twice";
    if (f.description.size() > kDescriptionSize) {
      return label + ": expected a description of at most 32 characters";
    }
    if (ExtraTypeSize(f.type) == 0) return label + ": unknown data type";
    if (f.values.size() != points) {
      return label + " has " + std::to_string(f.values.size()) + " values for " +
             std::to_string(points) + " points (expected one per point)";
    }
    const auto [lo, hi] = Range(f.type);
    for (size_t i = 0; i < points; ++i) {
      const double v = f.values[i];
      if (!std::isfinite(v) || v < lo || v > hi || (!IsFloat(f.type) && v != std::floor(v))) {
        return label + ", point " + std::to_string(i) + ": value " + FormatNumber(v, 17) +
               " (expected " + (IsFloat(f.type) ? "a finite number" : "a whole number") + " from " +
               FormatNumber(lo, 17) + " to " + FormatNumber(hi, 17) + ")";
      }
    }
  }
  size_t bytes = 0;
  for (const LasExtraField& f : fields) bytes += ExtraTypeSize(f.type);
  if (fields.size() * kExtraDescriptorSize > std::numeric_limits<uint16_t>::max() ||
      bytes > 65535 - 67) {
    return std::to_string(fields.size()) + " extra bytes fields (" + std::to_string(bytes) +
           " bytes) do not fit a LAS record and its VLR";
  }
  return "";
}

std::vector<uint8_t> EncodeExtraDescriptors(const std::vector<LasExtraField>& fields) {
  std::vector<uint8_t> out(fields.size() * kExtraDescriptorSize, 0);
  for (size_t k = 0; k < fields.size(); ++k) {
    const LasExtraField& f = fields[k];
    uint8_t* d = &out[k * kExtraDescriptorSize];
    d[kTypeAt] = static_cast<uint8_t>(f.type);
    std::memcpy(d + kNameAt, f.name.data(), f.name.size());
    std::memcpy(d + kDescriptionAt, f.description.data(), f.description.size());
    if (IsFloat(f.type) && !f.values.empty()) {
      // What a reader gets back: float fields round to float first.
      auto stored = [&](double v) {
        return f.type == LasExtraType::kFloat32 ? static_cast<double>(static_cast<float>(v)) : v;
      };
      const auto [lo, hi] = std::minmax_element(f.values.begin(), f.values.end());
      d[kOptionsAt] = kMinBit | kMaxBit;
      Put<double>(d + kMinAt, stored(*lo));
      Put<double>(d + kMaxAt, stored(*hi));
    }
  }
  return out;
}

void EncodeExtraValues(const std::vector<LasExtraField>& fields, size_t i, uint8_t* out) {
  for (const LasExtraField& f : fields) {
    const double v = f.values[i];
    switch (f.type) {
      case LasExtraType::kUint8:
        Put<uint8_t>(out, static_cast<uint8_t>(v));
        break;
      case LasExtraType::kInt8:
        Put<int8_t>(out, static_cast<int8_t>(v));
        break;
      case LasExtraType::kUint16:
        Put<uint16_t>(out, static_cast<uint16_t>(v));
        break;
      case LasExtraType::kInt16:
        Put<int16_t>(out, static_cast<int16_t>(v));
        break;
      case LasExtraType::kUint32:
        Put<uint32_t>(out, static_cast<uint32_t>(v));
        break;
      case LasExtraType::kInt32:
        Put<int32_t>(out, static_cast<int32_t>(v));
        break;
      case LasExtraType::kUint64:
        Put<uint64_t>(out, static_cast<uint64_t>(v));
        break;
      case LasExtraType::kInt64:
        Put<int64_t>(out, static_cast<int64_t>(v));
        break;
      case LasExtraType::kFloat32:
        Put<float>(out, static_cast<float>(v));
        break;
      case LasExtraType::kFloat64:
        Put<double>(out, v);
        break;
    }
    out += ExtraTypeSize(f.type);
  }
}

std::vector<ExtraFieldLayout> DecodeExtraDescriptors(const std::vector<uint8_t>& payload,
                                                     size_t available) {
  if (payload.size() % kExtraDescriptorSize != 0) return {};
  std::vector<ExtraFieldLayout> fields;
  size_t offset = 0;
  for (size_t at = 0; at < payload.size(); at += kExtraDescriptorSize) {
    const uint8_t* d = &payload[at];
    const unsigned type = d[kTypeAt];
    const uint8_t options = d[kOptionsAt];
    size_t size = 0;
    if (type == 0) {
      size = options;  // undocumented bytes: their count is in `options`
    } else if (type <= 10) {
      size = ExtraTypeSize(static_cast<LasExtraType>(type));
    } else if (type <= 30) {
      // Deprecated arrays: 11-20 pairs and 21-30 triples of types 1-10.
      const unsigned base = (type - 1) % 10 + 1, count = (type - 1) / 10 + 1;
      size = count * ExtraTypeSize(static_cast<LasExtraType>(base));
    } else {
      break;
    }
    if (offset + size > available) return {};
    if (type >= 1 && type <= 10) {
      ExtraFieldLayout f;
      f.field.name = FixedString(d + kNameAt, kNameSize);
      f.field.description = FixedString(d + kDescriptionAt, kDescriptionSize);
      f.field.type = static_cast<LasExtraType>(type);
      f.offset = offset;
      if (options & kScaleBit) f.scale = Get<double>(d + kScaleAt);
      if (options & kOffsetBit) f.add = Get<double>(d + kOffsetAt);
      fields.push_back(f);
    }
    offset += size;
  }
  return fields;
}

double DecodeExtraValue(const ExtraFieldLayout& layout, const uint8_t* extra) {
  const uint8_t* p = extra + layout.offset;
  double v = 0;
  switch (layout.field.type) {
    case LasExtraType::kUint8:
      v = Get<uint8_t>(p);
      break;
    case LasExtraType::kInt8:
      v = Get<int8_t>(p);
      break;
    case LasExtraType::kUint16:
      v = Get<uint16_t>(p);
      break;
    case LasExtraType::kInt16:
      v = Get<int16_t>(p);
      break;
    case LasExtraType::kUint32:
      v = Get<uint32_t>(p);
      break;
    case LasExtraType::kInt32:
      v = Get<int32_t>(p);
      break;
    case LasExtraType::kUint64:
      v = static_cast<double>(Get<uint64_t>(p));
      break;
    case LasExtraType::kInt64:
      v = static_cast<double>(Get<int64_t>(p));
      break;
    case LasExtraType::kFloat32:
      v = Get<float>(p);
      break;
    case LasExtraType::kFloat64:
      v = Get<double>(p);
      break;
  }
  return v * layout.scale + layout.add;
}

std::string FixedString(const uint8_t* p, size_t n) {
  if (n == 0) return {};  // an empty record's data() may be null
  return std::string(reinterpret_cast<const char*>(p),
                     strnlen(reinterpret_cast<const char*>(p), n));
}

}  // namespace sapmvs::las
