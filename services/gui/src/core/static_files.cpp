#include "gui/static_files.hpp"

#include <algorithm>
#include <cctype>
#include <system_error>
#include <vector>

namespace concert::gui {

namespace fs = std::filesystem;

namespace {

std::optional<std::string> percent_decode(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out += in[i];
      continue;
    }
    if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(in[i + 2]))) {
      return std::nullopt;
    }
    out += static_cast<char>(std::stoi(std::string(in.substr(i + 1, 2)), nullptr, 16));
    i += 2;
  }
  return out;
}

/// `rel` (a '/'-separated relative path) under `root`, if it stays inside and is a file.
std::optional<fs::path> under(const fs::path& root, std::string_view rel) {
  if (root.empty()) return std::nullopt;
  fs::path p = root;
  size_t start = 0;
  while (start <= rel.size()) {
    const size_t slash = std::min(rel.find('/', start), rel.size());
    const std::string_view part = rel.substr(start, slash - start);
    if (part == "..") return std::nullopt;
    if (!part.empty() && part != ".") p /= std::string(part);
    start = slash + 1;
  }
  std::error_code ec;
  const fs::path real = fs::canonical(p, ec);
  if (ec) return std::nullopt;
  const fs::path real_root = fs::canonical(root, ec);
  if (ec) return std::nullopt;
  // Inside the root after symbolic links are followed.
  auto r = real_root.begin();
  auto f = real.begin();
  for (; r != real_root.end(); ++r, ++f) {
    if (f == real.end() || *r != *f) return std::nullopt;
  }
  if (!fs::is_regular_file(real, ec)) return std::nullopt;
  return real;
}

}  // namespace

std::optional<fs::path> resolve_request(const StaticRoots& roots, std::string_view target) {
  target = target.substr(0, target.find_first_of("?#"));
  const auto decoded = percent_decode(target);
  if (!decoded || decoded->empty() || decoded->front() != '/' || decoded->find('\0') != std::string::npos ||
      decoded->find('\\') != std::string::npos) {
    return std::nullopt;
  }
  std::string_view path = *decoded;
  const std::string_view prefix = "/packages/";
  if (path.substr(0, prefix.size()) == prefix) {
    const std::string_view rest = path.substr(prefix.size());
    const size_t slash = rest.find('/');
    if (slash == std::string_view::npos) return std::nullopt;
    const auto pkg = roots.packages.find(std::string(rest.substr(0, slash)));
    if (pkg == roots.packages.end()) return std::nullopt;
    return under(pkg->second, rest.substr(slash + 1));
  }
  std::string rel(path.substr(1));
  if (rel.empty() || rel.back() == '/') rel += "index.html";
  return under(roots.app, rel);
}

std::string mime_type(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  static const std::map<std::string, std::string> kTypes = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".svg", "image/svg+xml"},
      {".png", "image/png"},
      {".jpg", "image/jpeg"},
      {".ico", "image/x-icon"},
      {".stl", "model/stl"},
      {".dae", "model/vnd.collada+xml"},
      {".obj", "model/obj"},
      {".urdf", "application/xml"},
      {".txt", "text/plain; charset=utf-8"},
  };
  const auto it = kTypes.find(ext);
  return it == kTypes.end() ? "application/octet-stream" : it->second;
}

std::pair<std::string, fs::path> package_of(const fs::path& package_dir) {
  fs::path p = package_dir;
  if (p.has_filename() == false) p = p.parent_path();
  return {p.filename().string(), p};
}

}  // namespace concert::gui
