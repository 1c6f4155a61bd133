#pragma once
// A small block on disk for the export tests: three textured images of odd
// size in three formats (PNG, JPEG, TIFF), one Brown-distorted camera with an
// off-centre principal point, and UTM-sized coordinates, so that undistortion,
// level scaling, names and the local frame are all exercised in well under a
// second (the simulator's `tiny` preset takes seconds).

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

namespace sapmvs::test {

// Writes DIR/block.yaml, DIR/orientation.txt and DIR/images/; returns the yaml.
inline std::filesystem::path WriteDistortedBlock(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir / "images");
  const std::vector<std::string> names = {"a.png", "b.jpg", "c.tif"};
  cv::RNG rng(42);
  std::ofstream orientation(dir / "orientation.txt");
  orientation.precision(17);
  for (size_t i = 0; i < names.size(); ++i) {
    cv::Mat noise(121, 161, CV_8UC3);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(noise, noise, cv::Size(5, 5), 1.2);
    cv::imwrite((dir / "images" / names[i]).string(), noise);
    // Three images 12 m apart along X, 100 m above the ground, tilted a little.
    orientation << names[i] << " " << 500123.4 + 12.0 * i << " " << 5400456.7 + 1.5 * i << " "
                << 400.25 << " " << 2.0 - i << " " << -1.5 + 0.5 * i << " " << 3.0 + 2 * i << "\n";
  }
  std::ofstream(dir / "block.yaml") << R"(crs: "EPSG:32632"
ground_height: 300.5
camera:
  name: distorted
  width: 161
  height: 121
  fx: 150.5
  fy: 149.25
  cx: 81.3
  cy: 59.7
  distortion: {k1: -0.1, k2: 0.02, k3: -0.003, p1: 0.001, p2: -0.0005}
images: images/
orientation:
  file: orientation.txt
  type: angles
  angles: omega-phi-kappa
  units: deg
)";
  return dir / "block.yaml";
}

}  // namespace sapmvs::test
