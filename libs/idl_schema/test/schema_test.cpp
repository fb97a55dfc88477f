#include <gtest/gtest.h>

#include "concert/idl_schema/schema.hpp"

namespace concert::idl {
namespace {

TEST(Schema, BuiltinHasTheProjectTypesWithFieldsInOrder) {
  const auto& s = Schema::builtin();
  const auto& scan = s.at("concert::msg::EscScan");
  ASSERT_EQ(scan.fields.size(), 4u);
  EXPECT_EQ(scan.fields[0].name, "scan_id");
  EXPECT_EQ(scan.fields[3].name, "slaves");
  EXPECT_EQ(Schema::spell(scan.fields[3].type), "sequence<concert::msg::EscSlave>");
  EXPECT_EQ(s.at("concert::msg::EscSlave").fields[1].type.kind, Kind::kOctet);
  const auto& cart = s.at("concert::msg::CartesianImpedanceCommand");
  auto it = std::find_if(cart.fields.begin(), cart.fields.end(), [](const Field& f) { return f.name == "stiffness"; });
  ASSERT_NE(it, cart.fields.end());
  EXPECT_EQ(Schema::spell(it->type), "double[6]");
}

TEST(Schema, KeysAndEnums) {
  const auto& s = Schema::builtin();
  EXPECT_TRUE(s.at("concert::msg::ServiceStatus").fields[0].key);
  EXPECT_TRUE(s.at("concert::msg::ServiceStatus").keyed());
  EXPECT_FALSE(s.at("concert::msg::JointState").keyed());
  const auto* state = s.find_enum("concert::msg::ServiceState");
  ASSERT_NE(state, nullptr);
  ASSERT_NE(state->name_of(1), nullptr);
  EXPECT_EQ(*state->name_of(1), "SERVICE_READY");
  EXPECT_EQ(state->name_of(99), nullptr);
}

TEST(Schema, UnknownTypeIsNamed) {
  try {
    Schema::builtin().at("concert::msg::Nope");
    FAIL() << "expected SchemaError";
  } catch (const SchemaError& e) {
    EXPECT_NE(std::string(e.what()).find("concert::msg::Nope"), std::string::npos);
  }
}

TEST(Schema, BadIdlIsRejected) {
  EXPECT_THROW(Schema::parse("module m { struct S { long a } };", "bad.idl"), SchemaError);
}

TEST(Schema, ShapeChangesWithAnyFieldChange) {
  const char* base = "module m { enum E { A, B }; struct In { double x; }; struct S { @key long id; In in; E e; sequence<string<8>, 4> names; }; };";
  const auto a = Schema::parse(base).shape("m::S");
  EXPECT_NE(a.find("@key int32 id"), std::string::npos);
  EXPECT_NE(a.find("sequence<string<8>, 4> names"), std::string::npos);
  EXPECT_NE(a.find("struct m::In"), std::string::npos);
  EXPECT_NE(a.find("enum m::E { A=0 B=1 }"), std::string::npos);
  EXPECT_NE(Schema::parse("module m { enum E { A, B }; struct In { float x; }; struct S { @key long id; In in; E e; sequence<string<8>, 4> names; }; };").shape("m::S"), a);
  EXPECT_NE(Schema::parse("module m { enum E { A, B, C }; struct In { double x; }; struct S { @key long id; In in; E e; sequence<string<8>, 4> names; }; };").shape("m::S"), a);
  EXPECT_NE(Schema::parse("module m { enum E { A, B }; struct In { double x; }; struct S { long id; In in; E e; sequence<string<8>, 4> names; }; };").shape("m::S"), a);
}

TEST(Schema, IdlTextOfEveryTypeParsesBackToTheSameShape) {
  const auto& s = Schema::builtin();
  for (const auto& name : s.struct_names()) {
    const std::string text = s.idl(name);
    Schema back;
    ASSERT_NO_THROW(back = Schema::parse(text, name)) << text;
    EXPECT_EQ(back.shape(name), s.shape(name)) << text;
  }
}

TEST(Schema, IdlTextHasOnlyWhatTheTypeUsesInDependencyOrder) {
  const auto s = Schema::parse(
      "module m { enum E { A, B }; struct In { double x; }; struct Unused { long u; };"
      " module n { struct T { In a[2][3]; }; };"
      " struct S { @key long id; n::T t; E e; sequence<In, 4> ins; string<8> name; unsigned long long big; }; };");
  const std::string text = s.idl("m::S");
  EXPECT_EQ(text.find("Unused"), std::string::npos) << text;
  EXPECT_LT(text.find("struct In"), text.find("module n"));
  EXPECT_LT(text.find("module n"), text.find("struct S"));
  EXPECT_NE(text.find("m::In a[2][3];"), std::string::npos) << text;
  EXPECT_NE(text.find("@key long id;"), std::string::npos) << text;
  EXPECT_NE(text.find("n::T t;"), std::string::npos) << text;
  EXPECT_NE(text.find("enum E { A, B };"), std::string::npos) << text;
  EXPECT_NE(text.find("sequence<In, 4> ins;"), std::string::npos) << text;
  EXPECT_NE(text.find("unsigned long long big;"), std::string::npos) << text;
  EXPECT_EQ(Schema::parse(text).shape("m::S"), s.shape("m::S"));
}

}  // namespace
}  // namespace concert::idl
