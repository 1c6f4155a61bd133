#pragma once
// Text pieces of a self-contained HTML page: escaped text, files inlined as
// data URIs, numbers as a reader of a report expects them.
#include <filesystem>
#include <string>

namespace sapmvs {

// `text` with &, <, >, " and ' escaped, for element content and attributes.
std::string HtmlEscape(const std::string& text);
// The bytes of `text` in base64 (RFC 4648, padded).
std::string Base64(const std::string& bytes);
// The file's bytes as a data URI of `mime` type; throws Error naming the file
// when it cannot be read.
std::string FileDataUri(const std::filesystem::path& path, const std::string& mime);
// An integer with thin spaces between thousands: 2 980 929.
std::string GroupedInteger(double value);
// `value` with `decimals` digits after the point; "–" when not finite.
std::string Decimal(double value, int decimals);

}  // namespace sapmvs
