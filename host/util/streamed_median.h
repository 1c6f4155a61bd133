#pragma once
// The median of values computed on demand, without storing them all: the
// filter's plane tolerance is the median of up to 16 distances per point,
// which stored were as large as the neighbour table itself.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace sapmvs {

// Of the m values that `fill` gives, k per row, that are not NaN (all
// others >= 0): the one at index m / 2 once sorted, what nth_element places
// at begin() + m / 2 of them. NaN when m = 0. fill(r, out) writes row r's k
// values to out[0..k); it must write the same floats each time it is called
// (it is called twice per row, from several threads). A row's values come
// together, so that what they share is computed once.
//
// A histogram of the top 16 bits of each value's float representation,
// which orders floats >= 0 as their values, finds the bin the median falls
// in; only that bin's values are then gathered and selected from.
template <typename Fill>
float StreamedMedianOfRows(size_t rows, int k, const Fill& fill) {
  constexpr int kShift = 16;
  constexpr size_t kBins = size_t{1} << (32 - kShift);
  auto bin = [](float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return bits >> kShift;
  };
  std::vector<uint64_t> histogram(kBins, 0);
#pragma omp parallel
  {
    std::vector<uint64_t> own(kBins, 0);
    std::vector<float> values(k);
#pragma omp for schedule(static) nowait
    for (size_t r = 0; r < rows; ++r) {
      fill(r, values.data());
      for (const float v : values) {
        if (!std::isnan(v)) ++own[bin(v)];
      }
    }
#pragma omp critical
    for (size_t b = 0; b < kBins; ++b) histogram[b] += own[b];
  }
  uint64_t total = 0;
  for (const uint64_t c : histogram) total += c;
  if (total == 0) return std::nanf("");
  uint64_t rank = total / 2;
  size_t median_bin = 0;
  while (rank >= histogram[median_bin]) rank -= histogram[median_bin++];
  // The order the threads gather them in does not change the selected value.
  std::vector<float> in_bin;
  in_bin.reserve(histogram[median_bin]);
#pragma omp parallel
  {
    std::vector<float> own, values(k);
#pragma omp for schedule(static) nowait
    for (size_t r = 0; r < rows; ++r) {
      fill(r, values.data());
      for (const float v : values) {
        if (!std::isnan(v) && bin(v) == median_bin) own.push_back(v);
      }
    }
#pragma omp critical
    in_bin.insert(in_bin.end(), own.begin(), own.end());
  }
  std::nth_element(in_bin.begin(), in_bin.begin() + rank, in_bin.end());
  return in_bin[rank];
}

}  // namespace sapmvs
