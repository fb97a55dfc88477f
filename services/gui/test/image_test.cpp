#include "gui/image.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <vector>

namespace concert::gui {
namespace {

TEST(Jpeg, ColourAndDepthImagesBecomeJpeg) {
  std::vector<uint8_t> rgb(64 * 48 * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7);
  std::string error;
  auto jpeg = encode_jpeg({"rgb8", 64, 48, 64 * 3, 0.0, rgb.data(), rgb.size()}, {}, error);
  ASSERT_TRUE(jpeg) << error;
  ASSERT_GT(jpeg->size(), 4u);
  EXPECT_EQ(static_cast<uint8_t>((*jpeg)[0]), 0xFF);
  EXPECT_EQ(static_cast<uint8_t>((*jpeg)[1]), 0xD8);
  std::vector<uint16_t> depth(64 * 48, 600);
  auto d = encode_jpeg({"16UC1", 64, 48, 128, 0.001, reinterpret_cast<const uint8_t*>(depth.data()), depth.size() * 2},
                       {}, error);
  ASSERT_TRUE(d) << error;
}

TEST(Jpeg, UnknownEncodingOrShortDataIsAnErrorNotACrash) {
  std::vector<uint8_t> data(10);
  std::string error;
  EXPECT_FALSE(encode_jpeg({"bgr16", 2, 2, 6, 0, data.data(), data.size()}, {}, error));
  EXPECT_THAT(error, testing::HasSubstr("bgr16"));
  EXPECT_FALSE(encode_jpeg({"rgb8", 64, 48, 192, 0, data.data(), data.size()}, {}, error));
  EXPECT_THAT(error, testing::HasSubstr("does not fit"));
}

}  // namespace
}  // namespace concert::gui
