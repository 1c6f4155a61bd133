#pragma once
// GDAL reports failures and warnings through a handler that prints to stderr
// by default. Ours keeps failures quiet, because the caller folds
// CPLGetLastErrorMsg() into its own one-line Error, and passes warnings on as
// detail lines (log.h): on stderr at -v, always in the log file.

#include <cpl_error.h>
#include <gdal_priv.h>

#include <memory>
#include <string>

namespace sapmvs {

void GdalMessageHandler(CPLErr level, CPLErrorNum number, const char* message);

// Makes GdalMessageHandler the process's handler (CPLSetErrorHandler). A
// scoped CPLPushErrorHandler(GdalMessageHandler) behaves the same.
void InstallGdalMessageHandler();

// While one of our calls into GDAL runs, its failure messages are kept quiet
// and folded into our exception instead, so the user sees each once, in our
// one-line format; warnings become detail lines.
class QuietGdalErrors {
 public:
  QuietGdalErrors() {
    CPLPushErrorHandler(GdalMessageHandler);
    CPLErrorReset();
  }
  ~QuietGdalErrors() { CPLPopErrorHandler(); }
  QuietGdalErrors(const QuietGdalErrors&) = delete;
  QuietGdalErrors& operator=(const QuietGdalErrors&) = delete;

  static bool Failed() { return CPLGetLastErrorType() >= CE_Failure; }
  // " (GDAL: message)", or "" when GDAL said nothing.
  static std::string Detail() {
    const char* msg = CPLGetLastErrorMsg();
    return msg && *msg ? std::string(" (GDAL: ") + msg + ")" : std::string();
  }
};

struct GdalDatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, GdalDatasetCloser>;

}  // namespace sapmvs
