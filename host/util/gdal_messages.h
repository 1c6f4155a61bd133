#pragma once
// GDAL reports failures and warnings through a handler that prints to stderr
// by default. Ours keeps failures quiet, because the caller folds
// CPLGetLastErrorMsg() into its own one-line Error, and passes warnings on as
// detail lines (log.h): on stderr at -v, always in the log file.

#include <cpl_error.h>

namespace sapmvs {

void GdalMessageHandler(CPLErr level, CPLErrorNum number, const char* message);

// Makes GdalMessageHandler the process's handler (CPLSetErrorHandler). A
// scoped CPLPushErrorHandler(GdalMessageHandler) behaves the same.
void InstallGdalMessageHandler();

}  // namespace sapmvs
