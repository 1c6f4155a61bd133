// A picture of a dense cloud for the docs and for eyeballing a run: the
// points are splatted through one of the block's cameras (or straight down),
// nearest first, in their own colour or coloured by height.
//
//   render_cloud CLOUD.ply --block BLOCK --image N --out picture.png
//   render_cloud CLOUD.ply --top --out picture.png [--width 1000]
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/util/error.h"

using namespace sapmvs;

int main(int argc, char** argv) {
  CLI::App app("Renders a cloud through a block camera or from above");
  std::string cloud_path, block_path, out_path;
  int image = 1, width = 1000, splat = 1;
  bool top = false, height_colours = false;
  app.add_option("cloud", cloud_path, "PLY cloud")->required();
  app.add_option("--block", block_path, "Block whose camera to render through");
  app.add_option("--image", image, "1-based image number of the camera")->capture_default_str();
  app.add_flag("--top", top, "Orthographic view from above instead of a camera");
  app.add_flag("--height", height_colours, "Colour by height instead of the points' colour");
  app.add_option("--width", width, "Picture width, pixels")->capture_default_str();
  app.add_option("--splat", splat, "Point radius, pixels")->capture_default_str();
  app.add_option("--out", out_path, "PNG to write")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const PointCloud cloud = ReadPly(cloud_path);
    if (cloud.points.empty()) throw Error(cloud_path + ": no points");
    std::vector<Eigen::Vector3d> uvz(cloud.points.size());  // pixel u, v, depth
    int w = width, h = width;
    if (top) {
      // The 0.5-99.5 % extent, so that a few stray points do not shrink the picture.
      std::vector<double> xs, ys;
      for (const CloudPoint& p : cloud.points) {
        xs.push_back(p.position.x());
        ys.push_back(p.position.y());
      }
      std::sort(xs.begin(), xs.end());
      std::sort(ys.begin(), ys.end());
      const size_t lo = xs.size() / 200, hi = xs.size() - 1 - xs.size() / 200;
      const double x0 = xs[lo], x1 = xs[hi], y0 = ys[lo], y1 = ys[hi];
      const double s = (width - 1) / std::max(x1 - x0, 1e-9);
      h = static_cast<int>((y1 - y0) * s) + 1;
      for (size_t i = 0; i < uvz.size(); ++i) {
        const Eigen::Vector3d& p = cloud.points[i].position;
        uvz[i] = {(p.x() - x0) * s, (y1 - p.y()) * s, -p.z()};
      }
    } else {
      if (block_path.empty()) throw Error("--block is needed unless --top");
      const Block block = ReadBlock(block_path);
      if (image < 1 || image > static_cast<int>(block.images.size())) {
        throw Error("--image: expected 1 to " + std::to_string(block.images.size()));
      }
      const Camera& cam = block.images[image - 1].camera;
      const double s = static_cast<double>(width) / cam.width();
      h = static_cast<int>(cam.height() * s);
      for (size_t i = 0; i < uvz.size(); ++i) {
        const Eigen::Vector3d& p = cloud.points[i].position;
        const Eigen::Vector2d uv = cam.Project(p);
        uvz[i] = {uv.x() * s, uv.y() * s, cam.Depth(p)};
      }
    }
    std::vector<double> zs;
    for (const CloudPoint& p : cloud.points) zs.push_back(p.position.z());
    std::sort(zs.begin(), zs.end());
    const double zlo = zs[zs.size() / 50], zhi = std::max(zlo + 1e-9, zs[zs.size() * 49 / 50]);
    cv::Mat depth(h, w, CV_64F, cv::Scalar(std::numeric_limits<double>::infinity()));
    cv::Mat picture(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
    // The colour scale once, as a 256-entry table.
    cv::Mat ramp(1, 256, CV_8UC1), colours;
    for (int k = 0; k < 256; ++k) ramp.at<uint8_t>(0, k) = static_cast<uint8_t>(k);
    cv::applyColorMap(ramp, colours, cv::COLORMAP_TURBO);
    for (size_t i = 0; i < uvz.size(); ++i) {
      const Eigen::Vector3d& q = uvz[i];
      if (!(q.z() > -1e300) || !std::isfinite(q.x()) || !std::isfinite(q.y())) continue;
      if (!top && !(q.z() > 0)) continue;
      cv::Vec3b c;
      const CloudPoint& p = cloud.points[i];
      if (height_colours || !cloud.has_colors) {
        c = colours.at<cv::Vec3b>(
            0, static_cast<int>(std::clamp((p.position.z() - zlo) / (zhi - zlo), 0.0, 1.0) * 255.0 +
                                0.5));
      } else {
        c = cv::Vec3b(p.color[2], p.color[1], p.color[0]);
      }
      const int u = static_cast<int>(std::lround(q.x())), v = static_cast<int>(std::lround(q.y()));
      for (int dv = -splat + 1; dv < splat; ++dv) {
        for (int du = -splat + 1; du < splat; ++du) {
          const int x = u + du, y = v + dv;
          if (x < 0 || y < 0 || x >= w || y >= h) continue;
          if (q.z() >= depth.at<double>(y, x)) continue;
          depth.at<double>(y, x) = q.z();
          picture.at<cv::Vec3b>(y, x) = c;
        }
      }
    }
    if (!cv::imwrite(out_path, picture)) throw Error(out_path + ": cannot write");
    std::cout << "wrote " << out_path << " (" << w << "x" << h << ")\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
