// The cases of docs/bad-inputs.md, first section: each breaks one fixture
// (bad_inputs_fixture.h) one way. bad_inputs_test.cc runs them and compares
// the output with the table.

#include <filesystem>

#include "bad_inputs_fixture.h"

namespace sapmvs::test {
namespace fs = std::filesystem;

namespace {

// A yaml fixture with `from` replaced by `to` in one of its files.
std::function<void(const fs::path&)> Yaml(const std::string& file, const std::string& from,
                                          const std::string& to) {
  return [=](const fs::path& d) {
    WriteYamlFixture(d);
    ReplaceInFile(d / file, from, to);
  };
}

std::function<void(const fs::path&)> Colmap(const std::string& file, const std::string& from,
                                            const std::string& to) {
  return [=](const fs::path& d) {
    WriteColmapFixture(d);
    ReplaceInFile(d / "sparse" / file, from, to);
  };
}

std::function<void(const fs::path&)> Strecha(const std::string& from, const std::string& to) {
  return [=](const fs::path& d) {
    WriteStrechaFixture(d);
    ReplaceInFile(d / "cams" / "a.png.camera", from, to);
  };
}

std::function<void(const fs::path&)> OpenSfm(const std::string& from, const std::string& to) {
  return [=](const fs::path& d) {
    WriteOpenSfmFixture(d);
    ReplaceInFile(d / "reconstruction.json", from, to);
  };
}

std::function<void(const fs::path&)> Metashape(const std::string& from, const std::string& to) {
  return [=](const fs::path& d) {
    WriteMetashapeFixture(d);
    ReplaceInFile(d / "cameras.txt", from, to);
  };
}

std::function<void(const fs::path&)> Pix4d(const std::string& from, const std::string& to) {
  return [=](const fs::path& d) {
    WritePix4dFixture(d);
    ReplaceInFile(d / kPix4dFixtureFile, from, to);
  };
}

std::function<void(const fs::path&)> OpenSfmLla(const std::string& from, const std::string& to) {
  return [=](const fs::path& d) {
    WriteOpenSfmLlaFixture(d);
    ReplaceInFile(d / "reference_lla.json", from, to);
  };
}

std::function<void(const fs::path&)> Pmvs(const std::string& from, const std::string& to) {
  return [=](const fs::path& d) {
    WritePmvsFixture(d);
    ReplaceInFile(d / "txt" / "00000000.txt", from, to);
  };
}

// An ASCII PLY cloud of two points whose second has `views` = `views`.
std::function<void(const fs::path&)> PlyViews(const std::string& views) {
  return [=](const fs::path& d) {
    WriteCloudFixture(d);
    WriteText(d / "cloud.ply",
              "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
              "property double z\nproperty float views\nend_header\n5 5 1 3\n6 7 1.5 " +
                  views + "\n");
  };
}

const char* kInfo = "info {D}/block.yaml";

void YamlAsIs(const fs::path& d) { WriteYamlFixture(d); }

}  // namespace

std::vector<BadInputCase> BadInputCases() {
  return {
      // block.yaml and its orientation file
      {"BlockMissing", "block path", "does not exist", [](const fs::path&) {},
       "info {D}/block.yaml"},
      {"BlockFifo", "block.yaml", "a FIFO (would block on open)",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         MakeFifo(d / "block.yaml");
       },
       kInfo},
      {"OrientationFifo", "orientation.txt", "a FIFO (would block on open)",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         MakeFifo(d / "orientation.txt");
       },
       kInfo},
      {"OrientationMissing", "orientation.txt", "missing",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         fs::remove(d / "orientation.txt");
       },
       kInfo},
      {"OrientationColumns", "orientation.txt", "a line with 6 fields",
       Yaml("orientation.txt", "b 3 0 100 0 0 0", "b 3 0 100 0 0"), kInfo},
      {"OrientationNotANumber", "orientation.txt", "a letter O for a zero",
       Yaml("orientation.txt", "b 3 0 100", "b 3 O 100"), kInfo},
      {"OrientationNaN", "orientation.txt", "nan for an angle",
       Yaml("orientation.txt", "b 3 0 100 0 0 0", "b 3 0 100 nan 0 0"), kInfo},
      {"OrientationImageTwice", "orientation.txt", "image a listed twice",
       Yaml("orientation.txt", "b 3 0 100", "a 3 0 100"), kInfo},
      {"OrientationImageMissing", "orientation.txt", "image c has no file",
       Yaml("orientation.txt", "b 3 0 100", "c 3 0 100"), kInfo},
      {"YamlSyntax", "block.yaml", "an unclosed [", Yaml("block.yaml", "width: 96", "width: [96"),
       kInfo},
      {"YamlNoCamera", "block.yaml", "no camera", Yaml("block.yaml", "camera:", "kamera:"), kInfo},
      {"YamlNegativeWidth", "block.yaml", "width: -96",
       Yaml("block.yaml", "width: 96", "width: -96"), kInfo},
      {"YamlUnknownUnits", "block.yaml", "units: mil",
       Yaml("block.yaml", "units: deg", "units: mil"), kInfo},
      {"YamlDemMissing", "block.yaml", "dem: names a missing file",
       Yaml("block.yaml", "ground_height: 0", "dem: dem.tif"), kInfo},
      {"CamerasLookUp", "orientation.txt", "omega 180: every camera looks up",
       Yaml("orientation.txt", "100 0 0 0", "100 180 0 0"), "plan {D}/block.yaml"},
      {"TileSizeTiny", "`plan --tile-size 1e-6`", "tiles far below a pixel (would plan for hours)",
       YamlAsIs, "plan {D}/block.yaml --strategy footprint --tile-size 1e-6"},
      {"UnknownBlockFile", "block path", "a file of no block format",
       [](const fs::path& d) { WriteText(d / "notes.txt", "hello\n"); }, "info {D}/notes.txt"},
      {"EmptyFolder", "block path", "a folder without a block", [](const fs::path&) {}, "info {D}"},
      {"UnknownFormatFlag", "`--format foo`", "not a format", YamlAsIs,
       "info {D}/block.yaml --format foo"},
      // the command line: refused before the block is read
      {"LevelNotAnInteger", "`run --level abc`", "not an integer", YamlAsIs,
       "run {D}/block.yaml --out {D}/out --level abc"},
      {"LasVersionUnknown", "`run --las-version 1.3`", "a LAS version sapmvs does not write",
       YamlAsIs, "run {D}/block.yaml --out {D}/out --las-version 1.3"},
      {"UnknownFlag", "`info --colour`", "no such flag", YamlAsIs, "info {D}/block.yaml --colour"},
      {"ThreadsNegative", "`--threads -1`", "a negative thread count", YamlAsIs,
       "--threads -1 info {D}/block.yaml"},
      {"LogFolderMissing", "`--log no/run.log`", "the log's folder does not exist", YamlAsIs,
       "info {D}/block.yaml --log {D}/no/run.log"},

      // images
      {"ImageZeroBytes", "images/a.png", "0 bytes",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         WriteText(d / "images" / "a.png", "");
       },
       kInfo},
      {"ImageJpegTruncated", "images/a.jpg", "cut to 60 % (libjpeg only warns)",
       [](const fs::path& d) {
         WriteYamlFixture(d, ".jpg");
         Truncate(d / "images" / "a.jpg", 0.6);
       },
       kInfo},
      {"ImageNotAnImage", "images/a.png", "text, not an image",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         WriteText(d / "images" / "a.png", "hello\n");
       },
       kInfo},
      {"ImageWrongSize", "images/a.png", "48 x 36 px, the camera says 96 x 72",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         WriteFixtureImage(d / "images" / "a.png", 48, 36);
       },
       kInfo},
      {"ImageAmbiguous", "images/a.jpg", "beside a.png: which is image a?",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         WriteFixtureImage(d / "images" / "a.jpg");
       },
       kInfo},
      {"ImageFifo", "images/a.png", "a FIFO (would block on open)",
       [](const fs::path& d) {
         WriteYamlFixture(d);
         MakeFifo(d / "images" / "a.png");
       },
       kInfo},

      // Metashape and Pix4D exports (block.yaml's orientation)
      {"MetashapeColumns", "cameras.txt (Metashape)", "a line with 15 fields",
       Metashape("b.png\t3\t0\t100\t0\t0\t0\t1", "b.png\t3\t0\t100\t0\t0\t1"), kInfo},
      {"MetashapeNotANumber", "cameras.txt (Metashape)", "a letter O for a zero",
       Metashape("b.png\t3\t0", "b.png\t3\tO"), kInfo},
      {"MetashapeImageTwice", "cameras.txt (Metashape)", "image a.png listed twice",
       Metashape("b.png\t3", "a.png\t3"), kInfo},
      {"MetashapeImageMissing", "cameras.txt (Metashape)", "image c.png has no file",
       Metashape("b.png\t3", "c.png\t3"), kInfo},
      {"MetashapeMatrixMismatch", "cameras.txt (Metashape)", "kappa 90 with r11..r33 of kappa 0",
       Metashape("b.png\t3\t0\t100\t0\t0\t0", "b.png\t3\t0\t100\t0\t0\t90"), kInfo},
      {"Pix4dColumns", "p_calibrated_external_camera_parameters.txt", "a line with 6 fields",
       Pix4d("b.png 3 0 100 0 0 0", "b.png 3 0 100 0 0"), kInfo},
      {"Pix4dNotANumber", "p_calibrated_external_camera_parameters.txt", "a letter O for a zero",
       Pix4d("b.png 3 0", "b.png 3 O"), kInfo},
      {"Pix4dImageTwice", "p_calibrated_external_camera_parameters.txt", "image a.png listed twice",
       Pix4d("b.png 3", "a.png 3"), kInfo},
      {"Pix4dImageMissing", "p_calibrated_external_camera_parameters.txt",
       "image c.png has no file", Pix4d("b.png 3", "c.png 3"), kInfo},
      {"Pix4dWgs84", "p_calibrated_external_camera_parameters_wgs84.txt",
       "Pix4D's latitude/longitude export",
       [](const fs::path& d) {
         WritePix4dFixture(d);
         ReplaceInFile(d / "block.yaml", "parameters.txt", "parameters_wgs84.txt");
         WriteText(d / "p_calibrated_external_camera_parameters_wgs84.txt",
                   "imageName latitude longitude altitude omega phi kappa\n"
                   "a.png 47.0 8.0 500 0 0 0\n");
       },
       kInfo},
      {"YamlExportUnits", "block.yaml", "units: gon for a Metashape export",
       [](const fs::path& d) {
         WriteMetashapeFixture(d);
         ReplaceInFile(d / "block.yaml", "format: metashape", "format: metashape\n  units: gon");
       },
       kInfo},

      // COLMAP
      {"ColmapImageTwice", "sparse/images.txt", "a.png listed twice",
       Colmap("images.txt", "1 b.png", "1 a.png"), "info {D}"},
      {"ColmapCameraModel", "sparse/cameras.txt", "model FISHEYE",
       Colmap("cameras.txt", "PINHOLE", "FISHEYE"), "info {D}"},
      {"ColmapQuaternion", "sparse/images.txt", "quaternion of norm 2",
       Colmap("images.txt", "1 0 1 0 0 0 0", "1 0 2 0 0 0 0"), "info {D}"},
      {"ColmapUnknownCamera", "sparse/images.txt", "CAMERA_ID 2, not in cameras.txt",
       Colmap("images.txt", "100 1 b.png", "100 2 b.png"), "info {D}"},
      {"ColmapImagesFifo", "sparse/images.txt", "a FIFO (would block on open)",
       [](const fs::path& d) {
         WriteColmapFixture(d);
         MakeFifo(d / "sparse" / "images.txt");
       },
       "info {D}/sparse/images.txt"},

      // Strecha
      {"StrechaNegativeFocal", "cams/a.png.camera", "fx = fy = -1000",
       Strecha("1000 0 48\n0 1000 36", "-1000 0 48\n0 -1000 36"), "info {D}/cams"},
      {"StrechaSameImage", "cams/a.camera", "beside a.png.camera: two cameras for a.png",
       [](const fs::path& d) {
         WriteStrechaFixture(d);
         fs::copy_file(d / "cams" / "a.png.camera", d / "cams" / "a.camera");
       },
       "info {D}/cams"},
      {"StrechaSkew", "cams/a.png.camera", "skew 50 px", Strecha("1000 0 48", "1000 50 48"),
       "info {D}/cams"},
      {"StrechaNotARotation", "cams/a.png.camera", "R with a row of length 2",
       Strecha("0 0 0\n1 0 0", "0 0 0\n2 0 0"), "info {D}/cams"},

      // OpenSfM
      {"OpenSfmHugeNumber", "reconstruction.json", "focal 1e999",
       OpenSfm("\"focal\": 10.4", "\"focal\": 1e999"), "info {D}"},
      {"OpenSfmBareWord", "reconstruction.json", "`\"camera\": hello` (not JSON)",
       OpenSfm("\"camera\": \"cam\",\n        \"rotation\": [3.14159265358979, 0, 0],\n"
               "        \"translation\": [0",
               "\"camera\": hello,\n        \"rotation\": [3.14159265358979, 0, 0],\n"
               "        \"translation\": [0"),
       "info {D}"},
      {"OpenSfmTypeNumber", "reconstruction.json", "projection_type 5",
       OpenSfm("\"perspective\"", "5"), "info {D}"},
      {"OpenSfmShotTwice", "reconstruction.json", "shot a.png twice",
       OpenSfm("\"b.png\": {", "\"a.png\": {"), "info {D}"},
      {"OpenSfmShotsOneFile", "reconstruction.json", "shots a.png and a: one file",
       OpenSfm("\"b.png\": {", "\"a\": {"), "info {D}"},
      {"OpenSfmUnknownCamera", "reconstruction.json", "a shot's camera is not in cameras",
       OpenSfm("\"camera\": \"cam\",\n        \"rotation\": [3.14159265358979, 0, 0],\n"
               "        \"translation\": [-3",
               "\"camera\": \"cam2\",\n        \"rotation\": [3.14159265358979, 0, 0],\n"
               "        \"translation\": [-3"),
       "info {D}"},

      {"OpenSfmLlaMissingKey", "reference_lla.json", "no altitude",
       OpenSfmLla(",\n  \"altitude\": 400.0", ""), "info {D}"},
      {"OpenSfmLlaNotANumber", "reference_lla.json", "latitude \"47.0\", a string",
       OpenSfmLla("47.0", "\"47.0\""), "info {D}"},
      {"OpenSfmLlaLatitude", "reference_lla.json", "latitude 91", OpenSfmLla("47.0", "91.0"),
       "info {D}"},
      {"OpenSfmLlaPolar", "reference_lla.json", "latitude 86, outside the UTM zones",
       OpenSfmLla("47.0", "86.0"), "info {D}"},

      // PMVS
      {"PmvsNegativeFocal", "txt/00000000.txt", "fx = -1000 in P, 00000001.txt right",
       Pmvs("1000 0 -48 4800", "-1000 0 -48 4800"), "info {D}"},
      {"PmvsJpgAndPng", "visualize/00000000.jpg", "beside 00000000.png: which is the image?",
       [](const fs::path& d) {
         WritePmvsFixture(d);
         WriteFixtureImage(d / "visualize" / "00000000.jpg");
       },
       "info {D}"},
      {"PmvsNoContour", "txt/00000000.txt", "no CONTOUR header", Pmvs("CONTOUR", "CONTOR"),
       "info {D}"},
      {"PmvsImageMissing", "visualize/00000001.png", "missing",
       [](const fs::path& d) {
         WritePmvsFixture(d);
         fs::remove(d / "visualize" / "00000001.png");
       },
       "info {D}"},

      // clouds given to evaluate
      {"EvaluateCloudFifo", "`evaluate` cloud.ply", "a FIFO (would block on open)",
       [](const fs::path& d) {
         WriteCloudFixture(d);
         MakeFifo(d / "cloud.ply");
       },
       "evaluate {D}/cloud.ply --reference {D}/lidar.xyz"},
      {"EvaluateLasFifo", "`evaluate --reference` lidar.las", "a FIFO (would block on open)",
       [](const fs::path& d) {
         WriteCloudFixture(d);
         MakeFifo(d / "lidar.las");
       },
       "evaluate {D}/cloud.xyz --reference {D}/lidar.las"},
      {"EvaluateRadiusHuge", "`evaluate --radius 1000`",
       "1000 x the LiDAR spacing (13 GB for 9,478 points)", WriteCloudFixture,
       "evaluate {D}/cloud.xyz --reference {D}/lidar.xyz --radius 1000"},
      {"PlyViewsNaN", "cloud.ply", "views = nan (cast to int: undefined)", PlyViews("nan"),
       "evaluate {D}/cloud.ply --reference {D}/lidar.xyz"},
      {"PlyViewsHuge", "cloud.ply", "views = 3e38 (cast to int: undefined)", PlyViews("3e38"),
       "evaluate {D}/cloud.ply --reference {D}/lidar.xyz"},
  };
}

}  // namespace sapmvs::test
