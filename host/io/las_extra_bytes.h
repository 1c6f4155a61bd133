#pragma once
// LAS Extra Bytes (LAS 1.4 R15, "Extra Bytes" VLR): the 192-byte descriptors
// of the Extra Bytes VLR (LASF_Spec/4) and the values they describe at the end
// of each point record. las_io.cc builds files with them; nothing here does
// I/O.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sapmvs/io/las_extra_field.h"

namespace sapmvs::las {

constexpr size_t kExtraDescriptorSize = 192;
constexpr char kSpecUserId[] = "LASF_Spec";
constexpr uint16_t kExtraBytesRecordId = 4;

// Bytes one value of `type` takes in a record.
size_t ExtraTypeSize(LasExtraType type);

// Empty when `fields` can be written for `points` points, else one line
// naming the field (and the point) at fault and what was expected.
std::string ExtraFieldsProblem(const std::vector<LasExtraField>& fields, size_t points);

// The Extra Bytes VLR's payload: one descriptor per field, in order. Float
// fields carry their min and max (options bits 1 and 2; see WriteLas).
std::vector<uint8_t> EncodeExtraDescriptors(const std::vector<LasExtraField>& fields);

// Point `i`'s values of `fields`, packed in order into `out` (the record's
// bytes after its format's own). The fields passed ExtraFieldsProblem.
void EncodeExtraValues(const std::vector<LasExtraField>& fields, size_t i, uint8_t* out);

// A described field as read: where its value lies after the format's own
// bytes, and how to turn the stored number into the value.
struct ExtraFieldLayout {
  LasExtraField field;  // without values
  size_t offset = 0;
  double scale = 1, add = 0;
};

// The fields a VLR payload describes, for records with `available` bytes
// after their format's own. Undocumented (type 0) and deprecated array types
// (11-30) are skipped over by their size; a reserved type (31-255) ends the
// list, since what follows cannot be placed. Empty when the payload is not
// whole descriptors or describes more bytes than `available` (LAS 1.4 R15:
// an "extra bytes mismatch" renders the VLR invalid).
std::vector<ExtraFieldLayout> DecodeExtraDescriptors(const std::vector<uint8_t>& payload,
                                                     size_t available);

// The value of `layout` in a record whose extra bytes start at `extra`.
double DecodeExtraValue(const ExtraFieldLayout& layout, const uint8_t* extra);

// A NUL-padded fixed-size text field of a LAS header or record (at most `n`
// bytes); "" for n = 0, where `p` may be null.
std::string FixedString(const uint8_t* p, size_t n);

}  // namespace sapmvs::las
