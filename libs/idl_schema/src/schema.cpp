#include "concert/idl_schema/schema.hpp"

#include <algorithm>
#include <functional>
#include <set>
#include <sstream>

#include "idl_walk.h"

namespace concert::idl {
namespace {

const std::map<std::string, Kind, std::less<>>& base_kinds() {
  static const std::map<std::string, Kind, std::less<>> kinds = {
      {"bool", Kind::kBool},     {"octet", Kind::kOctet},   {"char", Kind::kChar},     {"int8", Kind::kInt8},
      {"uint8", Kind::kUInt8},   {"int16", Kind::kInt16},   {"uint16", Kind::kUInt16}, {"int32", Kind::kInt32},
      {"uint32", Kind::kUInt32}, {"int64", Kind::kInt64},   {"uint64", Kind::kUInt64}, {"float", Kind::kFloat},
      {"double", Kind::kDouble}};
  return kinds;
}

// Reads the token form of idl_walk.h.
TypeRef read_type(std::istringstream& in) {
  std::string tag;
  in >> tag;
  TypeRef ref;
  if (tag == "seq") {
    ref.kind = Kind::kSequence;
    in >> ref.bound;
    ref.element = std::make_shared<TypeRef>(read_type(in));
  } else if (tag == "string") {
    ref.kind = Kind::kString;
    in >> ref.bound;
  } else if (tag == "struct" || tag == "enum") {
    ref.kind = tag == "struct" ? Kind::kStruct : Kind::kEnum;
    in >> ref.name;
  } else {
    std::string base;
    in >> base;
    ref.kind = base_kinds().at(base);
  }
  return ref;
}

struct Collector {
  std::map<std::string, StructDef, std::less<>>* structs;
  std::map<std::string, EnumDef, std::less<>>* enums;
  StructDef* current = nullptr;
};

}  // namespace

bool StructDef::keyed() const {
  return std::any_of(fields.begin(), fields.end(), [](const Field& f) { return f.key; });
}

const std::string* EnumDef::name_of(uint32_t value) const {
  for (const auto& [enumerator, v] : enumerators) {
    if (v == value) return &enumerator;
  }
  return nullptr;
}

Schema Schema::parse(std::string_view idl_text, std::string_view origin) {
  // libidl expects preprocessed input; our files use only include guards and #include of
  // each other, and are concatenated in dependency order, so directive lines are dropped.
  std::string text;
  std::istringstream in{std::string(idl_text)};
  for (std::string line; std::getline(in, line);) {
    const auto first = line.find_first_not_of(" \t");
    text += (first != std::string::npos && line[first] == '#') ? "" : line;
    text += '\n';
  }

  Schema schema;
  Collector collector{&schema.structs_, &schema.enums_};
  concert_idl_visitor visitor{};
  visitor.ctx = &collector;
  visitor.begin_struct = [](void* ctx, const char* name) {
    auto* c = static_cast<Collector*>(ctx);
    c->current = &(*c->structs)[name];
    c->current->name = name;
  };
  visitor.field = [](void* ctx, const char* name, int key, const char* type, const uint32_t* dims, size_t ndims) {
    auto* c = static_cast<Collector*>(ctx);
    Field field;
    field.name = name;
    field.key = key != 0;
    std::istringstream tokens{std::string(type)};
    field.type = read_type(tokens);
    for (size_t i = ndims; i > 0; --i) {  // wrap from the innermost dimension
      TypeRef array;
      array.kind = Kind::kArray;
      array.bound = dims[i - 1];
      array.element = std::make_shared<TypeRef>(field.type);
      field.type = array;
    }
    c->current->fields.push_back(std::move(field));
  };
  visitor.enumerator = [](void* ctx, const char* enum_name, const char* name, uint32_t value) {
    auto& en = (*static_cast<Collector*>(ctx)->enums)[enum_name];
    en.name = enum_name;
    en.enumerators.emplace_back(name, value);
  };
  char error[512] = "";
  if (concert_idl_walk(text.c_str(), &visitor, error, sizeof error) != 0) {
    throw SchemaError(std::string(origin) + ": " + error);
  }
  return schema;
}

const StructDef* Schema::find_struct(std::string_view name) const {
  auto it = structs_.find(name);
  return it == structs_.end() ? nullptr : &it->second;
}

const EnumDef* Schema::find_enum(std::string_view name) const {
  auto it = enums_.find(name);
  return it == enums_.end() ? nullptr : &it->second;
}

const StructDef& Schema::at(std::string_view name) const {
  if (const auto* s = find_struct(name)) return *s;
  throw SchemaError("unknown type '" + std::string(name) + "' (not in the project's IDL)");
}

std::vector<std::string> Schema::struct_names() const {
  std::vector<std::string> names;
  for (const auto& [name, def] : structs_) names.push_back(name);
  return names;
}

std::string Schema::spell(const TypeRef& type) {
  switch (type.kind) {
    case Kind::kBool: return "boolean";
    case Kind::kOctet: return "octet";
    case Kind::kChar: return "char";
    case Kind::kInt8: return "int8";
    case Kind::kUInt8: return "uint8";
    case Kind::kInt16: return "int16";
    case Kind::kUInt16: return "uint16";
    case Kind::kInt32: return "int32";
    case Kind::kUInt32: return "uint32";
    case Kind::kInt64: return "int64";
    case Kind::kUInt64: return "uint64";
    case Kind::kFloat: return "float";
    case Kind::kDouble: return "double";
    case Kind::kString: return type.bound ? "string<" + std::to_string(type.bound) + ">" : "string";
    case Kind::kEnum: return "enum " + type.name;
    case Kind::kStruct: return type.name;
    case Kind::kSequence:
      return "sequence<" + spell(*type.element) + (type.bound ? ", " + std::to_string(type.bound) : "") + ">";
    case Kind::kArray: return spell(*type.element) + "[" + std::to_string(type.bound) + "]";
  }
  return "?";
}

std::string Schema::shape(std::string_view struct_name) const {
  std::ostringstream out;
  std::set<std::string> done;
  std::vector<std::string> todo{std::string(struct_name)};
  at(struct_name);
  while (!todo.empty()) {
    const std::string name = todo.front();
    todo.erase(todo.begin());
    if (!done.insert(name).second) continue;
    if (const auto* en = find_enum(name)) {
      out << "enum " << name << " {";
      for (const auto& [e, v] : en->enumerators) out << " " << e << "=" << v;
      out << " }\n";
      continue;
    }
    const auto& def = at(name);
    out << "struct " << name << " {\n";
    for (const auto& f : def.fields) {
      out << "  " << (f.key ? "@key " : "") << spell(f.type) << " " << f.name << "\n";
      const TypeRef* t = &f.type;
      while (t->kind == Kind::kSequence || t->kind == Kind::kArray) t = t->element.get();
      if (t->kind == Kind::kStruct || t->kind == Kind::kEnum) todo.push_back(t->name);
    }
    out << "}\n";
  }
  return out.str();
}

}  // namespace concert::idl

namespace concert::idl {
namespace {

/// "concert::msg::Pose" -> {"concert", "msg"}, "Pose".
std::pair<std::vector<std::string>, std::string> split_scoped(const std::string& name) {
  std::vector<std::string> modules;
  size_t start = 0;
  for (size_t at = name.find("::"); at != std::string::npos; at = name.find("::", start)) {
    modules.push_back(name.substr(start, at - start));
    start = at + 2;
  }
  return {modules, name.substr(start)};
}

/// A type as IDL spells it in a declaration inside module `scope` (arrays excluded: their
/// dimensions follow the member name).
std::string idl_spelling(const TypeRef& type, const std::vector<std::string>& scope) {
  switch (type.kind) {
    case Kind::kBool:
      return "boolean";
    case Kind::kInt16:
      return "short";
    case Kind::kUInt16:
      return "unsigned short";
    case Kind::kInt32:
      return "long";
    case Kind::kUInt32:
      return "unsigned long";
    case Kind::kInt64:
      return "long long";
    case Kind::kUInt64:
      return "unsigned long long";
    case Kind::kStruct:
    case Kind::kEnum: {
      auto [modules, local] = split_scoped(type.name);
      return modules == scope ? local : type.name;
    }
    case Kind::kSequence:
      if (type.element->kind == Kind::kArray) {
        throw SchemaError(
            "a sequence of arrays needs a typedef, which the IDL text does not write");
      }
      return "sequence<" + idl_spelling(*type.element, scope) +
             (type.bound ? ", " + std::to_string(type.bound) : "") + ">";
    case Kind::kArray:
      throw SchemaError("arrays are spelled at the member");
    default:
      return Schema::spell(type);  // octet, char, int8, uint8, float, double, string
  }
}

}  // namespace

std::string Schema::idl(std::string_view struct_name) const {
  // Depth first, each definition after those it uses.
  std::vector<std::string> order;
  std::set<std::string> seen;
  std::function<void(const std::string&)> visit = [&](const std::string& name) {
    if (!seen.insert(name).second) return;
    if (find_enum(name) == nullptr) {
      for (const auto& f : at(name).fields) {
        const TypeRef* t = &f.type;
        while (t->kind == Kind::kSequence || t->kind == Kind::kArray) t = t->element.get();
        if (t->kind == Kind::kStruct || t->kind == Kind::kEnum) visit(t->name);
      }
    }
    order.push_back(name);
  };
  visit(std::string(struct_name));

  std::ostringstream out;
  out << "// " << struct_name << " and the types it uses (generated from the CONCERT IDL)\n";
  std::vector<std::string> open;  // modules currently open
  auto indent = [&] { return std::string(2 * open.size(), ' '); };
  for (const std::string& name : order) {
    auto [modules, local] = split_scoped(name);
    size_t common = 0;
    while (common < open.size() && common < modules.size() && open[common] == modules[common])
      ++common;
    while (open.size() > common) {
      open.pop_back();
      out << indent() << "};\n";
    }
    while (open.size() < modules.size()) {
      out << indent() << "module " << modules[open.size()] << " {\n";
      open.push_back(modules[open.size()]);
    }
    if (const auto* en = find_enum(name)) {
      out << indent() << "enum " << local << " {";
      for (size_t i = 0; i < en->enumerators.size(); ++i) {
        const auto& [e, v] = en->enumerators[i];
        out << (i ? ", " : " ") << (v == i ? "" : "@value(" + std::to_string(v) + ") ") << e;
      }
      out << " };\n";
      continue;
    }
    out << indent() << "struct " << local << " {\n";
    for (const auto& f : at(name).fields) {
      const TypeRef* t = &f.type;
      std::string dims;
      while (t->kind == Kind::kArray) {
        dims += "[" + std::to_string(t->bound) + "]";
        t = t->element.get();
      }
      out << indent() << "  " << (f.key ? "@key " : "") << idl_spelling(*t, modules) << " "
          << f.name << dims << ";\n";
    }
    out << indent() << "};\n";
  }
  while (!open.empty()) {
    open.pop_back();
    out << indent() << "};\n";
  }
  return out.str();
}

}  // namespace concert::idl
