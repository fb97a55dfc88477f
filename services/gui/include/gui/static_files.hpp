#pragma once
// Which file answers an HTTP GET: the app's built files, and the meshes of the module database
// under /packages/<name>/ (URDF mesh URIs are package://<name>/...). (C++17: used by the web
// server's translation unit.)

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace concert::gui {

struct StaticRoots {
  std::filesystem::path app;                               ///< the built app (index.html, ...)
  std::map<std::string, std::filesystem::path> packages;  ///< package name -> folder
};

/// The file for the request target `target` (path and optional query, e.g. "/", "/app.js?v=2",
/// "/packages/concert_resources/models/a%20b.stl"); nullopt for a path that is malformed, leaves
/// its root ("..", a symbolic link out), or names no regular file.
std::optional<std::filesystem::path> resolve_request(const StaticRoots& roots, std::string_view target);

/// The Content-Type of a file, by extension (application/octet-stream when unknown).
std::string mime_type(const std::filesystem::path& file);

/// `package_dir` named as URDF package:// URIs name it: the folder's own name.
std::pair<std::string, std::filesystem::path> package_of(const std::filesystem::path& package_dir);

}  // namespace concert::gui
