#include "sapmvs/io/ply_io.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/memory_use.h"
#include "util/input_file.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace {

// Binary values are copied as-is for little-endian files and reversed for
// big-endian ones.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "PLY I/O assumes a little-endian host");

// A header line longer than this, or a header with more lines, means the file
// is not PLY (a binary file read as text would otherwise be slurped whole).
constexpr size_t kMaxHeaderLineLength = 1 << 16;
constexpr int kMaxHeaderLines = 100000;
// Bytes per read refill.
constexpr size_t kReadBufferSize = 1 << 20;

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

bool ParseType(const std::string& name, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [n, t] : kNames) {
    if (name == n) {
      *type = t;
      return true;
    }
  }
  return false;
}

size_t TypeSize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

template <typename T>
T Load(const uint8_t* p, bool swap) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

double LoadScalar(const uint8_t* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::kInt8:
      return Load<int8_t>(p, swap);
    case PlyType::kUint8:
      return Load<uint8_t>(p, swap);
    case PlyType::kInt16:
      return Load<int16_t>(p, swap);
    case PlyType::kUint16:
      return Load<uint16_t>(p, swap);
    case PlyType::kInt32:
      return Load<int32_t>(p, swap);
    case PlyType::kUint32:
      return Load<uint32_t>(p, swap);
    case PlyType::kFloat32:
      return Load<float>(p, swap);
    case PlyType::kFloat64:
      return Load<double>(p, swap);
  }
  return 0;
}

// What a vertex property is read into.
enum class Role { kSkip, kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kScore, kViews };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // lists only
  Role role = Role::kSkip;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::string crs;
  int lines = 0;  // header lines, `end_header` included
};

Role RoleOf(const std::string& name) {
  static const std::pair<const char*, Role> kRoles[] = {
      {"x", Role::kX},
      {"y", Role::kY},
      {"z", Role::kZ},
      {"nx", Role::kNx},
      {"ny", Role::kNy},
      {"nz", Role::kNz},
      {"red", Role::kRed},
      {"green", Role::kGreen},
      {"blue", Role::kBlue},
      {"score", Role::kScore},
      {"views", Role::kViews},
      // What sapmvs writes since CloudCompare's command line keeps only
      // `scalar_*` properties; the plain names are what it wrote before.
      {"scalar_score", Role::kScore},
      {"scalar_views", Role::kViews}};
  for (const auto& [n, r] : kRoles) {
    if (name == n) return r;
  }
  return Role::kSkip;
}

// Reads one header line (without its '\n' and any '\r'); false at the end.
bool ReadHeaderLine(std::istream& in, std::string* line) {
  line->clear();
  char c;
  bool any = false;
  while (in.get(c)) {
    any = true;
    if (c == '\n') break;
    if (line->size() >= kMaxHeaderLineLength) return true;  // caught as malformed
    line->push_back(c);
  }
  if (!line->empty() && line->back() == '\r') line->pop_back();
  return any;
}

PlyHeader ReadHeader(std::istream& in, const std::string& file) {
  PlyHeader h;
  std::string line;
  int n = 0;
  auto fail = [&](const std::string& message) { return InputError(file, n, message); };
  if (!ReadHeaderLine(in, &line)) throw InputError(file, 0, "empty file (expected a PLY header)");
  n = 1;
  if (line != "ply") throw fail("expected 'ply' as the first line (not a PLY file)");
  bool have_format = false;
  while (true) {
    if (!ReadHeaderLine(in, &line)) throw fail("header ends without 'end_header'");
    if (++n > kMaxHeaderLines || line.size() >= kMaxHeaderLineLength) {
      throw fail("header line too long or too many header lines (not a PLY file?)");
    }
    const std::vector<std::string> t = SplitWhitespace(line);
    if (t.empty()) continue;
    const std::string& key = t[0];
    if (key == "end_header") {
      if (t.size() != 1) throw fail("expected 'end_header' alone on its line");
      break;
    } else if (key == "comment" || key == "obj_info") {
      const size_t at = line.find("crs ");
      if (key == "comment" && t.size() >= 3 && t[1] == "crs") {
        h.crs = line.substr(at + 4);
        h.crs.erase(0, h.crs.find_first_not_of(" \t"));
      }
    } else if (key == "format") {
      if (t.size() != 3) throw fail("expected 'format <ascii|binary_little_endian|...> 1.0'");
      if (t[1] == "ascii") {
        h.format = PlyFormat::kAscii;
      } else if (t[1] == "binary_little_endian") {
        h.format = PlyFormat::kBinaryLittleEndian;
      } else if (t[1] == "binary_big_endian") {
        h.format = PlyFormat::kBinaryBigEndian;
      } else {
        throw fail("unknown format '" + t[1] +
                   "' (expected ascii, binary_little_endian or binary_big_endian)");
      }
      if (t[2] != "1.0") throw fail("expected PLY version 1.0, got '" + t[2] + "'");
      have_format = true;
    } else if (key == "element") {
      if (t.size() != 3) throw fail("expected 'element <name> <count>'");
      char* end = nullptr;
      errno = 0;
      const unsigned long long count = std::strtoull(t[2].c_str(), &end, 10);
      if (*end != '\0' || t[2][0] == '-' || errno == ERANGE) {
        throw fail("expected a non-negative element count, got '" + t[2] + "'");
      }
      h.elements.push_back({t[1], static_cast<uint64_t>(count), {}});
    } else if (key == "property") {
      if (h.elements.empty()) throw fail("'property' before any 'element'");
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        p.is_list = true;
        if (!ParseType(t[2], &p.count_type) || !ParseType(t[3], &p.type)) {
          throw fail("unknown type in '" + line + "'");
        }
        if (p.count_type == PlyType::kFloat32 || p.count_type == PlyType::kFloat64) {
          throw fail("list count type must be an integer type, got '" + t[2] + "'");
        }
        p.name = t[4];
      } else if (t.size() == 3) {
        if (!ParseType(t[1], &p.type)) throw fail("unknown property type '" + t[1] + "'");
        p.name = t[2];
      } else {
        throw fail("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      if (h.elements.back().name == "vertex" && !p.is_list) p.role = RoleOf(p.name);
      h.elements.back().properties.push_back(p);
    } else {
      throw fail("unexpected header keyword '" + key + "'");
    }
  }
  if (!have_format) throw InputError(file, 2, "expected a 'format' line after 'ply'");
  h.lines = n;
  return h;
}

// Buffered reading of binary data.
class BinaryCursor {
 public:
  explicit BinaryCursor(std::istream& in) : in_(in) {}

  // A pointer to the next `n` bytes (valid until the next call), or nullptr
  // when the file ends first.
  const uint8_t* Take(size_t n) {
    if (end_ - pos_ < n && !Refill(n)) return nullptr;
    const uint8_t* p = buffer_.data() + pos_;
    pos_ += n;
    return p;
  }

  // Skips `n` bytes without holding them (a corrupt list count must not
  // allocate); false when the file ends first.
  bool Skip(uint64_t n) {
    while (n > 0) {
      const size_t step = static_cast<size_t>(std::min<uint64_t>(n, kReadBufferSize));
      if (!Take(step)) return false;
      n -= step;
    }
    return true;
  }

 private:
  bool Refill(size_t n) {
    const size_t keep = end_ - pos_;
    if (keep > 0) std::memmove(buffer_.data(), buffer_.data() + pos_, keep);  // data() may be null
    if (buffer_.size() < std::max(n, kReadBufferSize)) buffer_.resize(std::max(n, kReadBufferSize));
    in_.read(reinterpret_cast<char*>(buffer_.data() + keep),
             static_cast<std::streamsize>(buffer_.size() - keep));
    pos_ = 0;
    end_ = keep + static_cast<size_t>(in_.gcount());
    return end_ >= n;
  }

  std::istream& in_;
  std::vector<uint8_t> buffer_;
  size_t pos_ = 0, end_ = 0;
};

uint8_t ToColor8(double v, PlyType type) {
  // NaN passes std::clamp unchanged, and its cast is undefined (fuzzing).
  if (std::isnan(v)) return 0;
  if (type == PlyType::kUint16) v = std::floor((v + 128) / 257);
  return static_cast<uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
}

// A double outside float's range converts with undefined behaviour; it
// becomes an infinity instead.
float NarrowToFloat(double v) {
  if (v > std::numeric_limits<float>::max()) return std::numeric_limits<float>::infinity();
  if (v < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

// Stores one decoded value of a vertex property. Returns false for a views
// value that is no count an int can hold (NaN, 3e38, -1, 2.5): casting it
// would be undefined behaviour.
bool Assign(CloudPoint* p, Role role, PlyType type, double v) {
  switch (role) {
    case Role::kX:
      p->position.x() = v;
      break;
    case Role::kY:
      p->position.y() = v;
      break;
    case Role::kZ:
      p->position.z() = v;
      break;
    case Role::kNx:
      p->normal.x() = NarrowToFloat(v);
      break;
    case Role::kNy:
      p->normal.y() = NarrowToFloat(v);
      break;
    case Role::kNz:
      p->normal.z() = NarrowToFloat(v);
      break;
    case Role::kRed:
      p->color[0] = ToColor8(v, type);
      break;
    case Role::kGreen:
      p->color[1] = ToColor8(v, type);
      break;
    case Role::kBlue:
      p->color[2] = ToColor8(v, type);
      break;
    case Role::kScore:
      p->score = NarrowToFloat(v);
      break;
    case Role::kViews:
      if (!(v >= 0 && v <= std::numeric_limits<int>::max() && v == std::floor(v))) return false;
      p->num_views = static_cast<int>(v);
      break;
    case Role::kSkip:
      break;
  }
  return true;
}

std::string BadViews(double v) {
  std::ostringstream s;
  s << "views = " << v << " (expected a whole count 0.." << std::numeric_limits<int>::max() << ")";
  return s.str();
}

std::string Ordinal(uint64_t i, const PlyElement& e) {
  return e.name + " " + std::to_string(i) + " of " + std::to_string(e.count) + " (0-based)";
}

// One property of a point, its field and value checked (Assign), else an
// InputError naming the point.
void AssignOrThrow(CloudPoint* p, const PlyProperty& prop, double v, const std::string& file,
                   uint64_t i, const PlyElement& e) {
  if (!Assign(p, prop.role, prop.type, v)) {
    throw InputError(file, 0, Ordinal(i, e) + ": " + BadViews(v));
  }
}

// The point's position checked, then shown to `keep`; true when it is kept.
bool Keeps(const CloudPoint& p, const PointFilter& keep, const std::string& file, uint64_t i,
           const PlyElement& e) {
  if (!p.position.allFinite()) {
    throw InputError(file, 0, "non-finite coordinate in " + Ordinal(i, e));
  }
  return !keep || keep(p.position);
}

void ReadBinaryElement(BinaryCursor* in, const std::string& file, const PlyElement& e, bool swap,
                       std::vector<CloudPoint>* points, const PointFilter& keep) {
  // A point of fixed size (no list property) is taken in one piece, each
  // property read at its offset; a filtered read loads the position first
  // and nothing more of a point it drops. Property by property, a point cost
  // about 100 ns, and the tiled merge reads a group's cloud once per tile.
  struct Field {
    size_t offset;
    const PlyProperty* prop;
  };
  std::vector<Field> position, rest;
  size_t record = 0;
  bool fixed = points != nullptr;
  for (const PlyProperty& prop : e.properties) {
    if (prop.is_list) fixed = false;
    if (prop.role == Role::kX || prop.role == Role::kY || prop.role == Role::kZ) {
      position.push_back({record, &prop});
    } else if (prop.role != Role::kSkip) {
      rest.push_back({record, &prop});
    }
    record += TypeSize(prop.type);
  }
  for (uint64_t i = 0; i < e.count; ++i) {
    // A point cut short by the end of the file takes the path below, which
    // names the property it ends in (a failed Take consumes nothing).
    if (const uint8_t* b = fixed ? in->Take(record) : nullptr) {
      CloudPoint p;
      for (const Field& f : position) {
        Assign(&p, f.prop->role, f.prop->type, LoadScalar(b + f.offset, f.prop->type, swap));
      }
      if (!Keeps(p, keep, file, i, e)) continue;
      for (const Field& f : rest) {
        AssignOrThrow(&p, *f.prop, LoadScalar(b + f.offset, f.prop->type, swap), file, i, e);
      }
      points->push_back(p);
      continue;
    }
    CloudPoint p;
    for (const PlyProperty& prop : e.properties) {
      const uint8_t* b = in->Take(TypeSize(prop.is_list ? prop.count_type : prop.type));
      bool ok = b != nullptr;
      if (ok && prop.is_list) {
        const double n = LoadScalar(b, prop.count_type, swap);
        if (!(n >= 0 && n <= 1e15)) {
          throw InputError(file, 0,
                           "bad list length (not a count) in " + Ordinal(i, e) + ", property '" +
                               prop.name + "' (corrupt data)");
        }
        ok = in->Skip(static_cast<uint64_t>(n) * TypeSize(prop.type));
      } else if (ok && points && prop.role != Role::kSkip) {
        AssignOrThrow(&p, prop, LoadScalar(b, prop.type, swap), file, i, e);
      }
      if (!ok) {
        throw InputError(
            file, 0,
            "truncated: the data ends in " + Ordinal(i, e) + ", property '" + prop.name + "'");
      }
    }
    if (points && Keeps(p, keep, file, i, e)) points->push_back(p);
  }
}

double ParseAscii(const std::string& token, const TextLines& lines, const PlyProperty& prop) {
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (token.empty() || *end != '\0') {
    throw lines.Fail("expected a number for property '" + prop.name + "', got '" + token + "'");
  }
  return v;
}

void ReadAsciiElement(TextLines* lines, const PlyElement& e, std::vector<CloudPoint>* points,
                      const PointFilter& keep) {
  std::string line;
  for (uint64_t i = 0; i < e.count; ++i) {
    do {
      if (!lines->NextRaw(&line, false)) {
        throw InputError(lines->file(), lines->line(),
                         "truncated: expected " + std::to_string(e.count) + " " + e.name +
                             " lines, the file ends after " + std::to_string(i));
      }
    } while (line.find_first_not_of(" \t") == std::string::npos);
    const std::vector<std::string> t = SplitWhitespace(line);
    CloudPoint p;
    size_t k = 0;
    auto next = [&](const PlyProperty& prop) -> const std::string& {
      if (k >= t.size()) {
        throw lines->Fail("too few values for " + Ordinal(i, e) + " (missing property '" +
                          prop.name + "')");
      }
      return t[k++];
    };
    for (const PlyProperty& prop : e.properties) {
      const double v = ParseAscii(next(prop), *lines, prop);
      if (prop.is_list) {
        if (v < 0 || v != std::floor(v)) {
          throw lines->Fail("bad list length for property '" + prop.name + "'");
        }
        for (double j = 0; j < v; ++j) next(prop);
      } else if (points && !Assign(&p, prop.role, prop.type, v)) {
        throw lines->Fail(Ordinal(i, e) + ": " + BadViews(v));
      }
    }
    if (k != t.size()) {
      throw lines->Fail("expected " + std::to_string(k) + " values for " + Ordinal(i, e) +
                        ", got " + std::to_string(t.size()));
    }
    if (points) {
      if (!p.position.allFinite()) {
        throw lines->Fail("non-finite coordinate in " + Ordinal(i, e));
      }
      if (!keep || keep(p.position)) points->push_back(p);
    }
  }
}

bool Declares(const PlyElement& e, Role role) {
  return std::any_of(e.properties.begin(), e.properties.end(),
                     [role](const PlyProperty& p) { return p.role == role; });
}

}  // namespace

PointCloud ReadPly(const std::filesystem::path& path, const PointFilter& keep) {
  const std::string file = path.string();
  if (const std::string problem = NotRegularFile(path); !problem.empty()) {
    throw InputError(file, 0, "cannot open file (" + problem + "; expected a PLY file)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(file, 0, "cannot open file (unreadable; expected a PLY file)");
  const PlyHeader h = ReadHeader(in, file);

  const auto vertex = std::find_if(h.elements.begin(), h.elements.end(),
                                   [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == h.elements.end()) throw InputError(file, 0, "no 'vertex' element in the header");
  for (Role r : {Role::kX, Role::kY, Role::kZ}) {
    if (!Declares(*vertex, r)) {
      throw InputError(file, 0, "the vertex element lacks one of the properties x, y, z");
    }
  }
  PointCloud cloud;
  cloud.crs = h.crs;
  cloud.has_normals =
      Declares(*vertex, Role::kNx) && Declares(*vertex, Role::kNy) && Declares(*vertex, Role::kNz);
  cloud.has_colors = Declares(*vertex, Role::kRed) && Declares(*vertex, Role::kGreen) &&
                     Declares(*vertex, Role::kBlue);
  cloud.has_scores = Declares(*vertex, Role::kScore);
  cloud.has_views = Declares(*vertex, Role::kViews);
  // Cap the reservation: a corrupt count must not allocate before the data
  // proves it exists. A filtered read keeps an unknown share, and is
  // reserved for all only where the pages it leaves unwritten cost nothing
  // (the merge's tile of one group: its copies on growth were a fifth of the
  // read on `city`).
  if (!keep || UnwrittenMemoryIsFree()) {
    cloud.points.reserve(static_cast<size_t>(std::min<uint64_t>(vertex->count, 1u << 24)));
  }

  if (h.format == PlyFormat::kAscii) {
    in.close();
    TextLines lines(path);
    std::string skip;
    for (int i = 0; i < h.lines; ++i) lines.NextRaw(&skip, false);
    for (auto e = h.elements.begin(); e != std::next(vertex); ++e) {
      ReadAsciiElement(&lines, *e, e == vertex ? &cloud.points : nullptr, keep);
    }
    return cloud;
  }

  const bool swap = h.format == PlyFormat::kBinaryBigEndian;
  BinaryCursor cursor(in);
  for (auto e = h.elements.begin(); e != std::next(vertex); ++e) {
    ReadBinaryElement(&cursor, file, *e, swap, e == vertex ? &cloud.points : nullptr, keep);
  }
  return cloud;
}

}  // namespace sapmvs
