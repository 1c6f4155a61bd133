#pragma once
// Flight strips of an aerial block, found from the camera centres and
// headings alone (method.md 2.1), so that grouping needs no image and no flight
// log, and so that the result does not depend on the order the block lists
// its images in:
//  1. Headings: the camera's image x axis on the ground (kappa, for a frame
//     camera flown with image x along track). Headings are clustered on the
//     circle; a turn between strips (alternating directions, a cross strip at
//     90 deg) separates them.
//  2. Within one heading, the along-track axis is the mean direction from each
//     centre to its nearest neighbour (the forward base is shorter than the
//     strip spacing in any block flown for stereo), and the base is the
//     median nearest-neighbour distance.
//  3. Centres are split where their cross-track offsets jump (parallel strips
//     flown the same way) and where the along-track spacing jumps (a strip
//     broken off and resumed with no overlap).
//  4. Each strip is ordered in flight order: the block's own order when it
//     runs along the strip, else the direction of the image x axis.
#include <vector>

#include "sapmvs/block/block.h"

namespace sapmvs {

// Every image of `block` in exactly one strip, each strip in flight order;
// strips ordered by the smallest block index they hold.
std::vector<std::vector<int>> DetectStrips(const Block& block);

}  // namespace sapmvs
