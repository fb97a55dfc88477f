#pragma once
// Reflective description of the project's IDL types, parsed from the .idl text with Cyclone
// DDS's IDL front end (libcycloneddsidl). Used where a program must handle a type it was not
// compiled against: the type lock file, `concert topic echo`, and contract tests that fill
// and compare every field of every type without per-type code.

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace concert::idl {

/// Raised for IDL that cannot be parsed or a type name the schema does not know.
class SchemaError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Kind {
  kBool, kOctet, kChar, kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kInt64, kUInt64,
  kFloat, kDouble, kString, kEnum, kStruct, kSequence, kArray
};

/// A type as it appears in a member declaration.
struct TypeRef {
  Kind kind = Kind::kInt32;
  uint32_t bound = 0;                ///< string/sequence bound (0 = unbounded); array length
  std::string name;                  ///< scoped name of a struct or enum, e.g. "concert::msg::Pose"
  std::shared_ptr<TypeRef> element;  ///< element type of a sequence or array
};

struct Field {
  std::string name;
  TypeRef type;
  bool key = false;
};

struct StructDef {
  std::string name;  ///< scoped name, e.g. "concert::msg::EscScan"
  std::vector<Field> fields;
  bool keyed() const;
};

struct EnumDef {
  std::string name;
  std::vector<std::pair<std::string, uint32_t>> enumerators;  ///< name, value
  const std::string* name_of(uint32_t value) const;
};

/// All structs and enums of a set of IDL files.
class Schema {
 public:
  /// Parses IDL text (several files may be concatenated; preprocessor lines are ignored, so
  /// files must be given in dependency order). `origin` names the text in error messages.
  static Schema parse(std::string_view idl_text, std::string_view origin = "<idl>");

  /// The schema of this project's idl/ folder, compiled into the program.
  static const Schema& builtin();

  const StructDef* find_struct(std::string_view name) const;
  const EnumDef* find_enum(std::string_view name) const;
  /// Like find_struct, but throws SchemaError naming the type when unknown.
  const StructDef& at(std::string_view name) const;

  std::vector<std::string> struct_names() const;

  /// Canonical one-line-per-field description of a struct and everything it uses, for the
  /// type lock file: changes to any field name, type, bound, key or enumerator change it.
  std::string shape(std::string_view struct_name) const;

  /// OMG IDL text defining `struct_name` and every struct and enum it uses, each before its
  /// first use, in their modules: what a program that has only this text needs to decode the
  /// type (the schema of a recorded topic in an MCAP file). Throws SchemaError for an unknown
  /// type or a shape IDL cannot spell without a typedef (a sequence of arrays).
  std::string idl(std::string_view struct_name) const;

  /// Text of a type reference, e.g. "sequence<concert::msg::EscSlave>" or "double[6]".
  static std::string spell(const TypeRef& type);

 private:
  std::map<std::string, StructDef, std::less<>> structs_;
  std::map<std::string, EnumDef, std::less<>> enums_;
};

}  // namespace concert::idl
