#include "concert/bim/model.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

extern char** environ;

namespace concert::bim {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

constexpr std::array<std::pair<Category, const char*>, 13> kCategoryNames{{
    {Category::kWall, "wall"},
    {Category::kDoor, "door"},
    {Category::kWindow, "window"},
    {Category::kColumn, "column"},
    {Category::kSlab, "slab"},
    {Category::kStair, "stair"},
    {Category::kRailing, "railing"},
    {Category::kCovering, "covering"},
    {Category::kFurnishing, "furnishing"},
    {Category::kBeam, "beam"},
    {Category::kMember, "member"},
    {Category::kRoof, "roof"},
    {Category::kProxy, "proxy"},
}};

/// A fresh folder below the system's temporary folder, removed with its content when this goes.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "concert-bim-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) {
      throw BimError("cannot create a temporary folder in " + fs::temp_directory_path().string() +
                     ": " + std::strerror(errno));
    }
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string trimmed(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  return s;
}

/// Runs argv (argv[0] looked up in PATH) with stdout to /dev/null and stderr to `err_file`;
/// returns the exit status as waitpid gives it.
int run_child(const std::vector<std::string>& argv, const fs::path& err_file) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> args;
  std::vector<std::string> copy = argv;
  for (auto& a : copy) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    throw BimError("cannot run the IFC import step '" + argv[0] + "': " + std::strerror(rc) +
                   " (install Node.js: deploy/install-deps.sh)");
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR)
      throw BimError(std::string("waiting for the IFC import step: ") + std::strerror(errno));
  }
  return status;
}

template <class T>
T field(const Json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) throw BimError(where + ": missing field '" + key + "'");
  try {
    return j.at(key).get<T>();
  } catch (const Json::exception& e) {
    throw BimError(where + ": field '" + key + "': " + e.what());
  }
}

/// A count or offset: a non-negative integer (a float or a negative number converted to size_t
/// is undefined or wraps round).
std::size_t count_field(const Json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) throw BimError(where + ": missing field '" + key + "'");
  const Json& v = j.at(key);
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0)) {
    throw BimError(where + ": field '" + key + "': expected a non-negative integer, got " +
                   v.dump());
  }
  return v.get<std::size_t>();
}

Eigen::Vector3d vec3(const Json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw BimError(where + ": expected 3 numbers");
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

}  // namespace

std::string to_string(Category category) {
  for (const auto& [c, name] : kCategoryNames) {
    if (c == category) return name;
  }
  return "unknown";
}

Category category_from_string(const std::string& name) {
  std::string known;
  for (const auto& [c, n] : kCategoryNames) {
    if (name == n) return c;
    known += (known.empty() ? "" : ", ") + std::string(n);
  }
  throw BimError("unknown element category '" + name + "' (known: " + known + ")");
}

bool is_obstacle(Category category) {
  return category != Category::kDoor && category != Category::kSlab &&
         category != Category::kCovering;
}

const Storey& BimModel::storey(const std::string& name_or_id) const {
  for (const auto& s : storeys) {
    if (s.name == name_or_id) return s;
  }
  for (const auto& s : storeys) {
    if (s.global_id == name_or_id) return s;
  }
  std::string names;
  for (const auto& s : storeys) names += (names.empty() ? "" : ", ") + s.name;
  throw BimError("storey '" + name_or_id + "' not found in " + source +
                 "; storeys: " + (names.empty() ? "none" : names));
}

const Element& BimModel::element(const std::string& global_id) const {
  for (const auto& e : elements) {
    if (e.global_id == global_id) return e;
  }
  throw BimError("no element with GlobalId '" + global_id + "' in " + source);
}

std::vector<const Element*> BimModel::elements_of(const Storey& storey) const {
  std::vector<const Element*> out;
  for (const auto& e : elements) {
    if (e.storey == storey.global_id) out.push_back(&e);
  }
  return out;
}

double BimModel::storey_height(const Storey& storey, double fallback) const {
  double next = std::numeric_limits<double>::infinity();
  for (const auto& s : storeys) {
    if (s.elevation > storey.elevation + 1e-6) next = std::min(next, s.elevation);
  }
  return std::isfinite(next) ? next - storey.elevation : fallback;
}

std::string default_import_script() {
  if (const char* env = std::getenv("CONCERT_IFC_IMPORT"); env != nullptr && *env != '\0')
    return env;
  return CONCERT_IFC_IMPORT_SCRIPT;
}

namespace {

BimModel read_import_json(const std::string& json_path, const std::string& where) {
  std::ifstream in(json_path);
  if (!in) throw BimError(where + ": cannot be opened");
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::exception& e) {
    throw BimError(where + ": not JSON: " + e.what());
  }
  if (field<std::string>(j, "format", where) != "concert-ifc-import" ||
      !j.contains("version") || !j.at("version").is_number_integer() ||
      j.at("version").get<std::int64_t>() != 1) {
    throw BimError(where + ": not format concert-ifc-import version 1");
  }
  BimModel m;
  m.source = field<std::string>(j, "source", where);
  m.schema = field<std::string>(j, "schema", where);
  m.length_unit_m = field<double>(j, "length_unit_m", where);

  const Json& binary = field<Json>(j, "binary", where);
  // The step writes its binary file beside the JSON: a name with a folder in it (or an absolute
  // path) would let the file point anywhere, e.g. at a device that never ends.
  const std::string bin_name = field<std::string>(binary, "file", where + ": binary");
  if (bin_name.empty() || fs::path(bin_name).filename() != fs::path(bin_name) || bin_name == "." ||
      bin_name == "..") {
    throw BimError(where + ": binary.file '" + bin_name + "' is not a file name beside it");
  }
  const fs::path bin = fs::path(json_path).parent_path() / bin_name;
  const auto vertex_count = count_field(binary, "vertex_count", where + ": binary");
  const auto index_count = count_field(binary, "index_count", where + ": binary");
  std::error_code size_error;
  const bool regular = fs::is_regular_file(bin, size_error);
  const std::uintmax_t bin_size = regular ? fs::file_size(bin, size_error) : std::uintmax_t{0};
  if (!regular || size_error) {
    throw BimError(where + ": its binary file '" + bin.string() + "' cannot be opened");
  }
  // The counts are checked against the file's size before anything is allocated for them.
  constexpr std::uintmax_t kVertexBytes = 3 * sizeof(float);
  constexpr std::uintmax_t kIndexBytes = sizeof(std::uint32_t);
  if (vertex_count > bin_size / kVertexBytes || index_count > bin_size / kIndexBytes ||
      vertex_count * kVertexBytes + index_count * kIndexBytes != bin_size) {
    throw BimError(where + ": binary file '" + bin.string() + "' is " + std::to_string(bin_size) +
                   " bytes long, not the " + std::to_string(vertex_count) + " vertices and " +
                   std::to_string(index_count) + " indices the JSON says");
  }
  std::vector<float> vertices(vertex_count * 3);
  std::vector<std::uint32_t> indices(index_count);
  {
    std::ifstream b(bin, std::ios::binary);
    if (!b) throw BimError(where + ": its binary file '" + bin.string() + "' cannot be opened");
    b.read(reinterpret_cast<char*>(vertices.data()),
           static_cast<std::streamsize>(vertices.size() * sizeof(float)));
    b.read(reinterpret_cast<char*>(indices.data()),
           static_cast<std::streamsize>(indices.size() * sizeof(std::uint32_t)));
    if (!b) throw BimError(where + ": binary file '" + bin.string() + "' could not be read");
  }

  for (const auto& s : field<Json>(j, "storeys", where)) {
    const std::string w = where + ": storey";
    m.storeys.push_back({field<std::string>(s, "name", w), field<std::string>(s, "global_id", w),
                         field<double>(s, "elevation", w)});
  }
  for (const auto& e : field<Json>(j, "elements", where)) {
    Element el;
    el.global_id = field<std::string>(e, "global_id", where + ": element");
    const std::string w = where + ": element " + el.global_id;
    el.ifc_type = field<std::string>(e, "ifc_type", w);
    el.category = category_from_string(field<std::string>(e, "category", w));
    el.name = field<std::string>(e, "name", w);
    if (!e.at("storey").is_null()) el.storey = field<std::string>(e, "storey", w);
    el.storey_by_height = field<std::string>(e, "storey_from", w) == "height";
    if (!e.at("host").is_null()) el.host = field<std::string>(e, "host", w);
    if (!e.at("placement").is_null()) {
      el.placement_origin = vec3(e["placement"].at("origin"), w + ": placement.origin");
      el.placement_x = vec3(e["placement"].at("x_axis"), w + ": placement.x_axis");
    }
    const auto v0 = count_field(e, "vertex_offset", w);
    const auto nv = count_field(e, "vertex_count", w);
    const auto i0 = count_field(e, "index_offset", w);
    const auto ni = count_field(e, "index_count", w);
    if (v0 > vertex_count || nv > vertex_count - v0 || i0 > index_count ||
        ni > index_count - i0 || ni % 3 != 0) {
      throw BimError(w + ": mesh range outside the binary file's " + std::to_string(vertex_count) +
                     " vertices / " + std::to_string(index_count) + " indices");
    }
    el.mesh.vertices.reserve(nv);
    for (std::size_t k = 0; k < nv; ++k) {
      const float* p = &vertices[(v0 + k) * 3];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        throw BimError(w + ": vertex " + std::to_string(k) + " is not finite");
      }
      el.mesh.vertices.emplace_back(p[0], p[1], p[2]);
      el.bounds.extend(el.mesh.vertices.back());
    }
    for (std::size_t k = 0; k < ni; k += 3) {
      const std::uint32_t* t = &indices[i0 + k];
      if (t[0] >= nv || t[1] >= nv || t[2] >= nv)
        throw BimError(w + ": triangle index beyond its vertices");
      el.mesh.triangles.emplace_back(static_cast<int>(t[0]), static_cast<int>(t[1]),
                                     static_cast<int>(t[2]));
    }
    m.elements.push_back(std::move(el));
  }
  return m;
}

}  // namespace

BimModel read_import(const std::string& json_path) {
  const std::string where = "IFC import output '" + json_path + "'";
  try {
    return read_import_json(json_path, where);
  } catch (const Json::exception& e) {
    // A field of the wrong kind below the top level (e.g. `placement` not an object).
    throw BimError(where + ": " + e.what());
  }
}

BimModel load_ifc(const std::string& ifc_path, const ImportOptions& options) {
  if (!fs::is_regular_file(ifc_path)) throw BimError("IFC file '" + ifc_path + "': no such file");
  const std::string script = options.script.empty() ? default_import_script() : options.script;
  if (!fs::is_regular_file(script)) {
    throw BimError("the IFC import step '" + script +
                   "' does not exist (set CONCERT_IFC_IMPORT to tools/ifc_import/ifc_import.mjs)");
  }
  std::optional<TempDir> temp;
  fs::path out_dir;
  if (options.keep_dir.empty()) {
    temp.emplace();
    out_dir = temp->path();
  } else {
    out_dir = options.keep_dir;
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) throw BimError("cannot create '" + out_dir.string() + "': " + ec.message());
  }
  const fs::path err_file = out_dir / "import.stderr";
  const int status = run_child(
      {options.node, script, fs::absolute(ifc_path).string(), (out_dir / "model").string()},
      err_file);
  std::string err = trimmed(read_text(err_file));
  std::error_code ec;
  fs::remove(err_file, ec);
  const std::string prefix = "ifc_import: ";
  if (err.rfind(prefix, 0) == 0) err = err.substr(prefix.size());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string how = WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                              : "signal " + std::to_string(WTERMSIG(status));
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127 && err.empty()) {
      throw BimError("IFC file '" + ifc_path + "': cannot run '" + options.node +
                     "' (install Node.js)");
    }
    throw BimError("IFC file '" + ifc_path +
                   "': " + (err.empty() ? "the import step failed" : err) + " (" + how + ")");
  }
  BimModel model = read_import((out_dir / "model.json").string());
  model.source = ifc_path;
  const bool walls = std::any_of(
      model.elements.begin(), model.elements.end(),
      [](const Element& e) { return e.category == Category::kWall && !e.mesh.triangles.empty(); });
  if (!walls)
    throw BimError("IFC file '" + ifc_path + "': no walls with geometry (nothing to map)");
  if (model.storeys.empty()) throw BimError("IFC file '" + ifc_path + "': no IfcBuildingStorey");
  return model;
}

std::string slug(const std::string& name) {
  std::string out;
  for (const char ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (std::isalnum(c) && c < 128) {
      out += static_cast<char>(std::tolower(c));
    } else if (!out.empty() && out.back() != '-') {
      out += '-';
    }
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out.empty() ? "storey" : out;
}

}  // namespace concert::bim
