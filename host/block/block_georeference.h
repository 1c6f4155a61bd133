#pragma once
// A block's frame as the user names it (BlockReadOptions::crs, enu_origin)
// or as its coordinates show it (ECEF), applied once a reader is done: a
// block in a local east-north-up frame or in ECEF goes to the UTM zone of
// its origin the way an OpenSfM block does (topocentric_to_utm.h), so that
// every output carries an EPSG code.

#include <Eigen/Core>

#include "block/topocentric_to_utm.h"
#include "sapmvs/block/block.h"
#include "sapmvs/block/block_reader.h"

namespace sapmvs {

// True when the block's camera centres lie within the band of heights
// cameras fly at from the Earth's centre and the cameras look, on average,
// towards it: coordinates that are ECEF. A projected block far north (a
// northing of 6.3e6 m) has such centres too, but looks along its own -Z.
bool LooksEcef(const Block& block);

// BlockReadOptions::enu_origin (latitude, longitude, height) as a point.
GeoReference AsGeoReference(const Eigen::Vector3d& lat_lon_height);

// Applies options.crs and options.enu_origin to `block`, or moves a block
// that LooksEcef to UTM; sets block->crs and block->frame_note. Throws Error
// naming the block when an option contradicts the block's own CRS.
void ApplyFrame(const BlockReadOptions& options, Block* block);

}  // namespace sapmvs
