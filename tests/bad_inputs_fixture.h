#pragma once
// Small valid blocks in every format the readers take (two 96 x 72 images
// looking down from 100 m over ground at Z = 0), and point clouds for
// `evaluate`, written into a folder for bad_inputs_test.cc to break one way
// per case.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sapmvs::test {

constexpr int kFixtureWidth = 96;
constexpr int kFixtureHeight = 72;

// DIR/block.yaml, DIR/orientation.txt (images a, b), DIR/images/{a,b}.EXT.
void WriteYamlFixture(const std::filesystem::path& dir, const std::string& ext = ".png");
// The yaml fixture with its orientation as Metashape exports it:
// DIR/cameras.txt (`format: metashape`, tabs, r11..r33), no orientation.txt.
void WriteMetashapeFixture(const std::filesystem::path& dir);
// The yaml fixture with its orientation as Pix4D exports it (detected):
// DIR/p_calibrated_external_camera_parameters.txt, no orientation.txt.
void WritePix4dFixture(const std::filesystem::path& dir);
constexpr const char* kPix4dFixtureFile = "p_calibrated_external_camera_parameters.txt";
// DIR/sparse/{cameras,images}.txt, DIR/images/{a,b}.png.
void WriteColmapFixture(const std::filesystem::path& dir);
// DIR/cams/{a,b}.png.camera, DIR/images/{a,b}.png.
void WriteStrechaFixture(const std::filesystem::path& dir);
// DIR/reconstruction.json (shots a.png, b.png), DIR/images/{a,b}.png.
void WriteOpenSfmFixture(const std::filesystem::path& dir);
// The OpenSfM fixture georeferenced by DIR/reference_lla.json (47 N, 8 E).
void WriteOpenSfmLlaFixture(const std::filesystem::path& dir);
// DIR/txt/0000000{0,1}.txt, DIR/visualize/0000000{0,1}.png.
void WritePmvsFixture(const std::filesystem::path& dir);
// DIR/cloud.xyz (a few points) and DIR/lidar.xyz (a 20 x 20 grid, spacing 1).
void WriteCloudFixture(const std::filesystem::path& dir);

// A test image of the fixture's size (or w x h) at `path`, format from the
// extension.
void WriteFixtureImage(const std::filesystem::path& path, int w = kFixtureWidth,
                       int h = kFixtureHeight);
void WriteText(const std::filesystem::path& path, const std::string& text);
std::string ReadText(const std::filesystem::path& path);
// Replaces `path` (a file or nothing) by a FIFO.
void MakeFifo(const std::filesystem::path& path);
// Keeps the first `share` of a file's bytes.
void Truncate(const std::filesystem::path& path, double share);
// Replaces every `from` in a text file; throws when there is none.
void ReplaceInFile(const std::filesystem::path& path, const std::string& from,
                   const std::string& to);
std::string ReplaceAll(std::string s, const std::string& from, const std::string& to);

// One row of docs/bad-inputs.md, first section.
struct BadInputCase {
  std::string name;   // the test's name: BadInputRow.<name>
  std::string input;  // the table's first two columns
  std::string wrong;
  std::function<void(const std::filesystem::path&)> setup;  // writes a broken block there
  std::string args;                                         // CLI arguments; {D} is the folder
};
std::vector<BadInputCase> BadInputCases();

}  // namespace sapmvs::test
