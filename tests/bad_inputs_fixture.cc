#include "bad_inputs_fixture.h"

#include <sys/stat.h>

#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>

namespace sapmvs::test {
namespace fs = std::filesystem;

void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void MakeFifo(const fs::path& path) {
  fs::remove(path);
  if (::mkfifo(path.c_str(), 0600) != 0) throw std::runtime_error("mkfifo " + path.string());
}

std::string ReplaceAll(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

void Truncate(const fs::path& path, double share) {
  const std::string bytes = ReadText(path);
  WriteText(path, bytes.substr(0, static_cast<size_t>(share * static_cast<double>(bytes.size()))));
}

void ReplaceInFile(const fs::path& path, const std::string& from, const std::string& to) {
  const std::string text = ReadText(path);
  if (text.find(from) == std::string::npos) {
    throw std::runtime_error(path.string() + " lacks '" + from + "'");
  }
  WriteText(path, ReplaceAll(text, from, to));
}

void WriteFixtureImage(const fs::path& path, int w, int h) {
  fs::create_directories(path.parent_path());
  // Texture, so that a JPEG of it has entropy-coded data worth cutting.
  // A fixed seed: a JPEG's size, which a message may name, must not vary.
  cv::Mat image(h, w, CV_8UC3);
  cv::RNG rng(19);
  rng.fill(image, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(255));
  if (!cv::imwrite(path.string(), image)) throw std::runtime_error("imwrite " + path.string());
}

void WriteYamlFixture(const fs::path& dir, const std::string& ext) {
  WriteText(dir / "block.yaml",
            "ground_height: 0\n"
            "camera:\n"
            "  width: 96\n"
            "  height: 72\n"
            "  focal_mm: 10\n"
            "  pixel_um: 10\n"
            "images: images/\n"
            "orientation:\n"
            "  file: orientation.txt\n"
            "  type: angles\n"
            "  angles: omega-phi-kappa\n"
            "  units: deg\n");
  WriteText(dir / "orientation.txt",
            "# name X Y Z omega phi kappa\n"
            "a 0 0 100 0 0 0\n"
            "b 3 0 100 0 0 0\n");
  WriteFixtureImage(dir / "images" / ("a" + ext));
  WriteFixtureImage(dir / "images" / ("b" + ext));
}

namespace {
// block.yaml of the yaml fixture with `orientation` replaced by `orientation`.
void WriteExportBlockYaml(const fs::path& dir, const std::string& orientation) {
  WriteText(dir / "block.yaml",
            "ground_height: 0\n"
            "camera:\n"
            "  width: 96\n"
            "  height: 72\n"
            "  focal_mm: 10\n"
            "  pixel_um: 10\n"
            "images: images/\n"
            "orientation:\n" +
                orientation);
}
}  // namespace

void WriteMetashapeFixture(const fs::path& dir) {
  WriteYamlFixture(dir);
  fs::remove(dir / "orientation.txt");
  WriteExportBlockYaml(dir, "  file: cameras.txt\n  format: metashape\n");
  WriteText(dir / "cameras.txt",
            "# Cameras (2)\n"
            "# PhotoID, X, Y, Z, Omega, Phi, Kappa, r11, r12, r13, r21, r22, r23, r31, r32, r33\n"
            "a.png\t0\t0\t100\t0\t0\t0\t1\t0\t0\t0\t1\t0\t0\t0\t1\n"
            "b.png\t3\t0\t100\t0\t0\t0\t1\t0\t0\t0\t1\t0\t0\t0\t1\n");
}

void WritePix4dFixture(const fs::path& dir) {
  WriteYamlFixture(dir);
  fs::remove(dir / "orientation.txt");
  WriteExportBlockYaml(dir, std::string("  file: ") + kPix4dFixtureFile + "\n");
  WriteText(dir / kPix4dFixtureFile,
            "imageName X Y Z Omega Phi Kappa \n"
            "a.png 0 0 100 0 0 0\n"
            "b.png 3 0 100 0 0 0\n");
}

void WriteColmapFixture(const fs::path& dir) {
  WriteText(dir / "sparse" / "cameras.txt", "1 PINHOLE 96 72 1000 1000 48 36\n");
  // Looking down (x_cam = R X + t with R = diag(1, -1, -1)) from Z = 100.
  WriteText(dir / "sparse" / "images.txt",
            "1 0 1 0 0 0 0 100 1 a.png\n"
            "\n"
            "2 0 1 0 0 -3 0 100 1 b.png\n"
            "\n");
  WriteFixtureImage(dir / "images" / "a.png");
  WriteFixtureImage(dir / "images" / "b.png");
}

namespace {
std::string StrechaCamera(double x) {
  std::ostringstream s;
  s << "1000 0 48\n0 1000 36\n0 0 1\n0 0 0\n1 0 0\n0 -1 0\n0 0 -1\n" << x << " 0 100\n96 72\n";
  return s.str();
}
}  // namespace

void WriteStrechaFixture(const fs::path& dir) {
  WriteText(dir / "cams" / "a.png.camera", StrechaCamera(0));
  WriteText(dir / "cams" / "b.png.camera", StrechaCamera(3));
  WriteFixtureImage(dir / "images" / "a.png");
  WriteFixtureImage(dir / "images" / "b.png");
}

void WriteOpenSfmFixture(const fs::path& dir) {
  WriteText(dir / "reconstruction.json",
            "[\n"
            "  {\n"
            "    \"cameras\": {\n"
            "      \"cam\": {\n"
            "        \"projection_type\": \"perspective\",\n"
            "        \"width\": 96,\n"
            "        \"height\": 72,\n"
            "        \"focal\": 10.4\n"
            "      }\n"
            "    },\n"
            "    \"shots\": {\n"
            "      \"a.png\": {\n"
            "        \"camera\": \"cam\",\n"
            "        \"rotation\": [3.14159265358979, 0, 0],\n"
            "        \"translation\": [0, 0, 100]\n"
            "      },\n"
            "      \"b.png\": {\n"
            "        \"camera\": \"cam\",\n"
            "        \"rotation\": [3.14159265358979, 0, 0],\n"
            "        \"translation\": [-3, 0, 100]\n"
            "      }\n"
            "    }\n"
            "  }\n"
            "]\n");
  WriteFixtureImage(dir / "images" / "a.png");
  WriteFixtureImage(dir / "images" / "b.png");
}

void WriteOpenSfmLlaFixture(const fs::path& dir) {
  WriteOpenSfmFixture(dir);
  WriteText(dir / "reference_lla.json",
            "{\n"
            "  \"latitude\": 47.0,\n"
            "  \"longitude\": 8.0,\n"
            "  \"altitude\": 400.0\n"
            "}\n");
}

void WritePmvsFixture(const fs::path& dir) {
  // P = K [R | t], R = diag(1, -1, -1), t = -R C with C = (x, 0, 100).
  WriteText(dir / "txt" / "00000000.txt",
            "CONTOUR\n1000 0 -48 4800\n0 -1000 -36 3600\n0 0 -1 100\n");
  WriteText(dir / "txt" / "00000001.txt",
            "CONTOUR\n1000 0 -48 1800\n0 -1000 -36 3600\n0 0 -1 100\n");
  WriteFixtureImage(dir / "visualize" / "00000000.png");
  WriteFixtureImage(dir / "visualize" / "00000001.png");
}

void WriteCloudFixture(const fs::path& dir) {
  WriteText(dir / "cloud.xyz", "5 5 1\n6 7 1.5\n10 10 0.5\n");
  std::ostringstream lidar;
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) lidar << x << " " << y << " 1\n";
  }
  WriteText(dir / "lidar.xyz", lidar.str());
}

}  // namespace sapmvs::test
