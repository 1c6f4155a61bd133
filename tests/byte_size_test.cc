#include "sapmvs/util/byte_size.h"

#include <gtest/gtest.h>

#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

TEST(ByteSize, ParsesWhatUsersTypeAndFormatsForReports) {
  EXPECT_DOUBLE_EQ(ParseByteSize("8G"), 8.0 * (1ull << 30));
  EXPECT_DOUBLE_EQ(ParseByteSize("512M"), 512.0 * (1 << 20));
  EXPECT_DOUBLE_EQ(ParseByteSize("1.5G"), 1.5 * (1ull << 30));
  EXPECT_DOUBLE_EQ(ParseByteSize("1048576"), 1048576.0);
  EXPECT_DOUBLE_EQ(ParseByteSize("64k"), 65536.0);
  EXPECT_DOUBLE_EQ(ParseByteSize("2GiB"), 2.0 * (1ull << 30));
  EXPECT_DOUBLE_EQ(ParseByteSize("3GB"), 3.0 * (1ull << 30));
  for (const char* bad : {"", "abc", "-1G", "8X", "G", "0", "nan", "inf", "8 G", "1e400"}) {
    try {
      ParseByteSize(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + bad + "'"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_EQ(FormatBytes(8.0 * (1ull << 30)), "8 GiB");
  EXPECT_EQ(FormatBytes(1536), "1.5 KiB");
  EXPECT_EQ(FormatBytes(57.14 * (1 << 20)), "57.1 MiB");
  EXPECT_EQ(FormatBytes(100), "100 B");
}

}  // namespace
}  // namespace sapmvs
