#pragma once
// What a binary was built from, for --version and report.json.

namespace sapmvs {

// The project's version ("0.1.0").
const char* BuildVersion();
// The short git commit of the source at configure time, or "unknown" when the
// source was not a git checkout.
const char* BuildCommit();

}  // namespace sapmvs
