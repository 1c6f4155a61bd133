#pragma once
// Memory sizes as users type them (--memory-budget) and as reports print them.
#include <string>

namespace sapmvs {

// "8G", "512M", "1.5G", "64k", "1048576" (bytes; K, M, G, T are powers of
// 1024, an optional trailing "B" or "iB" is accepted). Throws Error naming
// `text` otherwise, or when the size is not positive.
double ParseByteSize(const std::string& text);
// 1536 -> "1.5 KiB".
std::string FormatBytes(double bytes);

}  // namespace sapmvs
