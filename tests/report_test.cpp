// Report helpers: --vary parsing and study tables.
#include "trochomill/report.hpp"

#include <gtest/gtest.h>

#include "trochomill/error.hpp"

namespace trochomill {
namespace {

TEST(Report, ParseVary) {
  const Vary v = parse_vary("path.aspect_ratio=0.5, 0.6 ,0.7");
  EXPECT_EQ(v.key, "path.aspect_ratio");
  ASSERT_EQ(v.values.size(), 3u);
  EXPECT_EQ(v.values[1], "0.6");
  const Vary t = parse_vary("tool.tooth_angles=[0, 90, 180, 270],[0, 95, 180, 275]");
  ASSERT_EQ(t.values.size(), 2u);
  EXPECT_EQ(t.values[1], "[0, 95, 180, 275]");
  const Vary q = parse_vary(R"(path.type="elliptical","linear-elliptical")");
  ASSERT_EQ(q.values.size(), 2u);
  EXPECT_THROW((void)parse_vary("path.step"), InputError);
  EXPECT_THROW((void)parse_vary("step=1,2"), InputError);
  EXPECT_THROW((void)parse_vary("path.step=1,,2"), InputError);
}

}  // namespace
}  // namespace trochomill
