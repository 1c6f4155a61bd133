#pragma once
// Exterior orientation as Metashape and Pix4D export it, read for block.yaml's
// `orientation: {file: ..., format: metashape|pix4d}`.
//
// Both write omega, phi, kappa in degrees in the convention of sapmvs's own
// orientation.txt (rotation.h): R = Rx(omega) Ry(phi) Rz(kappa) takes the
// photogrammetric camera frame (x right, y up, looking down -Z) to the world.
//   metashape  "Export Cameras > Omega Phi Kappa (*.txt)": `# Cameras (N)`,
//              then `# PhotoID, X, Y, Z, Omega, Phi, Kappa, r11, .., r33`;
//              fields separated by tabs or commas. r11..r33 is R transposed
//              (world to camera); the angles must agree with it.
//   pix4d      *_calibrated_external_camera_parameters.txt: the header
//              `imageName X Y Z Omega Phi Kappa`, fields separated by spaces.
//              The *_wgs84.txt variant (latitude, longitude) is refused: its
//              angles are not in a frame sapmvs can match in.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sapmvs {

enum class OrientationFormat { kAuto, kPlain, kMetashape, kPix4d };

// "auto", "plain", "metashape", "pix4d"; throws sapmvs::Error otherwise.
OrientationFormat ParseOrientationFormat(std::string_view text);
std::string ToString(OrientationFormat format);

// kMetashape for a first line `# Cameras (` or `# PhotoID`, kPix4d for a
// first field `imageName` or a Pix4D file name, else kPlain (sapmvs's own
// `name X Y Z a1 a2 a3`). Throws naming the file when it cannot be read.
OrientationFormat DetectOrientationFormat(const std::filesystem::path& path);

struct ExportedPose {
  std::string name;  // as the export names the image (with or without extension)
  int line = 0;      // of the file, for messages about this image
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d camera_to_world = Eigen::Matrix3d::Identity();  // R_pg (rotation.h)
};

// Reads every camera of an export; throws InputError naming file:line for a
// wrong field count, a non-number, an image listed twice, or (Metashape)
// r11..r33 that disagree with the angles by more than kMaxMatrixMismatch.
std::vector<ExportedPose> ReadMetashapeOpk(const std::filesystem::path& path);
std::vector<ExportedPose> ReadPix4dExternal(const std::filesystem::path& path);

// Largest |r_ij| difference accepted between Metashape's r11..r33 and the
// matrix of its angles: an export agrees to the rounding of its printed
// digits, far below this; a larger gap means another convention (a matrix
// not transposed, angles in another order) or an edited file.
constexpr double kMaxMatrixMismatch = 1e-6;

}  // namespace sapmvs
