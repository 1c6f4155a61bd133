#include "util/gdal_messages.h"

#include <string>

#include "sapmvs/util/log.h"

namespace sapmvs {

void GdalMessageHandler(CPLErr level, CPLErrorNum /*number*/, const char* message) {
  if (level != CE_Warning || message == nullptr) return;
  std::string line = std::string("GDAL warning: ") + message;
  for (char& c : line) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  LogDetail(line);
}

void InstallGdalMessageHandler() { CPLSetErrorHandler(GdalMessageHandler); }

}  // namespace sapmvs
