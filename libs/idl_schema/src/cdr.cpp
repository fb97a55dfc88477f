#include "concert/idl_schema/cdr.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <random>

namespace concert::idl {
namespace {

// Hand-written rather than taken from Fast CDR or Cyclone: both serialize only their own
// generated types; here the type is known only at run time, from the schema.

size_t primitive_size(Kind kind) {
  switch (kind) {
    case Kind::kBool: case Kind::kOctet: case Kind::kChar: case Kind::kInt8: case Kind::kUInt8: return 1;
    case Kind::kInt16: case Kind::kUInt16: return 2;
    case Kind::kInt32: case Kind::kUInt32: case Kind::kFloat: case Kind::kEnum: return 4;
    case Kind::kInt64: case Kind::kUInt64: case Kind::kDouble: return 8;
    default: return 0;
  }
}

class Writer {
 public:
  explicit Writer(const Schema& schema) : schema_(schema) { out_ = {0x00, 0x01, 0x00, 0x00}; }

  std::vector<uint8_t> finish() { return std::move(out_); }

  void value(const TypeRef& type, const Json& v, const std::string& path) {
    switch (type.kind) {
      case Kind::kStruct: structure(schema_.at(type.name), v, path); return;
      case Kind::kString: {
        if (!v.is_string()) fail(path, "expected a string");
        const auto& s = v.get_ref<const std::string&>();
        if (type.bound && s.size() > type.bound) fail(path, "string longer than its bound " + std::to_string(type.bound));
        put<uint32_t>(static_cast<uint32_t>(s.size() + 1));
        out_.insert(out_.end(), s.begin(), s.end());
        out_.push_back(0);
        return;
      }
      case Kind::kSequence: case Kind::kArray: {
        if (!v.is_array()) fail(path, "expected an array");
        if (type.kind == Kind::kArray && v.size() != type.bound) {
          fail(path, "expected " + std::to_string(type.bound) + " elements, got " + std::to_string(v.size()));
        }
        if (type.kind == Kind::kSequence) {
          if (type.bound && v.size() > type.bound) fail(path, "sequence longer than its bound");
          put<uint32_t>(static_cast<uint32_t>(v.size()));
        }
        for (size_t i = 0; i < v.size(); ++i) value(*type.element, v[i], path + "[" + std::to_string(i) + "]");
        return;
      }
      case Kind::kEnum: {
        const auto* en = schema_.find_enum(type.name);
        if (en == nullptr) fail(path, "unknown enum " + type.name);
        // By name or by value; either must be an enumerator (a reader refuses any other value).
        for (const auto& [name, val] : en->enumerators) {
          if ((v.is_string() && name == v.get_ref<const std::string&>()) ||
              (v.is_number_unsigned() && v.get<uint64_t>() == val) ||
              (v.is_number_integer() && v.get<int64_t>() == static_cast<int64_t>(val))) {
            put<uint32_t>(val);
            return;
          }
        }
        fail(path, "not an enumerator of " + type.name + ": " + v.dump());
      }
      case Kind::kBool:
        if (!v.is_boolean()) fail(path, "expected true or false");
        put<uint8_t>(v.get<bool>() ? 1 : 0);
        return;
      case Kind::kChar: {
        if (!v.is_string() || v.get_ref<const std::string&>().size() != 1) fail(path, "expected a one-character string");
        put<char>(v.get_ref<const std::string&>()[0]);
        return;
      }
      case Kind::kFloat: number<float>(v, path); return;
      case Kind::kDouble: number<double>(v, path); return;
      case Kind::kOctet: case Kind::kUInt8: integer<uint8_t>(v, path); return;
      case Kind::kInt8: integer<int8_t>(v, path); return;
      case Kind::kInt16: integer<int16_t>(v, path); return;
      case Kind::kUInt16: integer<uint16_t>(v, path); return;
      case Kind::kInt32: integer<int32_t>(v, path); return;
      case Kind::kUInt32: integer<uint32_t>(v, path); return;
      case Kind::kInt64: integer<int64_t>(v, path); return;
      case Kind::kUInt64: integer<uint64_t>(v, path); return;
    }
  }

  void structure(const StructDef& def, const Json& v, const std::string& path) {
    if (!v.is_object()) fail(path, "expected an object of type " + def.name);
    for (const auto& f : def.fields) {
      const std::string sub = path.empty() ? f.name : path + "." + f.name;
      auto it = v.find(f.name);
      if (it == v.end()) fail(sub, "missing");
      value(f.type, *it, sub);
    }
  }

 private:
  [[noreturn]] static void fail(const std::string& path, const std::string& what) {
    throw CdrError((path.empty() ? std::string("sample") : path) + ": " + what);
  }
  template <class T> void put(T v) {
    const size_t body = out_.size() - 4;
    out_.resize(out_.size() + (sizeof(T) - body % sizeof(T)) % sizeof(T), 0);
    uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(raw, raw + sizeof(T));
    out_.insert(out_.end(), raw, raw + sizeof(T));
  }
  template <class T> void integer(const Json& v, const std::string& path) {
    if (!v.is_number_integer()) fail(path, "expected an integer");
    if (v.is_number_unsigned()) {
      const auto u = v.get<uint64_t>();
      if (u > static_cast<uint64_t>(std::numeric_limits<T>::max())) fail(path, "out of range: " + v.dump());
      put<T>(static_cast<T>(u));
    } else {
      const auto s = v.get<int64_t>();
      if (s < static_cast<int64_t>(std::numeric_limits<T>::min()) ||
          (s > 0 && static_cast<uint64_t>(s) > static_cast<uint64_t>(std::numeric_limits<T>::max()))) {
        fail(path, "out of range: " + v.dump());
      }
      put<T>(static_cast<T>(s));
    }
  }
  template <class T> void number(const Json& v, const std::string& path) {
    if (!v.is_number()) fail(path, "expected a number");
    put<T>(v.get<T>());
  }

  const Schema& schema_;
  std::vector<uint8_t> out_;
};

class Reader {
 public:
  Reader(const Schema& schema, std::span<const uint8_t> bytes) : schema_(schema), bytes_(bytes) {
    if (bytes.size() < 4) throw CdrError("payload of " + std::to_string(bytes.size()) + " bytes has no encapsulation header");
    const unsigned id = (unsigned{bytes[0]} << 8) | bytes[1];
    switch (id) {
      case 0x0000: little_ = false; max_align_ = 8; break;  // CDR_BE (XCDR1)
      case 0x0001: little_ = true; max_align_ = 8; break;   // CDR_LE (XCDR1)
      case 0x0006: little_ = false; max_align_ = 4; break;  // CDR2_BE (plain XCDR2, final types)
      case 0x0007: little_ = true; max_align_ = 4; break;   // CDR2_LE
      default: throw CdrError("unsupported encapsulation 0x" + hex(id) + " (only plain CDR of final types is decoded)");
    }
    pos_ = 4;
  }

  Json value(const TypeRef& type, const std::string& path) {
    switch (type.kind) {
      case Kind::kStruct: return structure(schema_.at(type.name), path);
      case Kind::kString: {
        const auto n = get<uint32_t>(path);
        need(n, path);
        std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
        pos_ += n;
        if (n > 0) {
          if (s.back() != '\0') fail(path, "string is not NUL-terminated");
          s.pop_back();
        }
        // JSON text is Unicode: a string that is not valid UTF-8 cannot be shown (the JSON
        // library's serialiser, which would throw later, checks it here).
        try {
          (void)Json(s).dump();
        } catch (const Json::type_error& e) {
          fail(path, std::string("string is not valid UTF-8: ") + e.what());
        }
        return s;
      }
      case Kind::kSequence: case Kind::kArray: {
        const uint32_t n = type.kind == Kind::kArray ? type.bound : get<uint32_t>(path);
        if (type.kind == Kind::kSequence && n > bytes_.size() - pos_ && primitive_size(type.element->kind) > 0) {
          fail(path, "sequence length " + std::to_string(n) + " exceeds the payload");
        }
        Json arr = Json::array();
        for (uint32_t i = 0; i < n; ++i) arr.push_back(value(*type.element, path + "[" + std::to_string(i) + "]"));
        return arr;
      }
      case Kind::kEnum: {
        const auto v = get<uint32_t>(path);
        const auto* en = schema_.find_enum(type.name);
        const std::string* name = en ? en->name_of(v) : nullptr;
        if (name == nullptr) fail(path, "value " + std::to_string(v) + " is no enumerator of " + type.name);
        return *name;
      }
      case Kind::kBool: return get<uint8_t>(path) != 0;
      case Kind::kChar: return std::string(1, get<char>(path));
      case Kind::kFloat: return get<float>(path);
      case Kind::kDouble: return get<double>(path);
      case Kind::kOctet: case Kind::kUInt8: return get<uint8_t>(path);
      case Kind::kInt8: return get<int8_t>(path);
      case Kind::kInt16: return get<int16_t>(path);
      case Kind::kUInt16: return get<uint16_t>(path);
      case Kind::kInt32: return get<int32_t>(path);
      case Kind::kUInt32: return get<uint32_t>(path);
      case Kind::kInt64: return get<int64_t>(path);
      case Kind::kUInt64: return get<uint64_t>(path);
    }
    return nullptr;
  }

  Json structure(const StructDef& def, const std::string& path) {
    Json obj = Json::object();
    for (const auto& f : def.fields) obj[f.name] = value(f.type, path.empty() ? f.name : path + "." + f.name);
    return obj;
  }

  void finish() const {
    // Writers may pad the payload to a multiple of 4 bytes.
    if (bytes_.size() - pos_ > 3) {
      throw CdrError(std::to_string(bytes_.size() - pos_) + " bytes left over after the sample: wrong type?");
    }
  }

 private:
  static std::string hex(unsigned v) {
    static const char* digits = "0123456789abcdef";
    std::string s(4, '0');
    for (int i = 3; i >= 0; --i, v >>= 4) s[static_cast<size_t>(i)] = digits[v & 0xf];
    return s;
  }
  [[noreturn]] static void fail(const std::string& path, const std::string& what) {
    throw CdrError((path.empty() ? std::string("sample") : path) + ": " + what);
  }
  void need(size_t n, const std::string& path) const {
    if (bytes_.size() - pos_ < n) fail(path, "payload ends early (truncated or wrong type)");
  }
  template <class T> T get(const std::string& path) {
    const size_t align = std::min(sizeof(T), max_align_);
    const size_t body = pos_ - 4;
    const size_t pad = (align - body % align) % align;
    need(pad + sizeof(T), path);
    pos_ += pad;
    uint8_t raw[sizeof(T)];
    std::memcpy(raw, bytes_.data() + pos_, sizeof(T));
    if (little_ != (std::endian::native == std::endian::little)) std::reverse(raw, raw + sizeof(T));
    pos_ += sizeof(T);
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return v;
  }

  const Schema& schema_;
  std::span<const uint8_t> bytes_;
  size_t pos_ = 0;
  bool little_ = true;
  size_t max_align_ = 8;
};

class Filler {
 public:
  Filler(const Schema& schema, uint32_t seed) : schema_(schema), rng_(seed) {}

  Json value(const TypeRef& type, const std::string& path) {
    switch (type.kind) {
      case Kind::kStruct: {
        const auto& def = schema_.at(type.name);
        Json obj = Json::object();
        for (const auto& f : def.fields) obj[f.name] = value(f.type, path + "." + f.name);
        return obj;
      }
      case Kind::kString: {
        std::string s = path.substr(1) + "#" + std::to_string(pick(1, 999));
        if (type.bound && s.size() > type.bound) s.resize(type.bound);
        return s;
      }
      case Kind::kSequence: case Kind::kArray: {
        uint32_t n = type.kind == Kind::kArray ? type.bound : static_cast<uint32_t>(pick(2, 3));
        if (type.kind == Kind::kSequence && type.bound) n = std::min(n, type.bound);
        Json arr = Json::array();
        for (uint32_t i = 0; i < n; ++i) arr.push_back(value(*type.element, path + "[" + std::to_string(i) + "]"));
        return arr;
      }
      case Kind::kEnum: {
        const auto* en = schema_.find_enum(type.name);
        const auto n = en->enumerators.size();
        // Prefer a non-default enumerator, so that a field left at its default shows.
        return en->enumerators[n > 1 ? static_cast<size_t>(pick(1, static_cast<int>(n) - 1)) : 0].first;
      }
      case Kind::kBool: return true;
      case Kind::kChar: return std::string(1, static_cast<char>('a' + pick(0, 25)));
      // Multiples of 1/8 are exact in binary, so equality checks are meaningful.
      case Kind::kFloat: return static_cast<float>(pick(1, 4000)) / 8.0f;
      case Kind::kDouble: return static_cast<double>(pick(1, 2'000'000) - 1'000'001) / 8.0 + (pick(0, 1) ? 0.0 : 0.5);
      case Kind::kOctet: case Kind::kUInt8: return pick(1, 254);
      case Kind::kInt8: return pick(-120, -1);
      case Kind::kInt16: return pick(-30000, -1);
      case Kind::kUInt16: return pick(1, 60000);
      case Kind::kInt32: return pick(-2'000'000, 2'000'000) | 1;
      case Kind::kUInt32: return static_cast<uint32_t>(pick(1, 2'000'000'000)) * 2u;
      case Kind::kInt64: return static_cast<int64_t>(pick(1, 2'000'000'000)) * 1'000'003LL;
      case Kind::kUInt64: return static_cast<uint64_t>(pick(1, 2'000'000'000)) * 4'000'037ULL;
    }
    return nullptr;
  }

 private:
  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  const Schema& schema_;
  std::mt19937 rng_;
};

}  // namespace

std::vector<uint8_t> encode(const Schema& schema, std::string_view type, const Json& value) {
  Writer w(schema);
  w.structure(schema.at(type), value, "");
  return w.finish();
}

Json decode(const Schema& schema, std::string_view type, std::span<const uint8_t> bytes) {
  Reader r(schema, bytes);
  Json out = r.structure(schema.at(type), "");
  r.finish();
  return out;
}

std::string representation(std::span<const uint8_t> bytes) {
  if (bytes.size() < 4) return "none (payload shorter than its header)";
  switch ((unsigned{bytes[0]} << 8) | bytes[1]) {
    case 0x0000: return "XCDR1 big-endian";
    case 0x0001: return "XCDR1 little-endian";
    case 0x0002: return "XCDR1 parameter-list big-endian";
    case 0x0003: return "XCDR1 parameter-list little-endian";
    case 0x0006: return "XCDR2 big-endian";
    case 0x0007: return "XCDR2 little-endian";
    default: return "unknown";
  }
}

namespace {

Json default_value(const Schema& schema, const TypeRef& type) {
  switch (type.kind) {
    case Kind::kStruct: {
      Json out = Json::object();
      for (const auto& f : schema.at(type.name).fields) out[f.name] = default_value(schema, f.type);
      return out;
    }
    case Kind::kString:
      return "";
    case Kind::kSequence:
      return Json::array();
    case Kind::kArray: {
      Json out = Json::array();
      for (uint32_t i = 0; i < type.bound; ++i) out.push_back(default_value(schema, *type.element));
      return out;
    }
    case Kind::kEnum: {
      const auto* en = schema.find_enum(type.name);
      if (en == nullptr || en->enumerators.empty()) return 0;
      return en->enumerators.front().first;
    }
    case Kind::kBool:
      return false;
    case Kind::kChar:
      return std::string(1, '\0');
    case Kind::kFloat:
    case Kind::kDouble:
      return 0.0;
    default:
      return 0;
  }
}

Json complete_value(const Schema& schema, const TypeRef& type, const Json& v,
                    const std::string& path) {
  if (type.kind == Kind::kStruct) {
    const StructDef& def = schema.at(type.name);
    const std::string where = path.empty() ? std::string("sample") : path;
    if (!v.is_object())
      throw CdrError(where + ": expected an object of type " + def.name + ", got " + v.dump());
    for (const auto& [name, value] : v.items()) {
      const bool known = std::any_of(def.fields.begin(), def.fields.end(),
                                     [&](const Field& f) { return f.name == name; });
      if (!known) {
        std::string fields;
        for (const auto& f : def.fields) fields += (fields.empty() ? "" : ", ") + f.name;
        throw CdrError((path.empty() ? name : path + "." + name) + ": no such field in " +
                       def.name + " (fields: " + fields + ")");
      }
    }
    Json out = Json::object();
    for (const auto& f : def.fields) {
      const auto it = v.find(f.name);
      out[f.name] = it == v.end() ? default_value(schema, f.type)
                                  : complete_value(schema, f.type, *it,
                                                   path.empty() ? f.name : path + "." + f.name);
    }
    return out;
  }
  if ((type.kind == Kind::kSequence || type.kind == Kind::kArray) && v.is_array() &&
      type.element->kind == Kind::kStruct) {
    Json out = Json::array();
    for (size_t i = 0; i < v.size(); ++i) {
      out.push_back(
          complete_value(schema, *type.element, v[i], path + "[" + std::to_string(i) + "]"));
    }
    return out;
  }
  return v;  // checked by encode()
}

/// Appends the key fields of `def` in `v` as big-endian CDR; false if a key can exceed 16 bytes.
bool put_key(const Schema& schema, const StructDef& def, const Json& v, bool all_fields,
             std::vector<uint8_t>& out) {
  for (const auto& f : def.fields) {
    if (!all_fields && !f.key) continue;
    const Json& fv = v.at(f.name);
    if (f.type.kind == Kind::kStruct) {
      if (!put_key(schema, schema.at(f.type.name), fv, true, out)) return false;
      continue;
    }
    const size_t size = primitive_size(f.type.kind);
    if (size == 0) return false;  // strings, sequences, arrays: not a short key
    uint64_t bits = 0;
    if (f.type.kind == Kind::kEnum) {
      if (fv.is_string()) {
        for (const auto& [name, value] : schema.find_enum(f.type.name)->enumerators) {
          if (name == fv.get_ref<const std::string&>()) bits = value;
        }
      } else {
        bits = fv.get<uint32_t>();
      }
    } else if (f.type.kind == Kind::kFloat) {
      bits = std::bit_cast<uint32_t>(fv.get<float>());
    } else if (f.type.kind == Kind::kDouble) {
      bits = std::bit_cast<uint64_t>(fv.get<double>());
    } else if (f.type.kind == Kind::kBool) {
      bits = fv.get<bool>() ? 1 : 0;
    } else {
      bits =
          fv.is_number_unsigned() ? fv.get<uint64_t>() : static_cast<uint64_t>(fv.get<int64_t>());
    }
    out.resize(out.size() + (size - out.size() % size) % size, 0);
    for (size_t i = 0; i < size; ++i)
      out.push_back(static_cast<uint8_t>(bits >> (8 * (size - 1 - i))));
    if (out.size() > 16) return false;
  }
  return true;
}

}  // namespace

Json complete(const Schema& schema, std::string_view type, const Json& partial) {
  TypeRef ref;
  ref.kind = Kind::kStruct;
  ref.name = std::string(type);
  return complete_value(schema, ref, partial, "");
}

std::optional<std::array<uint8_t, 16>> key_hash(const Schema& schema, std::string_view type,
                                                const Json& sample) {
  const StructDef& def = schema.at(type);
  if (!def.keyed()) return std::nullopt;
  std::vector<uint8_t> bytes;
  if (!put_key(schema, def, sample, false, bytes)) return std::nullopt;
  std::array<uint8_t, 16> hash{};
  std::copy(bytes.begin(), bytes.end(), hash.begin());
  return hash;
}

std::optional<std::array<uint8_t, 16>> key_hash_of_cdr(const Schema& schema, std::string_view type,
                                                       std::span<const uint8_t> bytes) {
  const StructDef& def = schema.at(type);
  if (!def.keyed()) return std::nullopt;
  size_t last_key = 0;
  for (size_t i = 0; i < def.fields.size(); ++i) {
    if (def.fields[i].key) last_key = i;
  }
  Reader reader(schema, bytes);
  Json prefix = Json::object();
  for (size_t i = 0; i <= last_key; ++i) {
    const Field& f = def.fields[i];
    prefix[f.name] = reader.value(f.type, f.name);
  }
  return key_hash(schema, type, prefix);
}

Json sample_with_every_field_set(const Schema& schema, std::string_view type, uint32_t seed) {
  TypeRef ref;
  ref.kind = Kind::kStruct;
  ref.name = std::string(type);
  return Filler(schema, seed).value(ref, "");
}

}  // namespace concert::idl
