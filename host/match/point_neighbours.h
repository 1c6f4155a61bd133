#pragma once
// Each point's nearest others within a radius of its own: the neighbourhoods
// the filter's plane, patch-support and cluster tests read.
//
// Not FLANN's kd-tree (replaced in fa0c7a8): it answers "the k nearest", which
// the filter would then cut to the radius; its build is serial (one core
// idle for a tenth of a second per filter pass on the simulator's `city`)
// and its results, in size_t, must be searched in chunks to bound their
// memory. The radius is known before the search, so a grid of cells half a
// median radius wide finds the same neighbours with an O(n) build: points lie on
// surfaces, so the grid is dense in the two axes the cloud spans most and
// sorted along the third. Columns are read in rings around the point's and
// skipped once they lie beyond the k-th nearest found so far.
#include <cstdint>
#include <vector>

#include "sapmvs/util/default_init_allocator.h"

namespace sapmvs {

// For every point a of `xyz` (x, y, z of point a at 3a..3a+2): the indices of
// at most `k` other points b whose squared distance, summed in float in x, y,
// z order, is at most float(radius[a]^2), nearest first (ties by index);
// row a is out[a * k .. a * k + k), padded with -1 (every slot is
// written). Throws Error when the sizes disagree, k < 1, a radius is
// negative or not finite, or there are more than 2^31 - 1 points. `xyz` is
// taken by value so that a caller that moves it in frees it before the
// output is allocated.
//
// With `order`, the points are numbered in the grid's order instead: row r
// is point (*order)[r]'s, and its neighbours are given by their rows. Points
// near each other then have rows near each other, so that a caller reading
// its own per-point data through the rows finds the neighbours' in cache.
UninitializedVector<int32_t> NearestWithin(std::vector<float> xyz,
                                           const std::vector<double>& radius, int k,
                                           std::vector<int32_t>* order = nullptr);

// For each of `queries` (indices of points of `xyz`, laid out as above): the
// index of its nearest other point at any distance, by the float distance
// NearestWithin sums (ties by index); -1 for a cloud of one point. The same
// grid, sized to a few points per column at the cloud's mean density, is
// searched within a reach that doubles until a point is found. Throws Error
// when xyz's size is not a multiple of 3, a query is out of range, or there
// are more than 2^31 - 1 points.
std::vector<int32_t> NearestOther(const std::vector<float>& xyz,
                                  const std::vector<size_t>& queries);

}  // namespace sapmvs
