#pragma once
// Flight strips of an aerial block, found from the camera centres alone
// (method.md 2.1), so that grouping needs no image and no flight log.
//
// A strip is a run of the flight: consecutive exposures whose steps keep one
// direction. The flight order is the image names' (cameras number their
// files in the order they take them) or the block's, whichever gives the
// shorter path through the centres; the block's own order alone is not
// trusted, since a reconstruction may list its images in any order. Along
// that path:
//  1. Images whose height above the ground is far from the block's median
//     are the climb and descent: they see the ground at another scale.
//  2. The path is cut where a step turns away from the run's mean direction
//     or jumps over several bases. A hand-flown strip wanders (its heading
//     by 15-20 degrees, its spacing unevenly) but does not turn back; a
//     turn between strips is a side step at 90 degrees or a reversal.
//  3. Runs of a few images across the block's main direction are turns
//     (side steps photographed on the way), runs as long as the others are
//     cross strips; an end image whose step leaves the run's line is a
//     turn photo too.
// Blocks whose names and order both jump about (no flight order), and
// blocks that do not look down, fall back to the layout alone
// (StripsFromLayout): headings clustered, centres split where their
// cross-track offsets jump.
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/plan/grouping.h"

namespace sapmvs {

struct BlockGeometry;

// A strip is split where consecutive centres lie this many bases apart: one
// missed exposure doubles the gap and still leaves overlap; at 3 bases a 70 %
// forward overlap is gone.
inline constexpr double kStripGapBases = 3.0;

struct StripDetection {
  std::vector<std::vector<int>> strips;  // each in flight order, strips in flight order
  std::vector<StripOutlier> outliers;    // every image in no strip, in flight order
  // The flight order the strips were cut from (every image); empty when the
  // layout alone was used.
  std::vector<int> flight_order;
};

// Every image of `block` in exactly one strip or outlier. `geometry`: the
// block's (EstimateBlockGeometry), estimated here when nullptr.
StripDetection DetectStrips(const Block& block, const BlockGeometry* geometry = nullptr);

// The flight order of `block`: its images by name, digit runs compared as
// numbers, or in block order, whichever path through the centres is shorter;
// empty when even that path's median step exceeds twice the median distance
// to the nearest centre (names and order both shuffled).
std::vector<int> FlightOrder(const Block& block);

// The layout-only detection: every image in exactly one strip, strips ordered
// by the smallest block index they hold.
std::vector<std::vector<int>> StripsFromLayout(const Block& block, const std::vector<int>& images);

}  // namespace sapmvs
