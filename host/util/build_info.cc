#include "util/build_info.h"

// Defined on this file only (CMakeLists.txt): every other object stays the
// same from one commit to the next, and the compiler cache keeps hitting.
#ifndef SAPMVS_GIT_COMMIT
#define SAPMVS_GIT_COMMIT "unknown"
#endif

namespace sapmvs {

const char* BuildVersion() { return SAPMVS_VERSION; }
const char* BuildCommit() { return SAPMVS_GIT_COMMIT; }

}  // namespace sapmvs
