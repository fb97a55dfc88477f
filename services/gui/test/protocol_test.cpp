#include "gui/protocol.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace concert::gui {
namespace {

using testing::HasSubstr;

std::string error_of(std::string_view text) {
  try {
    parse_client_message(text);
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "";
}

TEST(Protocol, ParsesEachOperation) {
  auto s = std::get<Subscribe>(parse_client_message(R"({"op":"subscribe","topic":"a/b","max_hz":5,"id":3})"));
  EXPECT_EQ(s.topic, "a/b");
  EXPECT_EQ(s.max_hz, 5.0);
  EXPECT_EQ(s.id, 3);
  auto u = std::get<Unsubscribe>(parse_client_message(R"({"op":"unsubscribe","topic":"a/b"})"));
  EXPECT_EQ(u.topic, "a/b");
  EXPECT_FALSE(u.id);
  auto p = std::get<Publish>(parse_client_message(R"({"op":"publish","topic":"t","data":{"x":1}})"));
  EXPECT_EQ(p.data["x"], 1);
  EXPECT_TRUE(std::holds_alternative<Ping>(parse_client_message(R"({"op":"ping"})")));
}

TEST(Protocol, BadMessagesAreRefusedSayingWhat) {
  EXPECT_THAT(error_of("{nope"), HasSubstr("not JSON"));
  EXPECT_THAT(error_of(R"({"op": "ping", "id": 1e400})"), HasSubstr("not JSON"));  // beyond double
  EXPECT_THAT(error_of("[1]"), HasSubstr("JSON object"));
  EXPECT_THAT(error_of(R"({"topic":"x"})"), HasSubstr("'op'"));
  EXPECT_THAT(error_of(R"({"op":"dance"})"), HasSubstr("unknown op 'dance'"));
  EXPECT_THAT(error_of(R"({"op":"subscribe"})"), HasSubstr("needs a 'topic'"));
  EXPECT_THAT(error_of(R"({"op":"subscribe","topic":""})"), HasSubstr("non-empty"));
  EXPECT_THAT(error_of(R"({"op":"subscribe","topic":"t","max_hz":-1})"), HasSubstr("max_hz"));
  EXPECT_THAT(error_of(R"({"op":"publish","topic":"t","data":3})"), HasSubstr("'data'"));
  EXPECT_THAT(error_of(R"({"op":"ping","id":"x"})"), HasSubstr("'id'"));
}

TEST(Protocol, MessagesAreJsonWithTheirFields) {
  const Json s = Json::parse(sample_message("t", "ab", {{"v", 2}}));
  EXPECT_EQ(s["op"], "sample");
  EXPECT_EQ(s["topic"], "t");
  EXPECT_EQ(s["instance"], "ab");
  EXPECT_EQ(s["data"]["v"], 2);
  const Json e = Json::parse(error_message("bad \xff byte", 4));
  EXPECT_EQ(e["id"], 4);
  EXPECT_THAT(e["error"].get<std::string>(), HasSubstr("bad"));
  const std::string f = frame_message({{"op", "frame"}}, std::string("\xff\xd8\x00", 3));
  ASSERT_NE(f.find('\n'), std::string::npos);
  EXPECT_EQ(Json::parse(f.substr(0, f.find('\n')))["op"], "frame");
  EXPECT_EQ(f.substr(f.find('\n') + 1), std::string("\xff\xd8\x00", 3));
}

}  // namespace
}  // namespace concert::gui
